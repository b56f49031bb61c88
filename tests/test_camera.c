/* The camera: orthographic projection (core/camera.h), camera paths and TUM trajectories
 * (scene/camera_path.c), the run's camera with its overrides and the key fitting of its track
 * (scene/camera_rig.c), and the automatic framing (scene/framing.c): over the whole animation,
 * from a direction that sees the model. Scenes are built with scene/gltf_writer.h and loaded
 * through the importer. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "check.h"
#include "core/camera.h"
#include "scene/camera_rig.h"
#include "scene/framing.h"
#include "scene/gltf_writer.h"

#define PI_D 3.14159265358979323846

static double m34_maxdiff(const evr_m34 *a, const evr_m34 *b)
{
    double d = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 4; j++) d = fmax(d, fabs((double)a->m[i][j] - (double)b->m[i][j]));
    return d;
}

static evr_v3 column(const evr_m34 *m, int j)
{
    return evr_v3_make(m->m[0][j], m->m[1][j], m->m[2][j]);
}

/* ---- projection ---- */

/* An orthographic camera's rays are parallel (the pose's -Z) and start on its plane where the
 * pixel lies; projecting any point of a ray gives the pixel back. The perspective camera
 * round-trips the same way, and the ray cone's width follows each projection. */
static void test_projection(void)
{
    const evr_camera_intr o = evr_camera_intr_ortho(64, 32, 1.5f);
    const evr_camera_intr p = evr_camera_intr_make(64, 32, (float)(PI_D / 3));
    evr_m34 pose = evr_frame_look_along(evr_v3_make(1, 2, 3), evr_v3_make(0.3f, -0.2f, -1.0f),
                                        evr_v3_make(0, 1, 0));
    const evr_m34 inv = evr_m34_inverse(&pose);
    const evr_v3 fwd = evr_v3_scale(evr_v3_norm(column(&pose, 2)), -1.0f);
    static const float px[4][2] = {{0.5f, 0.5f}, {63.5f, 0.5f}, {31.25f, 17.75f}, {5.5f, 30.5f}};
    for (int k = 0; k < 4; k++) {
        const evr_ray r = evr_camera_ray(&o, &pose, px[k][0], px[k][1]);
        CHECK_NEAR(evr_v3_dot(r.dir, fwd), 1.0, 1e-6);
        /* the origin lies on the camera's plane, ymag * aspect and ymag from its centre at most */
        const evr_v3 q = evr_m34_point(&inv, r.org);
        CHECK_NEAR(q.z, 0.0, 1e-5);
        CHECK_NEAR(q.x, (2.0 * px[k][0] / 64.0 - 1.0) * 1.5 * 2.0, 1e-5);
        CHECK_NEAR(q.y, (1.0 - 2.0 * px[k][1] / 32.0) * 1.5, 1e-5);
        for (int m = 0; m < 2; m++) {
            const evr_camera_intr *c = m ? &p : &o;
            const evr_ray ray = m ? evr_camera_ray(&p, &pose, px[k][0], px[k][1]) : r;
            float x = -1.0f, y = -1.0f;
            CHECK(evr_camera_project(c, &inv, evr_v3_add(ray.org, evr_v3_scale(ray.dir, 7.0f)), &x,
                                     &y));
            CHECK_NEAR(x, px[k][0], 1e-3);
            CHECK_NEAR(y, px[k][1], 1e-3);
            /* behind the camera (its plane): not projected */
            CHECK(!evr_camera_project(c, &inv, evr_v3_sub(ray.org, evr_v3_scale(ray.dir, 0.5f)), &x,
                                      &y));
        }
    }
    /* parallel rays: a pixel's footprint does not grow with distance; a pinhole's does */
    CHECK_NEAR(evr_camera_cone(&o, 1.0f), 3.0 / 32.0, 1e-7);
    CHECK_NEAR(evr_camera_cone(&o, 100.0f), 3.0 / 32.0, 1e-7);
    CHECK(evr_camera_pixel_spread(&o) == 0.0f);
    CHECK_NEAR(evr_camera_cone(&p, 10.0f), 10.0 * evr_camera_pixel_spread(&p), 1e-6);
    CHECK_NEAR(evr_camera_pixel_size(&p, 2.0f), 2.0 * 2.0 * tan(PI_D / 6) / 32.0, 1e-6);
}

