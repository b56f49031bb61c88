/* evray bench: one simulation and one row of figures; the reference design's table (--suite
 * seed); how the cost per sample grows (--sweep, CSV and PNG plot). */
#include "commands.h"
#include "evray.h"
#include "evray_experimental.h"
#include "options.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

static void remove_run(const char *dir)
{
    char p[4200];
    int i;
    for (i = 0; evr_format_file(i); i++) {
        snprintf(p, sizeof p, "%s/%s", dir, evr_format_file(i));
        remove(p);
    }
    snprintf(p, sizeof p, "%s/run.json", dir);
    remove(p);
    rmdir(dir);
}

/* The figures of one run. */
typedef struct {
    evr_stats s;
    int width, height, samples_per_frame;
    double fps;         /* segments per simulated second */
    double temporal_us; /* mean time between a pixel's samples */
    double render_s;    /* device kernels on the GPU, else the render wait */
    double peak_mb;
    int skip;            /* change-driven sampling was on */
    int adaptive;        /* adaptive sampling (samples: those taken) */
    evr_load_times load; /* the scene's load */
} bench_figures;

/* Samples taken per pixel per simulated second. */
static double samples_per_pixel_s(const bench_figures *f)
{
    double d = (double)f->width * (double)f->height * f->s.sim_time;
    return d > 0.0 ? (double)f->s.samples / d : 0.0;
}

/* Reads the run's events (its first event file) into *ev. */
static int read_run_events(const char *dir, evr_event **ev, size_t *n)
{
    char p[4200];
    int i;
    for (i = 0; evr_format_file(i); i++) { /* every format reads back to the same events */
        evr_error err = {{0}};
        snprintf(p, sizeof p, "%s/%s", dir, evr_format_file(i));
        if (access(p, R_OK) != 0) continue;
        if (evr_events_read(p, ev, n, NULL, NULL, &err) == EVR_OK) return 1;
        cli_error("%s", err.msg);
        return 0;
    }
    cli_error("bench: the run wrote no event file to compare");
    return 0;
}

/* Runs cfg on scene, into a temporary folder unless keep (then into cfg->out_dir), and fills f;
 * with ev, also reads the run's events back. Returns the process exit code (0 ok; a message was
 * printed otherwise). */
static int bench_run_events(const evr_scene *scene, const evr_config *cfg_in, int keep,
                            bench_figures *f, evr_event **ev, size_t *nev)
{
    evr_config cfg = *cfg_in;
    char tmpdir[] = "/tmp/evray-bench-XXXXXX";
    evr_error err = {{0}};
    evr_sim *sim = NULL;
    evr_status st;
    int rc = 0;
    memset(f, 0, sizeof *f);
    if (!keep) {
        if (!mkdtemp(tmpdir)) {
            cli_error("cannot create a temporary folder");
            return 1;
        }
        cfg.out_dir = tmpdir;
        cfg.force = 1;
    }
    if ((st = evr_sim_new(scene, &cfg, &sim, &err)) != EVR_OK) {
        cli_error("%s", err.msg);
        if (!keep) rmdir(tmpdir);
        return st == EVR_ERR_ARG ? 2 : 1;
    }
    st = evr_sim_run(sim, NULL, NULL, &err);
    if (st != EVR_OK) {
        cli_error("%s", err.msg);
        rc = 1;
    } else {
        struct rusage ru;
        const evr_stats *s = evr_sim_stats(sim);
        cli_warn_photon_drops(s);
        getrusage(RUSAGE_SELF, &ru);
        f->s = *s;
        f->load = *evr_scene_load_times(scene);
        f->width = cfg.width;
        f->height = cfg.height;
        f->samples_per_frame = evr_config_samples_per_frame(&cfg);
        f->skip = !cfg.no_skip && cfg.sampling != EVR_SAMPLING_ADAPTIVE;
        f->adaptive = cfg.sampling == EVR_SAMPLING_ADAPTIVE;
        /* the set frame rate; else the scene's, as segments per simulated second (the last segment
         * may be partial, so this is approximate for short runs) */
        f->fps = cfg.fps > 0                                ? cfg.fps
                 : s->segments_total > 0 && s->sim_time > 0 ? s->segments_total / s->sim_time
                                                            : 0.0;
        f->temporal_us = f->fps > 0 ? 1e6 / (f->fps * f->samples_per_frame) : 0.0;
        if (f->adaptive)
            f->temporal_us = samples_per_pixel_s(f) > 0.0 ? 1e6 / samples_per_pixel_s(f) : 0.0;
        f->render_s = s->time_device > 0 ? s->time_device : s->time_render;
        f->peak_mb = (double)ru.ru_maxrss / 1024.0;
    }
    evr_sim_release(sim);
    if (rc == 0 && ev && !read_run_events(cfg.out_dir, ev, nev)) rc = 1;
    if (!keep) remove_run(tmpdir);
    return rc;
}

