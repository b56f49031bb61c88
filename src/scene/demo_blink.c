/* The "blink" scene: an eye that blinks by morph targets and a finger beside it that beckons by
 * skinning. Units metres, +Y up, the face looks along +Z; glTF conventions. Sizes below in
 * millimetres. 41,920 triangles; 3 joints, 6 morph targets.
 *
 *   eye          the eye scene's parts (demo_eye.c describes them), the eye centre at the origin:
 *                node "eyeball" (sclera, cornea, iris and pupil, still, looking along +Z), "skin"
 *                (out to a radius of 75, with a 1024 x 1024 texture) and "orbit".
 *   upper_lid,   the eye scene's lids, still nodes whose meshes deform by morph targets instead
 *   lower_lid    of turning. upper_lid: target "blink" is every vertex (and normal) turned by
 *                38 degrees about the X axis (front down), the closed lid; target "blink_arc" is
 *                the lid turned by half that minus the mean of the open and closed lids. A blink
 *                of closure b in [0, 1] gives the weights (b, 4 b (1 - b)): at b = 0, 1/2 and 1
 *                the lid is exactly the lid turned by 0, 19 and 38 degrees, and between them it
 *                stays within 0.01 of that arc (the straight path alone would cut 0.8 inside it,
 *                into the cornea). lower_lid: target "blink" turns it up by 2.5 degrees, weight b.
 *   upper_lashes, the eye scene's lashes on nodes of their own, with their lid's morph targets
 *   lower_lashes (each vertex turned the same way) and the same weight curves.
 *   finger       a skinned mesh on node "finger_skin" (no transform): a tapered tube along its
 *                +Y from -22 to 58 (radius 9 at the knuckle, 7.3 towards the tip, elliptical:
 *                0.85 as deep as wide, small bumps at the joints) closed by a rounded tip at 65;
 *                48 x 112 quads. Joints "finger_mcp" (y = 0), "finger_pip" (28) and "finger_dip"
 *                (48), each the child of the one before, under node "finger" at (32, -45, 30)
 *                turned 6 degrees about Z (leaning towards the eye). Each vertex follows the
 *                joint below it, blended over 6 mm around the PIP and DIP joints (two
 *                influences at most); inverse bind matrices are translations by -y of the joint.
 *                The palm side (+Z, u = 0.5) faces the camera: pads, creases and a fingerprint;
 *                knuckle wrinkles and a nail on the back.
 *   blink_camera camera on node "blink_camera" (no transform) under "blink_camera_mount" at
 *                (12, 0, 130), looking along -Z: yfov 2 atan(27 / 120) = 25.36 degrees,
 *                aspectRatio 16/9, znear 1, zfar 1000. The face (z = 10) shows x in [-36, 60],
 *                y in [-27, 27]; the eye's opening spans x in [-11.5, 11.5].
 *   lamp         point light at (-20, 30, 130), white, 0.03 candela: radiance about 0.4-0.6 on
 *                white at the face.
 *   animation    "blink", 3.6 s, looping (every curve has the same value at both ends):
 *                blinks start at 0.40 s (full), 1.45 s (half: closure 0.5, 0.6 times as long) and
 *                2.50 s (full); a full blink closes in 100 ms, holds 30 ms and opens in 170 ms
 *                (demo_eye_parts.h), so the lids rest in [0, 0.40], [0.70, 1.45], [1.63, 2.50]
 *                and [2.80, 3.6] with bit-identical keys. Weight keys every 2 ms in blinks.
 *                The finger beckons twice (1.8 s each): joint angles about their X axis (towards
 *                the palm) 10 f(t), 55 f(t - 0.06) and 35 f(t - 0.12) degrees for MCP, PIP and
 *                DIP, f(t) = (1 - cos(2 pi t / 1.8)) / 2; rotation keys every 1/60 s. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/demo_eye_parts.h"
#include "scene/demo_paint.h"

#define MM 0.001
#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

#define SKIN_OUTER 75.0
#define ANIM_LENGTH 3.6
#define BLINK_KEY_STEP 0.002
#define JOINT_KEY_STEP (1.0 / 60.0)
#define BEAT 1.8 /* one beckoning */

