#include "run/run_files.h"
#include "run/frames_out.h"
#include "run/camera_poses.h"
#include "run/labels_out.h"
#include "run/instance_table.h"
#include "io/mkdir_p.h"
#include "io/file_commit.h"
#include "io/event_formats.h"
#include "io/json.h"
#include "io/preview.h"

#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <assimp/version.h>
#include <embree3/rtcore_config.h>
#include <H5public.h>

static evr_status path_join(char *out, size_t n, const char *dir, const char *name, evr_error *err)
{
    if ((size_t)snprintf(out, n, "%s/%s", dir, name) >= n) {
        snprintf(err->msg, sizeof err->msg, "output path too long: %s/%s", dir, name);
        return EVR_ERR_ARG;
    }
    return EVR_OK;
}

/* The reserve: a file of EVR_RESERVE_BYTES made when the run starts and removed when it ends, or
 * as soon as a write fails, so that a full disk still leaves room to complete the files (the
 * HDF5 file's last chunk, index and metadata, run.json, the video's end). */
#define EVR_RESERVE_FILE ".evray-reserve"
#define EVR_RESERVE_BYTES ((off_t)2 << 20)

static evr_status make_reserve(evr_sim *sim, evr_error *err)
{
    char p[4200];
    int fd, r;
    evr_status st;
    if ((st = path_join(p, sizeof p, sim->out_dir, EVR_RESERVE_FILE, err)) != EVR_OK) return st;
    fd = open(p, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        snprintf(err->msg, sizeof err->msg, "cannot write in %s: %s", sim->out_dir,
                 strerror(errno));
        return EVR_ERR_IO;
    }
    r = posix_fallocate(fd, 0, EVR_RESERVE_BYTES); /* an error number, not errno */
    close(fd);
    if (r == 0) {
        sim->reserve_made = 1;
        return EVR_OK;
    }
    remove(p);
    if (r == ENOSPC || r == EDQUOT) {
        snprintf(err->msg, sizeof err->msg,
                 "not enough free space in %s: a run needs at least %d MB free to start (kept "
                 "in reserve to complete its files should the disk fill up)",
                 sim->out_dir, (int)(EVR_RESERVE_BYTES >> 20));
        return EVR_ERR_IO;
    }
    return EVR_OK; /* e.g. a file size limit below it: the run goes on without a reserve */
}

static void release_reserve(evr_sim *sim)
{
    char p[4200];
    if (!sim->reserve_made) return;
    snprintf(p, sizeof p, "%s/%s", sim->out_dir, EVR_RESERVE_FILE);
    remove(p);
    sim->reserve_made = 0;
}

/* Whether name (in the run folder, or in its preview/ when in_preview) is a file evray writes. */
static int owned_name(const char *name, int in_preview)
{
    static const char *const fixed[] = {"run.json",         "preview.apng", EVR_RESERVE_FILE,
                                        "camera_poses.txt", "labels.h5",    "imu.txt",
                                        "node_poses.txt",   "eye.txt"};
    char base[256];
    size_t n = strlen(name);
    int i, count;
    if (n >= sizeof base) return 0;
    strcpy(base, name);
    if (n > 4 && !strcmp(base + n - 4, ".tmp")) base[n - 4] = 0; /* and its temporary file */
    if (in_preview)
        return (!strncmp(base, "events_", 7) || !strncmp(base, "intensity_", 10)) &&
               strlen(base) > 4 && !strcmp(base + strlen(base) - 4, ".png");
    for (i = 0; i < (int)(sizeof fixed / sizeof fixed[0]); i++)
        if (!strcmp(base, fixed[i])) return 1;
    const evr_event_format *const *formats = evr_event_formats(&count);
    for (i = 0; i < count; i++)
        if (!strcmp(base, formats[i]->file)) return 1;
    return 0;
}

/* Removes the files evray writes in folder dir (in_preview: its preview/ folder); others stay. */
static void remove_owned(const char *dir, int in_preview)
{
    DIR *d = opendir(dir);
    struct dirent *de;
    char p[4600];
    if (!d) return;
    while ((de = readdir(d)) != NULL) {
        if (!owned_name(de->d_name, in_preview)) continue;
        snprintf(p, sizeof p, "%s/%s", dir, de->d_name);
        remove(p);
    }
    closedir(d);
}

