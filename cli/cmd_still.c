/* evray still: one image at one time, with or without global illumination, and its error
 * against a reference image. */
#include "commands.h"
#include "evray.h"
#include "evray_experimental.h"
#include "options.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void help(void)
{
    puts(
        "usage: evray still [SCENE | --scene NAME] [options] -o OUT.png\n"
        "\n"
        "Renders one image of the scene at one time: the event pipeline's direct shading through\n"
        "each pixel centre, plus indirect light (global illumination) when asked for. Writes 8-bit\n"
        "sRGB RGB PNG and/or linear RGB float PFM (by the extension of -o, and --pfm).\n"
        "\n"
        "  SCENE                  scene file (glTF 2.0 or anything Assimp reads)\n"
        "  --scene NAME           built-in scene instead (evray demo --list)\n"
        "  -o, --out FILE         output image: .png (8-bit sRGB) or .pfm (linear float RGB)\n"
        "  --pfm FILE             also write the linear image as PFM\n"
        "  --time T               seconds into the animation (default 0)\n"
        "  --res WxH              resolution (default 256x256)\n"
        "  --camera NAME          camera of the scene (default: the first)\n"
        "  --animation CLIP       animation clips that play: a clip's name or 0-based index alone,\n"
        "                         or all (default: clips that animate disjoint nodes play\n"
        "                         together, the later of two sharing a node does not)\n"
        "  --strict               fail on anything evray would otherwise warn about and leave\n"
        "                         out of the file (a texture it cannot find or decode, ...)\n"
        "  --allow-external-files let the scene read files outside its own folder\n"
        "  --gi MODE              none (default: direct light only), photon (image-space photon\n"
        "                         mapping) or path (brute-force path tracing: the reference)\n"
        "  --spp N                path: paths per pixel (default 64)\n"
        "  --photons N            photon: photons emitted (default 8 per pixel)\n"
        "  --gather-radius R      photon: distance filter r in scene units (default 2% of the\n"
        "                         scene's diagonal); the search window is r at the hit's distance\n"
        "  --gather-max K         photon: the search stops growing at K photons (default 256)\n"
        "  --gather-window H      photon: the window's half size at most, pixels (default 48)\n"
        "  --no-gather-area       photon: normalize the kernel over its whole disk, not over the part\n"
        "                         of it on surfaces like the query's (darker creases, cheaper)\n"
        "  --photon-layers L      photon: photons a buffer pixel holds (default 16, doubled up to 64\n"
        "                         while more than 3% of the photons find their pixel full; a number\n"
        "                         given here is kept as it is)\n"
        "  --max-bounces B        indirect bounces, both methods (default 8, at most 15)\n"
        "  --ambient A            ambient light as a fraction of the base colour (default 0.02)\n"
        "  --exposure E           PNG: linear value * E, clamped, sRGB-encoded (default 1)\n"
        "  --threads N            worker threads (default: all cores)\n"
        "  --seed N               seed of the photon sequence and the paths (default 1)\n"
        "  --reference FILE.pfm   print the relative RMSE (RMSE / mean of the reference, of the\n"
        "                         luminance) against this image: over all pixels, over --region,\n"
        "                         and of the indirect part alone over --region\n"
        "  --region NAMES         comma-separated node or mesh names: the pixels whose centre sees\n"
        "                         one of them (default: every pixel that sees something)\n"
        "  --compare FILE.pfm     compare this image instead of rendering one (with --reference; the\n"
        "                         region and the direct part come from a --gi none render)\n"
        "  -q, --quiet            no summary");
}

static int ends_with(const char *s, const char *suf)
{
    size_t a = strlen(s), b = strlen(suf);
    return a >= b && !strcmp(s + a - b, suf);
}

static int write_pfm(const char *path, const float *rgb, int w, int h)
{
    char tmp[4200];
    int y, ok;
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "wb");
    if (!f) return 0;
    ok = fprintf(f, "PF\n%d %d\n-1.0\n", w, h) > 0; /* little-endian floats, rows bottom to top */
    for (y = h - 1; y >= 0 && ok; y--)
        ok = fwrite(rgb + (size_t)y * (size_t)w * 3, sizeof(float), (size_t)w * 3, f) ==
             (size_t)w * 3;
    ok = (fclose(f) == 0) && ok;
    if (!ok || rename(tmp, path) != 0) {
        remove(tmp);
        return 0;
    }
    return 1;
}

