/* The "eye" and "eye-drift" scenes: what a head-mounted eye tracker's camera sees. Units metres, +Y up, the
 * subject looks along +Z; glTF conventions. Sizes below are in millimetres. 31,216 triangles.
 *
 *   eyeball      node "eyeball" at the origin, animated rotation (gaze); children (demo_eye_parts.c,
 *                evr_eye_globe, shared with the blink scene):
 *     sclera     a UV sphere of radius 12 (poles on the Z axis) behind the limbus (polar angle
 *                37.2 degrees and more from +Z), textured white-pink with faint conjunctival
 *                vessels; a moist dielectric, roughness 0.25.
 *     cornea     a closed volume of the cornea's (and aqueous humour's) index: its front surface
 *                the spherical cap of radius 7.8 centred at z = 6.7 (apex at z = 14.5, 2.5 in
 *                front of the eyeball) out to the limbus, where it meets the eyeball (z = 9.556,
 *                radius 7.258); closed behind by a disc in the limbus plane. Clear: transmission 1,
 *                IOR 1.376, roughness 0.03 (the tear film: the smooth dielectric whose reflection of
 *                the LED is the glint, the first Purkinje image), KHR_materials_volume thickness
 *                4.9 (apex to limbus plane).
 *     iris       inside the cornea's volume: a ring from the pupil's edge (radius 1.8, z = 11.6,
 *                2.9 behind the apex) nearly flat out to the visible iris's edge (radius 5.75,
 *                z = 11.15), then down to its root at the limbus; textured by a planar projection
 *                along Z (radial fibres, collarette, crypts, dark limbal ring; sclera-coloured
 *                beyond 6.1, as the sclera overlaps a real cornea's edge); roughness 0.5.
 *     pupil      a black unlit disc (radius 1.85) 0.05 behind the iris's inner edge: the hole.
 *   upper_lid,   sheets on nodes that rotate about the X axis through the eye centre. Each is a
 *   lower_lid    surface of revolution about that axis (so the rotation slides it over itself):
 *                at the middle a sphere around the eye centre of radius 14.8 (upper) or 15.1
 *                (lower), tapering from |x| = 7 to 11.2 to 12.4 / 12.7 so that the lids hug the
 *                eyeball at the corners, and going on past them as tubes under the skin. The
 *                almond-shaped margins: upper at y = +4.2 in front (over the top of the iris),
 *                lower at -5.6, canthi at x = +-11.5, y = -0.5 (+-0.46 tilt): an opening 9.8
 *                high and 23 wide; along each margin a band runs in to radius 12.2 (the lid's
 *                thickness, closing the gap to the eyeball). Larger than the ~12.8 of a thin
 *                lid on purpose: the cornea reaches 14.5 from the centre, and a lid sliding over
 *                it in a blink must pass outside it. The lower lid lies in front of the upper one,
 *                so a closed eye shows the lower margin. The lash line is painted along the
 *                margins. Lids and skin: roughness 0.55.
 *   upper_lashes, eyelashes: children of the lids (moving with them), curved cards rooted just
 *   lower_lashes outside each margin over |x| <= 9.5, in two pieces leaning from the lid's
 *                outward normal towards "away" (upper: 20 then 55 degrees, 8.5 long at the middle;
 *                lower: 35 then 65 degrees, 5 long), shortening to 0.4 of that at the ends;
 *                an RGBA texture of 130 (upper) or 70 (lower) strands, alphaMode MASK (cutoff
 *                0.5), two-sided.
 *   skin         a sheet of radius 35 around an almond-shaped opening (23.8 wide, 13.5 high)
 *                facing +Z: at the opening it hugs the lids (0.25 in front of the lower lid's
 *                surface, which is in front of the upper's, so no lid ever shows through and
 *                there is no gap to look into); within 7 of the opening it blends into a face at
 *                z = 10 (sinking 1 towards the eye).
 *   orbit        a dark bowl of radius 25 behind everything (z <= 0), a backstop for any ray that
 *                slips between skin and lids.
 *   eye_camera   camera on node "eye_camera" (no transform) under "eye_camera_mount" at
 *                (0, -10, 40), which turns it to look at the eye centre (tilted up by
 *                atan(10/40) = 14.04 degrees): yfov 45 degrees, aspectRatio 4/3, znear 1,
 *                zfar 1000.
 *   ir_led       a near-infrared point light at (5, -10, 40), beside the camera, white,
 *                2e-3 candela, radius 1.5 (extras "radius": an LED's emitting size, which a
 *                smooth cornea reflects as a small disc): a white Lambertian surface at the
 *                corneal apex (27.8 from the LED, facing it) gets radiance 0.82, the sclera, lids
 *                and skin 30-35 away about 0.5-0.7 (times the cosine). At rest gaze the glint
 *                (the LED reflected by the corneal sphere towards the camera) lies at
 *                (0.556, -2.238, 14.151), 17.2 degrees from the corneal axis: in a 640 x 480
 *                image at (331.9, 212.9) px from the top-left corner (the pupil's centre at
 *                (320.0, 185.6)); the glint moves about half as far as the pupil with gaze.
 *   animation    "gaze", 30 s, rotation channels of eyeball, upper_lid and lower_lid, from a gaze
 *                plan made in code: the first ten fixations are the original hand-written 3 s
 *                sequence, the rest is drawn from a fixed seed (splitmix64, EYE_PLAN_SEED). 84
 *                fixations of 180-450 ms and 83 saccades of 2.0-19.1 degrees (mean 7.6; random
 *                directions, small ones more likely; gaze within +-14.6 deg yaw, +-11.1 pitch)
 *                lasting 2.2 ms/deg + 21 ms with a smooth, skewed velocity profile (peak 1.63 A/D:
 *                130-490 deg/s); 8 blinks (at 0.665 s, then every 3.4-4.8 s), each 40 ms into a
 *                fixation of 380-450 ms (upper lid down 38 degrees in 100 ms, closed 30 ms, up in
 *                170 ms; the lower lid rises 2.5 degrees and the eye dips 2 degrees). The upper lid
 *                follows vertical gaze at 0.7 of its angle, the lower lid at 0.3. Saccades take
 *                3.12 s and blinks 2.40 s: the scene moves 18.4% of the time. LINEAR keys, every
 *                2 ms during saccades and blinks.
 *                "eye" (2,892 keys): no fixational drift, so during a fixation the eyeball and
 *                lids are still: its keys (at both ends, and around a blink) hold bit-identical
 *                rotations.
 *                "eye-drift" (3,867 keys): the same plan plus slow drift throughout (two
 *                sinusoids per axis, < 0.15 degrees, < 0.6 deg/s), keys every <= 25 ms in
 *                fixations; its first 3 s are the original 3 s animation.
 * The parts (textures, globe, lids, lashes, skin, socket, the blink's shape) are in demo_eye_parts.c,
 * which the blink scene shares; this file makes the gaze plan and puts the scene together. */