void evr_run_dir_clean(const char *dir)
{
    char p[4200];
    snprintf(p, sizeof p, "%s/preview", dir);
    remove_owned(p, 1);
    rmdir(p); /* unless it holds something else */
    remove_owned(dir, 0);
    evr_folder_sync(p);
}

evr_status evr_run_dir_prepare(evr_sim *sim, evr_error *err)
{
    struct stat sb;
    evr_status st;
    if (stat(sim->out_dir, &sb) == 0) {
        if (!S_ISDIR(sb.st_mode)) {
            snprintf(err->msg, sizeof err->msg, "output path %s exists and is not a folder",
                     sim->out_dir);
            return EVR_ERR_ARG;
        }
        DIR *d = opendir(sim->out_dir);
        struct dirent *de;
        int empty = 1;
        if (!d) {
            snprintf(err->msg, sizeof err->msg, "cannot open output folder %s: %s", sim->out_dir,
                     strerror(errno));
            return EVR_ERR_IO;
        }
        while ((de = readdir(d)) != NULL)
            if (strcmp(de->d_name, ".") && strcmp(de->d_name, "..")) empty = 0;
        closedir(d);
        if (!empty && !sim->cfg.force) {
            snprintf(err->msg, sizeof err->msg,
                     "run folder %s already exists and is not empty (use --force to overwrite)",
                     sim->out_dir);
            return EVR_ERR_ARG;
        }
        /* --force: an earlier run's files go first, so that none stays beside this run's */
        if (!empty) evr_run_dir_clean(sim->out_dir);
    } else {
        if (evr_mkdir_p(sim->out_dir) != 0) {
            snprintf(err->msg, sizeof err->msg, "cannot create output folder %s: %s", sim->out_dir,
                     strerror(errno));
            return EVR_ERR_IO;
        }
        sim->created_dir = 1;
    }
    sim->dir_ours = 1;
    if ((st = make_reserve(sim, err)) != EVR_OK) return st;
    if (sim->cfg.preview_window > 0.0 && sim->cfg.preview != EVR_PREVIEW_NONE) {
        sim->preview_window_us = (int64_t)llround(sim->cfg.preview_window * 1e6);
        if (sim->preview_window_us < 1) sim->preview_window_us = 1;
        return evr_preview_out_new(sim->cfg.preview, sim->out_dir, sim->cfg.width, sim->cfg.height,
                                   (int64_t)llround(sim->cfg.start * 1e6), sim->preview_window_us,
                                   &sim->preview, err);
    }
    return EVR_OK;
}

evr_status evr_run_writers_open(evr_sim *sim, evr_error *err)
{
    int i, count;
    const evr_event_format *const *formats = evr_event_formats(&count);
    evr_writer_meta meta;
    char p[4200];
    evr_status st;
    meta.width = sim->cfg.width;
    meta.height = sim->cfg.height;
    meta.config_json = sim->config_json;
    /* timestamps end with the run, moved by jitter and rounding to the resolution */
    meta.max_t_us =
        (int64_t)ceil((sim->cfg.start + sim->duration) * 1e6) + sim->timestamp_slack_us + 1;
    /* the instances' names, for the formats that list them (written as the files open) */
    evr_instance_table names = {0};
    meta.event_ids = sim->cfg.event_ids;
    if (meta.event_ids && !evr_instance_table_make(sim->scene, &names)) {
        snprintf(err->msg, sizeof err->msg, "out of memory for the instances' names");
        return EVR_ERR_NOMEM;
    }
    meta.inst_node = (const char *const *)names.node;
    meta.inst_mesh = names.mesh;
    meta.num_instances = names.n;
    st = EVR_OK;
    for (i = 0; i < count && i < EVR_MAX_WRITERS && st == EVR_OK; i++) {
        if (!(sim->cfg.formats & (1 << i))) continue;
        if ((st = path_join(p, sizeof p, sim->out_dir, formats[i]->file, err)) != EVR_OK) break;
        evr_event_writer *w = NULL;
        if ((st = formats[i]->open(p, &meta, &w, err)) != EVR_OK) break;
        sim->writers[sim->num_writers] = w;
        sim->writer_names[sim->num_writers] = formats[i]->file;
        sim->num_writers++;
        if (meta.event_ids && !formats[i]->holds_ids) { /* said, not silently dropped */
            size_t len = strlen(sim->st.notice);
            snprintf(sim->st.notice + len, sizeof sim->st.notice - len,
                     "%s%s has no place for event ids", len ? "; " : "", formats[i]->file);
        }
    }
    evr_instance_table_free(&names);
    return st;
}

