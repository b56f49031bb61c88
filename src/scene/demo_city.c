/* The "city" scene: a camera flying down a street through a large field of instanced buildings,
 * for scaling (millions of instanced triangles, thousands of instances).
 *
 * 12 building meshes (low blocks, mid-rises and stepped towers: boxes whose four facades carry a
 * grid of protruding window frames, a ledge every few floors and a parapet on the roof), each
 * stored once and placed by thousands of glTF nodes that share it (Assimp makes one evr_instance
 * per node, the meshes shared). Lots lie on a square grid of 36 m (streets of 14 m or more
 * between buildings of up to 22 m); the count buildings nearest the origin are placed, each of
 * a type and a quarter turn drawn from a hash of its lot. A ground plane, a low sun
 * (directional, white) and a camera flying at 40 m/s for 5 s down the street x = 0 (-z),
 * swaying and sinking from 34 m to 24 m above the ground, looking ahead and slightly down.
 *
 * detail tessellates every building finer without changing its shape: each facade cell (one
 * window: wall and frame) becomes detail x detail quads per face, so a building's triangles grow
 * as detail^2. At the defaults (detail 1, 4096 buildings): about 57k distinct triangles and 17M
 * instanced ones. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/demo_scenes.h"

#define CITY_SPACING 36.0 /* lot pitch (m) */
#define CITY_FLOOR 3.5    /* storey height (m) */
#define CITY_CELL 3.0     /* window pitch along a facade (m) */
#define CITY_TYPES 12
#define CITY_DURATION 5.0
#define CITY_KEYS 51 /* camera keys: every 0.1 s */

typedef struct {
    double wx, wz; /* footprint (m) */
    int floors;
    double top_wx, top_wz; /* stepped tower: the upper part's footprint (0: none) */
    int top_floors;
    float color[3];
} building_type;

static const building_type types[CITY_TYPES] = {
    {12, 12, 3, 0, 0, 0, {0.62f, 0.55f, 0.47f}},    {18, 12, 4, 0, 0, 0, {0.55f, 0.33f, 0.27f}},
    {15, 15, 6, 0, 0, 0, {0.70f, 0.68f, 0.62f}},    {21, 15, 5, 0, 0, 0, {0.45f, 0.47f, 0.50f}},
    {15, 21, 9, 0, 0, 0, {0.66f, 0.60f, 0.50f}},    {18, 18, 12, 0, 0, 0, {0.38f, 0.42f, 0.48f}},
    {12, 18, 8, 0, 0, 0, {0.72f, 0.66f, 0.56f}},    {21, 21, 10, 15, 15, 12, {0.50f, 0.52f, 0.55f}},
    {18, 18, 6, 12, 12, 20, {0.60f, 0.62f, 0.66f}}, {21, 18, 14, 0, 0, 0, {0.58f, 0.40f, 0.32f}},
    {15, 15, 16, 9, 9, 10, {0.42f, 0.46f, 0.52f}},  {21, 21, 8, 15, 12, 28, {0.68f, 0.70f, 0.74f}},
};

/* A tessellated rectangle: corner o, edges eu (cu cells) and ev (cv cells), normal n. */
static void panel(evr_demo_mesh *m, const double o[3], const double eu[3], const double ev[3],
                  int cu, int cv, const double n[3])
{
    uint32_t first = m->nv;
    int i, j, k;
    for (j = 0; j <= cv; j++)
        for (i = 0; i <= cu; i++) {
            double p[3], u = (double)i / cu, v = (double)j / cv;
            for (k = 0; k < 3; k++) p[k] = o[k] + u * eu[k] + v * ev[k];
            evr_demo_mesh_vertex(m, p, n, u, v);
        }
    evr_demo_mesh_grid(m, first, cu, cv);
}

/* An axis-aligned box from lo to hi, every face cut into d x d quads; bottom left out when
 * open_bottom. */
static void box(evr_demo_mesh *m, const double lo[3], const double hi[3], int d, int open_bottom)
{
    int axis, s, k;
    for (axis = 0; axis < 3; axis++)
        for (s = 0; s < 2; s++) {
            int u = (axis + 1) % 3, v = (axis + 2) % 3;
            double o[3], eu[3] = {0, 0, 0}, ev[3] = {0, 0, 0}, n[3] = {0, 0, 0};
            if (open_bottom && axis == 1 && s == 0) continue;
            for (k = 0; k < 3; k++) o[k] = lo[k];
            o[axis] = s ? hi[axis] : lo[axis];
            eu[u] = hi[u] - lo[u];
            ev[v] = hi[v] - lo[v];
            n[axis] = s ? 1.0 : -1.0;
            panel(m, o, eu, ev, d, d, n);
        }
}

