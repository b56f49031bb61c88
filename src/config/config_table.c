/* The rows of the configuration table (config_table.h says what each column means), in the
 * order of evray render --help; json_rank gives the order of run.json's config object. */
#include "config/config_table.h"
#include "evray_experimental.h"
#include "io/event_formats.h"
#include "scene/camera_path.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define F(field) offsetof(evr_config, field)
#define NO_LIMIT HUGE_VAL
/* below this a threshold makes thousands of events per unit of log intensity */
#define EVR_MIN_THRES 1e-3

/* ---- when a setting matters ---- */
static int is_adaptive(const evr_config *c) { return c->sampling == EVR_SAMPLING_ADAPTIVE; }
static int is_refine(const evr_config *c) { return evr_config_sampling(c) == EVR_SAMPLING_REFINE; }
static int has_gi(const evr_config *c) { return c->gi != 0; }
static int has_frames(const evr_config *c) { return c->frames_out != NULL; }
static int has_camera_path(const evr_config *c) { return c->camera_path != NULL; }
static int has_look_from(const evr_config *c) { return c->look_from_set; }
static int has_look_at(const evr_config *c) { return c->look_at_set; }
static int has_fov(const evr_config *c) { return c->fov > 0.0; }
static int has_labels(const evr_config *c) { return c->labels_fps > 0.0; }

/* ---- values that are not one field's ---- */
static void json_scene(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    evr_json_string(j, r->scene);
}
static void json_camera(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    evr_json_string(j, r->camera);
}
static void json_duration(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    evr_json_number(j, r->duration);
}
static void json_fps(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    evr_json_number(j, r->fps);
}
static void json_backend(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    evr_json_string(j, r->backend);
}
static void json_max_dt(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    evr_json_number(j, fmax(c->max_dt > 0.0 ? c->max_dt : 1.0 / r->fps, c->min_dt));
}
static void json_sampling(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    const evr_sampling s = evr_config_sampling(c);
    evr_json_string(j, s == EVR_SAMPLING_REFINE     ? "refine"
                       : s == EVR_SAMPLING_ADAPTIVE ? "adaptive"
                                                    : "uniform, per-pixel phase");
}
static void json_samples_per_frame(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    evr_json_number(j, evr_config_samples_per_frame(c));
}
static void json_frames_fps(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    evr_json_number(j, c->frames_fps > 0.0 ? c->frames_fps : r->fps);
}
static void json_vec3(evr_json *j, const double v[3])
{
    evr_json_begin_array(j);
    for (int k = 0; k < 3; k++) evr_json_number(j, v[k]);
    evr_json_end_array(j);
}
static void json_look_from(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    json_vec3(j, c->look_from);
}
static void json_look_at(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    json_vec3(j, c->look_at);
}
static void json_formats(evr_json *j, const evr_config *c, const evr_config_run *r)
{
    int k, count;
    const evr_event_format *const *formats = evr_event_formats(&count);
    evr_json_begin_array(j);
    for (k = 0; k < count; k++)
        if (c->formats & (1 << k)) evr_json_string(j, formats[k]->name);
    evr_json_end_array(j);
}

/* ---- options that set more than their field, or check more than a range ---- */
#define FAIL(...)                                         \
    do {                                                  \
        snprintf(err->msg, sizeof err->msg, __VA_ARGS__); \
        return EVR_ERR_ARG;                               \
    } while (0)

/* 0 turns previews off; a window shorter than a millisecond would make a file per event */
static evr_status check_preview_window(const evr_config *c, evr_error *err)
{
    if (c->preview_window > 0.0 && c->preview_window < 1e-3)
        FAIL("preview window must be 0 (no previews) or at least 0.001 seconds (got %g)",
             c->preview_window);
    return EVR_OK;
}

static evr_status parse_res(evr_config *c, const char *v, evr_error *err)
{
    return evr_parse_size("--res", v, &c->width, &c->height, err);
}
static evr_status parse_thres(evr_config *c, const char *v, evr_error *err)
{
    evr_status st = evr_parse_float("--thres", v, &c->pos_thres, err);
    if (st == EVR_OK) c->neg_thres = c->pos_thres;
    return st;
}
static evr_status parse_no_preview(evr_config *c, const char *v, evr_error *err)
{
    c->preview = EVR_PREVIEW_NONE;
    return EVR_OK;
}
static evr_status parse_formats(evr_config *c, const char *v, evr_error *err)
{
    return evr_event_formats_parse("--format", v, &c->formats, err);
}
static evr_status parse_frames_out(evr_config *c, const char *v, evr_error *err)
{
    if (!v[0]) FAIL("--frames-out needs a folder");
    c->frames_out = v;
    return EVR_OK;
}
static evr_status parse_event_capacity(evr_config *c, const char *v, evr_error *err)
{
    uint64_t cap;
    evr_status st = evr_parse_u64("--gpu-event-capacity", v, &cap, err);
    if (st == EVR_OK)
        c->gpu_event_capacity = cap > ((uint64_t)1 << 40) ? ((int64_t)1 << 40) : (int64_t)cap;
    return st;
}
static evr_status parse_sensor(evr_config *c, const char *v, evr_error *err)
{
    const char *name = evr_sensor_canonical(v);
    char list[128];
    if (!name) FAIL("--sensor: unknown sensor '%s' (%s)", v, evr_sensor_list(list, sizeof list));
    c->sensor = name;
    return EVR_OK;
}

