/* The "eye" and "eye-drift" scenes: what a head-mounted eye tracker's camera sees. Units metres, +Y up, the
 * subject looks along +Z; glTF conventions. Sizes below are in millimetres. 31,856 triangles.
 *
 *   eyeball      node "eyeball" at the origin, animated rotation (gaze); children:
 *     sclera     UV sphere of radius 12 (poles on the Z axis, the front pole at +Z), textured
 *                white-pink with faint conjunctival vessels.
 *     cornea     the corneal bulge: a spherical cap of radius 7.8 centred at z = 6.7 (apex at
 *                z = 14.5, 2.5 in front of the eyeball); it meets the eyeball at a radius of 7.3
 *                and continues a little inside it so that no crack shows. We have no refraction,
 *                so the iris (diameter 11.5, radial fibres, collarette, crypts, dark limbal ring)
 *                and the black pupil (diameter 3.6) are painted on it with a planar projection
 *                along Z; glossy (roughness 0.1) to give the corneal glint of the LED.
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
 *                so a closed eye shows the lower margin. Lashes are painted along the margins.
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
 *                2e-3 candela: a white Lambertian surface at the corneal apex (27.8 from the
 *                LED, facing it) gets radiance 0.82, the sclera, lids and skin 30-35 away about
 *                0.5-0.7 (times the cosine).
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
 *                fixations; its first 3 s are the original 3 s animation. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/vec.h"
#include "scene/demo_scenes.h"

#define MM 0.001
#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

/* geometry, millimetres */
#define EYE_R 12.0
#define CORNEA_R 7.8
#define CORNEA_C 6.7 /* centre of the corneal sphere on +Z: apex at 14.5 */
#define CORNEA_PSI_MAX (72.0 * DEG)
#define IRIS_TEX_HALF 7.5 /* the iris texture covers [-7.5, 7.5]^2 in x, y */
#define IRIS_R 5.75
#define PUPIL_R 1.8
#define LID_UP_R 14.8 /* lid radii at the middle ... */
#define LID_LO_R 15.1
#define LID_UP_R_CORNER 12.4 /* ... and towards the corners, where the lids hug the eyeball */
#define LID_LO_R_CORNER 12.7
#define LID_TAPER_A 7.0 /* |x| where the taper starts and ends */
#define LID_TAPER_B 11.2
#define LID_IN_R 12.2   /* inner edge of the margin band */
#define LID_RHO_MIN 4.0 /* past the corners the lids go on as tubes of this radius */
#define LID_X_MAX 16.0
#define LID_FAR (120.0 * DEG)
#define MARGIN_UP 4.2
#define MARGIN_LO (-5.6)
#define CANTHUS_X 11.5
#define CANTHUS_Y (-0.5)
#define CANTHUS_TILT 0.04 /* the lateral (+X) canthus sits a little higher */
#define SKIN_Z 10.0
#define SKIN_OVER_LID 0.25 /* the skin dome's radius over the lower lid's */
#define SKIN_SINK 1.0      /* the face sinks this much towards the eye */
#define SKIN_BLEND 5.0
#define SKIN_RIM_BLEND 7.0
#define SKIN_OUTER 35.0
#define ORBIT_R 25.0 /* the socket: a bowl behind everything, a backstop for rays */
#define HOLE_HALF_W 11.9
#define HOLE_UP 7.0
#define HOLE_LO 6.5

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
#define BLINK_CLOSE 0.100
#define BLINK_HOLD 0.030
#define BLINK_OPEN 0.170
#define BLINK_LEN (BLINK_CLOSE + BLINK_HOLD + BLINK_OPEN)
#define BLINK_AFTER_MIN 0.040 /* a blink's fixation goes on at least this long after it */
#define BLINK_GAP_MIN 2.5     /* from one blink to the next fixation that may hold one */
#define BLINK_GAP_MAX 4.45
#define DENSE_KEY_STEP 0.002 /* key spacing in saccades and blinks ... */
#define FIX_KEY_STEP 0.025   /* ... and in fixations with drift */
#define BLINK_UPPER_DEG 38.0
#define BLINK_LOWER_DEG 2.5
#define BLINK_EYE_DIP_DEG 2.0
#define LID_FOLLOW_UP 0.7
#define LID_FOLLOW_LO 0.3
#define MAX_FIX 256   /* 84 are used */
#define MAX_KEYS 8192 /* 2,892 are used without drift, 3,867 with */

/* ---- deterministic noise and painting ---- */

static uint32_t hash_u32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

typedef struct {
    uint32_t s;
} rng;

static double rng_uniform(rng *r)
{
    r->s += 0x9e3779b9u;
    return hash_u32(r->s) / 4294967296.0;
}

static double rng_range(rng *r, double a, double b) { return a + (b - a) * rng_uniform(r); }

static double lattice(int ix, int iy, uint32_t seed)
{
    return hash_u32((uint32_t)ix * 0x8da6b343u ^
                    hash_u32((uint32_t)iy * 0xd8163841u ^ seed * 0xcb1ab31fu)) /
           4294967295.0;
}

