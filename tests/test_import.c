/* The importer (scene/import.c): cameras (glTF quirks (b) and (c), Collada's FOV), lights
 * (KHR_lights_punctual), materials and textures (data URI, GLB buffer view, external file,
 * sharing, sRGB decoding, uv orientation), the automatic camera and default light, camera
 * lookup by name, memory loading, the description, and bad inputs. Scene files:
 * tests/data/import/ (made by make_data.py there; camera.dae written by hand). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "check.h"
#include "io/png.h"
#include "scene/framing.h"
#include "scene/scene.h"

#include <stb/stb_image_write.h>

#define DATA EVR_TEST_DATA "/import/"
#define PI_D 3.14159265358979323846

static int node_index(const evr_scene *s, const char *name)
{
    int i;
    for (i = 0; i < s->num_nodes; i++)
        if (!strcmp(s->nodes[i].name, name)) return i;
    return -1;
}

static int mesh_index(const evr_scene *s, const char *name)
{
    int i;
    for (i = 0; i < s->num_meshes; i++)
        if (!strcmp(s->meshes[i].name, name)) return i;
    return -1;
}

/* The automatic camera (no camera in the file, a still scene): 45 degrees, looking at the rest
 * bounds' centre from the direction framing.h picks, close enough that a corner of the bounds
 * lies at the edge of 90% of a square image and none beyond. */
static void check_automatic(const evr_scene *s)
{
    const evr_camera_desc *c = &s->cameras[0];
    const evr_v3 ctr = evr_v3_scale(evr_v3_add(s->bounds_min, s->bounds_max), 0.5f);
    const evr_v3 dir = evr_frame_direction(s, 0.0);
    const evr_v3 pos = evr_v3_make(c->local.m[0][3], c->local.m[1][3], c->local.m[2][3]);
    const evr_v3 back = evr_v3_make(c->local.m[0][2], c->local.m[1][2], c->local.m[2][2]);
    const evr_m34 inv = evr_m34_inverse(&c->local);
    const double lim = tan(PI_D / 8) * 0.9;
    double worst = 0.0;
    CHECK(c->automatic == 1 && c->node == -1 && !c->ortho);
    CHECK_NEAR(c->yfov, PI_D / 4, 1e-6);
    CHECK_NEAR(evr_v3_dot(back, dir), 1.0, 1e-5); /* the camera's +Z points back along dir */
    CHECK_NEAR(evr_v3_len(evr_v3_cross(evr_v3_sub(pos, ctr), dir)), 0.0, 1e-4);
    for (int k = 0; k < 8; k++) {
        const evr_v3 p = evr_v3_make(k & 1 ? s->bounds_max.x : s->bounds_min.x,
                                     k & 2 ? s->bounds_max.y : s->bounds_min.y,
                                     k & 4 ? s->bounds_max.z : s->bounds_min.z);
        const evr_v3 q = evr_m34_point(&inv, p);
        CHECK(q.z < 0.0f);
        worst = fmax(worst, fmax(fabs(q.x / q.z), fabs(q.y / q.z)) / lim);
    }
    CHECK(worst <= 1.0 + 1e-4 && worst > 0.999);
    CHECK(c->znear > 0.0f);
    CHECK(evr_scene_find_camera(s, "automatic") == 0);
}

static double srgb(double c) { return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4); }

/* Camera pose in the world at time t: node world transform times the camera's local pose. */
static evr_m34 camera_world(const evr_scene *s, int cam, double t)
{
    const evr_camera_desc *c = &s->cameras[cam];
    evr_m34 w = c->node >= 0 ? evr_node_world_at(s, c->node, t) : evr_m34_identity();
    return evr_m34_mul(w, c->local);
}

/* A status and a message of one non-empty line. */
static void check_one_line(evr_status st, evr_status want, const evr_error *err)
{
    CHECK(st == want);
    CHECK(err->msg[0] != 0);
    CHECK(strchr(err->msg, '\n') == NULL);
    if (st != want)
        fprintf(stderr, "  got status %d (%s), wanted %d\n", (int)st, err->msg, (int)want);
}

static int write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    size_t w;
    if (!f) return 0;
    w = fwrite(data, 1, n, f);
    return fclose(f) == 0 && w == n;
}