evr_status evr_run_preview_events(evr_sim *sim, const evr_event *ev, size_t n, int64_t limit_us,
                                  evr_error *err)
{
    evr_status st;
    if (!sim->preview) return EVR_OK;
    if ((st = evr_preview_out_events(sim->preview, ev, n, err)) != EVR_OK) return st;
    /* the run's last events (no limit): evr_run_close completes the windows */
    return limit_us == INT64_MAX ? EVR_OK : evr_preview_out_advance(sim->preview, limit_us, err);
}

/* Intensity frame k is taken at the end of the first segment that ends at or after the end of
 * preview window k (the pixels' latest samples); the last window may be partial. */
static int intensity_frame_due(const evr_sim *sim, int64_t frame, double t, int last)
{
    int64_t rel_us = (int64_t)llround((t - sim->cfg.start) * 1e6);
    return (frame + 1) * sim->preview_window_us <= rel_us ||
           (last && frame * sim->preview_window_us < rel_us);
}

int evr_run_preview_due(const evr_sim *sim, double t, int last)
{
    if (!sim->preview) return 0; /* previews off */
    /* frames already due at an earlier segment end are written when that one is collected */
    int64_t next = sim->intensity_frame;
    while (sim->preview_window_us > 0 && intensity_frame_due(sim, next, t - 1.0 / sim->fps, 0))
        next++;
    return intensity_frame_due(sim, next, t, last);
}

evr_status evr_run_preview_intensity(evr_sim *sim, const float *intensity, double t, int last,
                                     evr_error *err)
{
    evr_status st;
    if (!sim->preview) return EVR_OK;
    while (intensity_frame_due(sim, sim->intensity_frame, t, last)) {
        if ((st = evr_preview_out_intensity(sim->preview, intensity, err)) != EVR_OK) return st;
        sim->intensity_frame++;
    }
    return EVR_OK;
}