/* ---- paths: syntax and files ---- */

static void expect_error(const char *spec, int read_files, const char *needle)
{
    evr_camera_path p;
    evr_error err;
    err.msg[0] = 0;
    const evr_status st = evr_camera_path_parse(spec, read_files, &p, &err);
    if (st == EVR_OK || !strstr(err.msg, needle) || strchr(err.msg, '\n')) {
        fprintf(stderr, "spec '%s': status %d, message '%s' (wanted '%s')\n", spec, (int)st,
                err.msg, needle);
        CHECK(0);
    }
    evr_camera_path_free(&p);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    if (!f) return;
    fputs(text, f);
    fclose(f);
}

static void test_parse(void)
{
    evr_camera_path p;
    evr_error err;
    CHECK(evr_camera_path_parse("orbit:period=-4:centre=1,2,3+shake:amp=0.5:seed=7+pan:rate=-20", 1,
                                &p, &err) == EVR_OK);
    CHECK(p.num == 3 && p.m[0].kind == EVR_MOTION_ORBIT && p.m[0].period == -4.0 &&
          p.m[0].centre[2] == 3.0 && p.m[1].kind == EVR_MOTION_SHAKE && p.m[1].amp == 0.5 &&
          p.m[1].seed == 7 && p.m[2].kind == EVR_MOTION_PAN && p.m[2].rate == -20.0);
    evr_camera_path_free(&p);
    CHECK(evr_camera_path_parse("fly:speed=2:dir=0,0,-1", 1, &p, &err) == EVR_OK &&
          p.m[0].kind == EVR_MOTION_DOLLY);
    evr_camera_path_free(&p);
    /* syntax only: a file name is not opened */
    CHECK(evr_camera_path_parse("tum:/no/such/file.txt", 0, &p, &err) == EVR_OK);
    evr_camera_path_free(&p);
    expect_error("", 0, "empty");
    expect_error("orbitt", 0, "unknown kind 'orbitt' (orbit, dolly, fly, pan, tilt, shake");
    expect_error("orbit:speed=3", 0, "orbit: unknown parameter 'speed' (period, centre, axis)");
    expect_error("orbit:period=0", 0, "period must not be 0");
    expect_error("orbit:period=fast", 0, "period expects a number, got 'fast'");
    expect_error("orbit:centre=1,2", 0, "centre expects X,Y,Z");
    expect_error("orbit:axis=0,0,0", 0, "axis must not be zero");
    expect_error("orbit:period", 0, "needs a value");
    expect_error("pan:rate=5:amp=3", 0, "not both");
    expect_error("shake:tremor=-1", 0, "tremor must be >= 0");
    expect_error("orbit++shake", 0, "empty motion");
    expect_error("orbit+tum:x.txt", 0, "comes first");
    expect_error("tum:/no/such/file.txt", 1, "cannot open camera path file '/no/such/file.txt'");
    expect_error("tum:", 0, "needs a file name");
}

