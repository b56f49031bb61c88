/* The GPU backend's BVH and traversal (src/cuda), run on the host: against Embree built exactly
 * as the CPU backend builds it (instances grouped: the static ones baked into world space, those
 * of each moving node together), on the built-in scenes during motion (a saccade, a blink, the
 * moving square) and on a synthetic scene of many instances, for both node layouts (and there
 * also with the static instances instanced, not baked, as both backends do past
 * EVR_STATIC_BAKE_LIMIT triangles: a group per static instance, one tree per mesh):
 *   - the GPU BVH groups the instances as the CPU backend does (the eye's groups by name);
 *   - closest hits of camera rays, shadow-like rays between scene points and random rays agree
 *     (hit or miss, instance, triangle, distance to 1e-4, barycentrics); disagreements are
 *     allowed only for rays within a float epsilon of an edge or at a tie between surfaces,
 *     and must stay below 1e-4 of the rays;
 *   - occlusion (evr_trace_any) agrees with rtcOccluded1 in the same way;
 *   - the top level's per-segment group boxes hold the group at every time of the segment
 *     (also for synthetic tracks with large rotations, scaling and skew);
 *   - no ray leaks through a closed mesh, not even when aimed exactly at its vertices;
 *   - deforming meshes (morph targets on a moving and on a still node, a skin): their trees,
 *     made per segment from the vertex keys, agree with Embree's time steps (the CPU backend's
 *     way) at many ray times; a segment whose vertices hold still keeps its trees bit for bit;
 *     the top level's boxes hold every vertex at every time;
 *   - the rigid scenes' structures are what they were before deforming meshes (eye: node and
 *     triangle counts; Debian 12's Embree 3.13.5).
 * Prints traversal speed next to Embree's, and the deforming trees' build time, for
 * information. */
#include "check.h"
#include "backend.h"
#include "cpu/cpu_gi.h"
#include "core/rng.h"
#include "cuda/gpu_bvh.h"
#include "cuda/gpu_traverse.h"
#include "prep/deform_keys.h"
#include "prep/swept_bounds.h"
#include "scene/scene.h"

#include <embree3/rtcore.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Fewer rays where the build is slow (sanitizers, no optimization). */
#if defined(__SANITIZE_ADDRESS__)
#define RAY_SCALE 8
#elif !defined(__OPTIMIZE__)
#define RAY_SCALE 4
#else
#define RAY_SCALE 1
#endif

#define MAX_KEYS 65    /* as the segment loop (sim_state.h) */
#define EDGE_EPS 1e-4f /* barycentric distance to an edge that counts as "on the edge" */
#define MAX_MISMATCH_RATE 1e-4

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- the segment's motion, as src/sim.c's compute_motion makes it ---- */

typedef struct {
    evr_motion_key *keys;
    int *offset, *count;
} motion;

static void motion_compute(const evr_scene *s, int camera, double t0, double t1, motion *m)
{
    int i, off = 0;
    int *used = calloc((size_t)s->num_nodes + 1, sizeof(int));
    m->keys = malloc(sizeof *m->keys * ((size_t)s->num_nodes + 1) * MAX_KEYS);
    m->offset = malloc(sizeof(int) * ((size_t)s->num_nodes + 1));
    m->count = malloc(sizeof(int) * ((size_t)s->num_nodes + 1));
    for (i = 0; i < s->num_instances; i++) used[s->instances[i].node] = 1;
    for (i = 0; i < s->num_lights; i++)
        if (s->lights[i].node >= 0) used[s->lights[i].node] = 1;
    if (s->cameras[camera].node >= 0) used[s->cameras[camera].node] = 1;
    for (i = 0; i <= s->num_nodes; i++) {
        evr_motion_key *k = m->keys + off;
        int n = 1;
        if (i < s->num_nodes && used[i]) {
            n = evr_node_motion_keys(s, i, t0, t1, 1e-5f, k, MAX_KEYS);
        } else {
            evr_m34 id = evr_m34_identity();
            *k = evr_motion_key_from_matrix(&id);
        }
        m->offset[i] = off;
        m->count[i] = n;
        off += n;
    }
    free(used);
}

static void motion_free(motion *m)
{
    free(m->keys);
    free(m->offset);
    free(m->count);
}

/* ---- the Embree reference, built as src/cpu/cpu_backend.c builds it ---- */

typedef struct {
    RTCDevice dev;
    RTCScene top;
    int num_groups;
    RTCScene *group_scenes;
    int *group_track, *group_first, *members;
    int *group_instanced; /* 1: a static instance of its mesh's scene (past the bake limit), or
                             a deforming mesh on a node that never moves: its node's transform */
    int *group_deform;    /* a deforming mesh's group: its deform view, -1: none */
} reference;

static void to_embree(const evr_motion_key *k, struct RTCQuaternionDecomposition *q)
{
    rtcInitQuaternionDecomposition(q);
    q->scale_x = k->scale[0];
    q->scale_y = k->scale[1];
    q->scale_z = k->scale[2];
    q->skew_xy = k->skew[0];
    q->skew_xz = k->skew[1];
    q->skew_yz = k->skew[2];
    q->quaternion_r = k->rot.w;
    q->quaternion_i = k->rot.x;
    q->quaternion_j = k->rot.y;
    q->quaternion_k = k->rot.z;
    q->translation_x = k->trans.x;
    q->translation_y = k->trans.y;
    q->translation_z = k->trans.z;
}

static void add_mesh_geometry(RTCDevice dev, RTCScene sc, const evr_mesh *m, const evr_m34 *xf,
                              unsigned geom_id)
{
    uint32_t v;
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                        3 * sizeof(float), m->num_vertices);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(unsigned), m->num_triangles);
    for (v = 0; v < m->num_vertices; v++) {
        evr_v3 p =
            evr_v3_make(m->positions[3 * v], m->positions[3 * v + 1], m->positions[3 * v + 2]);
        if (xf) p = evr_m34_point(xf, p);
        vb[3 * v] = p.x;
        vb[3 * v + 1] = p.y;
        vb[3 * v + 2] = p.z;
    }
    memcpy(ib, m->indices, sizeof(unsigned) * 3 * m->num_triangles);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(sc, g, geom_id);
    rtcReleaseGeometry(g);
}

static int node_never_moves(const evr_scene *s, int node)
{
    for (; node >= 0; node = s->nodes[node].parent)
        if (s->nodes[node].animated) return 0;
    return 1;
}

/* A deforming mesh's vertex keys as the geometry's time steps (cpu_backend.c's update_deform). */
static void add_deform_geometry(RTCDevice dev, RTCScene sc, const evr_mesh *m,
                                const evr_deform_view *v)
{
    int k;
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(unsigned), m->num_triangles);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    rtcSetGeometryTimeStepCount(g, (unsigned)v->num_keys);
    for (k = 0; k < v->num_keys; k++) {
        float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, (unsigned)k,
                                            RTC_FORMAT_FLOAT3, 3 * sizeof(float), v->num_vertices);
        memcpy(vb, v->positions + (size_t)k * 3 * v->num_vertices,
               sizeof(float) * 3 * v->num_vertices);
    }
    memcpy(ib, m->indices, sizeof(unsigned) * 3 * m->num_triangles);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(sc, g, 0);
    rtcReleaseGeometry(g);
}

/* instance_static: the static instances are not baked but each a group of its own, an instance
 * of its mesh's scene with its node's transform (the CPU backend past EVR_STATIC_BAKE_LIMIT).
 * rs: the segment's deforming meshes' vertex keys (NULL: the scene has none): each such mesh a
 * group of its own (prep/instance_groups.h), in its node's space (a skin: world space), its
 * keys as time steps. */
static void reference_build(reference *r, const evr_scene *s, const motion *mo, int instance_static,
                            const evr_render_scene *rs)
{
    int n = s->num_instances, i, j, g, k;
    int *group_of = malloc(sizeof(int) * ((size_t)n + 1));
    memset(r, 0, sizeof *r);
    r->dev = rtcNewDevice(NULL);
    r->group_track = malloc(sizeof(int) * ((size_t)n + 1));
    r->group_first = calloc((size_t)n + 2, sizeof(int));
    r->members = malloc(sizeof(int) * ((size_t)n + 1));
    r->group_instanced = calloc((size_t)n + 1, sizeof(int));
    r->group_deform = malloc(sizeof(int) * ((size_t)n + 1));
    for (i = 0; i < n; i++) r->group_deform[i] = -1;
    for (i = 0; i < n; i++) {
        int node = s->instances[i].node, track = node_never_moves(s, node) ? -1 : node;
        if (rs && rs->instances[i].deform >= 0) { /* as the CPU backend's group_moves */
            const int skinned = s->meshes[s->instances[i].mesh].skin != NULL;
            r->group_deform[r->num_groups] = rs->instances[i].deform;
            r->group_track[r->num_groups] = skinned ? -1 : track;
            r->group_instanced[r->num_groups] = !skinned && track < 0;
            group_of[i] = r->num_groups++;
            continue;
        }
        if (track < 0 && instance_static) {
            r->group_instanced[r->num_groups] = 1;
            r->group_track[r->num_groups] = -1;
            group_of[i] = r->num_groups++;
            continue;
        }
        for (g = 0; g < r->num_groups && (r->group_track[g] != track || r->group_instanced[g] ||
                                          r->group_deform[g] >= 0);
             g++) {}
        if (g == r->num_groups) r->group_track[r->num_groups++] = track;
        group_of[i] = g;
    }
    for (g = 0, j = 0; g < r->num_groups; g++) {
        r->group_first[g] = j;
        for (i = 0; i < n; i++)
            if (group_of[i] == g) r->members[j++] = i;
    }
    r->group_first[r->num_groups] = j;
    free(group_of);
    r->group_scenes = calloc((size_t)r->num_groups + 1, sizeof *r->group_scenes);
    for (g = 0; g < r->num_groups; g++) {
        RTCScene sc = rtcNewScene(r->dev);
        r->group_scenes[g] = sc;
        rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_HIGH);
        if (r->group_deform[g] >= 0) {
            add_deform_geometry(r->dev, sc,
                                &s->meshes[s->instances[r->members[r->group_first[g]]].mesh],
                                &rs->deforms[r->group_deform[g]]);
            rtcCommitScene(sc);
            continue;
        }
        for (j = r->group_first[g]; j < r->group_first[g + 1]; j++) {
            const evr_instance *in = &s->instances[r->members[j]];
            evr_m34 world = evr_node_world_at(s, in->node, s->anim_start);
            add_mesh_geometry(r->dev, sc, &s->meshes[in->mesh],
                              r->group_track[g] < 0 && !r->group_instanced[g] ? &world : NULL,
                              (unsigned)(j - r->group_first[g]));
        }
        rtcCommitScene(sc);
    }
    r->top = rtcNewScene(r->dev);
    rtcSetSceneBuildQuality(r->top, RTC_BUILD_QUALITY_HIGH);
    for (g = 0; g < r->num_groups; g++) {
        RTCGeometry geom = rtcNewGeometry(r->dev, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(geom, r->group_scenes[g]);
        if (r->group_track[g] < 0) {
            evr_m34 xf =
                r->group_instanced[g]
                    ? evr_node_world_at(s, s->instances[r->members[r->group_first[g]]].node,
                                        s->anim_start)
                    : evr_m34_identity();
            rtcSetGeometryTransform(geom, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, &xf.m[0][0]);
        } else {
            int track = r->group_track[g], nk = mo->count[track];
            rtcSetGeometryTimeStepCount(geom, (unsigned)nk);
            for (k = 0; k < nk; k++) {
                struct RTCQuaternionDecomposition q;
                to_embree(&mo->keys[mo->offset[track] + k], &q);
                rtcSetGeometryTransformQuaternion(geom, (unsigned)k, &q);
            }
        }
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(r->top, geom, (unsigned)g);
        rtcReleaseGeometry(geom);
    }
    rtcCommitScene(r->top);
}

