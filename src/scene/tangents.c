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

#include "scene/import_internal.h"

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

int evr_mesh_generate_tangents(evr_mesh *m)
{
    uint32_t nv = m->num_vertices, v, f;
    weld_rec *rec = malloc((size_t)nv * sizeof *rec + 1);
    uint32_t *group = malloc((size_t)nv * sizeof *group + 1);
    /* per group and orientation (0 mirrored, 1 preserving): summed tangent and angle */
    float *acc = calloc((size_t)nv * 8 + 1, sizeof *acc);
    m->tangents = malloc((size_t)nv * 4 * sizeof(float) + 1);
    if (!rec || !group || !acc || !m->tangents) {
        free(rec);
        free(group);
        free(acc);
        free(m->tangents);
        m->tangents = NULL;
        return 0;
    }
    for (v = 0; v < nv; v++) {
        memcpy(rec[v].k, m->positions + 3 * v, 3 * sizeof(float));
        memcpy(rec[v].k + 3, m->normals + 3 * v, 3 * sizeof(float));
        memcpy(rec[v].k + 6, m->uvs + 2 * v, 2 * sizeof(float));
        rec[v].v = v;
    }
    qsort(rec, nv, sizeof *rec, weld_rec_cmp);
    for (v = 0; v < nv; v++) /* each vertex to the first of its run of equal keys */
        group[rec[v].v] = (v > 0 && !memcmp(rec[v].k, rec[v - 1].k, sizeof rec[v].k))
                              ? group[rec[v - 1].v]
                              : rec[v].v;

    for (f = 0; f < m->num_triangles; f++) {
        const uint32_t *t = &m->indices[3 * f];
        evr_v3 p[3], e1, e2, os;
        float s1, t1, s2, t2, area;
        int c, orient;
        for (c = 0; c < 3; c++) p[c] = vload(m->positions + 3 * t[c]);
        e1 = evr_v3_sub(p[1], p[0]);
        e2 = evr_v3_sub(p[2], p[0]);
        s1 = m->uvs[2 * t[1]] - m->uvs[2 * t[0]];
        s2 = m->uvs[2 * t[2]] - m->uvs[2 * t[0]];
        t1 = -(m->uvs[2 * t[1] + 1] - m->uvs[2 * t[0] + 1]); /* MikkTSpace's v grows up */
        t2 = -(m->uvs[2 * t[2] + 1] - m->uvs[2 * t[0] + 1]);
        area = s1 * t2 - t1 * s2;
        if (area == 0.0f || !isfinite(area)) continue; /* no uv gradient: adds nothing */
        orient = area > 0.0f;
        os = unit_or_zero(evr_v3_sub(evr_v3_scale(e1, t2), evr_v3_scale(e2, t1)));
        if (!orient) os = evr_v3_scale(os, -1.0f);
        for (c = 0; c < 3; c++) {
            uint32_t vi = t[c], g = group[vi];
            evr_v3 n = vload(m->normals + 3 * vi);
            evr_v3 a = unit_or_zero(flatten(evr_v3_sub(p[(c + 1) % 3], p[c]), n));
            evr_v3 b = unit_or_zero(flatten(evr_v3_sub(p[(c + 2) % 3], p[c]), n));
            evr_v3 tc = unit_or_zero(flatten(os, n));
            float cosang = fminf(fmaxf(evr_v3_dot(a, b), -1.0f), 1.0f), ang = acosf(cosang);
            float *slot = acc + 8 * (size_t)g + 4 * orient;
            slot[0] += tc.x * ang;
            slot[1] += tc.y * ang;
            slot[2] += tc.z * ang;
            slot[3] += ang;
        }
    }

    for (v = 0; v < nv; v++) {
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
    free(rec);
    free(group);
    free(acc);
    return 1;
}