static unsigned char *read_bytes(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    unsigned char *b;
    long len;
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    len = ftell(f);
    fseek(f, 0, SEEK_SET);
    b = malloc((size_t)len + 1);
    if (b && fread(b, 1, (size_t)len, f) != (size_t)len) {
        free(b);
        b = NULL;
    }
    fclose(f);
    *n = (size_t)len;
    return b;
}

/* ---- anim.gltf: two glTF cameras, no light ---- */

static void test_gltf_cameras(void)
{
    evr_scene *s = NULL;
    evr_error err;
    evr_m34 w;
    int main_cam, side_cam;
    if (evr_scene_load(DATA "anim.gltf", &s, &err) != EVR_OK) {
        fprintf(stderr, "anim.gltf: %s\n", err.msg);
        CHECK(!"anim.gltf loads");
        return;
    }
    CHECK(s->num_cameras == 2);
    CHECK(strcmp(s->format, "glTF2 Importer") == 0);
    /* --camera NAME */
    main_cam = evr_scene_find_camera(s, "cam_main");
    side_cam = evr_scene_find_camera(s, "cam_side");
    CHECK(main_cam == 0 && side_cam == 1);
    CHECK(evr_scene_find_camera(s, "no such camera") == -1);
    CHECK(evr_scene_find_camera(s, NULL) == 0);
    if (main_cam != 0 || side_cam != 1) {
        evr_scene_release(s);
        return;
    }

    /* quirk (b): Assimp stores yfov * aspect in mHorizontalFOV; we recover yfov */
    CHECK_NEAR(s->cameras[0].yfov, 0.5, 1e-6);
    CHECK_NEAR(s->cameras[0].aspect, 2.0, 1e-6);
    CHECK_NEAR(s->cameras[1].yfov, 0.7, 1e-6); /* no aspect: stored as is */
    CHECK(s->cameras[1].aspect == 0.0f);
    CHECK_NEAR(s->cameras[0].znear, 0.1, 1e-6);
    CHECK(!s->cameras[0].automatic);

    /* quirk (c): the node's translation is not applied a second time through mPosition */
    CHECK(s->cameras[0].node == node_index(s, "cam_main"));
    w = camera_world(s, 0, 0.0);
    CHECK_NEAR(w.m[0][3], 0.0, 1e-5);
    CHECK_NEAR(w.m[1][3], 1.0, 1e-5);
    CHECK_NEAR(w.m[2][3], 10.0, 1e-5);
    CHECK_NEAR(w.m[2][2], 1.0, 1e-6); /* looks along -Z */
    w = camera_world(s, 1, 0.0);      /* turned 90 about Y: looks along -X, from (10,0,0) */
    CHECK_NEAR(w.m[0][3], 10.0, 1e-5);
    CHECK_NEAR(w.m[1][3], 0.0, 1e-5);
    CHECK_NEAR(w.m[2][3], 0.0, 1e-5);
    CHECK_NEAR(-w.m[0][2], -1.0, 1e-5);
    CHECK_NEAR(w.m[1][1], 1.0, 1e-5);

    /* no light in the file: a directional headlight riding with the first camera */
    CHECK(s->default_light == 1);
    CHECK(s->num_lights == 1);
    if (s->num_lights == 1) {
        const evr_light *l = &s->lights[0];
        evr_m34 cw = camera_world(s, 0, 0.0);
        evr_m34 nw = evr_node_world_at(s, l->node, 0.0);
        evr_v3 d = evr_v3_norm(evr_m34_vector(&nw, l->direction));
        evr_v3 fwd = evr_v3_make(-cw.m[0][2], -cw.m[1][2], -cw.m[2][2]);
        evr_v3 up = evr_v3_make(cw.m[0][1], cw.m[1][1], cw.m[2][1]);
        evr_v3 right = evr_v3_make(cw.m[0][0], cw.m[1][0], cw.m[2][0]);
        CHECK(l->type == EVR_LIGHT_DIRECTIONAL);
        CHECK(l->node == s->cameras[0].node);
        CHECK(evr_v3_dot(d, fwd) > 0.9f);    /* shines where the camera looks */
        CHECK(evr_v3_dot(d, up) < -0.1f);    /* from above */
        CHECK(evr_v3_dot(d, right) > 0.1f);  /* from the left */
        CHECK_NEAR(l->color[0], PI_D, 1e-5); /* E = pi: white Lambertian radiance 1 */
        CHECK_NEAR(l->color[2], PI_D, 1e-5);
    }
    {
        char *d = evr_scene_describe(s);
        CHECK(d != NULL);
        if (d) {
            CHECK(strstr(d, "cam_main") != NULL);
            CHECK(strstr(d, "yfov 28.65 deg") != NULL);
            CHECK(strstr(d, "\"step_t\": translation 3 keys step") != NULL);
            CHECK(strstr(d, "0 s to 2 s") != NULL);
            CHECK(strstr(d, "headlight") != NULL);
            CHECK(strstr(d, "triangles") != NULL);
            CHECK(strstr(d, "bounds") != NULL);
            free(d);
        }
    }
    evr_scene_release(s);
}