/* 1 and *rgb (malloc'ed, rows top to bottom) on success; 0 after an error message. */
static int read_pfm(const char *path, float **rgb, int *w, int *h)
{
    FILE *f = fopen(path, "rb");
    char magic[3] = {0};
    double scale;
    int y, c;
    if (!f) {
        cli_error("cannot open %s", path);
        return 0;
    }
    if (fscanf(f, "%2s %d %d %lf", magic, w, h, &scale) != 4 || strcmp(magic, "PF") || *w <= 0 ||
        *h <= 0 || *w > 16384 || *h > 16384 || !(scale < 0.0)) {
        fclose(f);
        cli_error("%s is not a little-endian RGB PFM image", path);
        return 0;
    }
    c = fgetc(f); /* the single whitespace after the scale */
    (void)c;
    *rgb = malloc((size_t)*w * (size_t)*h * 3 * sizeof(float));
    if (!*rgb) {
        fclose(f);
        cli_error("out of memory");
        return 0;
    }
    for (y = *h - 1; y >= 0; y--) {
        if (fread(*rgb + (size_t)y * (size_t)*w * 3, sizeof(float), (size_t)*w * 3, f) !=
            (size_t)*w * 3) {
            fclose(f);
            free(*rgb);
            cli_error("%s: the image data is cut short", path);
            return 0;
        }
    }
    fclose(f);
    return 1;
}

static int write_png(const char *path, const float *rgb, int w, int h, float exposure)
{
    size_t n = (size_t)w * (size_t)h * 3, i;
    unsigned char *px = malloc(n);
    evr_error err = {{0}};
    if (!px) {
        cli_error("out of memory");
        return 0;
    }
    for (i = 0; i < n; i++) {
        float v = rgb[i] * exposure;
        v = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;
        v = v <= 0.0031308f ? 12.92f * v : 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
        px[i] = (unsigned char)(v * 255.0f + 0.5f);
    }
    evr_status st = evr_png_write(path, px, w, h, 3, 8, &err);
    free(px);
    if (st != EVR_OK) {
        cli_error("%s", err.msg);
        return 0;
    }
    return 1;
}

static float lum(const float *c) { return evr_rgb_luminance(c); }

/* 1 when instance inst's node or mesh name is one of the comma-separated names. */
static int in_region(const evr_scene *s, int inst, const char *names)
{
    const char *node = evr_scene_instance_node(s, inst), *mesh = evr_scene_instance_mesh(s, inst);
    const char *p = names;
    while (*p) {
        const char *e = strchr(p, ',');
        size_t n = e ? (size_t)(e - p) : strlen(p);
        if ((strlen(node) == n && !strncmp(node, p, n)) ||
            (strlen(mesh) == n && !strncmp(mesh, p, n)))
            return 1;
        if (!e) break;
        p = e + 1;
    }
    return 0;
}