/* The four facades of a block from y0 up over floors storeys, footprint wx x wz centred on the
 * origin: walls (cells of one window, d x d quads each), a frame around every window standing
 * 0.2 m out, a ledge every fourth floor. */
static void facades(evr_demo_mesh *m, double wx, double wz, double y0, int floors, int d)
{
    int side, i, j, k;
    double h = floors * CITY_FLOOR;
    for (side = 0; side < 4; side++) {
        /* walk the facade along t from corner a to corner b, outward normal n */
        int along_x = side % 2 == 0;
        double sgn = side < 2 ? 1.0 : -1.0;
        double len = along_x ? wx : wz;
        int cols = (int)floor(len / CITY_CELL + 0.5);
        double a[3], t[3] = {0, 0, 0}, n[3] = {0, 0, 0}, up[3] = {0, h, 0};
        if (cols < 1) cols = 1;
        if (along_x) { /* the facades facing +z and -z */
            a[0] = -sgn * wx / 2;
            a[1] = y0;
            a[2] = sgn * wz / 2;
            t[0] = sgn * wx;
            n[2] = sgn;
        } else { /* facing +x and -x */
            a[0] = sgn * wx / 2;
            a[1] = y0;
            a[2] = sgn * wz / 2;
            t[2] = -sgn * wz;
            n[0] = sgn;
        }
        panel(m, a, t, up, cols * d, floors * d, n);
        /* window frames: a shallow box per cell */
        for (j = 0; j < floors; j++)
            for (i = 0; i < cols; i++) {
                double lo[3], hi[3], c[3], hu = 0.5 * len / cols * 0.55,
                                           hv = 0.5 * CITY_FLOOR * 0.5;
                for (k = 0; k < 3; k++) c[k] = a[k] + t[k] * (i + 0.5) / cols + n[k] * 0.1;
                c[1] = y0 + (j + 0.55) * CITY_FLOOR;
                for (k = 0; k < 3; k++) {
                    double ext = fabs(t[k]) > 0 ? hu : k == 1 ? hv : 0.1;
                    lo[k] = c[k] - ext;
                    hi[k] = c[k] + ext;
                }
                box(m, lo, hi, d, 0);
            }
    }
    /* ledges: a slab 0.4 m out all round, every fourth floor (not at the top) */
    for (j = 4; j < floors; j += 4) {
        double lo[3] = {-wx / 2 - 0.4, y0 + j * CITY_FLOOR - 0.25, -wz / 2 - 0.4};
        double hi[3] = {wx / 2 + 0.4, y0 + j * CITY_FLOOR + 0.25, wz / 2 + 0.4};
        box(m, lo, hi, d, 0);
    }
}

/* Roof at height y over a footprint: the slab and a parapet of four thin boxes. */
static void roof(evr_demo_mesh *m, double wx, double wz, double y, int d)
{
    double lo[3] = {-wx / 2, y, -wz / 2}, hi[3] = {wx / 2, y + 0.01, wz / 2};
    int s;
    box(m, lo, hi, d, 1);
    for (s = 0; s < 4; s++) {
        double plo[3], phi[3];
        if (s < 2) {
            plo[0] = -wx / 2;
            phi[0] = wx / 2;
            plo[2] = s ? wz / 2 - 0.3 : -wz / 2;
            phi[2] = plo[2] + 0.3;
        } else {
            plo[2] = -wz / 2 + 0.3;
            phi[2] = wz / 2 - 0.3;
            plo[0] = s == 3 ? wx / 2 - 0.3 : -wx / 2;
            phi[0] = plo[0] + 0.3;
        }
        plo[1] = y;
        phi[1] = y + 1.0;
        box(m, plo, phi, d, 1);
    }
}

static int building_mesh(evr_gltf *g, int type, int d, int material)
{
    const building_type *b = &types[type];
    evr_demo_mesh m = {0};
    char name[32];
    double h = b->floors * CITY_FLOOR;
    facades(&m, b->wx, b->wz, 0.0, b->floors, d);
    roof(&m, b->wx, b->wz, h, d);
    if (b->top_floors > 0) {
        facades(&m, b->top_wx, b->top_wz, h, b->top_floors, d);
        roof(&m, b->top_wx, b->top_wz, h + b->top_floors * CITY_FLOOR, d);
    }
    snprintf(name, sizeof name, "building_%02d", type);
    return evr_demo_mesh_finish(g, &m, name, material);
}