/* ---- lights.gltf / lights.glb: lights, materials, textures ---- */

static void test_lights_materials(const char *path, int glb)
{
    evr_scene *s = NULL;
    evr_error err;
    int i, box, tri, tri2;
    if (evr_scene_load(path, &s, &err) != EVR_OK) {
        fprintf(stderr, "%s: %s\n", path, err.msg);
        CHECK(!"lights file loads");
        return;
    }
    (void)glb;
    /* KHR_lights_punctual: colour * intensity, attached to the node named like the light */
    CHECK(s->num_lights == 3);
    CHECK(s->default_light == 0);
    for (i = 0; i < s->num_lights; i++) {
        const evr_light *l = &s->lights[i];
        evr_m34 w = evr_node_world_at(s, l->node, 0.0);
        evr_v3 p = evr_m34_point(&w, l->position),
               d = evr_v3_norm(evr_m34_vector(&w, l->direction));
        if (!strcmp(l->name, "bulb_node")) {
            CHECK(l->type == EVR_LIGHT_POINT);
            CHECK(l->node == node_index(s, "bulb_node"));
            CHECK_NEAR(l->color[0], 10.0, 1e-5);
            CHECK_NEAR(l->color[1], 5.0, 1e-5);
            CHECK_NEAR(l->color[2], 2.5, 1e-5);
            CHECK_NEAR(p.x, 1.0, 1e-5);
            CHECK_NEAR(p.y, 2.0, 1e-5);
            CHECK_NEAR(p.z, 3.0, 1e-5);
        } else if (!strcmp(l->name, "torch_node")) {
            CHECK(l->type == EVR_LIGHT_SPOT);
            CHECK_NEAR(l->color[1], 5.0, 1e-5);
            CHECK_NEAR(l->inner_cone, 0.2, 1e-6); /* glTF half angles, kept as they are */
            CHECK_NEAR(l->outer_cone, 0.6, 1e-6);
            CHECK_NEAR(p.y, 4.0, 1e-5);
            CHECK_NEAR(d.y, -1.0, 1e-5); /* node turned -90 about X: -Z becomes -Y */
        } else if (!strcmp(l->name, "sun_node")) {
            CHECK(l->type == EVR_LIGHT_DIRECTIONAL);
            CHECK_NEAR(l->color[0], 0.0, 1e-6);
            CHECK_NEAR(l->color[1], 3.0, 1e-5);
            CHECK_NEAR(d.z, -1.0, 1e-5);
        } else {
            CHECK(!"unexpected light name");
        }
    }
    /* no camera in the file: an automatic one framing the bounds */
    CHECK(s->num_cameras == 1);
    if (s->num_cameras == 1) check_automatic(s);
    /* bounds: the cube (-0.5..0.5) and the triangles at x = 2 and x = -2 */
    CHECK_NEAR(s->bounds_min.x, -2.0, 1e-6);
    CHECK_NEAR(s->bounds_max.x, 3.0, 1e-6);
    CHECK_NEAR(s->bounds_min.y, -0.5, 1e-6);
    CHECK_NEAR(s->bounds_max.y, 1.0, 1e-6);

    /* points are dropped: three meshes, the points node places nothing */
    box = mesh_index(s, "box");
    tri = mesh_index(s, "tri");
    tri2 = mesh_index(s, "tri2");
    CHECK(s->num_meshes == 3 && box >= 0 && tri >= 0 && tri2 >= 0);
    CHECK(s->num_instances == 3);
    for (i = 0; i < s->num_instances; i++) CHECK(s->instances[i].node != node_index(s, "points"));
    if (box < 0 || tri < 0 || tri2 < 0) {
        evr_scene_release(s);
        return;
    }
    CHECK(s->meshes[box].num_triangles == 12);
    CHECK(s->meshes[box].uvs == NULL);
    for (i = 0; i < (int)s->meshes[box].num_vertices; i++) {
        const float *n = &s->meshes[box].normals[3 * i];
        CHECK_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-5);
    }

    /* materials */
    {
        const evr_material *m = &s->materials[s->meshes[box].material];
        const evr_material *e1 = &s->materials[s->meshes[tri].material];
        const evr_material *e2 = &s->materials[s->meshes[tri2].material];
        CHECK(strcmp(m->name, "embedded") == 0);
        CHECK_NEAR(m->p.base_color[0], 0.5, 1e-6);
        CHECK_NEAR(m->p.base_color[1], 0.25, 1e-6);
        CHECK_NEAR(m->p.base_color[2], 1.0, 1e-6);
        CHECK_NEAR(m->p.base_color[3], 1.0, 1e-6);
        CHECK_NEAR(m->p.metallic, 0.25, 1e-6);
        CHECK_NEAR(m->p.roughness, 0.75, 1e-6);
        /* emissive factor (1, 0.5, 0) times KHR_materials_emissive_strength 4 */
        CHECK_NEAR(m->p.emissive[0], 4.0, 1e-5);
        CHECK_NEAR(m->p.emissive[1], 2.0, 1e-5);
        CHECK_NEAR(m->p.emissive[2], 0.0, 1e-6);
        CHECK(strcmp(e1->name, "external") == 0 && strcmp(e2->name, "external_again") == 0);
        CHECK_NEAR(e1->p.emissive[0], 0.0, 1e-6);
        CHECK_NEAR(e2->p.metallic, 0.0, 1e-6);
        /* two textures: the embedded image, and the external file shared by two materials */
        CHECK(s->num_textures == 2);
        CHECK(m->p.tex[EVR_TEX_BASE].index >= 0 && e1->p.tex[EVR_TEX_BASE].index >= 0);
        CHECK(e1->p.tex[EVR_TEX_BASE].index == e2->p.tex[EVR_TEX_BASE].index);
        CHECK(m->p.tex[EVR_TEX_BASE].index != e1->p.tex[EVR_TEX_BASE].index);
        if (s->num_textures == 2 && m->p.tex[EVR_TEX_BASE].index >= 0 &&
            e1->p.tex[EVR_TEX_BASE].index >= 0) {
            int k;
            for (k = 0; k < 2; k++) {
                const evr_texture *t = &s->textures[k == 0 ? m->p.tex[EVR_TEX_BASE].index
                                                           : e1->p.tex[EVR_TEX_BASE].index];
                CHECK(t->width == 2 && t->height == 2);
                if (t->width != 2 || t->height != 2) continue;
                /* row 0 is the image's first (top) row: red, then (0, 128, 255) */
                CHECK_NEAR(t->rgba[0], 1.0, 1e-6);
                CHECK_NEAR(t->rgba[1], 0.0, 1e-6);
                CHECK_NEAR(t->rgba[3], 1.0, 1e-6);
                CHECK_NEAR(t->rgba[4], 0.0, 1e-6);
                CHECK_NEAR(t->rgba[5], srgb(128.0 / 255.0), 1e-6); /* exact sRGB EOTF: 0.2158605 */
                CHECK_NEAR(t->rgba[5], 0.2158605, 1e-6);
                CHECK_NEAR(t->rgba[6], 1.0, 1e-6);
                CHECK_NEAR(t->rgba[8], 0.0, 1e-6);
                CHECK_NEAR(t->rgba[12], 1.0, 1e-6);
                CHECK_NEAR(t->rgba[15], 128.0 / 255.0, 1e-6); /* alpha stays linear */
            }
        }
    }
    /* uv as in the file (glTF's: (0,0) at the image's top-left), whatever Assimp does inside */
    CHECK(s->meshes[tri].uvs != NULL && s->meshes[tri].num_vertices == 3);
    if (s->meshes[tri].uvs && s->meshes[tri].num_vertices == 3) {
        for (i = 0; i < 3; i++) {
            const float *p = &s->meshes[tri].positions[3 * i], *uv = &s->meshes[tri].uvs[2 * i];
            if (p[0] == 0.0f && p[1] == 0.0f) {
                CHECK_NEAR(uv[0], 0.25, 1e-6);
                CHECK_NEAR(uv[1], 0.75, 1e-6);
            } else if (p[0] == 1.0f) {
                CHECK_NEAR(uv[0], 0.5, 1e-6);
                CHECK_NEAR(uv[1], 0.125, 1e-6);
            } else {
                CHECK_NEAR(uv[0], 1.0, 1e-6);
                CHECK_NEAR(uv[1], 1.0, 1e-6);
            }
        }
    }
    {
        char *d = evr_scene_describe(s);
        CHECK(d && strstr(d, "spot") && strstr(d, "intensity 10 cd") && strstr(d, "automatic"));
        free(d);
    }
    evr_scene_release(s);
}

