/* The hits a material rules out (core/hit_filter.h) in the GPU backend's traversal
 * (src/cuda/gpu_traverse.h, its general search), run on the host, against the scene's geometry
 * worked out by hand, for both node layouts, with the static instances baked into world space and
 * instanced (EVR_STATIC_BAKE_LIMIT 0), at several ray times:
 *   - a card (moving in x) with an alpha MASK checkerboard: camera rays pass its holes and meet
 *     the wall behind, shadow rays (evr_trace_any) pass them too;
 *   - a single-sided card facing away from the camera (moving in y): camera rays never meet it,
 *     shadow rays from the wall do (they see back faces);
 *   - a single-sided card wound away from the camera but under a mirroring node (scale -1 in x):
 *     its world-space winding faces the camera (glTF: the determinant flips the winding), seen;
 *   - the evr_material_filter bits; the alpha test reads the texture through its transform
 *     (KHR_texture_transform, evr_texture_uv). */
#include "check.h"
#include "backend.h"
#include "core/hit_filter.h"
#include "cuda/gpu_bvh.h"
#include "cuda/gpu_traverse.h"
#include "scene/scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NTEX 4

typedef struct {
    evr_scene s;
    evr_mesh meshes[4];
    evr_material mats[3];
    evr_texture tex;
    evr_node nodes[4];
    evr_instance inst[4];
    evr_camera_desc cam;
    float texels[NTEX * NTEX * 4];
    float pos[4][12];
    double times[2];
    float card_t[6], back_t[6];
} filter_scene;

static const float quad_pos[12] = {-0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0.5f, 0.5f, 0, -0.5f, 0.5f, 0};
static const float quad_nrm[12] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
static const float quad_uv[8] = {0, 1, 1, 1, 1, 0, 0, 0}; /* uv (0, 0) at the top-left */
static const uint32_t quad_front[6] = {0, 1, 2, 0, 2, 3}; /* counter-clockwise seen from +Z */
static const uint32_t quad_back[6] = {0, 2, 1, 0, 3, 2};

static int checker(float u, float v)
{
    const int c = (int)(u * NTEX), r = (int)(v * NTEX);
    return (c + r) % 2 == 0;
}

static void quad(evr_mesh *m, float *p, const char *name, float size, const uint32_t *idx,
                 int material)
{
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "%s", name);
    for (int k = 0; k < 12; k++) p[k] = quad_pos[k] * size;
    m->num_vertices = 4;
    m->num_triangles = 2;
    m->positions = p;
    m->normals = (float *)quad_nrm;
    m->uvs = (float *)quad_uv;
    m->indices = (uint32_t *)idx;
    m->material = material;
    m->bounds_min = evr_v3_make(-0.5f * size, -0.5f * size, 0);
    m->bounds_max = evr_v3_make(0.5f * size, 0.5f * size, 0);
}

static void node(evr_node *n, const char *name, evr_v3 t, float sx)
{
    memset(n, 0, sizeof *n);
    snprintf(n->name, sizeof n->name, "%s", name);
    n->parent = -1;
    n->translation = t;
    n->scale = evr_v3_make(sx, 1, 1);
    n->rotation = evr_quat_make(1, 0, 0, 0);
    n->rest_matrix = evr_m34_identity();
    n->rest_matrix.m[0][0] = sx;
    n->rest_matrix.m[0][3] = t.x;
    n->rest_matrix.m[1][3] = t.y;
    n->rest_matrix.m[2][3] = t.z;
}

/* wall z = -4 (8 x 8, double-sided), card at z = -2 moving +0.25 in x over [0, 1] s (MASK),
 * back card at (1.2, 0, -2) moving +0.2 in y (single-sided, facing -Z), mirrored card at
 * (-1.2, 0, -2) scale (-1, 1, 1) (single-sided, wound facing -Z in its own space) */
