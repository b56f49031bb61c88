/* Per-vertex tangents generated from a mesh's uvs, following the definition of MikkTSpace (the
 * tangent space Blender, glTF exporters and most normal-map bakers use), written here from that
 * definition:
 *   - each triangle's tangent is its uv gradient: the direction of increasing u in the triangle's
 *     plane, (dv2 * e1 - dv1 * e2) for edges e1, e2 and their uv differences, normalized, with
 *     the sign of the triangle's signed uv area (its orientation: mirrored uvs flip it);
 *   - a vertex sums, over the triangle corners it has, that tangent projected orthogonal to the
 *     vertex normal and normalized, weighted by the corner's angle (measured between its two
 *     edges projected the same way); corners of the two orientations are summed apart;
 *   - vertices with the same position, normal and uv (bit for bit) are one vertex, as MikkTSpace
 *     welds them, so a mesh whose vertices were not joined gets the same tangents;
 *   - the result is projected orthogonal to the normal and normalized; w = +1 for a vertex whose
 *     corners preserve orientation, -1 for mirrored ones.
 * uv here is glTF's (v grows down the image); MikkTSpace's v grows up (Blender's, the one normal
 * maps are baked with), so v is negated: the bitangent cross(n, t) * w points up the image, the
 * +y (green) of a glTF normal map.
 * Unlike MikkTSpace, a vertex shared by corners of both orientations is not split (the mesh's
 * vertices are kept): it takes the orientation with the larger angle sum. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "par_pool.h"
#include "scene/import_internal.h"

/* Meshes of more vertices or triangles than this run their passes in parts on a pool of threads
 * (a 1 M-triangle mesh took 0.3 s on one); each part computes exactly what the one loop did, and
 * the sums over corners are added in the same order, so the tangents are the same bits. */
#define PAR_MIN 65536u
/* triangles whose corners are computed in parallel before they are added in order */
#define CHUNK 65536u

/* A vertex and the 8 floats that weld it: position, normal, uv. */
typedef struct {
    float k[8];
    uint32_t v;
} weld_rec;

static int weld_rec_cmp(const void *pa, const void *pb)
{
    const weld_rec *a = pa, *b = pb;
    int i;
    for (i = 0; i < 8; i++)
        if (a->k[i] != b->k[i]) return a->k[i] < b->k[i] ? -1 : 1;
    return a->v < b->v ? -1 : a->v > b->v;
}

static evr_v3 vload(const float *p) { return evr_v3_make(p[0], p[1], p[2]); }

/* v without its component along unit n. */
static evr_v3 flatten(evr_v3 v, evr_v3 n)
{
    return evr_v3_sub(v, evr_v3_scale(n, evr_v3_dot(n, v)));
}

static evr_v3 unit_or_zero(evr_v3 v)
{
    float l = evr_v3_len(v);
    return l > 0.0f && isfinite(l) ? evr_v3_scale(v, 1.0f / l) : evr_v3_make(0, 0, 0);
}

/* One triangle's corners: the tangent each adds (projected at its vertex) and the angle it
 * weighs by; orientation 0 mirrored, 1 preserving, -1 no uv gradient (adds nothing). */
typedef struct {
    float tc[3][3], ang[3];
    int orient;
} corner_rec;

static void triangle_corners(const evr_mesh *m, uint32_t f, corner_rec *out)
{
    const uint32_t *t = &m->indices[3 * f];
    evr_v3 p[3], e1, e2, os;
    float s1, t1, s2, t2, area;
    int c;
    for (c = 0; c < 3; c++) p[c] = vload(m->positions + 3 * t[c]);
    e1 = evr_v3_sub(p[1], p[0]);
    e2 = evr_v3_sub(p[2], p[0]);
    s1 = m->uvs[2 * t[1]] - m->uvs[2 * t[0]];
    s2 = m->uvs[2 * t[2]] - m->uvs[2 * t[0]];
    t1 = -(m->uvs[2 * t[1] + 1] - m->uvs[2 * t[0] + 1]); /* MikkTSpace's v grows up */
    t2 = -(m->uvs[2 * t[2] + 1] - m->uvs[2 * t[0] + 1]);
    area = s1 * t2 - t1 * s2;
    out->orient = -1;
    if (area == 0.0f || !isfinite(area)) return; /* no uv gradient: adds nothing */
    out->orient = area > 0.0f;
    os = unit_or_zero(evr_v3_sub(evr_v3_scale(e1, t2), evr_v3_scale(e2, t1)));
    if (!out->orient) os = evr_v3_scale(os, -1.0f);
    for (c = 0; c < 3; c++) {
        evr_v3 n = vload(m->normals + 3 * t[c]);
        evr_v3 a = unit_or_zero(flatten(evr_v3_sub(p[(c + 1) % 3], p[c]), n));
        evr_v3 b = unit_or_zero(flatten(evr_v3_sub(p[(c + 2) % 3], p[c]), n));
        evr_v3 tc = unit_or_zero(flatten(os, n));
        float cosang = fminf(fmaxf(evr_v3_dot(a, b), -1.0f), 1.0f);
        out->tc[c][0] = tc.x;
        out->tc[c][1] = tc.y;
        out->tc[c][2] = tc.z;
        out->ang[c] = acosf(cosang);
    }
}

