/* Per-segment plan of change-driven sampling: see skip_plan.h and core/skip.h. */
#include "prep/skip_plan.h"
#include "prep/swept_bounds.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int evr_skip_tracker_init(evr_skip_tracker *t, int num_tracks)
{
    memset(t, 0, sizeof *t);
    t->num_tracks = num_tracks;
    t->prev_last = calloc((size_t)num_tracks, sizeof *t->prev_last);
    t->prev_count = calloc((size_t)num_tracks, sizeof *t->prev_count);
    t->moved = calloc((size_t)num_tracks, sizeof *t->moved);
    t->last = calloc((size_t)num_tracks, sizeof *t->last);
    t->last_count = calloc((size_t)num_tracks, sizeof *t->last_count);
    return t->prev_last && t->prev_count && t->moved && t->last && t->last_count;
}

void evr_skip_tracker_free(evr_skip_tracker *t)
{
    free(t->prev_last);
    free(t->prev_count);
    free(t->moved);
    free(t->last);
    free(t->last_count);
    for (int i = 0; t->mesh_parts && i < t->num_meshes; i++) free(t->mesh_parts[i]);
    free(t->mesh_parts);
    for (int i = 0; t->tri_order && i < t->num_meshes; i++) free(t->tri_order[i]);
    free(t->tri_order);
    memset(t, 0, sizeof *t);
}

int evr_skip_tracker_parts(evr_skip_tracker *t, const evr_scene *s)
{
    t->num_meshes = s->num_meshes;
    t->mesh_parts = calloc((size_t)(s->num_meshes ? s->num_meshes : 1), sizeof *t->mesh_parts);
    t->tri_order = calloc((size_t)(s->num_meshes ? s->num_meshes : 1), sizeof *t->tri_order);
    return t->mesh_parts != NULL && t->tri_order != NULL;
}

typedef struct {
    float key;
    uint32_t tri;
} keyed_tri;

static int keyed_cmp(const void *a, const void *b)
{
    const keyed_tri *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->tri < y->tri ? -1 : x->tri > y->tri;
}

static void tri_box(const evr_mesh *m, uint32_t tri, float box[6])
{
    for (int c = 0; c < 3; c++) {
        const float *p = &m->positions[3 * m->indices[3 * tri + c]];
        for (int a = 0; a < 3; a++) {
            box[a] = fminf(box[a], p[a]);
            box[a + 3] = fmaxf(box[a + 3], p[a]);
        }
    }
}

static void empty_box(float box[6])
{
    box[0] = box[1] = box[2] = INFINITY;
    box[3] = box[4] = box[5] = -INFINITY;
}

/* Splits the triangles k[0 .. n) at the median of their centroids along the widest axis of the
 * centroids, depth times; the leaves' boxes go to out[0 .. 2^depth) in order (empty leaves
 * empty), so that 2^j consecutive leaves make a leaf of depth - j. */
static void split_parts(const evr_mesh *m, keyed_tri *k, size_t n, int depth, float (*out)[6])
{
    const size_t leaves = (size_t)1 << depth;
    if (depth == 0 || n <= 1) {
        for (size_t i = 0; i < leaves; i++) empty_box(out[i]);
        for (size_t i = 0; i < n; i++) tri_box(m, k[i].tri, out[0]);
        return;
    }
    float c[6];
    empty_box(c);
    for (size_t i = 0; i < n; i++) {
        const uint32_t *ix = &m->indices[3 * k[i].tri];
        for (int a = 0; a < 3; a++) {
            const float v = m->positions[3 * ix[0] + a] + m->positions[3 * ix[1] + a] +
                            m->positions[3 * ix[2] + a];
            c[a] = fminf(c[a], v);
            c[a + 3] = fmaxf(c[a + 3], v);
        }
    }
    int axis = 0;
    for (int a = 1; a < 3; a++)
        if (c[a + 3] - c[a] > c[axis + 3] - c[axis]) axis = a;
    for (size_t i = 0; i < n; i++) {
        const uint32_t *ix = &m->indices[3 * k[i].tri];
        k[i].key = m->positions[3 * ix[0] + axis] + m->positions[3 * ix[1] + axis] +
                   m->positions[3 * ix[2] + axis];
    }
    qsort(k, n, sizeof *k, keyed_cmp);
    split_parts(m, k, n / 2, depth - 1, out);
    split_parts(m, k + n / 2, n - n / 2, depth - 1, out + leaves / 2);
}