static char *run_json(const evr_sim *sim)
{
    const evr_stats *s = &sim->st;
    const evr_scene *sc = sim->scene;
    evr_json j;
    int i;
    long tris = 0;
    char buf[64];
    for (i = 0; i < sc->num_instances; i++)
        tris += (long)sc->meshes[sc->instances[i].mesh].num_triangles;
    evr_json_init(&j, 1);
    evr_json_begin_object(&j);
    evr_json_key(&j, "evray_version");
    evr_json_string(&j, EVR_VERSION);
    evr_json_key(&j, "versions");
    evr_json_begin_object(&j);
    snprintf(buf, sizeof buf, "%u.%u.%u", aiGetVersionMajor(), aiGetVersionMinor(),
             aiGetVersionPatch());
    evr_json_key(&j, "assimp");
    evr_json_string(&j, buf);
    evr_json_key(&j, "embree");
    evr_json_string(&j, RTC_VERSION_STRING);
    snprintf(buf, sizeof buf, "%d.%d.%d", H5_VERS_MAJOR, H5_VERS_MINOR, H5_VERS_RELEASE);
    evr_json_key(&j, "hdf5");
    evr_json_string(&j, buf);
    evr_json_end_object(&j);
    evr_json_key(&j, "config");
    evr_json_begin_object(&j);
    evr_json_end_object(&j); /* replaced below by the full configuration text */
    evr_json_key(&j, "scene");
    evr_json_begin_object(&j);
    evr_json_key(&j, "source");
    evr_json_string(&j, sc->source);
    evr_json_key(&j, "camera");
    evr_json_string(&j, sc->cameras[sim->camera].name);
    evr_json_key(&j, "automatic_camera");
    evr_json_boolean(&j, sc->cameras[sim->camera].automatic);
    evr_json_key(&j, "default_light");
    evr_json_boolean(&j, sc->default_light);
    evr_json_key(&j, "instances");
    evr_json_integer(&j, sc->num_instances);
    evr_json_key(&j, "triangles");
    evr_json_integer(&j, tris);
    evr_json_key(&j, "lights");
    evr_json_integer(&j, sc->num_lights);
    evr_json_key(&j, "animation_end");
    evr_json_number(&j, sc->anim_end);
    evr_json_key(&j, "clips_played"); /* the file's clips that played (names, "" unnamed) */
    evr_json_begin_array(&j);
    for (i = 0; i < sc->num_animations; i++)
        if (sc->clips[i].played) evr_json_string(&j, sc->clips[i].name);
    evr_json_end_array(&j);
    evr_json_end_object(&j);
    evr_json_key(&j, "outputs");
    evr_json_begin_array(&j);
    for (i = 0; i < sim->num_writers; i++)
        if (!sim->writer_lost[i]) evr_json_string(&j, sim->writer_names[i]);
    evr_json_end_array(&j);
    if (sim->failure[0]) { /* a failed run: its error, and the outputs it could not keep */
        evr_json_key(&j, "failed");
        evr_json_string(&j, sim->failure);
        if (sim->lost[0]) {
            evr_json_key(&j, "lost");
            evr_json_string(&j, sim->lost);
        }
    }
    evr_json_key(&j, "backend");
    evr_json_string(&j, s->backend);
    evr_json_key(&j, "device");
    evr_json_string(&j, s->device);
    if (s->notice[0]) {
        evr_json_key(&j, "notice");
        evr_json_string(&j, s->notice);
    }
    evr_json_key(&j, "stats");
    evr_json_begin_object(&j);
    evr_json_key(&j, "events");
    evr_json_unsigned(&j, s->events_on + s->events_off);
    evr_json_key(&j, "events_on");
    evr_json_unsigned(&j, s->events_on);
    evr_json_key(&j, "events_off");
    evr_json_unsigned(&j, s->events_off);
    evr_json_key(&j, "unique_timestamps");
    evr_json_unsigned(&j, s->unique_timestamps);
    evr_json_key(&j, "samples");
    evr_json_unsigned(&j, s->samples);
    evr_json_key(&j, "rays");
    evr_json_unsigned(&j, s->rays);
    /* change-driven sampling: samples is what brute force takes, samples_traced what was traced */
    evr_json_key(&j, "samples_traced");
    evr_json_unsigned(&j, s->samples_traced);
    evr_json_key(&j, "pixels_skipped");
    evr_json_unsigned(&j, s->pixels_skipped);
    evr_json_key(&j, "equivalent_samples_per_second");
    evr_json_number(&j, s->wall_time > 0 ? (double)s->samples / s->wall_time : 0.0);
    evr_json_key(&j, "traced_samples_per_second");
    evr_json_number(&j, s->wall_time > 0 ? (double)s->samples_traced / s->wall_time : 0.0);
    if (sim->skipped_per_segment) {
        int seg;
        evr_json_key(&j, "pixels_skipped_per_segment");
        evr_json_begin_array(&j);
        for (seg = 0; seg < s->segments_done; seg++)
            evr_json_unsigned(&j, sim->skipped_per_segment[seg]);
        evr_json_end_array(&j);
    }
    if (sim->cfg
            .gi) { /* the photon passes (a still segment reuses the previous segment's photons) */
        evr_json_key(&j, "photon_passes");
        evr_json_unsigned(&j, sim->backend->photon_passes);
        evr_json_key(&j, "photons_traced");
        evr_json_unsigned(&j, sim->backend->photons_traced);
        evr_json_key(&j, "photons_reused");
        evr_json_unsigned(&j, sim->backend->photons_reused);
        evr_json_key(&j, "photons_stored");
        evr_json_unsigned(&j, sim->backend->photons_stored);
        evr_json_key(&j, "photon_collisions");
        evr_json_unsigned(&j, sim->backend->photon_collisions);
        evr_json_key(&j, "photon_layers");
        evr_json_unsigned(&j, (uint64_t)sim->setup.photon_layers);
        evr_json_key(&j, "photon_cells_changed");
        evr_json_unsigned(&j, sim->backend->photon_cells_changed);
        evr_json_key(&j, "time_photons_seconds");
        evr_json_number(&j, sim->backend->photon_seconds);
    }
    evr_json_key(&j, "segments");
    evr_json_integer(&j, s->segments_done);
    evr_json_key(&j, "segments_planned");
    evr_json_integer(&j, s->segments_total);
    evr_json_key(&j, "interrupted");
    evr_json_boolean(&j, s->interrupted);
    /* the run ran to its end and every output is whole */
    evr_json_key(&j, "complete");
    evr_json_boolean(&j, !s->interrupted && !sim->failure[0]);
    /* the event files hold every event before this time (absolute seconds), none after */
    evr_json_key(&j, "complete_until_seconds");
    evr_json_number(&j, s->complete_until);
    evr_json_key(&j, "simulated_seconds");
    evr_json_number(&j, s->sim_time);
    evr_json_key(&j, "wall_seconds");
    evr_json_number(&j, s->wall_time);
    evr_json_key(&j, "samples_per_second");
    evr_json_number(&j, s->wall_time > 0 ? (double)s->samples / s->wall_time : 0.0);
    evr_json_key(&j, "rays_per_second");
    evr_json_number(&j, s->wall_time > 0 ? (double)s->rays / s->wall_time : 0.0);
    evr_json_key(&j, "realtime_factor");
    evr_json_number(&j, s->wall_time > 0 ? s->sim_time / s->wall_time : 0.0);
    { /* adaptive sampling: samples are those taken (all traced), their rate varies per pixel */
        double pix_s = (double)sim->cfg.width * (double)sim->cfg.height * s->sim_time;
        double spps = pix_s > 0.0 ? (double)s->samples / pix_s : 0.0;
        evr_json_key(&j, "samples_per_pixel_per_second");
        evr_json_number(&j, spps);
        evr_json_key(&j, "mean_sample_interval_seconds");
        evr_json_number(&j, sim->setup.adaptive ? (spps > 0.0 ? 1.0 / spps : 0.0)
                                                : 1.0 / (sim->fps * sim->setup.samples_per_frame));
    }
    evr_json_key(&j, "time_load_seconds"); /* the scene's (evr_scene_load_times) */
    evr_json_number(&j, evr_scene_load_times(sim->scene)->total);
    evr_json_key(&j, "time_setup_host_seconds");
    evr_json_number(&j, sim->time_setup_host);
    evr_json_key(&j, "time_setup_seconds");
    evr_json_number(&j, sim->time_setup);
    evr_json_key(&j, "time_setup_bvh_seconds");
    evr_json_number(&j, sim->backend->bvh_seconds);
    evr_json_key(&j, "bvh_trees"); /* made at set-up, and of them read from the BVH cache */
    evr_json_number(&j, sim->backend->bvh_trees);
    evr_json_key(&j, "bvh_trees_cached");
    evr_json_number(&j, sim->backend->bvh_trees_cached);
    evr_json_key(&j, "time_first_plan_seconds");
    evr_json_number(&j, sim->time_first_plan);
    evr_json_key(&j, "time_render_seconds");
    evr_json_number(&j, sim->time_render);
    evr_json_key(&j, "time_motion_seconds");
    evr_json_number(&j, sim->time_motion);
    evr_json_key(&j, "time_plan_wait_seconds");
    evr_json_number(&j, sim->time_plan_wait);
    evr_json_key(&j, "time_device_seconds");
    evr_json_number(&j, sim->backend->device_seconds);
    evr_json_key(&j, "time_device_wait_seconds");
    evr_json_number(&j, sim->backend->wait_seconds);
    evr_json_key(&j, "device_samples_per_second");
    evr_json_number(&j, sim->backend->device_seconds > 0
                            ? (double)s->samples / sim->backend->device_seconds
                            : 0.0);
    evr_json_key(&j, "time_sort_seconds");
    evr_json_number(&j, s->time_sort);
    evr_json_key(&j, "time_copy_seconds");
    evr_json_number(&j, s->time_copy);
    evr_json_key(&j, "device_memory_bytes");
    evr_json_unsigned(&j, s->device_memory);
    evr_json_key(&j, "time_write_wait_seconds");
    evr_json_number(&j, sim->time_write);
    evr_json_key(&j, "time_write_thread_seconds");
    evr_json_number(&j, sim->time_write_thread);
    evr_json_key(&j, "time_preview_seconds");
    evr_json_number(&j, sim->time_preview);
    evr_json_key(&j, "preview_frames"); /* windows: video frames, or pairs of PNG files */
    evr_json_integer(&j, evr_preview_out_windows(sim->preview));
    if (sim->preview) { /* the intensity's one exposure: linear intensity times this is white */
        evr_json_key(&j, "preview_exposure");
        evr_json_number(&j, evr_preview_out_exposure(sim->preview).scale);
    }
    if (sim->num_frames) {
        evr_json_key(&j, "intensity_frames");
        evr_json_integer(&j, sim->frames_written);
    }
    evr_json_end_object(&j);
    evr_json_end_object(&j);
    char *text = evr_json_take(&j);
    if (!text) return NULL;
    /* splice the configuration object in place of the empty one */
    const char *marker = "\"config\": {}";
    char *at = strstr(text, marker);
    if (!at) return text;
    size_t before = (size_t)(at - text), clen = strlen(sim->config_json), mlen = strlen(marker);
    char *out = malloc(strlen(text) + clen + 16);
    if (!out) {
        free(text);
        return NULL;
    }
    memcpy(out, text, before);
    memcpy(out + before, "\"config\": ", 10);
    memcpy(out + before + 10, sim->config_json, clen);
    strcpy(out + before + 10 + clen, at + mlen);
    free(text);
    return out;
}