static void reference_free(reference *r)
{
    int g;
    rtcReleaseScene(r->top);
    for (g = 0; g < r->num_groups; g++) rtcReleaseScene(r->group_scenes[g]);
    free(r->group_scenes);
    free(r->group_track);
    free(r->group_instanced);
    free(r->group_deform);
    free(r->group_first);
    free(r->members);
    rtcReleaseDevice(r->dev);
}

/* The GPU BVH's groups are the reference's (the CPU backend's): same order, nodes and members. */
static int same_groups(const evr_scene *s, const evr_gpu_bvh *b, const reference *r)
{
    int g, j;
    if (b->num_groups != r->num_groups) return 0;
    for (g = 0; g < r->num_groups; g++) {
        /* an instanced static group is in its node's space */
        int node = r->group_instanced[g] ? s->instances[r->members[r->group_first[g]]].node
                                         : r->group_track[g];
        if (b->group_node[g] != node || b->group_first[g + 1] != r->group_first[g + 1]) return 0;
        for (j = r->group_first[g]; j < r->group_first[g + 1]; j++)
            if (b->members[j] != r->members[j] || b->instance_group[r->members[j]] != g) return 0;
    }
    return 1;
}

/* Embree's answers over the reference's grouped scene (cpu/cpu_gi.h's queries). */
static int reference_closest(const reference *r, evr_ray ray, float tmax, float f, evr_gpu_hit *hit)
{
    evr_trace_hit h;
    if (!evr_embree_closest1(r->top, r->members, r->group_first, ray, 0.0f, tmax, f, &h)) return 0;
    hit->instance = h.inst;
    hit->prim = h.prim;
    hit->u = h.u;
    hit->v = h.v;
    hit->t = h.t;
    return 1;
}

static int reference_occluded(const reference *r, evr_ray ray, float tnear, float tfar, float f)
{
    return evr_embree_occluded1(r->top, ray, tnear, tfar, f);
}

/* ---- rays ---- */

typedef struct {
    evr_ray ray;
    float tnear, tfar, f;
} test_ray;

static float rnd(uint64_t *c) { return evr_uniform(evr_hash4(0x627668ull, (*c)++, 0, 0)); }

/* Vertex vi of instance i in world space at time f: the mesh's (meshes[...]) or, deforming, the
 * segment's vertex keys interpolated (rs->deforms), moved by the instance's track. */
static evr_v3 world_vertex(const evr_mesh *meshes, const evr_render_scene *rs, int i, uint32_t vi,
                           float f)
{
    const evr_instance_view *iv = &rs->instances[i];
    const evr_m34 xf = evr_motion_eval(evr_rs_track(rs, iv->track), f);
    evr_v3 p;
    if (iv->deform >= 0) {
        const evr_deform_view *d = &rs->deforms[iv->deform];
        p = evr_deform_lerp(d, d->positions, vi, f);
    } else {
        const float *q = meshes[iv->mesh].positions + 3 * (size_t)vi;
        p = evr_v3_make(q[0], q[1], q[2]);
    }
    return evr_m34_point(&xf, p);
}

/* A random point on a random instance's surface at time f, in world space, and the surface's
 * (geometric) normal there. */
static evr_v3 surface_point(const evr_scene *s, const evr_render_scene *rs, float f, uint64_t *c,
                            evr_v3 *normal)
{
    for (;;) {
        int i = (int)(rnd(c) * (float)s->num_instances) % s->num_instances;
        const evr_mesh *m = &s->meshes[s->instances[i].mesh];
        uint32_t t;
        float a, b;
        evr_v3 p[3];
        int k;
        if (!m->num_triangles) continue;
        t = (uint32_t)(rnd(c) * (float)m->num_triangles) % m->num_triangles;
        for (k = 0; k < 3; k++)
            p[k] = world_vertex(s->meshes, rs, i, m->indices[3 * t + (uint32_t)k], f);
        *normal = evr_v3_norm(evr_v3_cross(evr_v3_sub(p[1], p[0]), evr_v3_sub(p[2], p[0])));
        if (evr_v3_dot(*normal, *normal) == 0.0f) continue; /* a degenerate triangle */
        a = rnd(c);
        b = rnd(c);
        if (a + b > 1.0f) {
            a = 1.0f - a;
            b = 1.0f - b;
        }
        return evr_v3_add(evr_v3_add(evr_v3_scale(p[0], 1 - a - b), evr_v3_scale(p[1], a)),
                          evr_v3_scale(p[2], b));
    }
}

/* Camera rays through random image positions at random times; shadow-like rays between two
 * surface points, leaving the first and stopping short of the second as the renderer's shadow
 * rays leave a surface (evr_shadow_tnear: eps / max(cos, 0.05) along the ray), not along the
 * first surface's plane; random rays
 * through the scene's box. */
static test_ray *make_rays(const evr_scene *s, const evr_render_scene *rs, int n_cam, int n_shadow,
                           int n_random, uint64_t seed)
{
    test_ray *r = malloc(sizeof *r * (size_t)(n_cam + n_shadow + n_random));
    uint64_t c = seed;
    int i;
    float eps = rs->ray_eps;
    for (i = 0; i < n_cam; i++) {
        float f = rnd(&c);
        evr_m34 pose = evr_rs_camera_pose(rs, f);
        r[i].ray = evr_camera_ray(&rs->camera, &pose, rnd(&c) * (float)rs->camera.width,
                                  rnd(&c) * (float)rs->camera.height);
        r[i].tnear = 0.0f;
        r[i].tfar = INFINITY;
        r[i].f = f;
    }
    for (; i < n_cam + n_shadow; i++) {
        float f = rnd(&c), d, off_a, off_b;
        evr_v3 na, nb, a = surface_point(s, rs, f, &c, &na), b = surface_point(s, rs, f, &c, &nb);
        evr_v3 dir = evr_v3_sub(b, a);
        d = evr_v3_len(dir);
        if (!(d > 0.0f)) {
            i--;
            continue;
        }
        dir = evr_v3_scale(dir, 1.0f / d);
        /* a ray lying in its start surface's plane: which side it passes is rounding, and the
         * renderer never traces one (it skips lights with dot(wi, n) <= 0) */
        if (fabsf(evr_v3_dot(na, dir)) < 1e-3f) {
            i--;
            continue;
        }
        off_a = eps / fmaxf(fabsf(evr_v3_dot(na, dir)), 0.05f);
        off_b = eps / fmaxf(fabsf(evr_v3_dot(nb, dir)), 0.05f);
        if (!(d > 2.0f * (off_a + off_b))) {
            i--;
            continue;
        }
        r[i].ray.org = a;
        r[i].ray.dir = dir;
        r[i].tnear = off_a;
        r[i].tfar = d - off_b;
        r[i].f = f;
    }
    for (; i < n_cam + n_shadow + n_random; i++) {
        evr_v3 lo = s->bounds_min, hi = s->bounds_max, o, d;
        o = evr_v3_make(lo.x + (hi.x - lo.x) * (1.4f * rnd(&c) - 0.2f),
                        lo.y + (hi.y - lo.y) * (1.4f * rnd(&c) - 0.2f),
                        lo.z + (hi.z - lo.z) * (1.4f * rnd(&c) - 0.2f));
        do d = evr_v3_make(2 * rnd(&c) - 1, 2 * rnd(&c) - 1, 2 * rnd(&c) - 1);
        while (evr_v3_dot(d, d) > 1.0f || evr_v3_dot(d, d) < 1e-4f);
        r[i].ray.org = o;
        r[i].ray.dir = evr_v3_norm(d);
        r[i].tnear = 0.0f;
        r[i].tfar = INFINITY;
        r[i].f = rnd(&c);
    }
    return r;
}

/* ---- comparing ----
 *
 * The two tracers place a surface identically only to float precision: Embree and we evaluate
 * the same motion keys with different arithmetic, and the watertight test rounds differently
 * from Embree's. A position tolerance DELTA = 1e-6 of the scene's size (~8 float epsilons)
 * says which disagreements a float epsilon explains:
 *   edge     a hit within EDGE_EPS (barycentric) of its triangle's edge;
 *   contact  a hit within DELTA of the surface the ray starts or ends on: its distance from
 *            the range's end, times the cosine to the triangle, is below DELTA (shadow-like
 *            rays leave and reach surfaces, often at grazing angles);
 *   tie      two surfaces within DELTA of each other along the ray.
 * Distances of the same triangle agree when |dt| <= 1e-4 t or |dt| cos <= DELTA (the latter for
 * short or grazing rays, whose t is ill-conditioned). Anything else is a failure. */

enum { EX_NONE = 0, EX_EDGE = 1, EX_CONTACT = 2, EX_TIE = 3 };

typedef struct {
    const evr_mesh *meshes; /* by rs->instances[i].mesh */
    const evr_render_scene *rs;
    float delta;
} judge;

static float edge_distance(const evr_gpu_hit *h)
{
    return fminf(fminf(h->u, h->v), 1.0f - h->u - h->v);
}

/* |cosine| between a ray and the (world-space) triangle it hit. */
static float hit_cosine(const judge *j, const evr_gpu_hit *h, evr_ray ray, float f)
{
    const evr_mesh *m = &j->meshes[j->rs->instances[h->instance].mesh];
    evr_v3 p[3], n;
    int k;
    for (k = 0; k < 3; k++)
        p[k] =
            world_vertex(j->meshes, j->rs, h->instance, m->indices[3 * h->prim + (uint32_t)k], f);
    n = evr_v3_norm(evr_v3_cross(evr_v3_sub(p[1], p[0]), evr_v3_sub(p[2], p[0])));
    return fabsf(evr_v3_dot(n, evr_v3_norm(ray.dir)));
}

static int t_agrees(float t1, float t2, float cosine, float delta)
{
    float dt = fabsf(t1 - t2);
    return dt <= 1e-4f * fmaxf(t1, t2) || dt * cosine <= delta;
}

static int same_hit(const judge *j, const evr_gpu_hit *a, const evr_gpu_hit *b, evr_ray ray,
                    float f)
{
    float c;
    if (a->instance != b->instance || a->prim != b->prim) return 0;
    c = hit_cosine(j, b, ray, f);
    if (!t_agrees(a->t, b->t, c, j->delta)) return 0;
    /* barycentrics move with t along grazing rays */
    return c < 0.05f || (fabsf(a->u - b->u) <= 1e-3f && fabsf(a->v - b->v) <= 1e-3f);
}

/* How float epsilons explain hits a and b (either may be absent) of a ray over [0, tmax]. */
static int explain(const judge *j, evr_ray ray, float f, float tmax, int h1, const evr_gpu_hit *a,
                   int h2, const evr_gpu_hit *b)
{
    const evr_gpu_hit *h[2];
    int n = 0, k;
    if (h1) h[n++] = a;
    if (h2) h[n++] = b;
    for (k = 0; k < n; k++)
        if (edge_distance(h[k]) < EDGE_EPS) return EX_EDGE;
    for (k = 0; k < n; k++) {
        float c = hit_cosine(j, h[k], ray, f);
        if (h[k]->t * c <= j->delta || (isfinite(tmax) && (tmax - h[k]->t) * c <= j->delta))
            return EX_CONTACT;
    }
    if (n == 2 && (t_agrees(a->t, b->t, hit_cosine(j, a, ray, f), j->delta) ||
                   t_agrees(a->t, b->t, hit_cosine(j, b, ray, f), j->delta)))
        return EX_TIE;
    return EX_NONE;
}

