/* The eye scenes' parts (demo_eye_parts.h): textures painted in code, the eyeball, the lids, the
 * skin around them and the socket, and the shape of a blink. Geometry in millimetres, stored in
 * metres; demo_eye.c's opening comment describes every part. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/demo_eye_parts.h"
#include "scene/demo_paint.h"

#define MM 0.001
#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

/* geometry, millimetres */
#define EYE_R EVR_EYE_R
#define CORNEA_R EVR_EYE_CORNEA_R
#define CORNEA_C EVR_EYE_CORNEA_C
#define IRIS_TEX_HALF 7.5 /* the iris texture covers [-7.5, 7.5]^2 in x, y */
#define IRIS_R EVR_EYE_IRIS_R
#define PUPIL_R EVR_EYE_PUPIL_R
#define PUPIL_BEHIND 0.05 /* the pupil's black disc lies this far behind the iris's inner edge */
#define LASH_X 9.5        /* lashes grow on the margin over |x| <= LASH_X ... */
#define LASH_UP_LEN 8.5   /* ... this long (upper) at the middle ... */
#define LASH_LO_LEN 5.0   /* ... (lower), shorter towards the corners */
#define LID_UP_R 14.8     /* lid radii at the middle ... */
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
#define ORBIT_R 25.0 /* the socket: a bowl behind everything, a backstop for rays */
#define HOLE_HALF_W 11.9
#define HOLE_UP 7.0
#define HOLE_LO 6.5

static const double sclera_srgb[3] = {238.0, 226.0, 219.0};
static const double skin_srgb[3] = {222.0, 168.0, 142.0};

/* ---- textures ---- */

