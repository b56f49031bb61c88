/* The "square" scene: analytic ground truth for tests. Units metres, +Y up, glTF conventions.
 *
 *   background   mesh and node "background": a 4 m x 4 m square in the plane z = 0, centred at the
 *                origin, facing +Z (2 triangles); material "background": base colour 0.1 grey,
 *                metallic 0, roughness 1 (matte), no texture.
 *   square       mesh and node "square": a 0.5 m x 0.5 m square, facing +Z; the mesh lies at
 *                z = 0 in node space (corners (+-0.25, +-0.25, 0)) and the node is translated to
 *                z = 0.01; material "square": base colour 0.1 e^2 = 0.7389056 grey, so that
 *                ln(square / background) = 2 exactly under any lighting that scales with albedo.
 *   motion       animation "square_motion": the node's translation, LINEAR, two keys:
 *                t = 0 s: (-1, 0, 0.01), t = 2 s: (+1, 0, 0.01); i.e. x_centre(t) = -1 + t,
 *                1 m/s along +X; the rest pose is the t = 0 pose. Animation length 2 s.
 *                Square edges: leading (right) x = -0.75 + t, trailing (left) x = -1.25 + t,
 *                top/bottom y = +-0.25.
 *   camera       camera "square_camera" on node "square_camera" (no transform) under node
 *                "square_camera_mount" at (0, 0, 4) without rotation (looks along -Z, +Y up;
 *                the child keeps readers that copy a camera node's translation into the camera,
 *                as Assimp does, from applying it twice), yfov = 2 atan(1/4) = 0.489957326 rad (28.07 deg), aspectRatio 1,
 *                znear 0.1, zfar 100. The view spans exactly x, y in [-1, 1] on the background
 *                (distance 4); the square's plane is at distance 3.99, so a point (x, y) on the
 *                square appears at normalized image coordinates (nx, ny) = (x, y) * 4 / 3.99,
 *                nx in [-1, 1] left to right (pixel column c of W: nx = 2 (c + 0.5) / W - 1),
 *                ny in [-1, 1] bottom to top.
 *   crossings    a pixel at nx with |ny| < 0.25 * 4 / 3.99 sees the leading edge (dark -> bright,
 *                +2 in log intensity: ON events) at t_on = 0.75 + 0.9975 nx and the trailing edge
 *                (bright -> dark, -2: OFF events) at t_off = 1.25 + 0.9975 nx, where these lie in
 *                [0, 2] s. At t = 0 the square covers nx in [-1.2531, -0.7519] (partly outside
 *                the view); at t = 2 it covers [0.7519, 1.2531].
 *   light        light and node "lamp": KHR_lights_punctual point light, white, 16 pi candela, at
 *                the camera's position (0, 0, 4) (child of the camera mount). Seen from the
 *                camera every shadow falls exactly behind the object that casts it, so no shadow
 *                is visible and each pixel sees only the square or the lit background. Along
 *                the optical axis the background gets irradiance pi (radiance = albedo 0.1);
 *                a pixel's view ray meets the square at 3.99/4 of the background's distance
 *                along the same direction, so at every pixel the square is brighter than the
 *                background by the albedo ratio e^2 times (4/3.99)^2 (before the ambient term):
 *                ln(square / background) = 2 + 2 ln(4/3.99) = 2.005 (2.004 with the default
 *                ambient 0.02). */
#include <math.h>

#include "scene/demo_scenes.h"

#define SQUARE_DARK 0.1f
#define SQUARE_BRIGHT 0.738905609893065f /* 0.1 * e^2 */

static int add_quad(evr_gltf *g, const char *name, double half, int material)
{
    evr_demo_mesh m = {0};
    static const double n[3] = {0.0, 0.0, 1.0};
    double p[3];
    int i, j;
    for (j = 0; j < 2; j++) { /* row 0 at the top: texture v = 0 */
        for (i = 0; i < 2; i++) {
            p[0] = i ? half : -half;
            p[1] = j ? -half : half;
            p[2] = 0.0;
            evr_demo_mesh_vertex(&m, p, n, (double)i, (double)j);
        }
    }
    evr_demo_mesh_grid(&m, 0, 1, 1);
    return evr_demo_mesh_finish(g, &m, name, material);
}

void evr_demo_build_square(evr_gltf *g)
{
    evr_gltf_material mat;
    int m_bg, m_sq, mesh_bg, mesh_sq, n_bg, n_sq, n_mount, n_cam, n_sun, cam, sun, anim;
    const float times[2] = {0.0f, 2.0f};
    const float pos[6] = {-1.0f, 0.0f, 0.01f, 1.0f, 0.0f, 0.01f};

    evr_gltf_material_init(&mat, "background");
    mat.specular = 0.0f; /* matte: Lambert, whose intensities the tests know analytically */
    mat.base_color[0] = mat.base_color[1] = mat.base_color[2] = SQUARE_DARK;
    m_bg = evr_gltf_add_material(g, &mat);
    evr_gltf_material_init(&mat, "square");
    mat.specular = 0.0f; /* matte: Lambert, whose intensities the tests know analytically */
    mat.base_color[0] = mat.base_color[1] = mat.base_color[2] = SQUARE_BRIGHT;
    m_sq = evr_gltf_add_material(g, &mat);

    mesh_bg = add_quad(g, "background", 2.0, m_bg);
    mesh_sq = add_quad(g, "square", 0.25, m_sq);

    n_bg = evr_gltf_node(g, "background", -1);
    evr_gltf_node_mesh(g, n_bg, mesh_bg);
    n_sq = evr_gltf_node(g, "square", -1);
    evr_gltf_node_mesh(g, n_sq, mesh_sq);
    evr_gltf_node_translation(g, n_sq, pos[0], pos[1], pos[2]);

    cam = evr_gltf_camera(g, "square_camera", (float)(2.0 * atan(0.25)), 1.0f, 0.1f, 100.0f);
    n_mount = evr_gltf_node(g, "square_camera_mount", -1);
    evr_gltf_node_translation(g, n_mount, 0.0f, 0.0f, 4.0f);
    n_cam = evr_gltf_node(g, "square_camera", n_mount);
    evr_gltf_node_camera(g, n_cam, cam);

    sun = evr_gltf_light(g, "lamp", EVR_GLTF_POINT, NULL, 16.0f * 3.14159265f, 0.0f, 0.0f);
    n_sun = evr_gltf_node(g, "lamp", n_mount);
    evr_gltf_node_light(g, n_sun, sun);

    anim = evr_gltf_animation(g, "square_motion");
    evr_gltf_channel(g, anim, n_sq, EVR_GLTF_TRANSLATION, times, pos, 2, EVR_GLTF_LINEAR);
}
