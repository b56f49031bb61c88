/* The "disk" scene: the classic event-camera test pattern. A matte disk of radius 0.5 m with
 * 8 alternating black (albedo 0.05) and white (0.8) sectors spins about the camera's optical
 * axis at 1 revolution per second for 2 s, 0.02 m in front of a grey background (0.2) 2 m away
 * from the camera; a point light at the camera lights it without visible shadows. The sectors are
 * separate meshes (no texture filtering: the edges are exact), rotation keys every 45 degrees
 * (constant angular speed). */
#include <math.h>

#include "scene/demo_scenes.h"

#define DISK_SECTORS 8
#define DISK_SEGMENTS 32 /* arc segments per sector */
#define DISK_RADIUS 0.5
#define DISK_PI 3.14159265358979323846

/* The sectors of one colour: parity 0 or 1. */
static int add_sectors(evr_gltf *g, const char *name, int parity, int material)
{
    evr_demo_mesh m = {0};
    static const double n[3] = {0.0, 0.0, 1.0};
    int s, k;
    for (s = parity; s < DISK_SECTORS; s += 2) {
        double c[3] = {0.0, 0.0, 0.0};
        uint32_t centre = evr_demo_mesh_vertex(&m, c, n, 0.5, 0.5), prev = 0;
        for (k = 0; k <= DISK_SEGMENTS; k++) {
            double a = 2.0 * DISK_PI * ((double)s + (double)k / DISK_SEGMENTS) / DISK_SECTORS;
            double p[3] = {DISK_RADIUS * cos(a), DISK_RADIUS * sin(a), 0.0};
            uint32_t v = evr_demo_mesh_vertex(&m, p, n, 0.5 + 0.5 * cos(a), 0.5 - 0.5 * sin(a));
            if (k > 0) evr_demo_mesh_triangle(&m, centre, prev, v);
            prev = v;
        }
    }
    return evr_demo_mesh_finish(g, &m, name, material);
}

static int add_plane(evr_gltf *g, const char *name, double half, int material)
{
    evr_demo_mesh m = {0};
    static const double n[3] = {0.0, 0.0, 1.0};
    int i, j;
    for (j = 0; j < 2; j++)
        for (i = 0; i < 2; i++) {
            double p[3] = {i ? half : -half, j ? -half : half, 0.0};
            evr_demo_mesh_vertex(&m, p, n, (double)i, (double)j);
        }
    evr_demo_mesh_grid(&m, 0, 1, 1);
    return evr_demo_mesh_finish(g, &m, name, material);
}

void evr_demo_build_disk(evr_gltf *g)
{
    evr_gltf_material mat;
    float times[17], rot[17 * 4];
    int k;
    evr_gltf_material_init(&mat, "white");
    mat.specular = 0.0f; /* matte: Lambert, whose intensities the tests know analytically */
    mat.base_color[0] = mat.base_color[1] = mat.base_color[2] = 0.8f;
    int m_white = evr_gltf_add_material(g, &mat);
    evr_gltf_material_init(&mat, "black");
    mat.specular = 0.0f; /* matte: Lambert, whose intensities the tests know analytically */
    mat.base_color[0] = mat.base_color[1] = mat.base_color[2] = 0.05f;
    int m_black = evr_gltf_add_material(g, &mat);
    evr_gltf_material_init(&mat, "background");
    mat.specular = 0.0f; /* matte: Lambert, whose intensities the tests know analytically */
    mat.base_color[0] = mat.base_color[1] = mat.base_color[2] = 0.2f;
    int m_bg = evr_gltf_add_material(g, &mat);

    int mesh_w = add_sectors(g, "white_sectors", 0, m_white);
    int mesh_b = add_sectors(g, "black_sectors", 1, m_black);
    int mesh_bg = add_plane(g, "background", 1.5, m_bg);

    int n_bg = evr_gltf_node(g, "background", -1);
    evr_gltf_node_mesh(g, n_bg, mesh_bg);
    int n_disk = evr_gltf_node(g, "disk", -1);
    evr_gltf_node_translation(g, n_disk, 0.0f, 0.0f, 0.02f);
    int n_w = evr_gltf_node(g, "white_sectors", n_disk);
    evr_gltf_node_mesh(g, n_w, mesh_w);
    int n_b = evr_gltf_node(g, "black_sectors", n_disk);
    evr_gltf_node_mesh(g, n_b, mesh_b);

    int cam = evr_gltf_camera(g, "disk_camera", (float)(2.0 * atan(0.7 / 2.0)), 4.0f / 3.0f, 0.05f,
                              100.0f);
    int n_mount = evr_gltf_node(g, "disk_camera_mount", -1);
    evr_gltf_node_translation(g, n_mount, 0.0f, 0.0f, 2.0f);
    int n_cam = evr_gltf_node(g, "disk_camera", n_mount);
    evr_gltf_node_camera(g, n_cam, cam);
    int lamp = evr_gltf_light(g, "lamp", EVR_GLTF_POINT, NULL, 4.0f * 3.14159265f, 0.0f, 0.0f);
    int n_lamp = evr_gltf_node(g, "lamp", n_mount);
    evr_gltf_node_light(g, n_lamp, lamp);

    /* 1 revolution per second about +Z for 2 s: keys every 45 degrees (1/8 s) */
    for (k = 0; k <= 16; k++) {
        double a = 2.0 * DISK_PI * k / 8.0;
        times[k] = (float)k / 8.0f;
        rot[4 * k + 0] = 0.0f;
        rot[4 * k + 1] = 0.0f;
        rot[4 * k + 2] = (float)sin(0.5 * a);
        rot[4 * k + 3] = (float)cos(0.5 * a);
    }
    int anim = evr_gltf_animation(g, "spin");
    evr_gltf_channel(g, anim, n_disk, EVR_GLTF_ROTATION, times, rot, 17, EVR_GLTF_LINEAR);
}