static int bench_run(const evr_scene *scene, const evr_config *cfg_in, int keep, bench_figures *f)
{
    return bench_run_events(scene, cfg_in, keep, f, NULL, NULL);
}

/* Where the set-up went, from the file to the first segment's plan (none of it in wall_s). */
static void print_setup(const bench_figures *f)
{
    const evr_load_times *l = &f->load;
    const evr_stats *s = &f->s;
    char cached[64] = "";
    if (s->bvh_trees_cached) /* the GPU BVH cache's trees: loaded, not built */
        snprintf(cached, sizeof cached, ", %d of %d trees from the cache", s->bvh_trees_cached,
                 s->bvh_trees);
    printf("set-up %.3f s: load %.3f (glTF checks %.3f, Assimp %.3f, materials and textures %.3f, "
           "meshes %.3f with tangents %.3f, the rest %.3f), before the backend %.3f, backend "
           "%.3f (BVH %.3f%s), first plan %.3f\n",
           l->total + s->time_setup_host + s->time_setup + s->time_first_plan, l->total,
           l->gltf_checks, l->assimp, l->materials, l->meshes, l->tangents, l->rest,
           s->time_setup_host, s->time_setup, s->time_setup_bvh, cached, s->time_first_plan);
}

static void print_row(const char *name, const bench_figures *f, int json)
{
    const evr_stats *s = &f->s;
    double w = s->wall_time > 0 ? s->wall_time : 1.0;
    if (json) {
        printf(
            "{\"scene\": \"%s\", \"backend\": \"%s\", \"device\": \"%s\", \"width\": %d, \"height\": %d, "
            "\"samples_per_frame\": %d, \"simulated_seconds\": %.6f, \"events\": %llu, \"wall_seconds\": %.4f, "
            "\"realtime_factor\": %.5f, \"samples_per_second\": %.6g, \"rays_per_second\": %.6g, "
            "\"temporal_resolution_us\": %.2f, \"unique_timestamps\": %llu, \"peak_host_mb\": %.1f, "
            "\"device_memory_mb\": %.1f, \"setup_seconds\": %.4f, \"render_seconds\": %.4f, "
            "\"sort_seconds\": %.4f, \"copy_seconds\": %.4f, \"write_seconds\": %.4f, "
            "\"skip\": %s, \"samples_traced\": %llu, \"traced_samples_per_second\": %.6g, "
            "\"equivalent_samples_per_second\": %.6g, \"rays\": %llu, \"pixels_skipped\": %llu, "
            "\"pixels_skipped_per_segment\": %.1f, \"sampling\": \"%s\", \"samples_per_pixel_per_second\": %.6g, "
            "\"photon_seconds\": %.4f, \"photons_stored\": %llu, \"photon_collisions\": %llu, \"photon_cells_changed\": %llu, "
            "\"photons_traced\": %llu, \"photons_reused\": %llu, \"device_seconds\": %.4f, ",
            name, s->backend, s->device, f->width, f->height, f->samples_per_frame, s->sim_time,
            (unsigned long long)(s->events_on + s->events_off), s->wall_time, s->realtime_factor,
            (double)s->samples / w, (double)s->rays / w, f->temporal_us,
            (unsigned long long)s->unique_timestamps, f->peak_mb,
            (double)s->device_memory / 1048576.0, s->time_setup, f->render_s, s->time_sort,
            s->time_copy, s->time_write, f->skip ? "true" : "false",
            (unsigned long long)s->samples_traced, (double)s->samples_traced / w,
            (double)s->samples / w, (unsigned long long)s->rays,
            (unsigned long long)s->pixels_skipped,
            s->segments_done > 0 ? (double)s->pixels_skipped / s->segments_done : 0.0,
            f->adaptive ? "adaptive" : "uniform", samples_per_pixel_s(f), s->time_photons,
            (unsigned long long)s->photons_stored, (unsigned long long)s->photon_collisions,
            (unsigned long long)s->photon_cells_changed, (unsigned long long)s->photons_traced,
            (unsigned long long)s->photons_reused, s->time_device);
        printf("\"load_seconds\": %.4f, \"load_gltf_checks_seconds\": %.4f, "
               "\"load_assimp_seconds\": %.4f, \"load_materials_seconds\": %.4f, "
               "\"load_meshes_seconds\": %.4f, \"load_tangents_seconds\": %.4f, "
               "\"setup_host_seconds\": %.4f, \"setup_bvh_seconds\": %.4f, "
               "\"bvh_trees\": %d, \"bvh_trees_cached\": %d, \"first_plan_seconds\": %.4f}\n",
               f->load.total, f->load.gltf_checks, f->load.assimp, f->load.materials,
               f->load.meshes, f->load.tangents, s->time_setup_host, s->time_setup_bvh,
               s->bvh_trees, s->bvh_trees_cached, s->time_first_plan);
    } else {
        char res[32], spf[16];
        /* adaptive sampling has no samples per frame: each pixel picks its own times */
        if (f->adaptive) snprintf(spf, sizeof spf, "ad");
        else snprintf(spf, sizeof spf, "%d", f->samples_per_frame);
        printf("%-8s %-5s %9s %4s %12s %9s %9s %12s %12s %9s %12s %9s %8s  %s\n", "scene", "bknd",
               "res", "spf", "events", "wall_s", "rt_factor", "samples/s", "rays/s", "dt_us",
               "unique_ts", "host_MB", "gpu_MB", "share render/sort/copy/write");
        snprintf(res, sizeof res, "%dx%d", f->width, f->height);
        printf(
            "%-8.8s %-5s %9s %4s %12llu %9.3f %9.4f %12.4g %12.4g %9.1f %12llu %9.1f %8.1f  %.2f/%.2f/%.2f/%.2f\n",
            name, s->backend, res, spf, (unsigned long long)(s->events_on + s->events_off),
            s->wall_time, s->realtime_factor, (double)s->samples / w, (double)s->rays / w,
            f->temporal_us, (unsigned long long)s->unique_timestamps, f->peak_mb,
            (double)s->device_memory / 1048576.0, f->render_s / w, s->time_sort / w,
            s->time_copy / w, s->time_write / w);
        printf("(%s; %.3f s simulated; setup %.2f s not in wall_s)\n", s->device, s->sim_time,
               s->time_setup);
        print_setup(f);
        if (f->adaptive) {
            printf(
                "adaptive sampling: %.4g samples taken (all traced), %.1f per pixel per simulated second "
                "(mean %.1f us apart; samples/s counts samples taken)\n",
                (double)s->samples, samples_per_pixel_s(f), f->temporal_us);
        } else if (f->skip) {
            double npix =
                (double)f->width * f->height * (s->segments_done > 0 ? s->segments_done : 1);
            printf(
                "change-driven sampling: %.1f%% of pixel-segments skipped (%.0f pixels per segment), "
                "%.4g samples traced (%.4g/s), %llu rays; equivalent samples/s %.4g (samples brute force "
                "takes / wall time)\n",
                100.0 * (double)s->pixels_skipped / npix,
                s->segments_done > 0 ? (double)s->pixels_skipped / s->segments_done : 0.0,
                (double)s->samples_traced, (double)s->samples_traced / w,
                (unsigned long long)s->rays, (double)s->samples / w);
        } else {
            printf("brute force (--no-skip): every sample traced\n");
        }
        if (s->photons_traced + s->photons_reused > 0)
            printf(
                "global illumination: photon passes %.3f s, %llu photon paths traced, %llu reused (their last paths met "
                "nothing that moved), %llu photons stored, %llu collisions\n",
                s->time_photons, (unsigned long long)s->photons_traced,
                (unsigned long long)s->photons_reused, (unsigned long long)s->photons_stored,
                (unsigned long long)s->photon_collisions);
    }
}

