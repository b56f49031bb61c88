/* Simulation parameters: defaults, checks, and the JSON form stored with every output. */
#include "evray.h"
#include "config_json.h"
#include "io/event_formats.h"
#include "io/json.h"
#include "scene/scene.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

void evr_config_defaults(evr_config *c)
{
    memset(c, 0, sizeof *c);
    c->width = 346;               /* DAVIS346 */
    c->height = 260;
    c->duration = 0.0;
    c->start = 0.0;
    c->fps = 0.0;
    c->samples_per_frame = 10;
    c->sampling = EVR_SAMPLING_UNIFORM;
    c->adapt_frac = 0.25f;
    c->min_dt = 20e-6;
    c->max_dt = 0.0;              /* one segment */
    c->camera = NULL;
    c->pos_thres = 0.2f;
    c->neg_thres = 0.2f;
    c->refractory = 0.0f;
    c->log_floor = 0.02f;
    c->sensor = NULL;             /* the ideal sensor: every non-ideality off */
    c->sigma_thres = 0.0f;
    c->cutoff_hz = 0.0f;
    c->full_intensity = 1.0f;     /* a white diffuse surface under unit irradiance / pi */
    c->leak_rate = 0.0f;
    c->leak_jitter = 0.1f;        /* v2e's leak_jitter_fraction */
    c->shot_rate = 0.0f;
    c->hot_fraction = 0.0f;
    c->hot_rate = 100.0f;
    c->time_res = 1e-6;
    c->time_jitter = 0.0;
    c->ambient = 0.02f;
    c->seed = 1;
    c->threads = 0;
    c->out_dir = "evray-out";
    c->formats = EVR_FORMAT_H5;
    c->preview_window = 0.05;
    c->force = 0;
    c->frames_out = NULL;
    c->frames_fps = 0.0;
    c->frames_exposure = 1.0f;
    c->frames_max = 4.0f;
    c->gi = 0;
    c->photons = 0;
    c->gather_radius = 0.0f;
    c->gather_max = 0;   /* no limit: every photon of the disk, updated from the changed cells */
    c->gather_window = 8;
    c->photon_layers = 8;
    c->gi_bounces = 4;
}

/* Sensor presets; docs/sensors.md gives the source of every value (keep the two in step). */
typedef struct {
    const char *name;
    int width, height;            /* 0: keep the resolution */
    float pos_thres, neg_thres, sigma_thres, refractory, cutoff_hz;
    float leak_rate, leak_jitter, shot_rate, hot_fraction, hot_rate;
    double time_res;
} sensor_preset;

static const sensor_preset presets[] = {
    /* name            w     h    ON      OFF     sigma  refr    cutoff  leak   jit   shot  hot    hot Hz  t res */
    {"ideal",          0,    0,   0.2f,   0.2f,   0.0f,  0.0f,   0.0f,   0.0f,  0.1f, 0.0f, 0.0f,  100.0f, 1e-6},
    {"davis346",       346,  260, 0.134f, 0.255f, 0.03f, 1e-4f,  200.0f, 0.1f,  0.1f, 1.0f, 1e-4f, 100.0f, 1e-6},
    {"dvxplorer",      640,  480, 0.2f,   0.2f,   0.03f, 1e-4f,  200.0f, 0.05f, 0.1f, 0.5f, 1e-4f, 100.0f, 1e-4},
    {"prophesee-gen4", 1280, 720, 0.223f, 0.288f, 0.02f, 1e-4f,  500.0f, 0.05f, 0.1f, 0.1f, 1e-5f, 100.0f, 1e-6},
};
#define NUM_PRESETS ((int)(sizeof presets / sizeof presets[0]))

const char *const *evr_sensor_names(void)
{
    static const char *const names[NUM_PRESETS + 1] = {"ideal", "davis346", "dvxplorer", "prophesee-gen4", NULL};
    return names;
}

static const sensor_preset *find_preset(const char *name)
{
    int i;
    for (i = 0; name && i < NUM_PRESETS; i++)
        if (!strcmp(presets[i].name, name)) return &presets[i];
    return NULL;
}

