/* Textures filtered by the ray's footprint: the mip pyramid built at import
 * (scene/texture_mips.c), the trilinear lookup and the ray-cone level of detail
 * (core/material.h, core/shading.h). */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "core/shading.h"
#include "scene/texture_mips.h"

/* A w x h texture with every texel's four channels from fill(x, y, c). */
static evr_texture make_texture(int w, int h, float (*fill)(int x, int y, int c))
{
    evr_texture t;
    memset(&t, 0, sizeof t);
    t.width = w;
    t.height = h;
    t.rgba = malloc((size_t)w * (size_t)h * 4 * sizeof(float));
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 4; c++) t.rgba[4 * ((size_t)y * w + x) + c] = fill(x, y, c);
    return t;
}

static evr_texture_view view_of(const evr_texture *t)
{
    evr_texture_view v;
    v.width = t->width;
    v.height = t->height;
    v.levels = t->levels;
    v.rgba = t->rgba;
    return v;
}

static float checker(int x, int y, int c)
{
    (void)c;
    return (float)((x + y) & 1);
}

/* Checks of 3 x 3 texels: not a power of two, so no level is exactly uniform. */
static float checker3(int x, int y, int c)
{
    (void)c;
    return (float)((x / 3 + y / 3) & 1);
}

/* Deterministic noise in [0, 1), a different value per channel. */
static float noise(int x, int y, int c)
{
    unsigned h = (unsigned)x * 73856093u ^ (unsigned)y * 19349663u ^ (unsigned)c * 83492791u;
    h ^= h >> 13;
    h *= 0x5bd1e995u;
    h ^= h >> 15;
    return (float)(h & 0xffffu) / 65536.0f;
}

static float ramp(int x, int y, int c) { return (float)(x + 10 * y + 100 * c); }

/* Mean of channel c over level k. */
static double level_mean(const evr_texture_view *t, int k, int c)
{
    const evr_texture_view l = evr_texture_level_view(t, k);
    double s = 0.0;
    for (long i = 0; i < (long)l.width * l.height; i++) s += l.rgba[4 * i + c];
    return s / ((double)l.width * l.height);
}

/* Level sizes: each halves (rounded down, at least 1) down to 1 x 1; the array holds them all. */
static void test_sizes(void)
{
    static const int dims[][2] = {{8, 8}, {5, 3}, {1, 7}, {1, 1}, {6, 1}, {7, 7}, {640, 480}};
    for (size_t i = 0; i < sizeof dims / sizeof dims[0]; i++) {
        evr_error err;
        evr_texture t = make_texture(dims[i][0], dims[i][1], noise);
        CHECK(evr_texture_build_mips(&t, &err) == EVR_OK);
        int w = dims[i][0], h = dims[i][1], levels = 1;
        long texels = (long)w * h;
        while (w > 1 || h > 1) {
            w = w / 2 > 1 ? w / 2 : 1;
            h = h / 2 > 1 ? h / 2 : 1;
            const evr_texture_view v = view_of(&t);
            const evr_texture_view l = evr_texture_level_view(&v, levels);
            CHECK(l.width == w && l.height == h);
            CHECK(l.rgba == t.rgba + 4 * texels);
            texels += (long)w * h;
            levels++;
        }
        CHECK(t.levels == levels);
        const evr_texture_view v = view_of(&t);
        CHECK(evr_texture_texels(&v, t.levels) == texels);
        /* memory: at most 4/3 of level 0 for a square texture */
        if (dims[i][0] == dims[i][1] && dims[i][0] > 1)
            CHECK(3 * texels <= 4 * (long)dims[i][0] * dims[i][1]);
        free(t.rgba);
    }
}

/* Odd sizes weigh each texel by the area it covers: 3 -> 1 is the mean of three; 5 -> 2 gives
 * the middle texel half to each side; even sizes are 2 x 2 boxes. */