/* A hit of the unshifted ray on an edge, or within DELTA of where the ray starts (tnear). */
static int near_start(const judge *j, const evr_gpu_hit *h, const test_ray *r)
{
    if (edge_distance(h) < EDGE_EPS) return EX_EDGE;
    if (fabsf(h->t - r->tnear) * hit_cosine(j, h, r->ray, r->f) <= j->delta) return EX_CONTACT;
    return EX_NONE;
}

enum { RAY_CAMERA = 0, RAY_SHADOW = 1, RAY_RANDOM = 2 };
static const char *const ray_kind_name[3] = {"camera", "shadow-like", "random"};

typedef struct {
    long rays[3], hits[3];
    long closest[3][4]; /* mismatches by ray kind and explanation (EX_NONE: unexplained) */
    long occluded[3][4];
} tally;

static long sum4(const long *x) { return x[0] + x[1] + x[2] + x[3]; }

static void report_line(int kind, const tally *ty)
{
    const long *c = ty->closest[kind], *o = ty->occluded[kind];
    printf(
        "    %-11s %7ld rays (%ld hit): closest differ %ld (edge %ld, contact %ld, tie %ld, unexplained %ld), "
        "occlusion differ %ld (edge %ld, contact %ld, tie %ld, unexplained %ld)\n",
        ray_kind_name[kind], ty->rays[kind], ty->hits[kind], sum4(c), c[EX_EDGE], c[EX_CONTACT],
        c[EX_TIE], c[EX_NONE], sum4(o), o[EX_EDGE], o[EX_CONTACT], o[EX_TIE], o[EX_NONE]);
}

/* The nearest hit as the CUDA backend finds a camera ray's while the camera holds still: the
 * static group's hit (kept per pixel), unless the other groups have one nearer. Rays compared
 * and those where it differs from the search of all groups (other than by an exact tie). */
static long split_rays, split_differ;

static void compare(const char *what, const judge *j, const evr_gpu_scene_view *v,
                    const reference *ref, const test_ray *rays, const int *kind, int n, tally *ty)
{
    const evr_render_scene *rs = j->rs;
    int i, printed = 0;
    int dump = getenv("EVR_DUMP") != NULL;
    for (i = 0; i < n; i++) {
        const test_ray *r = &rays[i];
        int kd = kind[i];
        evr_gpu_hit a, b;
        evr_ray cr = r->ray;
        int h1, h2, o1, o2;
        float tmax = r->tfar;
        /* closest hits start at tnear: move the origin there (both tracers start at t = 0) */
        if (r->tnear > 0.0f) {
            cr.org = evr_v3_add(cr.org, evr_v3_scale(cr.dir, r->tnear));
            tmax = r->tfar - r->tnear;
        }
        memset(&a, 0, sizeof a);
        memset(&b, 0, sizeof b);
        h1 = evr_trace_closest(v, rs, cr, tmax, r->f, &a);
        {
            evr_gpu_hit st, mv;
            memset(&st, 0, sizeof st);
            memset(&mv, 0, sizeof mv);
            const int hs = evr_trace_closest_groups(v, rs, cr, tmax, r->f, EVR_GROUPS_STATIC, &st);
            const int hm =
                evr_trace_closest_groups(v, rs, cr, hs ? st.t : tmax, r->f, EVR_GROUPS_MOVING, &mv);
            const evr_gpu_hit *sp = hm ? &mv : &st;
            split_rays++;
            /* the same distance; another triangle there is a tie, either is the nearest */
            if ((hs || hm) != h1 || (h1 && sp->t != a.t)) split_differ++;
        }
        h2 = reference_closest(ref, cr, tmax, r->f, &b);
        ty->rays[kd]++;
        ty->hits[kd] += h2;
        if (h1 != h2 || (h1 && !same_hit(j, &a, &b, cr, r->f))) {
            int ex = explain(j, cr, r->f, tmax, h1, &a, h2, &b);
            ty->closest[kd][ex]++;
            if (dump || (ex == EX_NONE && printed++ < 5))
                printf(
                    "%s %s ray %d (class %d): ours %d inst %d prim %u t %.9g uv %.6g %.6g, Embree %d inst %d prim %u "
                    "t %.9g uv %.6g %.6g\n",
                    ex == EX_NONE ? "FAIL" : "note", what, i, ex, h1, a.instance, a.prim, a.t, a.u,
                    a.v, h2, b.instance, b.prim, b.t, b.u, b.v);
        }
        o1 = evr_trace_any(v, rs, r->ray, r->tnear, r->tfar, r->f);
        o2 = reference_occluded(ref, r->ray, r->tnear, r->tfar, r->f);
        if (o1 != o2) {
            /* the nearest surfaces after tnear and after the origin explain it */
            evr_gpu_hit c1, c2, d1, d2;
            int g1, g2, k1, k2, ex;
            float range = (r->tfar - r->tnear) * 1.001f;
            memset(&c1, 0, sizeof c1);
            memset(&c2, 0, sizeof c2);
            memset(&d1, 0, sizeof d1);
            memset(&d2, 0, sizeof d2);
            g1 = evr_trace_closest(v, rs, cr, range, r->f, &c1);
            g2 = reference_closest(ref, cr, range, r->f, &c2);
            ex = explain(j, cr, r->f, r->tfar - r->tnear, g1, &c1, g2, &c2);
            if (ex == EX_NONE && r->tnear > 0.0f) {
                k1 = evr_trace_closest(v, rs, r->ray, r->tfar, r->f, &d1);
                k2 = reference_closest(ref, r->ray, r->tfar, r->f, &d2);
                /* a surface the ray starts on, seen from the unshifted origin */
                if (k1) ex = near_start(j, &d1, r);
                if (ex == EX_NONE && k2) ex = near_start(j, &d2, r);
            }
            ty->occluded[kd][ex]++;
            if (dump || (ex == EX_NONE && printed++ < 5))
                printf("%s %s ray %d (class %d): occluded ours %d Embree %d (tnear %g tfar %g)\n",
                       ex == EX_NONE ? "FAIL" : "note", what, i, ex, o1, o2, r->tnear, r->tfar);
        }
    }
}

static void timing(const char *what, const evr_gpu_scene_view *v, const evr_render_scene *rs,
                   const reference *ref, const test_ray *rays, int n)
{
    double t0, t1, t2;
    long h1 = 0, h2 = 0;
    int i;
    evr_gpu_hit h;
    t0 = now();
    for (i = 0; i < n; i++)
        h1 += evr_trace_closest(v, rs, rays[i].ray, rays[i].tfar, rays[i].f, &h);
    t1 = now();
    for (i = 0; i < n; i++) h2 += reference_closest(ref, rays[i].ray, rays[i].tfar, rays[i].f, &h);
    t2 = now();
    printf("  %-34s %7.2f Mrays/s (Embree %6.2f Mrays/s, one thread; hits %ld / %ld)\n", what,
           1e-6 * n / (t1 - t0), 1e-6 * n / (t2 - t1), h1, h2);
}

#ifdef EVR_TRAVERSE_STATS
evr_traverse_stats evr_tstats;

static void stats_line(const char *what, long rays)
{
    const double n = rays > 0 ? (double)rays : 1.0;
    printf("    %-28s top nodes %6.1f, groups entered %5.1f, nodes %6.1f, triangles %6.1f a ray\n",
           what, evr_tstats.top_nodes / n, evr_tstats.groups / n, evr_tstats.nodes / n,
           evr_tstats.tris / n);
    memset(&evr_tstats, 0, sizeof evr_tstats);
}

/* The searches' work per ray (gpu_traverse.h's counters, kept by the CW8 searches): the camera
 * rays, and from each hit a shadow ray to the scene's first light. */
static void stats_add(evr_traverse_stats *sum)
{
    sum->top_nodes += evr_tstats.top_nodes;
    sum->groups += evr_tstats.groups;
    sum->nodes += evr_tstats.nodes;
    sum->tris += evr_tstats.tris;
    memset(&evr_tstats, 0, sizeof evr_tstats);
}

static void traverse_stats(const evr_gpu_scene_view *v, const evr_render_scene *rs,
                           const test_ray *rays, int n, float eps)
{
    const evr_light_view *l = rs->num_lights > 0 ? &rs->lights[0] : NULL;
    evr_traverse_stats cam, shadow;
    long shadows = 0;
    memset(&cam, 0, sizeof cam);
    memset(&shadow, 0, sizeof shadow);
    memset(&evr_tstats, 0, sizeof evr_tstats);
    for (int i = 0; i < n; i++) {
        evr_gpu_hit h;
        const int hit = evr_trace_closest(v, rs, rays[i].ray, rays[i].tfar, rays[i].f, &h);
        stats_add(&cam);
        if (!hit || !l) continue;
        const evr_v3 p = evr_v3_add(rays[i].ray.org, evr_v3_scale(rays[i].ray.dir, h.t));
        evr_v3 lpos = l->pos, ldir = l->dir;
        if (l->track >= 0) { /* the light's node at the ray's time */
            const evr_m34 m = evr_motion_eval(evr_rs_track(rs, l->track), rays[i].f);
            lpos = evr_m34_point(&m, lpos);
            ldir = evr_m34_vector(&m, ldir);
        }
        evr_v3 d =
            l->type == EVR_LIGHT_DIRECTIONAL ? evr_v3_scale(ldir, -1.0f) : evr_v3_sub(lpos, p);
        const float len = l->type == EVR_LIGHT_DIRECTIONAL ? INFINITY : evr_v3_len(d);
        const evr_ray sr = {p, evr_v3_norm(d)};
        evr_trace_any(v, rs, sr, eps, len, rays[i].f);
        stats_add(&shadow);
        shadows++;
    }
    evr_tstats = cam;
    stats_line("camera rays:", n);
    if (!l) return;
    evr_tstats = shadow;
    stats_line("shadow rays to light 0:", shadows);
}
#endif

/* ---- conservative motion bounds ---- */

static int inside(evr_v3 p, const float *lo, const float *hi)
{
    return p.x >= lo[0] && p.y >= lo[1] && p.z >= lo[2] && p.x <= hi[0] && p.y <= hi[1] &&
           p.z <= hi[2];
}

static long check_box_holds(const float box[6], const float *lo, const float *hi,
                            evr_motion_track tr, int samples, uint64_t *c)
{
    long bad = 0;
    int j, k;
    for (j = 0; j <= samples; j++) {
        float f = j < samples / 2 ? (float)j / (float)(samples / 2) : rnd(c);
        evr_m34 xf = evr_motion_eval(tr, f);
        for (k = 0; k < 8; k++) {
            evr_v3 p = evr_v3_make((k & 1) ? box[3] : box[0], (k & 2) ? box[4] : box[1],
                                   (k & 4) ? box[5] : box[2]);
            if (!inside(evr_m34_point(&xf, p), lo, hi)) bad++;
        }
    }
    return bad;
}

/* The top level's boxes hold every group at every time of the segment (a deforming group: every
 * vertex of its mesh, interpolated and moved, at sampled times). */
static long check_group_boxes(const evr_gpu_bvh *b, const evr_gpu_top *top,
                              const evr_render_scene *rs, int samples, uint64_t *c)
{
    long bad = 0;
    int g, k;
    for (g = 0; g < b->num_groups; g++) {
        const float *box = b->group_bounds + 6 * g, *lo = top->group_bounds + 6 * g, *hi = lo + 3;
        if (b->group_deform[g] >= 0) {
            const int i = b->members[b->group_first[g]];
            const evr_deform_view *d = &rs->deforms[rs->instances[i].deform];
            for (k = 0; k <= samples / 100; k++) {
                const float f = k < samples / 200 ? (float)k / (float)(samples / 200) : rnd(c);
                const evr_m34 xf = evr_motion_eval(evr_rs_track(rs, rs->instances[i].track), f);
                uint32_t v;
                for (v = 0; v < d->num_vertices; v++)
                    if (!inside(evr_m34_point(&xf, evr_deform_lerp(d, d->positions, v, f)), lo, hi))
                        bad++;
            }
            continue;
        }
        if (b->group_root[g] < 0) continue;
        if (b->group_node[g] < 0) { /* static: world space already */
            for (k = 0; k < 3; k++)
                if (!(lo[k] <= box[k] && hi[k] >= box[k + 3])) bad++;
            continue;
        }
        bad += check_box_holds(box, lo, hi,
                               evr_rs_track(rs, rs->instances[b->members[b->group_first[g]]].track),
                               samples, c);
    }
    return bad;
}