#include <math.h>
#include <stdlib.h>

#include "core/vec.h"
#include "scene/demo_eye_parts.h"

#define MM 0.001
#define PI 3.14159265358979323846
#define DEG (PI / 180.0)
#define SKIN_OUTER 35.0 /* the skin's outer radius, mm */
#define LED_POS_X 5.0   /* the LED, mm */
#define LED_POS_Y (-10.0)
#define LED_POS_Z 40.0
#define LED_RADIUS 1.5

/* animation */
#define ANIM_LENGTH 30.0
#define EYE_PLAN_SEED 0x6579652d67617a65ull /* the gaze plan's seed */
#define FIX_MIN 0.180                       /* fixation durations */
#define FIX_MAX 0.450
#define SACC_MIN_DEG 2.0 /* saccade amplitudes */
#define SACC_MAX_DEG 20.0
#define GAZE_YAW_MAX 15.0 /* gaze limits */
#define GAZE_PITCH_MAX 12.0
#define BLINK_FIX 2       /* the first blink happens during this fixation ... */
#define BLINK_DELAY 0.040 /* ... this long after it starts (as all blinks) */
#define BLINK_LEN EVR_EYE_BLINK_LEN
#define BLINK_AFTER_MIN 0.040 /* a blink's fixation goes on at least this long after it */
#define BLINK_GAP_MIN 2.5     /* from one blink to the next fixation that may hold one */
#define BLINK_GAP_MAX 4.45
#define DENSE_KEY_STEP 0.002 /* key spacing in saccades and blinks ... */
#define FIX_KEY_STEP 0.025   /* ... and in fixations with drift */
#define BLINK_UPPER_DEG EVR_EYE_BLINK_UPPER_DEG
#define BLINK_LOWER_DEG EVR_EYE_BLINK_LOWER_DEG
#define BLINK_EYE_DIP_DEG 2.0
#define LID_FOLLOW_UP 0.7
#define LID_FOLLOW_LO 0.3
#define MAX_FIX 256   /* 84 are used */
#define MAX_KEYS 8192 /* 2,892 are used without drift, 3,867 with */