/* the finger, in its node's space */
#define FINGER_BASE (-22.0)
#define FINGER_SHAFT_END 58.0
#define FINGER_TIP 65.0
#define FINGER_R0 9.0 /* radius at y = 0 ... */
#define FINGER_R1 7.3 /* ... and at the shaft's end */
#define FINGER_DEPTH 0.85
#define FINGER_BLEND 3.0 /* half the width of a joint's blend */
#define FINGER_AROUND 48
#define FINGER_RINGS 100 /* along the shaft; the tip adds FINGER_TIP_RINGS */
#define FINGER_TIP_RINGS 12

static const double joint_y[3] = {0.0, 28.0, 48.0};
static const double joint_max_deg[3] = {10.0, 55.0, 35.0};
static const double joint_lag[3] = {0.0, 0.06, 0.12};

typedef struct {
    double start, depth, pace; /* pace: the blink's duration over a full blink's */
} blink_spec;

static const blink_spec blinks[3] = {{0.40, 1.0, 1.0}, {1.45, 0.5, 0.6}, {2.50, 1.0, 1.0}};
#define NUM_BLINKS ((int)(sizeof blinks / sizeof blinks[0]))

/* ---- the lids' morph targets ---- */

static void turn_x(const float *v, double a, double out[3])
{
    double c = cos(a), s = sin(a);
    out[0] = v[0];
    out[1] = v[1] * c - v[2] * s;
    out[2] = v[1] * s + v[2] * c;
}

/* Targets of a lid turned by angle (radians) about X: the turned lid, and with arc set the
 * correction that makes weights (b, 4 b (1 - b)) pass through the lid turned by half the angle. */
static int lid_targets(const evr_demo_mesh *m, double angle, int arc, float *dp, float *dn)
{
    const size_t n3 = 3 * (size_t)m->nv;
    uint32_t v;
    int k;
    for (v = 0; v < m->nv; v++) {
        const float *p = m->pos + 3 * v, *nr = m->nrm + 3 * v;
        double pc[3], nc[3], ph[3], nh[3];
        turn_x(p, angle, pc);
        turn_x(nr, angle, nc);
        turn_x(p, 0.5 * angle, ph);
        turn_x(nr, 0.5 * angle, nh);
        for (k = 0; k < 3; k++) {
            dp[3 * v + k] = (float)(pc[k] - p[k]);
            dn[3 * v + k] = (float)(nc[k] - nr[k]);
            if (arc) {
                dp[n3 + 3 * v + k] = (float)(ph[k] - 0.5 * (p[k] + pc[k]));
                dn[n3 + 3 * v + k] = (float)(nh[k] - 0.5 * (nr[k] + nc[k]));
            }
        }
    }
    return arc ? 2 : 1;
}