static void test_synthetic_bounds(void)
{
    uint64_t c = 7;
    long bad = 0, tested = 0;
    double ratio = 0.0;
    int set, i;
    for (set = 0; set < 300; set++) {
        evr_motion_key keys[6];
        int n = 1 + set % 6;
        float box[6], lo[3], hi[3];
        for (i = 0; i < 3; i++) {
            float a = 4.0f * rnd(&c) - 2.0f, b = a + 0.01f + 3.0f * rnd(&c);
            box[i] = a;
            box[i + 3] = b;
        }
        for (i = 0; i < n; i++) {
            evr_motion_key *k = &keys[i];
            int a;
            for (a = 0; a < 3; a++) {
                k->scale[a] = 0.2f + 2.0f * rnd(&c);
                k->skew[a] = 0.5f * rnd(&c) - 0.25f;
            }
            if (set % 5 == 0) k->scale[2] = -k->scale[2]; /* mirrored */
            k->trans =
                evr_v3_make(10.0f * rnd(&c) - 5.0f, 10.0f * rnd(&c) - 5.0f, 10.0f * rnd(&c) - 5.0f);
            k->rot = evr_quat_normalize(
                evr_quat_make(rnd(&c) - 0.5f, rnd(&c) - 0.5f, rnd(&c) - 0.5f, rnd(&c) - 0.5f));
            if (i > 0) {
                /* up to ~120 degrees from the previous key (what evr_node_motion_keys allows), or
                 * nearly the same (the normalized-lerp branch of the slerp) */
                float amount = set % 3 == 0 ? 0.002f * rnd(&c) : rnd(&c) * 0.6f;
                k->rot = evr_quat_slerp(keys[i - 1].rot, k->rot, amount);
                if (evr_quat_dot(keys[i - 1].rot, k->rot) < 0.0f)
                    k->rot = evr_quat_make(-k->rot.w, -k->rot.x, -k->rot.y, -k->rot.z);
            }
        }
        {
            evr_motion_track tr;
            double exact_vol = 1.0, vol = 1.0;
            double elo[3] = {INFINITY, INFINITY, INFINITY},
                   ehi[3] = {-INFINITY, -INFINITY, -INFINITY};
            int j, k, a;
            tr.keys = keys;
            tr.n = n;
            evr_swept_bounds(box, box + 3, tr, lo, hi);
            bad += check_box_holds(box, lo, hi, tr, 4000, &c);
            tested++;
            /* how tight: against the union of densely sampled boxes */
            for (j = 0; j <= 2000; j++) {
                evr_m34 xf = evr_motion_eval(tr, (float)j / 2000.0f);
                for (k = 0; k < 8; k++) {
                    evr_v3 p = evr_m34_point(&xf, evr_v3_make((k & 1) ? box[3] : box[0],
                                                              (k & 2) ? box[4] : box[1],
                                                              (k & 4) ? box[5] : box[2]));
                    float q[3] = {p.x, p.y, p.z};
                    for (a = 0; a < 3; a++) {
                        elo[a] = fmin(elo[a], q[a]);
                        ehi[a] = fmax(ehi[a], q[a]);
                    }
                }
            }
            for (a = 0; a < 3; a++) {
                exact_vol *= ehi[a] - elo[a];
                vol *= (double)hi[a] - lo[a];
            }
            ratio += vol / exact_vol;
        }
    }
    printf(
        "synthetic tracks: %ld corner samples outside their segment box (of %ld tracks); boxes %.4f x the "
        "sampled volume on average\n",
        bad, tested, ratio / (double)tested);
    CHECK(bad == 0);
}

typedef struct {
    long rays, mismatches, edge, contact, unexplained, well_rays, well_mismatches;
} totals;

static const char *layout_name(int layout)
{
    int cw8 = (layout & ~EVR_GPU_BVH_UNGROUPED) == EVR_GPU_LAYOUT_CW8;
    if (layout & EVR_GPU_BVH_UNGROUPED) return cw8 ? "CW8 ungrouped" : "BVH4 ungrouped";
    return cw8 ? "CW8" : "BVH4";
}

/* ---- synthetic scenes ---- */

/* A closed mesh: a cube's faces subdivided n x n and pushed onto the unit sphere, vertices
 * shared by index (as an importer welds them). */
static void make_sphere(int n, evr_mesh *mesh)
{
    int nv = 6 * (n + 1) * (n + 1), nt = 6 * n * n * 2, f, i, j, k, vi = 0, ti = 0, u, w;
    float *pos = malloc(sizeof(float) * 3 * (size_t)nv);
    uint32_t *idx = malloc(sizeof(uint32_t) * 3 * (size_t)nt);
    int *remap = malloc(sizeof(int) * (size_t)nv);
    for (f = 0; f < 6; f++)
        for (j = 0; j <= n; j++)
            for (i = 0; i <= n; i++) {
                float a = 2.0f * (float)i / (float)n - 1.0f, b = 2.0f * (float)j / (float)n - 1.0f,
                      p[3], l;
                int ax = f % 3, sg = f < 3 ? 1 : -1;
                p[ax] = (float)sg;
                p[(ax + 1) % 3] = sg > 0 ? a : b;
                p[(ax + 2) % 3] = sg > 0 ? b : a;
                l = sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
                for (k = 0; k < 3; k++) pos[3 * vi + k] = p[k] / l;
                vi++;
            }
    for (u = 0; u < nv; u++) { /* weld the copies along the cube's edges */
        remap[u] = u;
        for (w = 0; w < u; w++)
            if (fabsf(pos[3 * w] - pos[3 * u]) < 1e-6f &&
                fabsf(pos[3 * w + 1] - pos[3 * u + 1]) < 1e-6f &&
                fabsf(pos[3 * w + 2] - pos[3 * u + 2]) < 1e-6f) {
                remap[u] = remap[w];
                break;
            }
    }
    for (f = 0; f < 6; f++)
        for (j = 0; j < n; j++)
            for (i = 0; i < n; i++) {
                int b0 = f * (n + 1) * (n + 1);
                int v00 = remap[b0 + j * (n + 1) + i], v10 = remap[b0 + j * (n + 1) + i + 1];
                int v01 = remap[b0 + (j + 1) * (n + 1) + i],
                    v11 = remap[b0 + (j + 1) * (n + 1) + i + 1];
                idx[3 * ti] = (uint32_t)v00;
                idx[3 * ti + 1] = (uint32_t)v10;
                idx[3 * ti + 2] = (uint32_t)v11;
                ti++;
                idx[3 * ti] = (uint32_t)v00;
                idx[3 * ti + 1] = (uint32_t)v11;
                idx[3 * ti + 2] = (uint32_t)v01;
                ti++;
            }
    free(remap);
    memset(mesh, 0, sizeof *mesh);
    mesh->num_vertices = (uint32_t)nv;
    mesh->num_triangles = (uint32_t)nt;
    mesh->positions = pos;
    mesh->normals = calloc((size_t)nv * 3, sizeof(float));
    mesh->indices = idx;
    for (k = 0; k < 3; k++) {
        (&mesh->bounds_min.x)[k] = -1.0f;
        (&mesh->bounds_max.x)[k] = 1.0f;
    }
}

/* A flat, open mesh: an n x n grid over [-1, 1]^2 in the plane z = 0, gently waved. */
static void make_sheet(int n, evr_mesh *mesh)
{
    int nv = (n + 1) * (n + 1), nt = 2 * n * n, i, j, ti = 0;
    float *pos = malloc(sizeof(float) * 3 * (size_t)nv);
    uint32_t *idx = malloc(sizeof(uint32_t) * 3 * (size_t)nt);
    for (j = 0; j <= n; j++)
        for (i = 0; i <= n; i++) {
            float x = 2.0f * (float)i / (float)n - 1.0f, y = 2.0f * (float)j / (float)n - 1.0f;
            pos[3 * (j * (n + 1) + i)] = x;
            pos[3 * (j * (n + 1) + i) + 1] = y;
            pos[3 * (j * (n + 1) + i) + 2] = 0.1f * sinf(3.0f * x) * cosf(2.0f * y);
        }
    for (j = 0; j < n; j++)
        for (i = 0; i < n; i++) {
            uint32_t v00 = (uint32_t)(j * (n + 1) + i), v10 = v00 + 1,
                     v01 = v00 + (uint32_t)(n + 1), v11 = v01 + 1;
            idx[3 * ti] = v00;
            idx[3 * ti + 1] = v10;
            idx[3 * ti + 2] = v11;
            ti++;
            idx[3 * ti] = v00;
            idx[3 * ti + 1] = v11;
            idx[3 * ti + 2] = v01;
            ti++;
        }
    memset(mesh, 0, sizeof *mesh);
    mesh->num_vertices = (uint32_t)nv;
    mesh->num_triangles = (uint32_t)nt;
    mesh->positions = pos;
    mesh->normals = calloc((size_t)nv * 3, sizeof(float));
    mesh->indices = idx;
}

static void free_mesh(evr_mesh *m)
{
    free(m->positions);
    free(m->normals);
    free(m->indices);
}

/* Rays from inside a closed mesh, aimed exactly at its vertices, at its edges' midpoints and
 * anywhere, must all hit it; the mesh's node static (the static group, baked) or animated (a
 * group of its own). */
/* A closed sphere of 12 n^2 triangles: no ray from inside escapes. Past 262,144 triangles
 * (n 148 and more) its tree is built without spatial splits (evr_tree_high_quality). */