static void test_weights(void)
{
    evr_error err;
    evr_texture t = make_texture(5, 3, ramp);
    CHECK(evr_texture_build_mips(&t, &err) == EVR_OK);
    CHECK(t.levels == 3);
    const evr_texture_view v = view_of(&t);
    const evr_texture_view l1 = evr_texture_level_view(&v, 1); /* 2 x 1 */
    const evr_texture_view l2 = evr_texture_level_view(&v, 2); /* 1 x 1 */
    for (int c = 0; c < 4; c++) {
        /* rows 0..2 average to row 1 (10 + 100 c); columns (0, 1, half of 2) / 2.5 */
        CHECK_NEAR(l1.rgba[c], (0.0 + 1.0 + 0.5 * 2.0) / 2.5 + 10.0 + 100.0 * c, 1e-4);
        CHECK_NEAR(l1.rgba[4 + c], (0.5 * 2.0 + 3.0 + 4.0) / 2.5 + 10.0 + 100.0 * c, 1e-4);
        CHECK_NEAR(l2.rgba[c], 2.0 + 10.0 + 100.0 * c, 1e-4);
    }
    free(t.rgba);
    t = make_texture(4, 2, ramp);
    CHECK(evr_texture_build_mips(&t, &err) == EVR_OK);
    CHECK(t.levels == 3);
    CHECK(t.rgba[4 * 8] == (0.0f + 1.0f + 10.0f + 11.0f) / 4.0f);
    free(t.rgba);
}

/* Every level keeps level 0's mean (energy), alpha included, for odd and even sizes; a
 * checkerboard's levels converge to its mean (0.5) and the last level is it. */
static void test_means(void)
{
    static const int dims[][2] = {{7, 5}, {16, 16}, {33, 9}, {9, 9}};
    for (size_t i = 0; i < sizeof dims / sizeof dims[0]; i++) {
        evr_error err;
        evr_texture t = make_texture(dims[i][0], dims[i][1], noise);
        CHECK(evr_texture_build_mips(&t, &err) == EVR_OK);
        const evr_texture_view v = view_of(&t);
        for (int c = 0; c < 4; c++) {
            const double m0 = level_mean(&v, 0, c);
            for (int k = 1; k < t.levels; k++) CHECK_NEAR(level_mean(&v, k, c), m0, 2e-6);
        }
        free(t.rgba);

        t = make_texture(dims[i][0], dims[i][1], checker);
        CHECK(evr_texture_build_mips(&t, &err) == EVR_OK);
        const evr_texture_view cv = view_of(&t);
        const double mean = level_mean(&cv, 0, 0);
        double last_dev = 1.0;
        for (int k = 1; k < t.levels; k++) {
            const evr_texture_view l = evr_texture_level_view(&cv, k);
            double dev = 0.0;
            for (long j = 0; j < (long)l.width * l.height; j++)
                dev = fmax(dev, fabs(l.rgba[4 * j] - mean));
            CHECK(dev <= last_dev + 1e-6);
            last_dev = dev;
        }
        CHECK(last_dev < 1e-6);
        if (dims[i][0] % 2 == 0 && dims[i][1] % 2 == 0) {
            const evr_texture_view l1 = evr_texture_level_view(&cv, 1);
            for (long j = 0; j < (long)l1.width * l1.height; j++) CHECK(l1.rgba[4 * j] == 0.5f);
        }
        free(t.rgba);
    }
}

/* The lookup: lod 0 (and below) is level 0's bilinear exactly; a lod between levels blends the
 * two levels' bilinear lookups; above the last level, the last level. */
static void test_lookup(void)
{
    evr_error err;
    evr_texture t = make_texture(37, 20, noise);
    CHECK(evr_texture_build_mips(&t, &err) == EVR_OK);
    const evr_texture_view v = view_of(&t);
    const evr_texture_view l1 = evr_texture_level_view(&v, 1), l2 = evr_texture_level_view(&v, 2);
    const evr_texture_view last = evr_texture_level_view(&v, t.levels - 1);
    for (int i = 0; i < 50; i++) {
        const float u = noise(i, 1, 0) * 3.0f - 1.0f, w = noise(i, 2, 0) * 3.0f - 1.0f;
        float a[4], b[4], c[4], d[4];
        evr_texture_bilinear(&v, u, w, a);
        evr_texture_sample(&v, u, w, 0.0f, b);
        CHECK(memcmp(a, b, sizeof a) == 0);
        evr_texture_sample(&v, u, w, EVR_TEX_LOD_SHARPEST, b);
        CHECK(memcmp(a, b, sizeof a) == 0);
        evr_texture_bilinear(&l1, u, w, a);
        evr_texture_bilinear(&l2, u, w, b);
        evr_texture_sample(&v, u, w, 1.25f, c);
        for (int k = 0; k < 4; k++) CHECK_NEAR(c[k], 0.75 * a[k] + 0.25 * b[k], 1e-6);
        evr_texture_sample(&v, u, w, 1.0f, c);
        CHECK(memcmp(a, c, sizeof a) == 0);
        evr_texture_bilinear(&last, u, w, a);
        evr_texture_sample(&v, u, w, 40.0f, d);
        CHECK(memcmp(a, d, sizeof a) == 0);
    }
    free(t.rgba);
}