/* The parts of mesh i (made on first use); NULL when the tracker has none or memory ran out. */
static const float (*mesh_parts(evr_skip_tracker *t, const evr_scene *s, int i))[6]
{
    if (!t->mesh_parts || i < 0 || i >= t->num_meshes) return NULL;
    if (!t->mesh_parts[i]) {
        const evr_mesh *m = &s->meshes[i];
        float(*out)[6] = malloc(sizeof *out * EVR_SKIP_MESH_PARTS);
        keyed_tri *k = malloc(sizeof *k * (m->num_triangles ? m->num_triangles : 1));
        if (!k || !out) {
            free(k);
            free(out);
            return NULL;
        }
        for (uint32_t j = 0; j < m->num_triangles; j++) k[j].tri = j;
        int depth = 0;
        while ((1 << depth) < EVR_SKIP_MESH_PARTS) depth++;
        split_parts(m, k, m->num_triangles, depth, out);
        free(k);
        t->mesh_parts[i] = out;
    }
    return (const float(*)[6])t->mesh_parts[i];
}

/* The leaves split_parts makes of k[first .. first + n): leaf l holds k[bounds[l] ..
 * bounds[l + 1]) (the same recursion, without the sorting). */
static void leaf_bounds(uint32_t first, uint32_t n, int depth, uint32_t *bounds)
{
    const uint32_t leaves = (uint32_t)1 << depth;
    if (depth == 0 || n <= 1) {
        bounds[0] = first;
        for (uint32_t i = 1; i <= leaves; i++) bounds[i] = first + n;
        return;
    }
    leaf_bounds(first, n / 2, depth - 1, bounds);
    leaf_bounds(first + n / 2, n - n / 2, depth - 1, bounds + leaves / 2);
}

/* The parts of a deforming mesh i: its triangles in split_parts' order (split at rest) and each
 * leaf's first; their boxes are made every segment from the vertex keys (deform_part_boxes). */
static int deform_parts(evr_skip_tracker *t, const evr_scene *s, int i)
{
    if (!t->tri_order || i < 0 || i >= t->num_meshes) return 0;
    if (t->tri_order[i]) return 1;
    const evr_mesh *m = &s->meshes[i];
    float(*scratch)[6] = malloc(sizeof *scratch * EVR_SKIP_MESH_PARTS);
    keyed_tri *k = malloc(sizeof *k * (m->num_triangles ? m->num_triangles : 1));
    uint32_t *order = malloc(sizeof *order * (m->num_triangles ? m->num_triangles : 1) +
                             sizeof *order * (EVR_SKIP_MESH_PARTS + 1));
    if (!scratch || !k || !order) {
        free(scratch);
        free(k);
        free(order);
        return 0;
    }
    for (uint32_t j = 0; j < m->num_triangles; j++) k[j].tri = j;
    int depth = 0;
    while ((1 << depth) < EVR_SKIP_MESH_PARTS) depth++;
    split_parts(m, k, m->num_triangles, depth, scratch);
    for (uint32_t j = 0; j < m->num_triangles; j++) order[j] = k[j].tri;
    leaf_bounds(0, m->num_triangles, depth, order + m->num_triangles);
    free(scratch);
    free(k);
    t->tri_order[i] = order;
    return 1;
}

/* Each part's box over every key of the segment (in the instance's track space). */
static void deform_part_boxes(const evr_skip_tracker *t, const evr_scene *s, int mesh,
                              const evr_deform_view *v, float (*out)[6])
{
    const evr_mesh *m = &s->meshes[mesh];
    const uint32_t *order = t->tri_order[mesh], *first = order + m->num_triangles;
    for (int l = 0; l < EVR_SKIP_MESH_PARTS; l++) {
        empty_box(out[l]);
        for (uint32_t j = first[l]; j < first[l + 1]; j++)
            for (int c = 0; c < 3; c++) {
                const uint32_t vi = m->indices[3 * order[j] + c];
                for (int k = 0; k < v->num_keys; k++) {
                    const float *p = v->positions + ((size_t)k * v->num_vertices + vi) * 3;
                    for (int a = 0; a < 3; a++) { /* finite: no libm call for NaN rules */
                        out[l][a] = p[a] < out[l][a] ? p[a] : out[l][a];
                        out[l][a + 3] = p[a] > out[l][a + 3] ? p[a] : out[l][a + 3];
                    }
                }
            }
    }
}