static void test_watertight(int layout, int animated, int n)
{
    evr_mesh mesh;
    evr_node node;
    evr_instance scene_inst;
    evr_scene sc;
    evr_gpu_bvh bvh;
    evr_gpu_top top;
    evr_gpu_scene_view view;
    evr_render_scene rs;
    evr_instance_view inst;
    evr_motion_key key;
    int off = 0, cnt = 1, missed = 0, rays = 0, k;
    uint64_t c = 11;
    evr_m34 id = evr_m34_identity();
    make_sphere(n, &mesh);
    memset(&node, 0, sizeof node);
    node.parent = -1;
    node.rest_matrix = id;
    node.animated = animated;
    scene_inst.mesh = 0;
    scene_inst.node = 0;
    memset(&sc, 0, sizeof sc);
    sc.num_meshes = 1;
    sc.meshes = &mesh;
    sc.num_nodes = 1;
    sc.nodes = &node;
    sc.num_instances = 1;
    sc.instances = &scene_inst;
    memset(&rs, 0, sizeof rs);
    memset(&top, 0, sizeof top);
    inst.mesh = 0;
    inst.track = 0;
    inst.deform = -1;
    key = evr_motion_key_from_matrix(&id);
    rs.instances = &inst;
    rs.num_instances = 1;
    rs.keys = &key;
    rs.track_offset = &off;
    rs.track_count = &cnt;
    CHECK_OK(evr_gpu_bvh_build(&sc, layout, NULL, &bvh, &e_));
    CHECK(bvh.num_groups == 1 && bvh.group_node[0] == (animated ? 0 : -1));
    CHECK_OK(evr_gpu_top_build(&bvh, NULL, &rs, &top, &e_));
    evr_gpu_scene_view_host(&bvh, NULL, &top, &view);
    for (k = 0; k < 60000 / RAY_SCALE; k++) {
        evr_ray r;
        evr_gpu_hit h;
        uint32_t t = (uint32_t)(rnd(&c) * (float)mesh.num_triangles) % mesh.num_triangles;
        const float *p0 = mesh.positions + 3 * mesh.indices[3 * t],
                    *p1 = mesh.positions + 3 * mesh.indices[3 * t + 1];
        evr_v3 target;
        int kind = k % 3;
        if (kind == 0) target = evr_v3_make(p0[0], p0[1], p0[2]); /* a vertex */
        else if (kind == 1)
            target =
                evr_v3_make(0.5f * (p0[0] + p1[0]), 0.5f * (p0[1] + p1[1]), 0.5f * (p0[2] + p1[2]));
        else target = evr_v3_make(2 * rnd(&c) - 1, 2 * rnd(&c) - 1, 2 * rnd(&c) - 1);
        r.org = k % 2 ? evr_v3_make(0, 0, 0)
                      : evr_v3_make(0.5f * rnd(&c) - 0.25f, 0.5f * rnd(&c) - 0.25f,
                                    0.5f * rnd(&c) - 0.25f);
        r.dir = evr_v3_norm(evr_v3_sub(target, r.org));
        if (evr_v3_dot(r.dir, r.dir) == 0.0f) continue;
        rays++;
        if (!evr_trace_closest(&view, &rs, r, INFINITY, 0.5f, &h)) missed++;
        else if (!evr_trace_any(&view, &rs, r, 0.0f, INFINITY, 0.5f)) missed++;
    }
    printf("watertight (layout %s, %s group, %u triangles): %d of %d rays from inside a closed "
           "mesh escaped\n",
           layout == EVR_GPU_LAYOUT_CW8 ? "CW8" : "BVH4", animated ? "a moving" : "the static",
           mesh.num_triangles, missed, rays);
    CHECK(missed == 0);
    evr_gpu_top_free(&top);
    evr_gpu_bvh_free(&bvh);
    free_mesh(&mesh);
}

/* A random motion key; rotations near prev when given (up to ~120 degrees away). */
static evr_motion_key random_key(uint64_t *c, const evr_motion_key *prev)
{
    evr_motion_key k;
    int a;
    for (a = 0; a < 3; a++) {
        k.scale[a] = 0.3f + 0.7f * rnd(c);
        k.skew[a] = 0.4f * rnd(c) - 0.2f;
    }
    k.rot = evr_quat_normalize(
        evr_quat_make(rnd(c) - 0.5f, rnd(c) - 0.5f, rnd(c) - 0.5f, rnd(c) - 0.5f));
    k.trans = evr_v3_make(16.0f * rnd(c) - 8.0f, 16.0f * rnd(c) - 8.0f, 16.0f * rnd(c) - 8.0f);
    if (prev) {
        k.rot = evr_quat_slerp(prev->rot, k.rot, 0.6f * rnd(c));
        if (evr_quat_dot(prev->rot, k.rot) < 0.0f)
            k.rot = evr_quat_make(-k.rot.w, -k.rot.x, -k.rot.y, -k.rot.z);
        k.trans = evr_v3_lerp(prev->trans, k.trans, 0.1f);
    }
    return k;
}

/* Many instances on random motion tracks: a quarter on static nodes (the static group, baked
 * into world space), some of those under an animated node that places nothing (groups that
 * could move but do not in the segment), the rest on moving nodes of their own or two to a node
 * (groups of two meshes); moving groups of the same meshes share a tree. Exercises the grouping,
 * the instance numbers of shared trees and the top level (its boxes over the segment, its
 * traversal and stack) against Embree grouped as the CPU backend groups. */
static void test_many_instances(int n_inst, int n_rays, totals *tot)
{
    evr_mesh meshes[2];
    evr_scene sc;
    evr_render_scene rs;
    evr_node *nodes = calloc((size_t)n_inst + 1, sizeof *nodes);
    evr_instance *sinst = malloc(sizeof *sinst * (size_t)n_inst);
    evr_instance_view *inst = malloc(sizeof *inst * (size_t)n_inst);
    evr_motion_key *keys = malloc(sizeof *keys * ((size_t)n_inst + 1) * 5);
    int *off = malloc(sizeof(int) * ((size_t)n_inst + 1)),
        *cnt = malloc(sizeof(int) * ((size_t)n_inst + 1));
    int *kind = malloc(sizeof(int) * (size_t)n_rays);
    test_ray *rays = malloc(sizeof *rays * (size_t)n_rays);
    reference ref, ref_inst;
    motion mo;
    evr_m34 id = evr_m34_identity();
    uint64_t c = 21;
    int i, k, li, nk = 0, nn = 0, parent, n_static = 0;
    judge j;

    make_sphere(6, &meshes[0]);
    make_sheet(8, &meshes[1]);
    /* node 0: animated, places nothing, the parent of some static nodes */
    parent = nn++;
    nodes[parent].parent = -1;
    nodes[parent].rest_matrix = id;
    nodes[parent].animated = 1;
    off[parent] = nk;
    cnt[parent] = 1;
    keys[nk++] = evr_motion_key_from_matrix(&id);
    for (i = 0; i < n_inst; i++) {
        int node;
        if (i % 10 == 9) {
            node = sinst[i - 1].node; /* a second mesh on the previous instance's node */
        } else {
            int n = i % 4 == 0 ? 1 : 2 + i % 4; /* a quarter static, the rest 3 to 5 keys */
            node = nn++;
            nodes[node].parent = i % 16 == 8 ? parent : -1;
            nodes[node].animated = i % 4 != 0;
            off[node] = nk;
            cnt[node] = n;
            for (k = 0; k < n; k++, nk++) keys[nk] = random_key(&c, k ? &keys[nk - 1] : NULL);
            nodes[node].rest_matrix = evr_motion_key_matrix(&keys[off[node]]);
        }
        snprintf(nodes[node].name, sizeof nodes[node].name, "node %d", node);
        /* the second mesh on a node is the other one: the same twice would be a tie everywhere */
        sinst[i].mesh = inst[i].mesh = i % 10 == 9 ? !sinst[i - 1].mesh : i % 3 == 0;
        sinst[i].node = node;
        inst[i].track = node;
        inst[i].deform = -1;
        n_static += nodes[node].parent < 0 && !nodes[node].animated;
    }
    memset(&sc, 0, sizeof sc);
    sc.num_meshes = 2;
    sc.meshes = meshes;
    sc.num_nodes = nn;
    sc.nodes = nodes;
    sc.num_instances = n_inst;
    sc.instances = sinst;
    memset(&rs, 0, sizeof rs);
    rs.instances = inst;
    rs.num_instances = n_inst;
    rs.keys = keys;
    rs.track_offset = off;
    rs.track_count = cnt;
    mo.keys = keys;
    mo.offset = off;
    mo.count = cnt;
    reference_build(&ref, &sc, &mo, 0, NULL);
    reference_build(&ref_inst, &sc, &mo, 1, NULL);

    for (i = 0; i < n_rays; i++) {
        evr_v3 d;
        rays[i].ray.org =
            evr_v3_make(24.0f * rnd(&c) - 12.0f, 24.0f * rnd(&c) - 12.0f, 24.0f * rnd(&c) - 12.0f);
        do d = evr_v3_make(2 * rnd(&c) - 1, 2 * rnd(&c) - 1, 2 * rnd(&c) - 1);
        while (evr_v3_dot(d, d) > 1.0f || evr_v3_dot(d, d) < 1e-4f);
        rays[i].ray.dir = evr_v3_norm(d);
        rays[i].f = rnd(&c);
        rays[i].tnear = i % 2 ? 0.0f : 0.5f * rnd(&c);
        rays[i].tfar = i % 4 == 1 ? INFINITY : 2.0f + 20.0f * rnd(&c);
        kind[i] = RAY_RANDOM;
    }
    j.meshes = meshes;
    j.rs = &rs;
    j.delta = 1e-6f * 40.0f;
    /* both layouts, without grouping, and with the static instances instanced (CW8, BVH4) */
    for (li = 0; li < 5; li++) {
        int layout = li == 1 ? EVR_GPU_LAYOUT_BVH4 : EVR_GPU_LAYOUT_CW8;
        evr_gpu_bvh bvh;
        evr_gpu_top top;
        evr_gpu_scene_view view;
        tally ty;
        long bad, m;
        char what[64];
        if (li == 2) layout |= EVR_GPU_BVH_UNGROUPED;
        if (li == 4) layout = EVR_GPU_LAYOUT_BVH4;
        memset(&top, 0, sizeof top);
        memset(&ty, 0, sizeof ty);
        if (li >= 3) setenv("EVR_STATIC_BAKE_LIMIT", "0", 1); /* past the limit: instance */
        CHECK_OK(evr_gpu_bvh_build(&sc, layout, NULL, &bvh, &e_));
        unsetenv("EVR_STATIC_BAKE_LIMIT");
        if (li >= 3) {
            CHECK(bvh.grouped && bvh.static_instanced && bvh.static_group < 0);
            CHECK(same_groups(&sc, &bvh, &ref_inst));
            /* trees: one per mesh for every single-mesh group, static or moving, and the two
             * two-mesh groups' (mesh orders 0 1 and 1 0) */
            CHECK(bvh.num_trees == 4);
        } else if (li < 2) {
            CHECK(!bvh.static_instanced);
            CHECK(bvh.grouped && same_groups(&sc, &bvh, li < 3 ? &ref : &ref_inst));
            CHECK(bvh.static_group >= 0 &&
                  bvh.group_first[bvh.static_group + 1] - bvh.group_first[bvh.static_group] ==
                      n_static);
            /* trees: the static group's, one per mesh for the single-mesh groups, two for the
             * two-mesh groups (mesh orders 0 1 and 1 0) */
            CHECK(bvh.num_trees == 5);
        } else {
            /* an instance a group, one tree per mesh */
            CHECK(!bvh.grouped && bvh.num_groups == n_inst && bvh.static_group < 0 &&
                  bvh.num_trees == 2);
        }
        CHECK_OK(evr_gpu_top_build(&bvh, NULL, &rs, &top, &e_));
        evr_gpu_scene_view_host(&bvh, NULL, &top, &view);
        bad = check_group_boxes(&bvh, &top, &rs, 200, &c);
        CHECK(bad == 0);
        snprintf(what, sizeof what, "instances/%s", layout_name(layout));
        if (li >= 3)
            snprintf(what, sizeof what, "instances/%s static instanced", layout_name(layout));
        compare(what, &j, &view, li >= 3 ? &ref_inst : &ref, rays, kind, n_rays, &ty);
        printf(
            "%d instances on %d nodes, layout %s%s: %d groups (%d instances static), %d trees, %u triangle "
            "references; top level %u nodes, stack %d of %d\n",
            n_inst, nn, layout_name(layout), li >= 3 ? " (static instanced)" : "", bvh.num_groups,
            n_static, bvh.num_trees, bvh.num_tris, top.num_nodes, top.stack_need,
            EVR_GPU_STACK_SIZE);
        report_line(RAY_RANDOM, &ty);
        CHECK(ty.closest[RAY_RANDOM][EX_NONE] == 0);
        CHECK(ty.occluded[RAY_RANDOM][EX_NONE] == 0);
        m = sum4(ty.closest[RAY_RANDOM]) + sum4(ty.occluded[RAY_RANDOM]);
        tot->rays += ty.rays[RAY_RANDOM];
        tot->mismatches += m;
        tot->well_rays += ty.rays[RAY_RANDOM];
        tot->well_mismatches += m;
        tot->edge += ty.closest[RAY_RANDOM][EX_EDGE] + ty.occluded[RAY_RANDOM][EX_EDGE];
        tot->contact += ty.closest[RAY_RANDOM][EX_CONTACT] + ty.occluded[RAY_RANDOM][EX_CONTACT];
        tot->unexplained += ty.closest[RAY_RANDOM][EX_NONE] + ty.occluded[RAY_RANDOM][EX_NONE];
        snprintf(what, sizeof what, "random rays, %s", layout_name(layout));
        timing(what, &view, &rs, li >= 3 ? &ref_inst : &ref, rays, n_rays);
        evr_gpu_top_free(&top);
        evr_gpu_bvh_free(&bvh);
    }
    reference_free(&ref);
    reference_free(&ref_inst);
    free_mesh(&meshes[0]);
    free_mesh(&meshes[1]);
    free(nodes);
    free(sinst);
    free(inst);
    free(keys);
    free(off);
    free(cnt);
    free(kind);
    free(rays);
}

