/* Simulation parameters: defaults, checks and the JSON form stored with every output, all made
 * from the configuration table (config_table.c); the sensor presets; the size rule of evr_config. */
#include "evray.h"
#include "config/config_json.h"
#include "config/config_table.h"
#include "io/json.h"
#include "scene/scene.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

void *evr_config_field(evr_config *c, const evr_config_option *o)
{
    return o->type == EVR_OPT_NONE ? NULL : (char *)c + o->offset;
}

const void *evr_config_field_const(const evr_config *c, const evr_config_option *o)
{
    return o->type == EVR_OPT_NONE ? NULL : (const char *)c + o->offset;
}

/* A number field's value (0 for strings and rows without a field). */
static double field_number(const evr_config *c, const evr_config_option *o)
{
    const void *f = evr_config_field_const(c, o);
    switch (o->type) {
    case EVR_OPT_FLAG:
    case EVR_OPT_INT:
    case EVR_OPT_CHOICE: return *(const int *)f;
    case EVR_OPT_INT64: return (double)*(const int64_t *)f;
    case EVR_OPT_U32: return *(const uint32_t *)f;
    case EVR_OPT_U64: return (double)*(const uint64_t *)f;
    case EVR_OPT_FLOAT: return *(const float *)f;
    case EVR_OPT_DOUBLE: return *(const double *)f;
    default: return 0.0;
    }
}

/* The smallest evr_config a caller may pass: the first version with a size field. When fields
 * are added at the end, this stays and older callers' configurations get defaults for the rest. */
#define EVR_CONFIG_FIRST_SIZE sizeof(evr_config)

static void fill_defaults(evr_config *c)
{
    int i, n;
    const evr_config_option *t = evr_config_table(&n);
    memset(c, 0, sizeof *c);
    c->size = sizeof *c;
    for (i = 0; i < n; i++) {
        void *f = evr_config_field(c, &t[i]);
        switch (t[i].type) {
        case EVR_OPT_FLAG:
        case EVR_OPT_INT:
        case EVR_OPT_CHOICE: *(int *)f = (int)t[i].def; break;
        case EVR_OPT_INT64: *(int64_t *)f = (int64_t)t[i].def; break;
        case EVR_OPT_U32: *(uint32_t *)f = (uint32_t)t[i].def; break;
        case EVR_OPT_U64: *(uint64_t *)f = (uint64_t)t[i].def; break;
        case EVR_OPT_FLOAT: *(float *)f = (float)t[i].def; break;
        case EVR_OPT_DOUBLE: *(double *)f = t[i].def; break;
        case EVR_OPT_STRING: *(const char **)f = t[i].def_text; break;
        case EVR_OPT_NONE: break;
        }
    }
}

/* Sensor presets; docs/sensors.md gives the source of every value (keep the two in step). */
typedef struct {
    const char *name;
    int width, height; /* 0: keep the resolution */
    float pos_thres, neg_thres, sigma_thres, refractory, cutoff_hz;
    float leak_rate, leak_jitter, shot_rate, hot_fraction, hot_rate;
    double time_res;
} sensor_preset;

static const sensor_preset presets[] = {
    /* name            w     h    ON      OFF     sigma  refr    cutoff  leak   jit   shot  hot    hot Hz  t res */
    {"ideal", 0, 0, 0.2f, 0.2f, 0.0f, 0.0f, 0.0f, 0.0f, 0.1f, 0.0f, 0.0f, 100.0f, 1e-6},
    {"davis346", 346, 260, 0.134f, 0.255f, 0.03f, 1e-4f, 200.0f, 0.1f, 0.1f, 1.0f, 1e-4f, 100.0f,
     1e-6},
    {"dvxplorer", 640, 480, 0.2f, 0.2f, 0.03f, 1e-4f, 200.0f, 0.05f, 0.1f, 0.5f, 1e-4f, 100.0f,
     1e-4},
    {"prophesee-gen4", 1280, 720, 0.223f, 0.288f, 0.02f, 1e-4f, 500.0f, 0.05f, 0.1f, 0.1f, 1e-5f,
     100.0f, 1e-6},
};
#define NUM_PRESETS ((int)(sizeof presets / sizeof presets[0]))

const char *const *evr_sensor_names(void)
{
    static const char *const names[NUM_PRESETS + 1] = {"ideal", "davis346", "dvxplorer",
                                                       "prophesee-gen4", NULL};
    return names;
}

