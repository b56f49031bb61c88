/* The segment loop: scene motion per segment -> backend -> time-ordered events -> writers,
 * previews and run statistics. */
#include "sim_state.h"
#include "par_pool.h"
#include "host_clock.h"
#include "config/config_json.h"
#include "config/config_table.h"
#include "io/json.h"
#include "io/preview.h"
#include "run/run_files.h"
#include "run/frames_out.h"
#include "run/camera_poses.h"
#include "run/labels_out.h"
#include "run/event_sink.h"
#include "prep/gi_params.h"
#ifdef EVR_HAVE_CUDA
#include "cuda/cuda_backend.h"
#endif

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

const char *evr_version(void) { return EVR_VERSION; }

static evr_status nomem(evr_error *err)
{
    snprintf(err->msg, sizeof err->msg, "out of memory");
    return EVR_ERR_NOMEM;
}

static void mark_used(evr_sim *sim, int node)
{
    /* a node's motion depends on its ancestors, but keys are computed for the node's world
     * transform, so only the node itself needs a track */
    if (node >= 0) sim->node_used[node] = 1;
}

/* The GPU BVH cache's folder for the setting ("auto", "off" or a folder) into buf; NULL: none
 * (off, or auto without a home to put it in). */
static const char *bvh_cache_dir(const char *opt, char *buf, size_t n)
{
    const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    buf[0] = 0;
    if (!opt || strcmp(opt, "off") == 0) return NULL;
    if (strcmp(opt, "auto") != 0) snprintf(buf, n, "%s", opt);
    else if (xdg && xdg[0] == '/') snprintf(buf, n, "%s/evray", xdg); /* the XDG spec: absolute */
    else if (home && home[0]) snprintf(buf, n, "%s/.cache/evray", home);
    return buf[0] ? buf : NULL;
}

/* The backend the configuration asks for; auto tries CUDA first and says why it did not. */
static evr_status make_backend(evr_sim *sim, evr_error *err)
{
    const evr_scene *s = sim->scene;
    evr_backend_kind kind = sim->cfg.backend;
    evr_status st;
#ifdef EVR_HAVE_CUDA
    if (kind == EVR_BACKEND_CUDA || kind == EVR_BACKEND_AUTO) {
        evr_error cerr;
        cerr.msg[0] = 0;
        st = evr_cuda_backend_new(s, &sim->host, &sim->setup, &sim->backend, &cerr);
        if (st == EVR_OK) {
            snprintf(sim->st.backend, sizeof sim->st.backend, "cuda");
            snprintf(sim->st.device, sizeof sim->st.device, "%s",
                     evr_cuda_device_name(sim->backend));
            return EVR_OK;
        }
        if (kind == EVR_BACKEND_CUDA) {
            *err = cerr;
            return st;
        }
        snprintf(sim->st.notice, sizeof sim->st.notice,
                 "CUDA backend not used: %s; running on the CPU", cerr.msg);
    }
#else
    if (kind == EVR_BACKEND_CUDA) {
        snprintf(err->msg, sizeof err->msg,
                 "this evray was built without CUDA (nvcc was not found at build time)");
        return EVR_ERR_BACKEND;
    }
#endif
    if ((st = evr_cpu_backend_new(s, &sim->host, &sim->setup, &sim->backend, err)) != EVR_OK)
        return st;
    snprintf(sim->st.backend, sizeof sim->st.backend, "cpu");
    snprintf(sim->st.device, sizeof sim->st.device, "%d CPU threads",
             evr_cpu_backend_threads(sim->backend));
    return EVR_OK;
}

/* How far timestamp jitter (clipped) and rounding to the resolution can move an event's
 * timestamp from its crossing, in microseconds (0 for exact timestamps). */
static int64_t timestamp_slack_us(const evr_sim *sim)
{
    if (sim->cfg.time_jitter <= 0.0 && sim->setup.pixel.time_res_us <= 1) return 0;
    return (int64_t)ceil((double)EVR_JITTER_CLIP * sim->cfg.time_jitter * 1e6) +
           sim->setup.pixel.time_res_us;
}

/* The writers' flush interval: EVR_WRITE_FLUSH_SECONDS, or the hidden EVR_FLUSH_SECONDS (tests
 * flush after every batch with 0 to show that when files are flushed changes none of their
 * bytes). */