/* The vertex's tangent from its group's sums. */
static void vertex_tangent(const evr_mesh *m, const float *acc, const uint32_t *group, uint32_t v)
{
    const float *a = acc + 8 * (size_t)group[v];
    int orient = a[7] >= a[3]; /* the orientation with the larger angle sum */
    const float *s = a + 4 * orient;
    evr_v3 n = vload(m->normals + 3 * v);
    evr_v3 t = unit_or_zero(flatten(vload(s), n));
    float *out = m->tangents + 4 * v;
    if (t.x == 0.0f && t.y == 0.0f && t.z == 0.0f) {
        /* no uv gradient here: any unit vector orthogonal to the normal */
        evr_v3 axis = fabsf(n.x) < 0.9f ? evr_v3_make(1, 0, 0) : evr_v3_make(0, 1, 0);
        t = unit_or_zero(flatten(axis, n));
        orient = 1;
    }
    out[0] = t.x;
    out[1] = t.y;
    out[2] = t.z;
    out[3] = orient ? 1.0f : -1.0f;
}

/* The work of the passes that run in parts (ctx of every evr_par_fn below). */
typedef struct {
    evr_mesh *m;
    weld_rec *rec, *merged; /* the records; the merge's output */
    uint32_t *group;
    float *acc;
    corner_rec *corners; /* the chunk's triangles from f0 */
    uint32_t f0, nf;
    int parts;
} tan_job;

static void sort_part(void *ctx, int k, int thread)
{
    tan_job *j = ctx;
    size_t b, e;
    (void)thread;
    evr_par_share(j->m->num_vertices, 2, k, &b, &e); /* two halves, merged after */
    qsort(j->rec + b, e - b, sizeof *j->rec, weld_rec_cmp);
}

static void corners_part(void *ctx, int k, int thread)
{
    tan_job *j = ctx;
    size_t b, e;
    (void)thread;
    evr_par_share(j->nf, j->parts, k, &b, &e);
    for (size_t i = b; i < e; i++) triangle_corners(j->m, j->f0 + (uint32_t)i, &j->corners[i]);
}

static void vertices_part(void *ctx, int k, int thread)
{
    tan_job *j = ctx;
    size_t b, e;
    (void)thread;
    evr_par_share(j->m->num_vertices, j->parts, k, &b, &e);
    for (size_t v = b; v < e; v++) vertex_tangent(j->m, j->acc, j->group, (uint32_t)v);
}

/* rec sorted: as parts sorted apart, then merged (the order is total, so it is the one order a
 * single sort gives); 0 when out of memory. */
static int sort_records(tan_job *j, evr_par_pool *pool)
{
    const size_t n = j->m->num_vertices;
    size_t b1, e0, a, c, o = 0;
    if (j->parts < 2) {
        qsort(j->rec, n, sizeof *j->rec, weld_rec_cmp);
        return 1;
    }
    evr_par_pool_run(pool, 2, sort_part, j);
    if (!(j->merged = malloc(n * sizeof *j->merged))) return 0;
    evr_par_share(n, 2, 0, &a, &e0);
    evr_par_share(n, 2, 1, &b1, &c);
    for (c = b1; a < e0 || c < n;)
        j->merged[o++] = (c >= n || (a < e0 && weld_rec_cmp(&j->rec[a], &j->rec[c]) < 0))
                             ? j->rec[a++]
                             : j->rec[c++];
    memcpy(j->rec, j->merged, n * sizeof *j->rec);
    return 1;
}

/* A vertex's weld key: the bits of its position, normal and uv. */
static void weld_key(const evr_mesh *m, uint32_t v, uint32_t k[8])
{
    memcpy(k, m->positions + 3 * (size_t)v, 3 * sizeof(float));
    memcpy(k + 3, m->normals + 3 * (size_t)v, 3 * sizeof(float));
    memcpy(k + 6, m->uvs + 2 * (size_t)v, 2 * sizeof(float));
}

/* The groups the sort gives, by hashing: each vertex to the first vertex of the same key bits.
 * With no -0 and no NaN in any key, keys equal as floats are equal bits, so the sort's runs are
 * these sets and a run's first vertex (ties go by vertex) is the set's first. 1 when done; 0
 * when a key holds -0 or NaN or memory ran out (then the sort decides). */