/* ---- refitted and rebuilt deforming trees ---- */

/* A sheet whose vertices move by three segments of keys: its first tree is built, then its
 * vertices scatter (a refit of the sheet's topology would be far worse than a new tree: built
 * again), then they move a little (refitted). Every segment, rays at random times find what a
 * search of every triangle (interpolated, the same watertight test) finds. */
static void test_deform_refit(int layout)
{
    evr_mesh mesh;
    evr_morph morph;
    evr_node node;
    evr_instance sinst = {0, 0};
    evr_scene sc;
    evr_mesh_view mv;
    evr_instance_view iv;
    evr_deform_view dv;
    evr_render_scene rs;
    evr_motion_key key;
    evr_gpu_bvh bvh;
    evr_gpu_deform d;
    evr_gpu_top top;
    evr_gpu_scene_view view;
    evr_m34 id = evr_m34_identity();
    int off = 0, cnt = 1, seg, moved = 1, bad = 0, hits = 0;
    uint64_t c = 99;
    uint32_t v, nv;
    float *keys;
    make_sheet(16, &mesh);
    nv = mesh.num_vertices;
    keys = malloc(sizeof(float) * 3 * nv * 2);
    memset(&morph, 0, sizeof morph);
    mesh.morph = &morph; /* deforms (the keys are made here) */
    memset(&node, 0, sizeof node);
    node.parent = -1;
    node.rest_matrix = id;
    memset(&sc, 0, sizeof sc);
    sc.num_meshes = 1;
    sc.meshes = &mesh;
    sc.num_nodes = 1;
    sc.nodes = &node;
    sc.num_instances = 1;
    sc.instances = &sinst;
    mv.positions = mesh.positions;
    mv.normals = mesh.normals;
    mv.uvs = NULL;
    mv.indices = mesh.indices;
    mv.num_triangles = mesh.num_triangles;
    mv.material = 0;
    iv.mesh = 0;
    iv.track = 0;
    iv.deform = 0;
    dv.num_vertices = nv;
    dv.positions = keys;
    dv.normals = keys;
    key = evr_motion_key_from_matrix(&id);
    memset(&rs, 0, sizeof rs);
    rs.meshes = &mv;
    rs.instances = &iv;
    rs.num_instances = 1;
    rs.deforms = &dv;
    rs.num_deforms = 1;
    rs.keys = &key;
    rs.track_offset = &off;
    rs.track_count = &cnt;
    memset(&d, 0, sizeof d);
    memset(&top, 0, sizeof top);
    CHECK_OK(evr_gpu_bvh_build(&sc, layout, NULL, &bvh, &e_));
    CHECK(bvh.num_deforming == 1 && bvh.num_trees == 0);
    for (seg = 0; seg < 3; seg++) {
        int i;
        /* keys: the sheet; the sheet to scattered points; those moved a little */
        memcpy(keys, mesh.positions, sizeof(float) * 3 * nv);
        dv.num_keys = seg ? 2 : 1;
        for (v = 0; v < nv && seg; v++)
            for (i = 0; i < 3; i++) {
                float *p = keys + 3 * (nv + v) + i;
                *p = 2.0f * evr_uniform(evr_hash4(0x5ca7ull, v, (uint64_t)i, 0)) - 1.0f;
                if (seg == 2) {
                    keys[3 * v + (uint32_t)i] = *p;
                    *p += 0.05f * (rnd(&c) - 0.5f);
                }
            }
        CHECK_OK(evr_gpu_deform_update(&bvh, &rs, &moved, &d, &e_));
        printf(
            "deforming tree, %s, segment %d: built %d, refitted %d, cost %.3g of its built %.3g\n",
            layout_name(layout), seg, d.rebuilt, d.refitted, d.trees[0].cost,
            d.trees[0].built_cost);
        CHECK(d.rebuilt == (seg < 2) && d.refitted == (seg == 2));
        CHECK_OK(evr_gpu_top_build(&bvh, &d, &rs, &top, &e_));
        evr_gpu_scene_view_host(&bvh, &d, &top, &view);
        for (i = 0; i < 4000 / RAY_SCALE; i++) {
            evr_v3 o = evr_v3_make(3.0f * rnd(&c) - 1.5f, 3.0f * rnd(&c) - 1.5f, 2.0f),
                   to = evr_v3_make(2.0f * rnd(&c) - 1.0f, 2.0f * rnd(&c) - 1.0f,
                                    2.0f * rnd(&c) - 1.0f);
            evr_ray ray;
            evr__tray tr;
            evr_gpu_hit h;
            float f = rnd(&c), best = INFINITY;
            uint32_t t, best_prim = 0;
            int a;
            ray.org = o;
            ray.dir = evr_v3_norm(evr_v3_sub(to, o));
            evr__tray_init(&tr, ray.org, ray.dir);
            for (t = 0; t < mesh.num_triangles; t++) { /* every triangle, at time f */
                evr_gpu_tri tri;
                float *p[3] = {tri.v0, tri.v1, tri.v2}, tt, uu, vv;
                for (a = 0; a < 3; a++) {
                    evr_v3 q =
                        evr_deform_lerp(&dv, dv.positions, mesh.indices[3 * t + (uint32_t)a], f);
                    p[a][0] = q.x;
                    p[a][1] = q.y;
                    p[a][2] = q.z;
                }
                if (evr__tri(&tr, &tri, 0.0f, best, &tt, &uu, &vv) && tt < best) {
                    best = tt;
                    best_prim = t;
                }
            }
            /* the same distance (the same arithmetic); another triangle only at a tie */
            if (evr_trace_closest(&view, &rs, ray, INFINITY, f, &h) != (best < INFINITY)) bad++;
            else if (best < INFINITY && (h.instance != 0 || h.t != best)) bad++;
            else if (best < INFINITY && h.prim != best_prim) {
                evr_gpu_tri tri;
                float *p[3] = {tri.v0, tri.v1, tri.v2}, tt, uu, vv;
                for (a = 0; a < 3; a++) {
                    evr_v3 q = evr_deform_lerp(&dv, dv.positions,
                                               mesh.indices[3 * h.prim + (uint32_t)a], f);
                    p[a][0] = q.x;
                    p[a][1] = q.y;
                    p[a][2] = q.z;
                }
                if (!evr__tri(&tr, &tri, 0.0f, INFINITY, &tt, &uu, &vv) || tt != best) bad++;
            }
            hits += best < INFINITY;
        }
    }
    printf("deforming tree, %s: %d of the rays' hits differ from a search of every triangle "
           "(%d hits)\n",
           layout_name(layout), bad, hits);
    CHECK(bad == 0 && hits > 0);
    evr_gpu_top_free(&top);
    evr_gpu_deform_free(&d);
    evr_gpu_bvh_free(&bvh);
    free(keys);
    free_mesh(&mesh);
}

/* ---- one scene segment ---- */

/* The groups of a BVH, as "node: mesh mesh | ..." ("static" for the static group, "skinned" for a
 * skinned mesh's, in world space). */
static void describe_groups(const evr_scene *s, const evr_gpu_bvh *b, char *out, size_t size)
{
    size_t len = 0;
    int g, k;
    out[0] = 0;
    for (g = 0; g < b->num_groups && len < size; g++) {
        len += (size_t)snprintf(out + len, size - len, "%s%s:", g ? " | " : "",
                                b->group_node[g] >= 0     ? s->nodes[b->group_node[g]].name
                                : b->group_deform[g] >= 0 ? "skinned"
                                                          : "static");
        for (k = b->group_first[g]; k < b->group_first[g + 1] && len < size; k++)
            len += (size_t)snprintf(out + len, size - len, " %s",
                                    s->meshes[s->instances[b->members[k]].mesh].name);
    }
}

/* What test_scene checks beyond the comparison (each may be NULL/0). */
typedef struct {
    const char *groups;     /* the groups, as describe_groups writes them */
    const uint32_t *counts; /* nodes and triangle references, CW8 then BVH4 */
    int still_segments;     /* segments whose deforming meshes all hold still, at least */
    int refits, rebuilds;   /* deforming trees refitted, and built again (after the first
                               segment), at least (both layouts) */
} scene_expect;

/* FNV-1a of a deforming trees' packed arrays (to tell a kept tree from a rebuilt one). */
static uint64_t deform_hash(const evr_gpu_deform *d)
{
    const unsigned char *p[3];
    size_t n[3], i;
    uint64_t h = 1469598103934665603ull;
    int k;
    p[0] = (const unsigned char *)d->nodes4;
    n[0] = d->nodes4 ? d->num_nodes * sizeof *d->nodes4 : 0;
    p[1] = (const unsigned char *)d->nodes8;
    n[1] = d->nodes8 ? d->num_nodes * sizeof *d->nodes8 : 0;
    p[2] = (const unsigned char *)d->tris;
    n[2] = d->num_tris * sizeof *d->tris;
    for (k = 0; k < 3; k++)
        for (i = 0; i < n[k]; i++) {
            h ^= p[k][i];
            h *= 1099511628211ull;
        }
    return h;
}

/* A scene's bottom level is built once per layout (its groups and sizes as ex says); every
 * segment rebuilds the top level in place (as the backend does), and the trees of the deforming
 * meshes from the segment's vertex keys (prep/deform_keys.c, segments in order), and is checked
 * against an Embree scene with that segment's keys. */