static void compare(const evr_scene *s, const evr_still_image *r, const float *ref,
                    const char *region)
{
    size_t npix = (size_t)r->width * (size_t)r->height, i;
    double se_all = 0, sum_all = 0, se_reg = 0, sum_reg = 0, se_ind = 0, sum_ind = 0;
    long n_all = 0, n_reg = 0;
    for (i = 0; i < npix; i++) {
        float a = lum(r->rgb + 3 * i), b = lum(ref + 3 * i), d = lum(r->direct + 3 * i);
        se_all += (double)(a - b) * (a - b);
        sum_all += b;
        n_all++;
        int inst = r->instance[i];
        if (inst < 0 || (region && !in_region(s, inst, region))) continue;
        se_reg += (double)(a - b) * (a - b);
        sum_reg += b;
        se_ind += (double)(a - b) *
                  (a - b); /* the direct parts are the same code: differences are indirect */
        sum_ind += (double)(b - d);
        n_reg++;
    }
    printf("compare: all %ld pixels: relative RMSE %.4f (RMSE %.5g, reference mean %.5g)\n", n_all,
           sum_all > 0 ? sqrt(se_all / (double)n_all) / (sum_all / (double)n_all) : 0.0,
           sqrt(se_all / (double)n_all), sum_all / (double)n_all);
    if (n_reg) {
        printf(
            "compare: region (%s) %ld pixels: relative RMSE %.4f (RMSE %.5g, reference mean %.5g)\n",
            region ? region : "every hit", n_reg,
            sum_reg > 0 ? sqrt(se_reg / (double)n_reg) / (sum_reg / (double)n_reg) : 0.0,
            sqrt(se_reg / (double)n_reg), sum_reg / (double)n_reg);
        printf("compare: region indirect only: relative RMSE %.4f (reference indirect mean %.5g)\n",
               sum_ind > 0 ? sqrt(se_ind / (double)n_reg) / (sum_ind / (double)n_reg) : 0.0,
               sum_ind / (double)n_reg);
    } else {
        printf("compare: region (%s): no pixel\n", region ? region : "every hit");
    }
}