static double flush_seconds(void)
{
    const char *v = getenv("EVR_FLUSH_SECONDS");
    char *end;
    double s = v ? strtod(v, &end) : 0.0;
    return v && end != v && !*end && s >= 0.0 && s <= 1e6 ? s : EVR_WRITE_FLUSH_SECONDS;
}

/* The run's wall time so far, and the rates that follow from it, into sim->st. */
static void set_wall(evr_sim *sim)
{
    sim->st.wall_time = evr_host_seconds() - sim->wall0;
    sim->st.samples_per_second =
        sim->st.wall_time > 0 ? (double)sim->st.samples / sim->st.wall_time : 0.0;
    sim->st.rays_per_second =
        sim->st.wall_time > 0 ? (double)sim->st.rays / sim->st.wall_time : 0.0;
    sim->st.realtime_factor = sim->st.wall_time > 0 ? sim->st.sim_time / sim->st.wall_time : 0.0;
}

evr_status evr_sim_new(const evr_scene *s, const evr_config *c, evr_sim **out, evr_error *err)
{
    evr_status st;
    int i;
    *out = NULL;
    evr_config cur;
    const double t_new = evr_host_seconds();
    if ((st = evr_config_validate(c, s, err)) != EVR_OK ||
        (st = evr_config_current(c, &cur, err)) != EVR_OK)
        return st;
    c = &cur; /* this library's evr_config, whatever the caller's size */
    evr_sim *sim = calloc(1, sizeof *sim);
    if (!sim) return nomem(err);
    sim->scene = s;
    sim->cfg = *c;
    snprintf(sim->out_dir, sizeof sim->out_dir, "%s", c->out_dir);
    sim->cfg.out_dir = sim->out_dir;
    sim->cfg.camera = NULL; /* not owned; the index below is what counts */
    if (c->sensor) {        /* not owned either: keep the library's own copy of the name */
        const char *const *names = evr_sensor_names();
        for (i = 0; names[i]; i++)
            if (!strcmp(names[i], c->sensor)) sim->cfg.sensor = names[i];
    }
    if (c->camera_path) { /* kept: the configuration's strings are the caller's */
        snprintf(sim->camera_path, sizeof sim->camera_path, "%s", c->camera_path);
        sim->cfg.camera_path = sim->camera_path;
    }
    sim->camera = c->camera ? evr_scene_find_camera(s, c->camera) : 0;
    if ((st = evr_camera_rig_init(&sim->rig, s, sim->camera, c, err)) != EVR_OK) {
        evr_camera_rig_free(&sim->rig);
        free(sim);
        return st;
    }
    const double path_end = evr_camera_rig_path_end(&sim->rig);
    evr_config_run_span(c, s, &sim->duration, &sim->fps); /* bounded by evr_config_validate */
    if (!(c->duration > 0.0) && path_end > c->start) {
        sim->duration = path_end - c->start; /* the trajectory's */
        if (!(sim->duration <= EVR_MAX_DURATION)) {
            snprintf(err->msg, sizeof err->msg,
                     "the camera's trajectory runs %g s from --start: more than %g s cannot be "
                     "simulated (give --duration)",
                     sim->duration, EVR_MAX_DURATION);
            evr_camera_rig_free(&sim->rig);
            free(sim);
            return EVR_ERR_ARG;
        }
    }
    sim->num_segments = (int)ceil(sim->duration * sim->fps - 1e-9);
    if (sim->num_segments < 1) sim->num_segments = 1;
    if ((st = evr_camera_rig_setup(&sim->rig, c, c->start, c->start + sim->duration, err)) !=
            EVR_OK ||
        (st = evr_render_host_init(&sim->host, s, sim->camera, c->width, c->height, c->ambient,
                                   err)) != EVR_OK) {
        evr_camera_rig_free(&sim->rig);
        free(sim);
        return st;
    }
    /* the camera as the rig says: its projection, and a fixed pose or a track of its own */
    evr_render_scene *rs = &sim->host.rs;
    rs->camera = sim->rig.ortho ? evr_camera_intr_ortho(c->width, c->height, sim->rig.ymag)
                                : evr_camera_intr_make(c->width, c->height, sim->rig.yfov);
    sim->num_tracks = s->num_nodes + 1;
    if (sim->rig.has_path) {
        rs->camera_track = sim->num_tracks++;
        rs->camera_local = evr_m34_identity();
    } else if (sim->rig.node < 0) {
        rs->camera_track = s->num_nodes; /* the world frame */
        rs->camera_local = sim->rig.local;
    }
    sim->poses_last = evr_quat_make(1, 0, 0, 0);
    sim->host.rs.max_bounces = c->max_bounces;
    sim->setup.width = c->width;
    sim->setup.height = c->height;
    sim->setup.samples_per_frame = evr_config_samples_per_frame(c);
    sim->setup.seed = c->seed;
    sim->setup.pixel.pos_thres = c->pos_thres;
    sim->setup.pixel.neg_thres = c->neg_thres;
    sim->setup.pixel.refractory = c->refractory;
    sim->setup.pixel.log_floor = c->log_floor;
    sim->setup.pixel.sigma_thres = c->sigma_thres;
    sim->setup.pixel.cutoff_hz = c->cutoff_hz;
    sim->setup.pixel.full_intensity = c->full_intensity;
    sim->setup.pixel.leak_rate = c->leak_rate;
    sim->setup.pixel.leak_jitter = c->leak_jitter;
    sim->setup.pixel.shot_rate = c->shot_rate;
    sim->setup.pixel.hot_fraction = c->hot_fraction;
    sim->setup.pixel.hot_rate = c->hot_rate;
    sim->setup.pixel.time_jitter = (float)c->time_jitter;
    sim->setup.pixel.time_res_us = (int)llround(c->time_res * 1e6);
    sim->setup.pixel.seed = c->seed;
    sim->setup.threads = c->threads;
    sim->setup.gpu_bvh = c->gpu_bvh;
    sim->setup.bvh_cache = bvh_cache_dir(c->bvh_cache, sim->bvh_cache, sizeof sim->bvh_cache);
    sim->setup.gpu_event_capacity = c->gpu_event_capacity;
    sim->setup.adaptive = c->sampling == EVR_SAMPLING_ADAPTIVE;
    sim->setup.refine = evr_config_sampling(c) == EVR_SAMPLING_REFINE;
    sim->setup.refine_params.tol = (float)c->time_tol;
    sim->setup.refine_params.n = sim->setup.samples_per_frame;
    sim->setup.refine_params.px = (float)c->refine_px;
    sim->setup.event_ids = c->event_ids;
    sim->setup.adapt.frac = c->adapt_frac;
    sim->setup.adapt.min_dt = (float)c->min_dt;
    sim->setup.adapt.max_dt = (float)(c->max_dt > 0.0 ? c->max_dt : 1.0 / sim->fps);
    if (sim->setup.adapt.max_dt < sim->setup.adapt.min_dt)
        sim->setup.adapt.max_dt = sim->setup.adapt.min_dt;
    sim->setup.gi = c->gi;
    sim->setup.photons = c->photons;
    sim->setup.gather_radius =
        c->gather_radius > 0.0f ? c->gather_radius : 0.02f * sim->host.scene_size;
    sim->setup.gather_max = c->gather_max;
    sim->setup.gather_window = c->gather_window;
    sim->setup.photon_layers =
        evr_gi_photon_layers(c->photon_layers, c->photons, sim->setup.width, sim->setup.height);
    sim->st.photon_layers = sim->setup.photon_layers;
    sim->setup.gi_bounces = c->gi_bounces;
    sim->setup.gi_blur = c->gi_blur;
    sim->timestamp_slack_us = timestamp_slack_us(sim);
    sim->setup.cancel = &sim->cancel;
    sim->emitted_until_us = (int64_t)llround(c->start * 1e6);
    sim->st.complete_until = c->start;

    int ntracks = sim->num_tracks;
    sim->node_used = calloc((size_t)ntracks, sizeof(int));
    sim->par = evr_par_pool_new(evr_par_threads(8)); /* NULL: counted on this thread */
    if (!sim->node_used || !evr_skip_tracker_init(&sim->skip, ntracks) ||
        !evr_skip_tracker_parts(&sim->skip, s) ||
        !evr_deform_tracker_init(&sim->deform, s, &sim->host) ||
        !(sim->skipped_per_segment =
              calloc((size_t)sim->num_segments, sizeof *sim->skipped_per_segment))) {
        evr_sim_release(sim);
        return nomem(err);
    }
    if ((st = evr_frames_plan(sim, err)) != EVR_OK || (st = evr_labels_plan(sim, err)) != EVR_OK) {
        evr_sim_release(sim);
        return st;
    }
    if (c->event_ids && s->num_instances > EVR_MAX_EVENT_ID) {
        snprintf(err->msg, sizeof err->msg,
                 "event ids name at most %d instances (16 bits an event); this scene has %d",
                 EVR_MAX_EVENT_ID, s->num_instances);
        evr_sim_release(sim);
        return EVR_ERR_ARG;
    }
    for (i = 0; i < s->num_instances; i++) mark_used(sim, s->instances[i].node);
    for (i = 0; i < s->num_lights; i++) mark_used(sim, s->lights[i].node);
    if (!sim->rig.has_path) mark_used(sim, sim->rig.node);

    double t_setup = evr_host_seconds();
    sim->time_setup_host = t_setup - t_new;
    st = make_backend(sim, err);
    sim->time_setup = evr_host_seconds() - t_setup;
    if (st != EVR_OK) {
        evr_sim_release(sim);
        return st;
    }
    if (sim->backend->notice[0] && !sim->st.notice[0])
        snprintf(sim->st.notice, sizeof sim->st.notice, "%s", sim->backend->notice);
    sim->config_json = evr_config_to_json(&sim->cfg, sim->duration, sim->fps, s->source,
                                          s->cameras[sim->camera].name, sim->backend->name, 0);
    if (!sim->config_json) {
        evr_sim_release(sim);
        return nomem(err);
    }
    if ((st = evr_frames_check(sim, err)) != EVR_OK) {
        evr_sim_release(sim);
        return st;
    }
    if ((st = evr_run_dir_prepare(sim, err)) != EVR_OK) {
        evr_run_dir_discard(sim);
        evr_sim_release(sim);
        return st;
    }
    if (sim->labels && evr_labels_times(sim) && !sim->backend->label_hits) {
        snprintf(err->msg, sizeof err->msg, "the %s backend cannot make label frames",
                 sim->backend->name);
        evr_sim_release(sim);
        return EVR_ERR_ARG;
    }
    if ((st = evr_frames_prepare(sim, err)) != EVR_OK ||
        (st = evr_camera_poses_open(sim, err)) != EVR_OK ||
        (st = evr_labels_open(sim, err)) != EVR_OK) {
        evr_run_dir_discard(sim);
        evr_sim_release(sim);
        return st;
    }
    if ((st = evr_run_writers_open(sim, err)) != EVR_OK ||
        (st = evr_write_queue_start(sim->writers, sim->num_writers, flush_seconds(), &sim->wq,
                                    err)) != EVR_OK) {
        evr_run_dir_discard(sim);
        evr_sim_release(sim);
        return st;
    }
    sim->st.segments_total = sim->num_segments;
    sim->last_t = INT64_MIN;
    *out = sim;
    return EVR_OK;
}