/* ---- animation ---- */

/* The gaze plan: the first ten fixations are written by hand (the original 3 s sequence, with its
 * blink in the third fixation); the rest, up to ANIM_LENGTH, is drawn from a fixed seed. */
typedef struct {
    double yaw, pitch; /* degrees; yaw towards +X, pitch up */
    double duration;   /* seconds; < 0: drawn like the generated ones */
} fixation_spec;

static const fixation_spec plan_start[] = {
    {0.0, 0.0, 0.280},   {10.0, 3.0, 0.240}, {-8.0, 1.0, 0.400}, {-6.0, 9.0, 0.200},
    {-3.0, -9.0, 0.380}, {2.0, -6.0, 0.180}, {4.0, -4.0, 0.250}, {12.0, 2.0, 0.220},
    {0.0, 0.0, 0.250},   {-2.0, 4.0, -1.0},
};
#define NUM_START ((int)(sizeof plan_start / sizeof plan_start[0]))

typedef struct {
    double yaw, pitch; /* degrees */
    double start, end; /* seconds; saccade k runs from fix[k].end to fix[k + 1].start */
    double blink;      /* start of the blink in this fixation, < 0 for none */
} fixation;

typedef struct {
    fixation fix[MAX_FIX];
    int num_fix, num_blinks;
    int drift; /* 1: slow fixational drift added everywhere ("eye-drift") */
} gaze_plan;

/* splitmix64: a small deterministic generator, the same on every platform. */
static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double plan_uniform(uint64_t *s, double a, double b)
{
    return a + (b - a) * ((double)(splitmix64(s) >> 11) * (1.0 / 9007199254740992.0));
}

static double saccade_duration(double yaw0, double pitch0, double yaw1, double pitch1)
{
    return (2.2 * hypot(yaw1 - yaw0, pitch1 - pitch0) + 21.0) * 1e-3; /* the main sequence */
}

/* The next saccade's target: amplitude SACC_MIN_DEG..SACC_MAX_DEG (small ones more likely), a
 * uniformly random direction, redrawn until the target lies within the gaze limits. */
static void next_target(uint64_t *s, double yaw, double pitch, double *ty, double *tp)
{
    int tries;
    for (tries = 0; tries < 1000; tries++) {
        double a =
            SACC_MIN_DEG + (SACC_MAX_DEG - SACC_MIN_DEG) * pow(plan_uniform(s, 0.0, 1.0), 1.5);
        double dir = plan_uniform(s, -PI, PI);
        *ty = yaw + a * cos(dir);
        *tp = pitch + a * sin(dir);
        if (fabs(*ty) <= GAZE_YAW_MAX && fabs(*tp) <= GAZE_PITCH_MAX) return;
    }
    *ty = 0.0; /* not reached in practice: back to the centre */
    *tp = 0.0;
}

/* Times are rounded to float, as the keys store them. */
static double key_time(double t) { return (double)(float)t; }

/* Builds the plan; 0 when it does not fit in MAX_FIX fixations. Every fixation lasts
 * FIX_MIN..FIX_MAX; a blink comes BLINK_GAP_MIN..BLINK_GAP_MAX after the previous one (measured
 * from the first fixation that starts late enough), BLINK_DELAY into a fixation that is made long
 * enough to hold it. A variant (seed, evr_gltf_variant) draws every fixation after the first,
 * straight ahead, from its own seed. */