static int weld_by_hash(const evr_mesh *m, uint32_t *group)
{
    const uint32_t nv = m->num_vertices;
    size_t cap = 16, mask;
    while (cap < 2 * (size_t)nv) cap *= 2;
    mask = cap - 1;
    uint32_t *slot = malloc(cap * sizeof *slot);
    if (!slot) return 0;
    memset(slot, 0xff, cap * sizeof *slot); /* empty */
    for (uint32_t v = 0; v < nv; v++) {
        uint32_t k[8], u[8];
        uint64_t h = 0x9e3779b97f4a7c15ull;
        weld_key(m, v, k);
        for (int i = 0; i < 8; i++) {
            if (k[i] == 0x80000000u || (k[i] & 0x7fffffffu) > 0x7f800000u) {
                free(slot); /* -0 or NaN */
                return 0;
            }
            h = (h ^ k[i]) * 0x100000001b3ull;
            h ^= h >> 29;
        }
        size_t at = (size_t)h & mask;
        group[v] = v;
        for (; slot[at] != 0xffffffffu; at = (at + 1) & mask) {
            weld_key(m, slot[at], u);
            if (!memcmp(u, k, sizeof k)) {
                group[v] = slot[at];
                break;
            }
        }
        if (group[v] == v) slot[at] = v;
    }
    free(slot);
    return 1;
}

int evr_mesh_generate_tangents(evr_mesh *m)
{
    const int big = m->num_vertices >= PAR_MIN || m->num_triangles >= PAR_MIN;
    return evr_mesh_tangents_threads(m, big ? evr_par_threads(8) : 1, 0);
}

int evr_mesh_tangents_threads(evr_mesh *m, int threads, int by_sort)
{
    uint32_t nv = m->num_vertices, v, f;
    uint32_t *group = malloc((size_t)nv * sizeof *group + 1);
    const int hashed = group && !by_sort && weld_by_hash(m, group);
    weld_rec *rec = hashed ? NULL : malloc((size_t)nv * sizeof *rec + 1);
    /* per group and orientation (0 mirrored, 1 preserving): summed tangent and angle */
    float *acc = calloc((size_t)nv * 8 + 1, sizeof *acc);
    evr_par_pool *pool = threads > 1 ? evr_par_pool_new(threads) : NULL;
    tan_job j;
    memset(&j, 0, sizeof j);
    j.m = m;
    j.rec = rec;
    j.group = group;
    j.acc = acc;
    j.parts = evr_par_pool_threads(pool) > 1 ? 2 * evr_par_pool_threads(pool) : 1;
    j.corners =
        malloc(sizeof *j.corners * (m->num_triangles < CHUNK ? m->num_triangles : CHUNK) + 1);
    m->tangents = malloc((size_t)nv * 4 * sizeof(float) + 1);
    int ok = (hashed || rec) && group && acc && j.corners && m->tangents;
    for (v = 0; ok && !hashed && v < nv; v++) {
        memcpy(rec[v].k, m->positions + 3 * v, 3 * sizeof(float));
        memcpy(rec[v].k + 3, m->normals + 3 * v, 3 * sizeof(float));
        memcpy(rec[v].k + 6, m->uvs + 2 * v, 2 * sizeof(float));
        rec[v].v = v;
    }
    if (ok && !hashed) ok = sort_records(&j, pool);
    /* by the sort: each vertex to the first of its run of equal keys */
    for (v = 0; ok && !hashed && v < nv; v++)
        group[rec[v].v] = (v > 0 && !memcmp(rec[v].k, rec[v - 1].k, sizeof rec[v].k))
                              ? group[rec[v - 1].v]
                              : rec[v].v;

    for (j.f0 = 0; ok && j.f0 < m->num_triangles; j.f0 += j.nf) {
        j.nf = m->num_triangles - j.f0 < CHUNK ? m->num_triangles - j.f0 : CHUNK;
        evr_par_pool_run(pool, j.parts, corners_part, &j);
        for (f = 0; f < j.nf; f++) { /* in triangle order, as one loop adds them */
            const corner_rec *cr = &j.corners[f];
            const uint32_t *t = &m->indices[3 * (size_t)(j.f0 + f)];
            if (cr->orient < 0) continue;
            for (int c = 0; c < 3; c++) {
                float *slot = acc + 8 * (size_t)group[t[c]] + 4 * cr->orient;
                const float ang = cr->ang[c];
                slot[0] += cr->tc[c][0] * ang;
                slot[1] += cr->tc[c][1] * ang;
                slot[2] += cr->tc[c][2] * ang;
                slot[3] += ang;
            }
        }
    }
    if (ok) evr_par_pool_run(pool, j.parts, vertices_part, &j);
    evr_par_pool_free(pool);
    free(j.corners);
    free(j.merged);
    free(rec);
    free(group);
    free(acc);
    if (!ok) {
        free(m->tangents);
        m->tangents = NULL;
    }
    return ok;
}