/* ---- --vs-brute: change-driven sampling against brute force, same build, same run ---- */

static size_t first_difference(const evr_event *a, size_t na, const evr_event *b, size_t nb)
{
    size_t i, n = na < nb ? na : nb;
    for (i = 0; i < n; i++)
        if (a[i].t != b[i].t || a[i].x != b[i].x || a[i].y != b[i].y || a[i].p != b[i].p) return i;
    return na == nb ? (size_t)-1 : n;
}

static int run_vs_brute(const evr_scene *scene, const evr_config *base, const char *name, int json)
{
    evr_config cfg = *base;
    bench_figures fs, fb;
    evr_event *es = NULL, *eb = NULL;
    size_t ns = 0, nb = 0, d;
    int rc;
    cfg.no_skip = 0;
    if ((rc = bench_run_events(scene, &cfg, 0, &fs, &es, &ns)) != 0) return rc;
    cfg.no_skip = 1;
    if ((rc = bench_run_events(scene, &cfg, 0, &fb, &eb, &nb)) != 0) {
        free(es);
        return rc;
    }
    print_row(name, &fs, json);
    print_row(name, &fb, json);
    d = first_difference(es, ns, eb, nb);
    if (json) {
        printf("{\"identical\": %s, \"events\": %zu, \"events_brute\": %zu, \"speedup\": %.4f}\n",
               d == (size_t)-1 ? "true" : "false", ns, nb,
               fs.s.wall_time > 0 ? fb.s.wall_time / fs.s.wall_time : 0.0);
    } else {
        printf("speedup over brute force: %.2fx (wall %.3f s vs %.3f s)\n",
               fs.s.wall_time > 0 ? fb.s.wall_time / fs.s.wall_time : 0.0, fs.s.wall_time,
               fb.s.wall_time);
        if (d == (size_t)-1) printf("events: identical (%zu events)\n", ns);
        else
            printf("events: DIFFERENT (%zu vs %zu events, first difference at event %zu)\n", ns, nb,
                   d);
    }
    free(es);
    free(eb);
    return d == (size_t)-1 ? 0 : 3;
}