/* ---- a file with nothing but two cubes ---- */

static void test_plain(void)
{
    evr_scene *s = NULL;
    evr_error err;
    if (evr_scene_load(DATA "plain.gltf", &s, &err) != EVR_OK) {
        fprintf(stderr, "plain.gltf: %s\n", err.msg);
        CHECK(!"plain.gltf loads");
        return;
    }
    CHECK(s->num_cameras == 1 && s->cameras[0].automatic && s->cameras[0].node == -1);
    CHECK(s->num_lights == 1 && s->default_light == 1);
    CHECK_NEAR(s->bounds_min.x, -1.5, 1e-6);
    CHECK_NEAR(s->bounds_max.x, 1.5, 1e-6);
    CHECK_NEAR(s->bounds_min.z, -0.5, 1e-6);
    CHECK_NEAR(s->bounds_max.z, 0.5, 1e-6);
    /* the headlight shines along the automatic camera's view, from above-left */
    if (s->num_lights == 1) {
        const evr_light *l = &s->lights[0];
        const evr_m34 *m = &s->cameras[0].local;
        const evr_v3 fwd = evr_v3_make(-m->m[0][2], -m->m[1][2], -m->m[2][2]);
        const evr_v3 up = evr_v3_make(m->m[0][1], m->m[1][1], m->m[2][1]);
        const evr_v3 right = evr_v3_make(m->m[0][0], m->m[1][0], m->m[2][0]);
        CHECK(l->node == -1);
        CHECK(evr_v3_dot(l->direction, fwd) > 0.9f && evr_v3_dot(l->direction, up) < 0.0f &&
              evr_v3_dot(l->direction, right) > 0.0f);
    }
    /* two cubes side by side: seen from in front, turned and raised (more of their faces) */
    check_automatic(s);
    {
        const evr_v3 d = evr_frame_direction(s, 0.0);
        CHECK_NEAR(d.x, sin(PI_D / 4) * cos(PI_D / 6), 1e-5);
        CHECK_NEAR(d.y, 0.5, 1e-5);
        CHECK_NEAR(d.z, cos(PI_D / 4) * cos(PI_D / 6), 1e-5);
    }
    CHECK(s->anim_start == 0.0 && s->anim_end == 0.0);
    evr_scene_release(s);
}