static const sensor_preset *find_preset(const char *name)
{
    int i;
    for (i = 0; name && i < NUM_PRESETS; i++)
        if (!strcmp(presets[i].name, name)) return &presets[i];
    return NULL;
}

const char *evr_sensor_canonical(const char *name)
{
    const sensor_preset *p = find_preset(name);
    return p ? p->name : NULL;
}

const char *evr_sensor_list(char *buf, size_t n)
{
    int i;
    size_t len = 0;
    buf[0] = 0;
    for (i = 0; i < NUM_PRESETS && len < n; i++)
        len += (size_t)snprintf(buf + len, n - len, "%s%s", i ? ", " : "", presets[i].name);
    return buf;
}

evr_status evr_config_sensor(evr_config *c, const char *name, evr_error *err)
{
    const sensor_preset *p = find_preset(name);
    char list[128];
    if (!p) {
        snprintf(err->msg, sizeof err->msg, "unknown sensor '%s' (%s)", name ? name : "",
                 evr_sensor_list(list, sizeof list));
        return EVR_ERR_ARG;
    }
    c->sensor = p->name;
    if (p->width > 0) {
        c->width = p->width;
        c->height = p->height;
    }
    c->pos_thres = p->pos_thres;
    c->neg_thres = p->neg_thres;
    c->sigma_thres = p->sigma_thres;
    c->refractory = p->refractory;
    c->cutoff_hz = p->cutoff_hz;
    c->leak_rate = p->leak_rate;
    c->leak_jitter = p->leak_jitter;
    c->shot_rate = p->shot_rate;
    c->hot_fraction = p->hot_fraction;
    c->hot_rate = p->hot_rate;
    c->time_res = p->time_res;
    c->time_jitter = 0.0;
    return EVR_OK;
}

void evr_config_init(evr_config *c, size_t size)
{
    evr_config d;
    fill_defaults(&d);
    if (size >= EVR_CONFIG_FIRST_SIZE &&
        size <= sizeof d) { /* an older caller: its own fields only */
        memcpy(c, &d, size);
        c->size = size;
    } else if (size > sizeof d) { /* a newer caller: ours, and a size it will be refused with */
        memcpy(c, &d, sizeof d);
        c->size = size;
    }
}

evr_sampling evr_config_sampling(const evr_config *c)
{
    if (c->sampling != EVR_SAMPLING_AUTO) return (evr_sampling)c->sampling;
    return c->samples_per_frame > 0 || c->gi ? EVR_SAMPLING_UNIFORM : EVR_SAMPLING_REFINE;
}

int evr_config_samples_per_frame(const evr_config *c)
{
    return c->samples_per_frame > 0 ? c->samples_per_frame : 10;
}

evr_status evr_config_current(const evr_config *c, evr_config *out, evr_error *err)
{
    if (!c || c->size < EVR_CONFIG_FIRST_SIZE || c->size > sizeof *out) {
        snprintf(
            err->msg, sizeof err->msg,
            "evr_config of %zu bytes is not one this evray (%zu bytes) knows: make it with evr_config_defaults",
            c ? c->size : (size_t)0, sizeof *out);
        return EVR_ERR_ARG;
    }
    fill_defaults(out); /* the fields an older caller does not have */
    memcpy(out, c, c->size);
    out->size = sizeof *out;
    return EVR_OK;
}

static evr_status check_run_size(const evr_config *c, const evr_scene *s, evr_error *err);

#define BAD(...)                                          \
    do {                                                  \
        snprintf(err->msg, sizeof err->msg, __VA_ARGS__); \
        return EVR_ERR_ARG;                               \
    } while (0)

/* Whether a choice row's value is one of its choices. */
static int choice_known(const evr_config_option *o, int v)
{
    const evr_opt_choice *ch;
    for (ch = o->choices; ch->name || ch->json; ch++)
        if (!ch->refuse && ch->value == v) return 1;
    return 0;
}

void evr_config_choice_names(const evr_config_option *o, char *buf, size_t n)
{
    const evr_opt_choice *ch;
    size_t len = 0;
    buf[0] = 0;
    for (ch = o->choices; ch->name || ch->json; ch++)
        if (ch->name && !ch->refuse && len < n)
            len += (size_t)snprintf(buf + len, n - len, "%s%s", len ? ", " : "", ch->name);
}