static void test_scene(const char *name, const evr_scene *s, const scene_expect *ex,
                       const double *t0s, int nseg, int n_cam, int n_shadow, int n_random,
                       totals *tot)
{
    evr_render_host host;
    evr_error err;
    evr_gpu_bvh bvh[2];
    evr_gpu_top top[2];
    evr_gpu_deform dtrees[2];
    evr_deform_tracker tracker;
    evr_deform_keys dkeys;
    const int layouts[2] = {EVR_GPU_LAYOUT_CW8, EVR_GPU_LAYOUT_BVH4};
    int li, i, seg, n = n_cam + n_shadow + n_random, still_segments = 0, refits = 0, rebuilds = 0;
    unsigned ntri = 0;
    uint64_t c = 3;

    CHECK_OK(evr_render_host_init(&host, s, 0, 640, 480, 0.02f, &err));
    memset(&dkeys, 0, sizeof dkeys);
    memset(dtrees, 0, sizeof dtrees);
    CHECK(evr_deform_tracker_init(&tracker, s, &host));
    for (i = 0; i < s->num_meshes; i++) ntri += s->meshes[i].num_triangles;
    for (li = 0; li < 2; li++) {
        double tb = now();
        char groups[512];
        memset(&top[li], 0, sizeof top[li]);
        CHECK_OK(evr_gpu_bvh_build(s, layouts[li], NULL, &bvh[li], &err));
        printf(
            "%s, layout %s: %u nodes of %zu bytes, %u triangle references for %u triangles, stack %d; build %.1f ms\n",
            name, layout_name(layouts[li]), bvh[li].num_nodes,
            layouts[li] == EVR_GPU_LAYOUT_CW8 ? sizeof(evr_gpu_node8) : sizeof(evr_gpu_node4),
            bvh[li].num_tris, ntri, bvh[li].max_stack, 1e3 * (now() - tb));
        describe_groups(s, &bvh[li], groups, sizeof groups);
        printf("  %d groups (%d trees, %d deforming): %s\n", bvh[li].num_groups, bvh[li].num_trees,
               bvh[li].num_deforming, groups);
        if (ex && ex->groups) CHECK(strcmp(groups, ex->groups) == 0);
        if (ex && ex->counts)
            CHECK(bvh[li].num_nodes == ex->counts[2 * li] &&
                  bvh[li].num_tris == ex->counts[2 * li + 1]);
        CHECK(bvh[li].num_deforming == host.num_deforms);
    }

    for (seg = 0; seg < nseg; seg++) {
        double t0 = t0s[seg], t1 = t0 + 1.0 / 30.0;
        motion mo;
        reference ref;
        test_ray *rays;
        int *kind, moving = 0, moved = 0;
        judge j;
        motion_compute(s, 0, t0, t1, &mo);
        host.rs.keys = mo.keys;
        host.rs.track_offset = mo.offset;
        host.rs.track_count = mo.count;
        if (host.num_deforms) {
            CHECK(evr_deform_keys_make(&tracker, s, &host, t0, t1, 1e-5f, MAX_KEYS, &dkeys));
            host.rs.deforms = dkeys.views;
            for (i = 0; i < host.num_deforms; i++) moved += dkeys.moved[i];
            still_segments += moved == 0;
        }
        for (i = 0; i < s->num_instances; i++) moving += mo.count[host.rs.instances[i].track] > 1;
        reference_build(&ref, s, &mo, 0, host.num_deforms ? &host.rs : NULL);
        CHECK(same_groups(s, &bvh[0], &ref) && same_groups(s, &bvh[1], &ref));
        rays = make_rays(s, &host.rs, n_cam, n_shadow, n_random, 0x5eedull + (uint64_t)(t0 * 1000));
        kind = malloc(sizeof(int) * (size_t)n);
        for (i = 0; i < n; i++)
            kind[i] = i < n_cam ? RAY_CAMERA : (i < n_cam + n_shadow ? RAY_SHADOW : RAY_RANDOM);
        j.meshes = s->meshes;
        j.rs = &host.rs;
        j.delta = 1e-6f * host.scene_size;
        printf("%s, segment %.4f .. %.4f s: %d instances (%d moving, %d deforming, %d of them "
               "moved), %d rays\n",
               name, t0, t1, s->num_instances, moving, host.num_deforms, moved, n);

        for (li = 0; li < 2; li++) {
            evr_gpu_scene_view view;
            tally ty;
            double tt = now();
            char what[96];
            long bad = 0, well = 0, well_bad = 0, all_bad = 0;
            int k;
            memset(&ty, 0, sizeof ty);
            if (host.num_deforms) {
                const unsigned long long gen = dtrees[li].gen;
                const uint64_t before = deform_hash(&dtrees[li]);
                double td = now();
                CHECK_OK(evr_gpu_deform_update(&bvh[li], &host.rs, dkeys.moved, &dtrees[li], &err));
                printf("  layout %s: deforming trees: %d built, %d refitted in %.2f ms, %u nodes, "
                       "%u triangles, stack %d; cost (refitted / built):",
                       layout_name(layouts[li]), dtrees[li].rebuilt, dtrees[li].refitted,
                       1e3 * (now() - td), dtrees[li].num_nodes, dtrees[li].num_tris,
                       dtrees[li].max_stack);
                for (k = 0; k < dtrees[li].num; k++)
                    printf(" %.3g", dtrees[li].trees[k].cost / dtrees[li].trees[k].built_cost);
                printf("\n");
                /* every moved mesh's tree made again (the first segment: built); while all
                 * hold still the trees stay the bits */
                CHECK(dtrees[li].rebuilt + dtrees[li].refitted ==
                      (seg == 0 ? host.num_deforms : moved));
                if (seg == 0) CHECK(dtrees[li].rebuilt == host.num_deforms);
                refits += dtrees[li].refitted;
                rebuilds += seg ? dtrees[li].rebuilt : 0;
                if (seg > 0 && moved == 0)
                    CHECK(dtrees[li].gen == gen && deform_hash(&dtrees[li]) == before);
            }
            CHECK_OK(evr_gpu_top_build(&bvh[li], host.num_deforms ? &dtrees[li] : NULL, &host.rs,
                                       &top[li], &err));
            evr_gpu_scene_view_host(&bvh[li], host.num_deforms ? &dtrees[li] : NULL, &top[li],
                                    &view);
            printf("  layout %s: top level %u nodes, %u groups, stack %d of %d, built in %.3f ms\n",
                   layout_name(layouts[li]), top[li].num_nodes, top[li].num_insts,
                   top[li].stack_need, EVR_GPU_STACK_SIZE, 1e3 * (now() - tt));

            /* segment boxes hold every group at every time */
            bad = check_group_boxes(&bvh[li], &top[li], &host.rs, 2000, &c);
            CHECK(bad == 0);

            snprintf(what, sizeof what, "%s/%s", name, layout_name(layouts[li]));
            compare(what, &j, &view, &ref, rays, kind, n, &ty);
            for (k = 0; k < 3; k++) report_line(k, &ty);
            for (k = 0; k < 3; k++) {
                long m = sum4(ty.closest[k]) + sum4(ty.occluded[k]);
                all_bad += m;
                tot->edge += ty.closest[k][EX_EDGE] + ty.occluded[k][EX_EDGE];
                tot->contact += ty.closest[k][EX_CONTACT] + ty.occluded[k][EX_CONTACT];
                tot->unexplained += ty.closest[k][EX_NONE] + ty.occluded[k][EX_NONE];
                CHECK(ty.closest[k][EX_NONE] == 0);
                CHECK(ty.occluded[k][EX_NONE] == 0);
                if (k != RAY_SHADOW) {
                    well += ty.rays[k];
                    well_bad += m;
                }
            }
            tot->rays += ty.rays[0] + ty.rays[1] + ty.rays[2];
            tot->mismatches += all_bad;
            tot->well_rays += well;
            tot->well_mismatches += well_bad;
            snprintf(what, sizeof what, "camera rays, %s", layout_name(layouts[li]));
            timing(what, &view, &host.rs, &ref, rays, n_cam);
#ifdef EVR_TRAVERSE_STATS
            if (layouts[li] == EVR_GPU_LAYOUT_CW8) /* the counters are CW8's */
                traverse_stats(&view, &host.rs, rays, n_cam, 1e-4f * host.scene_size);
#endif
        }
        free(kind);
        free(rays);
        reference_free(&ref);
        motion_free(&mo);
    }
    if (ex)
        CHECK(still_segments >= ex->still_segments && refits >= ex->refits &&
              rebuilds >= ex->rebuilds);
    for (li = 0; li < 2; li++) {
        evr_gpu_deform_free(&dtrees[li]);
        evr_gpu_top_free(&top[li]);
        evr_gpu_bvh_free(&bvh[li]);
    }
    evr_deform_keys_free(&dkeys);
    evr_deform_tracker_free(&tracker);
    evr_render_host_free(&host);
}

static void test_demo(const char *name, const scene_expect *ex, const double *t0s, int nseg,
                      int n_cam, int n_shadow, int n_random, totals *tot)
{
    evr_scene *s = NULL;
    evr_error err;
    CHECK_OK(evr_demo_load(name, &s, &err));
    if (!s) return;
    /* the traversal against Embree's plain triangles: every surface opaque and two-sided here
     * (the hit filters, alpha holes and culled back faces, have tests/test_hit_filter.c) */
    for (int i = 0; i < s->num_materials; i++) {
        s->materials[i].p.alpha_mode = EVR_ALPHA_OPAQUE;
        s->materials[i].p.double_sided = 1;
    }
    test_scene(name, s, ex, t0s, nseg, n_cam, n_shadow, n_random, tot);
    evr_scene_release(s);
}

/* ---- a scene of deforming meshes ---- */

static evr_m34 trs(evr_v3 t, float sx, float sy, float sz)
{
    evr_m34 m = evr_m34_identity();
    m.m[0][0] = sx;
    m.m[1][1] = sy;
    m.m[2][2] = sz;
    m.m[0][3] = t.x;
    m.m[1][3] = t.y;
    m.m[2][3] = t.z;
    return m;
}

static void rest_node(evr_node *n, const char *name, int parent, evr_v3 t, float sx, float sy,
                      float sz)
{
    memset(n, 0, sizeof *n);
    snprintf(n->name, sizeof n->name, "%s", name);
    n->parent = parent;
    n->translation = t;
    n->scale = evr_v3_make(sx, sy, sz);
    n->rotation = evr_quat_make(1, 0, 0, 0);
    n->rest_matrix = trs(t, sx, sy, sz);
}

static void set_curve(evr_curve *c, int n, double *times, float *values)
{
    c->num_keys = n;
    c->times = times;
    c->values = values;
    c->interp = EVR_INTERP_LINEAR;
}

/* An open tube along x from 0 to len (rings x sides vertices), radius r, radial normals. */
static void make_tube(int rings, int sides, float len, float r, evr_mesh *mesh)
{
    int nv = rings * sides, nt = 2 * (rings - 1) * sides, i, k, ti = 0;
    float *pos = malloc(sizeof(float) * 3 * (size_t)nv),
          *nrm = malloc(sizeof(float) * 3 * (size_t)nv);
    uint32_t *idx = malloc(sizeof(uint32_t) * 3 * (size_t)nt);
    for (i = 0; i < rings; i++)
        for (k = 0; k < sides; k++) {
            const float a = 6.2831853f * (float)k / (float)sides,
                        x = len * (float)i / (float)(rings - 1);
            float *p = pos + 3 * (i * sides + k), *q = nrm + 3 * (i * sides + k);
            p[0] = x;
            p[1] = r * cosf(a);
            p[2] = r * sinf(a);
            q[0] = 0.0f;
            q[1] = cosf(a);
            q[2] = sinf(a);
        }
    for (i = 0; i + 1 < rings; i++)
        for (k = 0; k < sides; k++) {
            const uint32_t a = (uint32_t)(i * sides + k),
                           b = (uint32_t)(i * sides + (k + 1) % sides);
            const uint32_t c2 = a + (uint32_t)sides, d = b + (uint32_t)sides;
            idx[3 * ti] = a;
            idx[3 * ti + 1] = b;
            idx[3 * ti + 2] = d;
            ti++;
            idx[3 * ti] = a;
            idx[3 * ti + 1] = d;
            idx[3 * ti + 2] = c2;
            ti++;
        }
    memset(mesh, 0, sizeof *mesh);
    mesh->num_vertices = (uint32_t)nv;
    mesh->num_triangles = (uint32_t)nt;
    mesh->positions = pos;
    mesh->normals = nrm;
    mesh->indices = idx;
    mesh->bounds_min = evr_v3_make(0.0f, -r, -r);
    mesh->bounds_max = evr_v3_make(len, r, r);
}

/* Morph targets, a skin, a rigid mover and a still floor, timed so that the segments below
 * see them move, bend at a curve's key, and hold still:
 *   node 1 "blob-a"  morph targets (weights ramp to 1 by t = 1, back to 0.3 by 1.5, then held)
 *                    on a node that moves: a deforming group moved by its track;
 *   node 2 "blob-b"  the same mesh on a node that never moves (weights ramp over 0.5 .. 1.5);
 *   nodes 3, 4       a shoulder and an elbow that turns 90 degrees about z by t = 1.2;
 *   node 5 "arm"     the skinned tube (its node's transform ignored: 5 units up);
 *   node 6 "ball"    a rigid sphere that moves; node 7 "floor" a still sheet. */