static int close_to(float a, float b, float tol) { return fabsf(a - b) <= tol; }

static int keys_close(const evr_motion_key *a, const evr_motion_key *b, float size)
{
    const float r = 1e-6f, d = 1e-9f * size;
    int i;
    for (i = 0; i < 3; i++)
        if (!close_to(a->scale[i], b->scale[i], r * fmaxf(1.0f, fabsf(a->scale[i]))) ||
            !close_to(a->skew[i], b->skew[i], r * fmaxf(1.0f, fabsf(a->skew[i]))))
            return 0;
    return close_to(a->rot.w, b->rot.w, r) && close_to(a->rot.x, b->rot.x, r) &&
           close_to(a->rot.y, b->rot.y, r) && close_to(a->rot.z, b->rot.z, r) &&
           close_to(a->trans.x, b->trans.x, d + r * fabsf(a->trans.x)) &&
           close_to(a->trans.y, b->trans.y, d + r * fabsf(a->trans.y)) &&
           close_to(a->trans.z, b->trans.z, d + r * fabsf(a->trans.z));
}

void evr_skip_tracker_update(evr_skip_tracker *t, evr_motion_key *keys, const int *track_offset,
                             const int *track_count, float scene_size)
{
    int i, j;
    if (t->have_prev) { /* the segment seen last is now the previous one */
        memcpy(t->prev_last, t->last, sizeof *t->last * (size_t)t->num_tracks);
        memcpy(t->prev_count, t->last_count, sizeof *t->last_count * (size_t)t->num_tracks);
    }
    for (i = 0; i < t->num_tracks; i++) {
        evr_motion_key *k = keys + track_offset[i];
        int n = track_count[i];
        if (n == 1 && t->have_prev && t->prev_count[i] == 1 &&
            keys_close(&k[0], &t->prev_last[i], scene_size))
            k[0] = t->prev_last[i];
        /* the same inside the segment: a key as close to the one before is that key, so that a
         * part of the segment where the track holds still is still bit for bit */
        for (j = 1; j < n; j++)
            if (keys_close(&k[j], &k[j - 1], scene_size)) k[j] = k[j - 1];
        t->moved[i] = n > 1 || (t->have_prev && memcmp(&k[0], &t->prev_last[i], sizeof k[0]) != 0);
        t->last[i] = k[n - 1];
        t->last_count[i] = n;
    }
    t->have_prev = 1;
}

static void box_union(float lo[3], float hi[3], const float l2[3], const float h2[3])
{
    int a;
    for (a = 0; a < 3; a++) {
        lo[a] = fminf(lo[a], l2[a]);
        hi[a] = fmaxf(hi[a], h2[a]);
    }
}

/* Instance i's box in its track's space: its mesh's, or for a deforming instance the box of its
 * vertex keys over the segment and where they were at the previous segment's end. */
static void local_box(const evr_scene *s, const evr_render_scene *rs, const evr_deform_keys *dk,
                      int i, float lo[3], float hi[3])
{
    const int d = rs->instances[i].deform;
    if (d >= 0 && dk && d < dk->num_deforms) {
        memcpy(lo, dk->motion[d].lo, 3 * sizeof(float));
        memcpy(hi, dk->motion[d].hi, 3 * sizeof(float));
        return;
    }
    const evr_mesh *m = &s->meshes[rs->instances[i].mesh];
    lo[0] = m->bounds_min.x;
    lo[1] = m->bounds_min.y;
    lo[2] = m->bounds_min.z;
    hi[0] = m->bounds_max.x;
    hi[1] = m->bounds_max.y;
    hi[2] = m->bounds_max.z;
}