/* ---- --suite seed: the rows of the reference design's Table 4.2 ---- */

static int run_suite(const evr_scene *scene, const evr_config *base, int json)
{
    static const struct {
        const char *name;
        double fps;
        int spf;
        int gi;
        const char *meaning;
    } rows[] = {
        {"Standard", 30.0, 10, 0, "10 samples per frame, 30 frames per simulated second"},
        {"Slow", 300.0, 10, 0,
         "animation at 0.1x speed: 10x the frames per simulated second, 10 samples each"},
        {"Extra", 30.0, 100, 0, "100 samples per frame"},
        {"Photon", 30.0, 10, 1, "Standard with global illumination (image-space photon mapping)"},
    };
    int i, rc;
    if (!json) {
        printf(
            "suite seed: eye scene, %dx%d, backend %s; every row simulates the whole 30 s animation (as the\n"
            "reference design's eye did) or --duration\n",
            base->width, base->height,
            base->backend == EVR_BACKEND_CPU    ? "cpu"
            : base->backend == EVR_BACKEND_CUDA ? "cuda"
                                                : "auto");
        printf("%-8s %5s %4s %10s %12s %9s %10s %12s %12s %8s\n", "row", "fps", "spf", "simulated",
               "events", "wall_s", "dt_ms", "unique_ts", "samples/s", "backend");
    } else {
        printf("[\n");
    }
    for (i = 0; i < (int)(sizeof rows / sizeof rows[0]); i++) {
        evr_config cfg = *base;
        bench_figures f;
        cfg.fps = rows[i].fps;
        cfg.samples_per_frame = rows[i].spf;
        cfg.gi = rows[i].gi;
        if ((rc = bench_run(scene, &cfg, 0, &f)) != 0) return rc;
        if (json) {
            printf(
                "  {\"row\": \"%s\", \"fps\": %g, \"samples_per_frame\": %d, \"width\": %d, \"height\": %d, "
                "\"simulated_seconds\": %.6f, \"events\": %llu, \"wall_seconds\": %.4f, \"temporal_resolution_us\": %.2f, "
                "\"unique_timestamps\": %llu, \"samples_per_second\": %.6g, \"backend\": \"%s\", \"device\": \"%s\"},\n",
                rows[i].name, rows[i].fps, rows[i].spf, f.width, f.height, f.s.sim_time,
                (unsigned long long)(f.s.events_on + f.s.events_off), f.s.wall_time, f.temporal_us,
                (unsigned long long)f.s.unique_timestamps, f.s.samples_per_second, f.s.backend,
                f.s.device);
        } else {
            char sim[32];
            snprintf(sim, sizeof sim, "%.3f s", f.s.sim_time);
            printf("%-8s %5g %4d %10s %12llu %9.2f %10.4f %12llu %12.4g %8s\n", rows[i].name,
                   rows[i].fps, rows[i].spf, sim,
                   (unsigned long long)(f.s.events_on + f.s.events_off), f.s.wall_time,
                   f.temporal_us / 1000.0, (unsigned long long)f.s.unique_timestamps,
                   f.s.samples_per_second, f.s.backend);
        }
        fflush(stdout);
    }
    if (json) {
        printf("  {\"row\": \"end\"}\n]\n");
    } else {
        printf(
            "rows: Standard = 10 samples per frame at 30 fps; Slow = the reference's animation at 0.1x speed,\n"
            "i.e. 10x the frames (300 fps) of 10 samples each, timestamps kept in animation time (divide the\n"
            "reference's by 10 to compare); Extra = 100 samples per frame at 30 fps. Slow and Extra sample each\n"
            "pixel equally densely (dt_ms = 1 / (fps x spf)); they differ in segments, i.e. host round trips.\n");
    }
    return 0;
}

/* ---- --sweep res|samples|triangles|instances ---- */