static double segment_start(const evr_sim *sim, int i)
{
    return sim->cfg.start + (double)i / sim->fps;
}
static double segment_end(const evr_sim *sim, int i)
{
    return i + 1 == sim->num_segments ? sim->cfg.start + sim->duration : segment_start(sim, i + 1);
}

/* Plans segment i (on the planner's thread, in order): motion keys of every used node over the
 * segment (the extra last track is the fixed world frame), the tracker, and the plans. */
static void plan_segment(void *user, int i, evr_planned_segment *out)
{
    evr_sim *sim = user;
    const evr_scene *s = sim->scene;
    const double t0 = segment_start(sim, i), t1 = segment_end(sim, i);
    int off = 0;
    float tol = 1e-5f;
    for (int n = 0; n <= s->num_nodes; n++) {
        evr_motion_key *k = out->keys + off;
        int c = 1;
        if (n < s->num_nodes && sim->node_used[n]) {
            c = evr_node_motion_keys(s, n, t0, t1, tol, k, EVR_MAX_KEYS);
        } else {
            evr_m34 id = evr_m34_identity();
            *k = evr_motion_key_from_matrix(&id);
        }
        out->track_offset[n] = off;
        out->track_count[n] = c;
        off += c;
    }
    if (sim->rig.has_path) { /* the camera's own track, last */
        out->track_offset[s->num_nodes + 1] = off;
        out->track_count[s->num_nodes + 1] =
            evr_camera_rig_keys(&sim->rig, t0, t1, tol, out->keys + off, EVR_MAX_KEYS);
        off += out->track_count[s->num_nodes + 1];
    }
    out->num_keys = off;
    evr_skip_tracker_update(&sim->skip, out->keys, out->track_offset, out->track_count,
                            sim->host.scene_size);
    out->failed =
        !evr_deform_keys_make(&sim->deform, s, &sim->host, t0, t1, tol, EVR_MAX_KEYS, &out->deform);
    evr_render_scene rs = sim->host.rs;
    rs.keys = out->keys;
    rs.track_offset = out->track_offset;
    rs.track_count = out->track_count;
    rs.deforms = out->deform.views;
    const evr_deform_keys *dk = out->failed ? NULL : &out->deform;
    evr_skip_plan_build(&sim->skip, s, &rs, dk, !sim->cfg.no_skip && !sim->setup.adaptive,
                        &out->plan);
    if (sim->setup.adaptive || sim->setup.refine)
        evr_adapt_plan_build(&sim->skip, s, &rs, dk, &sim->setup.adapt, t1 - t0, &out->adapt);
}