static int make_plan(gaze_plan *p, int drift, uint64_t seed)
{
    uint64_t s = EYE_PLAN_SEED;
    const int num_start = seed ? 1 : NUM_START;
    if (seed) {
        uint64_t v = seed;
        s ^= splitmix64(&v);
    }
    double t = 0.0, next_blink = 0.0, ny, np;
    int k;
    p->num_fix = 0;
    p->num_blinks = 0;
    p->drift = drift;
    ny = plan_start[0].yaw;
    np = plan_start[0].pitch;
    for (k = 0;; k++) {
        fixation *f = &p->fix[k];
        double rest = ANIM_LENGTH - t, dur, sacc, need = BLINK_DELAY + BLINK_LEN + BLINK_AFTER_MIN;
        int blink;
        if (k >= MAX_FIX) return 0;
        f->yaw = ny;
        f->pitch = np;
        f->start = t;
        f->blink = -1.0;
        p->num_fix = k + 1;
        blink = k == BLINK_FIX || (k > BLINK_FIX && t + BLINK_DELAY >= next_blink);
        if (k < num_start && plan_start[k].duration >= 0.0) dur = plan_start[k].duration;
        else if (blink) dur = need + plan_uniform(&s, 0.0, FIX_MAX - need);
        else dur = plan_uniform(&s, FIX_MIN, FIX_MAX);
        if (k >= num_start && rest <= FIX_MAX) { /* the last fixation runs to the end */
            f->end = ANIM_LENGTH;
            if (blink && rest >= need) {
                f->blink = key_time(t + BLINK_DELAY);
                p->num_blinks++;
            }
            return 1;
        }
        if (k + 1 < num_start) {
            ny = plan_start[k + 1].yaw;
            np = plan_start[k + 1].pitch;
        } else {
            next_target(&s, f->yaw, f->pitch, &ny, &np);
        }
        sacc = saccade_duration(f->yaw, f->pitch, ny, np);
        if (dur > rest - sacc - FIX_MIN)
            dur = rest - sacc - FIX_MIN; /* leave room for a last one */
        if (blink && dur >= need - 1e-9) {
            f->blink = key_time(t + BLINK_DELAY);
            p->num_blinks++;
            next_blink = f->blink + plan_uniform(&s, BLINK_GAP_MIN, BLINK_GAP_MAX);
        }
        f->end = key_time(t + dur);
        t = key_time(f->end + sacc);
    }
}

/* Lid closure in fixation k at time t (0 outside its blink). */
static double blink_at(const gaze_plan *p, int k, double t)
{
    if (p->fix[k].blink < 0.0) return 0.0;
    return evr_eye_blink_closure(t - p->fix[k].blink);
}

/* Gaze (degrees) and lid closure at time t. Inside a fixation without drift it is exactly the
 * fixation's gaze (the blink's dip aside), so all keys of a fixation hold the same values. */
static void gaze_at(const gaze_plan *p, double t, double *yaw, double *pitch, double *closure)
{
    int k;
    double b = 0.0;
    *yaw = p->fix[p->num_fix - 1].yaw;
    *pitch = p->fix[p->num_fix - 1].pitch;
    for (k = 0; k < p->num_fix; k++) {
        const fixation *f = &p->fix[k];
        if (t <= f->end) {
            *yaw = f->yaw;
            *pitch = f->pitch;
            b = blink_at(p, k, t);
            break;
        }
        if (k + 1 < p->num_fix && t < p->fix[k + 1].start) {
            const fixation *g = &p->fix[k + 1];
            double s = evr_eye_saccade_profile((t - f->end) / (g->start - f->end));
            *yaw = f->yaw + (g->yaw - f->yaw) * s;
            *pitch = f->pitch + (g->pitch - f->pitch) * s;
            break;
        }
    }
    if (p->drift) { /* slow drift, continuous across the whole sequence (peak speed ~0.55 deg/s) */
        *yaw += 0.06 * sin(2.0 * PI * 0.83 * t + 0.3) + 0.02 * sin(2.0 * PI * 2.1 * t + 1.1);
        *pitch += 0.05 * sin(2.0 * PI * 0.61 * t + 2.0) + 0.02 * sin(2.0 * PI * 2.9 * t + 0.5);
    }
    *pitch -= BLINK_EYE_DIP_DEG * b; /* the eye dips during a blink */
    *closure = b;
}

/* Adds n + 1 uniformly spaced times over [a, b] (both ends exactly) with spacing at most step;
 * returns -1 when MAX_KEYS would be exceeded. */
static int add_times(double *times, int count, double a, double b, double step)
{
    int n = (int)ceil((b - a) / step - 1e-9), i;
    if (count < 0) return -1;
    if (n < 1) n = 1;
    if (count + n + 1 > MAX_KEYS) return -1;
    for (i = 0; i <= n; i++) times[count++] = i == n ? b : a + (b - a) * i / n;
    return count;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : (x > y ? 1 : 0);
}

static void quat_axis(double ax, double ay, double az, double angle_deg, evr_quat *q)
{
    double h = 0.5 * angle_deg * DEG, s = sin(h);
    *q = evr_quat_make((float)cos(h), (float)(ax * s), (float)(ay * s), (float)(az * s));
}

/* Keys: at both ends of every fixation and saccade, every 2 ms in saccades and blinks, and with
 * drift every <= 25 ms in fixations. Without drift the keys of a fixation are bit-identical. */