/* The backend's timings into the statistics. */
static void backend_times(evr_sim *sim)
{
    sim->st.time_setup = sim->time_setup;
    sim->st.time_setup_host = sim->time_setup_host;
    sim->st.time_setup_bvh = sim->backend->bvh_seconds;
    sim->st.bvh_trees = sim->backend->bvh_trees;
    sim->st.bvh_trees_cached = sim->backend->bvh_trees_cached;
    sim->st.time_first_plan = sim->time_first_plan;
    sim->st.time_render = sim->time_render;
    sim->st.time_device = sim->backend->device_seconds;
    sim->st.time_sort = sim->backend->sort_seconds;
    sim->st.time_copy = sim->backend->copy_seconds;
    sim->st.device_memory = sim->backend->device_bytes;
}

/* Stops the writer thread, its timings into the statistics. */
static void stop_queue(evr_sim *sim)
{
    if (!sim->wq) return;
    sim->time_write = evr_write_queue_wait_seconds(sim->wq);
    sim->time_write_thread = evr_write_queue_busy_seconds(sim->wq);
    sim->st.time_write = sim->time_write_thread;
    evr_write_queue_stop(sim->wq);
    sim->wq = NULL;
}

/* The simulated time the event files hold every event of (an interrupted run's, up to
 * complete_until), in microseconds: the writers' and previews' duration. */