/* Checks row o's range (or choices); fills err when it is out. */
static evr_status check_range(const evr_config *c, const evr_config_option *o, evr_error *err)
{
    char names[128];
    if (o->type == EVR_OPT_CHOICE) {
        int v = *(const int *)evr_config_field_const(c, o);
        if (choice_known(o, v)) return EVR_OK;
        evr_config_choice_names(o, names, sizeof names);
        BAD("%s %d (%s)", o->what ? o->what : o->name, v, names);
    }
    if (!o->what) return EVR_OK;
    double v = field_number(c, o);
    int ok = v >= o->lo && v <= o->hi && !(o->lo_open && v == o->lo) && !(o->hi_open && v == o->hi);
    if (o->type == EVR_OPT_FLOAT || o->type == EVR_OPT_DOUBLE) ok = ok && isfinite(v);
    if (ok) return EVR_OK;
    switch (o->type) {
    case EVR_OPT_INT: BAD("%s (got %d)", o->what, *(const int *)evr_config_field_const(c, o));
    case EVR_OPT_INT64:
        BAD("%s (got %lld)", o->what, (long long)*(const int64_t *)evr_config_field_const(c, o));
    case EVR_OPT_U32:
    case EVR_OPT_U64: BAD("%s (got %.0f)", o->what, v);
    default: BAD("%s (got %g)", o->what, v);
    }
}

evr_status evr_config_validate(const evr_config *given, const evr_scene *s, evr_error *err)
{
    int i, n;
    evr_status st;
    evr_config cur;
    const evr_config *c = &cur;
    const evr_config_option *t = evr_config_table(&n);
    if ((st = evr_config_current(given, &cur, err)) != EVR_OK) return st;
    for (i = 0; i < n; i++) {
        if (t[i].applies && !t[i].applies(c)) continue;
        if ((st = check_range(c, &t[i], err)) != EVR_OK) return st;
        if (t[i].check && (st = t[i].check(c, err)) != EVR_OK) return st;
    }
    if (s) {
        if (c->camera && evr_scene_find_camera(s, c->camera) < 0) {
            char names[256] = "";
            size_t len = 0;
            for (i = 0; i < s->num_cameras && len < 180; i++) {
                if (s->cameras[i].automatic) continue;
                len += (size_t)snprintf(names + len, sizeof names - len, "%s%.60s", len ? ", " : "",
                                        s->cameras[i].name);
            }
            BAD("no camera named '%s' in the scene (cameras: %s)", c->camera,
                names[0] ? names : "none");
        }
        double end = s->anim_end;
        if (end > 0.0 && !c->camera_path) { /* a camera path may go on past it (the scene
                                               holds its last pose) */
            if (c->start >= end)
                BAD("start time %g s is at or beyond the end of the animation (%g s)", c->start,
                    end);
            if (c->duration > 0.0 && c->start + c->duration > end + 1e-6)
                BAD("duration %g s from %g s goes beyond the end of the animation (%g s)",
                    c->duration, c->start, end);
        }
        if ((st = check_run_size(c, s, err)) != EVR_OK) return st;
    }
    return EVR_OK;
}

void evr_config_run_span(const evr_config *c, const evr_scene *s, double *duration, double *fps)
{
    *fps = c->fps > 0.0 ? c->fps : (s->frame_rate > 0.0 ? s->frame_rate : 30.0);
    if (c->duration > 0.0) *duration = c->duration;
    else if (s->anim_end > c->start) *duration = s->anim_end - c->start;
    else *duration = 1.0; /* a static scene: one second unless told */
}

/* The work the run will do, estimated before anything is allocated: a run that would take days,
 * fill the disk with noise or overflow its counters is refused with one line, past limits the
 * caller can raise (max_samples, max_noise_events), rather than started. */