static void test_tum_errors(const char *dir)
{
    char path[512], spec[600];
    static const struct {
        const char *text, *needle;
    } bad[] = {
        {"# nothing\n\n", "no poses"},
        {"0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 1\n", "line 2: expected 8 numbers 't tx ty tz qx qy qz "
                                               "qw', got '0.1 0 0 0 0 0 1'"},
        {"0 0 0 0 0 0 0 1\n0.1 0 0 x 0 0 0 1\n", "line 2: expected 8 numbers"},
        {"0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 1 5\n", "line 2: expected 8 numbers"},
        {"# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n0 0 0 0 0 0 0 1\n",
         "line 3: time 0 is not after the line before's (0): times must increase"},
        {"1 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n", "line 2: time 0.5 is not after"},
        {"0 0 0 0 0 0 0 0\n", "line 1: the quaternion is zero"},
        {"0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 nan\n", "line 2: expected 8 numbers"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(path, sizeof path, "%s/bad%zu.txt", dir, i);
        write_text(path, bad[i].text);
        snprintf(spec, sizeof spec, "tum:%s", path);
        expect_error(spec, 1, bad[i].needle);
        expect_error(path, 1, bad[i].needle); /* a name that looks like a file needs no tum: */
        remove(path);
    }
}

/* A TUM pose is the optical frame (x right, y down, z forward) to the world: the identity
 * quaternion looks along +Z with +Y down; times start at the file's first line; between lines
 * the pose is interpolated (lerp, slerp) and clamped outside. */
static void test_tum(const char *dir)
{
    char path[512];
    evr_camera_path p;
    evr_error err;
    const double h = sqrt(0.5);
    snprintf(path, sizeof path, "%s/tum.txt", dir);
    char text[512];
    /* 100 s offset (TUM files carry epoch times); a quarter turn about world +Y over 1 s */
    snprintf(text, sizeof text,
             "# timestamp tx ty tz qx qy qz qw\n100.0 1 2 3 0 0 0 1\n\n101.0 3 2 3 0 %.17g 0 "
             "%.17g\n",
             h, h);
    write_text(path, text);
    CHECK(evr_camera_path_parse(path, 1, &p, &err) == EVR_OK);
    CHECK(p.num == 1 && p.m[0].kind == EVR_MOTION_TUM && p.m[0].n == 2);
    CHECK_NEAR(evr_camera_path_end(&p), 1.0, 1e-12);
    evr_path_context ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.start = 0.0;
    ctx.end = 1.0;
    CHECK(evr_camera_path_bind(&p, &ctx, evr_m34_identity(), &err) == EVR_OK);
    const evr_m34 a = evr_camera_path_apply(&p, 0.0, evr_m34_identity());
    CHECK_NEAR(a.m[0][3], 1.0, 1e-6);
    CHECK_NEAR(a.m[1][3], 2.0, 1e-6);
    /* glTF's camera looks along its -Z: the optical +Z; its +Y is the optical -Y */
    CHECK_NEAR(column(&a, 2).z, -1.0, 1e-6);
    CHECK_NEAR(column(&a, 1).y, -1.0, 1e-6);
    CHECK_NEAR(column(&a, 0).x, 1.0, 1e-6);
    const evr_m34 m = evr_camera_path_apply(&p, 0.5, evr_m34_identity());
    CHECK_NEAR(m.m[0][3], 2.0, 1e-6); /* halfway */
    const evr_v3 look = evr_v3_scale(column(&m, 2), -1.0f);
    CHECK_NEAR(look.x, sin(PI_D / 4), 1e-5); /* 45 degrees of the quarter turn: +Z towards +X */
    CHECK_NEAR(look.z, cos(PI_D / 4), 1e-5);
    const evr_m34 late = evr_camera_path_apply(&p, 5.0, evr_m34_identity());
    CHECK_NEAR(late.m[0][3], 3.0, 1e-6);
    /* a run beyond the trajectory is refused */
    ctx.end = 1.5;
    CHECK(evr_camera_path_bind(&p, &ctx, evr_m34_identity(), &err) == EVR_ERR_ARG &&
          strstr(err.msg, "covers 0 to 1 s"));
    int n = 0;
    double bends[4];
    n = evr_camera_path_bends(&p, -1.0, 0.5, bends, n, 4);
    CHECK(n == 1 && bends[0] == 0.0);
    evr_camera_path_free(&p);
    remove(path);
}

/* ---- scenes ---- */

static const float quad_pos[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
static const uint32_t quad_idx[6] = {0, 1, 2, 0, 2, 3};
static const float cube_pos[24] = {-0.5f, -0.5f, -0.5f, 0.5f,  -0.5f, -0.5f, 0.5f, 0.5f,
                                   -0.5f, -0.5f, 0.5f,  -0.5f, -0.5f, -0.5f, 0.5f, 0.5f,
                                   -0.5f, 0.5f,  0.5f,  0.5f,  0.5f,  -0.5f, 0.5f, 0.5f};
static const uint32_t cube_idx[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                      3, 6, 2, 3, 7, 6, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5};

/* What a test scene holds. */
enum { QUAD_FRONT, QUAD_BACK, QUAD_FLAT, CUBE, CUBE_AWAY, CAMERA_SPIN };

/* One mesh (a quad facing +Z turned as the kind says, or a cube), single-sided; CUBE_AWAY's cube
 * moves from x = 0 to x = 10 over 2 s (its rest pose at 0); CAMERA_SPIN: a cube with a camera
 * at z = 5 that turns about +Y at 30 degrees per second over 1 s. */
static evr_scene *scene(int kind)
{
    evr_gltf *g = evr_gltf_new("test");
    evr_gltf_material mat;
    void *glb = NULL;
    size_t size = 0;
    evr_error err;
    evr_scene *s = NULL;
    evr_gltf_material_init(&mat, "grey");
    mat.double_sided = 0;
    const int mi = evr_gltf_add_material(g, &mat);
    const int cube = kind == CUBE || kind == CUBE_AWAY || kind == CAMERA_SPIN;
    const int mesh = cube ? evr_gltf_mesh(g, "cube", cube_pos, NULL, NULL, 8, cube_idx, 36, mi)
                          : evr_gltf_mesh(g, "quad", quad_pos, NULL, NULL, 4, quad_idx, 6, mi);
    const int node = evr_gltf_node(g, "thing", -1);
    evr_gltf_node_mesh(g, node, mesh);
    const float h = (float)sqrt(0.5);
    if (kind == QUAD_BACK) evr_gltf_node_rotation(g, node, 0, 1, 0, 0);  /* faces -Z */
    if (kind == QUAD_FLAT) evr_gltf_node_rotation(g, node, -h, 0, 0, h); /* faces +Y */
    if (kind == CUBE_AWAY) {
        const float times[2] = {0, 2}, xs[6] = {0, 0, 0, 10, 0, 0};
        evr_gltf_channel(g, evr_gltf_animation(g, "away"), node, EVR_GLTF_TRANSLATION, times, xs, 2,
                         EVR_GLTF_LINEAR);
    }
    if (kind == CAMERA_SPIN) {
        const int cam = evr_gltf_node(g, "cam", -1);
        evr_gltf_node_camera(g, cam, evr_gltf_camera(g, "cam", (float)(PI_D / 4), 0, 0.1f, 0));
        evr_gltf_node_translation(g, cam, 0, 0, 5);
        const float times[3] = {0, 0.5f, 1};
        float q[12];
        for (int k = 0; k < 3; k++) {
            const double a = 15.0 * k * PI_D / 360.0; /* 15 degrees per key, half angle */
            q[4 * k] = 0;
            q[4 * k + 1] = (float)sin(a);
            q[4 * k + 2] = 0;
            q[4 * k + 3] = (float)cos(a);
        }
        evr_gltf_channel(g, evr_gltf_animation(g, "spin"), cam, EVR_GLTF_ROTATION, times, q, 3,
                         EVR_GLTF_LINEAR);
    }
    if (evr_gltf_glb(g, &glb, &size, &err) != EVR_OK ||
        evr_scene_load_memory(glb, size, "glb", &s, &err) != EVR_OK) {
        fprintf(stderr, "test scene %d: %s\n", kind, err.msg);
        CHECK(0);
    }
    free(glb);
    evr_gltf_free(g);
    return s;
}

/* ---- framing ---- */

static void check_dir(int kind, double x, double y, double z)
{
    evr_scene *s = scene(kind);
    if (!s) return;
    const evr_v3 d = evr_frame_direction(s, 0.0);
    if (!(fabs(d.x - x) < 1e-5 && fabs(d.y - y) < 1e-5 && fabs(d.z - z) < 1e-5)) {
        fprintf(stderr, "scene %d seen from (%g %g %g), expected (%g %g %g)\n", kind, d.x, d.y, d.z,
                x, y, z);
        CHECK(0);
    }
    /* the automatic camera looks from there */
    const evr_v3 back = evr_v3_norm(column(&s->cameras[0].local, 2));
    CHECK(s->cameras[0].automatic && evr_v3_dot(back, d) > 0.9999f);
    evr_scene_release(s);
}

/* Where the camera's corners of box [lo, hi] fall in a square image of half-angle tan t: the
 * largest |x/z| or |y/z| over t. */
static double box_extent(const evr_m34 *pose, evr_v3 lo, evr_v3 hi, double t)
{
    const evr_m34 inv = evr_m34_inverse(pose);
    double worst = 0.0;
    for (int k = 0; k < 8; k++) {
        const evr_v3 q = evr_m34_point(
            &inv, evr_v3_make(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z));
        if (!(q.z < 0.0f)) return INFINITY;
        worst = fmax(worst, fmax(fabs(q.x / q.z), fabs(q.y / q.z)) / t);
    }
    return worst;
}

static void test_framing(void)
{
    /* a flat model is seen face-on, never edge-on; a single-sided one from its front; a cube
     * turned and from above, where the most of its faces show */
    check_dir(QUAD_FRONT, 0, 0, 1);
    check_dir(QUAD_BACK, 0, 0, -1);
    check_dir(QUAD_FLAT, 0, 1, 0);
    check_dir(CUBE, sin(PI_D / 4) * cos(PI_D / 6), 0.5, cos(PI_D / 4) * cos(PI_D / 6));
    {
        evr_scene *s = scene(QUAD_FLAT);
        if (s) { /* seen from above with the scene's front (+Z) at the image's bottom */
            const evr_m34 *m = &s->cameras[0].local;
            CHECK(column(m, 1).z < -0.99f);
            evr_scene_release(s);
        }
    }
    /* the animated cube leaves its rest bounds: the swept bounds hold it all the way, and the
     * automatic camera frames them (its rest pose alone would leave it at x = 10) */
    evr_scene *s = scene(CUBE_AWAY);
    if (!s) return;
    evr_v3 lo, hi;
    CHECK(evr_frame_swept_bounds(s, s->anim_start, s->anim_end, &lo, &hi));
    CHECK_NEAR(lo.x, -0.5, 1e-5);
    CHECK_NEAR(hi.x, 10.5, 1e-5);
    CHECK_NEAR(s->bounds_max.x, 0.5, 1e-5); /* the rest bounds */
    const evr_m34 cam = s->cameras[0].local;
    const double t = tan(PI_D / 8);
    CHECK(box_extent(&cam, lo, hi, t) <= 0.9 + 1e-4);
    for (int k = 0; k <= 4; k++) { /* the cube itself, wherever it is */
        const evr_v3 at = evr_v3_make(10.0f * k / 4.0f, 0, 0);
        CHECK(box_extent(&cam, evr_v3_add(at, evr_v3_make(-0.5f, -0.5f, -0.5f)),
                         evr_v3_add(at, evr_v3_make(0.5f, 0.5f, 0.5f)), t) < 0.9 + 1e-4);
    }
    /* all around: every turn about the vertical keeps the box in view */
    float d1, d16;
    const evr_v3 dir = evr_v3_norm(column(&cam, 2));
    (void)evr_frame_box(lo, hi, dir, (float)(PI_D / 4), 1.0f, 0, &d1);
    const evr_m34 around = evr_frame_box(lo, hi, dir, (float)(PI_D / 4), 1.0f, 1, &d16);
    CHECK(d16 > d1);
    for (int k = 0; k < 8; k++) {
        const double a = 2.0 * PI_D * k / 8.0;
        const evr_v3 c = evr_v3_scale(evr_v3_add(lo, hi), 0.5f);
        /* the box's corners turned about the vertical through its centre: in view */
        const evr_m34 inv = evr_m34_inverse(&around);
        for (int q = 0; q < 8; q++) {
            const evr_v3 p = evr_v3_sub(
                evr_v3_make(q & 1 ? hi.x : lo.x, q & 2 ? hi.y : lo.y, q & 4 ? hi.z : lo.z), c);
            const evr_v3 r = evr_v3_add(c, evr_v3_make((float)(cos(a) * p.x + sin(a) * p.z), p.y,
                                                       (float)(-sin(a) * p.x + cos(a) * p.z)));
            const evr_v3 v = evr_m34_point(&inv, r);
            CHECK(v.z < 0.0f && fabs(v.x / v.z) <= t * 0.9 + 1e-3 &&
                  fabs(v.y / v.z) <= t * 0.9 + 1e-3);
        }
    }
    evr_scene_release(s);
}

/* ---- the run's camera ---- */

static void test_rig(void)
{
    evr_scene *s = scene(CUBE);
    evr_config c;
    evr_camera_rig r;
    evr_error err;
    if (!s) return;
    evr_config_defaults(&c);
    c.width = 64;
    c.height = 64;
    /* the automatic camera framed again for the run: the same as the import's on a square image */
    CHECK(evr_camera_rig_init(&r, s, 0, &c, &err) == EVR_OK);
    CHECK(evr_camera_rig_setup(&r, &c, 0.0, 1.0, &err) == EVR_OK);
    CHECK(!r.has_path && r.node == -1);
    CHECK(m34_maxdiff(&r.local, &s->cameras[0].local) < 1e-5);
    evr_camera_rig_free(&r);

    /* orbit: a quarter of the period turns the camera a quarter about +Y through the centre
     * (the cube's, at the origin), starting where the camera is */
    c.camera_path = "orbit:period=4";
    CHECK(evr_camera_rig_init(&r, s, 0, &c, &err) == EVR_OK);
    CHECK(evr_camera_rig_setup(&r, &c, 0.5, 2.5, &err) == EVR_OK);
    const evr_m34 p0 = evr_camera_rig_pose(&r, 0.5), p1 = evr_camera_rig_pose(&r, 1.5);
    CHECK(m34_maxdiff(&p0, &r.local) < 1e-6);
    CHECK_NEAR(p1.m[0][3], p0.m[2][3], 1e-5); /* (x, z) -> (z, -x) */
    CHECK_NEAR(p1.m[2][3], -p0.m[0][3], 1e-5);
    CHECK_NEAR(p1.m[1][3], p0.m[1][3], 1e-5);
    /* the keys of a segment follow the pose (the fitting's tolerance, 1e-5 of the scene) */
    evr_motion_key keys[EVR_MAX_KEYS];
    const int n = evr_camera_rig_keys(&r, 1.0, 1.0 + 1.0 / 30.0, 1e-5f, keys, EVR_MAX_KEYS);
    CHECK(n >= 2);
    evr_motion_track tr = {keys, n};
    for (int k = 0; k <= 10; k++) {
        const double f = k / 10.0;
        const evr_m34 truth = evr_camera_rig_pose(&r, 1.0 + f / 30.0),
                      fit = evr_motion_eval(tr, (float)f);
        CHECK(m34_maxdiff(&truth, &fit) < 1e-4 * r.size);
    }
    evr_camera_rig_free(&r);

    /* --look-from / --look-at: a fixed pose looking at the point; a pan then turns it right */
    c.camera_path = "pan:rate=90";
    c.look_from_set = c.look_at_set = 1;
    c.look_from[0] = 0, c.look_from[1] = 0, c.look_from[2] = 4;
    c.look_at[0] = 0, c.look_at[1] = 0, c.look_at[2] = 0;
    CHECK(evr_camera_rig_init(&r, s, 0, &c, &err) == EVR_OK);
    CHECK(evr_camera_rig_setup(&r, &c, 0.0, 1.0, &err) == EVR_OK);
    const evr_m34 a = evr_camera_rig_pose(&r, 0.0), b = evr_camera_rig_pose(&r, 1.0);
    CHECK_NEAR(a.m[2][3], 4.0, 1e-6);
    CHECK_NEAR(column(&a, 2).z, 1.0, 1e-6);  /* looks along -Z */
    CHECK_NEAR(column(&b, 2).x, -1.0, 1e-5); /* after 90 degrees to the right: along +X */
    CHECK_NEAR(b.m[2][3], 4.0, 1e-6);        /* turning in place */
    evr_camera_rig_free(&r);
    /* the camera may not sit where it looks */
    c.camera_path = NULL;
    c.look_at_set = 0;
    c.look_from[0] = c.look_from[1] = c.look_from[2] = 0; /* the cube's centre */
    CHECK(evr_camera_rig_init(&r, s, 0, &c, &err) == EVR_OK);
    CHECK(evr_camera_rig_setup(&r, &c, 0.0, 1.0, &err) == EVR_ERR_ARG &&
          strstr(err.msg, "look-from"));
    evr_camera_rig_free(&r);
    evr_scene_release(s);

    /* a path composes with the camera's own animation: shake on the spinning camera stays
     * within a degree of it and is not it; a dolly moves it along its view */
    s = scene(CAMERA_SPIN);
    if (!s) return;
    evr_config_defaults(&c);
    c.camera_path = "dolly:speed=1";
    CHECK(evr_camera_rig_init(&r, s, 0, &c, &err) == EVR_OK);
    CHECK(evr_camera_rig_setup(&r, &c, 0.0, 1.0, &err) == EVR_OK);
    const evr_m34 own =
        evr_m34_mul(evr_node_world_at(s, s->cameras[0].node, 1.0), s->cameras[0].local);
    const evr_m34 moved = evr_camera_rig_pose(&r, 1.0);
    CHECK(m34_maxdiff(&own, &moved) > 0.5);                   /* moved by a metre ... */
    CHECK_NEAR(moved.m[2][3], own.m[2][3] - 1.0, 1e-5);       /* ... along where it looked at 0 */
    CHECK_NEAR(column(&moved, 2).x, column(&own, 2).x, 1e-6); /* its own turn kept */
    evr_camera_rig_free(&r);
    c.camera_path = "shake";
    CHECK(evr_camera_rig_init(&r, s, 0, &c, &err) == EVR_OK);
    CHECK(evr_camera_rig_setup(&r, &c, 0.0, 1.0, &err) == EVR_OK);
    double most = 0.0, diff = 0.0;
    for (int k = 1; k <= 100; k++) {
        const double t = k / 100.0;
        const evr_m34 o = evr_m34_mul(evr_node_world_at(s, s->cameras[0].node, t),
                                      s->cameras[0].local),
                      sh = evr_camera_rig_pose(&r, t);
        const double cosang = evr_v3_dot(evr_v3_norm(column(&o, 2)), evr_v3_norm(column(&sh, 2)));
        most = fmax(most, acos(fmin(1.0, cosang)) * 180.0 / PI_D);
        diff = fmax(diff, m34_maxdiff(&o, &sh));
    }
    CHECK(most < 1.5 && diff > 1e-4);
    evr_camera_rig_free(&r);
    evr_scene_release(s);
}

/* The shake's spectrum: its turns about x have the drift's RMS and 8-12 Hz tremor on top (the
 * wave amplitudes as documented in docs/camera.md). */
static void test_shake(void)
{
    evr_camera_path p;
    evr_error err;
    evr_path_context ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.end = 10.0;
    ctx.distance = 2.0f;
    ctx.seed = 5;
    CHECK(evr_camera_path_parse("shake:amp=0.4:tremor=0.05", 1, &p, &err) == EVR_OK);
    CHECK(evr_camera_path_bind(&p, &ctx, evr_m34_identity(), &err) == EVR_OK);
    double drift2 = 0.0, tremor2 = 0.0, move2 = 0.0;
    for (int k = 0; k < EVR_SHAKE_WAVES; k++) {
        const evr_wave *w = &p.m[0].wave[0][k];
        if (w->freq < 2.0 + 1e-9) {
            CHECK(w->freq >= 0.2 - 1e-9);
            drift2 += 0.5 * w->amp * w->amp;
        } else {
            CHECK(w->freq >= 8.0 - 1e-9 && w->freq <= 12.0 + 1e-9);
            tremor2 += 0.5 * w->amp * w->amp;
        }
        move2 += 0.5 * p.m[0].wave[3][k].amp * p.m[0].wave[3][k].amp;
    }
    CHECK_NEAR(sqrt(drift2), 0.4 * PI_D / 180.0, 1e-9);
    CHECK_NEAR(sqrt(tremor2), 0.05 * PI_D / 180.0, 1e-9);
    CHECK_NEAR(sqrt(move2), sqrt(1.01) * 0.004, 1e-9); /* 0.2% of 2, tremor a tenth of it */
    /* time 0 is the camera's own pose */
    const evr_m34 a = evr_camera_path_apply(&p, 0.0, evr_m34_identity());
    const evr_m34 id = evr_m34_identity();
    CHECK(m34_maxdiff(&a, &id) < 1e-6);
    evr_camera_path_free(&p);
}

int main(void)
{
    char dir[] = "/tmp/evray-test-camera-XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    test_projection();
    test_parse();
    test_tum_errors(dir);
    test_tum(dir);
    test_framing();
    test_rig();
    test_shake();
    rmdir(dir);
    return check_report("test_camera");
}