static uint32_t hash2(int i, int j)
{
    uint32_t h = (uint32_t)i * 0x9e3779b1u ^ ((uint32_t)j + 0x7f4a7c15u) * 0x85ebca6bu;
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    h *= 0x297a2d39u;
    h ^= h >> 15;
    return h;
}

typedef struct {
    int i, j;
    double d2;
} lot;

static int lot_cmp(const void *pa, const void *pb)
{
    const lot *a = pa, *b = pb;
    if (a->d2 != b->d2) return a->d2 < b->d2 ? -1 : 1;
    if (a->j != b->j) return a->j < b->j ? -1 : 1;
    return (a->i > b->i) - (a->i < b->i);
}

/* Lot (i, j) centre: x = (i + 0.5) * spacing, z likewise, so the streets x = 0 and z = 0 run
 * between lots. */
static double lot_x(int i) { return (i + 0.5) * CITY_SPACING; }

/* The camera at time t (s): position and a point it looks at. */
static void camera_at(double t, double p[3], double target[3])
{
    double s = t / CITY_DURATION;
    p[0] = 2.5 * sin(2.0 * 3.14159265358979 * s);
    p[1] = 34.0 - 10.0 * s;
    p[2] = 100.0 - 40.0 * t;
    target[0] = 0.6 * p[0] + 6.0 * sin(2.0 * 3.14159265358979 * (s + 0.15));
    target[1] = p[1] - 9.0;
    target[2] = p[2] - 60.0;
}