/* The sums of one part: branch-free in locals (ON and OFF alternate at random), about 10x faster
 * than counting per branch. */
static void count_part(void *ctx, int k, int thread)
{
    evr_event_counts *c = (evr_event_counts *)ctx + k;
    (void)thread;
    uint64_t on = 0, changes = 0;
    int64_t last = c->prev;
    for (size_t i = 0; i < c->n; i++) {
        on += c->ev[i].p != 0;
        changes += c->ev[i].t != last;
        last = c->ev[i].t;
    }
    c->on = on;
    c->changes = changes;
}

/* Adds the batch being counted, if any, to the run's ON/OFF and unique timestamp counts. */
static void count_events_finish(evr_sim *sim)
{
    if (!sim->count_parts) return;
    evr_par_pool_wait(sim->par);
    for (int k = 0; k < sim->count_parts; k++) {
        sim->st.events_on += sim->counting[k].on;
        sim->st.events_off += sim->counting[k].n - sim->counting[k].on;
        sim->st.unique_timestamps += sim->counting[k].changes;
    }
    sim->count_parts = 0;
    evr_batch_mark *m = &sim->marks[sim->counting_batch % EVR_BATCH_MARKS];
    m->events = sim->st.events_on + sim->st.events_off;
    m->on = sim->st.events_on;
    m->unique = sim->st.unique_timestamps;
}