/* ---- a Collada camera: Assimp stores the full horizontal FOV ---- */

static void test_collada_camera(void)
{
    evr_scene *s = NULL;
    evr_error err;
    if (evr_scene_load(DATA "camera.dae", &s, &err) != EVR_OK) {
        fprintf(stderr, "camera.dae: %s\n", err.msg);
        CHECK(!"camera.dae loads");
        return;
    }
    CHECK(s->num_cameras == 1);
    /* xfov 60 degrees, aspect 2: yfov = 2 atan(tan(30 deg) / 2) */
    CHECK_NEAR(s->cameras[0].yfov, 2.0 * atan(tan(PI_D / 6) / 2.0), 1e-5);
    CHECK(evr_scene_find_camera(s, "CamNode") == 0);
    {
        evr_m34 w = camera_world(s, 0, 0.0);
        CHECK_NEAR(w.m[2][3], 5.0, 1e-5);
        CHECK_NEAR(w.m[2][2], 1.0, 1e-5);
    }
    CHECK(strcmp(s->format, "Collada Importer") == 0);
    evr_scene_release(s);
}

/* ---- a 3DS camera (make_data.py's camera_3ds): Z-up, a keyframer section ---- */

static void test_3ds_camera(void)
{
    evr_scene *s = NULL;
    evr_error err;
    if (evr_scene_load(DATA "camera.3ds", &s, &err) != EVR_OK) {
        fprintf(stderr, "camera.3ds: %s\n", err.msg);
        CHECK(!"camera.3ds loads");
        return;
    }
    CHECK(s->num_cameras == 1 && !s->cameras[0].automatic && !s->cameras[0].ortho);
    /* lens 43.456 mm across 36 mm: 45 degrees horizontally; no aspect in the file, so the image
     * gives the vertical angle */
    CHECK_NEAR(s->cameras[0].xfov, PI_D / 4, 1e-4);
    CHECK_NEAR(evr_camera_yfov(&s->cameras[0], 2.0f), 2.0 * atan(tan(PI_D / 8) / 2.0), 1e-4);
    /* (1, -10, 1) in 3DS's Z-up world is (1, 1, 10) in Y-up, once (the node repeats it); it
     * looks along 3DS +Y (-Z) with 3DS +Z (+Y) up */
    evr_m34 w = camera_world(s, 0, 0.0);
    CHECK_NEAR(w.m[0][3], 1.0, 1e-5);
    CHECK_NEAR(w.m[1][3], 1.0, 1e-5);
    CHECK_NEAR(w.m[2][3], 10.0, 1e-5);
    CHECK_NEAR(w.m[2][2], 1.0, 1e-5); /* +Z back */
    CHECK_NEAR(w.m[1][1], 1.0, 1e-5); /* +Y up */
    CHECK_NEAR(w.m[0][0], 1.0, 1e-5); /* +X right */
    /* the L's long bar (3DS x 0..2 at z 0..0.5) lies below and right of the view's centre */
    {
        const evr_m34 inv = evr_m34_inverse(&w);
        const evr_v3 end = evr_m34_point(&inv, evr_v3_make(2, 0.25f, 0));
        const evr_v3 top = evr_m34_point(&inv, evr_v3_make(0.25f, 2, 0));
        CHECK(end.x > 0.5f && end.y < 0.0f && top.y > 0.5f && top.x < 0.0f);
    }
    evr_scene_release(s);
}

