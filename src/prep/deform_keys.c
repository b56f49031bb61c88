/* Per-segment vertex keys of the deforming instances (see deform_keys.h). */
#include "prep/deform_keys.h"
#include "par_pool.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Key times inside (t0, t1) of the curves the deformation follows (the joints' chains, the morph
 * weights): where a piecewise curve bends, the check must look. */
#define INNER_MAX 32
static void add_curve_times(const evr_curve *c, double t0, double t1, double *out, int *n)
{
    for (int k = 0; k < c->num_keys && *n < INNER_MAX; k++)
        if (c->times[k] > t0 && c->times[k] < t1) out[(*n)++] = c->times[k];
}
static int inner_times(const evr_scene *s, int inst, double t0, double t1, double *out)
{
    const evr_instance *in = &s->instances[inst];
    const evr_mesh *m = &s->meshes[in->mesh];
    int n = 0;
    if (m->morph && in->node >= 0 && in->node < s->num_nodes)
        add_curve_times(&s->nodes[in->node].w_curve, t0, t1, out, &n);
    for (int j = 0; m->skin && j < m->skin->num_joints; j++) {
        int node = m->skin->joint_nodes[j], guard = 0;
        while (node >= 0 && node < s->num_nodes && guard++ <= s->num_nodes) {
            const evr_node *nd = &s->nodes[node];
            add_curve_times(&nd->t_curve, t0, t1, out, &n);
            add_curve_times(&nd->r_curve, t0, t1, out, &n);
            add_curve_times(&nd->s_curve, t0, t1, out, &n);
            node = nd->parent;
        }
    }
    return n;
}

/* Largest distance between the positions of a and the interpolation of k0, k1 at fraction f. */
static float lerp_error(const float *a, const float *k0, const float *k1, float f, uint32_t nv)
{
    float worst = 0.0f;
    for (size_t i = 0; i < 3 * (size_t)nv; i += 3) {
        float d2 = 0.0f;
        for (int c = 0; c < 3; c++) {
            const float e = a[i + c] - (k0[i + c] + (k1[i + c] - k0[i + c]) * f);
            d2 += e * e;
        }
        if (!(d2 <= worst * worst)) worst = d2 == d2 ? sqrtf(d2) : INFINITY;
    }
    return worst;
}

/* Largest distance a vertex moves between position arrays a and b. */
static float max_move(const float *a, const float *b, uint32_t nv)
{
    float worst = 0.0f;
    for (size_t i = 0; i < 3 * (size_t)nv; i += 3) {
        const float dx = a[i] - b[i], dy = a[i + 1] - b[i + 1], dz = a[i + 2] - b[i + 2];
        const float d = sqrtf(dx * dx + dy * dy + dz * dz);
        if (!(d <= worst)) worst = d == d ? d : INFINITY;
    }
    return worst;
}

static int close_arrays(const float *a, const float *b, size_t n, float tol)
{
    for (size_t i = 0; i < n; i++)
        if (!(fabsf(a[i] - b[i]) <= tol)) return 0;
    return 1;
}

static void box_of(const float *p, uint32_t nv, float box[6])
{
    for (size_t i = 0; i < 3 * (size_t)nv; i += 3)
        for (int c = 0; c < 3; c++) { /* a NaN vertex widens nothing; no libm call */
            box[c] = p[i + c] < box[c] ? p[i + c] : box[c];
            box[3 + c] = p[i + c] > box[3 + c] ? p[i + c] : box[3 + c];
        }
}

static int grow(float **p, size_t *cap, size_t want)
{
    if (want <= *cap) return 1;
    size_t n = *cap ? *cap : 1024;
    while (n < want) n *= 2;
    float *q = realloc(*p, n * sizeof *q);
    if (!q) return 0;
    *p = q;
    *cap = n;
    return 1;
}

int evr_deform_tracker_init(evr_deform_tracker *t, const evr_scene *s, const evr_render_host *h)
{
    memset(t, 0, sizeof *t);
    t->num_deforms = h->num_deforms;
    if (!h->num_deforms) return 1;
    t->last = calloc((size_t)h->num_deforms, sizeof *t->last);
    t->last_box = calloc((size_t)h->num_deforms, sizeof *t->last_box);
    if (!t->last || !t->last_box) return 0;
    for (int d = 0; d < h->num_deforms; d++) {
        const evr_mesh *m = &s->meshes[s->instances[h->deform_instance[d]].mesh];
        if (!(t->last[d] = malloc(sizeof(float) * 6 * ((size_t)m->num_vertices + 1)))) return 0;
    }
    return 1;
}

void evr_deform_tracker_free(evr_deform_tracker *t)
{
    for (int d = 0; t->last && d < t->num_deforms; d++) free(t->last[d]);
    free(t->last);
    free(t->last_box);
    free(t->scratch);
    free(t->work);
    evr_par_pool_free(t->pool);
    memset(t, 0, sizeof *t);
}

void evr_deform_keys_free(evr_deform_keys *k)
{
    free(k->views);
    free(k->motion);
    free(k->moved);
    free(k->data);
    memset(k, 0, sizeof *k);
}