/* Starts counting ev[0 .. n) in parts on the pool; the writers only read the events, so the loop
 * goes on meanwhile (counted on the main thread, the eye's 218.7 M events took 0.57 s of it, and
 * 0.3-0.5 s on the pool while it waited). The events stay where they are until
 * count_events_finish: the write queue hands a taken buffer back no sooner than the next push. */
static void count_events_start(evr_sim *sim, const evr_event *ev, size_t n)
{
    size_t parts = n >> 16; /* 65,536 events a part at least */
    count_events_finish(sim);
    if (parts < 1) parts = 1;
    if (parts > EVR_COUNT_PARTS) parts = EVR_COUNT_PARTS;
    for (size_t k = 0; k < parts; k++) {
        size_t i0, i1;
        evr_par_share(n, (int)parts, (int)k, &i0, &i1);
        evr_event_counts *c = &sim->counting[k];
        c->ev = ev + i0;
        c->n = i1 - i0;
        c->prev = i0 ? ev[i0 - 1].t : sim->last_t;
    }
    if (n) sim->last_t = ev[n - 1].t;
    sim->count_parts = (int)parts;
    sim->counting_batch = sim->batches; /* the batch about to be pushed */
    if (sim->par) evr_par_pool_start(sim->par, (int)parts, count_part, sim->counting);
    else evr_par_pool_run(NULL, (int)parts, count_part, sim->counting); /* no pool: here, now */
}