/* Whether instance i moves in the segment or since the last: its track or its vertices. */
static int instance_moved(const evr_skip_tracker *t, const evr_render_scene *rs,
                          const evr_deform_keys *dk, int i)
{
    const int d = rs->instances[i].deform;
    return t->moved[rs->instances[i].track] ||
           (d >= 0 && dk && d < dk->num_deforms && dk->moved[d]);
}

/* World box of instance i over the segment, and where it was at the previous segment's end. */
static void instance_box(const evr_skip_tracker *t, const evr_scene *s, const evr_render_scene *rs,
                         const evr_deform_keys *dk, int i, float blo[3], float bhi[3])
{
    const int tr = rs->instances[i].track;
    float lo[3], hi[3];
    local_box(s, rs, dk, i, lo, hi);
    evr_swept_bounds(lo, hi, evr_rs_track(rs, tr), blo, bhi);
    if (t->prev_count[tr] > 0) {
        evr_motion_track prev;
        float plo[3], phi[3];
        prev.keys = &t->prev_last[tr];
        prev.n = 1;
        evr_swept_bounds(lo, hi, prev, plo, phi);
        box_union(blo, bhi, plo, phi);
    }
}

/* min and max without libm's NaN rules (no call): the sweep's inputs are finite */
static inline double dmin(double a, double b) { return a < b ? a : b; }
static inline double dmax(double a, double b) { return a > b ? a : b; }

static double upper_norm(const evr_motion_key *k) /* Frobenius norm of U */
{
    double n = 0.0;
    for (int a = 0; a < 3; a++)
        n += (double)k->scale[a] * k->scale[a] + (double)k->skew[a] * k->skew[a];
    return sqrt(n);
}

static double upper_diff_norm(const evr_motion_key *a, const evr_motion_key *b)
{
    double n = 0.0;
    for (int i = 0; i < 3; i++) {
        const double ds = (double)b->scale[i] - a->scale[i], dk = (double)b->skew[i] - a->skew[i];
        n += ds * ds + dk * dk;
    }
    return sqrt(n);
}

/* One track's motion over the segment, for sweeping many boxes: each key's matrix and, per key
 * interval, the bound on how fast a point at unit distance from the origin moves (the same
 * bound as evr_swept_bounds: rotation at the slerp's angular speed times |U c|, plus the
 * change of U). */
typedef struct {
    int n;
    double m[EVR_MAX_KEYS][3][4];  /* each key's matrix */
    double am[EVR_MAX_KEYS][3][3]; /* |linear part|, for the box of a box (Arvo) */
    double speed[EVR_MAX_KEYS];    /* per interval, per unit of |c| */
} track_sweep;

static void track_sweep_init(const evr_render_scene *rs, int tr, track_sweep *ts)
{
    const evr_motion_track tk = evr_rs_track(rs, tr);
    ts->n = tk.n < EVR_MAX_KEYS ? tk.n : EVR_MAX_KEYS;
    for (int k = 0; k < ts->n; k++) {
        const evr_m34 m = evr_motion_key_matrix(&tk.keys[k]);
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 4; c++) {
                ts->m[k][r][c] = m.m[r][c];
                if (c < 3) ts->am[k][r][c] = fabs((double)m.m[r][c]);
            }
    }
    for (int k = 0; k + 1 < ts->n; k++) {
        const evr_motion_key *a = &tk.keys[k], *b = &tk.keys[k + 1];
        double d = fabs((double)evr_quat_dot(a->rot, b->rot));
        const double qa = sqrt((double)evr_quat_dot(a->rot, a->rot)),
                     qb = sqrt((double)evr_quat_dot(b->rot, b->rot));
        d = qa > 0.0 && qb > 0.0 ? d / (qa * qb) : 1.0;
        const double w = 2.0 * acos(d > 1.0 ? 1.0 : d) * 1.01 + 1e-6;
        ts->speed[k] = w * fmax(upper_norm(a), upper_norm(b)) + upper_diff_norm(a, b);
    }
}

/* World box of the object-space box [lo, hi] moved by the track over the segment: the boxes at
 * the keys, each key interval's pair widened by half its speed times the farthest corner's
 * distance (a point moving at speed L between two keys stays within L / 2 of one of them),
 * translation taken as its box. evr_swept_bounds bounds the same motion more tightly, with
 * samples between the keys; this one is for many boxes of one track (a moving mesh's parts, 1,024
 * per segment on the eye), its per-track work done once in track_sweep_init. */