/* X,Y,Z: three finite numbers. */
static evr_status parse_vec3(const char *opt, const char *v, double out[3], evr_error *err)
{
    const char *p = v;
    for (int k = 0; k < 3; k++) {
        char *end;
        errno = 0;
        out[k] = strtod(p, &end);
        if (end == p || errno || !isfinite(out[k]) || *end != (k < 2 ? ',' : 0))
            FAIL("%s expects X,Y,Z (three numbers, scene units), got '%s'", opt, v);
        p = end + 1;
    }
    return EVR_OK;
}
static evr_status parse_look_from(evr_config *c, const char *v, evr_error *err)
{
    evr_status st = parse_vec3("--look-from", v, c->look_from, err);
    if (st == EVR_OK) c->look_from_set = 1;
    return st;
}
static evr_status parse_look_at(evr_config *c, const char *v, evr_error *err)
{
    evr_status st = parse_vec3("--look-at", v, c->look_at, err);
    if (st == EVR_OK) c->look_at_set = 1;
    return st;
}
/* The path's syntax (its file is read when a run starts, evr_camera_rig_init). */
static evr_status check_camera_path(const evr_config *c, evr_error *err)
{
    evr_camera_path p;
    evr_status st = evr_camera_path_parse(c->camera_path, 0, &p, err);
    evr_camera_path_free(&p);
    return st;
}
static evr_status check_look(const evr_config *c, evr_error *err)
{
    for (int k = 0; k < 3; k++)
        if ((c->look_from_set && !isfinite(c->look_from[k])) ||
            (c->look_at_set && !isfinite(c->look_at[k])))
            FAIL("look from and look at must be finite points");
    if (c->look_from_set && c->look_at_set && c->look_from[0] == c->look_at[0] &&
        c->look_from[1] == c->look_at[1] && c->look_from[2] == c->look_at[2])
        FAIL("--look-from and --look-at are the same point: the camera would look nowhere");
    return EVR_OK;
}

static evr_status check_resolution(const evr_config *c, evr_error *err)
{
    if (c->width < 1 || c->height < 1 || c->width > 65535 || c->height > 65535)
        FAIL("resolution %dx%d is out of range (1 to 65535 pixels a side)", c->width, c->height);
    if ((double)c->width * (double)c->height > 1e9)
        FAIL("resolution %dx%d is too large", c->width, c->height);
    return EVR_OK;
}
static evr_status check_max_dt(const evr_config *c, evr_error *err)
{
    if (!(c->max_dt <= 1.0) || c->max_dt < 0.0 || !isfinite(c->max_dt) ||
        (c->max_dt > 0.0 && c->max_dt < c->min_dt))
        FAIL("max dt must be between min dt (%g s) and 1 s, or 0 for one segment (got %g)",
             c->min_dt, c->max_dt);
    return EVR_OK;
}
static evr_status check_sampling(const evr_config *c, evr_error *err)
{
    if (c->sampling == EVR_SAMPLING_REFINE && c->gi)
        FAIL("--sampling refine does not take --gi yet: use --sampling uniform");
    return EVR_OK;
}
static evr_status check_sensor(const evr_config *c, evr_error *err)
{
    char list[128];
    if (c->sensor && !evr_sensor_canonical(c->sensor))
        FAIL("unknown sensor '%s' (%s)", c->sensor, evr_sensor_list(list, sizeof list));
    return EVR_OK;
}
static evr_status check_time_res(const evr_config *c, evr_error *err)
{
    if (!(c->time_res >= 1e-6 * (1.0 - 1e-9)) || !(c->time_res <= 0.1) ||
        fabs(c->time_res * 1e6 - floor(c->time_res * 1e6 + 0.5)) > 1e-6 * c->time_res * 1e6)
        FAIL(
            "timestamp resolution must be a whole number of microseconds from 1e-6 to 0.1 s (got %g)",
            c->time_res);
    return EVR_OK;
}
static evr_status check_out_dir(const evr_config *c, evr_error *err)
{
    if (!c->out_dir || !c->out_dir[0]) FAIL("no output folder given");
    return EVR_OK;
}
static evr_status check_formats(const evr_config *c, evr_error *err)
{
    /* 0: no event file, for a run whose events go to a sink (evr_sim_set_sink) */
    if (c->formats & ~evr_event_formats_all()) FAIL("no valid output format selected");
    return EVR_OK;
}
static evr_status check_frames_out(const evr_config *c, evr_error *err)
{
    if (c->frames_out && !c->frames_out[0]) FAIL("frames folder is an empty path");
    return EVR_OK;
}

static evr_status check_bvh_cache(const evr_config *c, evr_error *err)
{
    struct stat sb;
    if (!c->bvh_cache || strcmp(c->bvh_cache, "auto") == 0 || strcmp(c->bvh_cache, "off") == 0)
        return EVR_OK;
    if (!c->bvh_cache[0]) FAIL("--bvh-cache is an empty path");
    if (stat(c->bvh_cache, &sb) == 0 && !S_ISDIR(sb.st_mode))
        FAIL("--bvh-cache: '%s' is not a folder", c->bvh_cache);
    return EVR_OK;
}

static void help_formats(char *buf, size_t n)
{
    int k, count;
    size_t len = 0;
    const evr_event_format *const *formats = evr_event_formats(&count);
    buf[0] = 0;
    for (k = 0; k < count && len < n; k++)
        len += (size_t)snprintf(buf + len, n - len, "%s, ", formats[k]->name);
    if (len >= 2 && len < n) buf[len - 2] = 0;
    snprintf(buf + strlen(buf), n - strlen(buf), " or all, comma-separated (default %s)",
             formats[0]->name);
}

/* ---- choices ---- */
static const evr_opt_choice sampling_choices[] = {
    {"uniform", EVR_SAMPLING_UNIFORM, "uniform, per-pixel phase", NULL},
    {"adaptive", EVR_SAMPLING_ADAPTIVE, "adaptive", NULL},
    {"refine", EVR_SAMPLING_REFINE, "refine", NULL},
    {"auto", EVR_SAMPLING_AUTO, "auto", NULL},
    {NULL, -1, NULL, NULL}};
static const evr_opt_choice backend_choices[] = {{"auto", EVR_BACKEND_AUTO, "auto", NULL},
                                                 {"cpu", EVR_BACKEND_CPU, "cpu", NULL},
                                                 {"cuda", EVR_BACKEND_CUDA, "cuda", NULL},
                                                 {NULL, -1, NULL, NULL}};
static const evr_opt_choice gpu_bvh_choices[] = {{NULL, 0, "default", NULL},
                                                 {"bvh4", 4, "bvh4", NULL},
                                                 {"cw8", 8, "cw8", NULL},
                                                 {NULL, -1, NULL, NULL}};
static const evr_opt_choice skip_choices[] = {/* no_skip's names in run.json */
                                              {NULL, 0, "exact", NULL},
                                              {NULL, 1, "off", NULL},
                                              {NULL, -1, NULL, NULL}};
static const evr_opt_choice preview_choices[] = {{"video", EVR_PREVIEW_VIDEO, "video", NULL},
                                                 {"png", EVR_PREVIEW_PNG, "png", NULL},
                                                 {"none", EVR_PREVIEW_NONE, "none", NULL},
                                                 {NULL, -1, NULL, NULL}};