/* ---- loading from memory: the same glTF handling (STEP read from the JSON) ---- */

static void test_memory(void)
{
    size_t n = 0;
    unsigned char *b = read_bytes(DATA "anim.gltf", &n);
    evr_scene *s = NULL;
    evr_error err;
    int i;
    CHECK(b != NULL);
    if (!b) return;
    CHECK_OK(evr_scene_load_memory(b, n, "gltf", &s, &err));
    if (s) {
        i = node_index(s, "step_t");
        CHECK(i >= 0 && s->nodes[i].t_curve.interp == EVR_INTERP_STEP);
        CHECK_NEAR(s->cameras[0].yfov, 0.5, 1e-6);
        CHECK(strncmp(s->source, "<memory>", 8) == 0);
        evr_scene_release(s);
    }
    free(b);
}

/* A scene in memory has no folder: it reads no file (an OBJ's material library, a glTF's
 * buffer), unless external files are allowed (then relative to the current folder). */
static void test_memory_reads_no_files(void)
{
    static const char obj[] = "mtllib ../../../../../../etc/passwd\nv 0 0 -1\nv 1 0 -1\n"
                              "v 0 1 -1\nf 1 2 3\n";
    static const char gltf[] =
        "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"/etc/passwd\","
        "\"byteLength\":4}]}";
    evr_scene *s = NULL;
    evr_error err;
    evr_load_options o;
    CHECK(evr_scene_load_memory(gltf, sizeof gltf - 1, "gltf", &s, &err) == EVR_ERR_FORMAT &&
          strstr(err.msg, "a scene in memory cannot read") != NULL);
    CHECK(s == NULL);
    /* the OBJ loads, without the material library Assimp was refused */
    CHECK_OK(evr_scene_load_memory(obj, sizeof obj - 1, "obj", &s, &err));
    evr_scene_release(s);
    s = NULL;
    evr_load_options_defaults(&o);
    o.allow_external = 1; /* allowed: the file is read, and the document fails on what it is */
    CHECK(evr_scene_load_memory_with(gltf, sizeof gltf - 1, "gltf", &o, &s, &err) != EVR_OK &&
          strstr(err.msg, "buffer") == NULL);
    evr_scene_release(s);
}