static double smooth01(double t) { return t * t * (3.0 - 2.0 * t); }

static double clampd(double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); }

static double smoothstep(double a, double b, double x)
{
    return smooth01(clampd((x - a) / (b - a), 0.0, 1.0));
}

/* Value noise in [0,1]; period > 0 wraps x with that integer period. */
static double vnoise(double x, double y, uint32_t seed, int period)
{
    double fx = floor(x), fy = floor(y);
    int ix = (int)fx, iy = (int)fy, ix1;
    double tx = smooth01(x - fx), ty = smooth01(y - fy);
    double a, b, c, d;
    if (period > 0) {
        ix %= period;
        if (ix < 0) ix += period;
        ix1 = (ix + 1) % period;
    } else {
        ix1 = ix + 1;
    }
    a = lattice(ix, iy, seed);
    b = lattice(ix1, iy, seed);
    c = lattice(ix, iy + 1, seed);
    d = lattice(ix1, iy + 1, seed);
    return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}

/* Fractal noise in [0,1] (octaves of vnoise, each twice the frequency and half the weight). */
static double fbm(double x, double y, uint32_t seed, int octaves, int period)
{
    double sum = 0.0, amp = 1.0, norm = 0.0;
    int k;
    for (k = 0; k < octaves; k++) {
        sum += amp * vnoise(x, y, seed + (uint32_t)k * 101u, period);
        norm += amp;
        amp *= 0.5;
        x *= 2.0;
        y *= 2.0;
        if (period > 0) period *= 2;
    }
    return sum / norm;
}

/* An 8-bit sRGB image being painted, with a coverage mask for strokes. */
typedef struct {
    int w, h, wrap_x;
    double *rgb; /* 0..255, 3 per pixel */
    float *mask;
} image;

static int image_init(image *im, int w, int h, int wrap_x)
{
    im->w = w;
    im->h = h;
    im->wrap_x = wrap_x;
    im->rgb = malloc(sizeof(double) * 3 * (size_t)w * (size_t)h);
    im->mask = calloc((size_t)w * (size_t)h, sizeof(float));
    return im->rgb && im->mask;
}

static void image_free(image *im)
{
    free(im->rgb);
    free(im->mask);
}

static void image_set(image *im, int x, int y, const double c[3])
{
    double *p = im->rgb + 3 * ((size_t)y * (size_t)im->w + (size_t)x);
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
}

/* Adds a stroke from (xa,ya) to (xb,yb), radius r0 -> r1, opacity a0 -> a1, to the coverage mask
 * (the maximum is kept, so that overlapping pieces of one stroke do not build up); image_apply
 * then paints the mask in one colour. */
static void image_stroke(image *im, double xa, double ya, double xb, double yb, double r0,
                         double r1, double a0, double a1)
{
    double len = hypot(xb - xa, yb - ya), rmax = r0 > r1 ? r0 : r1;
    int xmin = (int)floor((xa < xb ? xa : xb) - rmax - 2),
        xmax = (int)ceil((xa > xb ? xa : xb) + rmax + 2);
    int ymin = (int)floor((ya < yb ? ya : yb) - rmax - 2),
        ymax = (int)ceil((ya > yb ? ya : yb) + rmax + 2);
    int x, y;
    if (ymin < 0) ymin = 0;
    if (ymax > im->h - 1) ymax = im->h - 1;
    if (!im->wrap_x) {
        if (xmin < 0) xmin = 0;
        if (xmax > im->w - 1) xmax = im->w - 1;
    }
    for (y = ymin; y <= ymax; y++) {
        for (x = xmin; x <= xmax; x++) {
            double px = x + 0.5, py = y + 0.5, t = 0.0, d, r, a, cov;
            int wx = im->wrap_x ? ((x % im->w) + im->w) % im->w : x;
            float *m;
            if (len > 0.0)
                t = clampd(((px - xa) * (xb - xa) + (py - ya) * (yb - ya)) / (len * len), 0.0, 1.0);
            d = hypot(px - (xa + t * (xb - xa)), py - (ya + t * (yb - ya)));
            r = r0 + (r1 - r0) * t;
            a = a0 + (a1 - a0) * t;
            cov = clampd(r + 0.5 - d, 0.0, 1.0) * a;
            m = &im->mask[(size_t)y * (size_t)im->w + (size_t)wx];
            if (cov > *m) *m = (float)cov;
        }
    }
}

/* Composites the mask in colour c over the image and clears it. */
static void image_apply(image *im, const double c[3])
{
    size_t i, n = (size_t)im->w * (size_t)im->h;
    int k;
    for (i = 0; i < n; i++) {
        double a = im->mask[i];
        if (a <= 0.0) continue;
        for (k = 0; k < 3; k++) im->rgb[3 * i + k] += (c[k] - im->rgb[3 * i + k]) * a;
        im->mask[i] = 0.0f;
    }
}