static void build_animation(evr_gltf *g, int eyeball, int upper, int lower, int drift,
                            uint64_t seed)
{
    gaze_plan *plan = malloc(sizeof *plan);
    double *t = malloc(sizeof(double) * MAX_KEYS);
    float *times = malloc(sizeof(float) * MAX_KEYS), *qe = malloc(sizeof(float) * 4 * MAX_KEYS);
    float *qu = malloc(sizeof(float) * 4 * MAX_KEYS), *ql = malloc(sizeof(float) * 4 * MAX_KEYS);
    int n = 0, m = 0, k, anim;
    if (!plan || !t || !times || !qe || !qu || !ql) {
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while building the eye animation");
        goto done;
    }
    if (!make_plan(plan, drift, seed)) {
        evr_gltf_fail(g, EVR_ERR_ARG,
                      "eye animation: the gaze plan needs more than MAX_FIX fixations");
        goto done;
    }
    for (k = 0; k < plan->num_fix; k++) {
        const fixation *f = &plan->fix[k];
        n = add_times(t, n, f->start, f->end, drift ? FIX_KEY_STEP : 2.0 * ANIM_LENGTH);
        if (f->blink >= 0.0) n = add_times(t, n, f->blink, f->blink + BLINK_LEN, DENSE_KEY_STEP);
        if (k + 1 < plan->num_fix)
            n = add_times(t, n, f->end, plan->fix[k + 1].start, DENSE_KEY_STEP);
    }
    if (n < 0) {
        evr_gltf_fail(g, EVR_ERR_ARG, "eye animation: more than MAX_KEYS keys");
        goto done;
    }
    qsort(t, (size_t)n, sizeof(double), cmp_double);
    for (k = 0; k < n; k++) { /* merge times closer than 0.4 ms (exact repeats at the ends) */
        if (m > 0 && t[k] - t[m - 1] < 4e-4) continue;
        t[m++] = t[k];
    }
    for (k = 0; k < m; k++) {
        double yaw, pitch, b;
        evr_quat qy, qx, q;
        gaze_at(plan, t[k], &yaw, &pitch, &b);
        times[k] = (float)t[k];
        quat_axis(0, 1, 0, yaw, &qy);
        quat_axis(1, 0, 0, -pitch, &qx); /* a positive turn about +X moves the front down */
        q = evr_quat_normalize(evr_quat_mul(qy, qx));
        qe[4 * k] = q.x;
        qe[4 * k + 1] = q.y;
        qe[4 * k + 2] = q.z;
        qe[4 * k + 3] = q.w;
        quat_axis(1, 0, 0, -LID_FOLLOW_UP * pitch + BLINK_UPPER_DEG * b, &q);
        qu[4 * k] = q.x;
        qu[4 * k + 1] = q.y;
        qu[4 * k + 2] = q.z;
        qu[4 * k + 3] = q.w;
        quat_axis(1, 0, 0, -LID_FOLLOW_LO * pitch - BLINK_LOWER_DEG * b, &q);
        ql[4 * k] = q.x;
        ql[4 * k + 1] = q.y;
        ql[4 * k + 2] = q.z;
        ql[4 * k + 3] = q.w;
    }
    /* rest pose: the pose at t = 0 */
    evr_gltf_node_rotation(g, eyeball, qe[0], qe[1], qe[2], qe[3]);
    evr_gltf_node_rotation(g, upper, qu[0], qu[1], qu[2], qu[3]);
    evr_gltf_node_rotation(g, lower, ql[0], ql[1], ql[2], ql[3]);
    anim = evr_gltf_animation(g, "gaze");
    evr_gltf_channel(g, anim, eyeball, EVR_GLTF_ROTATION, times, qe, m, EVR_GLTF_LINEAR);
    evr_gltf_channel(g, anim, upper, EVR_GLTF_ROTATION, times, qu, m, EVR_GLTF_LINEAR);
    evr_gltf_channel(g, anim, lower, EVR_GLTF_ROTATION, times, ql, m, EVR_GLTF_LINEAR);
done:
    free(plan);
    free(t);
    free(times);
    free(qe);
    free(qu);
    free(ql);
}

/* ---- the scene ---- */

static int build_lid(evr_gltf *g, int upper, int material)
{
    evr_demo_mesh m = {0};
    evr_eye_lid(&m, upper);
    return evr_demo_mesh_finish(g, &m, upper ? "upper_lid" : "lower_lid", material);
}