/* extra_head (NULL: none) names columns appended to every row from extra[i] (",a,b"). */
static int write_sweep(const char *dir, const char *kind, const char *qname, const double *q,
                       const bench_figures *f, int n, const char *scene_name,
                       const char *extra_head, char (*extra)[200])
{
    char path[4200], title[200], xlabel[200];
    double *ns = malloc((size_t)n * sizeof *ns);
    FILE *fp;
    int i;
    evr_error err = {{0}};
    if (!ns) {
        cli_error("out of memory");
        return 1;
    }
    snprintf(path, sizeof path, "%s/sweep_%s.csv", dir, kind);
    if (!(fp = fopen(path, "w"))) {
        cli_error("cannot write %s", path);
        free(ns);
        return 1;
    }
    fprintf(
        fp,
        "%s,width,height,samples_per_frame,samples,wall_s,ns_per_sample,samples_per_s,events%s\n",
        qname, extra_head ? extra_head : "");
    for (i = 0; i < n; i++) {
        ns[i] = f[i].s.samples > 0 ? f[i].s.wall_time * 1e9 / (double)f[i].s.samples : 0.0;
        fprintf(fp, "%.10g,%d,%d,%d,%llu,%.6f,%.4f,%.6g,%llu%s\n", q[i], f[i].width, f[i].height,
                f[i].samples_per_frame, (unsigned long long)f[i].s.samples, f[i].s.wall_time, ns[i],
                f[i].s.samples_per_second,
                (unsigned long long)(f[i].s.events_on + f[i].s.events_off),
                extra_head ? extra[i] : "");
    }
    if (fclose(fp) != 0) {
        cli_error("cannot write %s", path);
        free(ns);
        return 1;
    }
    printf("wrote %s\n", path);
    {
        evr_plot_series s;
        evr_plot_spec spec;
        memset(&s, 0, sizeof s);
        memset(&spec, 0, sizeof spec);
        s.x = q;
        s.y = ns;
        s.n = (size_t)n;
        s.color[2] = 200;
        s.markers = 1;
        snprintf(title, sizeof title, "evray bench --sweep %s (%s, %s)", kind, scene_name,
                 n ? f[0].s.backend : "");
        snprintf(xlabel, sizeof xlabel, "%s", qname);
        spec.width = 800;
        spec.height = 480;
        spec.title = title;
        spec.xlabel = xlabel;
        spec.ylabel = "wall time per sample (ns)";
        spec.y_from_zero = 1;
        snprintf(path, sizeof path, "%s/sweep_%s.png", dir, kind);
        if (evr_plot_lines_png(path, &spec, &s, 1, &err) != EVR_OK) {
            cli_error("%s", err.msg);
            free(ns);
            return 1;
        }
        printf("wrote %s\n", path);
    }
    free(ns);
    return 0;
}

static int run_sweep(const evr_scene *scene, const evr_config *base, const char *kind,
                     const char *dir, int max_w, int max_h, const char *scene_name)
{
    static const int res[][2] = {{80, 60},   {160, 120}, {320, 240},
                                 {640, 360}, {960, 540}, {1280, 720}};
    static const int spfs[] = {1, 2, 5, 10, 20, 50};
    bench_figures f[8];
    double q[8];
    int n = 0, i, rc, is_res = !strcmp(kind, "res");
    int count = is_res ? (int)(sizeof res / sizeof res[0]) : (int)(sizeof spfs / sizeof spfs[0]);
    printf("sweep %s: %s, %.3g s per run\n", kind, scene_name, base->duration);
    printf("%12s %10s %4s %12s %9s %10s %12s %12s\n", is_res ? "pixels" : "spf", "res", "spf",
           "samples", "wall_s", "ns/sample", "samples/s", "events");
    for (i = 0; i < count; i++) {
        evr_config cfg = *base;
        char rs[32];
        if (is_res) {
            if (res[i][0] > max_w || res[i][1] > max_h) continue;
            cfg.width = res[i][0];
            cfg.height = res[i][1];
            q[n] = (double)cfg.width * cfg.height;
        } else {
            cfg.samples_per_frame = spfs[i];
            q[n] = spfs[i];
        }
        if ((rc = bench_run(scene, &cfg, 0, &f[n])) != 0) return rc;
        snprintf(rs, sizeof rs, "%dx%d", cfg.width, cfg.height);
        printf("%12.0f %10s %4d %12llu %9.3f %10.2f %12.4g %12llu\n", q[n], rs,
               cfg.samples_per_frame, (unsigned long long)f[n].s.samples, f[n].s.wall_time,
               f[n].s.samples ? f[n].s.wall_time * 1e9 / (double)f[n].s.samples : 0.0,
               f[n].s.samples_per_second,
               (unsigned long long)(f[n].s.events_on + f[n].s.events_off));
        fflush(stdout);
        n++;
    }
    if (n == 0) {
        cli_error(
            "--sweep res: no resolution fits within --sweep-max-res %dx%d (the smallest is 80x60)",
            max_w, max_h);
        return 2;
    }
    return write_sweep(dir, kind, is_res ? "pixels" : "samples_per_frame", q, f, n, scene_name,
                       NULL, NULL);
}

/* --sweep triangles: the city's buildings tessellated finer (detail 1, 2, 3, 4, 6, 8 up to
 * max_detail; 4096 buildings); --sweep instances: more buildings (64 .. 65536 up to
 * max_buildings; detail 1). Each point generates and loads its city, then runs as any sweep.
 * The static instances are instanced at every point (EVR_STATIC_BAKE_LIMIT=0 unless set), so
 * that small points are not baked into one tree while large ones are. */