static evr_status check_run_size(const evr_config *c, const evr_scene *s, evr_error *err)
{
    double duration, fps, segments, per_pixel, frames = 0.0, previews = 0.0, work, noise;
    double pixels = (double)c->width * (double)c->height;
    evr_config_run_span(c, s, &duration, &fps);
    if (!(duration <= EVR_MAX_DURATION))
        BAD("the scene's animation runs to %g s: more than %g s from --start %g s cannot be "
            "simulated (give --duration)",
            s->anim_end, EVR_MAX_DURATION, c->start);
    segments = ceil(duration * fps - 1e-9);
    if (segments > EVR_MAX_SEGMENTS)
        BAD("%g s at %g segments per second is %.4g segments, more than %g: lower --fps or "
            "--duration",
            duration, fps, segments, EVR_MAX_SEGMENTS);
    if (segments < 1.0) segments = 1.0;
    /* adaptive sampling may take a sample every min_dt */
    per_pixel = c->sampling == EVR_SAMPLING_ADAPTIVE
                    ? ceil(duration / c->min_dt)
                    : (double)evr_config_samples_per_frame(c) * segments;
    if (c->frames_out)
        frames = floor(duration * (c->frames_fps > 0.0 ? c->frames_fps : fps) + 1e-9) + 1.0;
    if (c->preview != EVR_PREVIEW_NONE && c->preview_window > 0.0)
        previews = ceil(duration / c->preview_window);
    work = pixels * (per_pixel + frames + previews);
    if (c->max_samples > 0.0 && work > c->max_samples)
        BAD("the run would take %.3g pixel samples (%dx%d pixels x (%.4g samples + %.4g frames + "
            "%.4g previews) over %g s), more than --max-samples %g: shorten it or raise the limit",
            work, c->width, c->height, per_pixel, frames, previews, duration, c->max_samples);
    noise = pixels * duration *
            ((double)c->leak_rate * (1.0 + (double)c->leak_jitter) + (double)c->shot_rate +
             (double)c->hot_fraction * (double)c->hot_rate);
    if (c->max_noise_events > 0.0 && noise > c->max_noise_events)
        BAD("the noise settings would make about %.3g events (%dx%d pixels x %g s x the leak, shot "
            "and hot-pixel rates), more than --max-noise-events %g: lower the rates or raise the "
            "limit",
            noise, c->width, c->height, duration, c->max_noise_events);
    return EVR_OK;
}

/* Row o's value in JSON, when it is the field's own. */
static void json_field(evr_json *j, const evr_config *c, const evr_config_option *o)
{
    const void *f = evr_config_field_const(c, o);
    if (o->choices) { /* a choice, or a flag with names */
        const evr_opt_choice *ch;
        int v = *(const int *)f;
        for (ch = o->choices; ch->name || ch->json; ch++)
            if (ch->json && ch->value == v) {
                evr_json_string(j, ch->json);
                return;
            }
        evr_json_integer(j, v);
        return;
    }
    switch (o->type) {
    case EVR_OPT_FLAG:
    case EVR_OPT_INT:
    case EVR_OPT_CHOICE: evr_json_integer(j, *(const int *)f); break;
    case EVR_OPT_INT64: evr_json_integer(j, *(const int64_t *)f); break;
    case EVR_OPT_U32: evr_json_unsigned(j, *(const uint32_t *)f); break;
    case EVR_OPT_U64: evr_json_unsigned(j, *(const uint64_t *)f); break;
    case EVR_OPT_FLOAT: evr_json_float(j, *(const float *)f); break;
    case EVR_OPT_DOUBLE: evr_json_number(j, *(const double *)f); break;
    case EVR_OPT_STRING: evr_json_string(j, *(const char *const *)f); break;
    case EVR_OPT_NONE: evr_json_null(j); break;
    }
}

char *evr_config_to_json(const evr_config *c, double duration, double fps, const char *scene,
                         const char *camera, const char *backend, int pretty)
{
    int i, n, rank, found = 1;
    const evr_config_option *t = evr_config_table(&n);
    evr_config_run run;
    evr_json j;
    run.duration = duration;
    run.fps = fps;
    run.scene = scene;
    run.camera = camera;
    run.backend = backend;
    evr_json_init(&j, pretty);
    evr_json_begin_object(&j);
    for (rank = 1; found; rank++) { /* the rows in json_rank order */
        found = 0;
        for (i = 0; i < n; i++) {
            if (t[i].json_rank != rank) continue;
            found = 1;
            if (t[i].json_if && !t[i].json_if(c)) break;
            evr_json_key(&j, t[i].json);
            if (t[i].json_value) t[i].json_value(&j, c, &run);
            else json_field(&j, c, &t[i]);
            break;
        }
    }
    evr_json_end_object(&j);
    return evr_json_take(&j);
}