static int image_texture(evr_gltf *g, image *im, const char *name)
{
    size_t i, n = (size_t)im->w * (size_t)im->h * 3;
    uint8_t *px = malloc(n);
    int tex;
    if (!px) {
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (i = 0; i < n; i++) px[i] = (uint8_t)clampd(floor(im->rgb[i] + 0.5), 0.0, 255.0);
    tex = evr_gltf_texture_png(g, name, px, im->w, im->h, 3);
    free(px);
    return tex;
}

static void mix3(double out[3], const double a[3], const double b[3], double t)
{
    int k;
    for (k = 0; k < 3; k++) out[k] = a[k] + (b[k] - a[k]) * t;
}

static const double sclera_srgb[3] = {238.0, 226.0, 219.0};
static const double skin_srgb[3] = {222.0, 168.0, 142.0};

/* ---- textures ---- */

/* Equirectangular around the Z axis: u = azimuth / 2 pi, v = polar angle from +Z / pi. */
static int paint_sclera(evr_gltf *g)
{
    image im;
    rng r = {12345u};
    int x, y, k, tex;
    const double vein[3] = {172.0, 62.0, 60.0};
    if (!image_init(&im, 512, 256, 1)) {
        image_free(&im);
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (y = 0; y < im.h; y++) {
        double th = (y + 0.5) / im.h * PI;
        for (x = 0; x < im.w; x++) {
            double u = (x + 0.5) / im.w, c[3], n = fbm(u * 16.0, th * 5.0, 7u, 4, 16) - 0.5;
            double back =
                smoothstep(70.0 * DEG, 130.0 * DEG, th); /* a little yellower at the back */
            c[0] = sclera_srgb[0] * (1.0 + 0.05 * n);
            c[1] = sclera_srgb[1] * (1.0 + 0.05 * n - 0.04 * back);
            c[2] = sclera_srgb[2] * (1.0 + 0.05 * n - 0.10 * back);
            image_set(&im, x, y, c);
        }
    }
    /* Conjunctival vessels: wandering from the periphery towards the limbus, thinning and fading,
     * with a few side branches. */
    for (k = 0; k < 44; k++) {
        double px = rng_range(&r, 0.0, im.w), py = rng_range(&r, 72.0, 100.0) / 180.0 * im.h;
        double stop = rng_range(&r, 44.0, 62.0) / 180.0 * im.h,
               dir = -PI / 2 + rng_range(&r, -0.5, 0.5);
        double w = rng_range(&r, 0.7, 1.3), a = rng_range(&r, 0.35, 0.6), start = py;
        int step = 0;
        while (py > stop && step < 400) {
            double nx, ny, f = (start - py) / (start - stop), rr = w * (1.0 - 0.6 * f),
                           aa = a * (1.0 - 0.7 * f);
            dir += rng_range(&r, -0.35, 0.35);
            dir = -PI / 2 + clampd(dir + PI / 2, -0.9, 0.9);
            nx = px + 2.0 * cos(dir);
            ny = py + 2.0 * sin(dir);
            image_stroke(&im, px, py, nx, ny, rr, rr, aa, aa);
            if (rng_uniform(&r) < 0.04) { /* a side branch */
                double bx = nx, by = ny,
                       bd = dir + (rng_uniform(&r) < 0.5 ? -1.0 : 1.0) * rng_range(&r, 0.6, 1.1);
                int j;
                for (j = 0; j < 14; j++) {
                    double cx = bx + 1.8 * cos(bd), cy = by + 1.8 * sin(bd);
                    bd += rng_range(&r, -0.3, 0.3);
                    image_stroke(&im, bx, by, cx, cy, rr * 0.6, rr * 0.5, aa * 0.7, aa * 0.5);
                    bx = cx;
                    by = cy;
                }
            }
            px = nx;
            py = ny;
            step++;
        }
        image_apply(&im, vein);
    }
    tex = image_texture(g, &im, "sclera_texture");
    image_free(&im);
    return tex;
}

/* The iris, pupil and limbus painted for the cornea: planar over [-7.5, 7.5] mm in x and y,
 * row 0 at y = +7.5. */
static int paint_iris(evr_gltf *g)
{
    image im;
    rng r = {777u};
    int x, y, k, tex;
    double crypt_a[36], crypt_t[36], crypt_s[36];
    const double pupil[3] = {10.0, 9.0, 9.0};
    const double inner[3] = {150.0, 108.0, 68.0}, outer[3] = {112.0, 90.0, 74.0};
    const double ruff[3] = {62.0, 42.0, 32.0};
    if (!image_init(&im, 512, 512, 0)) {
        image_free(&im);
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (k = 0; k < 36; k++) {
        crypt_a[k] = rng_range(&r, -PI, PI);
        crypt_t[k] = rng_range(&r, 0.36, 0.78);
        crypt_s[k] = rng_range(&r, 0.6, 1.4);
    }
    for (y = 0; y < im.h; y++) {
        for (x = 0; x < im.w; x++) {
            double mx = ((x + 0.5) / im.w * 2.0 - 1.0) * IRIS_TEX_HALF;
            double my = (1.0 - (y + 0.5) / im.h * 2.0) * IRIS_TEX_HALF;
            double rad = hypot(mx, my), ang = atan2(my, mx),
                   t = (rad - PUPIL_R) / (IRIS_R - PUPIL_R);
            double au = (ang + PI) / (2.0 * PI), c[3], f1, f2, coll, shade, sc[3];
            double tc = 0.34 + 0.035 * sin(11.0 * ang) + 0.02 * sin(23.0 * ang + 1.0);
            /* radial fibres: noise stretched along the radius, periodic in angle */
            f1 = fbm(au * 90.0 + 0.6 * sin(7.0 * t), t * 3.0, 31u, 3, 90);
            f2 = vnoise(au * 260.0, t * 9.0, 47u, 260);
            mix3(c, inner, outer, smoothstep(tc - 0.05, tc + 0.25, t));
            shade = 0.78 + 0.45 * (f1 - 0.5) * 1.6 + 0.18 * (f2 - 0.5);
            coll = exp(-pow((t - tc) / 0.035, 2.0)); /* the collarette ridge */
            shade += 0.22 * coll;
            shade -=
                0.10 * exp(-pow((t - 0.74) / 0.012, 2.0)) * (vnoise(au * 40.0, 0.0, 5u, 40) > 0.4);
            shade -=
                0.10 * exp(-pow((t - 0.86) / 0.012, 2.0)) * (vnoise(au * 40.0, 3.0, 6u, 40) > 0.45);
            for (k = 0; k < 36; k++) { /* crypts */
                double da = remainder(ang - crypt_a[k], 2.0 * PI) / (0.05 * crypt_s[k]);
                double dt = (t - crypt_t[k]) / (0.05 * crypt_s[k]);
                shade -= 0.35 * exp(-(da * da + dt * dt));
            }
            for (k = 0; k < 3; k++) c[k] *= clampd(shade, 0.15, 1.6);
            mix3(c, ruff, c, smoothstep(0.0, 0.06, t)); /* pupillary ruff */
            for (k = 0; k < 3; k++)
                c[k] *= 1.0 - 0.6 * smoothstep(IRIS_R - 0.9, IRIS_R - 0.05, rad); /* limbal ring */
            for (k = 0; k < 3; k++)
                sc[k] = sclera_srgb[k] * (1.0 + 0.04 * (fbm(mx * 1.5, my * 1.5, 9u, 3, 0) - 0.5));
            mix3(c, c, sc, smoothstep(IRIS_R - 0.05, IRIS_R + 0.35, rad));
            mix3(c, pupil, c, smoothstep(PUPIL_R - 0.04, PUPIL_R + 0.04, rad));
            image_set(&im, x, y, c);
        }
    }
    tex = image_texture(g, &im, "iris_texture");
    image_free(&im);
    return tex;
}

static void skin_colour(double c[3], double x, double y, uint32_t seed)
{
    double low = fbm(x * 0.15, y * 0.15, seed, 3, 0) - 0.5,
           pores = vnoise(x * 4.0, y * 4.0, seed + 9u, 0) - 0.5;
    int k;
    for (k = 0; k < 3; k++) c[k] = skin_srgb[k] * (1.0 + 0.10 * low + 0.06 * pores);
    c[0] *= 1.0 + 0.03 * low; /* blotches are redder */
}

/* Lids: u along the lid (0..1 over x in [-16, 16] mm), v from the margin band (v < 0.05)
 * away from the margin. */
static int paint_eyelid(evr_gltf *g, const char *name, uint32_t seed, int lashes, double len_lo,
                        double len_hi)
{
    image im;
    rng r = {seed};
    int x, y, k, tex;
    const double band[3] = {204.0, 124.0, 118.0}, lash[3] = {24.0, 19.0, 17.0},
                 crease[3] = {170.0, 118.0, 98.0};
    if (!image_init(&im, 512, 256, 0)) {
        image_free(&im);
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (y = 0; y < im.h; y++) {
        double v = (y + 0.5) / im.h;
        for (x = 0; x < im.w; x++) {
            double u = (x + 0.5) / im.w, c[3];
            skin_colour(c, u * 36.0, v * 21.0, 77u);
            if (v < 0.05) {
                double n = vnoise(u * 80.0, v * 40.0, 3u, 0) - 0.5;
                for (k = 0; k < 3; k++) c[k] = band[k] * (1.0 + 0.08 * n);
            }
            image_set(&im, x, y, c);
        }
    }
    /* the lid crease, a soft darker fold */
    for (k = 0; k < 64; k++) {
        double u0 = 0.12 + 0.76 * k / 64.0, u1 = 0.12 + 0.76 * (k + 1) / 64.0;
        double v0 = 0.42 + 0.10 * pow((u0 - 0.5) / 0.38, 2.0),
               v1 = 0.42 + 0.10 * pow((u1 - 0.5) / 0.38, 2.0);
        double a = 0.35 * sin(PI * (u0 - 0.12) / 0.76);
        image_stroke(&im, u0 * im.w, v0 * im.h, u1 * im.w, v1 * im.h, 2.0, 2.0, a, a);
    }
    image_apply(&im, crease);
    /* the lash line just above the margin band */
    image_stroke(&im, 0.16 * im.w, 0.062 * im.h, 0.84 * im.w, 0.062 * im.h, 2.2, 2.2, 0.85, 0.85);
    image_apply(&im, lash);
    /* lashes: curved dark strokes leaning towards the nearer corner */
    for (k = 0; k < lashes; k++) {
        double u = rng_range(&r, 0.21, 0.79), lean = (u - 0.5) * 1.9 + rng_range(&r, -0.25, 0.25);
        double len = rng_range(&r, len_lo, len_hi) * (1.0 - 0.9 * pow(fabs(u - 0.5) / 0.29, 4.0));
        double px = u * im.w, py = 0.06 * im.h, dir = PI / 2 - lean * 0.8;
        int j, n = 8;
        if (len < 6.0) len = 6.0;
        for (j = 0; j < n; j++) {
            double f0 = (double)j / n, f1 = (double)(j + 1) / n;
            double nx = px + len / n * cos(dir), ny = py + len / n * sin(dir);
            image_stroke(&im, px, py, nx, ny, 0.9 * (1.0 - 0.6 * f0), 0.9 * (1.0 - 0.6 * f1), 0.9,
                         0.75);
            dir -= lean * 0.12; /* curl outwards */
            px = nx;
            py = ny;
        }
        image_apply(&im, lash);
    }
    tex = image_texture(g, &im, name);
    image_free(&im);
    return tex;
}

/* The face around the eye, planar over [-35, 35] mm, row 0 at y = +35; a few fine wrinkles at
 * the lateral corner (crow's feet). */
static int paint_skin(evr_gltf *g)
{
    image im;
    rng r = {999u};
    int x, y, k, tex;
    const double wrinkle[3] = {176.0, 124.0, 104.0};
    if (!image_init(&im, 512, 512, 0)) {
        image_free(&im);
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (y = 0; y < im.h; y++) {
        for (x = 0; x < im.w; x++) {
            double mx = ((x + 0.5) / im.w * 2.0 - 1.0) * SKIN_OUTER,
                   my = (1.0 - (y + 0.5) / im.h * 2.0) * SKIN_OUTER;
            double c[3];
            skin_colour(c, mx, my, 55u);
            image_set(&im, x, y, c);
        }
    }
    for (k = 0; k < 7; k++) {
        double ang = rng_range(&r, -0.5, 0.5), r0 = rng_range(&r, 14.0, 16.0),
               r1 = r0 + rng_range(&r, 5.0, 9.0);
        int j;
        for (j = 0; j < 12; j++) {
            double ra = r0 + (r1 - r0) * j / 12.0, rb = r0 + (r1 - r0) * (j + 1) / 12.0;
            double aa = ang + 0.02 * sin(j * 1.3), ab = ang + 0.02 * sin((j + 1) * 1.3);
            double xa = (ra * cos(aa) / SKIN_OUTER + 1.0) / 2.0 * im.w,
                   ya = (1.0 - ra * sin(aa) / SKIN_OUTER) / 2.0 * im.h;
            double xb = (rb * cos(ab) / SKIN_OUTER + 1.0) / 2.0 * im.w,
                   yb = (1.0 - rb * sin(ab) / SKIN_OUTER) / 2.0 * im.h;
            double a = 0.45 * sin(PI * (j + 0.5) / 12.0);
            image_stroke(&im, xa, ya, xb, yb, 0.6, 0.6, a, a);
        }
        image_apply(&im, wrinkle);
    }
    tex = image_texture(g, &im, "skin_texture");
    image_free(&im);
    return tex;
}

/* ---- geometry (built in millimetres, stored in metres) ---- */

static uint32_t vert_mm(evr_demo_mesh *m, double x, double y, double z, const double n[3], double u,
                        double v)
{
    double p[3];
    p[0] = x * MM;
    p[1] = y * MM;
    p[2] = z * MM;
    return evr_demo_mesh_vertex(m, p, n, u, v);
}

static int build_sclera(evr_gltf *g, int material)
{
    evr_demo_mesh m = {0};
    const int cols = 64, rows = 48;
    int i, j;
    for (j = 0; j <= rows; j++) {
        double th = PI * j / rows;
        for (i = 0; i <= cols; i++) {
            double ph = 2.0 * PI * i / cols, n[3];
            n[0] = sin(th) * cos(ph);
            n[1] = sin(th) * sin(ph);
            n[2] = cos(th);
            vert_mm(&m, EYE_R * n[0], EYE_R * n[1], EYE_R * n[2], n, (double)i / cols,
                    (double)j / rows);
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    return evr_demo_mesh_finish(g, &m, "sclera", material);
}

static int build_cornea(evr_gltf *g, int material)
{
    evr_demo_mesh m = {0};
    const int cols = 96, rows = 32;
    int i, j;
    for (j = 0; j <= rows; j++) {
        double ps = CORNEA_PSI_MAX * j / rows;
        for (i = 0; i <= cols; i++) {
            double ph = 2.0 * PI * i / cols, n[3], x, y;
            n[0] = sin(ps) * cos(ph);
            n[1] = sin(ps) * sin(ph);
            n[2] = cos(ps);
            x = CORNEA_R * n[0];
            y = CORNEA_R * n[1];
            vert_mm(&m, x, y, CORNEA_C + CORNEA_R * n[2], n, 0.5 + x / (2.0 * IRIS_TEX_HALF),
                    0.5 - y / (2.0 * IRIS_TEX_HALF));
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    return evr_demo_mesh_finish(g, &m, "cornea", material);
}

/* Height of the lid margins (mm) at the front, as a function of x: an almond between the canthi
 * that keeps going past them, so that the lids overlap at the corners. */
static double almond(double t)
{
    double a = 1.0 - t * t;
    return a >= 0.0 ? pow(a, 0.6) : -pow(-a, 0.6);
}

static double margin_y(double x, int upper)
{
    double yc = CANTHUS_Y + CANTHUS_TILT * x, g = almond(x / CANTHUS_X);
    return upper ? yc + (MARGIN_UP - CANTHUS_Y) * g : yc - (CANTHUS_Y - MARGIN_LO) * g;
}

/* The lids are surfaces of revolution about the X axis (so that rotating them about it slides
 * them over themselves): at abscissa x, a circle of radius lid_rho(x) around the axis. Their
 * distance from the eye centre tapers from the middle towards the corners, where the lids hug
 * the eyeball; past the corners they go on as tubes, under the skin. */
static double smooth_max(double a, double b, double k)
{
    return 0.5 * (a + b + sqrt((a - b) * (a - b) + k * k));
}

static double lid_rho(double x, int upper)
{
    double mid = upper ? LID_UP_R : LID_LO_R, corner = upper ? LID_UP_R_CORNER : LID_LO_R_CORNER;
    double r = corner + (mid - corner) * (1.0 - smoothstep(LID_TAPER_A, LID_TAPER_B, fabs(x)));
    double rmin = upper ? LID_RHO_MIN : LID_RHO_MIN + (LID_LO_R_CORNER - LID_UP_R_CORNER);
    return sqrt(smooth_max(r * r - x * x, rmin * rmin, 4.0));
}

static double lid_radius(double x, int upper)
{
    double rho = lid_rho(x, upper);
    return sqrt(rho * rho + x * x);
}

/* Point of a lid at abscissa x and angle phi about the X axis (from +Z towards +Y). */
static void lid_point(double x, double phi, int upper, double p[3])
{
    double rho = lid_rho(x, upper);
    p[0] = x;
    p[1] = rho * sin(phi);
    p[2] = rho * cos(phi);
}

static double margin_phi(double x, int upper)
{
    return asin(clampd(margin_y(x, upper) / lid_rho(x, upper), -0.95, 0.95));
}

static int build_lid(evr_gltf *g, int upper, int material)
{
    evr_demo_mesh m = {0};
    const int cols = 96, rows = 28, band_rows = 2;
    const double far = upper ? LID_FAR : -LID_FAR, h = 1e-3;
    uint32_t band_first;
    int i, j, k;
    for (j = 0; j <= rows; j++) {
        double s = pow((double)j / rows, 1.3);
        for (i = 0; i <= cols; i++) {
            double x = -LID_X_MAX + 2.0 * LID_X_MAX * i / cols, phm = margin_phi(x, upper);
            double phi = phm + s * (far - phm), p[3], n[3];
            double drho = (lid_rho(x + h, upper) - lid_rho(x - h, upper)) / (2.0 * h);
            lid_point(x, phi, upper, p);
            n[0] = -drho; /* normal of a surface of revolution about X */
            n[1] = sin(phi);
            n[2] = cos(phi);
            vert_mm(&m, p[0], p[1], p[2], n, (double)i / cols, 0.05 + 0.95 * s);
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    /* the band along the margin, from the lid's surface in towards the eyeball */
    band_first = m.nv;
    for (j = 0; j <= band_rows; j++) {
        for (i = 0; i <= cols; i++) {
            double x = -LID_X_MAX + 2.0 * LID_X_MAX * i / cols, phm = margin_phi(x, upper);
            double pa[3], pb[3], p[3], t[3], d[3], n[3], l, f;
            double rad = lid_radius(x, upper), rr = rad - (rad - LID_IN_R) * j / band_rows;
            lid_point(x - h, margin_phi(x - h, upper), upper, pa);
            lid_point(x + h, margin_phi(x + h, upper), upper, pb);
            lid_point(x, phm, upper, p);
            l = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            for (k = 0; k < 3; k++) {
                t[k] = pb[k] - pa[k];
                d[k] = p[k] / l;
                p[k] = d[k] * rr;
            }
            n[0] = t[1] * d[2] - t[2] * d[1];
            n[1] = t[2] * d[0] - t[0] * d[2];
            n[2] = t[0] * d[1] - t[1] * d[0];
            /* facing the opening: down for the upper lid, up for the lower */
            f = n[1] * cos(phm) - n[2] * sin(phm);
            if (f * (upper ? -1.0 : 1.0) < 0.0)
                for (k = 0; k < 3; k++) n[k] = -n[k];
            vert_mm(&m, p[0], p[1], p[2], n, (double)i / cols,
                    0.05 * (1.0 - (double)j / band_rows));
        }
    }
    evr_demo_mesh_grid(&m, band_first, cols, band_rows);
    return evr_demo_mesh_finish(g, &m, upper ? "upper_lid" : "lower_lid", material);
}

/* The skin: a height field over a ring from the almond-shaped opening (s = 0) out to a circle of
 * radius SKIN_OUTER (s = 1), t the angle around. Near the opening it is a dome a little in front
 * of the lower lid, whose distance from the centre exceeds the upper lid's, so the skin never lets
 * a lid through and hugs them at the rim (no gaps to look into); within SKIN_RIM_BLEND of the rim it
 * turns into the smooth maximum of that dome and the face, a plane at SKIN_Z sinking a little
 * towards the eye. */
static double skin_dome(double x, double y)
{
    double r = lid_radius(x, 0) + SKIN_OVER_LID, q = r * r - x * x - y * y, q0 = 4.0;
    return q >= q0 ? sqrt(q) : sqrt(q0) + (q - q0) / (2.0 * sqrt(q0)); /* C1 past its edge */
}

static void skin_point(double t, double s, double p[3])
{
    double st = sin(t), hx = HOLE_HALF_W * cos(t), ox = SKIN_OUTER * cos(t), oy = SKIN_OUTER * st;
    double hy = CANTHUS_Y + CANTHUS_TILT * hx +
                (st >= 0.0 ? HOLE_UP * pow(st, 2.2) : -HOLE_LO * pow(-st, 1.7));
    double f = pow(s, 1.6), x = hx + (ox - hx) * f, y = hy + (oy - hy) * f, dome = skin_dome(x, y);
    double face = SKIN_Z - SKIN_SINK * (1.0 - smoothstep(10.0, 18.0, hypot(x, y)));
    double w = smoothstep(0.0, SKIN_RIM_BLEND, f * hypot(ox - hx, oy - hy));
    double target =
        skin_dome(hx, hy) + (smooth_max(face, dome, SKIN_BLEND) - skin_dome(hx, hy)) * w;
    p[0] = x;
    p[1] = y;
    p[2] = smooth_max(target, dome, 0.5); /* never behind the dome, hence never behind a lid */
}

static int build_skin(evr_gltf *g, int material)
{
    evr_demo_mesh m = {0};
    const int cols = 128, rows = 28;
    const double h = 1e-4;
    int i, j, k;
    for (j = 0; j <= rows; j++) {
        double s = (double)j / rows;
        for (i = 0; i <= cols; i++) {
            double t = 2.0 * PI * i / cols, p[3], a[3], b[3], c[3], d[3], n[3];
            skin_point(t, s, p);
            skin_point(t - h, s, a);
            skin_point(t + h, s, b);
            skin_point(t, s > h ? s - h : 0.0, c);
            skin_point(t, s + h, d);
            for (k = 0; k < 3; k++) {
                a[k] = b[k] - a[k];
                c[k] = d[k] - c[k];
            }
            n[0] = a[1] * c[2] - a[2] * c[1];
            n[1] = a[2] * c[0] - a[0] * c[2];
            n[2] = a[0] * c[1] - a[1] * c[0];
            if (n[2] < 0.0)
                for (k = 0; k < 3; k++) n[k] = -n[k];
            vert_mm(&m, p[0], p[1], p[2], n, 0.5 + p[0] / (2.0 * SKIN_OUTER),
                    0.5 - p[1] / (2.0 * SKIN_OUTER));
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    return evr_demo_mesh_finish(g, &m, "skin", material);
}

/* The socket behind the eye: the back half of a sphere, seen from inside. Rays entering the
 * opening between skin and lids end on it instead of leaving the scene. */
static int build_orbit(evr_gltf *g, int material)
{
    evr_demo_mesh m = {0};
    const int cols = 48, rows = 12;
    int i, j;
    for (j = 0; j <= rows; j++) {
        double th = PI / 2 + PI / 2 * j / rows; /* from the rim (z = 0) to the back pole */
        for (i = 0; i <= cols; i++) {
            double ph = 2.0 * PI * i / cols, n[3];
            n[0] = -sin(th) * cos(ph); /* facing the centre */
            n[1] = -sin(th) * sin(ph);
            n[2] = -cos(th);
            vert_mm(&m, -ORBIT_R * n[0], -ORBIT_R * n[1], -ORBIT_R * n[2], n, (double)i / cols,
                    (double)j / rows);
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    return evr_demo_mesh_finish(g, &m, "orbit", material);
}

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
 * enough to hold it. */
static int make_plan(gaze_plan *p, int drift)
{
    uint64_t s = EYE_PLAN_SEED;
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
        if (k < NUM_START && plan_start[k].duration >= 0.0) dur = plan_start[k].duration;
        else if (blink) dur = need + plan_uniform(&s, 0.0, FIX_MAX - need);
        else dur = plan_uniform(&s, FIX_MIN, FIX_MAX);
        if (k >= NUM_START && rest <= FIX_MAX) { /* the last fixation runs to the end */
            f->end = ANIM_LENGTH;
            if (blink && rest >= need) {
                f->blink = key_time(t + BLINK_DELAY);
                p->num_blinks++;
            }
            return 1;
        }
        if (k + 1 < NUM_START) {
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

/* Position along a saccade: the integral of a velocity profile t (1-t)^1.5, normalized. Its peak
 * comes at 40% of the duration and is 1.63 times the mean velocity, as in real saccades. */
static double saccade_profile(double t)
{
    double w = 1.0 - clampd(t, 0.0, 1.0);
    return 1.0 - 3.5 * pow(w, 2.5) + 2.5 * pow(w, 3.5);
}

/* Lid closure 0 (open) .. 1 (closed). Exactly 0 outside the blinks (and where the closure is
 * below 1e-9, so that a key at a blink's end rounded in time still holds the open pose). */
static double blink_at(const gaze_plan *p, int k, double t)
{
    double s = t - p->fix[k].blink, b;
    if (p->fix[k].blink < 0.0 || s <= 0.0 || s >= BLINK_LEN) return 0.0;
    if (s < BLINK_CLOSE) b = saccade_profile(s / BLINK_CLOSE);
    else if (s < BLINK_CLOSE + BLINK_HOLD) b = 1.0;
    else b = 1.0 - saccade_profile((s - BLINK_CLOSE - BLINK_HOLD) / BLINK_OPEN);
    return b < 1e-9 ? 0.0 : b;
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
            double s = saccade_profile((t - f->end) / (g->start - f->end));
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
static void build_animation(evr_gltf *g, int eyeball, int upper, int lower, int drift)
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
    if (!make_plan(plan, drift)) {
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

static int add_material(evr_gltf *g, const char *name, int texture, float roughness)
{
    evr_gltf_material m;
    evr_gltf_material_init(&m, name);
    m.base_texture = texture;
    m.roughness = roughness;
    return evr_gltf_add_material(g, &m);
}

static void build_eye(evr_gltf *g, int drift)
{
    static const double cam_pos[3] = {0.0, -10.0 * MM, 40.0 * MM}, target[3] = {0.0, 0.0, 0.0},
                        up[3] = {0.0, 1.0, 0.0};
    float q[4];
    evr_gltf_material mat;
    int m_sclera, m_iris, m_lid_up, m_lid_lo, m_skin, m_orbit, eyeball, node, upper, lower, mount,
        cam, led;

    m_sclera = add_material(g, "sclera", paint_sclera(g), 0.35f);
    m_iris = add_material(g, "iris", paint_iris(g), 0.1f);
    m_lid_up = add_material(g, "upper_eyelid",
                            paint_eyelid(g, "upper_eyelid_texture", 4242u, 170, 22.0, 50.0), 0.6f);
    m_lid_lo = add_material(g, "lower_eyelid",
                            paint_eyelid(g, "lower_eyelid_texture", 4343u, 90, 10.0, 24.0), 0.6f);
    m_skin = add_material(g, "skin", paint_skin(g), 0.6f);
    evr_gltf_material_init(&mat, "orbit");
    mat.base_color[0] = 0.25f;
    mat.base_color[1] = 0.09f;
    mat.base_color[2] = 0.08f;
    m_orbit = evr_gltf_add_material(g, &mat);
    if (evr_gltf_status(g, NULL) != EVR_OK) return;

    eyeball = evr_gltf_node(g, "eyeball", -1);
    node = evr_gltf_node(g, "sclera", eyeball);
    evr_gltf_node_mesh(g, node, build_sclera(g, m_sclera));
    node = evr_gltf_node(g, "cornea", eyeball);
    evr_gltf_node_mesh(g, node, build_cornea(g, m_iris));

    upper = evr_gltf_node(g, "upper_lid", -1);
    evr_gltf_node_mesh(g, upper, build_lid(g, 1, m_lid_up));
    lower = evr_gltf_node(g, "lower_lid", -1);
    evr_gltf_node_mesh(g, lower, build_lid(g, 0, m_lid_lo));

    node = evr_gltf_node(g, "skin", -1);
    evr_gltf_node_mesh(g, node, build_skin(g, m_skin));
    node = evr_gltf_node(g, "orbit", -1);
    evr_gltf_node_mesh(g, node, build_orbit(g, m_orbit));

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

    led = evr_gltf_light(g, "ir_led", EVR_GLTF_POINT, NULL, 2e-3f, 0.0f, 0.0f);
    node = evr_gltf_node(g, "ir_led", -1);
    evr_gltf_node_translation(g, node, (float)(5.0 * MM), (float)(-10.0 * MM), (float)(40.0 * MM));
    evr_gltf_node_light(g, node, led);

    build_animation(g, eyeball, upper, lower, drift);
}

void evr_demo_build_eye(evr_gltf *g) { build_eye(g, 0); }

void evr_demo_build_eye_drift(evr_gltf *g) { build_eye(g, 1); }