static void scene_make(filter_scene *f)
{
    evr_scene *s = &f->s;
    memset(f, 0, sizeof *f);
    for (int r = 0; r < NTEX; r++)
        for (int c = 0; c < NTEX; c++) {
            float *t = f->texels + 4 * (r * NTEX + c);
            t[0] = t[1] = t[2] = 1.0f;
            t[3] = (c + r) % 2 == 0 ? 1.0f : 0.0f;
        }
    f->tex.width = f->tex.height = NTEX;
    f->tex.levels = 1;
    f->tex.rgba = f->texels;
    for (int i = 0; i < 3; i++) evr_material_defaults(&f->mats[i].p);
    f->mats[0].p.double_sided = 1;
    f->mats[1].p.double_sided = 1;
    f->mats[1].p.alpha_mode = EVR_ALPHA_MASK;
    f->mats[1].p.tex[EVR_TEX_BASE].index = 0;
    quad(&f->meshes[0], f->pos[0], "wall", 8, quad_front, 0);
    quad(&f->meshes[1], f->pos[1], "card", 1, quad_front, 1);
    quad(&f->meshes[2], f->pos[2], "back", 1, quad_back, 2);
    quad(&f->meshes[3], f->pos[3], "mirrored", 1, quad_back, 2);
    node(&f->nodes[0], "wall", evr_v3_make(0, 0, -4), 1);
    node(&f->nodes[1], "card", evr_v3_make(0, 0, -2), 1);
    node(&f->nodes[2], "back", evr_v3_make(1.2f, 0, -2), 1);
    node(&f->nodes[3], "mirrored", evr_v3_make(-1.2f, 0, -2), -1);
    f->times[0] = 0.0;
    f->times[1] = 1.0;
    const float card_t[6] = {0, 0, -2, 0.25f, 0, -2}, back_t[6] = {1.2f, 0, -2, 1.2f, 0.2f, -2};
    memcpy(f->card_t, card_t, sizeof card_t);
    memcpy(f->back_t, back_t, sizeof back_t);
    f->nodes[1].t_curve.num_keys = f->nodes[2].t_curve.num_keys = 2;
    f->nodes[1].t_curve.times = f->nodes[2].t_curve.times = f->times;
    f->nodes[1].t_curve.values = f->card_t;
    f->nodes[2].t_curve.values = f->back_t;
    f->nodes[1].animated = f->nodes[2].animated = 1;
    for (int i = 0; i < 4; i++) {
        f->inst[i].mesh = i;
        f->inst[i].node = i;
        f->nodes[i].has_bounds = 1;
        f->nodes[i].bounds_min = f->meshes[i].bounds_min;
        f->nodes[i].bounds_max = f->meshes[i].bounds_max;
    }
    f->cam.node = -1;
    f->cam.yfov = 0.927295218f; /* 2 atan(0.5): the plane z = -1 spans [-0.5, 0.5] */
    f->cam.local = evr_m34_identity();
    snprintf(f->cam.name, sizeof f->cam.name, "camera");
    s->num_meshes = 4;
    s->meshes = f->meshes;
    s->num_materials = 3;
    s->materials = f->mats;
    s->num_textures = 1;
    s->textures = &f->tex;
    s->num_nodes = 4;
    s->nodes = f->nodes;
    s->num_instances = 4;
    s->instances = f->inst;
    s->num_cameras = 1;
    s->cameras = &f->cam;
    s->anim_start = 0.0;
    s->anim_end = 1.0;
    s->bounds_min = evr_v3_make(-4, -4, -4);
    s->bounds_max = evr_v3_make(4, 4, -2);
}

/* What a camera ray through (x, y) on the plane z = -1 meets at time t: the instance (the card
 * where opaque, the mirrored card, else the wall), -2 when (x, y) is too near an edge to say. */
static int expect_camera(float x, float y, float t)
{
    const float px = 2 * x, py = 2 * y, e = 2e-3f, cu = px - 0.25f * t + 0.5f, cv = 0.5f - py;
    if (fabsf(fabsf(py) - 0.5f) < e) return -2;
    if (fabsf(py) < 0.5f) {
        if (fabsf(cu) < e || fabsf(cu - 1) < e || fabsf(px + 1.7f) < e || fabsf(px + 0.7f) < e)
            return -2;
        if (cu > 0 && cu < 1) { /* the checker's cell edges */
            const float gu = cu * NTEX - floorf(cu * NTEX + 0.5f),
                        gv = cv * NTEX - floorf(cv * NTEX + 0.5f);
            if (fabsf(gu) < e * NTEX || fabsf(gv) < e * NTEX) return -2;
            if (checker(cu, cv)) return 1;
        }
        if (px > -1.7f && px < -0.7f) return 3;
    }
    return 0;
}