/* ---- bad inputs ---- */

static void test_bad_inputs(void)
{
    evr_scene *s = (evr_scene *)&s; /* must come back NULL */
    evr_error err;
    evr_status st;
    char dir[] = "/tmp/evray_import_XXXXXX";
    char path[256];
    size_t n = 0;
    unsigned char *glb;
    static const char garbage[] = "\x01\x02 this is not a scene \xff\xfe\x00 at all";

    st = evr_scene_load(DATA "does_not_exist.gltf", &s, &err);
    check_one_line(st, EVR_ERR_IO, &err);
    CHECK(s == NULL);
    CHECK(strstr(err.msg, "does_not_exist.gltf") != NULL);

    st = evr_scene_load(DATA "lines.gltf", &s, &err);
    check_one_line(st, EVR_ERR_FORMAT, &err);
    CHECK(strstr(err.msg, "no triangles") != NULL);
    CHECK(s == NULL);

    st = evr_scene_load_memory(garbage, sizeof garbage, "glb", &s, &err);
    check_one_line(st, EVR_ERR_FORMAT, &err);
    st = evr_scene_load_memory(garbage, sizeof garbage, "gltf", &s, &err);
    check_one_line(st, EVR_ERR_FORMAT, &err);
    st = evr_scene_load_memory(NULL, 0, "glb", &s, &err);
    check_one_line(st, EVR_ERR_ARG, &err);
    st = evr_scene_load(NULL, &s, &err);
    check_one_line(st, EVR_ERR_ARG, &err);

    if (!mkdtemp(dir)) {
        CHECK(!"mkdtemp");
        return;
    }
    glb = read_bytes(DATA "lights.glb", &n);
    CHECK(glb != NULL && n > 100);
    if (glb) {
        size_t cut[3];
        int k;
        cut[0] = n / 2;
        cut[1] = n - 30;
        cut[2] = 30;
        for (k = 0; k < 3; k++) {
            snprintf(path, sizeof path, "%s/truncated%d.glb", dir, k);
            CHECK(write_bytes(path, glb, cut[k]));
            st = evr_scene_load(path, &s, &err);
            check_one_line(st, EVR_ERR_FORMAT, &err);
            CHECK(s == NULL);
            unlink(path);
        }
        free(glb);
    }
    snprintf(path, sizeof path, "%s/garbage.glb", dir);
    CHECK(write_bytes(path, garbage, sizeof garbage));
    st = evr_scene_load(path, &s, &err);
    check_one_line(st, EVR_ERR_FORMAT, &err);
    unlink(path);
    snprintf(path, sizeof path, "%s/empty.gltf", dir);
    CHECK(write_bytes(path, "", 0));
    st = evr_scene_load(path, &s, &err);
    check_one_line(st, EVR_ERR_FORMAT, &err);
    unlink(path);
    /* a folder is not a scene */
    st = evr_scene_load(dir, &s, &err);
    check_one_line(st, EVR_ERR_IO, &err);
    /* an external texture that is missing: a warning naming it (the material keeps its
     * factors), an error when loading strictly */
    {
        size_t m = 0;
        unsigned char *txt = read_bytes(DATA "lights.gltf", &m);
        CHECK(txt != NULL);
        if (txt) {
            evr_load_options o;
            snprintf(path, sizeof path, "%s/lights.gltf", dir);
            CHECK(write_bytes(path, txt, m));
            CHECK_OK(evr_scene_load(path, &s, &e_));
            CHECK(s && strstr(evr_scene_warnings(s), "checker.png") &&
                  strstr(evr_scene_warnings(s), "keeps its factors"));
            evr_scene_release(s);
            s = NULL;
            evr_load_options_defaults(&o);
            o.strict = 1;
            st = evr_scene_load_with(path, &o, &s, &err);
            check_one_line(st, EVR_ERR_IO, &err);
            CHECK(strstr(err.msg, "checker.png") != NULL);
            CHECK(s == NULL);
            unlink(path);
            free(txt);
        }
    }
    rmdir(dir);
}