/* One evaluation cut into parts for the tracker's pool. */
typedef struct {
    const evr_scene *s;
    int inst, parts;
    double t;
    float *slot;
    uint32_t nv;
    int failed[EVR_DEFORM_PARTS];
} eval_job;

static void eval_part(void *ctx, int part, int thread)
{
    eval_job *j = ctx;
    size_t a, b;
    (void)thread;
    evr_par_share(j->nv, j->parts, part, &a, &b);
    j->failed[part] = !evr_instance_deformed_range(j->s, j->inst, j->t, (uint32_t)a, (uint32_t)b,
                                                   j->slot, j->slot + 3 * (size_t)j->nv);
}

/* Evaluates instance inst at time t into key slot (positions then normals, 6 nv floats), on the
 * tracker's threads when the mesh is large enough to pay for them. */
static int eval_at(evr_deform_tracker *t, const evr_scene *s, int inst, double time, float *slot,
                   uint32_t nv)
{
    if (nv >= 8192 && !t->pool && !t->pool_tried) { /* started for the first large mesh */
        t->pool_tried = 1;
        t->pool = evr_par_pool_new(evr_par_threads(EVR_DEFORM_PARTS)); /* NULL: on this thread */
    }
    const int threads = evr_par_pool_threads(t->pool);
    if (!t->pool || threads < 2 || nv < 8192)
        return evr_instance_deformed_at(s, inst, time, slot, slot + 3 * (size_t)nv);
    eval_job j;
    j.s = s;
    j.inst = inst;
    j.t = time;
    j.slot = slot;
    j.nv = nv;
    j.parts = threads < EVR_DEFORM_PARTS ? threads : EVR_DEFORM_PARTS;
    evr_par_pool_run(t->pool, j.parts, eval_part, &j);
    for (int k = 0; k < j.parts; k++)
        if (j.failed[k]) return 0;
    return 1;
}

/* Fits the keys of deform d into work (key-major, 6 nv floats a key); returns the count, 0 when
 * out of memory. */
static int fit_keys(evr_deform_tracker *t, const evr_scene *s, int inst, double t0, double t1,
                    float limit, int cap, uint32_t nv, float **work, size_t *work_cap)
{
    const size_t per = 6 * (size_t)nv;
    double inner[INNER_MAX];
    const int ninner = inner_times(s, inst, t0, t1, inner);
    const double span = t1 - t0;
    if (!grow(work, work_cap, 2 * per) || !eval_at(t, s, inst, t0, *work, nv)) return 0;
    if (!(span > 0.0) || cap < 2 || !evr_instance_deform_animated(s, inst)) return 1;
    if (!eval_at(t, s, inst, t1, *work + per, nv)) return 0;
    int n = 2;
    for (;;) {
        /* the midpoints of every interval: the keys added if the check fails */
        if (!grow(&t->scratch, &t->scratch_cap, (size_t)(n - 1) * per)) return 0;
        int ok = 1;
        for (int i = 0; i + 1 < n; i++) {
            float *mid = t->scratch + (size_t)i * per;
            if (!eval_at(t, s, inst, t0 + span * ((double)i + 0.5) / (double)(n - 1), mid, nv))
                return 0;
            if (ok && lerp_error(mid, *work + (size_t)i * per, *work + (size_t)(i + 1) * per, 0.5f,
                                 nv) > limit)
                ok = 0;
        }
        for (int k = 0; k < ninner && ok; k++) { /* where a curve bends */
            float *probe = t->scratch;           /* overwritten: only needed when ok stays */
            const double f = (inner[k] - t0) / span * (double)(n - 1);
            int i = (int)floor(f);
            if (i > n - 2) i = n - 2;
            if (!eval_at(t, s, inst, inner[k], probe, nv)) return 0;
            if (lerp_error(probe, *work + (size_t)i * per, *work + (size_t)(i + 1) * per,
                           (float)(f - i), nv) > limit)
                ok = 0;
        }
        if (ok && n == 2) {
            /* still in the segment: one key (the quarter points and the bends checked too) */
            float still_tol = limit * 1e-3f;
            int still = max_move(*work, *work + per, nv) <= still_tol;
            for (int q = 1; q < 4 && still; q++) {
                if (!eval_at(t, s, inst, t0 + span * 0.25 * q, t->scratch, nv)) return 0;
                still = max_move(*work, t->scratch, nv) <= still_tol;
            }
            for (int k = 0; k < ninner && still; k++) {
                if (!eval_at(t, s, inst, inner[k], t->scratch, nv)) return 0;
                still = max_move(*work, t->scratch, nv) <= still_tol;
            }
            if (still) return 1;
        }
        if (ok || n >= cap) return n;
        if (ok == 0 && !grow(work, work_cap, (size_t)(2 * n - 1) * per)) return 0;
        if (ok == 0 && ninner) { /* the probe overwrote the first midpoint */
            if (!eval_at(t, s, inst, t0 + span * 0.5 / (double)(n - 1), t->scratch, nv)) return 0;
        }
        for (int i = n - 1; i >= 1; i--)
            memmove(*work + (size_t)(2 * i) * per, *work + (size_t)i * per, per * sizeof(float));
        for (int i = 0; i + 1 < n; i++)
            memcpy(*work + (size_t)(2 * i + 1) * per, t->scratch + (size_t)i * per,
                   per * sizeof(float));
        n = 2 * n - 1;
    }
}