static int64_t complete_us(const evr_sim *sim)
{
    return (int64_t)llround((sim->st.complete_until - sim->cfg.start) * 1e6);
}

/* Notes an output a failed run could not keep. */
static void note_lost(evr_sim *sim, const char *why)
{
    size_t len = strlen(sim->lost);
    snprintf(sim->lost + len, sizeof sim->lost - len, "%s%s", len ? "; " : "", why);
}

/* The end of a failed run once its outputs are settled: run.json says so, or, if it cannot be
 * written, nothing is left (no file that looks complete without it). Returns st, err kept. */
static evr_status end_failed(evr_sim *sim, evr_status st)
{
    evr_error e2;
    sim->st.interrupted = 1;
    sim->st.outputs_kept = evr_run_write_json(sim, &e2) == EVR_OK;
    if (!sim->st.outputs_kept) evr_run_dir_discard(sim);
    return st;
}

evr_status evr_run_fail(evr_sim *sim, evr_status st, evr_error *err)
{
    evr_error e2;
    uint64_t events = 0, batches = 0;
    int64_t until_us = sim->emitted_until_us;
    int w;
    snprintf(sim->failure, sizeof sim->failure, "%s", err->msg);
    release_reserve(sim); /* room to complete the files */
    backend_times(sim);
    if (sim->wq) {
        evr_write_queue_drain(sim->wq,
                              &e2); /* a queue that did not fail still writes its batches */
        evr_write_queue_accepted(sim->wq, &events, &batches);
        stop_queue(sim);
        /* the files keep what every writer took: the counts and the time of those batches */
        if (batches < sim->batches) until_us = sim->marks[batches % EVR_BATCH_MARKS].before_us;
        if (batches > 0) {
            const evr_batch_mark *m = &sim->marks[(batches - 1) % EVR_BATCH_MARKS];
            sim->st.events_on = m->on;
            sim->st.events_off = m->events - m->on;
            sim->st.unique_timestamps = m->unique;
        } else {
            sim->st.events_on = sim->st.events_off = sim->st.unique_timestamps = 0;
        }
    }
    sim->st.complete_until =
        until_us == INT64_MAX ? sim->cfg.start + sim->duration : (double)until_us * 1e-6;
    for (w = 0; w < sim->num_writers; w++) {
        evr_event_writer *wr = sim->writers[w];
        sim->writers[w] = NULL;
        if (wr->salvage(wr, events, complete_us(sim), &e2) != EVR_OK) {
            sim->writer_lost[w] = 1;
            note_lost(sim, e2.msg);
        }
    }
    if (sim->preview && evr_preview_out_finish(sim->preview, complete_us(sim), &e2) != EVR_OK)
        note_lost(sim, e2.msg);
    if (evr_frames_finish(sim, &e2) != EVR_OK) note_lost(sim, e2.msg);
    /* the camera's poses and the labels are kept only with a complete run */
    evr_camera_poses_discard(sim);
    evr_labels_discard(sim);
    return end_failed(sim, st);
}