/* Hands events up to (not including) limit_us to the writers and statistics. */
static evr_status emit_events(evr_sim *sim, int64_t limit_us, evr_error *err)
{
    evr_event_vec *v = &sim->pending;
    size_t n = evr_events_before(v->data, v->n, limit_us);
    evr_status st;
    double t = evr_host_seconds();
    /* no event before limit_us is to come: the previews' windows that end by then are done */
    if (n == 0) {
        st = evr_run_preview_events(sim, NULL, 0, limit_us, err);
        sim->time_preview += evr_host_seconds() - t;
        if (st == EVR_OK) sim->emitted_until_us = limit_us;
        return st;
    }
    count_events_start(sim, v->data, n); /* finishes the batch before it first */
    sim->time_write += evr_host_seconds() - t;
    t = evr_host_seconds();
    if ((st = evr_run_preview_events(sim, v->data, n, limit_us, err)) != EVR_OK) return st;
    sim->time_preview += evr_host_seconds() - t;
    t = evr_host_seconds();
    /* the writers take the buffer; the events held back move to one of the queue's */
    sim->marks[sim->batches % EVR_BATCH_MARKS].before_us = sim->emitted_until_us;
    if ((st = evr_write_queue_push_take(sim->wq, v, n, err)) != EVR_OK) return st;
    sim->batches++;
    sim->emitted_until_us = limit_us;
    sim->time_write += evr_host_seconds() - t;
    return EVR_OK;
}

/* A piece of a segment's events (evr_backend.emit_piece): written as a segment's would be. */
static evr_status emit_piece(void *user, int64_t limit_us, evr_error *err)
{
    evr_sim *sim = user;
    const double t = evr_host_seconds();
    evr_status st = emit_events(sim, limit_us, err);
    sim->time_piece_emit += evr_host_seconds() - t;
    return st;
}

static evr_status submit_segment(evr_sim *sim, int i, evr_error *err)
{
    evr_segment seg;
    seg.index = i;
    seg.t0 = segment_start(sim, i);
    seg.t1 = segment_end(sim, i);
    const double tw = evr_host_seconds();
    const evr_planned_segment *pl = evr_planner_take(sim->planner, i);
    sim->time_plan_wait += evr_host_seconds() - tw;
    if (i == 0) sim->time_first_plan = evr_host_seconds() - sim->wall0; /* the planner started */
    if (pl->failed) {
        evr_planner_release(sim->planner, i);
        return nomem(err);
    }
    seg.deforms = pl->deform.views;
    seg.deform_moved = pl->deform.moved;
    seg.num_deforms = pl->deform.num_deforms;
    seg.keys = pl->keys;
    seg.track_offset = pl->track_offset;
    seg.track_count = pl->track_count;
    seg.num_tracks = sim->num_tracks;
    seg.num_keys = pl->num_keys;
    seg.camera_static = pl->track_count[sim->host.rs.camera_track] == 1;
    seg.skip = &pl->plan;
    seg.adapt = sim->setup.adaptive || sim->setup.refine ? &pl->adapt : NULL;
    seg.want_intensity = evr_run_preview_due(sim, seg.t1, i + 1 == sim->num_segments);
    { /* the camera's poses as the backend renders them */
        evr_render_scene rs = sim->host.rs;
        rs.keys = pl->keys;
        rs.track_offset = pl->track_offset;
        rs.track_count = pl->track_count;
        evr_status pst =
            evr_camera_poses_segment(sim, &rs, seg.t0, seg.t1, i + 1 == sim->num_segments, err);
        if (pst != EVR_OK) {
            evr_planner_release(sim->planner, i);
            return pst;
        }
    }
    int first;
    evr_frames_of_segment(sim, i, &first, &seg.num_frames);
    seg.frame_times = seg.num_frames ? sim->frame_times + first : NULL;
    evr_labels_of_segment(sim, i, &first, &seg.num_labels);
    seg.label_times = seg.num_labels ? evr_labels_times(sim) + first : NULL;
    double t =
        evr_host_seconds(); /* the CPU backend renders inside submit, a GPU only queues work */
    evr_status st = sim->backend->submit(sim->backend, &seg, err);
    sim->time_render += evr_host_seconds() - t;
    evr_planner_release(sim->planner, i); /* the backend has what it needs of the plan */
    return st;
}

static int cancelled(const evr_sim *sim) { return __atomic_load_n(&sim->cancel, __ATOMIC_RELAXED); }

/* Segment i's events: merged into the pending (time-ordered) events, of which those that no
 * later segment can precede go to the writers (all of them after the last segment). */