int evr_deform_keys_make(evr_deform_tracker *t, const evr_scene *s, const evr_render_host *h,
                         double t0, double t1, float tol, int max_keys, evr_deform_keys *out)
{
    const int nd = h->num_deforms;
    const float size = h->scene_size > 0.0f ? h->scene_size : 1.0f;
    const float limit = tol * size, same = 1e-9f * size;
    int cap = 2;
    while ((cap - 1) * 2 + 1 <= max_keys) cap = (cap - 1) * 2 + 1;
    if (max_keys < 2) cap = 1;
    if (out->num_deforms != nd) {
        evr_deform_keys_free(out);
        out->views = calloc((size_t)nd + 1, sizeof *out->views);
        out->motion = calloc((size_t)nd + 1, sizeof *out->motion);
        out->moved = calloc((size_t)nd + 1, sizeof *out->moved);
        if (!out->views || !out->motion || !out->moved) return 0;
        out->num_deforms = nd;
    }
    /* first pass: fit each deform's keys into the data, key-major; then split each into its
     * positions and normals blocks */
    size_t used = 0;
    size_t *offset = malloc(sizeof *offset * ((size_t)nd + 1));
    int *count = malloc(sizeof *count * ((size_t)nd + 1));
    if (!offset || !count) goto nomem;
    for (int d = 0; d < nd; d++) {
        const int inst = h->deform_instance[d];
        const uint32_t nv = s->meshes[s->instances[inst].mesh].num_vertices;
        const size_t per = 6 * (size_t)nv;
        int n = fit_keys(t, s, inst, t0, t1, limit, cap, nv, &t->work, &t->work_cap);
        float *work = t->work;
        if (n < 1) goto nomem;
        /* a key as close to the one before is that key (a still stretch is still bit for
         * bit); a segment that holds the previous segment's last pose keeps it exactly */
        for (int k = 1; k < n; k++)
            if (close_arrays(work + (size_t)k * per, work + (size_t)(k - 1) * per, 3 * nv, same))
                memcpy(work + (size_t)k * per, work + (size_t)(k - 1) * per, per * sizeof(float));
        if (n == 1 && t->have_prev && close_arrays(work, t->last[d], 3 * nv, same))
            memcpy(work, t->last[d], per * sizeof(float));
        if (!grow(&out->data, &out->cap, used + (size_t)n * per)) goto nomem;
        evr_deform_motion *mo = &out->motion[d];
        float box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
        mo->move = 0.0f;
        for (int k = 0; k < n; k++) {
            const float *key = work + (size_t)k * per;
            memcpy(out->data + used + (size_t)k * 3 * nv, key, 3 * nv * sizeof(float));
            memcpy(out->data + used + (size_t)(n + k) * 3 * nv, key + 3 * nv,
                   3 * nv * sizeof(float));
            box_of(key, nv, box);
            if (k) mo->move = fmaxf(mo->move, max_move(key - per, key, nv));
        }
        mo->jump = 0.0f;
        mo->moved = n > 1;
        if (t->have_prev) {
            mo->jump = max_move(t->last[d], work, nv);
            if (memcmp(t->last[d], work, 3 * nv * sizeof(float)) != 0) mo->moved = 1;
            for (int c = 0; c < 3; c++) {
                box[c] = fminf(box[c], t->last_box[d][c]);
                box[3 + c] = fmaxf(box[3 + c], t->last_box[d][3 + c]);
            }
        }
        memcpy(mo->lo, box, sizeof mo->lo);
        memcpy(mo->hi, box + 3, sizeof mo->hi);
        out->moved[d] = mo->moved;
        /* the last key is the next segment's previous pose */
        const float *last = work + (size_t)(n - 1) * per;
        memcpy(t->last[d], last, per * sizeof(float));
        float lb[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
        box_of(last, nv, lb);
        memcpy(t->last_box[d], lb, sizeof lb);
        offset[d] = used;
        count[d] = n;
        used += (size_t)n * per;
    }
    for (int d = 0; d < nd; d++) { /* pointers once the data has stopped moving */
        const uint32_t nv = s->meshes[s->instances[h->deform_instance[d]].mesh].num_vertices;
        out->views[d].num_keys = count[d];
        out->views[d].num_vertices = nv;
        out->views[d].positions = out->data + offset[d];
        out->views[d].normals = out->data + offset[d] + (size_t)count[d] * 3 * nv;
    }
    t->have_prev = 1;
    free(offset);
    free(count);
    return 1;
nomem:
    free(offset);
    free(count);
    return 0;
}