/* A lid (lashes = 0) or its lashes (lashes = 1) as a mesh with the lid's morph targets. */
static int lid_mesh(evr_gltf *g, int upper, int lashes, int material)
{
    static const char *const upper_names[2] = {"blink", "blink_arc"}, *const lower_names[1] = {
                                                                          "blink"};
    static const float zeros[2] = {0.0f, 0.0f};
    evr_demo_mesh m = {0};
    evr_gltf_mesh_desc d;
    float *dp, *dn;
    int r = -1;
    if (lashes) evr_eye_lashes(&m, upper);
    else evr_eye_lid(&m, upper);
    dp = malloc(sizeof(float) * 3 * 2 * (size_t)m.nv);
    dn = malloc(sizeof(float) * 3 * 2 * (size_t)m.nv);
    if (m.failed || !dp || !dn) {
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while generating the blink's lids");
    } else {
        evr_gltf_mesh_desc_init(&d, lashes ? (upper ? "upper_lashes" : "lower_lashes")
                                           : (upper ? "upper_lid" : "lower_lid"));
        d.positions = m.pos;
        d.normals = m.nrm;
        d.texcoords = m.uv;
        d.num_vertices = m.nv;
        d.indices = m.idx;
        d.num_indices = m.ni;
        d.material = material;
        d.num_targets = upper ? lid_targets(&m, EVR_EYE_BLINK_UPPER_DEG * DEG, 1, dp, dn)
                              : lid_targets(&m, -EVR_EYE_BLINK_LOWER_DEG * DEG, 0, dp, dn);
        d.target_positions = dp;
        d.target_normals = dn;
        d.default_weights = zeros;
        d.target_names = upper ? upper_names : lower_names;
        r = evr_gltf_add_mesh(g, &d);
    }
    free(dp);
    free(dn);
    free(m.pos);
    free(m.nrm);
    free(m.uv);
    free(m.idx);
    return r;
}

/* ---- the finger ---- */

/* Radius of the shaft at y: tapering, with a bump at the PIP and DIP joints. */
static double finger_radius(double y)
{
    double r = FINGER_R0 + (FINGER_R1 - FINGER_R0) * y / FINGER_SHAFT_END;
    int k;
    for (k = 1; k < 3; k++) r += 0.45 * exp(-pow((y - joint_y[k]) / 4.0, 2.0));
    return r;
}

/* Point of the finger at angle th around its axis (0: the palm, +Z) and parameter t in [0, 1]
 * along it: the shaft up to FINGER_RINGS / (FINGER_RINGS + FINGER_TIP_RINGS), then the tip, a
 * quarter ellipse closing at y = FINGER_TIP. */
static void finger_point(double th, double t, double p[3])
{
    const double ts = (double)FINGER_RINGS / (FINGER_RINGS + FINGER_TIP_RINGS);
    double y, r;
    if (t <= ts) {
        y = FINGER_BASE + (FINGER_SHAFT_END - FINGER_BASE) * t / ts;
        r = finger_radius(y);
    } else {
        double psi = 0.5 * PI * (t - ts) / (1.0 - ts);
        y = FINGER_SHAFT_END + (FINGER_TIP - FINGER_SHAFT_END) * sin(psi);
        r = finger_radius(FINGER_SHAFT_END) * cos(psi);
    }
    p[0] = r * sin(th);
    p[1] = y;
    p[2] = FINGER_DEPTH * r * cos(th);
}

/* Joints and weights of a vertex at height y: the joint below it, blended with the one below
 * that over FINGER_BLEND either side of a joint. */
static void finger_influences(double y, uint16_t *j, float *w)
{
    double b1 = evr_demo_smoothstep(joint_y[1] - FINGER_BLEND, joint_y[1] + FINGER_BLEND, y);
    double b2 = evr_demo_smoothstep(joint_y[2] - FINGER_BLEND, joint_y[2] + FINGER_BLEND, y);
    memset(j, 0, 4 * sizeof *j);
    memset(w, 0, 4 * sizeof *w);
    if (b2 > 0.0) { /* between PIP and DIP's influence, b1 is 1 */
        j[0] = 1;
        j[1] = 2;
        w[0] = (float)(1.0 - b2);
        w[1] = (float)b2;
    } else {
        j[0] = 0;
        j[1] = 1;
        w[0] = (float)(1.0 - b1);
        w[1] = (float)b1;
    }
    w[0] = 1.0f - w[1]; /* exactly 1 in float */
}