/* A lid's lashes on a child node of the lid, so that they move with it. */
static void build_lashes(evr_gltf *g, int lid, int upper, int material)
{
    evr_demo_mesh m = {0};
    const char *name = upper ? "upper_lashes" : "lower_lashes";
    evr_eye_lashes(&m, upper);
    evr_gltf_node_mesh(g, evr_gltf_node(g, name, lid), evr_demo_mesh_finish(g, &m, name, material));
}

static void build_eye(evr_gltf *g, int drift)
{
    static const double cam_pos[3] = {0.0, -10.0 * MM, 40.0 * MM}, target[3] = {0.0, 0.0, 0.0},
                        up[3] = {0.0, 1.0, 0.0};
    float q[4];
    evr_gltf_material mat;
    evr_gltf_light_desc led;
    int m_lid_up, m_lid_lo, m_lash_up, m_lash_lo, m_skin, m_orbit, eyeball, node, upper, lower,
        mount, cam;

    m_lid_up = evr_eye_material(
        g, "upper_eyelid", evr_eye_paint_eyelid(g, "upper_eyelid_texture", 4242u, 0, 22.0, 50.0),
        0.55f);
    m_lid_lo = evr_eye_material(
        g, "lower_eyelid", evr_eye_paint_eyelid(g, "lower_eyelid_texture", 4343u, 0, 10.0, 24.0),
        0.55f);
    m_lash_up = evr_eye_lash_material(g, 1);
    m_lash_lo = evr_eye_lash_material(g, 0);
    m_skin = evr_eye_material(g, "skin", evr_eye_paint_skin(g, SKIN_OUTER, 512), 0.55f);
    evr_gltf_material_init(&mat, "orbit");
    mat.base_color[0] = 0.25f;
    mat.base_color[1] = 0.09f;
    mat.base_color[2] = 0.08f;
    m_orbit = evr_gltf_add_material(g, &mat);
    if (evr_gltf_status(g, NULL) != EVR_OK) return;

    eyeball = evr_gltf_node(g, "eyeball", -1);
    evr_eye_globe(g, eyeball);

    upper = evr_gltf_node(g, "upper_lid", -1);
    evr_gltf_node_mesh(g, upper, build_lid(g, 1, m_lid_up));
    build_lashes(g, upper, 1, m_lash_up);
    lower = evr_gltf_node(g, "lower_lid", -1);
    evr_gltf_node_mesh(g, lower, build_lid(g, 0, m_lid_lo));
    build_lashes(g, lower, 0, m_lash_lo);

    node = evr_gltf_node(g, "skin", -1);
    evr_gltf_node_mesh(g, node, evr_eye_skin(g, m_skin, SKIN_OUTER));
    node = evr_gltf_node(g, "orbit", -1);
    evr_gltf_node_mesh(g, node, evr_eye_orbit(g, m_orbit));

    /* The camera sits on an untransformed child of its mount, so that readers which also copy a
     * camera node's translation into the camera itself (Assimp does) place it right. */
    mount = evr_gltf_node(g, "eye_camera_mount", -1);
    evr_gltf_node_translation(g, mount, (float)cam_pos[0], (float)cam_pos[1], (float)cam_pos[2]);
    evr_demo_look_at(cam_pos, target, up, q);
    evr_gltf_node_rotation(g, mount, q[0], q[1], q[2], q[3]);
    cam =
        evr_gltf_camera(g, "eye_camera", (float)(45.0 * DEG), 4.0f / 3.0f, 1.0f * (float)MM, 1.0f);
    node = evr_gltf_node(g, "eye_camera", mount);
    evr_gltf_node_camera(g, node, cam);

    /* the eye tracker's near-infrared LED: a small sphere beside the camera */
    evr_gltf_light_desc_init(&led, "ir_led", EVR_GLTF_POINT);
    led.intensity = 2e-3f;
    led.radius = (float)(LED_RADIUS * MM);
    node = evr_gltf_node(g, "ir_led", -1);
    evr_gltf_node_translation(g, node, (float)(LED_POS_X * MM), (float)(LED_POS_Y * MM),
                              (float)(LED_POS_Z * MM));
    evr_gltf_node_light(g, node, evr_gltf_add_light(g, &led));

    build_animation(g, eyeball, upper, lower, drift, evr_gltf_variant(g));
}

void evr_demo_build_eye(evr_gltf *g) { build_eye(g, 0); }

void evr_demo_build_eye_drift(evr_gltf *g) { build_eye(g, 1); }