static void sweep_box(const track_sweep *ts, const float lo[3], const float hi[3], float out_lo[3],
                      float out_hi[3])
{
    double blo[3] = {INFINITY, INFINITY, INFINITY}, bhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double pc[3] = {0.0, 0.0, 0.0}, ph[3] = {0.0, 0.0, 0.0}, r = 0.0, mag = 0.0, mc[3], mh[3];
    for (int c = 0; c < 8; c++) {
        const double x = c & 1 ? hi[0] : lo[0], y = c & 2 ? hi[1] : lo[1],
                     z = c & 4 ? hi[2] : lo[2];
        r = dmax(r, sqrt(x * x + y * y + z * z));
    }
    for (int a = 0; a < 3; a++) {
        mc[a] = 0.5 * ((double)lo[a] + hi[a]);
        mh[a] = 0.5 * ((double)hi[a] - lo[a]);
    }
    for (int k = 0; k < ts->n; k++) {
        double c[3], h[3];
        for (int a = 0; a < 3; a++) { /* the box at key k, about its translation (Arvo) */
            c[a] = ts->m[k][a][0] * mc[0] + ts->m[k][a][1] * mc[1] + ts->m[k][a][2] * mc[2];
            h[a] = ts->am[k][a][0] * mh[0] + ts->am[k][a][1] * mh[1] + ts->am[k][a][2] * mh[2];
            const double t = ts->m[k][a][3];
            blo[a] = dmin(blo[a], t + c[a] - h[a]);
            bhi[a] = dmax(bhi[a], t + c[a] + h[a]);
        }
        if (k > 0) { /* the interval from key k - 1 */
            const double margin = 0.5 * ts->speed[k - 1] * r;
            for (int a = 0; a < 3; a++) {
                const double t0 = ts->m[k - 1][a][3], t1 = ts->m[k][a][3];
                blo[a] = dmin(blo[a], dmin(t0, t1) + dmin(pc[a] - ph[a], c[a] - h[a]) - margin);
                bhi[a] = dmax(bhi[a], dmax(t0, t1) + dmax(pc[a] + ph[a], c[a] + h[a]) + margin);
            }
        }
        for (int a = 0; a < 3; a++) {
            pc[a] = c[a];
            ph[a] = h[a];
        }
    }
    for (int a = 0; a < 3; a++) mag = dmax(mag, dmax(fabs(blo[a]), fabs(bhi[a])));
    for (int a = 0; a < 3; a++) {
        /* float evaluation of the transforms (in the traversal and here) is off by a few ulps */
        const double slack = 1e-6 * mag + 1e-30;
        out_lo[a] = evr_round_down(blo[a] - slack);
        out_hi[a] = evr_round_up(bhi[a] + slack);
    }
}

/* Box b (instance i's) as a tree of its mesh's parts, `leaves` leaves (merged from the mesh's
 * EVR_SKIP_MESH_PARTS in order), each swept over the segment; an inner node the union of its
 * children. Where the part was before the segment does not matter here: a pixel's cache is
 * clean only if its rays met nothing that moved in its own segment, so it holds the static
 * scene's answer, and it holds now when its rays meet nothing where things are now. */