static int run_city_sweep(const evr_config *base, const char *kind, const char *dir, int max_detail,
                          int max_buildings)
{
    static const int details[] = {1, 2, 3, 4, 6, 8};
    static const int counts[] = {64, 256, 1024, 4096, 16384, 65536};
    bench_figures f[8];
    double q[8];
    char extra[8][200];
    int n = 0, i, rc = 0, is_tri = !strcmp(kind, "triangles");
    int count = is_tri ? (int)(sizeof details / sizeof details[0])
                       : (int)(sizeof counts / sizeof counts[0]);
    setenv("EVR_STATIC_BAKE_LIMIT", "0", 0);
    printf(
        "sweep %s: city, %s, %.3g s per run, %dx%d, %d samples per frame (static instances %s)\n",
        kind, is_tri ? "4096 buildings, detail growing" : "detail 1, buildings growing",
        base->duration, base->width, base->height, base->samples_per_frame,
        strcmp(getenv("EVR_STATIC_BAKE_LIMIT"), "0") ? "as EVR_STATIC_BAKE_LIMIT says"
                                                     : "instanced, not baked");
    printf("%7s %9s %11s %13s %7s %7s %12s %9s %10s %12s %10s\n", "detail", "buildings",
           "mesh_tris", "scene_tris", "load_s", "setup_s", "samples", "wall_s", "ns/sample",
           "samples/s", "events");
    for (i = 0; i < count; i++) {
        evr_config cfg = *base;
        evr_scene *scene = NULL;
        evr_error err = {{0}};
        uint64_t mesh_tris = 0, scene_tris = 0;
        double load_s;
        int ninst, detail = is_tri ? details[i] : EVR_CITY_DETAIL,
                   buildings = is_tri ? EVR_CITY_BUILDINGS : counts[i];
        if (is_tri ? detail > max_detail : buildings > max_buildings) continue;
        const double t0 = evr_seconds();
        if (evr_demo_city_load(detail, buildings, &scene, &err) != EVR_OK) {
            cli_error("%s", err.msg);
            return 1;
        }
        load_s = evr_seconds() - t0;
        evr_scene_triangles(scene, &mesh_tris, &scene_tris);
        ninst = evr_scene_num_instances(scene);
        rc = bench_run(scene, &cfg, 0, &f[n]);
        evr_scene_release(scene);
        if (rc != 0) return rc;
        q[n] = is_tri ? (double)scene_tris : (double)ninst;
        snprintf(extra[n], sizeof extra[n], ",%d,%d,%llu,%llu,%.4f,%.4f", detail, buildings,
                 (unsigned long long)mesh_tris, (unsigned long long)scene_tris, load_s,
                 f[n].s.time_setup);
        printf("%7d %9d %11llu %13llu %7.2f %7.2f %12llu %9.3f %10.2f %12.4g %10llu\n", detail,
               buildings, (unsigned long long)mesh_tris, (unsigned long long)scene_tris, load_s,
               f[n].s.time_setup, (unsigned long long)f[n].s.samples, f[n].s.wall_time,
               f[n].s.samples ? f[n].s.wall_time * 1e9 / (double)f[n].s.samples : 0.0,
               f[n].s.samples_per_second,
               (unsigned long long)(f[n].s.events_on + f[n].s.events_off));
        fflush(stdout);
        n++;
    }
    if (n == 0) {
        cli_error("--sweep %s: no point fits within %s", kind,
                  is_tri ? "--sweep-max-detail" : "--sweep-max-buildings");
        return 2;
    }
    return write_sweep(dir, kind, is_tri ? "triangles" : "instances", q, f, n, "city",
                       ",detail,buildings,mesh_triangles,scene_triangles,load_s,setup_s", extra);
}