/* A plane z = 0 of half-width 1 (uv [0, 1]^2 over [-1, 1]^2) with a texture n x n texels, seen
 * from (0, 0, dist) along dir; xf places the instance. The surface at the plane's point (px, py). */
typedef struct {
    evr_mesh_view mesh;
    evr_material_params mat;
    evr_instance_view inst;
    evr_texture_view tex;
    evr_render_scene rs;
} plane_scene;

static const float plane_pos[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
static const float plane_nrm[] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
static const float plane_uv[] = {0, 1, 1, 1, 1, 0, 0, 0};
static const uint32_t plane_idx[] = {0, 1, 2, 0, 2, 3};

static void plane_init(plane_scene *p, const evr_texture *t)
{
    memset(p, 0, sizeof *p);
    p->mesh.positions = plane_pos;
    p->mesh.normals = plane_nrm;
    p->mesh.uvs = plane_uv;
    p->mesh.indices = plane_idx;
    p->mesh.num_triangles = 2;
    evr_material_defaults(&p->mat);
    p->mat.tex[EVR_TEX_BASE].index = 0;
    p->inst.track = -1;
    p->inst.deform = -1;
    p->tex = view_of(t);
    p->rs.meshes = &p->mesh;
    p->rs.materials = &p->mat;
    p->rs.textures = &p->tex;
    p->rs.instances = &p->inst;
    p->rs.num_instances = 1;
}

/* The surface where a ray from org hits the plane as xf places it (plane z = xf's z). */
static void plane_hit(const plane_scene *p, const evr_m34 *xf, evr_v3 org, evr_v3 target,
                      float cone_spread, evr_surface *s)
{
    evr_ray r;
    r.org = org;
    r.dir = evr_v3_norm(evr_v3_sub(target, org));
    const float t = evr_v3_len(evr_v3_sub(target, org));
    /* barycentrics of target's object-space point in triangle 0 (0, 1, 2) */
    const evr_v3 q = evr_v3_make((target.x - xf->m[0][3]) / xf->m[0][0],
                                 (target.y - xf->m[1][3]) / xf->m[1][1], 0.0f);
    const float u = (q.x + 1.0f) / 2.0f - (q.y + 1.0f) / 2.0f, v = (q.y + 1.0f) / 2.0f;
    evr_surface_at(&p->rs, 0, 0, u, v, xf, 0.0f, r, t, cone_spread * t, s);
}

static evr_m34 scale_xf(float k, float z)
{
    evr_m34 m;
    memset(&m, 0, sizeof m);
    m.m[0][0] = m.m[1][1] = m.m[2][2] = k;
    m.m[2][3] = z;
    return m;
}

/* The level of detail of a plane at a known distance is the analytic one: a pixel's cone
 * spread * dist wide, over texels 2 / n wide, is log2(spread * dist * n / 2) levels up; seen at
 * 60 degrees from the normal one level more; the plane scaled twice as large, one level less.
 * No cone: level 0 exactly (the untextured-path identity). */
static void test_lod(void)
{
    evr_error err;
    evr_texture t = make_texture(256, 256, noise);
    CHECK(evr_texture_build_mips(&t, &err) == EVR_OK);
    plane_scene p;
    plane_init(&p, &t);
    const evr_camera_intr cam = evr_camera_intr_make(64, 64, 0.8f);
    const float spread = evr_camera_pixel_spread(&cam);
    CHECK_NEAR(spread, atan(2.0 * tan(0.4) / 64.0), 1e-7);
    const evr_m34 id = scale_xf(1.0f, 0.0f);
    const float dist = 3.0f;
    evr_surface s;
    plane_hit(&p, &id, evr_v3_make(0.2f, 0.1f, dist), evr_v3_make(0.2f, 0.1f, 0.0f), spread, &s);
    const double want = log2(spread * dist * 256.0 / 2.0);
    CHECK_NEAR(evr_texture_level(&p.tex, &p.mat.tex[EVR_TEX_BASE], s.tex_lod), want, 1e-4);
    /* the albedo is the lookup at that level */
    float tex[4];
    evr_texture_sample(&p.tex, 0.6f, 0.45f, (float)want, tex);
    CHECK_NEAR(s.albedo[0], tex[0], 1e-4);
    /* 60 degrees off the normal, the same distance: footprint twice as wide */
    const evr_v3 at = evr_v3_make(0.1f, -0.2f, 0.0f);
    const float sx = dist * sinf((float)(EVR_PI / 3.0)), sz = dist * cosf((float)(EVR_PI / 3.0));
    plane_hit(&p, &id, evr_v3_make(at.x + sx, at.y, sz), at, spread, &s);
    CHECK_NEAR(evr_texture_level(&p.tex, &p.mat.tex[EVR_TEX_BASE], s.tex_lod), want + 1.0, 1e-3);
    /* the instance scaled by 2 (at z = -1, the same distance): texels twice as large */
    const evr_m34 big = scale_xf(2.0f, -1.0f);
    plane_hit(&p, &big, evr_v3_make(0.2f, 0.1f, dist - 1.0f), evr_v3_make(0.2f, 0.1f, -1.0f),
              spread, &s);
    CHECK_NEAR(evr_texture_level(&p.tex, &p.mat.tex[EVR_TEX_BASE], s.tex_lod), want - 1.0, 1e-4);
    /* a texture transform tiling the texture 4 x 4: two levels more */
    p.mat.tex[EVR_TEX_BASE].xf[0] = p.mat.tex[EVR_TEX_BASE].xf[4] = 4.0f;
    CHECK_NEAR(evr_texture_level(&p.tex, &p.mat.tex[EVR_TEX_BASE], s.tex_lod), want + 1.0, 1e-4);
    p.mat.tex[EVR_TEX_BASE].xf[0] = p.mat.tex[EVR_TEX_BASE].xf[4] = 1.0f;
    /* no cone: the sharpest level, the albedo level 0's bilinear lookup */
    plane_hit(&p, &id, evr_v3_make(0.2f, 0.1f, dist), evr_v3_make(0.2f, 0.1f, 0.0f), 0.0f, &s);
    CHECK(s.tex_lod == EVR_TEX_LOD_SHARPEST);
    evr_texture_bilinear(&p.tex, 0.6f, 0.45f, tex);
    CHECK(s.albedo[0] == tex[0] && s.albedo[1] == tex[1] && s.albedo[2] == tex[2]);
    free(t.rgba);
}

/* Why: a checkerboard of checks 3/8 of a pixel wide, sampled at the pixel centres of a row as it
 * slides by a tenth of a texel at a time. Sharp (level 0), each pixel's value jumps between
 * black and white (events a real pixel, which averages its area, would not make); filtered by
 * the pixels' cones, every pixel sees nearly the mean at every step. */
static void test_moving_checker(void)
{
    evr_error err;
    evr_texture t = make_texture(1024, 1024, checker3);
    CHECK(evr_texture_build_mips(&t, &err) == EVR_OK);
    plane_scene p;
    plane_init(&p, &t);
    const float dist = 2.0f;
    /* 1024 texels over 2 world units; one pixel spans 8 texels: spread * dist = 16 / 1024 */
    const float spread = 16.0f / 1024.0f / dist;
    const float y = -0.59765625f; /* texel rows 817 and 818: one row of checks */
    double sharp_dev = 0.0, filtered_dev = 0.0;
    for (int step = 0; step < 20; step++) {
        const evr_m34 xf = scale_xf(1.0f, 0.0f);
        for (int px = 0; px < 32; px++) {
            const float x = -0.5f + (float)px * spread * dist + (float)step * 0.1f * 2.0f / 1024.0f;
            evr_surface s;
            plane_hit(&p, &xf, evr_v3_make(x, y, dist), evr_v3_make(x, y, 0.0f), spread, &s);
            filtered_dev = fmax(filtered_dev, fabs(s.albedo[0] - 0.5));
            plane_hit(&p, &xf, evr_v3_make(x, y, dist), evr_v3_make(x, y, 0.0f), 0.0f, &s);
            sharp_dev = fmax(sharp_dev, fabs(s.albedo[0] - 0.5));
        }
    }
    printf("test_moving_checker: |albedo - mean| up to %.3f sharp, %.3f filtered\n", sharp_dev,
           filtered_dev);
    CHECK(sharp_dev > 0.3);
    CHECK(filtered_dev < 0.03);
    free(t.rgba);
}

int main(void)
{
    test_sizes();
    test_weights();
    test_means();
    test_lookup();
    test_lod();
    test_moving_checker();
    return check_report("test_texture");
}