static void add_parts(evr_skip_tracker *t, const evr_scene *s, const evr_render_scene *rs,
                      const evr_deform_keys *dk, int i, int leaves, evr_skip_plan *pl, int b,
                      track_sweep *ts, float (*deformed)[6])
{
    /* a deforming mesh's parts: the same triangles, boxed where the segment's keys put them */
    const int d = rs->instances[i].deform, mesh = rs->instances[i].mesh;
    const float(*parts)[6] = NULL;
    if (d < 0) parts = mesh_parts(t, s, mesh);
    else if (dk && d < dk->num_deforms && deformed && deform_parts(t, s, mesh)) {
        deform_part_boxes(t, s, mesh, &dk->views[d], deformed);
        parts = (const float(*)[6])deformed;
    }
    const int base = pl->part_first[b], per = EVR_SKIP_MESH_PARTS / leaves;
    if (!parts) { /* no tree: the instance's box alone */
        pl->part_first[b + 1] = base;
        return;
    }
    track_sweep_init(rs, rs->instances[i].track, ts);
    for (int l = 0; l < leaves; l++) {
        float box[6], *lo = pl->part_lo[base + leaves - 1 + l],
                      *hi = pl->part_hi[base + leaves - 1 + l];
        empty_box(box);
        for (int q = l * per; q < (l + 1) * per; q++)
            box_union(box, box + 3, parts[q], parts[q] + 3);
        if (box[0] <= box[3] && box[1] <= box[4] && box[2] <= box[5]) {
            sweep_box(ts, box, box + 3, lo, hi);
        } else {
            memcpy(lo, box, 3 * sizeof(float));
            memcpy(hi, box + 3, 3 * sizeof(float));
        }
    }
    for (int n = leaves - 2; n >= 0; n--) {
        float *lo = pl->part_lo[base + n], *hi = pl->part_hi[base + n];
        memcpy(lo, pl->part_lo[base + 2 * n + 1], 3 * sizeof(float));
        memcpy(hi, pl->part_hi[base + 2 * n + 1], 3 * sizeof(float));
        box_union(lo, hi, pl->part_lo[base + 2 * n + 2], pl->part_hi[base + 2 * n + 2]);
    }
    pl->part_first[b + 1] = base + 2 * leaves - 1;
}

/* Merges the plan's boxes of the same track (box_track[b]: box b's track) into one each. */
static void merge_by_track(evr_skip_plan *pl, int *box_track)
{
    int b, c, n = 0;
    for (b = 0; b < pl->num_boxes; b++) {
        for (c = 0; c < n && box_track[c] != box_track[b]; c++) {}
        if (c == n) {
            memcpy(pl->lo[n], pl->lo[b], 3 * sizeof(float));
            memcpy(pl->hi[n], pl->hi[b], 3 * sizeof(float));
            box_track[n++] = box_track[b];
        } else {
            box_union(pl->lo[c], pl->hi[c], pl->lo[b], pl->hi[b]);
        }
    }
    pl->num_boxes = n;
}

/* The plan's still span: before the first and after the last change between consecutive keys of
 * any moving instance's track (with a hundredth of a key interval to spare, so that a time's
 * float key position never lands in the interval of a change). */
static void still_span(const evr_render_scene *rs, const evr_skip_tracker *t,
                       const evr_deform_keys *dk, evr_skip_plan *pl)
{
    int i, j;
    pl->still_before = 2.0f;
    pl->still_after = -1.0f;
    for (i = 0; i < rs->num_instances; i++) {
        const int tr = rs->instances[i].track, d = rs->instances[i].deform;
        if (d >= 0 && dk && d < dk->num_deforms && dk->moved[d]) {
            const evr_deform_view *v = &dk->views[d];
            const size_t per = 3 * (size_t)v->num_vertices;
            for (j = 0; j + 1 < v->num_keys; j++) {
                if (!memcmp(v->positions + j * per, v->positions + (j + 1) * per,
                            per * sizeof(float)) &&
                    !memcmp(v->normals + j * per, v->normals + (j + 1) * per, per * sizeof(float)))
                    continue;
                pl->still_before =
                    fminf(pl->still_before, ((float)j - 0.01f) / (float)(v->num_keys - 1));
                pl->still_after =
                    fmaxf(pl->still_after, ((float)j + 1.01f) / (float)(v->num_keys - 1));
            }
        }
        if (!t->moved[tr]) continue;
        const evr_motion_track tk = evr_rs_track(rs, tr);
        for (j = 0; j + 1 < tk.n; j++) {
            if (evr_motion_key_same(&tk.keys[j], &tk.keys[j + 1])) continue;
            pl->still_before = fminf(pl->still_before, ((float)j - 0.01f) / (float)(tk.n - 1));
            pl->still_after = fmaxf(pl->still_after, ((float)j + 1.01f) / (float)(tk.n - 1));
        }
    }
}

