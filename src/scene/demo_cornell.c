/* The "cornell" scene: a Cornell box with a moving box, for global illumination ("cornell-still":
 * the same with the short box held still by its animation; "cornell-bleed": white side walls and
 * a red short box sliding along the right wall, so that the colour bled onto the wall and floor
 * comes from what moves). A 1 m room
 * (x in [-0.5, 0.5], y in [0, 1], z in [-0.5, 0.5], open at +z) with a red left wall (0.63, 0.065,
 * 0.05), a green right wall (0.14, 0.45, 0.091), white floor, ceiling and back wall (0.725, 0.71,
 * 0.68: the reflectances of the classic Cornell data); an emissive ceiling panel (0.25 m square,
 * radiance 1, the most a glTF emissive factor holds) with a point light just below it for direct
 * light and shadows;
 * a tall white box standing still and a short white box sliding 0.35 m across the floor and back
 * over 2 s. The camera looks into the open side from z = 1.9. */
#include <math.h>

#include "scene/demo_scenes.h"

/* An axis-aligned quad: centre c, half sizes along axes u and v (0 x, 1 y, 2 z), normal sign. */
static void quad(evr_demo_mesh *m, const double c[3], int u, int v, double hu, double hv,
                 const double n[3])
{
    uint32_t first = m->nv;
    int i, j;
    for (j = 0; j < 2; j++)
        for (i = 0; i < 2; i++) {
            double p[3] = {c[0], c[1], c[2]};
            p[u] += i ? hu : -hu;
            p[v] += j ? -hv : hv;
            evr_demo_mesh_vertex(m, p, n, (double)i, (double)j);
        }
    evr_demo_mesh_triangle(m, first, first + 2, first + 1);
    evr_demo_mesh_triangle(m, first + 1, first + 2, first + 3);
}

static int wall(evr_gltf *g, const char *name, const double c[3], int u, int v, double hu,
                double hv, const double n[3], int material)
{
    evr_demo_mesh m = {0};
    quad(&m, c, u, v, hu, hv, n);
    return evr_demo_mesh_finish(g, &m, name, material);
}

/* A closed box centred on the origin with half sizes h. */
static int box(evr_gltf *g, const char *name, const double h[3], int material)
{
    evr_demo_mesh m = {0};
    int axis, s;
    for (axis = 0; axis < 3; axis++)
        for (s = -1; s <= 1; s += 2) {
            double c[3] = {0, 0, 0}, n[3] = {0, 0, 0};
            int u = (axis + 1) % 3, v = (axis + 2) % 3;
            c[axis] = s * h[axis];
            n[axis] = s;
            quad(&m, c, u, v, h[u], h[v], n);
        }
    return evr_demo_mesh_finish(g, &m, name, material);
}

static int material(evr_gltf *g, const char *name, float r, float gg, float b, float e)
{
    evr_gltf_material mat;
    evr_gltf_material_init(&mat, name);
    mat.base_color[0] = r;
    mat.base_color[1] = gg;
    mat.base_color[2] = b;
    mat.emissive[0] = mat.emissive[1] = mat.emissive[2] = e;
    mat.double_sided = 1;
    return evr_gltf_add_material(g, &mat);
}

static void place(evr_gltf *g, const char *name, int mesh, float x, float y, float z)
{
    int n = evr_gltf_node(g, name, -1);
    evr_gltf_node_mesh(g, n, mesh);
    evr_gltf_node_translation(g, n, x, y, z);
}

/* moving 0: the short box's animation holds it where it starts (cornell-still: nothing moves,
 * though the box is animated; with global illumination on it must make no events). bleed: the
 * side walls white, the short box red and unturned, sliding 0.4 m along the right wall 0.1 m
 * from it and back over 2 s (cornell-bleed). */