static int finger_mesh(evr_gltf *g, int material)
{
    const int cols = FINGER_AROUND, rows = FINGER_RINGS + FINGER_TIP_RINGS;
    const double h = 1e-4;
    evr_demo_mesh m = {0};
    evr_gltf_mesh_desc d;
    uint16_t *jv = NULL;
    float *wv = NULL;
    int i, j, k, r = -1;
    for (j = 0; j <= rows; j++) {
        double t = (double)j / rows;
        for (i = 0; i <= cols; i++) {
            double th = 2.0 * PI * i / cols - PI, p[3], a[3], b[3], c[3], e[3], n[3];
            finger_point(th, t, p);
            if (j == rows) { /* the tip's pole */
                n[0] = n[2] = 0.0;
                n[1] = 1.0;
            } else {
                finger_point(th - h, t, a);
                finger_point(th + h, t, b);
                finger_point(th, t > h ? t - h : 0.0, c);
                finger_point(th, t + h, e);
                for (k = 0; k < 3; k++) {
                    a[k] = b[k] - a[k];
                    c[k] = e[k] - c[k];
                }
                n[0] = a[1] * c[2] - a[2] * c[1]; /* outwards: around x along */
                n[1] = a[2] * c[0] - a[0] * c[2];
                n[2] = a[0] * c[1] - a[1] * c[0];
            }
            evr_demo_mesh_vertex_mm(&m, p[0], p[1], p[2], n, (double)i / cols,
                                    1.0 - (p[1] - FINGER_BASE) / (FINGER_TIP - FINGER_BASE));
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    jv = malloc(sizeof *jv * 4 * (size_t)m.nv);
    wv = malloc(sizeof *wv * 4 * (size_t)m.nv);
    if (m.failed || !jv || !wv) {
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while generating the finger");
    } else {
        uint32_t v;
        for (v = 0; v < m.nv; v++) finger_influences(m.pos[3 * v + 1] / MM, jv + 4 * v, wv + 4 * v);
        evr_gltf_mesh_desc_init(&d, "finger");
        d.positions = m.pos;
        d.normals = m.nrm;
        d.texcoords = m.uv;
        d.num_vertices = m.nv;
        d.indices = m.idx;
        d.num_indices = m.ni;
        d.material = material;
        d.joints = jv;
        d.weights = wv;
        r = evr_gltf_add_mesh(g, &d);
    }
    free(jv);
    free(wv);
    free(m.pos);
    free(m.nrm);
    free(m.uv);
    free(m.idx);
    return r;
}

/* The finger's skin: u around (0.5 the palm, 0 and 1 the back), v from the tip (0) to the base
 * (1), as finger_mesh maps them; painted in millimetres along the finger. */
static int paint_finger(evr_gltf *g)
{
    const double around = 2.0 * PI * 8.2, len = FINGER_TIP - FINGER_BASE;
    const double crease[3] = {150.0, 96.0, 80.0}, nail[3] = {226.0, 170.0, 160.0},
                 nail_edge[3] = {240.0, 226.0, 212.0}, ridge[3] = {180.0, 122.0, 104.0};
    evr_demo_image im;
    evr_demo_rng r = {2468u};
    int x, y, k, tex;
    if (!evr_demo_image_init(&im, 256, 512, 1)) {
        evr_demo_image_free(&im);
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
#define PX(u) ((u)*im.w)
#define PY(ymm) ((1.0 - ((ymm)-FINGER_BASE) / len) * im.h)
    for (y = 0; y < im.h; y++) {
        for (x = 0; x < im.w; x++) {
            double u = (x + 0.5) / im.w, c[3], palm = 0.5 + 0.5 * cos(2.0 * PI * (u - 0.5));
            evr_eye_skin_colour(c, u * around, (1.0 - (y + 0.5) / im.h) * len, 313u);
            for (k = 0; k < 3; k++) c[k] *= 1.0 + 0.06 * palm; /* the palm side is paler */
            evr_demo_image_set(&im, x, y, c);
        }
    }
    /* palmar creases: a double one at the PIP, single ones at the DIP and near the base */
    for (k = 0; k < 4; k++) {
        static const double cy[4] = {26.5, 29.0, 47.0, 8.0};
        evr_demo_image_stroke(&im, PX(0.30), PY(cy[k] + 0.6), PX(0.70), PY(cy[k] - 0.6), 1.6, 1.6,
                              0.75, 0.75);
    }
    evr_demo_image_apply(&im, crease);
    /* knuckle wrinkles on the back: short curved strokes over the PIP and DIP */
    for (k = 0; k < 14; k++) {
        double yc = k < 8 ? joint_y[1] : joint_y[2], yy = yc + evr_demo_rng_range(&r, -3.5, 3.5);
        double u0 = evr_demo_rng_range(&r, -0.16, -0.04), u1 = evr_demo_rng_range(&r, 0.04, 0.16);
        evr_demo_image_stroke(&im, PX(1.0 + u0), PY(yy - 0.4), PX(1.0 + 0.5 * (u0 + u1)), PY(yy),
                              1.0, 1.0, 0.6, 0.6);
        evr_demo_image_stroke(&im, PX(1.0 + 0.5 * (u0 + u1)), PY(yy), PX(1.0 + u1), PY(yy - 0.4),
                              1.0, 1.0, 0.6, 0.6);
    }
    evr_demo_image_apply(&im, crease);
    /* the fingerprint: arcs around the pad's centre on the palm side */
    for (k = 0; k < 12; k++) {
        double rr = 1.0 + 0.55 * k;
        int s;
        for (s = 0; s < 24; s++) {
            double a0 = PI * s / 24.0, a1 = PI * (s + 1) / 24.0;
            evr_demo_image_stroke(&im, PX(0.5 + rr * cos(a0) / around),
                                  PY(57.0 + 0.8 * rr * sin(a0) - 2.0),
                                  PX(0.5 + rr * cos(a1) / around),
                                  PY(57.0 + 0.8 * rr * sin(a1) - 2.0), 0.8, 0.8, 0.45, 0.45);
        }
    }
    evr_demo_image_apply(&im, ridge);
    /* the nail on the back: 9.6 wide from a rounded base at y = 51 to a pale free edge */
    for (y = 0; y < im.h; y++) {
        double ymm = FINGER_BASE + (1.0 - (y + 0.5) / im.h) * len;
        for (x = 0; x < im.w; x++) {
            double u = (x + 0.5) / im.w, du = (u < 0.5 ? u : 1.0 - u) * around, e = du / 4.8;
            double *px = im.rgb + 3 * ((size_t)y * (size_t)im.w + (size_t)x);
            if (e >= 1.0 || ymm < 51.0 + 2.0 * e * e) continue;
            for (k = 0; k < 3; k++)
                px[k] = ymm > FINGER_TIP - 1.5 + 0.8 * e * e ? nail_edge[k] : nail[k];
        }
    }
#undef PX
#undef PY
    tex = evr_demo_image_texture(g, &im, "finger_texture");
    evr_demo_image_free(&im);
    return tex;
}

/* ---- animation ---- */

static double blink_closure_at(double t)
{
    double b = 0.0;
    int k;
    for (k = 0; k < NUM_BLINKS; k++)
        b += blinks[k].depth * evr_eye_blink_closure((t - blinks[k].start) / blinks[k].pace);
    return b;
}

static double beckon(double t) { return 0.5 - 0.5 * cos(2.0 * PI * t / BEAT); }

/* Weight keys: the ends of the animation and every <= 2 ms through each blink (the lids hold
 * bit-identical weights between blinks); joint keys every 1/60 s. */
static void build_animation(evr_gltf *g, const int *upper, const int *lower, const int *joints)
{
    const int max_keys = 1024;
    const int nj = (int)ceil(ANIM_LENGTH / JOINT_KEY_STEP - 1e-9);
    float *times = malloc(sizeof(float) * (size_t)max_keys);
    float *wu = malloc(sizeof(float) * 2 * (size_t)max_keys);
    float *wl = malloc(sizeof(float) * (size_t)max_keys);
    float *jt = malloc(sizeof(float) * (size_t)(nj + 1));
    float *q = malloc(sizeof(float) * 4 * (size_t)(nj + 1));
    int n = 0, k, i, anim;
    if (!times || !wu || !wl || !jt || !q) {
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while building the blink animation");
        goto done;
    }
    times[n++] = 0.0f;
    for (k = 0; k < NUM_BLINKS; k++) {
        double a = blinks[k].start, len = EVR_EYE_BLINK_LEN * blinks[k].pace;
        int steps = (int)ceil(len / BLINK_KEY_STEP - 1e-9);
        for (i = 0; i <= steps && n < max_keys - 1; i++)
            times[n++] = (float)(i == steps ? a + len : a + len * i / steps);
    }
    times[n++] = (float)ANIM_LENGTH;
    for (k = 0; k < n; k++) {
        double b = blink_closure_at(times[k]);
        wu[2 * k] = (float)b;
        wu[2 * k + 1] = (float)(4.0 * b * (1.0 - b));
        wl[k] = (float)b;
    }
    anim = evr_gltf_animation(g, "blink");
    for (k = 0; k < 2; k++) { /* each lid and its lashes */
        evr_gltf_channel(g, anim, upper[k], EVR_GLTF_WEIGHTS, times, wu, n, EVR_GLTF_LINEAR);
        evr_gltf_channel(g, anim, lower[k], EVR_GLTF_WEIGHTS, times, wl, n, EVR_GLTF_LINEAR);
    }
    for (k = 0; k < 3; k++) {
        for (i = 0; i <= nj; i++) {
            double t = i == nj ? ANIM_LENGTH : i * JOINT_KEY_STEP;
            double a = joint_max_deg[k] * DEG * beckon(t - joint_lag[k]);
            jt[i] = (float)t;
            q[4 * i] = (float)sin(0.5 * a); /* about +X: towards the palm */
            q[4 * i + 1] = 0.0f;
            q[4 * i + 2] = 0.0f;
            q[4 * i + 3] = (float)cos(0.5 * a);
        }
        evr_gltf_node_rotation(g, joints[k], q[0], q[1], q[2], q[3]); /* rest: the pose at 0 */
        evr_gltf_channel(g, anim, joints[k], EVR_GLTF_ROTATION, jt, q, nj + 1, EVR_GLTF_LINEAR);
    }
done:
    free(times);
    free(wu);
    free(wl);
    free(jt);
    free(q);
}

/* ---- the scene ---- */

void evr_demo_build_blink(evr_gltf *g)
{
    evr_gltf_material mat;
    float ibm[3 * 16];
    int m_lid_up, m_lid_lo, m_lash_up, m_lash_lo, m_skin, m_orbit, m_finger, eyeball, node,
        upper[2], lower[2], root, joints[3], skin, mount, cam, lamp, k;

    m_lid_up = evr_eye_material(
        g, "upper_eyelid", evr_eye_paint_eyelid(g, "upper_eyelid_texture", 4242u, 0, 22.0, 50.0),
        0.55f);
    m_lid_lo = evr_eye_material(
        g, "lower_eyelid", evr_eye_paint_eyelid(g, "lower_eyelid_texture", 4343u, 0, 10.0, 24.0),
        0.55f);
    m_lash_up = evr_eye_lash_material(g, 1);
    m_lash_lo = evr_eye_lash_material(g, 0);
    m_skin = evr_eye_material(g, "skin", evr_eye_paint_skin(g, SKIN_OUTER, 1024), 0.55f);
    m_finger = evr_eye_material(g, "finger", paint_finger(g), 0.5f);
    evr_gltf_material_init(&mat, "orbit");
    mat.base_color[0] = 0.25f;
    mat.base_color[1] = 0.09f;
    mat.base_color[2] = 0.08f;
    m_orbit = evr_gltf_add_material(g, &mat);
    if (evr_gltf_status(g, NULL) != EVR_OK) return;

    eyeball = evr_gltf_node(g, "eyeball", -1);
    evr_eye_globe(g, eyeball);
    upper[0] = evr_gltf_node(g, "upper_lid", -1);
    evr_gltf_node_mesh(g, upper[0], lid_mesh(g, 1, 0, m_lid_up));
    upper[1] = evr_gltf_node(g, "upper_lashes", -1);
    evr_gltf_node_mesh(g, upper[1], lid_mesh(g, 1, 1, m_lash_up));
    lower[0] = evr_gltf_node(g, "lower_lid", -1);
    evr_gltf_node_mesh(g, lower[0], lid_mesh(g, 0, 0, m_lid_lo));
    lower[1] = evr_gltf_node(g, "lower_lashes", -1);
    evr_gltf_node_mesh(g, lower[1], lid_mesh(g, 0, 1, m_lash_lo));
    node = evr_gltf_node(g, "skin", -1);
    evr_gltf_node_mesh(g, node, evr_eye_skin(g, m_skin, SKIN_OUTER));
    node = evr_gltf_node(g, "orbit", -1);
    evr_gltf_node_mesh(g, node, evr_eye_orbit(g, m_orbit));

    /* the finger: its rig, then the skinned mesh on a node of its own (glTF ignores that node's
     * transform; the joints place the mesh) */
    root = evr_gltf_node(g, "finger", -1);
    evr_gltf_node_translation(g, root, (float)(32.0 * MM), (float)(-45.0 * MM), (float)(30.0 * MM));
    evr_gltf_node_rotation(g, root, 0.0f, 0.0f, (float)sin(3.0 * DEG), (float)cos(3.0 * DEG));
    joints[0] = evr_gltf_node(g, "finger_mcp", root);
    joints[1] = evr_gltf_node(g, "finger_pip", joints[0]);
    evr_gltf_node_translation(g, joints[1], 0.0f, (float)((joint_y[1] - joint_y[0]) * MM), 0.0f);
    joints[2] = evr_gltf_node(g, "finger_dip", joints[1]);
    evr_gltf_node_translation(g, joints[2], 0.0f, (float)((joint_y[2] - joint_y[1]) * MM), 0.0f);
    memset(ibm, 0, sizeof ibm);
    for (k = 0; k < 3; k++) { /* column-major: a translation by -joint_y */
        float *mk = ibm + 16 * k;
        mk[0] = mk[5] = mk[10] = mk[15] = 1.0f;
        mk[13] = (float)(-joint_y[k] * MM);
    }
    skin = evr_gltf_skin(g, "finger_rig", joints, 3, ibm, joints[0]);
    node = evr_gltf_node(g, "finger_skin", -1);
    evr_gltf_node_mesh(g, node, finger_mesh(g, m_finger));
    evr_gltf_node_skin(g, node, skin);

    /* The camera sits on an untransformed child of its mount (see demo_eye.c). */
    mount = evr_gltf_node(g, "blink_camera_mount", -1);
    evr_gltf_node_translation(g, mount, (float)(12.0 * MM), 0.0f, (float)(130.0 * MM));
    cam = evr_gltf_camera(g, "blink_camera", (float)(2.0 * atan(27.0 / 120.0)), 16.0f / 9.0f,
                          1.0f * (float)MM, 1.0f);
    node = evr_gltf_node(g, "blink_camera", mount);
    evr_gltf_node_camera(g, node, cam);

    lamp = evr_gltf_light(g, "lamp", EVR_GLTF_POINT, NULL, 0.03f, 0.0f, 0.0f);
    node = evr_gltf_node(g, "lamp", -1);
    evr_gltf_node_translation(g, node, (float)(-20.0 * MM), (float)(30.0 * MM),
                              (float)(130.0 * MM));
    evr_gltf_node_light(g, node, lamp);

    build_animation(g, upper, lower, joints);
}