typedef struct {
    evr_scene s;
    evr_mesh meshes[4];
    evr_node nodes[8];
    evr_instance inst[5];
    evr_camera_desc cam;
    evr_morph morph;
    evr_skin skin;
    evr_m34 inv_bind[2];
    float *d_pos, def_w[2], rest_w[2];
} deform_scene;

static double ta_times[2] = {0.0, 2.0}, wa_times[3] = {0.0, 1.0, 1.5}, wb_times[2] = {0.5, 1.5},
              elbow_times[2] = {0.0, 1.2}, ball_times[2] = {0.0, 2.0};
static float ta_values[6] = {-2.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f},
             wa_values[6] = {0.0f, 0.0f, 1.0f, 0.5f, 0.3f, 1.0f},
             wb_values[4] = {0.0f, 1.0f, 1.0f, 0.0f},
             elbow_values[8] = {1.0f, 0.0f, 0.0f, 0.0f, 0.70710678f, 0.0f, 0.0f, 0.70710678f},
             ball_values[6] = {0.0f, 2.5f, 1.0f, 0.0f, -2.5f, 1.0f};

static void deform_scene_make(deform_scene *d)
{
    evr_scene *s = &d->s;
    evr_mesh *blob = &d->meshes[1], *arm = &d->meshes[2];
    uint32_t v;
    int k;
    memset(d, 0, sizeof *d);
    make_sheet(8, &d->meshes[0]);
    for (v = 0; v < d->meshes[0].num_vertices; v++) d->meshes[0].normals[3 * v + 2] = 1.0f;
    make_sphere(20, blob);
    memcpy(blob->normals, blob->positions, sizeof(float) * 3 * blob->num_vertices);
    /* target 0 bulges +x, target 1 shears z by y */
    d->d_pos = calloc(2 * 3 * (size_t)blob->num_vertices, sizeof(float));
    for (v = 0; v < blob->num_vertices; v++) {
        const float *p = blob->positions + 3 * v;
        d->d_pos[3 * v] = p[0] > 0.0f ? 0.8f * p[0] * p[0] : 0.0f;
        d->d_pos[3 * (blob->num_vertices + v) + 2] = 0.6f * sinf(2.0f * p[0]) * p[1];
    }
    d->morph.num_targets = 2;
    d->morph.d_positions = d->d_pos;
    d->morph.default_weights = d->def_w;
    blob->morph = &d->morph;
    make_tube(25, 12, 3.0f, 0.3f, arm);
    d->skin.num_joints = 2;
    d->skin.joint_nodes = malloc(2 * sizeof(int));
    d->skin.joint_nodes[0] = 3;
    d->skin.joint_nodes[1] = 4;
    d->inv_bind[0] = evr_m34_identity();
    d->inv_bind[1] = trs(evr_v3_make(-1.5f, 0.0f, 0.0f), 1.0f, 1.0f, 1.0f);
    d->skin.inverse_bind = d->inv_bind;
    d->skin.influences = 2;
    d->skin.joints = malloc(sizeof(uint16_t) * 2 * arm->num_vertices);
    d->skin.weights = malloc(sizeof(float) * 2 * arm->num_vertices);
    for (v = 0; v < arm->num_vertices; v++) { /* blended over 1 <= x <= 2 */
        float w = arm->positions[3 * v] - 1.0f;
        w = w < 0.0f ? 0.0f : w > 1.0f ? 1.0f : w;
        d->skin.joints[2 * v] = 0;
        d->skin.joints[2 * v + 1] = 1;
        d->skin.weights[2 * v] = 1.0f - w;
        d->skin.weights[2 * v + 1] = w;
    }
    arm->skin = &d->skin;
    make_sphere(4, &d->meshes[3]);
    memcpy(d->meshes[3].normals, d->meshes[3].positions,
           sizeof(float) * 3 * d->meshes[3].num_vertices);
    for (k = 0; k < 4; k++)
        snprintf(d->meshes[k].name, sizeof d->meshes[k].name, "%s",
                 k == 0   ? "floor"
                 : k == 1 ? "blob"
                 : k == 2 ? "arm"
                          : "ball");

    rest_node(&d->nodes[0], "root", -1, evr_v3_make(0, 0, 0), 1, 1, 1);
    rest_node(&d->nodes[1], "blob-a", -1, evr_v3_make(-2, 0, 0), 1, 1, 1);
    set_curve(&d->nodes[1].t_curve, 2, ta_times, ta_values);
    set_curve(&d->nodes[1].w_curve, 3, wa_times, wa_values);
    d->nodes[1].animated = 1;
    rest_node(&d->nodes[2], "blob-b", -1, evr_v3_make(2.5f, -1.0f, 0.5f), 1, 1, 1);
    set_curve(&d->nodes[2].w_curve, 2, wb_times, wb_values);
    rest_node(&d->nodes[3], "shoulder", -1, evr_v3_make(-1.0f, -2.5f, 0.5f), 1, 1, 1);
    rest_node(&d->nodes[4], "elbow", 3, evr_v3_make(1.5f, 0, 0), 1, 1, 1);
    set_curve(&d->nodes[4].r_curve, 2, elbow_times, elbow_values);
    d->nodes[4].animated = 1;
    rest_node(&d->nodes[5], "arm", -1, evr_v3_make(0, 0, 5), 1, 1, 1);
    rest_node(&d->nodes[6], "ball", -1, evr_v3_make(0, 2.5f, 1), 0.5f, 0.5f, 0.5f);
    set_curve(&d->nodes[6].t_curve, 2, ball_times, ball_values);
    d->nodes[6].animated = 1;
    rest_node(&d->nodes[7], "floor", -1, evr_v3_make(0, 0, -1.5f), 5, 5, 1);
    for (k = 1; k <= 2; k++) {
        d->nodes[k].num_weights = 2;
        d->nodes[k].weights = d->rest_w;
    }
    d->inst[0].mesh = 0; /* floor */
    d->inst[0].node = 7;
    d->inst[1].mesh = 1;
    d->inst[1].node = 1;
    d->inst[2].mesh = 3; /* the ball between the deforming meshes */
    d->inst[2].node = 6;
    d->inst[3].mesh = 2;
    d->inst[3].node = 5;
    d->inst[4].mesh = 1;
    d->inst[4].node = 2;
    d->cam.node = -1;
    d->cam.yfov = 0.9f;
    d->cam.local = trs(evr_v3_make(0, 0, 9), 1, 1, 1);
    snprintf(d->cam.name, sizeof d->cam.name, "camera");
    s->num_meshes = 4;
    s->meshes = d->meshes;
    s->num_nodes = 8;
    s->nodes = d->nodes;
    s->num_instances = 5;
    s->instances = d->inst;
    s->num_cameras = 1;
    s->cameras = &d->cam;
    s->anim_start = 0.0;
    s->anim_end = 2.0;
    s->bounds_min = evr_v3_make(-5, -5, -2);
    s->bounds_max = evr_v3_make(5, 5, 3);
}

static void deform_scene_free(deform_scene *d)
{
    int k;
    for (k = 0; k < 4; k++) free_mesh(&d->meshes[k]);
    free(d->d_pos);
    free(d->skin.joint_nodes);
    free(d->skin.joints);
    free(d->skin.weights);
}

int main(void)
{
    totals tot;
    memset(&tot, 0, sizeof tot);
    setvbuf(stdout, NULL, _IOLBF, 0);
    double t = now();
    test_synthetic_bounds();
    test_watertight(EVR_GPU_LAYOUT_CW8, 0, 24);
    test_watertight(EVR_GPU_LAYOUT_BVH4, 0, 24);
    test_watertight(EVR_GPU_LAYOUT_CW8, 1, 24);
    test_watertight(EVR_GPU_LAYOUT_BVH4, 1, 24);
    test_watertight(EVR_GPU_LAYOUT_CW8, 0, 150); /* a tree built without spatial splits */
    test_deform_refit(EVR_GPU_LAYOUT_CW8);
    test_deform_refit(EVR_GPU_LAYOUT_BVH4);
    printf("(%.1f s)\n", now() - t);
    test_many_instances(600, 20000 / RAY_SCALE,
                        &tot); /* Embree takes ~1.5 ms per quaternion-motion instance */
    printf("(%.1f s)\n", now() - t);
    {
        /* a saccade starts at 1.025 s; a blink closes the upper lid over 0.665 .. 0.765 s */
        static const double eye_t0[2] = {1.0, 0.72}, square_t0[1] = {0.5};
        /* grouped as the CPU backend groups: skin and orbit never move; sclera, cornea, iris and
         * pupil are on nodes of their own under the animated "eyeball" node, the lashes under
         * the lids', so each is a group */
        /* and the nodes and triangle references of the eye with its iris, pupil and lashes */
        static const uint32_t eye_counts[4] = {5485, 35781, 8519, 35243};
        scene_expect eye = {"sclera: sclera | cornea: cornea | iris: iris | pupil: pupil | "
                            "upper_lid: upper_lid | upper_lashes: upper_lashes | lower_lid: "
                            "lower_lid | lower_lashes: lower_lashes | static: skin orbit",
                            eye_counts, 0, 0, 0};
        /* deforming: moving (blob-a, the elbow), across the weight curve's key at 1.0, then
         * the weights and the elbow held (from 1.5 on): the last two segments hold still */
        static const double deform_t0[4] = {0.3, 0.98, 1.6, 1.6 + 1.0 / 30.0};
        scene_expect deforming = {"static: floor | blob-a: blob | ball: ball | skinned: arm | "
                                  "blob-b: blob",
                                  NULL, 1, 1, 0};
        deform_scene ds;
        test_demo("eye", &eye, eye_t0, 2, 60000 / RAY_SCALE, 45000 / RAY_SCALE, 15000 / RAY_SCALE,
                  &tot);
        printf("(%.1f s)\n", now() - t);
#ifdef EVR_TRAVERSE_STATS
        {
            static const double city_t0[1] = {1.0}; /* the camera flying down the street */
            test_demo("city", NULL, city_t0, 1, 20000, 2000, 2000, &tot);
        }
#endif
        test_demo("square", NULL, square_t0, 1, 20000 / RAY_SCALE, 10000 / RAY_SCALE,
                  10000 / RAY_SCALE, &tot);
        printf("(%.1f s)\n", now() - t);
        deform_scene_make(&ds);
        test_scene("deforming", &ds.s, &deforming, deform_t0, 4, 20000 / RAY_SCALE,
                   10000 / RAY_SCALE, 10000 / RAY_SCALE, &tot);
        deform_scene_free(&ds);
        printf("(%.1f s)\n", now() - t);
    }
    /* each ray is asked twice (closest and occlusion): rates are per question */
    printf(
        "all: %ld rays x 2 queries; disagreements %.2e per query (edge %.2e, contact %.2e, unexplained %ld); "
        "camera and random rays alone %.2e\n",
        tot.rays, (double)tot.mismatches / (2.0 * (double)tot.rays),
        (double)tot.edge / (2.0 * (double)tot.rays), (double)tot.contact / (2.0 * (double)tot.rays),
        tot.unexplained, (double)tot.well_mismatches / (2.0 * (double)tot.well_rays));
    CHECK(tot.rays >= 200000 / RAY_SCALE);
    CHECK(tot.unexplained == 0);
    CHECK((double)tot.mismatches / (2.0 * (double)tot.rays) < MAX_MISMATCH_RATE);
    CHECK((double)tot.edge / (2.0 * (double)tot.rays) < MAX_MISMATCH_RATE);
    CHECK((double)tot.well_mismatches / (2.0 * (double)tot.well_rays) < MAX_MISMATCH_RATE);
    printf(
        "static group's hit, then the others' nearer: %ld rays, %ld differ from one search of all groups\n",
        split_rays, split_differ);
    CHECK(split_rays > 0 && split_differ == 0);
    return check_report("test_gpu_bvh");
}