void evr_skip_plan_build(evr_skip_tracker *t, const evr_scene *s, const evr_render_scene *rs,
                         const evr_deform_keys *dk, int enabled, evr_skip_plan *pl)
{
    int i, tr, per_track = 0;
    int box_track[EVR_SKIP_MAX_BOXES];
    memset(pl, 0, sizeof *pl);
    pl->pad = rs->ray_eps;
    /* the camera and the lights must hold still: inside the segment to cache, and since the
     * previous segment too to reuse */
    int cam = rs->camera_track, cache = rs->track_count[cam] == 1, still = !t->moved[cam];
    for (i = 0; i < rs->num_lights; i++) {
        tr = rs->lights[i].track;
        if (tr < 0) continue;
        if (rs->track_count[tr] != 1) cache = 0;
        if (t->moved[tr]) still = 0;
    }
    /* still spans with and without skipping: brute force traces their samples at the same times */
    pl->spans = cache;
    still_span(rs, t, dk, pl);
    if (!enabled) return;
    /* a box per moving instance; once they are too many, a box per moving track */
    for (i = 0; i < rs->num_instances; i++) {
        float lo[3], hi[3];
        int b = pl->num_boxes;
        tr = rs->instances[i].track;
        if (!instance_moved(t, rs, dk, i)) continue;
        instance_box(t, s, rs, dk, i, lo, hi);
        if (per_track)
            for (b = 0; b < pl->num_boxes && box_track[b] != tr; b++) {}
        if (b == EVR_SKIP_MAX_BOXES && !per_track) {
            per_track = 1;
            merge_by_track(pl, box_track);
            for (b = 0; b < pl->num_boxes && box_track[b] != tr; b++) {}
        }
        if (b < pl->num_boxes) {
            box_union(pl->lo[b], pl->hi[b], lo, hi);
        } else if (b < EVR_SKIP_MAX_BOXES) {
            memcpy(pl->lo[b], lo, sizeof lo);
            memcpy(pl->hi[b], hi, sizeof hi);
            box_track[b] = tr;
            pl->num_boxes++;
        } else { /* too many moving things to bound: trace all */
            pl->num_boxes = 0;
            return;
        }
    }
    /* a box per instance: each also a tree of parts, as many as fit */
    if (!per_track && pl->num_boxes > 0 && t->mesh_parts) {
        int leaves = EVR_SKIP_MESH_PARTS;
        track_sweep *ts = malloc(sizeof *ts);
        float(*deformed)[6] =
            dk && dk->num_deforms ? malloc(sizeof *deformed * EVR_SKIP_MESH_PARTS) : NULL;
        while (leaves > 1 && (2 * leaves - 1) * pl->num_boxes > EVR_SKIP_MAX_PARTS) leaves /= 2;
        for (int j = 0, nb = 0; ts && leaves > 1 && j < rs->num_instances; j++)
            if (instance_moved(t, rs, dk, j))
                add_parts(t, s, rs, dk, j, leaves, pl, nb++, ts, deformed);
        free(deformed);
        free(ts);
    }
    pl->cache = cache;
    pl->reuse = cache && still;
}

/* Largest distance a point of box [lo, hi] (object space) moves between keys a and b: a point of
 * the box is a convex combination of its corners, and the keys' transforms are affine. */
static float corner_move(const float lo[3], const float hi[3], const evr_motion_key *a,
                         const evr_motion_key *b)
{
    evr_m34 ma = evr_motion_key_matrix(a), mb = evr_motion_key_matrix(b);
    float d = 0.0f;
    int c;
    for (c = 0; c < 8; c++) {
        evr_v3 p = evr_v3_make(c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]);
        evr_v3 q = evr_v3_sub(evr_m34_point(&mb, p), evr_m34_point(&ma, p));
        d = fmaxf(d, sqrtf(evr_v3_dot(q, q)));
    }
    return d;
}