evr_status evr_config_sensor(evr_config *c, const char *name, evr_error *err)
{
    const sensor_preset *p = find_preset(name);
    if (!p) {
        snprintf(err->msg, sizeof err->msg, "unknown sensor '%s' (ideal, davis346, dvxplorer, prophesee-gen4)", name ? name : "");
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

#define BAD(...) do { snprintf(err->msg, sizeof err->msg, __VA_ARGS__); return EVR_ERR_ARG; } while (0)

evr_status evr_config_validate(const evr_config *c, const evr_scene *s, evr_error *err)
{
    if (c->width < 1 || c->height < 1 || c->width > 65535 || c->height > 65535)
        BAD("resolution %dx%d is out of range (1 to 65535 pixels a side)", c->width, c->height);
    if ((double)c->width * (double)c->height > 1e9) BAD("resolution %dx%d is too large", c->width, c->height);
    if (c->samples_per_frame < 1 || c->samples_per_frame > 1000000)
        BAD("samples per frame must be between 1 and 1000000 (got %d)", c->samples_per_frame);
    if (c->sampling != EVR_SAMPLING_UNIFORM && c->sampling != EVR_SAMPLING_ADAPTIVE)
        BAD("unknown sampling %d (uniform, adaptive)", c->sampling);
    if (!(c->adapt_frac > 0.0f) || !(c->adapt_frac <= 1.0f))
        BAD("adapt fraction must be in (0, 1] (got %g)", (double)c->adapt_frac);
    if (!(c->min_dt >= 1e-6) || !(c->min_dt <= 1.0))
        BAD("min dt must be between 1e-6 and 1 s (got %g)", c->min_dt);
    if (!(c->max_dt <= 1.0) || c->max_dt < 0.0 || !isfinite(c->max_dt) || (c->max_dt > 0.0 && c->max_dt < c->min_dt))
        BAD("max dt must be between min dt (%g s) and 1 s, or 0 for one segment (got %g)", c->min_dt, c->max_dt);
    if (!(c->pos_thres > 0.0f) || !isfinite(c->pos_thres)) BAD("ON threshold must be a positive number (got %g)", (double)c->pos_thres);
    if (!(c->neg_thres > 0.0f) || !isfinite(c->neg_thres)) BAD("OFF threshold must be a positive number (got %g)", (double)c->neg_thres);
    if (!(c->refractory >= 0.0f) || !isfinite(c->refractory)) BAD("refractory period must be >= 0 seconds (got %g)", (double)c->refractory);
    if (!(c->log_floor > 0.0f) || !isfinite(c->log_floor)) BAD("log floor must be a positive intensity (got %g)", (double)c->log_floor);
    if (c->sensor && !find_preset(c->sensor))
        BAD("unknown sensor '%s' (ideal, davis346, dvxplorer, prophesee-gen4)", c->sensor);
    if (!(c->sigma_thres >= 0.0f) || !isfinite(c->sigma_thres))
        BAD("threshold mismatch must be >= 0 (got %g)", (double)c->sigma_thres);
    if (!(c->cutoff_hz >= 0.0f) || !(c->cutoff_hz <= 1e6f))
        BAD("photoreceptor cutoff must be between 0 (off) and 1e6 Hz (got %g)", (double)c->cutoff_hz);
    if (!(c->full_intensity > 0.0f) || !isfinite(c->full_intensity))
        BAD("full intensity must be a positive intensity (got %g)", (double)c->full_intensity);
    if (!(c->leak_rate >= 0.0f) || !(c->leak_rate <= 1e5f))
        BAD("leak rate must be between 0 (off) and 1e5 Hz (got %g)", (double)c->leak_rate);
    if (!(c->leak_jitter >= 0.0f) || !isfinite(c->leak_jitter))
        BAD("leak jitter must be >= 0 (got %g)", (double)c->leak_jitter);
    if (!(c->shot_rate >= 0.0f) || !(c->shot_rate <= 1e5f))
        BAD("shot noise rate must be between 0 (off) and 1e5 Hz (got %g)", (double)c->shot_rate);
    if (!(c->hot_fraction >= 0.0f) || !(c->hot_fraction <= 1.0f))
        BAD("hot pixel fraction must be between 0 and 1 (got %g)", (double)c->hot_fraction);
    if (!(c->hot_rate >= 0.0f) || !(c->hot_rate <= 1e5f))
        BAD("hot pixel rate must be between 0 and 1e5 Hz (got %g)", (double)c->hot_rate);
    if (!(c->time_res >= 1e-6 * (1.0 - 1e-9)) || !(c->time_res <= 0.1) ||
        fabs(c->time_res * 1e6 - floor(c->time_res * 1e6 + 0.5)) > 1e-6 * c->time_res * 1e6)
        BAD("timestamp resolution must be a whole number of microseconds from 1e-6 to 0.1 s (got %g)", c->time_res);
    if (!(c->time_jitter >= 0.0) || !(c->time_jitter <= 0.1))
        BAD("timestamp jitter must be between 0 and 0.1 s (got %g)", c->time_jitter);
    if (!(c->ambient >= 0.0f) || !isfinite(c->ambient)) BAD("ambient must be >= 0 (got %g)", (double)c->ambient);
    if (!isfinite(c->fps) || c->fps < 0.0 || c->fps > 1e6) BAD("fps must be a positive number of segments per second (got %g)", c->fps);
    if (!isfinite(c->duration) || c->duration < 0.0) BAD("duration must be a positive number of seconds (got %g)", c->duration);
    if (!isfinite(c->start) || c->start < 0.0) BAD("start time must be >= 0 seconds (got %g)", c->start);
    if (c->preview_window < 0.0 || !isfinite(c->preview_window)) BAD("preview window must be >= 0 seconds (got %g)", c->preview_window);
    if (c->backend != EVR_BACKEND_AUTO && c->backend != EVR_BACKEND_CPU && c->backend != EVR_BACKEND_CUDA)
        BAD("unknown backend %d", (int)c->backend);
    if (c->gpu_bvh != 0 && c->gpu_bvh != 4 && c->gpu_bvh != 8) BAD("unknown GPU BVH layout %d (4 or 8)", c->gpu_bvh);
    if (c->gi != 0 && c->gi != 1) BAD("unknown global illumination mode %d", c->gi);
    if (c->gi) {
        if (c->gather_max < 0 || c->gather_max > 65536) BAD("--gather-max must be between 0 (no limit) and 65536 (got %d)", c->gather_max);
        if (c->gather_window < 0 || c->gather_window > 256) BAD("--gather-window must be between 0 and 256 pixels (got %d)", c->gather_window);
        if (c->photon_layers < 1 || c->photon_layers > 64) BAD("--photon-layers must be between 1 and 64 (got %d)", c->photon_layers);
        if (c->gi_bounces < 0 || c->gi_bounces > 64) BAD("--gi-bounces must be between 0 and 64 (got %d)", c->gi_bounces);
        if (!isfinite(c->gather_radius) || c->gather_radius < 0.0f) BAD("--gather-radius must be a positive number or 0 (automatic), got %g", (double)c->gather_radius);
    }
    if (c->gpu_event_capacity < 0 || c->gpu_event_capacity > ((int64_t)1 << 31))
        BAD("GPU event capacity must be between 0 (automatic) and 2^31 (got %lld)", (long long)c->gpu_event_capacity);
    if (c->threads < 0 || c->threads > 4096) BAD("threads must be between 0 (all cores) and 4096 (got %d)", c->threads);
    if (!c->out_dir || !c->out_dir[0]) BAD("no output folder given");
    if (!c->formats || (c->formats & ~evr_event_formats_all())) BAD("no valid output format selected");
    if (c->frames_out && !c->frames_out[0]) BAD("frames folder is an empty path");
    if (!isfinite(c->frames_fps) || c->frames_fps < 0.0 || c->frames_fps > 1e6)
        BAD("frames fps must be a positive number of frames per second (got %g)", c->frames_fps);
    if (!(c->frames_exposure > 0.0f) || !isfinite(c->frames_exposure))
        BAD("frames exposure must be a positive number (got %g)", (double)c->frames_exposure);
    if (!(c->frames_max > 0.0f) || !isfinite(c->frames_max))
        BAD("frames max must be a positive intensity (got %g)", (double)c->frames_max);
    if (s) {
        if (c->camera && evr_scene_find_camera(s, c->camera) < 0) {
            char names[256] = "";
            size_t len = 0;
            int i;
            for (i = 0; i < s->num_cameras && len < 180; i++) {
                if (s->cameras[i].automatic) continue;
                len += (size_t)snprintf(names + len, sizeof names - len, "%s%.60s", len ? ", " : "", s->cameras[i].name);
            }
            BAD("no camera named '%s' in the scene (cameras: %s)", c->camera, names[0] ? names : "none");
        }
        double end = s->anim_end;
        if (end > 0.0) {
            if (c->start >= end) BAD("start time %g s is at or beyond the end of the animation (%g s)", c->start, end);
            if (c->duration > 0.0 && c->start + c->duration > end + 1e-6)
                BAD("duration %g s from %g s goes beyond the end of the animation (%g s)", c->duration, c->start, end);
        }
    }
    return EVR_OK;
}

char *evr_config_to_json(const evr_config *c, double duration, double fps, const char *scene, const char *camera,
                         const char *backend, int pretty)
{
    evr_json j;
    evr_json_init(&j, pretty);
    evr_json_begin_object(&j);
    evr_json_key(&j, "scene"); evr_json_string(&j, scene);
    evr_json_key(&j, "camera"); evr_json_string(&j, camera);
    evr_json_key(&j, "width"); evr_json_integer(&j, c->width);
    evr_json_key(&j, "height"); evr_json_integer(&j, c->height);
    evr_json_key(&j, "start"); evr_json_number(&j, c->start);
    evr_json_key(&j, "duration"); evr_json_number(&j, duration);
    evr_json_key(&j, "fps"); evr_json_number(&j, fps);
    evr_json_key(&j, "samples_per_frame"); evr_json_integer(&j, c->samples_per_frame);
    if (c->sampling == EVR_SAMPLING_ADAPTIVE) {
        evr_json_key(&j, "sampling"); evr_json_string(&j, "adaptive");
        evr_json_key(&j, "adapt_frac"); evr_json_float(&j, c->adapt_frac);
        evr_json_key(&j, "min_dt"); evr_json_number(&j, c->min_dt);
        evr_json_key(&j, "max_dt"); evr_json_number(&j, fmax(c->max_dt > 0.0 ? c->max_dt : 1.0 / fps, c->min_dt));
    } else {
        evr_json_key(&j, "sampling"); evr_json_string(&j, "uniform, per-pixel phase");
    }
    evr_json_key(&j, "pos_thres"); evr_json_float(&j, c->pos_thres);
    evr_json_key(&j, "neg_thres"); evr_json_float(&j, c->neg_thres);
    evr_json_key(&j, "refractory"); evr_json_float(&j, c->refractory);
    evr_json_key(&j, "log_floor"); evr_json_float(&j, c->log_floor);
    evr_json_key(&j, "sensor"); evr_json_string(&j, c->sensor);
    evr_json_key(&j, "sigma_thres"); evr_json_float(&j, c->sigma_thres);
    evr_json_key(&j, "cutoff_hz"); evr_json_float(&j, c->cutoff_hz);
    evr_json_key(&j, "full_intensity"); evr_json_float(&j, c->full_intensity);
    evr_json_key(&j, "leak_rate_hz"); evr_json_float(&j, c->leak_rate);
    evr_json_key(&j, "leak_jitter"); evr_json_float(&j, c->leak_jitter);
    evr_json_key(&j, "shot_noise_rate_hz"); evr_json_float(&j, c->shot_rate);
    evr_json_key(&j, "hot_pixel_fraction"); evr_json_float(&j, c->hot_fraction);
    evr_json_key(&j, "hot_pixel_rate_hz"); evr_json_float(&j, c->hot_rate);
    evr_json_key(&j, "time_res"); evr_json_number(&j, c->time_res);
    evr_json_key(&j, "time_jitter"); evr_json_number(&j, c->time_jitter);
    evr_json_key(&j, "ambient"); evr_json_float(&j, c->ambient);
    evr_json_key(&j, "seed"); evr_json_unsigned(&j, c->seed);
    evr_json_key(&j, "backend"); evr_json_string(&j, backend);
    evr_json_key(&j, "gpu_event_capacity"); evr_json_integer(&j, c->gpu_event_capacity);
    evr_json_key(&j, "skip"); evr_json_string(&j, c->no_skip ? "off" : "exact");
    evr_json_key(&j, "gpu_bvh"); evr_json_string(&j, c->gpu_bvh == 4 ? "bvh4" : c->gpu_bvh == 8 ? "cw8" : "default");
    evr_json_key(&j, "gi"); evr_json_string(&j, c->gi ? "photon" : "none");
    if (c->gi) {
        evr_json_key(&j, "photons"); evr_json_unsigned(&j, c->photons);
        evr_json_key(&j, "gather_radius"); evr_json_float(&j, c->gather_radius);
        evr_json_key(&j, "gather_max"); evr_json_integer(&j, c->gather_max);
        evr_json_key(&j, "gather_window"); evr_json_integer(&j, c->gather_window);
        evr_json_key(&j, "photon_layers"); evr_json_integer(&j, c->photon_layers);
        evr_json_key(&j, "gi_bounces"); evr_json_integer(&j, c->gi_bounces);
    }
    evr_json_key(&j, "preview_window"); evr_json_number(&j, c->preview_window);
    evr_json_key(&j, "frames_out"); evr_json_string(&j, c->frames_out);
    if (c->frames_out) {
        evr_json_key(&j, "frames_fps"); evr_json_number(&j, c->frames_fps > 0.0 ? c->frames_fps : fps);
        evr_json_key(&j, "frames_exposure"); evr_json_float(&j, c->frames_exposure);
        evr_json_key(&j, "frames_max"); evr_json_float(&j, c->frames_max);
    }
    evr_json_key(&j, "formats"); evr_json_begin_array(&j);
    {
        int k, count;
        const evr_event_format *const *formats = evr_event_formats(&count);
        for (k = 0; k < count; k++)
            if (c->formats & (1 << k)) evr_json_string(&j, formats[k]->name);
    }
    evr_json_end_array(&j);
    evr_json_end_object(&j);
    return evr_json_take(&j);
}