static const evr_opt_choice gi_choices[] = {
    {"none", 0, "none", NULL},
    {"photon", 1, "photon", NULL},
    {"path", 0, NULL, "--gi path renders one image: use evray still (render takes none or photon)"},
    {NULL, -1, NULL, NULL}};

static const evr_config_option table[] = {
    {.name = "scene", .json = "scene", .json_rank = 1, .json_value = json_scene},

    /* ---- output ---- */
    {.name = "out_dir",
     .type = EVR_OPT_STRING,
     .offset = F(out_dir),
     .def_text = "evray-out",
     .check = check_out_dir,
     .flag = "--out",
     .alias = "-o",
     .section = "output",
     .label = "-o, --out DIR",
     .help = "run folder (default ./evray-out)"},
    {.name = "force",
     .type = EVR_OPT_FLAG,
     .offset = F(force),
     .flag = "--force",
     .label = "--force",
     .help = "overwrite a non-empty run folder"},
    {.name = "formats",
     .type = EVR_OPT_INT,
     .offset = F(formats),
     .def = EVR_FORMAT_H5,
     .check = check_formats,
     .flag = "--format",
     .parse = parse_formats,
     .label = "--format LIST",
     .help_text = help_formats,
     .json = "formats",
     .json_rank = 46,
     .json_value = json_formats},
    {.name = "preview_window",
     .type = EVR_OPT_DOUBLE,
     .offset = F(preview_window),
     .def = 0.05,
     .lo = 0,
     .hi = 1e4,
     .check = check_preview_window,
     .what = "preview window must be between 0 (no previews) and 1e4 seconds",
     .flag = "--preview-window",
     .label = "--preview-window S",
     .help = "seconds per preview frame: 0 (no previews), or 0.001 to 1e4\n"
             "(default 0.05)",
     .json = "preview_window",
     .json_rank = 41},
    {.name = "preview",
     .type = EVR_OPT_CHOICE,
     .offset = F(preview),
     .def = EVR_PREVIEW_VIDEO,
     .choices = preview_choices,
     .noun = "preview",
     .what = "unknown preview kind",
     .flag = "--preview",
     .label = "--preview KIND",
     .help = "video (default): one animated PNG, preview.apng, with each\n"
             "window's events (ON blue, OFF red) and intensity side by side,\n"
             "playing in real time (open it in a web browser); png: two PNG\n"
             "files per window in preview/; none. The intensity has one\n"
             "exposure for the whole run, from the visible scene",
     .json = "preview",
     .json_rank = 48},
    {.name = "no_preview",
     .flag = "--no-preview",
     .no_value = 1,
     .parse = parse_no_preview,
     .label = "--no-preview",
     .help = "no previews (--preview none)"},
    {.name = "quiet",
     .flag = "--quiet",
     .alias = "-q",
     .no_value = 1, /* the program's */
     .label = "-q, --quiet",
     .help = "no progress bar or summary"},

    /* ---- intensity frames ---- */
    {.name = "frames_out",
     .type = EVR_OPT_STRING,
     .offset = F(frames_out),
     .check = check_frames_out,
     .flag = "--frames-out",
     .parse = parse_frames_out,
     .section = "intensity frames for frame-based tools (v2e and the like)",
     .label = "--frames-out DIR",
     .help = "also write frame k = every pixel's intensity at exactly\n"
             "start + k/F (one sample at the pixel centre, unseen by the\n"
             "pixel model), for every such time up to and including the end\n"
             "(floor(duration*F) + 1 frames): DIR/frame_NNNNNN.png (8-bit\n"
             "sRGB), DIR/frame_NNNNNN_linear16.png (16-bit linear) and\n"
             "DIR/frames.csv (index,time_s,srgb8_png,linear16_png); DIR may\n"
             "be inside the run folder or not, and must hold no frames\n"
             "unless --force",
     .json = "frames_out",
     .json_rank = 42},
    {.name = "frames_fps",
     .type = EVR_OPT_DOUBLE,
     .offset = F(frames_fps),
     .def = 0.0,
     .lo = 0,
     .hi = 1e6,
     .what = "frames fps must be a positive number of frames per second",
     .flag = "--frames-fps",
     .cli_lo = 0,
     .cli_hi = NO_LIMIT,
     .cli_lo_open = 1,
     .cli_what = "%s must be a positive number (got %s)",
     .label = "--frames-fps F",
     .help = "frames per second (default: the segment rate, --fps)",
     .json = "frames_fps",
     .json_rank = 43,
     .json_if = has_frames,
     .json_value = json_frames_fps},
    {.name = "frames_exposure",
     .type = EVR_OPT_FLOAT,
     .offset = F(frames_exposure),
     .def = 1.0,
     .lo = 0,
     .hi = 1e9,
     .lo_open = 1,
     .what = "frames exposure must be in (0, 1e9]",
     .flag = "--frames-exposure",
     .cli_lo = 0,
     .cli_hi = NO_LIMIT,
     .cli_lo_open = 1,
     .cli_what = "%s must be a positive number (got %s)",
     .label = "--frames-exposure E",
     .help = "8-bit frames: intensity * E clamped to [0, 1], sRGB-encoded\n"
             "(default 1: intensity 1 is white)",
     .json = "frames_exposure",
     .json_rank = 44,
     .json_if = has_frames},
    {.name = "frames_max",
     .type = EVR_OPT_FLOAT,
     .offset = F(frames_max),
     .def = 4.0,
     .lo = 0,
     .hi = 1e9,
     .lo_open = 1,
     .what = "frames max must be an intensity in (0, 1e9]",
     .flag = "--frames-max",
     .cli_lo = 0,
     .cli_hi = NO_LIMIT,
     .cli_lo_open = 1,
     .cli_what = "%s must be a positive intensity (got %s)",
     .label = "--frames-max M",
     .help = "16-bit frames: value = round(intensity * 65535 / M), clamped\n"
             "(default 4)",
     .json = "frames_max",
     .json_rank = 45,
     .json_if = has_frames},

    /* ---- image and time ---- */
    {.name = "res",
     .flag = "--res",
     .parse = parse_res,
     .section = "image and time",
     .label = "--res WxH",
     .help = "resolution (default 346x260)"},
    {.name = "width",
     .type = EVR_OPT_INT,
     .offset = F(width),
     .def = 346,
     .check = check_resolution, /* DAVIS346 */
     .json = "width",
     .json_rank = 3},
    {.name = "height",
     .type = EVR_OPT_INT,
     .offset = F(height),
     .def = 260,
     .json = "height",
     .json_rank = 4},
    {.name = "camera",
     .type = EVR_OPT_STRING,
     .offset = F(camera),
     .flag = "--camera",
     .label = "--camera NAME",
     .help = "camera of the scene (default: the first)",
     .json = "camera",
     .json_rank = 2,
     .json_value = json_camera},
    {.name = "duration",
     .type = EVR_OPT_DOUBLE,
     .offset = F(duration),
     .def = 0.0,
     .lo = 0,
     .hi = EVR_MAX_DURATION,
     .what = "duration must be a positive number of seconds, at most 1e6",
     .flag = "--duration",
     .cli_lo = 0,
     .cli_hi = EVR_MAX_DURATION,
     .cli_lo_open = 1,
     .cli_what = "%s must be a positive number of seconds, at most 1e6 (got %s)",
     .label = "--duration S",
     .help = "seconds to simulate, at most 1e6 (default: the animation's\n"
             "length)",
     .json = "duration",
     .json_rank = 6,
     .json_value = json_duration},
    {.name = "start",
     .type = EVR_OPT_DOUBLE,
     .offset = F(start),
     .def = 0.0,
     .lo = 0,
     .hi = EVR_MAX_DURATION,
     .what = "start time must be between 0 and 1e6 seconds",
     .flag = "--start",
     .label = "--start S",
     .help = "start time in the animation, 0 to 1e6 (default 0)",
     .json = "start",
     .json_rank = 5},
    {.name = "fps",
     .type = EVR_OPT_DOUBLE,
     .offset = F(fps),
     .def = 0.0,
     .lo = 0,
     .hi = 1e6,
     .what = "fps must be a positive number of segments per second",
     .flag = "--fps",
     .cli_lo = 0,
     .cli_hi = NO_LIMIT,
     .cli_lo_open = 1,
     .cli_what = "%s must be a positive number (got %s)",
     .label = "--fps F",
     .help = "segments per second (default: the scene's frame rate, else 30)",
     .json = "fps",
     .json_rank = 7,
     .json_value = json_fps},
    {.name = "samples_per_frame",
     .type = EVR_OPT_INT,
     .offset = F(samples_per_frame),
     .def = 0,
     .lo = 0,
     .hi = 1000000,
     .what = "samples per frame must be between 1 and 1000000 (0: the default)",
     .flag = "--samples-per-frame",
     .cli_lo = 1,
     .cli_hi = 1000000,
     .cli_what = "%s must be between 1 and 1000000 (got %s)",
     .label = "--samples-per-frame N",
     .help = "samples per pixel per segment, 10 unless given; given alone, it\n"
             "chooses uniform sampling at that count (the speed runs'\n"
             "and comparisons' mode)",
     .json = "samples_per_frame",
     .json_rank = 8,
     .json_value = json_samples_per_frame},
    {.name = "threads",
     .type = EVR_OPT_INT,
     .offset = F(threads),
     .def = 0,
     .lo = 0,
     .hi = 4096,
     .what = "threads must be between 0 (all cores) and 4096",
     .flag = "--threads",
     .label = "--threads N",
     .help = "worker threads (default: all cores)"},
    {.name = "backend",
     .type = EVR_OPT_CHOICE,
     .offset = F(backend),
     .def = EVR_BACKEND_AUTO,
     .choices = backend_choices,
     .noun = "backend",
     .what = "unknown backend",
     .flag = "--backend",
     .label = "--backend B",
     .help = "auto (default: CUDA when a GPU is usable, else CPU), cpu or cuda",
     .json = "backend",
     .json_rank = 30,
     .json_value = json_backend},
    {.name = "gpu_bvh",
     .type = EVR_OPT_CHOICE,
     .offset = F(gpu_bvh),
     .def = 0,
     .choices = gpu_bvh_choices,
     .noun = "layout",
     .what = "unknown GPU BVH layout",
     .flag = "--gpu-bvh",
     .label = "--gpu-bvh L",
     .help = "GPU BVH node layout: cw8 (default, compressed 8-wide) or bvh4",
     .json = "gpu_bvh",
     .json_rank = 33},
    {.name = "gpu_event_capacity",
     .type = EVR_OPT_INT64,
     .offset = F(gpu_event_capacity),
     .def = 0,
     .lo = 0,
     .hi = 2147483648.0,
     .what = "GPU event capacity must be between 0 (automatic) and 2^31",
     .flag = "--gpu-event-capacity",
     .parse = parse_event_capacity,
     .label = "--gpu-event-capacity N",
     .help = "events a GPU segment buffer holds at first (default: automatic; it\n"
             "grows and the segment is rendered again whenever it overflows)",
     .json = "gpu_event_capacity",
     .json_rank = 31},
    {.name = "bvh_cache",
     .type = EVR_OPT_STRING,
     .offset = F(bvh_cache),
     .def_text = "auto",
     .check = check_bvh_cache,
     .flag = "--bvh-cache",
     .label = "--bvh-cache DIR",
     .help = "CUDA: keep the trees of big meshes (65,536 triangles or more) in\n"
             "DIR across runs, keyed by their triangles, and load them instead\n"
             "of building them again; at most 4 GiB, the least recently used\n"
             "removed first (default auto: $XDG_CACHE_HOME/evray, else\n"
             "~/.cache/evray; off: none)",
     .json = "bvh_cache",
     .json_rank = 66},
    {.name = "no_skip",
     .type = EVR_OPT_FLAG,
     .offset = F(no_skip),
     .choices = skip_choices,
     .flag = "--no-skip",
     .label = "--no-skip",
     .help = "trace every sample (brute force); by default a pixel that nothing\n"
             "moving can reach keeps its last intensity (identical events)",
     .json = "skip",
     .json_rank = 32},
    {.name = "sampling",
     .type = EVR_OPT_CHOICE,
     .offset = F(sampling),
     .def = EVR_SAMPLING_AUTO,
     .choices = sampling_choices,
     .noun = "sampling",
     .what = "unknown sampling",
     .check = check_sampling,
     .flag = "--sampling",
     .label = "--sampling S",
     .help = "refine (the default; uniform when --samples-per-frame is given\n"
             "or with --gi): where something moving reaches a pixel, 10\n"
             "samples per segment, and every interval in which the pixel\n"
             "fires bisected until its events' timing error is within\n"
             "--time-tol; pixels nothing moving reaches take no samples.\n"
             "uniform: --samples-per-frame samples per pixel per segment.\n"
             "adaptive: each pixel picks its next sample time so\n"
             "that its log intensity moves by at most --adapt-frac of a\n"
             "threshold and anything its rays meet moves by at most\n"
             "2 * --adapt-frac pixels; a pixel nothing moving reaches samples\n"
             "every --max-dt; a sample that changed by more than that is\n"
             "held back while the interval before it is bisected down to\n"
             "--min-dt (ignores --samples-per-frame and --no-skip)",
     .json = "sampling",
     .json_rank = 9,
     .json_value = json_sampling},
    {.name = "time_tol",
     .type = EVR_OPT_DOUBLE,
     .offset = F(time_tol),
     .def = 50e-6,
     .lo = 1e-6,
     .hi = 1,
     .what = "time tolerance must be between 1e-6 and 1 s",
     .flag = "--time-tol",
     .cli_lo = 1e-6,
     .cli_hi = 1,
     .cli_what = "%s must be between 1e-6 and 1 seconds (got %s)",
     .label = "--time-tol S",
     .help = "refine: the timing error of events the refinement aims at,\n"
             "seconds (default 50e-6)",
     .json = "time_tol",
     .json_rank = 63,
     .json_if = is_refine},
    {.name = "refine_px",
     .type = EVR_OPT_DOUBLE,
     .offset = F(refine_px),
     .def = 0.5,
     .lo = 0,
     .hi = 1000,
     .what = "refine pixels must be between 0 and 1000",
     .flag = "--refine-px",
     .cli_lo = 0,
     .cli_hi = 1000,
     .cli_what = "%s must be between 0 and 1000 pixels (got %s)",
     .label = "--refine-px P",
     .help = "refine: what moves in a pixel's rays moves by at most P pixels\n"
             "between its grid samples, so thin things (lashes, their\n"
             "shadows, glints) are seen crossing it (default 0.5; 0: the\n"
             "grid alone)",
     .json = "refine_px",
     .json_rank = 64,
     .json_if = is_refine},
    {.name = "adapt_frac",
     .type = EVR_OPT_FLOAT,
     .offset = F(adapt_frac),
     .def = 0.25,
     .lo = 0,
     .hi = 1,
     .lo_open = 1,
     .what = "adapt fraction must be in (0, 1]",
     .flag = "--adapt-frac",
     .cli_lo = 0,
     .cli_hi = 1,
     .cli_lo_open = 1,
     .cli_what = "%s must be in (0, 1] (got %s)",
     .label = "--adapt-frac F",
     .help = "adaptive: in (0, 1] (default 0.25)",
     .json = "adapt_frac",
     .json_rank = 10,
     .json_if = is_adaptive},
    {.name = "min_dt",
     .type = EVR_OPT_DOUBLE,
     .offset = F(min_dt),
     .def = 20e-6,
     .lo = 1e-6,
     .hi = 1,
     .what = "min dt must be between 1e-6 and 1 s",
     .flag = "--min-dt",
     .cli_lo = 1e-6,
     .cli_hi = 1,
     .cli_what = "%s must be between 1e-6 and 1 seconds (got %s)",
     .label = "--min-dt S, --max-dt S",
     .help = "adaptive: bounds on the time between a pixel's samples, seconds\n"
             "(default 20e-6; one segment); a moving camera or light samples\n"
             "every pixel every --min-dt",
     .json = "min_dt",
     .json_rank = 11,
     .json_if = is_adaptive},
    {.name = "max_dt",
     .type = EVR_OPT_DOUBLE,
     .offset = F(max_dt),
     .def = 0.0,
     .check = check_max_dt, /* 0: one segment */
     .flag = "--max-dt",
     .cli_lo = 0,
     .cli_hi = 1,
     .cli_lo_open = 1,
     .cli_what = "%s must be a number of seconds in (0, 1] (got %s)",
     .json = "max_dt",
     .json_rank = 12,
     .json_if = is_adaptive,
     .json_value = json_max_dt},

    /* ---- global illumination ---- */
    {.name = "gi",
     .type = EVR_OPT_CHOICE,
     .offset = F(gi),
     .def = 0,
     .choices = gi_choices,
     .noun = "mode",
     .what = "unknown global illumination mode",
     .flag = "--gi",
     .section = "global illumination (CPU and CUDA backends)",
     .label = "--gi MODE",
     .help = "none (default) or photon: image-space photon mapping, a photon\n"
             "pass at every segment boundary and the indirect light linear in\n"
             "time between them (the same photons every pass: a still scene\n"
             "gets the same indirect light, so GI makes no events by itself)",
     .json = "gi",
     .json_rank = 34},
    {.name = "photons",
     .type = EVR_OPT_U32,
     .offset = F(photons),
     .def = 0,
     .flag = "--photons",
     .cli_lo = 0,
     .cli_hi = 1 << 30,
     .cli_what = "%s: at most 2^30 photons per pass (got %s)",
     .label = "--photons N",
     .help = "photons per pass (default: one per pixel)",
     .json = "photons",
     .json_rank = 35,
     .json_if = has_gi},
    {.name = "gather_radius",
     .type = EVR_OPT_FLOAT,
     .offset = F(gather_radius),
     .def = 0.0,
     .lo = 0,
     .hi = 1e9,
     .what = "--gather-radius must be a positive number up to 1e9, or 0 for automatic",
     .applies = has_gi,
     .flag = "--gather-radius",
     .label = "--gather-radius R",
     .help = "distance filter, world units (default 2% of the scene's diagonal)",
     .json = "gather_radius",
     .json_rank = 36,
     .json_if = has_gi},
    {.name = "gather_max",
     .type = EVR_OPT_INT,
     .offset = F(gather_max),
     .def = 0, /* no limit: every photon of the disk */
     .lo = 0,
     .hi = 65536,
     .what = "--gather-max must be between 0 (no limit) and 65536",
     .applies = has_gi,
     .flag = "--gather-max",
     .label = "--gather-max N",
     .help = "photons per estimate at most (default 0: no limit, every photon of the disk)",
     .json = "gather_max",
     .json_rank = 37,
     .json_if = has_gi},
    {.name = "gather_window",
     .type = EVR_OPT_INT,
     .offset = F(gather_window),
     .def = 8,
     .lo = 0,
     .hi = 256,
     .what = "--gather-window must be between 0 and 256 pixels",
     .applies = has_gi,
     .flag = "--gather-window",
     .label = "--gather-window N",
     .help = "gather window half size at most, pixels (default 8)",
     .json = "gather_window",
     .json_rank = 38,
     .json_if = has_gi},
    {.name = "photon_layers",
     .type = EVR_OPT_INT,
     .offset = F(photon_layers),
     .def = 0,
     .lo = 0,
     .hi = 4096,
     .what = "--photon-layers must be between 0 (from --photons) and 4096",
     .applies = has_gi,
     .flag = "--photon-layers",
     .label = "--photon-layers N",
     .help = "photons each pixel of the buffer holds (default 0: 8 for\n"
             "each photon per pixel of --photons, at most 64)",
     .json = "photon_layers",
     .json_rank = 39,
     .json_if = has_gi},
    {.name = "gi_bounces",
     .type = EVR_OPT_INT,
     .offset = F(gi_bounces),
     .def = 4,
     .lo = 0,
     .hi = 64,
     .what = "--gi-bounces must be between 0 and 64",
     .applies = has_gi,
     .flag = "--gi-bounces",
     .label = "--gi-bounces N",
     .help = "indirect bounces of a photon (default 4)",
     .json = "gi_bounces",
     .json_rank = 40,
     .json_if = has_gi},
    {.name = "gi_blur",
     .type = EVR_OPT_FLOAT,
     .offset = F(gi_blur),
     .def = 4.0,
     .lo = 0,
     .hi = 16,
     .what = "--gi-blur must be between 0 (off) and 16",
     .applies = has_gi,
     .flag = "--gi-blur",
     .label = "--gi-blur K",
     .help = "indirect light estimated once per photon pass where the\n"
             "camera sees and blurred over each surface, sigma K x the\n"
             "gather radius (default 4; 0: a gather at every sample)",
     .json = "gi_blur",
     .json_rank = 65,
     .json_if = has_gi},

    /* ---- sensor ---- */
    {.name = "sensor",
     .type = EVR_OPT_STRING,
     .offset = F(sensor),
     .check = check_sensor, /* NULL: ideal */
     .flag = "--sensor",
     .parse = parse_sensor,
     .section =
         "sensor (laws, presets and their sources: docs/sensors.md; the default is the ideal sensor)",
     .label = "--sensor NAME",
     .help = "preset: ideal, davis346, dvxplorer or prophesee-gen4; it sets the\n"
             "defaults (and the resolution) that the options below override,\n"
             "whatever their order",
     .json = "sensor",
     .json_rank = 17},
    {.name = "pos_thres",
     .type = EVR_OPT_FLOAT,
     .offset = F(pos_thres),
     .def = 0.2,
     .lo = EVR_MIN_THRES,
     .hi = 100,
     .what = "ON threshold must be between 0.001 and 100",
     .flag = "--pos-thres",
     .label = "--pos-thres C, --neg-thres C",
     .help = "ON/OFF contrast thresholds in log intensity, 0.001 to 100\n"
             "(default 0.2)",
     .json = "pos_thres",
     .json_rank = 13},
    {.name = "neg_thres",
     .type = EVR_OPT_FLOAT,
     .offset = F(neg_thres),
     .def = 0.2,
     .lo = EVR_MIN_THRES,
     .hi = 100,
     .what = "OFF threshold must be between 0.001 and 100",
     .flag = "--neg-thres",
     .json = "neg_thres",
     .json_rank = 14},
    {.name = "thres",
     .flag = "--thres",
     .parse = parse_thres,
     .label = "--thres C",
     .help = "both thresholds"},
    {.name = "sigma_thres",
     .type = EVR_OPT_FLOAT,
     .offset = F(sigma_thres),
     .def = 0.0,
     .lo = 0,
     .hi = 10,
     .what = "threshold mismatch must be between 0 and 10",
     .flag = "--sigma-thres",
     .label = "--sigma-thres S",
     .help = "threshold mismatch: per-pixel thresholds drawn once from\n"
             "N(threshold, S), a fixed pattern (default 0)",
     .json = "sigma_thres",
     .json_rank = 18},
    {.name = "refractory",
     .type = EVR_OPT_FLOAT,
     .offset = F(refractory),
     .def = 0.0,
     .lo = 0,
     .hi = 1000,
     .what = "refractory period must be between 0 and 1000 seconds",
     .flag = "--refractory",
     .label = "--refractory S",
     .help = "refractory period in seconds (default 0)",
     .json = "refractory",
     .json_rank = 15},
    {.name = "cutoff_hz",
     .type = EVR_OPT_FLOAT,
     .offset = F(cutoff_hz),
     .def = 0.0,
     .lo = 0,
     .hi = 1e6,
     .what = "photoreceptor cutoff must be between 0 (off) and 1e6 Hz",
     .flag = "--cutoff-hz",
     .label = "--cutoff-hz F",
     .help = "photoreceptor low-pass cutoff at full brightness, falling to 7%\n"
             "of F for black (default 0: no filter)",
     .json = "cutoff_hz",
     .json_rank = 19},
    {.name = "full_intensity",
     .type = EVR_OPT_FLOAT,
     .offset = F(full_intensity),
     .def = 1.0, /* white diffuse under unit irradiance / pi */
     .lo = 0,
     .hi = NO_LIMIT,
     .lo_open = 1,
     .what = "full intensity must be a positive intensity",
     .flag = "--full-intensity",
     .label = "--full-intensity I",
     .help = "intensity that counts as full brightness (default 1)",
     .json = "full_intensity",
     .json_rank = 20},
    {.name = "leak_rate",
     .type = EVR_OPT_FLOAT,
     .offset = F(leak_rate),
     .def = 0.0,
     .lo = 0,
     .hi = 1e5,
     .what = "leak rate must be between 0 (off) and 1e5 Hz",
     .flag = "--leak-rate-hz",
     .label = "--leak-rate-hz R",
     .help = "leak ON events per second per pixel (default 0)",
     .json = "leak_rate_hz",
     .json_rank = 21},
    {.name = "leak_jitter",
     .type = EVR_OPT_FLOAT,
     .offset = F(leak_jitter),
     .def = 0.1, /* v2e's leak_jitter_fraction */
     .lo = 0,
     .hi = 10,
     .what = "leak jitter must be between 0 and 10",
     .flag = "--leak-jitter",
     .label = "--leak-jitter J",
     .help = "relative spread of the per-pixel leak rates (default 0.1)",
     .json = "leak_jitter",
     .json_rank = 22},
    {.name = "shot_rate",
     .type = EVR_OPT_FLOAT,
     .offset = F(shot_rate),
     .def = 0.0,
     .lo = 0,
     .hi = 1e5,
     .what = "shot noise rate must be between 0 (off) and 1e5 Hz",
     .flag = "--shot-noise-rate-hz",
     .label = "--shot-noise-rate-hz R",
     .help = "shot-noise events per second (ON + OFF) of a black pixel; a pixel\n"
             "at full brightness has R/4 (default 0)",
     .json = "shot_noise_rate_hz",
     .json_rank = 23},
    {.name = "hot_fraction",
     .type = EVR_OPT_FLOAT,
     .offset = F(hot_fraction),
     .def = 0.0,
     .lo = 0,
     .hi = 1,
     .what = "hot pixel fraction must be between 0 and 1",
     .flag = "--hot-pixel-fraction",
     .label = "--hot-pixel-fraction F",
     .help = "fraction of hot pixels (default 0)",
     .json = "hot_pixel_fraction",
     .json_rank = 24},
    {.name = "hot_rate",
     .type = EVR_OPT_FLOAT,
     .offset = F(hot_rate),
     .def = 100.0,
     .lo = 0,
     .hi = 1e5,
     .what = "hot pixel rate must be between 0 and 1e5 Hz",
     .flag = "--hot-pixel-rate-hz",
     .label = "--hot-pixel-rate-hz R",
     .help = "ON events per second of a hot pixel (default 100)",
     .json = "hot_pixel_rate_hz",
     .json_rank = 25},
    {.name = "time_res",
     .type = EVR_OPT_DOUBLE,
     .offset = F(time_res),
     .def = 1e-6,
     .check = check_time_res,
     .flag = "--time-res",
     .label = "--time-res S",
     .help = "timestamp resolution in seconds, whole microseconds (default 1e-6)",
     .json = "time_res",
     .json_rank = 26},
    {.name = "time_jitter",
     .type = EVR_OPT_DOUBLE,
     .offset = F(time_jitter),
     .def = 0.0,
     .lo = 0,
     .hi = 0.1,
     .what = "timestamp jitter must be between 0 and 0.1 s",
     .flag = "--time-jitter",
     .label = "--time-jitter S",
     .help = "std dev of Gaussian timestamp jitter in seconds (default 0)",
     .json = "time_jitter",
     .json_rank = 27},
    {.name = "log_floor",
     .type = EVR_OPT_FLOAT,
     .offset = F(log_floor),
     .def = 0.02,
     .lo = 0,
     .hi = NO_LIMIT,
     .lo_open = 1,
     .what = "log floor must be a positive intensity",
     .flag = "--log-floor",
     .label = "--log-floor I",
     .help = "intensity below which the response is linear (default 0.02)",
     .json = "log_floor",
     .json_rank = 16},
    {.name = "seed",
     .type = EVR_OPT_U64,
     .offset = F(seed),
     .def = 1,
     .flag = "--seed",
     .label = "--seed N",
     .help = "seed of the per-pixel sample phases and of the sensor's fixed\n"
             "pattern and noise (default 1)",
     .json = "seed",
     .json_rank = 29},

    /* ---- shading ---- */
    {.name = "ambient",
     .type = EVR_OPT_FLOAT,
     .offset = F(ambient),
     .def = 0.02,
     .lo = 0,
     .hi = NO_LIMIT,
     .what = "ambient must be >= 0",
     .flag = "--ambient",
     .section = "shading",
     .label = "--ambient A",
     .help = "ambient light as a fraction of the base colour (default 0.02)",
     .json = "ambient",
     .json_rank = 28},
    {.name = "max_bounces",
     .type = EVR_OPT_INT,
     .offset = F(max_bounces),
     .def = 4,
     .lo = 0,
     .hi = 16,
     .what = "--max-bounces must be between 0 and 16",
     .flag = "--max-bounces",
     .section = "shading",
     .label = "--max-bounces N",
     .help = "reflections and refractions a camera ray may take (default 4)",
     .json = "max_bounces",
     .json_rank = 47},

    /* ---- ground truth ---- */
    {.name = "labels_fps",
     .type = EVR_OPT_DOUBLE,
     .offset = F(labels_fps),
     .def = 0.0,
     .lo = 0,
     .hi = 1e6,
     .what = "labels fps must be between 0 and 1e6 frames per second",
     .flag = "--labels-fps",
     .cli_lo = 0,
     .cli_hi = NO_LIMIT,
     .cli_lo_open = 1,
     .cli_what = "%s must be a positive number (got %s)",
     .section = "ground truth (README \"Ground truth\")",
     .label = "--labels-fps F",
     .help = "write labels.h5: at every start + k/F up to and including the\n"
             "end, each pixel's depth, instance id, optical flow (px/s, from\n"
             "the motion) and displacement over --flow-dt (default: off)",
     .json = "labels_fps",
     .json_rank = 54},
    {.name = "flow_dt",
     .type = EVR_OPT_DOUBLE,
     .offset = F(flow_dt),
     .def = 0.01,
     .lo = 0,
     .hi = 1e6,
     .lo_open = 1,
     .what = "flow dt must be a positive number of seconds",
     .flag = "--flow-dt",
     .cli_lo = 0,
     .cli_hi = NO_LIMIT,
     .cli_lo_open = 1,
     .cli_what = "%s must be a positive number of seconds (got %s)",
     .label = "--flow-dt S",
     .help = "labels.h5: the forward displacement's time step, seconds\n"
             "(default 0.01)",
     .json = "flow_dt",
     .json_rank = 55,
     .json_if = has_labels},
    {.name = "label_normals",
     .type = EVR_OPT_FLAG,
     .offset = F(label_normals),
     .flag = "--label-normals",
     .label = "--label-normals",
     .help = "labels.h5: also each pixel's surface normal",
     .json = "label_normals",
     .json_rank = 56,
     .json_if = has_labels},
    {.name = "trajectories",
     .type = EVR_OPT_FLAG,
     .offset = F(trajectories),
     .flag = "--trajectories",
     .label = "--trajectories",
     .help = "write imu.txt (an ideal IMU on the camera) and node_poses.txt\n"
             "(every animated node's world pose) at 1 kHz",
     .json = "trajectories",
     .json_rank = 57},
    {.name = "eye_labels",
     .type = EVR_OPT_FLAG,
     .offset = F(eye_labels),
     .flag = "--eye-labels",
     .label = "--eye-labels",
     .help = "write eye.txt at 1 kHz: gaze, pupil centre and radius in the\n"
             "image, eyelid openness, phase (a scene with an eye's nodes:\n"
             "README \"Ground truth\")",
     .json = "eye_labels",
     .json_rank = 58},
    {.name = "event_ids",
     .type = EVR_OPT_FLAG,
     .offset = F(event_ids),
     .flag = "--event-ids",
     .label = "--event-ids",
     .help = "label every event with the instance its pixel saw (1 + the\n"
             "instance hit at the sample after the crossing, 0 none):\n"
             "events.h5 events/id and /instances, events.npy's id field,\n"
             "events.txt's fifth column (README \"Ground truth\")",
     .json = "event_ids",
     .json_rank = 62},

    /* ---- scene loading ---- */
    {.name = "strict",
     .type = EVR_OPT_FLAG,
     .offset = F(strict),
     .flag = "--strict",
     .section = "scene loading",
     .label = "--strict",
     .help = "fail on anything evray would otherwise warn about and leave\n"
             "out (a texture it cannot find or decode, an extension it does\n"
             "not render, ...); by default each is one warning and the load\n"
             "goes on (a material whose texture is missing keeps its factors)",
     .json = "strict",
     .json_rank = 49},
    /* ---- the camera ---- */
    {.name = "camera_path",
     .type = EVR_OPT_STRING,
     .offset = F(camera_path),
     .applies = has_camera_path,
     .check = check_camera_path,
     .flag = "--camera-path",
     .section = "camera (README: camera paths and framing)",
     .label = "--camera-path P",
     .help = "move the camera (on top of its own motion): orbit[:period=S][:centre=X,Y,Z]\n"
             "[:axis=X,Y,Z], dolly[:speed=U][:dir=X,Y,Z] (or fly), pan[:rate=D] or\n"
             "pan:amp=D[:period=S], tilt (the same), shake[:amp=D][:tremor=D][:move=U]\n"
             "[:seed=N] (hand-held), joined by + (orbit+shake); or tum:FILE, a TUM\n"
             "trajectory 't tx ty tz qx qy qz qw' that replaces its pose; scene units,\n"
             "seconds, degrees. The pose used is written to camera_poses.txt",
     .json = "camera_path",
     .json_rank = 50,
     .json_if = has_camera_path},
    {.name = "look_from",
     .flag = "--look-from",
     .parse = parse_look_from,
     .check = check_look,
     .label = "--look-from X,Y,Z",
     .help = "place the camera there (world), fixed (default: where it is; with\n"
             "--look-at alone, its position at the start)",
     .json = "look_from",
     .json_rank = 51,
     .json_if = has_look_from,
     .json_value = json_look_from},
    {.name = "look_at",
     .flag = "--look-at",
     .parse = parse_look_at,
     .label = "--look-at X,Y,Z",
     .help = "aim the camera at that point (default with --look-from: the centre of\n"
             "the scene's bounds over its animation); also the orbit's centre",
     .json = "look_at",
     .json_rank = 52,
     .json_if = has_look_at,
     .json_value = json_look_at},
    {.name = "fov",
     .type = EVR_OPT_DOUBLE,
     .offset = F(fov),
     .def = 0.0,
     .lo = 0,
     .hi = 180,
     .hi_open = 1,
     .what = "field of view must be between 0 (the camera's own) and 180 degrees",
     .flag = "--fov",
     .cli_lo = 0,
     .cli_hi = 180,
     .cli_lo_open = 1,
     .cli_what = "%s must be between 0 and 180 degrees (got %s)",
     .label = "--fov DEG",
     .help = "vertical field of view of a perspective camera (default: the camera's\n"
             "own; the automatic camera's 45, framed again for it)",
     .json = "fov",
     .json_rank = 53,
     .json_if = has_fov},
    {.name = "allow_external_files",
     .type = EVR_OPT_FLAG,
     .offset = F(allow_external_files),
     .flag = "--allow-external-files",
     .label = "--allow-external-files",
     .help = "let the scene read files outside its own folder (buffers and\n"
             "images given by an absolute path, by '..' or through a link\n"
             "out of the folder); by default such a buffer fails the load\n"
             "and such a texture is a warning. FIFOs and devices are never\n"
             "read",
     .json = "allow_external_files",
     .json_rank = 59},

    /* ---- how much a run may take ---- */
    {.name = "max_samples",
     .type = EVR_OPT_DOUBLE,
     .offset = F(max_samples),
     .def = 1e12,
     .lo = 0,
     .hi = NO_LIMIT,
     .what = "--max-samples must be >= 0 (0: no limit)",
     .flag = "--max-samples",
     .section = "limits (checked before the run starts)",
     .label = "--max-samples N",
     .help = "refuse a run whose pixel work, width x height x (samples per\n"
             "segment x segments + intensity frames + preview frames), is\n"
             "more than N (default 1e12; 0: no limit)",
     .json = "max_samples",
     .json_rank = 60},
    {.name = "max_noise_events",
     .type = EVR_OPT_DOUBLE,
     .offset = F(max_noise_events),
     .def = 1e9,
     .lo = 0,
     .hi = NO_LIMIT,
     .what = "--max-noise-events must be >= 0 (0: no limit)",
     .flag = "--max-noise-events",
     .label = "--max-noise-events N",
     .help = "refuse a run expected to make more than N noise events\n"
             "(pixels x duration x the leak, shot and hot-pixel rates;\n"
             "default 1e9; 0: no limit)",
     .json = "max_noise_events",
     .json_rank = 61},
};

const evr_config_option *evr_config_table(int *count)
{
    *count = (int)(sizeof table / sizeof table[0]);
    return table;
}
