/* Framing: see framing.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/framing.h"

#define FRAME_UNIFORM 65        /* times spread over the animation */
#define FRAME_MAX_TIMES 1024    /* times in all, key times included */
#define FRAME_DEFORM_TIMES 17   /* times a deforming instance is evaluated at, at most */
#define FRAME_DEFORM_BUDGET 8e6 /* vertex evaluations for deforming instances, at most */
#define FRAME_TRIANGLES 2000000 /* triangles the direction's choice looks at, at most */

static void grow(evr_v3 *lo, evr_v3 *hi, evr_v3 p)
{
    lo->x = fminf(lo->x, p.x);
    lo->y = fminf(lo->y, p.y);
    lo->z = fminf(lo->z, p.z);
    hi->x = fmaxf(hi->x, p.x);
    hi->y = fmaxf(hi->y, p.y);
    hi->z = fmaxf(hi->z, p.z);
}

static void grow_box(evr_v3 *lo, evr_v3 *hi, const evr_m34 *m, evr_v3 a, evr_v3 b)
{
    for (int c = 0; c < 8; c++)
        grow(
            lo, hi,
            evr_m34_point(m, evr_v3_make(c & 1 ? b.x : a.x, c & 2 ? b.y : a.y, c & 4 ? b.z : a.z)));
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The times the bounds are taken at: FRAME_UNIFORM spread over [t0, t1] and the key times of
 * every curve inside it (every k-th of them when there are too many), sorted. */
static double *frame_times(const evr_scene *s, double t0, double t1, int *count)
{
    int nkeys = 0, n = 0, i;
    for (i = 0; i < s->num_nodes; i++) {
        const evr_node *nd = &s->nodes[i];
        nkeys += nd->t_curve.num_keys + nd->r_curve.num_keys + nd->s_curve.num_keys +
                 nd->w_curve.num_keys;
    }
    const int stride =
        nkeys > FRAME_MAX_TIMES - FRAME_UNIFORM
            ? (nkeys + FRAME_MAX_TIMES - FRAME_UNIFORM - 1) / (FRAME_MAX_TIMES - FRAME_UNIFORM)
            : 1;
    double *t = malloc(sizeof *t * (FRAME_MAX_TIMES + 1));
    if (!t) return NULL;
    for (i = 0; i < FRAME_UNIFORM; i++) t[n++] = t0 + (t1 - t0) * i / (FRAME_UNIFORM - 1);
    for (i = 0, nkeys = 0; i < s->num_nodes; i++) {
        const evr_curve *cv[4] = {&s->nodes[i].t_curve, &s->nodes[i].r_curve, &s->nodes[i].s_curve,
                                  &s->nodes[i].w_curve};
        for (int c = 0; c < 4; c++)
            for (int k = 0; k < cv[c]->num_keys; k++, nkeys++)
                if (nkeys % stride == 0 && n < FRAME_MAX_TIMES && cv[c]->times[k] > t0 &&
                    cv[c]->times[k] < t1)
                    t[n++] = cv[c]->times[k];
    }
    qsort(t, (size_t)n, sizeof *t, cmp_double);
    *count = n;
    return t;
}

/* Grows [lo, hi] by deforming instance i at time t (its vertices, placed by its node unless
 * skinned). Returns 0 when out of memory. */
static int grow_deformed(const evr_scene *s, int i, double t, float *pos, evr_v3 *lo, evr_v3 *hi)
{
    const evr_mesh *m = &s->meshes[s->instances[i].mesh];
    if (!evr_instance_deformed_at(s, i, t, pos, NULL)) return 0;
    evr_v3 a = evr_v3_make(INFINITY, INFINITY, INFINITY), b = evr_v3_scale(a, -1.0f);
    for (uint32_t v = 0; v < m->num_vertices; v++)
        grow(&a, &b, evr_v3_make(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]));
    if (!(a.x <= b.x)) return 1;
    evr_m34 w = m->skin ? evr_m34_identity() : evr_node_world_at(s, s->instances[i].node, t);
    grow_box(lo, hi, &w, a, b);
    return 1;
}