void evr_adapt_plan_build(const evr_skip_tracker *t, const evr_scene *s, const evr_render_scene *rs,
                          const evr_deform_keys *dk, const evr_adapt_params *ap, double seconds,
                          evr_adapt_plan *pl)
{
    int i, k;
    memset(pl, 0, sizeof *pl);
    pl->pad = rs->ray_eps;
    int cam = rs->camera_track;
    if (rs->track_count[cam] != 1 || t->moved[cam]) pl->all_min = 1;
    for (i = 0; i < rs->num_lights; i++) {
        int tr = rs->lights[i].track;
        if (tr >= 0 && (rs->track_count[tr] != 1 || t->moved[tr])) pl->all_min = 1;
    }
    if (pl->all_min) return;
    /* a world displacement d at distance r from the camera moves the image by at most
     * d / r * f_px * (1 + tx^2 + ty^2) pixels (the pinhole's largest stretch, at the corners);
     * an orthographic camera's image by d / (the pixel's size) */
    evr_m34 pose = evr_rs_camera_pose(rs, 0.0f);
    evr_v3 eye = evr_v3_make(pose.m[0][3], pose.m[1][3], pose.m[2][3]);
    const float ty = rs->camera.tan_half_y, tx = ty * rs->camera.aspect;
    const float px_per_rad = 0.5f * (float)rs->camera.height / ty * (1.0f + tx * tx + ty * ty);
    for (i = 0; i < rs->num_instances; i++) {
        int tr = rs->instances[i].track, b, di = rs->instances[i].deform;
        if (!instance_moved(t, rs, dk, i)) continue;
        float lo[3], hi[3];
        local_box(s, rs, dk, i, lo, hi);
        float blo[3], bhi[3], r2 = 0.0f, move = 0.0f, jump = 0.0f;
        instance_box(t, s, rs, dk, i, blo, bhi);
        for (k = 0; k < 3; k++) { /* distance from the camera to the box */
            const float e = k == 0 ? eye.x : k == 1 ? eye.y : eye.z;
            const float d = e < blo[k] ? blo[k] - e : e > bhi[k] ? e - bhi[k] : 0.0f;
            r2 += d * d;
        }
        const evr_motion_track tk = evr_rs_track(rs, tr);
        for (k = 0; k + 1 < tk.n; k++)
            move = fmaxf(move, corner_move(lo, hi, &tk.keys[k], &tk.keys[k + 1]));
        if (t->prev_count[tr] > 0) jump = corner_move(lo, hi, &t->prev_last[tr], &tk.keys[0]);
        const float r = sqrtf(r2);
        /* keys are close (< 120 degrees apart, 1e-5 of the scene from the curves): 1.25 covers
         * a point's arc between keys being longer than its chord */
        float speed = tk.n > 1 ? 1.25f * move * (float)(tk.n - 1) / (float)seconds : 0.0f;
        if (di >= 0 && dk && di < dk->num_deforms) { /* and the vertices' own motion (a track
                                                      * stretches it by at most its largest
                                                      * column sum) */
            const evr_deform_view *v = &dk->views[di];
            float stretch = 0.0f;
            for (k = 0; k < tk.n; k++) {
                const evr_m34 mk = evr_motion_key_matrix(&tk.keys[k]);
                for (int c = 0; c < 3; c++)
                    stretch =
                        fmaxf(stretch, fabsf(mk.m[0][c]) + fabsf(mk.m[1][c]) + fabsf(mk.m[2][c]));
            }
            if (v->num_keys > 1)
                speed += 1.25f * stretch * dk->motion[di].move * (float)(v->num_keys - 1) /
                         (float)seconds;
            jump += stretch * dk->motion[di].jump;
        }
        float jump_px;
        if (rs->camera.ortho) { /* parallel rays: a displacement moves the image as far anywhere */
            const float px_per_unit = 1.0f / evr_camera_pixel_size(&rs->camera, 0.0f);
            jump_px = jump * px_per_unit;
            speed *= px_per_unit;
        } else {
            jump_px = jump * px_per_rad / r;
            speed = r > 0.0f ? speed * px_per_rad / r : INFINITY;
        }
        if (!(speed >= 0.0f)) speed = INFINITY;
        if (pl->num_boxes < EVR_SKIP_MAX_BOXES) {
            b = pl->num_boxes++;
            memcpy(pl->lo[b], blo, sizeof blo);
            memcpy(pl->hi[b], bhi, sizeof bhi);
            pl->speed[b] = 0.0f;
        } else { /* too many: the last box holds the rest */
            b = EVR_SKIP_MAX_BOXES - 1;
            box_union(pl->lo[b], pl->hi[b], blo, bhi);
        }
        pl->speed[b] = fmaxf(pl->speed[b], speed);
        if (!(jump_px <= EVR_ADAPT_PX_PER_FRAC * ap->frac)) pl->jump[b] = 1;
    }
}