/* ---- texture decoding: 16-bit PNG and Radiance HDR (8-bit PNG: test_lights_materials) ---- */

/* lights.gltf in dir with its external checker.png replaced by the image in file; returns the
 * decoded texture's first texels through rgba (16 floats), 0 when it does not load. */
static int load_external_texture(const char *dir, const char *image, float rgba[16])
{
    char gltf[512], png[512];
    size_t m = 0;
    unsigned char *txt = read_bytes(DATA "lights.gltf", &m);
    evr_scene *s = NULL;
    evr_error err;
    int ok = 0;
    snprintf(gltf, sizeof gltf, "%s/lights.gltf", dir);
    snprintf(png, sizeof png, "%s/checker.png", dir);
    if (txt && write_bytes(gltf, txt, m) && rename(image, png) == 0 &&
        evr_scene_load(gltf, &s, &err) == EVR_OK) {
        for (int i = 0; i < s->num_materials; i++) {
            const evr_material *e = &s->materials[i];
            if (!strcmp(e->name, "external") && e->p.tex[EVR_TEX_BASE].index >= 0) {
                const evr_texture *t = &s->textures[e->p.tex[EVR_TEX_BASE].index];
                ok = t->width == 2 && t->height == 2;
                if (ok) memcpy(rgba, t->rgba, 16 * sizeof(float));
            }
        }
        evr_scene_release(s);
    }
    free(txt);
    unlink(gltf);
    unlink(png);
    return ok;
}

static void test_texture_depths(void)
{
    char dir[] = "/tmp/evray_tex_XXXXXX", path[512];
    float rgba[16];
    evr_error err;
    if (!mkdtemp(dir)) {
        CHECK(!"mkdtemp");
        return;
    }
    /* 16-bit: colour channels sRGB-encoded, alpha linear */
    {
        const uint16_t px[16] = {65535, 0, 32768, 16384, 0, 0, 0, 65535,
                                 0,     0, 0,     65535, 0, 0, 0, 65535};
        void *png = NULL;
        size_t n = 0;
        snprintf(path, sizeof path, "%s/img16", dir);
        CHECK(evr_png_encode(px, 2, 2, 4, 16, &png, &n, &err) == EVR_OK);
        CHECK(png && write_bytes(path, png, n));
        free(png);
        CHECK(load_external_texture(dir, path, rgba));
        CHECK_NEAR(rgba[0], 1.0, 1e-6);
        CHECK_NEAR(rgba[1], 0.0, 1e-6);
        CHECK_NEAR(rgba[2], srgb(32768.0 / 65535.0), 1e-6);
        CHECK_NEAR(rgba[3], 16384.0 / 65535.0, 1e-6);
    }
    /* Radiance HDR: linear already, values above 1 kept */
    {
        const float px[12] = {4.0f, 0.5f, 0.25f, 0.0f, 1.0f, 2.0f,
                              0.0f, 0.0f, 0.0f,  1.0f, 1.0f, 1.0f};
        snprintf(path, sizeof path, "%s/img.hdr", dir);
        CHECK(stbi_write_hdr(path, 2, 2, 3, px) != 0);
        CHECK(load_external_texture(dir, path, rgba));
        CHECK_NEAR(rgba[0], 4.0, 1e-6);
        CHECK_NEAR(rgba[1], 0.5, 1e-6);
        CHECK_NEAR(rgba[2], 0.25, 1e-6);
        CHECK_NEAR(rgba[3], 1.0, 1e-6);
        CHECK_NEAR(rgba[5], 1.0, 1e-6);
        CHECK_NEAR(rgba[6], 2.0, 1e-6);
    }
    rmdir(dir);
}

int main(void)
{
    test_texture_depths();
    test_gltf_cameras();
    test_lights_materials(DATA "lights.gltf", 0);
    test_lights_materials(DATA "lights.glb", 1);
    test_plain();
    test_collada_camera();
    test_3ds_camera();
    test_memory();
    test_memory_reads_no_files();
    test_bad_inputs();
    return check_report("test_import");
}