static int bench_usage(void)
{
    puts(
        "usage: evray bench [--scene NAME | SCENE] [render options] [--vs-brute] [--json]\n"
        "       evray bench --suite seed [--res WxH] [--duration S] [--backend B] [--json]\n"
        "       evray bench --sweep res|samples [--scene NAME] [--duration S] [--backend B] [-o DIR]\n"
        "                   [--sweep-max-res WxH]\n"
        "       evray bench --sweep triangles|instances [--res WxH] [--duration S] [--backend B] [-o DIR]\n"
        "                   [--sweep-max-detail D] [--sweep-max-buildings N]\n\n"
        "Runs one simulation (no previews; into a temporary folder unless -o is given) and prints\n"
        "one row: events, processing time, real-time factor, samples/s, rays/s, the mean time\n"
        "between a pixel's samples (temporal resolution), unique timestamps, peak host and GPU\n"
        "memory, and the share of the wall time spent rendering, sorting, copying and writing\n"
        "(writing runs on its own thread, overlapping rendering).\n"
        "Render options are those of evray render (--res, --samples-per-frame, --duration,\n"
        "--backend, --format, --no-skip, --animation, ...). With change-driven sampling (the default) the row\n"
        "also gives the share of pixel-segments skipped, the samples actually traced and the\n"
        "equivalent samples/s (samples brute force takes / wall time; samples/s is that figure).\n"
        "With --sampling adaptive, samples are those taken (every one traced): the row adds\n"
        "the samples taken per pixel per simulated second, and dt_us is their mean spacing.\n"
        "--vs-brute     runs the row twice, with change-driven sampling and with --no-skip, prints\n"
        "               both, the speedup, and whether the events are identical (exit 3 if not)\n\n"
        "--suite seed   the rows of the reference design's Table 4.2 on the eye scene, default 1280x720\n"
        "               over the whole 30 s animation (as the reference design's; --duration\n"
        "               shortens it, --res changes the size). Each row prints the simulated time,\n"
        "               total events, processing (wall) time, temporal resolution (mean time between a\n"
        "               pixel's samples), unique timestamps and samples/s:\n"
        "                 Standard  10 samples per frame at 30 fps (3.3 ms between a pixel's samples)\n"
        "                 Slow      the reference played its animation at 0.1x speed with the same\n"
        "                           frames per (wall-clock) second: 10x the frames per second of\n"
        "                           scene time. Here: 300 fps, 10 samples per frame (0.33 ms);\n"
        "                           timestamps stay in scene time\n"
        "                 Extra     100 samples per frame at 30 fps (0.33 ms): the same sampling\n"
        "                           density as Slow (samples are per pixel, spread over each frame)\n"
        "                           but 10x fewer segments, i.e. fewer host round trips\n"
        "                 Photon    Standard with --gi photon (image-space photon mapping)\n"
        "--sweep KIND   a series of short runs (default 0.2 s each) growing one quantity; prints the\n"
        "               rows and writes DIR/sweep_KIND.csv (quantity, size, samples per frame, samples,\n"
        "               wall s, ns per sample, samples/s, events) and DIR/sweep_KIND.png (time per\n"
        "               sample against the quantity); -o DIR defaults to the current folder.\n"
        "                 res       80x60, 160x120, 320x240, 640x360, 960x540, 1280x720 (up to\n"
        "                           --sweep-max-res WxH), at --samples-per-frame (default 10)\n"
        "                 samples   1, 2, 5, 10, 20, 50 samples per frame at --res (default 346x260)\n"
        "                 triangles the city scene (4096 buildings) with its buildings tessellated\n"
        "                           finer: detail 1, 2, 3, 4, 6, 8 (up to --sweep-max-detail, default\n"
        "                           6; a building's triangles grow as detail^2, its shape unchanged);\n"
        "                           the quantity is the scene's (instanced) triangles\n"
        "                 instances the city at detail 1 with 64, 256, 1024, 4096, 16384, 65536\n"
        "                           buildings (up to --sweep-max-buildings, default 16384)\n"
        "               triangles and instances (quantity: the scene's triangles, instances) add the\n"
        "               columns detail, buildings, mesh_triangles (distinct), scene_triangles\n"
        "               (instanced; the ground is one more instance), load_s (generate and\n"
        "               import) and setup_s; they instance the static buildings at every point\n"
        "               (EVR_STATIC_BAKE_LIMIT=0 unless set; see docs/benchmarks.md).");
    return 0;
}