/* Whether the wall at (x, y) is in the shadow of light travelling along -Z at time t (-2: near
 * an edge). */
static int expect_shadow(float x, float y, float t)
{
    const float e = 2e-3f, cu = x - 0.25f * t + 0.5f, cv = 0.5f - y, by = y - 0.2f * t;
    if (fabsf(fabsf(y) - 0.5f) < e || fabsf(fabsf(by) - 0.5f) < e || fabsf(cu) < e ||
        fabsf(cu - 1) < e || fabsf(fabsf(x - 1.2f) - 0.5f) < e || fabsf(fabsf(x + 1.2f) - 0.5f) < e)
        return -2;
    if (cu > 0 && cu < 1 && fabsf(y) < 0.5f) {
        const float gu = cu * NTEX - floorf(cu * NTEX + 0.5f),
                    gv = cv * NTEX - floorf(cv * NTEX + 0.5f);
        if (fabsf(gu) < e * NTEX || fabsf(gv) < e * NTEX) return -2;
        if (checker(cu, cv)) return 1;
    }
    if (fabsf(x - 1.2f) < 0.5f && fabsf(by) < 0.5f) return 1; /* its back face: still a shadow */
    if (fabsf(x + 1.2f) < 0.5f && fabsf(y) < 0.5f) return 1;
    return 0;
}

/* The segment [0, 1] s's motion keys: the animated nodes' two ends (linear), the others one. */
static void keys_make(const filter_scene *f, evr_motion_key *keys, int *off, int *cnt)
{
    int n = 0;
    for (int i = 0; i <= f->s.num_nodes; i++) {
        off[i] = n;
        cnt[i] = i < f->s.num_nodes && f->nodes[i].animated ? 2 : 1;
        for (int k = 0; k < cnt[i]; k++) {
            evr_m34 m =
                i < f->s.num_nodes ? evr_node_world_at(&f->s, i, (double)k) : evr_m34_identity();
            keys[n++] = evr_motion_key_from_matrix(&m);
        }
    }
}

static void test_layout(int layout, const char *what)
{
    filter_scene f;
    evr_render_host host;
    evr_gpu_bvh bvh;
    evr_gpu_top top;
    evr_gpu_scene_view v;
    evr_motion_key keys[16];
    int off[5], cnt[5];
    long cam_checked = 0, cam_wrong = 0, sh_checked = 0, sh_wrong = 0, seen[4] = {0, 0, 0, 0};
    scene_make(&f);
    CHECK_OK(evr_render_host_init(&host, &f.s, 0, 64, 64, 0.0f, &e_));
    CHECK(host.meshes[0].filter == 0);
    CHECK(host.meshes[1].filter == EVR_FILTER_MASK);
    CHECK(host.meshes[2].filter == EVR_FILTER_CULL && host.meshes[3].filter == EVR_FILTER_CULL);
    keys_make(&f, keys, off, cnt);
    host.rs.keys = keys;
    host.rs.track_offset = off;
    host.rs.track_count = cnt;
    memset(&top, 0, sizeof top);
    CHECK_OK(evr_gpu_bvh_build(&f.s, layout, NULL, &bvh, &e_));
    CHECK(bvh.filtered == 1);
    CHECK_OK(evr_gpu_top_build(&bvh, NULL, &host.rs, &top, &e_));
    evr_gpu_scene_view_host(&bvh, NULL, &top, &v);
    CHECK(v.filtered == 1 && evr__trace_general(&v));
    for (int ti = 0; ti < 3; ti++) {
        const float t = 0.2f + 0.3f * (float)ti;
        for (int j = 0; j < 96; j++)
            for (int i = 0; i < 192; i++) {
                const float x = -1.0f + (2.0f * (float)i + 1.0f) / 192.0f,
                            y = -0.5f + ((float)j + 0.5f) / 96.0f;
                evr_ray ray;
                evr_gpu_hit h = {0}; /* written on a hit only */
                int want = expect_camera(x, y, t), got;
                ray.org = evr_v3_make(0, 0, 0);
                ray.dir = evr_v3_norm(evr_v3_make(x, y, -1));
                got = evr_trace_closest(&v, &host.rs, ray, 1e30f, t, &h) ? h.instance : -1;
                if (want != -2) {
                    cam_checked++;
                    cam_wrong += got != want;
                    if (got >= 0) seen[got]++;
                }
                /* a shadow ray from the wall at (2x, 2y) towards the light (+Z) */
                const float wx = 2 * x, wy = 2 * y;
                want = expect_shadow(wx, wy, t);
                if (want == -2) continue;
                ray.org = evr_v3_make(wx, wy, -4);
                ray.dir = evr_v3_make(0, 0, 1);
                got = evr_trace_any(&v, &host.rs, ray, 1e-3f, 3.5f, t);
                sh_checked++;
                sh_wrong += got != want;
            }
    }
    printf("%s: camera rays %ld checked, %ld wrong (card %ld, mirrored %ld, back %ld); shadow rays "
           "%ld checked, %ld wrong\n",
           what, cam_checked, cam_wrong, seen[1], seen[3], seen[2], sh_checked, sh_wrong);
    CHECK(cam_checked > 40000 && cam_wrong == 0);
    CHECK(sh_checked > 40000 && sh_wrong == 0);
    CHECK(seen[1] > 1000 && seen[3] > 1000 && seen[2] == 0);
    evr_gpu_top_free(&top);
    evr_gpu_bvh_free(&bvh);
    evr_render_host_free(&host);
}