void evr_demo_build_city_with(evr_gltf *g, int detail, int count)
{
    int mats[CITY_TYPES], meshes[CITY_TYPES], t, k, n, side, half;
    lot *lots;
    if (detail < 1) detail = 1;
    if (count < 0) count = 0;
    for (t = 0; t < CITY_TYPES; t++) {
        evr_gltf_material mat;
        char name[32];
        snprintf(name, sizeof name, "facade_%02d", t);
        evr_gltf_material_init(&mat, name);
        memcpy(mat.base_color, types[t].color, sizeof types[t].color);
        mats[t] = evr_gltf_add_material(g, &mat);
        meshes[t] = building_mesh(g, t, detail, mats[t]);
    }
    /* lots nearest the origin first */
    for (side = 2; side * side < count; side += 2) {}
    half = side / 2;
    lots = malloc(sizeof *lots * (size_t)side * (size_t)side);
    if (!lots) {
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while generating the city");
        return;
    }
    n = 0;
    for (k = 0; k < side * side; k++) {
        lots[n].i = k % side - half;
        lots[n].j = k / side - half;
        lots[n].d2 = lot_x(lots[n].i) * lot_x(lots[n].i) + lot_x(lots[n].j) * lot_x(lots[n].j);
        n++;
    }
    qsort(lots, (size_t)n, sizeof *lots, lot_cmp);
    for (k = 0; k < count; k++) {
        uint32_t h = hash2(lots[k].i, lots[k].j);
        int type = (int)(h % CITY_TYPES), turn = (int)((h >> 8) & 3);
        double a = 0.25 * 3.14159265358979 * turn; /* half the quarter-turn angle */
        char name[32];
        int node;
        /* taller types more often near the centre */
        if (lots[k].d2 < 300.0 * 300.0 && ((h >> 12) & 1)) type = 7 + (int)((h >> 16) % 5);
        snprintf(name, sizeof name, "b_%d_%d", lots[k].i, lots[k].j);
        node = evr_gltf_node(g, name, -1);
        evr_gltf_node_mesh(g, node, meshes[type]);
        evr_gltf_node_translation(g, node, (float)lot_x(lots[k].i), 0.0f, (float)lot_x(lots[k].j));
        if (turn) evr_gltf_node_rotation(g, node, 0.0f, (float)sin(a), 0.0f, (float)cos(a));
    }
    free(lots);

    /* the ground: a square reaching past the last lots */
    {
        evr_gltf_material mat;
        evr_demo_mesh m = {0};
        double e = (half + 2) * CITY_SPACING;
        double o[3] = {-e, 0, e}, eu[3] = {2 * e, 0, 0}, ev[3] = {0, 0, -2 * e}, up[3] = {0, 1, 0};
        int node;
        evr_gltf_material_init(&mat, "asphalt");
        mat.base_color[0] = 0.20f;
        mat.base_color[1] = 0.20f;
        mat.base_color[2] = 0.21f;
        panel(&m, o, eu, ev, 1, 1, up);
        node = evr_gltf_node(g, "ground", -1);
        evr_gltf_node_mesh(g, node,
                           evr_demo_mesh_finish(g, &m, "ground", evr_gltf_add_material(g, &mat)));
    }

    /* a low sun from the south-west: illuminance pi gives a white surface facing it radiance 1 */
    {
        static const float warm[3] = {1.0f, 0.95f, 0.85f};
        static const double from[3] = {-0.5, 0.45, 0.6}, zero[3] = {0, 0, 0}, yup[3] = {0, 1, 0};
        float q[4];
        int sun = evr_gltf_light(g, "sun", EVR_GLTF_DIRECTIONAL, warm, 3.14159265f, 0.0f, 0.0f);
        int node = evr_gltf_node(g, "sun", -1);
        evr_demo_look_at(from, zero, yup, q);
        evr_gltf_node_rotation(g, node, q[0], q[1], q[2], q[3]);
        evr_gltf_node_light(g, node, sun);
    }

    /* the camera: keys every 0.1 s of a smooth path (linear between keys) */
    {
        static const double yup[3] = {0, 1, 0};
        float times[CITY_KEYS], pos[3 * CITY_KEYS], rot[4 * CITY_KEYS];
        int cam = evr_gltf_camera(g, "city_camera", (float)(50.0 * 3.14159265358979 / 180.0),
                                  4.0f / 3.0f, 0.5f, 3000.0f);
        int node = evr_gltf_node(g, "city_camera", -1), anim;
        for (k = 0; k < CITY_KEYS; k++) {
            double tt = CITY_DURATION * k / (CITY_KEYS - 1), p[3], target[3];
            float q[4];
            camera_at(tt, p, target);
            evr_demo_look_at(p, target, yup, q);
            /* keep neighbouring quaternions in one hemisphere */
            if (k > 0 && q[0] * rot[4 * k - 4] + q[1] * rot[4 * k - 3] + q[2] * rot[4 * k - 2] +
                                 q[3] * rot[4 * k - 1] <
                             0)
                for (t = 0; t < 4; t++) q[t] = -q[t];
            times[k] = (float)tt;
            for (t = 0; t < 3; t++) pos[3 * k + t] = (float)p[t];
            for (t = 0; t < 4; t++) rot[4 * k + t] = q[t];
        }
        evr_gltf_node_translation(g, node, pos[0], pos[1], pos[2]);
        evr_gltf_node_rotation(g, node, rot[0], rot[1], rot[2], rot[3]);
        evr_gltf_node_camera(g, node, cam);
        anim = evr_gltf_animation(g, "fly");
        evr_gltf_channel(g, anim, node, EVR_GLTF_TRANSLATION, times, pos, CITY_KEYS,
                         EVR_GLTF_LINEAR);
        evr_gltf_channel(g, anim, node, EVR_GLTF_ROTATION, times, rot, CITY_KEYS, EVR_GLTF_LINEAR);
    }
}

void evr_demo_build_city(evr_gltf *g)
{
    evr_demo_build_city_with(g, EVR_CITY_DETAIL, EVR_CITY_BUILDINGS);
}

evr_status evr_demo_city_glb(int detail, int count, void **glb, size_t *size, evr_error *err)
{
    evr_gltf *g = evr_gltf_new("city");
    evr_status st;
    *glb = NULL;
    *size = 0;
    if (detail < 1 || detail > 64 || count < 0 || count > 1000000) {
        snprintf(err->msg, sizeof err->msg,
                 "city: detail must be 1..64 and the building count 0..1000000 (got %d, %d)",
                 detail, count);
        evr_gltf_free(g);
        return EVR_ERR_ARG;
    }
    if (!g) {
        snprintf(err->msg, sizeof err->msg, "demo city: out of memory");
        return EVR_ERR_NOMEM;
    }
    evr_demo_build_city_with(g, detail, count);
    st = evr_gltf_glb(g, glb, size, err);
    evr_gltf_free(g);
    return st;
}

evr_status evr_demo_city_load(int detail, int count, evr_scene **out, evr_error *err)
{
    void *glb = NULL;
    size_t size = 0;
    evr_status st;
    *out = NULL;
    st = evr_demo_city_glb(detail, count, &glb, &size, err);
    if (st != EVR_OK) return st;
    st = evr_scene_load_memory(glb, size, "glb", out, err);
    free(glb);
    return st;
}