/* Equirectangular around the Z axis: u = azimuth / 2 pi, v = polar angle from +Z / pi. */
int evr_eye_paint_sclera(evr_gltf *g)
{
    evr_demo_image im;
    evr_demo_rng r = {12345u};
    int x, y, k, tex;
    const double vein[3] = {172.0, 62.0, 60.0};
    if (!evr_demo_image_init(&im, 512, 256, 1)) {
        evr_demo_image_free(&im);
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (y = 0; y < im.h; y++) {
        double th = (y + 0.5) / im.h * PI;
        for (x = 0; x < im.w; x++) {
            double u = (x + 0.5) / im.w, c[3],
                   n = evr_demo_fbm(u * 16.0, th * 5.0, 7u, 4, 16) - 0.5;
            double back = evr_demo_smoothstep(70.0 * DEG, 130.0 * DEG,
                                              th); /* a little yellower at the back */
            c[0] = sclera_srgb[0] * (1.0 + 0.05 * n);
            c[1] = sclera_srgb[1] * (1.0 + 0.05 * n - 0.04 * back);
            c[2] = sclera_srgb[2] * (1.0 + 0.05 * n - 0.10 * back);
            evr_demo_image_set(&im, x, y, c);
        }
    }
    /* Conjunctival vessels: wandering from the periphery towards the limbus, thinning and fading,
     * with a few side branches. */
    for (k = 0; k < 44; k++) {
        double px = evr_demo_rng_range(&r, 0.0, im.w),
               py = evr_demo_rng_range(&r, 72.0, 100.0) / 180.0 * im.h;
        double stop = evr_demo_rng_range(&r, 44.0, 62.0) / 180.0 * im.h,
               dir = -PI / 2 + evr_demo_rng_range(&r, -0.5, 0.5);
        double w = evr_demo_rng_range(&r, 0.7, 1.3), a = evr_demo_rng_range(&r, 0.35, 0.6),
               start = py;
        int step = 0;
        while (py > stop && step < 400) {
            double nx, ny, f = (start - py) / (start - stop), rr = w * (1.0 - 0.6 * f),
                           aa = a * (1.0 - 0.7 * f);
            dir += evr_demo_rng_range(&r, -0.35, 0.35);
            dir = -PI / 2 + evr_demo_clamp(dir + PI / 2, -0.9, 0.9);
            nx = px + 2.0 * cos(dir);
            ny = py + 2.0 * sin(dir);
            evr_demo_image_stroke(&im, px, py, nx, ny, rr, rr, aa, aa);
            if (evr_demo_rng_uniform(&r) < 0.04) { /* a side branch */
                double bx = nx, by = ny,
                       bd = dir + (evr_demo_rng_uniform(&r) < 0.5 ? -1.0 : 1.0) *
                                      evr_demo_rng_range(&r, 0.6, 1.1);
                int j;
                for (j = 0; j < 14; j++) {
                    double cx = bx + 1.8 * cos(bd), cy = by + 1.8 * sin(bd);
                    bd += evr_demo_rng_range(&r, -0.3, 0.3);
                    evr_demo_image_stroke(&im, bx, by, cx, cy, rr * 0.6, rr * 0.5, aa * 0.7,
                                          aa * 0.5);
                    bx = cx;
                    by = cy;
                }
            }
            px = nx;
            py = ny;
            step++;
        }
        evr_demo_image_apply(&im, vein);
    }
    tex = evr_demo_image_texture(g, &im, "sclera_texture");
    evr_demo_image_free(&im);
    return tex;
}

/* Iris colours (sRGB 0-255: near the pupil, outer, the pupillary ruff): the scene's own first,
 * then those a variant (evr_gltf_variant) may draw. */
static const double iris_palettes[][3][3] = {
    {{150.0, 108.0, 68.0}, {112.0, 90.0, 74.0}, {62.0, 42.0, 32.0}},   /* hazel-brown */
    {{96.0, 62.0, 36.0}, {70.0, 46.0, 30.0}, {40.0, 26.0, 18.0}},      /* dark brown */
    {{142.0, 136.0, 78.0}, {86.0, 104.0, 82.0}, {70.0, 56.0, 34.0}},   /* green */
    {{150.0, 168.0, 178.0}, {84.0, 112.0, 140.0}, {78.0, 70.0, 58.0}}, /* blue */
    {{140.0, 142.0, 138.0}, {98.0, 104.0, 108.0}, {66.0, 60.0, 54.0}}, /* grey */
};

/* The iris, pupil and limbus painted for the cornea: planar over [-7.5, 7.5] mm in x and y,
 * row 0 at y = +7.5. A variant draws its colours and its fibres and crypts from its seed. */
int evr_eye_paint_iris(evr_gltf *g)
{
    evr_demo_image im;
    const uint64_t seed = evr_gltf_variant(g);
    const uint32_t v = (uint32_t)(seed ^ (seed >> 32)) * 2654435761u; /* noise seeds' offset */
    evr_demo_rng r = {777u ^ v};
    int x, y, k, tex;
    double crypt_a[36], crypt_t[36], crypt_s[36];
    const double pupil[3] = {10.0, 9.0, 9.0};
    const int n_pal = (int)(sizeof iris_palettes / sizeof iris_palettes[0]);
    const int pal = seed ? (int)(seed % (uint64_t)n_pal) : 0;
    const double *inner = iris_palettes[pal][0], *outer = iris_palettes[pal][1],
                 *ruff = iris_palettes[pal][2];
    if (!evr_demo_image_init(&im, 512, 512, 0)) {
        evr_demo_image_free(&im);
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (k = 0; k < 36; k++) {
        crypt_a[k] = evr_demo_rng_range(&r, -PI, PI);
        crypt_t[k] = evr_demo_rng_range(&r, 0.36, 0.78);
        crypt_s[k] = evr_demo_rng_range(&r, 0.6, 1.4);
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
            f1 = evr_demo_fbm(au * 90.0 + 0.6 * sin(7.0 * t), t * 3.0, 31u + v, 3, 90);
            f2 = evr_demo_vnoise(au * 260.0, t * 9.0, 47u + v, 260);
            evr_demo_mix3(c, inner, outer, evr_demo_smoothstep(tc - 0.05, tc + 0.25, t));
            shade = 0.78 + 0.45 * (f1 - 0.5) * 1.6 + 0.18 * (f2 - 0.5);
            coll = exp(-pow((t - tc) / 0.035, 2.0)); /* the collarette ridge */
            shade += 0.22 * coll;
            shade -= 0.10 * exp(-pow((t - 0.74) / 0.012, 2.0)) *
                     (evr_demo_vnoise(au * 40.0, 0.0, 5u + v, 40) > 0.4);
            shade -= 0.10 * exp(-pow((t - 0.86) / 0.012, 2.0)) *
                     (evr_demo_vnoise(au * 40.0, 3.0, 6u + v, 40) > 0.45);
            for (k = 0; k < 36; k++) { /* crypts */
                double da = remainder(ang - crypt_a[k], 2.0 * PI) / (0.05 * crypt_s[k]);
                double dt = (t - crypt_t[k]) / (0.05 * crypt_s[k]);
                shade -= 0.35 * exp(-(da * da + dt * dt));
            }
            for (k = 0; k < 3; k++) c[k] *= evr_demo_clamp(shade, 0.15, 1.6);
            evr_demo_mix3(c, ruff, c, evr_demo_smoothstep(0.0, 0.06, t)); /* pupillary ruff */
            for (k = 0; k < 3; k++)
                c[k] *= 1.0 - 0.6 * evr_demo_smoothstep(IRIS_R - 0.9, IRIS_R - 0.05,
                                                        rad); /* limbal ring */
            for (k = 0; k < 3; k++)
                sc[k] = sclera_srgb[k] *
                        (1.0 + 0.04 * (evr_demo_fbm(mx * 1.5, my * 1.5, 9u, 3, 0) - 0.5));
            evr_demo_mix3(c, c, sc, evr_demo_smoothstep(IRIS_R - 0.05, IRIS_R + 0.35, rad));
            evr_demo_mix3(c, pupil, c, evr_demo_smoothstep(PUPIL_R - 0.04, PUPIL_R + 0.04, rad));
            evr_demo_image_set(&im, x, y, c);
        }
    }
    tex = evr_demo_image_texture(g, &im, "iris_texture");
    evr_demo_image_free(&im);
    return tex;
}

void evr_eye_skin_colour(double c[3], double x, double y, uint32_t seed)
{
    double low = evr_demo_fbm(x * 0.15, y * 0.15, seed, 3, 0) - 0.5,
           pores = evr_demo_vnoise(x * 4.0, y * 4.0, seed + 9u, 0) - 0.5;
    int k;
    for (k = 0; k < 3; k++) c[k] = skin_srgb[k] * (1.0 + 0.10 * low + 0.06 * pores);
    c[0] *= 1.0 + 0.03 * low; /* blotches are redder */
}

/* Lids: u along the lid (0..1 over x in [-16, 16] mm), v from the margin band (v < 0.05)
 * away from the margin. */
int evr_eye_paint_eyelid(evr_gltf *g, const char *name, uint32_t seed, int lashes, double len_lo,
                         double len_hi)
{
    evr_demo_image im;
    evr_demo_rng r = {seed};
    int x, y, k, tex;
    const double band[3] = {204.0, 124.0, 118.0}, lash[3] = {24.0, 19.0, 17.0},
                 crease[3] = {170.0, 118.0, 98.0};
    if (!evr_demo_image_init(&im, 512, 256, 0)) {
        evr_demo_image_free(&im);
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (y = 0; y < im.h; y++) {
        double v = (y + 0.5) / im.h;
        for (x = 0; x < im.w; x++) {
            double u = (x + 0.5) / im.w, c[3];
            evr_eye_skin_colour(c, u * 36.0, v * 21.0, 77u);
            if (v < 0.05) {
                double n = evr_demo_vnoise(u * 80.0, v * 40.0, 3u, 0) - 0.5;
                for (k = 0; k < 3; k++) c[k] = band[k] * (1.0 + 0.08 * n);
            }
            evr_demo_image_set(&im, x, y, c);
        }
    }
    /* the lid crease, a soft darker fold */
    for (k = 0; k < 64; k++) {
        double u0 = 0.12 + 0.76 * k / 64.0, u1 = 0.12 + 0.76 * (k + 1) / 64.0;
        double v0 = 0.42 + 0.10 * pow((u0 - 0.5) / 0.38, 2.0),
               v1 = 0.42 + 0.10 * pow((u1 - 0.5) / 0.38, 2.0);
        double a = 0.35 * sin(PI * (u0 - 0.12) / 0.76);
        evr_demo_image_stroke(&im, u0 * im.w, v0 * im.h, u1 * im.w, v1 * im.h, 2.0, 2.0, a, a);
    }
    evr_demo_image_apply(&im, crease);
    /* the lash line just above the margin band */
    evr_demo_image_stroke(&im, 0.16 * im.w, 0.062 * im.h, 0.84 * im.w, 0.062 * im.h, 2.2, 2.2, 0.85,
                          0.85);
    evr_demo_image_apply(&im, lash);
    /* lashes: curved dark strokes leaning towards the nearer corner */
    for (k = 0; k < lashes; k++) {
        double u = evr_demo_rng_range(&r, 0.21, 0.79),
               lean = (u - 0.5) * 1.9 + evr_demo_rng_range(&r, -0.25, 0.25);
        double len =
            evr_demo_rng_range(&r, len_lo, len_hi) * (1.0 - 0.9 * pow(fabs(u - 0.5) / 0.29, 4.0));
        double px = u * im.w, py = 0.06 * im.h, dir = PI / 2 - lean * 0.8;
        int j, n = 8;
        if (len < 6.0) len = 6.0;
        for (j = 0; j < n; j++) {
            double f0 = (double)j / n, f1 = (double)(j + 1) / n;
            double nx = px + len / n * cos(dir), ny = py + len / n * sin(dir);
            evr_demo_image_stroke(&im, px, py, nx, ny, 0.9 * (1.0 - 0.6 * f0),
                                  0.9 * (1.0 - 0.6 * f1), 0.9, 0.75);
            dir -= lean * 0.12; /* curl outwards */
            px = nx;
            py = ny;
        }
        evr_demo_image_apply(&im, lash);
    }
    tex = evr_demo_image_texture(g, &im, name);
    evr_demo_image_free(&im);
    return tex;
}

int evr_eye_paint_lashes(evr_gltf *g, int upper)
{
    evr_demo_image im;
    evr_demo_rng r = {upper ? 5151u : 5252u};
    const double lash[3] = {30.0, 23.0, 20.0};
    const int count = upper ? 130 : 70;
    int x, y, k, j;
    if (!evr_demo_image_init(&im, 512, 64, 0)) {
        evr_demo_image_free(&im);
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (y = 0; y < im.h; y++)
        for (x = 0; x < im.w; x++) evr_demo_image_set(&im, x, y, lash);
    /* strands from the roots (row 0) to the tips, leaning towards the nearer corner and curling
     * further that way; 2.6 texels (0.1 mm) thick at the root, thinning */
    for (k = 0; k < count; k++) {
        double u = evr_demo_rng_range(&r, 0.01, 0.99),
               lean = (u - 0.5) * 1.2 + evr_demo_rng_range(&r, -0.25, 0.25);
        double len = evr_demo_rng_range(&r, 0.6, 1.0) * im.h, px = u * im.w, py = 0.0;
        const int n = 6;
        for (j = 0; j < n; j++) {
            double f0 = (double)j / n, f1 = (double)(j + 1) / n;
            double nx = px + lean * (0.3 + 0.9 * f1) * len / n, ny = py + len / n;
            evr_demo_image_stroke(&im, px, py, nx, ny, 1.3 * (1.0 - 0.5 * f0),
                                  1.3 * (1.0 - 0.5 * f1), 1.0, 1.0);
            px = nx;
            py = ny;
        }
    }
    k = evr_demo_image_texture_masked(g, &im,
                                      upper ? "upper_lashes_texture" : "lower_lashes_texture");
    evr_demo_image_free(&im);
    return k;
}

int evr_eye_paint_skin(evr_gltf *g, double outer, int size)
{
    evr_demo_image im;
    evr_demo_rng r = {999u};
    int x, y, k, tex;
    const double wrinkle[3] = {176.0, 124.0, 104.0};
    if (!evr_demo_image_init(&im, size, size, 0)) {
        evr_demo_image_free(&im);
        evr_gltf_fail(g, EVR_ERR_NOMEM, "out of memory while painting a demo texture");
        return -1;
    }
    for (y = 0; y < im.h; y++) {
        for (x = 0; x < im.w; x++) {
            double mx = ((x + 0.5) / im.w * 2.0 - 1.0) * outer,
                   my = (1.0 - (y + 0.5) / im.h * 2.0) * outer;
            double c[3];
            evr_eye_skin_colour(c, mx, my, 55u);
            evr_demo_image_set(&im, x, y, c);
        }
    }
    for (k = 0; k < 7; k++) {
        double ang = evr_demo_rng_range(&r, -0.5, 0.5), r0 = evr_demo_rng_range(&r, 14.0, 16.0),
               r1 = r0 + evr_demo_rng_range(&r, 5.0, 9.0);
        int j;
        for (j = 0; j < 12; j++) {
            double ra = r0 + (r1 - r0) * j / 12.0, rb = r0 + (r1 - r0) * (j + 1) / 12.0;
            double aa = ang + 0.02 * sin(j * 1.3), ab = ang + 0.02 * sin((j + 1) * 1.3);
            double xa = (ra * cos(aa) / outer + 1.0) / 2.0 * im.w,
                   ya = (1.0 - ra * sin(aa) / outer) / 2.0 * im.h;
            double xb = (rb * cos(ab) / outer + 1.0) / 2.0 * im.w,
                   yb = (1.0 - rb * sin(ab) / outer) / 2.0 * im.h;
            double a = 0.45 * sin(PI * (j + 0.5) / 12.0);
            evr_demo_image_stroke(&im, xa, ya, xb, yb, 0.6, 0.6, a, a);
        }
        evr_demo_image_apply(&im, wrinkle);
    }
    tex = evr_demo_image_texture(g, &im, "skin_texture");
    evr_demo_image_free(&im);
    return tex;
}

/* ---- geometry (built in millimetres, stored in metres) ---- */

/* The limbus, where the cornea's sphere meets the eyeball's: z and radius. The sclera ends there,
 * the cornea's front surface begins, and the iris is rooted. */
static double limbus_z(void)
{
    return (EYE_R * EYE_R - CORNEA_R * CORNEA_R + CORNEA_C * CORNEA_C) / (2.0 * CORNEA_C);
}

static double limbus_r(void) { return sqrt(EYE_R * EYE_R - limbus_z() * limbus_z()); }

/* The eyeball behind the limbus: a UV sphere with its front cap (inside the limbus) left out,
 * where the cornea and the iris take over. */
static int sclera_mesh(evr_gltf *g, int material)
{
    evr_demo_mesh m = {0};
    const int cols = 64, rows = 40;
    const double th0 = atan2(limbus_r(), limbus_z());
    int i, j;
    for (j = 0; j <= rows; j++) {
        double th = th0 + (PI - th0) * j / rows;
        for (i = 0; i <= cols; i++) {
            double ph = 2.0 * PI * i / cols, n[3];
            n[0] = sin(th) * cos(ph);
            n[1] = sin(th) * sin(ph);
            n[2] = cos(th);
            evr_demo_mesh_vertex_mm(&m, EYE_R * n[0], EYE_R * n[1], EYE_R * n[2], n,
                                    (double)i / cols, th / PI);
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    return evr_demo_mesh_finish(g, &m, "sclera", material);
}

/* A closed volume of the cornea's (and aqueous humour's) index: the front surface, a spherical
 * cap out to the limbus (its tear film is the smooth dielectric that gives the LED's glint),
 * closed behind by a disc in the limbus plane facing back (into the eye). The iris and the pupil
 * lie inside it. */
static int cornea_mesh(evr_gltf *g, int material)
{
    evr_demo_mesh m = {0};
    const int cols = 96, rows = 24;
    const double psi_max = acos((limbus_z() - CORNEA_C) / CORNEA_R), back[3] = {0.0, 0.0, -1.0};
    uint32_t centre, first;
    int i, j;
    for (j = 0; j <= rows; j++) {
        double ps = psi_max * j / rows;
        for (i = 0; i <= cols; i++) {
            double ph = 2.0 * PI * i / cols, n[3];
            n[0] = sin(ps) * cos(ph);
            n[1] = sin(ps) * sin(ph);
            n[2] = cos(ps);
            evr_demo_mesh_vertex_mm(&m, CORNEA_R * n[0], CORNEA_R * n[1],
                                    CORNEA_C + CORNEA_R * n[2], n, (double)i / cols,
                                    (double)j / rows);
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    centre = evr_demo_mesh_vertex_mm(&m, 0.0, 0.0, limbus_z(), back, 0.5, 1.0);
    first = m.nv;
    for (i = 0; i <= cols; i++) {
        double ph = 2.0 * PI * i / cols;
        evr_demo_mesh_vertex_mm(&m, limbus_r() * cos(ph), limbus_r() * sin(ph), limbus_z(), back,
                                (double)i / cols, 1.0);
    }
    for (i = 0; i < cols; i++)
        evr_demo_mesh_triangle(&m, centre, first + (uint32_t)i, first + (uint32_t)i + 1);
    return evr_demo_mesh_finish(g, &m, "cornea", material);
}

/* The iris's front surface at radius r: nearly flat from the pupil's edge (2.9 behind the
 * apex) to the visible iris's edge, then down to its root at the limbus. */
static double iris_z(double r)
{
    if (r <= IRIS_R)
        return EVR_EYE_PUPIL_Z -
               (EVR_EYE_PUPIL_Z - EVR_EYE_IRIS_EDGE_Z) * (r - PUPIL_R) / (IRIS_R - PUPIL_R);
    return EVR_EYE_IRIS_EDGE_Z +
           (limbus_z() - EVR_EYE_IRIS_EDGE_Z) * (r - IRIS_R) / (limbus_r() - IRIS_R);
}

/* The iris: a ring from the pupil to the limbus, under the cornea, textured by a planar
 * projection along Z (the painted iris spans IRIS_R; beyond it, towards the limbus, the texture
 * is sclera-coloured, as the sclera overlaps the cornea's edge in a real eye). */
static int iris_mesh(evr_gltf *g, int material)
{
    evr_demo_mesh m = {0};
    const int cols = 64, rows_in = 8, rows_out = 3, rows = rows_in + rows_out;
    int i, j;
    for (j = 0; j <= rows; j++) {
        double r = j <= rows_in ? PUPIL_R + (IRIS_R - PUPIL_R) * j / rows_in
                                : IRIS_R + (limbus_r() - IRIS_R) * (j - rows_in) / rows_out;
        /* the slope of the piece the ring lies on (at the kink between them, their mean) */
        const double s_in = (iris_z(IRIS_R) - iris_z(PUPIL_R)) / (IRIS_R - PUPIL_R),
                     s_out = (limbus_z() - iris_z(IRIS_R)) / (limbus_r() - IRIS_R);
        double slope = j < rows_in ? s_in : (j > rows_in ? s_out : 0.5 * (s_in + s_out));
        double l = sqrt(1.0 + slope * slope);
        for (i = 0; i <= cols; i++) {
            double ph = 2.0 * PI * i / cols, x = r * cos(ph), y = r * sin(ph), n[3];
            n[0] = -slope * cos(ph) / l;
            n[1] = -slope * sin(ph) / l;
            n[2] = 1.0 / l;
            evr_demo_mesh_vertex_mm(&m, x, y, iris_z(r), n, 0.5 + x / (2.0 * IRIS_TEX_HALF),
                                    0.5 - y / (2.0 * IRIS_TEX_HALF));
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    return evr_demo_mesh_finish(g, &m, "iris", material);
}

/* The pupil: a black disc just behind the iris's inner edge, a little wider than the hole. */
static int pupil_mesh(evr_gltf *g, int material)
{
    evr_demo_mesh m = {0};
    const int cols = 32;
    const double z = EVR_EYE_PUPIL_Z - PUPIL_BEHIND, r = PUPIL_R + PUPIL_BEHIND,
                 front[3] = {0.0, 0.0, 1.0};
    uint32_t centre = evr_demo_mesh_vertex_mm(&m, 0.0, 0.0, z, front, 0.5, 0.5);
    int i;
    for (i = 0; i <= cols; i++) {
        double ph = 2.0 * PI * i / cols;
        evr_demo_mesh_vertex_mm(&m, r * cos(ph), r * sin(ph), z, front, 0.5, 0.5);
    }
    for (i = 0; i < cols; i++)
        evr_demo_mesh_triangle(&m, centre, centre + 1 + (uint32_t)i, centre + 2 + (uint32_t)i);
    return evr_demo_mesh_finish(g, &m, "pupil", material);
}

void evr_eye_globe(evr_gltf *g, int eyeball)
{
    evr_gltf_material mat;
    int m_sclera, m_cornea, m_iris, m_pupil, node;
    /* moist sclera: a dielectric with a soft sheen */
    m_sclera = evr_eye_material(g, "sclera", evr_eye_paint_sclera(g), 0.25f);
    /* the cornea and its tear film: clear, smooth, refracting; a volume (not thin-walled) */
    evr_gltf_material_init(&mat, "cornea");
    mat.roughness = 0.03f;
    mat.transmission = 1.0f;
    mat.ior = EVR_EYE_CORNEA_IOR;
    mat.thickness = (float)((CORNEA_C + CORNEA_R - limbus_z()) * MM);
    m_cornea = evr_gltf_add_material(g, &mat);
    m_iris = evr_eye_material(g, "iris", evr_eye_paint_iris(g), 0.5f);
    /* the pupil: a hole into the dark eye, nothing comes back out */
    evr_gltf_material_init(&mat, "pupil");
    mat.base_color[0] = mat.base_color[1] = mat.base_color[2] = 0.0f;
    mat.unlit = 1;
    m_pupil = evr_gltf_add_material(g, &mat);
    if (evr_gltf_status(g, NULL) != EVR_OK) return;
    node = evr_gltf_node(g, "sclera", eyeball);
    evr_gltf_node_mesh(g, node, sclera_mesh(g, m_sclera));
    node = evr_gltf_node(g, "cornea", eyeball);
    evr_gltf_node_mesh(g, node, cornea_mesh(g, m_cornea));
    node = evr_gltf_node(g, "iris", eyeball);
    evr_gltf_node_mesh(g, node, iris_mesh(g, m_iris));
    node = evr_gltf_node(g, "pupil", eyeball);
    evr_gltf_node_mesh(g, node, pupil_mesh(g, m_pupil));
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
    double r =
        corner + (mid - corner) * (1.0 - evr_demo_smoothstep(LID_TAPER_A, LID_TAPER_B, fabs(x)));
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
    return asin(evr_demo_clamp(margin_y(x, upper) / lid_rho(x, upper), -0.95, 0.95));
}

void evr_eye_lid(evr_demo_mesh *m, int upper)
{
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
            evr_demo_mesh_vertex_mm(m, p[0], p[1], p[2], n, (double)i / cols, 0.05 + 0.95 * s);
        }
    }
    evr_demo_mesh_grid(m, 0, cols, rows);
    /* the band along the margin, from the lid's surface in towards the eyeball */
    band_first = m->nv;
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
            evr_demo_mesh_vertex_mm(m, p[0], p[1], p[2], n, (double)i / cols,
                                    0.05 * (1.0 - (double)j / band_rows));
        }
    }
    evr_demo_mesh_grid(m, band_first, cols, band_rows);
}

/* The lashes' direction at angle a from the lid's outward normal towards "away" (up for the
 * upper lid, down for the lower), in the plane of the two. */
static void lash_dir(const double nout[3], const double away[3], double a, double d[3])
{
    int k;
    for (k = 0; k < 3; k++) d[k] = cos(a) * nout[k] + sin(a) * away[k];
}

void evr_eye_lashes(evr_demo_mesh *m, int upper)
{
    const int cols = 40, rows = 2;
    const double a0 = (upper ? 20.0 : 35.0) * DEG, a1 = (upper ? 55.0 : 65.0) * DEG, h = 1e-3;
    const double len_mid = upper ? LASH_UP_LEN : LASH_LO_LEN;
    uint32_t first = m->nv;
    int i, j, k;
    for (j = 0; j <= rows; j++) {
        for (i = 0; i <= cols; i++) {
            double x = -LASH_X + 2.0 * LASH_X * i / cols, phm = margin_phi(x, upper);
            double drho = (lid_rho(x + h, upper) - lid_rho(x - h, upper)) / (2.0 * h);
            double t = x / LASH_X, len = len_mid * (0.4 + 0.6 * (1.0 - t * t));
            double p[3], nout[3], away[3], d0[3], d1[3], dj[3], n[3], l;
            lid_point(x, phm, upper, p);
            l = sqrt(1.0 + drho * drho);
            nout[0] = -drho / l;
            nout[1] = sin(phm) / l;
            nout[2] = cos(phm) / l;
            away[0] = 0.0;
            away[1] = upper ? cos(phm) : -cos(phm);
            away[2] = upper ? -sin(phm) : sin(phm);
            lash_dir(nout, away, a0, d0);
            lash_dir(nout, away, a1, d1);
            lash_dir(nout, away, j == 0 ? a0 : (j == 1 ? 0.5 * (a0 + a1) : a1), dj);
            for (k = 0; k < 3; k++) /* the root just outside the lid, then two straight pieces */
                p[k] += 0.05 * nout[k] + (j >= 1 ? 0.5 * len * d0[k] : 0.0) +
                        (j >= 2 ? 0.5 * len * d1[k] : 0.0);
            /* the card's normal: across the strands (x) and along them, on the outward side */
            n[0] = 0.0;
            n[1] = -dj[2];
            n[2] = dj[1];
            if (n[1] * nout[1] + n[2] * nout[2] < 0.0) {
                n[1] = -n[1];
                n[2] = -n[2];
            }
            evr_demo_mesh_vertex_mm(m, p[0], p[1], p[2], n, (double)i / cols, (double)j / rows);
        }
    }
    evr_demo_mesh_grid(m, first, cols, rows);
}

int evr_eye_lash_material(evr_gltf *g, int upper)
{
    evr_gltf_material m;
    evr_gltf_material_init(&m, upper ? "upper_lashes" : "lower_lashes");
    m.base_texture.index = evr_eye_paint_lashes(g, upper);
    m.roughness = 0.45f;
    m.alpha_mode = EVR_GLTF_MASK;
    m.alpha_cutoff = 0.5f;
    return evr_gltf_add_material(g, &m);
}

/* The skin: a height field over a ring from the almond-shaped opening (s = 0) out to a circle of
 * radius outer (s = 1), t the angle around. Near the opening it is a dome a little in front
 * of the lower lid, whose distance from the centre exceeds the upper lid's, so the skin never lets
 * a lid through and hugs them at the rim (no gaps to look into); within SKIN_RIM_BLEND of the rim it
 * turns into the smooth maximum of that dome and the face, a plane at SKIN_Z sinking a little
 * towards the eye. */
static double skin_dome(double x, double y)
{
    double r = lid_radius(x, 0) + SKIN_OVER_LID, q = r * r - x * x - y * y, q0 = 4.0;
    return q >= q0 ? sqrt(q) : sqrt(q0) + (q - q0) / (2.0 * sqrt(q0)); /* C1 past its edge */
}

static void skin_point(double t, double s, double outer, double p[3])
{
    double st = sin(t), hx = HOLE_HALF_W * cos(t), ox = outer * cos(t), oy = outer * st;
    double hy = CANTHUS_Y + CANTHUS_TILT * hx +
                (st >= 0.0 ? HOLE_UP * pow(st, 2.2) : -HOLE_LO * pow(-st, 1.7));
    double f = pow(s, 1.6), x = hx + (ox - hx) * f, y = hy + (oy - hy) * f, dome = skin_dome(x, y);
    double face = SKIN_Z - SKIN_SINK * (1.0 - evr_demo_smoothstep(10.0, 18.0, hypot(x, y)));
    double w = evr_demo_smoothstep(0.0, SKIN_RIM_BLEND, f * hypot(ox - hx, oy - hy));
    double target =
        skin_dome(hx, hy) + (smooth_max(face, dome, SKIN_BLEND) - skin_dome(hx, hy)) * w;
    p[0] = x;
    p[1] = y;
    p[2] = smooth_max(target, dome, 0.5); /* never behind the dome, hence never behind a lid */
}

int evr_eye_skin(evr_gltf *g, int material, double outer)
{
    evr_demo_mesh m = {0};
    const int cols = 128, rows = 28;
    const double h = 1e-4;
    int i, j, k;
    for (j = 0; j <= rows; j++) {
        double s = (double)j / rows;
        for (i = 0; i <= cols; i++) {
            double t = 2.0 * PI * i / cols, p[3], a[3], b[3], c[3], d[3], n[3];
            skin_point(t, s, outer, p);
            skin_point(t - h, s, outer, a);
            skin_point(t + h, s, outer, b);
            skin_point(t, s > h ? s - h : 0.0, outer, c);
            skin_point(t, s + h, outer, d);
            for (k = 0; k < 3; k++) {
                a[k] = b[k] - a[k];
                c[k] = d[k] - c[k];
            }
            n[0] = a[1] * c[2] - a[2] * c[1];
            n[1] = a[2] * c[0] - a[0] * c[2];
            n[2] = a[0] * c[1] - a[1] * c[0];
            if (n[2] < 0.0)
                for (k = 0; k < 3; k++) n[k] = -n[k];
            evr_demo_mesh_vertex_mm(&m, p[0], p[1], p[2], n, 0.5 + p[0] / (2.0 * outer),
                                    0.5 - p[1] / (2.0 * outer));
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    return evr_demo_mesh_finish(g, &m, "skin", material);
}

/* The socket behind the eye: the back half of a sphere, seen from inside. Rays entering the
 * opening between skin and lids end on it instead of leaving the scene. */
int evr_eye_orbit(evr_gltf *g, int material)
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
            evr_demo_mesh_vertex_mm(&m, -ORBIT_R * n[0], -ORBIT_R * n[1], -ORBIT_R * n[2], n,
                                    (double)i / cols, (double)j / rows);
        }
    }
    evr_demo_mesh_grid(&m, 0, cols, rows);
    return evr_demo_mesh_finish(g, &m, "orbit", material);
}

/* ---- motion ---- */

double evr_eye_saccade_profile(double t)
{
    double w = 1.0 - evr_demo_clamp(t, 0.0, 1.0);
    return 1.0 - 3.5 * pow(w, 2.5) + 2.5 * pow(w, 3.5);
}

double evr_eye_blink_closure(double s)
{
    double b;
    if (s <= 0.0 || s >= EVR_EYE_BLINK_LEN) return 0.0;
    if (s < EVR_EYE_BLINK_CLOSE) b = evr_eye_saccade_profile(s / EVR_EYE_BLINK_CLOSE);
    else if (s < EVR_EYE_BLINK_CLOSE + EVR_EYE_BLINK_HOLD) b = 1.0;
    else
        b = 1.0 - evr_eye_saccade_profile((s - EVR_EYE_BLINK_CLOSE - EVR_EYE_BLINK_HOLD) /
                                          EVR_EYE_BLINK_OPEN);
    return b < 1e-9 ? 0.0 : b;
}

int evr_eye_material(evr_gltf *g, const char *name, int texture, float roughness)
{
    evr_gltf_material m;
    evr_gltf_material_init(&m, name);
    m.base_texture.index = texture;
    m.roughness = roughness;
    return evr_gltf_add_material(g, &m);
}