/* evr_hit_alpha_cut reads the base texture through its KHR_texture_transform: with
 * uv' = (u / 2 + 1 / 4, v) the card's checkerboard shows cell column 1 where the untransformed
 * texture shows column 0. */
static void test_texture_transform(void)
{
    filter_scene f;
    evr_render_host host;
    scene_make(&f);
    CHECK_OK(evr_render_host_init(&host, &f.s, 0, 8, 8, 0.0f, &e_));
    /* triangle 0 of the card: uv = (1-a-b) (0,1) + a (1,1) + b (1,0) = (a + b, 1 - b); at
     * (a, b) = (0.05, 0.05): uv (0.1, 0.95), cell (0, 3): a hole (bilinear alpha 0.34); through
     * the transform uv (0.3, 0.95), cell (1, 3): opaque (alpha 0.58) */
    CHECK(evr_hit_alpha_cut(&host.rs, &host.meshes[1], 0, 0.05f, 0.05f) == 1);
    f.mats[1].p.tex[EVR_TEX_BASE].xf[0] = 0.5f;
    f.mats[1].p.tex[EVR_TEX_BASE].xf[2] = 0.25f;
    host.materials[1] = f.mats[1].p;
    CHECK(evr_hit_alpha_cut(&host.rs, &host.meshes[1], 0, 0.05f, 0.05f) == 0);
    evr_render_host_free(&host);
}

int main(void)
{
    evr_material_params m;
    evr_material_defaults(&m);
    m.double_sided = 1;
    CHECK(evr_material_filter(&m, 1) == 0);
    m.alpha_mode = EVR_ALPHA_MASK;
    CHECK(evr_material_filter(&m, 1) == 0); /* no texture, alpha 1 >= cutoff: never a hole */
    m.tex[EVR_TEX_BASE].index = 0;
    CHECK(evr_material_filter(&m, 1) == EVR_FILTER_MASK);
    CHECK(evr_material_filter(&m, 0) == 0); /* no uvs: the texture is not read */
    m.base_color[3] = 0.25f;
    m.double_sided = 0;
    CHECK(evr_material_filter(&m, 0) == (EVR_FILTER_MASK | EVR_FILTER_CULL));
    m.alpha_mode = EVR_ALPHA_BLEND;
    CHECK(evr_material_filter(&m, 1) == EVR_FILTER_CULL);

    test_texture_transform();
    test_layout(EVR_GPU_LAYOUT_CW8, "CW8, baked");
    test_layout(EVR_GPU_LAYOUT_BVH4, "BVH4, baked");
    setenv("EVR_STATIC_BAKE_LIMIT", "0", 1);
    test_layout(EVR_GPU_LAYOUT_CW8, "CW8, instanced");
    test_layout(EVR_GPU_LAYOUT_BVH4, "BVH4, instanced");
    return check_report("test_hit_filter");
}