int evr_frame_swept_bounds(const evr_scene *s, double t0, double t1, evr_v3 *lo, evr_v3 *hi)
{
    int nt = 1, i, k, ok = 1;
    double one = t0, *times = &one;
    *lo = s->bounds_min;
    *hi = s->bounds_max;
    if (s->num_instances == 0) return 0;
    if (t1 > t0 && !(times = frame_times(s, t0, t1, &nt))) return 0;
    evr_v3 a = evr_v3_make(INFINITY, INFINITY, INFINITY), b = evr_v3_scale(a, -1.0f);
    for (i = 0; i < s->num_instances && ok; i++) {
        const evr_instance *in = &s->instances[i];
        const evr_mesh *m = &s->meshes[in->mesh];
        if (m->num_vertices == 0) continue;
        if (evr_instance_deforms(s, i)) {
            float *pos = malloc(sizeof *pos * 3 * (size_t)m->num_vertices);
            const int animated = evr_instance_deform_animated(s, i) ||
                                 (!m->skin && evr_node_chain_animated(s, in->node));
            int steps = animated ? FRAME_DEFORM_TIMES : 1;
            while (steps > 2 &&
                   (double)steps * m->num_vertices * s->num_instances > FRAME_DEFORM_BUDGET)
                steps = (steps + 1) / 2;
            if (nt < steps) steps = nt;
            ok = pos != NULL;
            for (k = 0; k < steps && ok; k++)
                ok = grow_deformed(s, i, times[steps > 1 ? k * (nt - 1) / (steps - 1) : 0], pos, &a,
                                   &b);
            free(pos);
            continue;
        }
        const int steps = evr_node_chain_animated(s, in->node) ? nt : 1;
        for (k = 0; k < steps; k++) {
            evr_m34 w = evr_node_world_at(s, in->node, times[k]);
            grow_box(&a, &b, &w, m->bounds_min, m->bounds_max);
        }
    }
    if (times != &one) free(times);
    if (!ok || !(a.x <= b.x && a.y <= b.y && a.z <= b.z) || !isfinite(a.x + a.y + a.z) ||
        !isfinite(b.x + b.y + b.z))
        return 0;
    *lo = a;
    *hi = b;
    return 1;
}

/* ---- the direction ---- */

/* Candidate views in order of preference: azimuth from +Z towards +X and elevation, degrees.
 * The front first, then turning around it, higher views before lower ones at each azimuth;
 * straight down and views from below last. */
static const float candidates[][2] = {
    {0, 0},   {0, 30},   {45, 0},   {-45, 0},   {45, 30},   {-45, 30},  {90, 0},  {-90, 0},
    {90, 30}, {-90, 30}, {135, 0},  {-135, 0},  {135, 30},  {-135, 30}, {180, 0}, {180, 30},
    {0, 90},  {0, -30},  {90, -30}, {-90, -30}, {180, -30}, {0, -90},
};
#define NUM_CANDIDATES ((int)(sizeof candidates / sizeof candidates[0]))

static evr_v3 candidate_dir(int c)
{
    const double az = candidates[c][0] * EVR_PI_D / 180.0, el = candidates[c][1] * EVR_PI_D / 180.0;
    if (fabs(candidates[c][1]) == 90.0f) return evr_v3_make(0, candidates[c][1] > 0 ? 1 : -1, 0);
    return evr_v3_make((float)(sin(az) * cos(el)), (float)sin(el), (float)(cos(az) * cos(el)));
}

evr_v3 evr_frame_direction(const evr_scene *s, double t)
{
    double area[NUM_CANDIDATES], best = 0.0;
    evr_v3 dir[NUM_CANDIDATES];
    long total = 0;
    int c, i;
    for (c = 0; c < NUM_CANDIDATES; c++) {
        area[c] = 0.0;
        dir[c] = candidate_dir(c);
    }
    for (i = 0; i < s->num_instances; i++) total += s->meshes[s->instances[i].mesh].num_triangles;
    const long stride =
        total > FRAME_TRIANGLES ? (total + FRAME_TRIANGLES - 1) / FRAME_TRIANGLES : 1;
    long seen = 0;
    for (i = 0; i < s->num_instances; i++) {
        const evr_instance *in = &s->instances[i];
        const evr_mesh *m = &s->meshes[in->mesh];
        const int both = m->material >= 0 && m->material < s->num_materials &&
                         s->materials[m->material].p.double_sided;
        /* a skinned mesh's vertices are where its bind pose puts them */
        const evr_m34 w = m->skin ? evr_m34_identity() : evr_node_world_at(s, in->node, t);
        for (uint32_t f = 0; f < m->num_triangles; f++, seen++) {
            if (seen % stride) continue;
            evr_v3 p[3];
            for (int k = 0; k < 3; k++) {
                const float *v = &m->positions[3 * m->indices[3 * f + k]];
                p[k] = evr_m34_point(&w, evr_v3_make(v[0], v[1], v[2]));
            }
            /* twice the area times the unit normal */
            const evr_v3 n = evr_v3_cross(evr_v3_sub(p[1], p[0]), evr_v3_sub(p[2], p[0]));
            for (c = 0; c < NUM_CANDIDATES; c++) {
                const double d = evr_v3_dot(n, dir[c]);
                area[c] += d > 0.0 ? d : (both ? -d : 0.0);
            }
        }
    }
    for (c = 0; c < NUM_CANDIDATES; c++)
        if (area[c] > best) best = area[c];
    for (c = 0; c < NUM_CANDIDATES; c++)
        if (area[c] >= 0.99 * best) break;
    return dir[c < NUM_CANDIDATES ? c : 0];
}