static evr_status finish_segment(evr_sim *sim, int i, int last, evr_error *err)
{
    const int final = last;
    const int n = sim->setup.samples_per_frame;
    const float *intensity = NULL, *frames = NULL;
    double t0 = segment_start(sim, i), t1 = segment_end(sim, i);
    evr_status st;
    /* Later segments can still produce events back to every pixel's last sample here, which
     * is no earlier than t0 + (n-1)/n of the segment: hold those back to keep file order (the
     * last segment the loop finishes holds back none). */
    int64_t safe =
        final ? INT64_MAX : (int64_t)floor((t0 + (t1 - t0) * (double)(n - 1) / (double)n) * 1e6);
    /* adaptive sampling: a pixel's last sample here is no earlier than t1 - max_dt */
    if (!final && sim->setup.adaptive)
        safe = (int64_t)floor((t1 - (double)sim->setup.adapt.max_dt) * 1e6) - 1;
    /* timestamp jitter and rounding to the resolution can move a later event earlier still */
    if (!final) safe -= sim->timestamp_slack_us;
    double t = evr_host_seconds();
    sim->time_piece_emit = 0.0;
    if ((st = sim->backend->collect(sim->backend, &sim->pending, safe, &intensity, &frames, err)) !=
        EVR_OK)
        return st;
    sim->time_render += evr_host_seconds() - t - sim->time_piece_emit;
    if ((st = emit_events(sim, safe, err)) != EVR_OK)
        return st; /* written and flushed on the writer thread */
    if (intensity) {
        t = evr_host_seconds();
        if ((st = evr_run_preview_intensity(sim, intensity, t1, last, err)) != EVR_OK) return st;
        sim->time_preview += evr_host_seconds() - t;
    }
    int first, count, k;
    evr_frames_of_segment(sim, i, &first, &count);
    if (count && !frames) {
        snprintf(err->msg, sizeof err->msg,
                 "internal error: the backend returned no intensity frames");
        return EVR_ERR_BACKEND;
    }
    t = evr_host_seconds();
    for (k = 0; k < count; k++) {
        size_t npix = (size_t)sim->cfg.width * (size_t)sim->cfg.height;
        if ((st = evr_frames_write(sim, first + k, frames + (size_t)k * npix, err)) != EVR_OK)
            return st;
    }
    sim->time_preview += evr_host_seconds() - t;
    if (sim->labels) {
        t = evr_host_seconds();
        const evr_hit *hits =
            sim->backend->label_hits ? sim->backend->label_hits(sim->backend) : NULL;
        if ((st = evr_labels_segment(sim, i, t0, t1, last, hits, err)) != EVR_OK) return st;
        sim->time_preview += evr_host_seconds() - t;
    }
    sim->st.segments_done = i + 1;
    sim->st.samples = sim->backend->samples;
    sim->st.rays = sim->backend->rays;
    sim->st.samples_traced = sim->backend->samples_traced;
    sim->skipped_per_segment[i] = (uint32_t)(sim->backend->pixels_skipped - sim->st.pixels_skipped);
    sim->st.pixels_skipped = sim->backend->pixels_skipped;
    sim->st.time_photons = sim->backend->photon_seconds;
    sim->st.photons_stored = sim->backend->photons_stored;
    sim->st.photon_collisions = sim->backend->photon_collisions;
    sim->st.photons_traced = sim->backend->photons_traced;
    sim->st.photons_reused = sim->backend->photons_reused;
    sim->st.photon_cells_changed = sim->backend->photon_cells_changed;
    sim->st.sim_time = t1 - sim->cfg.start;
    set_wall(sim);
    return EVR_OK;
}