int cmd_bench(int argc, char **argv)
{
    evr_config cfg;
    render_options ro;
    const char *scene_path = NULL, *demo = "eye", *suite = NULL, *sweep = NULL, *v,
               *animation = NULL;
    int json = 0, keep = 0, i, r, set_res = 0, set_spf = 0, set_fps = 0, set_dur = 0, max_w = 1280,
        max_h = 720;
    int set_scene = 0, vs_brute = 0;
    int max_detail = 6, max_buildings = 16384, city_sweep = 0;
    evr_config_defaults(&cfg);
    cfg.preview_window = 0.0;
    if (!render_options_init(&ro, &cfg, 1, argc)) return 1;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            render_options_free(&ro);
            return bench_usage();
        }
        if (opt_is(a, "--res") || opt_is(a, "--sensor")) set_res = 1;
        if (opt_is(a, "--samples-per-frame")) set_spf = 1;
        if (opt_is(a, "--fps")) set_fps = 1;
        if (opt_is(a, "--duration")) set_dur = 1;
        if (!strcmp(a, "--json")) json = 1;
        else if (!strcmp(a, "--vs-brute")) vs_brute = 1;
        else if (opt_is(a, "--scene")) {
            set_scene = 1;
            if (!(demo = opt_value(argc, argv, &i, "--scene"))) {
                render_options_free(&ro);
                return 2;
            }
        } else if ((r = cli_is_animation_option(argc, argv, &i, &animation)) != 0) {
            if (r < 0) {
                render_options_free(&ro);
                return 2;
            }
        } else if (opt_is(a, "--suite")) {
            if (!(suite = opt_value(argc, argv, &i, "--suite"))) {
                render_options_free(&ro);
                return 2;
            }
        } else if (opt_is(a, "--sweep")) {
            if (!(sweep = opt_value(argc, argv, &i, "--sweep"))) {
                render_options_free(&ro);
                return 2;
            }
        } else if (opt_is(a, "--sweep-max-detail")) {
            if (!(v = opt_value(argc, argv, &i, "--sweep-max-detail")) ||
                !opt_int("--sweep-max-detail", v, &max_detail)) {
                render_options_free(&ro);
                return 2;
            }
        } else if (opt_is(a, "--sweep-max-buildings")) {
            if (!(v = opt_value(argc, argv, &i, "--sweep-max-buildings")) ||
                !opt_int("--sweep-max-buildings", v, &max_buildings)) {
                render_options_free(&ro);
                return 2;
            }
        } else if (opt_is(a, "--sweep-max-res")) {
            if (!(v = opt_value(argc, argv, &i, "--sweep-max-res")) ||
                !opt_size("--sweep-max-res", v, &max_w, &max_h)) {
                render_options_free(&ro);
                return 2;
            }
        } else if ((r = parse_render_option(argc, argv, &i, &ro)) < 0) {
            render_options_free(&ro);
            return 2;
        } else if (r > 0) {
            if (!strcmp(a, "-o") || opt_is(a, "--out")) keep = 1;
        } else if (a[0] == '-' && a[1]) {
            cli_error("bench: unknown option '%s'", a);
            render_options_free(&ro);
            return 2;
        } else if (!scene_path) scene_path = a;
        else {
            cli_error("bench: unexpected argument '%s'", a);
            render_options_free(&ro);
            return 2;
        }
    }
    r = render_options_finish(&ro, argc, argv);
    cfg = ro.cfg;
    render_options_free(&ro);
    if (!r) return 2;
    if (suite && sweep) {
        cli_error("bench: --suite and --sweep cannot be combined");
        return 2;
    }
    if (vs_brute && (suite || sweep || keep || cfg.no_skip)) {
        cli_error(
            "bench: --vs-brute runs one row twice (with and without skipping); drop --suite, --sweep, -o and --no-skip");
        return 2;
    }
    if (suite) {
        if (strcmp(suite, "seed")) {
            cli_error("--suite: unknown suite '%s' (seed)", suite);
            return 2;
        }
        if (scene_path || set_scene || animation) {
            cli_error("--suite seed runs the eye scene; drop --scene/SCENE/--animation");
            return 2;
        }
        if (set_spf || set_fps) {
            cli_error("--suite seed sets --samples-per-frame and --fps per row; drop them");
            return 2;
        }
        if (keep) {
            cli_error("--suite seed writes no run folder; drop -o");
            return 2;
        }
        if (!set_res) {
            cfg.width = 1280;
            cfg.height = 720;
        }
    }
    if (sweep) {
        city_sweep = !strcmp(sweep, "triangles") || !strcmp(sweep, "instances");
        if (strcmp(sweep, "res") && strcmp(sweep, "samples") && !city_sweep) {
            cli_error("--sweep: unknown kind '%s' (res, samples, triangles, instances)", sweep);
            return 2;
        }
        if (city_sweep && (scene_path || set_scene || animation)) {
            cli_error("--sweep %s grows the city scene itself; drop --scene/SCENE/--animation",
                      sweep);
            return 2;
        }
        if (!strcmp(sweep, "res") && set_res) {
            cli_error("--sweep res sets the resolution; use --sweep-max-res to cap it");
            return 2;
        }
        if (!strcmp(sweep, "samples") && set_spf) {
            cli_error("--sweep samples sets --samples-per-frame itself");
            return 2;
        }
        if (!set_dur) cfg.duration = 0.2;
    }
    if (city_sweep) {
        const char *dir = keep && cfg.out_dir ? cfg.out_dir : ".";
        cfg.out_dir = NULL;
        return run_city_sweep(&cfg, sweep, dir, max_detail, max_buildings);
    }
    /* the row goes to stdout; the loader's notice (clips left out) to stderr */
    evr_scene *scene = cli_load_scene(scene_path, demo, 0, animation, 0, 0, 0);
    if (!scene) return 1;
    int rc;
    if (suite) {
        rc = run_suite(scene, &cfg, json);
    } else if (sweep) {
        const char *dir = keep && cfg.out_dir ? cfg.out_dir : ".";
        cfg.out_dir = NULL;
        rc = run_sweep(scene, &cfg, sweep, dir, max_w, max_h, scene_path ? scene_path : demo);
    } else if (vs_brute) {
        rc = run_vs_brute(scene, &cfg, scene_path ? scene_path : demo, json);
    } else {
        bench_figures f;
        rc = bench_run(scene, &cfg, keep, &f);
        if (rc == 0) print_row(scene_path ? scene_path : demo, &f, json);
    }
    evr_scene_release(scene);
    return rc;
}