int cmd_still(int argc, char **argv)
{
    evr_still_params p;
    const char *scene_path = NULL, *demo = NULL, *out = NULL, *pfm = NULL, *ref_path = NULL,
               *region = NULL, *v;
    const char *cmp_path = NULL, *animation = NULL;
    float exposure = 1.0f;
    int quiet = 0, strict = 0, external = 0, i, ar;
    evr_still_defaults(&p);
#define VAL(name)                                             \
    do {                                                      \
        if (!(v = opt_value(argc, argv, &i, name))) return 2; \
    } while (0)
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return 0;
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) quiet = 1;
        else if (!strcmp(a, "--strict")) strict = 1;
        else if (!strcmp(a, "--allow-external-files")) external = 1;
        else if (!strcmp(a, "-o")) {
            VAL("-o");
            out = v;
        } else if (opt_is(a, "--out")) {
            VAL("--out");
            out = v;
        } else if (opt_is(a, "--pfm")) {
            VAL("--pfm");
            pfm = v;
        } else if (opt_is(a, "--scene")) {
            VAL("--scene");
            demo = v;
        } else if (opt_is(a, "--reference")) {
            VAL("--reference");
            ref_path = v;
        } else if (opt_is(a, "--compare")) {
            VAL("--compare");
            cmp_path = v;
        } else if (opt_is(a, "--region")) {
            VAL("--region");
            if (!v[0]) {
                cli_error("--region needs names");
                return 2;
            }
            region = v;
        } else if (opt_is(a, "--time")) {
            VAL("--time");
            if (!opt_double("--time", v, &p.time)) return 2;
            if (!(p.time >= 0.0 && p.time <= 1e6)) {
                cli_error("--time must be between 0 and 1e6 seconds (got %s)", v);
                return 2;
            }
        } else if (opt_is(a, "--res")) {
            VAL("--res");
            if (!opt_size("--res", v, &p.width, &p.height)) return 2;
        } else if (opt_is(a, "--camera")) {
            VAL("--camera");
            p.camera = v;
        } else if ((ar = cli_is_animation_option(argc, argv, &i, &animation)) != 0) {
            if (ar < 0) return 2;
        } else if (opt_is(a, "--gi")) {
            VAL("--gi");
            if (!strcmp(v, "none")) p.gi = EVR_GI_NONE;
            else if (!strcmp(v, "photon")) p.gi = EVR_GI_PHOTON;
            else if (!strcmp(v, "path")) p.gi = EVR_GI_PATH;
            else {
                cli_error("--gi: unknown mode '%s' (none, photon, path)", v);
                return 2;
            }
        } else if (opt_is(a, "--spp")) {
            VAL("--spp");
            if (!opt_int("--spp", v, &p.spp)) return 2;
            if (p.spp < 1 || p.spp > 1000000) {
                cli_error("--spp must be between 1 and 1000000 (got %s)", v);
                return 2;
            }
        } else if (opt_is(a, "--photons")) {
            VAL("--photons");
            uint64_t n;
            if (!opt_u64("--photons", v, &n)) return 2;
            if (n < 1 || n > (1u << 28)) {
                cli_error("--photons must be between 1 and 268435456 (got %s)", v);
                return 2;
            }
            p.photons = (uint32_t)n;
        } else if (opt_is(a, "--gather-radius")) {
            VAL("--gather-radius");
            if (!opt_float("--gather-radius", v, &p.gather_radius)) return 2;
            if (!(p.gather_radius > 0.0f)) {
                cli_error("--gather-radius must be a positive distance (got %s)", v);
                return 2;
            }
        } else if (opt_is(a, "--gather-max")) {
            VAL("--gather-max");
            if (!opt_int("--gather-max", v, &p.gather_max)) return 2;
            if (p.gather_max < 1) {
                cli_error("--gather-max must be at least 1 (got %s)", v);
                return 2;
            }
        } else if (opt_is(a, "--gather-window")) {
            VAL("--gather-window");
            if (!opt_int("--gather-window", v, &p.gather_window)) return 2;
            if (p.gather_window < 0 || p.gather_window > 1024) {
                cli_error("--gather-window must be between 0 and 1024 (got %s)", v);
                return 2;
            }
        } else if (opt_is(a, "--photon-layers")) {
            VAL("--photon-layers");
            if (!opt_int("--photon-layers", v, &p.photon_layers)) return 2;
            if (p.photon_layers < 1 || p.photon_layers > 64) {
                cli_error("--photon-layers must be between 1 and 64 (got %s)", v);
                return 2;
            }
            p.auto_layers = 0;
        } else if (opt_is(a, "--max-bounces")) {
            VAL("--max-bounces");
            if (!opt_int("--max-bounces", v, &p.max_bounces)) return 2;
            if (p.max_bounces < 1 || p.max_bounces > 15) {
                cli_error("--max-bounces must be between 1 and 15 (got %s)", v);
                return 2;
            }
        } else if (opt_is(a, "--ambient")) {
            VAL("--ambient");
            if (!opt_float("--ambient", v, &p.ambient)) return 2;
            if (!(p.ambient >= 0.0f)) {
                cli_error("--ambient must be >= 0 (got %s)", v);
                return 2;
            }
        } else if (opt_is(a, "--exposure")) {
            VAL("--exposure");
            if (!opt_float("--exposure", v, &exposure)) return 2;
            if (!(exposure > 0.0f)) {
                cli_error("--exposure must be a positive number (got %s)", v);
                return 2;
            }
        } else if (opt_is(a, "--threads")) {
            VAL("--threads");
            if (!opt_int("--threads", v, &p.threads)) return 2;
            if (p.threads < 0) {
                cli_error("--threads must be >= 0 (got %s)", v);
                return 2;
            }
        } else if (!strcmp(a, "--no-gather-area")) p.gather_area = 0;
        else if (opt_is(a, "--seed")) {
            VAL("--seed");
            if (!opt_u64("--seed", v, &p.seed)) return 2;
        } else if (a[0] == '-' && a[1]) {
            cli_error("unknown option '%s' (see evray still --help)", a);
            return 2;
        } else if (!scene_path) scene_path = a;
        else {
            cli_error("unexpected argument '%s'", a);
            return 2;
        }
    }