evr_status evr_sim_run(evr_sim *sim, evr_progress_fn progress, void *user, evr_error *err)
{
    evr_status st = EVR_OK;
    int submitted = 0, i, stop = 0;
    sim->wall0 = evr_host_seconds();
    sim->backend->emit_piece = emit_piece;
    sim->backend->emit_user = sim;
    /* keep the backend's depth of segments in flight (at least two: one renders while the previous
     * one is taken in and written) */
    const int depth = sim->backend->depth > 2 ? sim->backend->depth : 2;
    if (!sim->planner) {
        sim->planner = evr_planner_start(sim->num_segments, (size_t)sim->num_tracks * EVR_MAX_KEYS,
                                         sim->num_tracks, plan_segment, sim);
        if (!sim->planner) return nomem(err);
    }
    if ((st = submit_segment(sim, 0, err)) == EVR_OK) submitted = 1;
    for (i = 0; st == EVR_OK && i < submitted; i++) {
        while (!stop && st == EVR_OK && submitted < sim->num_segments && submitted < i + depth) {
            if ((st = submit_segment(sim, submitted, err)) != EVR_OK) break;
            submitted++;
        }
        if (st == EVR_OK && cancelled(sim)) st = EVR_ERR_INTERRUPTED; /* not one more segment */
        if (st != EVR_OK) break;
        if ((st = finish_segment(sim, i, i + 1 == sim->num_segments, err)) != EVR_OK) break;
        if (progress && progress(user, &sim->st)) stop = 1;
    }
    sim->time_motion = evr_planner_busy_seconds(sim->planner);
    evr_planner_stop(sim->planner); /* stops early when the run did */
    sim->planner = NULL;
    count_events_finish(sim);
    set_wall(sim);
    if (st != EVR_OK && st != EVR_ERR_INTERRUPTED) return evr_run_fail(sim, st, err);
    /* Stopped (or cancelled: the segments in flight given up), the events held back are not
     * kept: the next segment's samples would have added events before them. The files hold
     * every event before the last limit emitted, and say so. */
    sim->st.interrupted = st == EVR_ERR_INTERRUPTED || sim->st.segments_done < sim->num_segments;
    sim->st.complete_until = sim->emitted_until_us == INT64_MAX
                                 ? sim->cfg.start + sim->duration
                                 : (double)sim->emitted_until_us * 1e-6;
    if ((st = evr_run_close(sim, err)) != EVR_OK) return st;
    set_wall(sim); /* the run's wall time includes draining and closing every output */
    if ((st = evr_run_write_json(sim, err)) != EVR_OK) {
        /* no outputs without the run.json that says what they are */
        evr_run_dir_discard(sim);
        return st;
    }
    return sim->st.interrupted ? EVR_ERR_INTERRUPTED : EVR_OK;
}

void evr_sim_cancel(evr_sim *sim)
{
    if (sim) __atomic_store_n(&sim->cancel, 1, __ATOMIC_RELAXED);
}

evr_status evr_sim_set_sink(evr_sim *sim, evr_event_sink_fn sink, void *user, evr_error *err)
{
    if (!sink) return EVR_OK;
    if (sim->sink || sim->batches || sim->st.segments_done || !sim->wq) {
        snprintf(err->msg, sizeof err->msg,
                 sim->sink ? "the run has a sink already"
                           : "a sink can only be set before the run starts");
        return EVR_ERR_ARG;
    }
    evr_event_writer *w = evr_event_sink_new(sink, user, &sim->cancel);
    if (!w) return nomem(err);
    evr_status st = evr_write_queue_add(sim->wq, w, err);
    if (st != EVR_OK) {
        evr_event_sink_free(w);
        return st;
    }
    sim->sink = w;
    return EVR_OK;
}

const evr_stats *evr_sim_stats(const evr_sim *sim) { return &sim->st; }

void evr_sim_release(evr_sim *sim)
{
    int w;
    if (!sim) return;
    evr_write_queue_stop(sim->wq);
    evr_event_sink_free(sim->sink); /* the queue has stopped calling it */
    for (w = 0; w < sim->num_writers; w++)
        if (sim->writers[w]) sim->writers[w]->abort(sim->writers[w]);
    if (sim->backend) sim->backend->release(sim->backend);
    evr_render_host_free(&sim->host);
    evr_event_vec_free(&sim->pending);
    evr_event_vec_free(&sim->scratch);
    evr_planner_stop(sim->planner);
    evr_par_pool_free(sim->par);
    free(sim->node_used);
    evr_skip_tracker_free(&sim->skip);
    evr_deform_tracker_free(&sim->deform);
    free(sim->skipped_per_segment);
    free(sim->config_json);
    evr_preview_out_release(sim->preview);
    evr_frames_free(sim);
    evr_camera_poses_discard(sim); /* nothing when the run closed it */
    free(sim->poses_tmp);
    evr_camera_rig_free(&sim->rig);
    evr_labels_free(sim);
    free(sim);
}