/* ---- poses ---- */

evr_m34 evr_frame_look_along(evr_v3 pos, evr_v3 look, evr_v3 up)
{
    evr_m34 m;
    evr_v3 z = evr_v3_norm(evr_v3_scale(look, -1.0f)), x, y;
    if (evr_v3_len(z) == 0.0f) z = evr_v3_make(0, 0, 1);
    x = evr_v3_cross(up, z);
    if (evr_v3_len(x) < 1e-6f)
        x = evr_v3_cross(fabsf(z.y) < 0.9f ? evr_v3_make(0, 1, 0) : evr_v3_make(1, 0, 0), z);
    x = evr_v3_norm(x);
    y = evr_v3_cross(z, x);
    m.m[0][0] = x.x;
    m.m[0][1] = y.x;
    m.m[0][2] = z.x;
    m.m[0][3] = pos.x;
    m.m[1][0] = x.y;
    m.m[1][1] = y.y;
    m.m[1][2] = z.y;
    m.m[1][3] = pos.y;
    m.m[2][0] = x.z;
    m.m[2][1] = y.z;
    m.m[2][2] = z.z;
    m.m[2][3] = pos.z;
    return m;
}

/* World up for a camera looking along look: +Y, or for a view (nearly) straight down -Z and
 * straight up +Z. */
static evr_v3 up_for(evr_v3 look)
{
    const evr_v3 l = evr_v3_norm(look);
    if (l.y < -0.99f) return evr_v3_make(0, 0, -1);
    if (l.y > 0.99f) return evr_v3_make(0, 0, 1);
    return evr_v3_make(0, 1, 0);
}

evr_m34 evr_frame_look_at(evr_v3 from, evr_v3 to)
{
    const evr_v3 look = evr_v3_sub(to, from);
    return evr_frame_look_along(from, look, up_for(look));
}

/* The distance from the centre c at which the camera with basis x, y, z (z towards the camera)
 * sees every corner of [lo, hi] within 90% of the image's half extents tx, ty (at unit
 * distance). */
static float fit_distance(evr_v3 lo, evr_v3 hi, evr_v3 c, evr_v3 x, evr_v3 y, evr_v3 z, float tx,
                          float ty, float gap)
{
    const float margin = 0.9f;
    float d = 0.0f, zmax = -INFINITY;
    for (int k = 0; k < 8; k++) {
        const evr_v3 p = evr_v3_make(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
        const evr_v3 r = evr_v3_sub(p, c);
        const float cx = fabsf(evr_v3_dot(r, x)), cy = fabsf(evr_v3_dot(r, y)),
                    cz = evr_v3_dot(r, z);
        d = fmaxf(d, cz + cx / (tx * margin));
        d = fmaxf(d, cz + cy / (ty * margin));
        zmax = fmaxf(zmax, cz);
    }
    return fmaxf(d, zmax + gap);
}

evr_m34 evr_frame_box(evr_v3 lo, evr_v3 hi, evr_v3 dir, float yfov, float aspect, int all_around,
                      float *dist)
{
    const evr_v3 c = evr_v3_scale(evr_v3_add(lo, hi), 0.5f);
    float r = 0.5f * evr_v3_len(evr_v3_sub(hi, lo));
    if (!(r > 0.0f) || !isfinite(r)) r = 1.0f;
    const float ty = tanf(0.5f * yfov), tx = ty * (aspect > 0.0f ? aspect : 1.0f);
    const evr_v3 look = evr_v3_scale(dir, -1.0f);
    const evr_m34 basis = evr_frame_look_along(c, look, up_for(look));
    float d = 0.0f;
    const int turns = all_around ? 16 : 1;
    for (int k = 0; k < turns; k++) { /* the basis turned about the vertical through c */
        const float a = (float)(2.0 * EVR_PI_D * k / turns), ca = cosf(a), sa = sinf(a);
        evr_v3 ax[3];
        for (int j = 0; j < 3; j++) {
            const evr_v3 v = evr_v3_make(basis.m[0][j], basis.m[1][j], basis.m[2][j]);
            ax[j] = evr_v3_make(ca * v.x + sa * v.z, v.y, -sa * v.x + ca * v.z);
        }
        d = fmaxf(d, fit_distance(lo, hi, c, ax[0], ax[1], ax[2], tx, ty, 0.01f * r));
    }
    if (dist) *dist = d;
    return evr_frame_look_along(evr_v3_add(c, evr_v3_scale(dir, d)), look, up_for(look));
}

float evr_camera_yfov(const evr_camera_desc *c, float aspect)
{
    if (c->xfov > 0.0f && aspect > 0.0f) return 2.0f * atanf(tanf(0.5f * c->xfov) / aspect);
    return c->yfov;
}