static void build_cornell(evr_gltf *g, int moving, int bleed)
{
    int white = material(g, "white", 0.725f, 0.71f, 0.68f, 0.0f);
    int red = material(g, "red", 0.63f, 0.065f, 0.05f, 0.0f);
    int right = bleed ? white : material(g, "green", 0.14f, 0.45f, 0.091f, 0.0f);
    int left = bleed ? white : red;
    int light =
        material(g, "light", 0.78f, 0.78f, 0.78f, 1.0f); /* glTF caps emissive factors at 1 */
    static const double floor_c[3] = {0, 0, 0}, floor_n[3] = {0, 1, 0};
    static const double ceil_c[3] = {0, 1, 0}, ceil_n[3] = {0, -1, 0};
    static const double back_c[3] = {0, 0.5, -0.5}, back_n[3] = {0, 0, 1};
    static const double left_c[3] = {-0.5, 0.5, 0}, left_n[3] = {1, 0, 0};
    static const double right_c[3] = {0.5, 0.5, 0}, right_n[3] = {-1, 0, 0};
    static const double panel_c[3] = {0, 0.999, 0};
    place(g, "floor", wall(g, "floor", floor_c, 0, 2, 0.5, 0.5, floor_n, white), 0, 0, 0);
    place(g, "ceiling", wall(g, "ceiling", ceil_c, 0, 2, 0.5, 0.5, ceil_n, white), 0, 0, 0);
    place(g, "back_wall", wall(g, "back_wall", back_c, 0, 1, 0.5, 0.5, back_n, white), 0, 0, 0);
    place(g, "left_wall", wall(g, "left_wall", left_c, 2, 1, 0.5, 0.5, left_n, left), 0, 0, 0);
    place(g, "right_wall", wall(g, "right_wall", right_c, 2, 1, 0.5, 0.5, right_n, right), 0, 0, 0);
    place(g, "light_panel", wall(g, "light_panel", panel_c, 0, 2, 0.125, 0.125, ceil_n, light), 0,
          0, 0);

    static const double tall_h[3] = {0.15, 0.3, 0.15}, short_h[3] = {0.15, 0.15, 0.15};
    int n_tall = evr_gltf_node(g, "tall_box", -1);
    evr_gltf_node_mesh(g, n_tall, box(g, "tall_box", tall_h, white));
    evr_gltf_node_translation(g, n_tall, -0.17f, 0.3f, -0.15f);
    evr_gltf_node_rotation(g, n_tall, 0.0f, (float)sin(0.5 * 0.29), 0.0f, (float)cos(0.5 * 0.29));
    int n_short = evr_gltf_node(g, "short_box", -1);
    evr_gltf_node_mesh(g, n_short, box(g, "short_box", short_h, bleed ? red : white));
    if (!bleed)
        evr_gltf_node_rotation(g, n_short, 0.0f, (float)sin(-0.5 * 0.3), 0.0f,
                               (float)cos(-0.5 * 0.3));
    const float times[3] = {0.0f, 1.0f, 2.0f};
    const float pos_moving[9] = {0.18f, 0.15f, 0.12f, -0.17f, 0.15f, 0.2f, 0.18f, 0.15f, 0.12f};
    const float pos_still[9] = {0.18f, 0.15f, 0.12f, 0.18f, 0.15f, 0.12f, 0.18f, 0.15f, 0.12f};
    const float pos_bleed[9] = {0.25f, 0.15f, 0.2f, 0.25f, 0.15f, -0.2f, 0.25f, 0.15f, 0.2f};
    const float *pos = bleed ? pos_bleed : moving ? pos_moving : pos_still;
    /* cornell-still: the rest pose differs from the held one, so the importer keeps the curve
     * and the box is an animated node that never moves */
    if (moving) evr_gltf_node_translation(g, n_short, pos[0], pos[1], pos[2]);
    else evr_gltf_node_translation(g, n_short, pos[0], pos[1] + 0.5f, pos[2]);
    int anim = evr_gltf_animation(g, "box_motion");
    evr_gltf_channel(g, anim, n_short, EVR_GLTF_TRANSLATION, times, pos, 3, EVR_GLTF_LINEAR);

    /* a point light just below the panel lights the room directly (shadows, colour of the walls) */
    int lamp =
        evr_gltf_light(g, "ceiling_light", EVR_GLTF_POINT, NULL, 15.0f * 0.0625f, 0.0f, 0.0f);
    int n_lamp = evr_gltf_node(g, "ceiling_light", -1);
    evr_gltf_node_translation(g, n_lamp, 0.0f, 0.97f, 0.0f);
    evr_gltf_node_light(g, n_lamp, lamp);

    int cam =
        evr_gltf_camera(g, "cornell_camera", (float)(2.0 * atan(0.5 / 1.4)), 1.0f, 0.05f, 100.0f);
    int n_mount = evr_gltf_node(g, "cornell_camera_mount", -1);
    evr_gltf_node_translation(g, n_mount, 0.0f, 0.5f, 1.9f);
    int n_cam = evr_gltf_node(g, "cornell_camera", n_mount);
    evr_gltf_node_camera(g, n_cam, cam);
}

void evr_demo_build_cornell(evr_gltf *g) { build_cornell(g, 1, 0); }
void evr_demo_build_cornell_still(evr_gltf *g) { build_cornell(g, 0, 0); }
void evr_demo_build_cornell_bleed(evr_gltf *g) { build_cornell(g, 1, 1); }