evr_status evr_run_close(evr_sim *sim, evr_error *err)
{
    evr_status st = EVR_OK;
    evr_error e2;
    int w;
    backend_times(sim);
    /* everything written and flushed while the reserve is still there: a write that fails here
     * still leaves room to salvage the files */
    if (sim->wq) {
        st = evr_write_queue_flush(sim->wq, err);
        if (st != EVR_OK) return evr_run_fail(sim, st, err);
        stop_queue(sim);
    }
    release_reserve(sim); /* room for what completing the files writes */
    for (w = 0; w < sim->num_writers; w++) {
        evr_event_writer *wr = sim->writers[w];
        sim->writers[w] = NULL;
        if (wr->finish(wr, complete_us(sim), &e2) != EVR_OK) { /* its file is gone */
            sim->writer_lost[w] = 1;
            if (st == EVR_OK) *err = e2;
            st = EVR_ERR_IO;
            note_lost(sim, e2.msg);
        }
    }
    if (sim->preview && evr_preview_out_finish(sim->preview, complete_us(sim), &e2) != EVR_OK) {
        if (st == EVR_OK) *err = e2;
        st = EVR_ERR_IO;
        note_lost(sim, e2.msg);
    }
    if (evr_frames_finish(sim, &e2) != EVR_OK || evr_camera_poses_close(sim, &e2) != EVR_OK ||
        evr_labels_close(sim, &e2) != EVR_OK) {
        if (st == EVR_OK) *err = e2;
        st = EVR_ERR_IO;
        note_lost(sim, e2.msg);
    }
    if (st != EVR_OK) {
        snprintf(sim->failure, sizeof sim->failure, "%s", err->msg);
        return end_failed(sim, st);
    }
    return EVR_OK;
}

evr_status evr_run_write_json(evr_sim *sim, evr_error *err)
{
    evr_status st;
    char *text = run_json(sim);
    char p[4200], tmp[4300];
    if (!text) {
        snprintf(err->msg, sizeof err->msg, "out of memory writing run.json");
        return EVR_ERR_NOMEM;
    }
    if ((st = path_join(p, sizeof p, sim->out_dir, "run.json", err)) != EVR_OK) {
        free(text);
        return st;
    }
    snprintf(tmp, sizeof tmp, "%s.tmp", p);
    FILE *f = fopen(tmp, "w");
    int ok = f && fputs(text, f) >= 0 && fputc('\n', f) != EOF;
    if (f) ok = (fclose(f) == 0) && ok;
    free(text);
    if (!ok || evr_file_publish(tmp, p) != 0) {
        const int e = errno;
        remove(tmp);
        snprintf(err->msg, sizeof err->msg, "cannot write %s: %s", p, strerror(e));
        return EVR_ERR_IO;
    }
    return EVR_OK;
}

void evr_run_dir_discard(evr_sim *sim)
{
    int w;
    evr_frames_discard(sim);
    evr_camera_poses_discard(sim);
    evr_labels_discard(sim);
    evr_write_queue_stop(sim->wq); /* the thread must be done with the writers */
    sim->wq = NULL;
    for (w = 0; w < sim->num_writers; w++) {
        if (sim->writers[w]) sim->writers[w]->abort(sim->writers[w]);
        sim->writers[w] = NULL;
    }
    evr_preview_out_release(sim->preview); /* an unfinished video's temporary file goes */
    sim->preview = NULL;
    sim->reserve_made = 0;
    /* the folder held nothing of evray's before this run (it was new, empty, or emptied of
     * evray's files by --force): whatever of evray's it holds is this run's */
    if (sim->dir_ours) evr_run_dir_clean(sim->out_dir);
    if (sim->created_dir) rmdir(sim->out_dir);
}