#undef VAL
    if (scene_path && demo) {
        cli_error("give a scene file or --scene NAME, not both");
        return 2;
    }
    if (!scene_path && !demo) {
        cli_error("still needs a scene (evray still SCENE or --scene NAME)");
        return 2;
    }
    if (cmp_path && !ref_path) {
        cli_error("--compare needs --reference");
        return 2;
    }
    if (cmp_path) p.gi = EVR_GI_NONE;
    if (!out && !pfm && !cmp_path) {
        cli_error("still needs an output image (-o OUT.png or OUT.pfm)");
        return 2;
    }
    if (out && !ends_with(out, ".png") && !ends_with(out, ".pfm")) {
        cli_error("-o: the image must end in .png or .pfm (got '%s')", out);
        return 2;
    }
    if (p.width > 16384 || p.height > 16384) {
        cli_error("--res: at most 16384x16384");
        return 2;
    }

    float *ref = NULL, *cmp = NULL;
    int rw = 0, rh = 0;
    if (ref_path) {
        if (!read_pfm(ref_path, &ref, &rw, &rh)) return 1;
        if (rw != p.width || rh != p.height) {
            cli_error("%s is %dx%d, the image is %dx%d (use the same --res)", ref_path, rw, rh,
                      p.width, p.height);
            free(ref);
            return 2;
        }
    }
    if (cmp_path) {
        int cw = 0, ch = 0;
        if (!read_pfm(cmp_path, &cmp, &cw, &ch)) {
            free(ref);
            return 1;
        }
        if (cw != p.width || ch != p.height) {
            cli_error("%s is %dx%d, the reference is %dx%d", cmp_path, cw, ch, p.width, p.height);
            free(ref);
            free(cmp);
            return 2;
        }
    }
    /* a path-traced reference is the one still image whose work has no natural bound */
    if (p.gi == EVR_GI_PATH && (double)p.width * p.height * p.spp > 1e12) {
        cli_error("--gi path: %dx%d pixels x %d paths is more than 1e12 paths", p.width, p.height,
                  p.spp);
        free(ref);
        free(cmp);
        return 2;
    }
    evr_scene *scene = cli_load_scene(scene_path, demo, 0, animation, strict, external, quiet);
    if (!scene) {
        free(ref);
        free(cmp);
        return 1;
    }
    evr_error err = {{0}};
    evr_still_image r;
    evr_status st = evr_still_image_render(scene, &p, &r, &err);
    if (st != EVR_OK) {
        cli_error("%s", err.msg);
        free(ref);
        free(cmp);
        evr_scene_release(scene);
        return st == EVR_ERR_ARG ? 2 : 1;
    }
    int rc = 0;
    if (cmp) { /* the image to compare replaces the render; direct part and regions stay */
        memcpy(r.rgb, cmp, (size_t)r.width * (size_t)r.height * 3 * sizeof(float));
        free(cmp);
        quiet = 1;
    }
    if (out && ends_with(out, ".png") && !write_png(out, r.rgb, r.width, r.height, exposure))
        rc = 1;
    if (out && ends_with(out, ".pfm") && !write_pfm(out, r.rgb, r.width, r.height)) {
        cli_error("cannot write %s", out);
        rc = 1;
    }
    if (pfm && !write_pfm(pfm, r.rgb, r.width, r.height)) {
        cli_error("cannot write %s", pfm);
        rc = 1;
    }
    if (!quiet) {
        static const char *const modes[3] = {"none", "photon", "path"};
        printf(
            "still: %dx%d at t = %g s, gi %s, %d threads: setup %.2f s, photons %.2f s, shading %.2f s\n",
            r.width, r.height, p.time, modes[p.gi], r.threads, r.seconds_setup, r.seconds_photons,
            r.seconds_shading);
        if (p.gi == EVR_GI_PATH)
            printf("path: %d paths per pixel, at most %d bounces\n", p.spp, p.max_bounces);
        if (p.gi == EVR_GI_PHOTON) {
            double stored = (double)r.photons_visible;
            printf(
                "photon: %llu paths, %llu stayed, %llu seen by the camera, %llu in the buffer, %llu collisions (%.2f%%); "
                "%d layers, gather radius %.4g, %.1f photons per estimate\n",
                (unsigned long long)r.photon_paths, (unsigned long long)r.photons_stayed,
                (unsigned long long)r.photons_visible, (unsigned long long)r.photons_inserted,
                (unsigned long long)r.photon_collisions,
                stored > 0 ? 100.0 * (double)r.photon_collisions / stored : 0.0, r.photon_layers,
                r.gather_radius, r.photons_per_estimate);
            if (stored > 0 && (double)r.photon_collisions > 0.03 * stored && r.photon_layers < 64)
                printf(
                    "photon: note: more than 3%% of the photons found their pixel full; --photon-layers %d keeps them\n",
                    r.photon_layers * 2);
        }
    }
    if (ref) compare(scene, &r, ref, region);
    free(ref);
    evr_still_image_free(&r);
    evr_scene_release(scene);
    return rc;
}
