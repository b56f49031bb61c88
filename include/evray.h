/* evray: an event-camera (DVS) simulator driven by a ray tracer.
 *
 * The public C interface. A scene (evr_scene) is loaded from a file or generated; a simulation
 * (evr_sim) renders it over time, every pixel sampling at its own times, and turns the sampled
 * log intensity into a time-sorted stream of ON/OFF events written to the run folder and/or
 * handed to the caller as the run goes (evr_sim_set_sink).
 *
 * Conventions: every function that can fail returns an evr_status and fills an evr_error with
 * one line saying why; no function prints or exits; every handle made by a *_new/_load has a
 * matching *_release. */
#ifndef EVRAY_H
#define EVRAY_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    EVR_OK = 0,
    EVR_ERR_ARG,        /* a parameter value that makes no sense */
    EVR_ERR_IO,         /* a file could not be read or written */
    EVR_ERR_FORMAT,     /* a file was read but is not a usable scene or event file */
    EVR_ERR_NOMEM,      /* out of memory */
    EVR_ERR_BACKEND,    /* the ray tracer or device failed */
    EVR_ERR_INTERRUPTED /* stopped on request; outputs hold every finished segment */
} evr_status;

typedef struct {
    char msg[512];
} evr_error;

/* One DVS event, 16 bytes. Polarity p: 1 ON (brighter), 0 OFF (darker). Timestamp in
 * microseconds. id (with evr_config.event_ids): 1 + the scene instance whose surface the pixel
 * centre's primary ray hit at the pixel's sample after the crossing (labels.h5's ids), 0 when it
 * hit nothing (or ids are off); 16 bits, in the padding the other fields leave, so that ids cost
 * no memory: event ids take scenes of at most EVR_MAX_EVENT_ID instances. */
typedef struct {
    int64_t t;
    uint16_t x, y;
    int8_t p;
    uint16_t id;
} evr_event;
#define EVR_MAX_EVENT_ID 65535

/* ---- scenes ---- */
typedef struct evr_scene evr_scene;

/* Loads any format Assimp reads (glTF 2.0 .gltf/.glb first of all), with the default load
 * options (evr_load_options_defaults). */
evr_status evr_scene_load(const char *path, evr_scene **out, evr_error *err);
/* Loads from memory; hint is the file extension ("glb", "gltf", "obj", ...). */
evr_status evr_scene_load_memory(const void *data, size_t size, const char *hint, evr_scene **out,
                                 evr_error *err);

/* How a scene is loaded. Make one with evr_load_options_defaults and change the fields you need;
 * size works as evr_config's does (fields are only ever added at the end; a size the library
 * does not know is refused with EVR_ERR_ARG). Strings are read during the load, not kept.
 *
 * animation: which of the file's animation clips play. Every played clip runs from time 0 with
 * its keys at the times the file gives them.
 *   NULL or "" (the default): clips that animate disjoint sets of nodes play together. Clips are
 *     taken in file order, and a clip is taken when it animates no node that an already taken
 *     clip animates; the others do not play, and evr_scene_notice names them. A clip animates
 *     the nodes its transform channels name, and those its morph-weight and mesh channels name
 *     (a node of that name, else the nodes that place a mesh of that name). So one clip per
 *     object (as Blender exports) all play, and of walk/run/idle clips of one character only the
 *     first plays.
 *   "all": every clip plays; where two clips animate the same property, the first one's keys
 *     are used.
 *   a clip's name, else its 0-based index in the file ("2"): that clip alone. "all" is always
 *     the keyword (name such a clip by index). A name or index the file does not have fails
 *     with EVR_ERR_ARG and a message listing the clips.
 *
 * strict: 0 (the default): what evray cannot render of the file as it is (a texture it cannot
 *   find, read or decode, an extension it does not render, ...) is a warning
 *   (evr_scene_warnings) and the load goes on: a material whose texture is missing keeps its
 *   factors. 1: any such warning fails the load with EVR_ERR_FORMAT and a message giving the
 *   first one. */
typedef struct {
    size_t size; /* sizeof(evr_load_options) as the caller sees it: set by the defaults */
    const char *animation;
    int strict;
    /* 0 (the default): the scene reads only files inside its own folder (buffers, images,
     * materials a format names beside it); a path that leads outside it (an absolute path, '..',
     * a symbolic link out) fails the load (a texture: a warning, as a missing one). 1: any
     * file. Either way only regular files are read (never a FIFO or a device). A scene in memory
     * has no folder: 0 reads no file at all, 1 reads them relative to the current folder. */
    int allow_external;
} evr_load_options;

void evr_load_options_init(evr_load_options *o, size_t size);
#define evr_load_options_defaults(o) evr_load_options_init((o), sizeof(evr_load_options))
/* evr_scene_load and evr_scene_load_memory with options (NULL: the defaults). */
evr_status evr_scene_load_with(const char *path, const evr_load_options *opts, evr_scene **out,
                               evr_error *err);
evr_status evr_scene_load_memory_with(const void *data, size_t size, const char *hint,
                                      const evr_load_options *opts, evr_scene **out,
                                      evr_error *err);
/* One line the loader has for the user (e.g. the animation clips that do not play by the
 * default rule), or NULL when it has nothing to say. Valid while the scene lives. */
const char *evr_scene_notice(const evr_scene *s);
/* Where a load's time went: seconds of wall time, each step's own (total: the whole load). */
typedef struct {
    double total;
    double gltf_checks; /* glTF: the JSON and buffers checked (and patched) before Assimp reads */
    double assimp;      /* Assimp's read and post-processing (identical vertices joined) */
    double materials;   /* materials, their textures decoded and mip-mapped */
    double meshes;      /* meshes taken from Assimp's, tangents included */
    double tangents;    /* of meshes: tangents generated from uvs */
    double rest;        /* nodes, animation, deformation, cameras, lights, number checks */
} evr_load_times;
/* The load's timings (zeros for NULL). Valid while the scene lives. */
const evr_load_times *evr_scene_load_times(const evr_scene *s);
/* Names of the built-in scenes, NULL-terminated. */
const char *const *evr_demo_names(void);
/* 1 if the built-in scene takes a seed (evr_demo_glb_variant), 0 if not or unknown. */
int evr_demo_has_variants(const char *name);
/* Builds a built-in scene as a binary glTF (GLB) in memory; free *glb with free(). */
evr_status evr_demo_glb(const char *name, void **glb, size_t *size, evr_error *err);
/* The same for a variant of the scene: seed 0 is the scene itself; any other seed draws what the
 * scene lets vary (eye, eye-drift: the gaze plan, blinks included, and the iris's pattern and
 * colour), the same for the same seed. Other scenes refuse a seed. */
evr_status evr_demo_glb_variant(const char *name, uint64_t seed, void **glb, size_t *size,
                                evr_error *err);
/* Builds a built-in scene and loads it (through the same importer as any file). */
evr_status evr_demo_load(const char *name, evr_scene **out, evr_error *err);
/* The same for a variant (evr_demo_glb_variant). */
evr_status evr_demo_load_variant(const char *name, uint64_t seed, evr_scene **out, evr_error *err);
void evr_scene_release(evr_scene *s);

/* A human-readable description (cameras, lights, animation clips and whether each plays,
 * animations and time ranges, meshes, triangles, skins and morph targets, warnings); free the
 * returned string with free(). */
char *evr_scene_describe(const evr_scene *s);
/* What evray does not render of the file as it is (e.g. CUBICSPLINE morph weights, interpolated
 * linearly): one warning per line, each ending in a newline; "" when there is none. */
const char *evr_scene_warnings(const evr_scene *s);

/* ---- simulation ---- */
/* Event output formats as bits of evr_config.formats: format i of the registry
 * (src/io/event_formats.c) is bit 1 << i; formats without a constant here are found by name
 * (evr_formats_parse, evr_format_name in evray_experimental.h). */
typedef enum { EVR_FORMAT_H5 = 1, EVR_FORMAT_TXT = 2, EVR_FORMAT_NPY = 4 } evr_format;

/* auto: CUDA when this build has it and a usable GPU is present, else the CPU (with a notice). */
typedef enum {
    EVR_SAMPLING_UNIFORM = 0,
    EVR_SAMPLING_ADAPTIVE = 1,
    EVR_SAMPLING_REFINE = 2,
    EVR_SAMPLING_AUTO = 3 /* evr_config_sampling decides */
} evr_sampling;

typedef enum { EVR_BACKEND_AUTO = 0, EVR_BACKEND_CPU = 1, EVR_BACKEND_CUDA = 2 } evr_backend_kind;

/* The simulation's settings. Make one with evr_config_defaults and change the fields you need:
 * size tells the library which version of this struct the caller was compiled with, so that
 * fields can be added (only ever at the end) without breaking compiled callers; a size the
 * library does not know is refused with EVR_ERR_ARG. Strings are not copied by the setters here
 * (evr_sim_new copies what it keeps). */
typedef struct {
    size_t size; /* sizeof(evr_config) as the caller sees it: set by evr_config_defaults */
    /* image and time */
    int width, height;     /* pixels */
    double duration;       /* seconds; <= 0: the scene's animation length */
    double start;          /* seconds into the animation */
    double fps;            /* segments per second; <= 0: the scene's frame rate, else 30 */
    int samples_per_frame; /* samples per pixel per segment; 0: 10 (evr_config_samples_per_frame) */
    const char *camera;    /* camera name, NULL for the first */
    /* pixel model */
    float pos_thres, neg_thres; /* contrast thresholds in log intensity */
    float refractory;           /* seconds */
    float log_floor;            /* intensity below which log response turns linear */
    /* sensor non-idealities (laws, sources and presets in docs/sensors.md); 0 turns each off,
     * and with all of them off the sensor is ideal (the default) */
    const char *sensor;   /* name of the preset applied by evr_config_sensor, NULL: none */
    float sigma_thres;    /* threshold mismatch: std dev of the per-pixel thresholds, log units */
    float cutoff_hz;      /* photoreceptor low-pass cutoff at full brightness, Hz */
    float full_intensity; /* intensity that counts as full brightness (bandwidth, shot noise) */
    float leak_rate;      /* leak ON events per second per pixel, mean */
    float leak_jitter;    /* relative std dev of the per-pixel leak rate */
    float shot_rate;      /* shot-noise events (ON + OFF) per second of a black pixel */
    float hot_fraction;   /* fraction of pixels that are hot */
    float hot_rate;       /* ON events per second of a hot pixel */
    double time_res;      /* timestamp resolution, seconds (a whole number of microseconds) */
    double time_jitter;   /* std dev of Gaussian timestamp jitter, seconds */
    /* shading */
    float ambient; /* ambient fraction of the base colour */
    uint64_t seed;
    int threads; /* 0: all cores */
    evr_backend_kind backend;
    int gpu_bvh; /* GPU node layout: 0 default, 4 (BVH4, float boxes), 8 (CW8, compressed) */
    int64_t
        gpu_event_capacity; /* events a GPU segment buffer holds at first (0: automatic); it grows
                                     and the segment is rendered again when it overflows */
    int no_skip;            /* 1: trace every sample (brute force) instead of reusing the
                                     intensity of pixels nothing moving can reach (identical events) */
    /* sampling: EVR_SAMPLING_AUTO (the default: evr_config_sampling); EVR_SAMPLING_REFINE,
     * samples_per_frame per pixel per segment where something moving reaches the pixel, each
     * interval in which its model fires bisected until its events' timing error is within
     * time_tol (docs/architecture.md, "Refined sampling"); EVR_SAMPLING_UNIFORM, samples_per_frame
     * per pixel per segment at the pixel's own phase; EVR_SAMPLING_ADAPTIVE, each pixel picks its next sample time from how fast its log
     * intensity changes (adapt_frac of a threshold between samples) and from a bound on how fast
     * what its rays meet moves in the image (2 adapt_frac pixels between samples), within
     * [min_dt, max_dt] (docs/architecture.md, "Adaptive sampling") */
    int sampling;
    float adapt_frac;      /* (0, 1] */
    double min_dt, max_dt; /* seconds; max_dt <= 0: one segment (1 / fps) */
    /* output */
    const char *out_dir;
    int formats;           /* evr_format bits; 0: no event file (a sink takes the events:
                              evr_sim_set_sink) */
    double preview_window; /* seconds per preview frame; <= 0: no previews (see preview) */
    int force;             /* overwrite an existing run folder (and frames in frames_out) */
    /* intensity frames for frame-based tools (v2e and the like): frame k is every pixel's
     * intensity at exactly t_k = start + k / frames_fps (one sample at the pixel centre, not seen
     * by the pixel model), for every t_k <= start + duration (both ends included), written to
     * frames_out as frame_NNNNNN.png (8-bit gray, sRGB-encoded: intensity * frames_exposure
     * clamped to [0, 1]), frame_NNNNNN_linear16.png (16-bit gray, linear:
     * round(intensity * 65535 / frames_max) clamped) and frames.csv (index, time, files) */
    const char *frames_out; /* folder; NULL: no frames */
    double frames_fps;      /* frames per second; <= 0: the segment rate (fps) */
    float frames_exposure;  /* 8-bit frames: intensity that maps to white is 1 / this */
    float frames_max;       /* 16-bit frames: intensity that maps to 65535 */
    /* global illumination: image-space photon mapping (src/core/photon.h) */
    int gi;              /* 0: direct light only, 1: photon mapping */
    uint32_t photons;    /* photons per segment (0: one per pixel) */
    float gather_radius; /* distance filter r, world units (<= 0: 2% of the scene's diagonal) */
    int gather_max;      /* photons per estimate at most */
    int gather_window;   /* the gather window's half size at most, pixels */
    int photon_layers;   /* photons each pixel of the buffer holds (0: from photons) */
    int gi_bounces;      /* indirect bounces of a photon */
    float gi_blur;       /* > 0: indirect light from a per-pass estimate blurred over each
                          * surface, sigma this x gather_radius (core/photon_blur.h);
                          * 0: a gather at every sample */
    /* shading: reflections and refractions a camera ray may take (core/path.h) */
    int max_bounces;
    /* previews (one per preview_window): EVR_PREVIEW_VIDEO, one animated PNG preview.apng in
     * the run folder with each window's events and intensity side by side; EVR_PREVIEW_PNG, two
     * PNG files per window in preview/; EVR_PREVIEW_NONE, none. The intensity is tone mapped with
     * one exposure for the whole run (io/preview.h). */
    int preview;
    /* scene loading: 1 makes every import warning an error (evr_load_options.strict); the evray
     * program loads the scene with it, evr_sim_new does not read it */
    int strict;
    /* the camera (README, "Camera paths and framing"): camera_path moves it along built-in
     * motions and/or a TUM trajectory file (the syntax: src/scene/camera_path.h; NULL: its own
     * motion only); look_from / look_at (when their _set is 1) place it at a world position
     * and aim it at a world point, replacing its own pose; fov > 0 sets a perspective camera's
     * vertical field of view in degrees */
    const char *camera_path;
    double fov;
    int look_from_set, look_at_set;
    double look_from[3], look_at[3];
    /* ground truth (README "Ground truth"): labels_fps > 0 writes labels.h5 in the run folder,
     * label frame k at exactly start + k / labels_fps (both ends included, as intensity frames):
     * every pixel's depth, instance id, optical flow (image velocity of the surface point it
     * sees, px/s, from the motion) and its displacement over flow_dt seconds, and with
     * label_normals its surface normal. trajectories: imu.txt (an ideal IMU on the camera) and
     * node_poses.txt (every animated node's world pose) at 1 kHz. eye_labels: eye.txt (gaze,
     * pupil, eyelids and phase at 1 kHz) for a scene with an eye's named nodes. */
    double labels_fps; /* <= 0: no labels.h5 */
    double flow_dt;    /* seconds, > 0 */
    int label_normals;
    int trajectories;
    int eye_labels;
    /* event_ids: every event gets evr_event.id (its instance), written by the file formats that
     * have a place for it (events.h5 events/id and an instances table, events.npy's id field,
     * events.txt's fifth column); a scene of more than EVR_MAX_EVENT_ID instances is refused */
    int event_ids;
    /* scene loading: 1 lets a scene read files outside its folder (evr_load_options
     * .allow_external); the evray program loads the scene with it */
    int allow_external_files;
    /* The most a run may take, refused by evr_sim_new before anything starts (0: no limit):
     * max_samples bounds the pixel work, width x height x (samples per segment x segments +
     * intensity frames + preview frames); max_noise_events the expected noise events (pixels x
     * duration x the leak, shot and hot-pixel rates). */
    double max_samples;
    double max_noise_events;
    double time_tol;  /* refined sampling: the timing error its refinement aims at, seconds */
    double refine_px; /* refined sampling: image motion between grid samples, pixels, at most */
    /* the CUDA backend's trees of big meshes kept across runs (src/cuda/gpu_bvh_cache.h): a
     * folder, "auto" ($XDG_CACHE_HOME/evray, else $HOME/.cache/evray; the default) or "off" */
    const char *bvh_cache;
} evr_config;

enum { EVR_PREVIEW_NONE = 0, EVR_PREVIEW_PNG = 1, EVR_PREVIEW_VIDEO = 2 };

/* Fills c with the defaults (the ideal sensor at 346x260, docs/sensors.md) and sets c->size.
 * The macro passes the size of the caller's evr_config. */
void evr_config_init(evr_config *c, size_t size);
#define evr_config_defaults(c) evr_config_init((c), sizeof(evr_config))
/* The sampling a configuration runs with: its own, or for EVR_SAMPLING_AUTO, refined sampling
 * unless samples_per_frame is set (today's uniform sampling at that count) or global
 * illumination is on (uniform). */
evr_sampling evr_config_sampling(const evr_config *c);
/* The samples per pixel per segment it runs with (refined sampling: its grid). */
int evr_config_samples_per_frame(const evr_config *c);
/* Names of the sensor presets, NULL-terminated: ideal, davis346, dvxplorer, prophesee-gen4. */
const char *const *evr_sensor_names(void);
/* Applies a sensor preset: thresholds, mismatch, refractory period, bandwidth, noise, timestamp
 * resolution and (except for ideal) the resolution; other fields are kept. */
evr_status evr_config_sensor(evr_config *c, const char *name, evr_error *err);
/* Checks every value (and c->size); fills err with the first problem. */
evr_status evr_config_validate(const evr_config *c, const evr_scene *s, evr_error *err);

typedef struct {
    uint64_t events_on, events_off, unique_timestamps;
    uint64_t samples, rays;  /* samples: every pixel sample, as brute force would take them
                                     (adaptive sampling: every sample taken, all traced) */
    uint64_t samples_traced; /* samples that traced rays; the rest reused a cached intensity */
    uint64_t pixels_skipped; /* pixel-segments that traced nothing (change-driven sampling) */
    double sim_time;         /* seconds simulated */
    double wall_time;        /* seconds */
    double samples_per_second, rays_per_second, realtime_factor;
    int segments_done, segments_total;
    int interrupted;
    /* where the time went (seconds; filled at the end of a run) */
    double time_setup;           /* scene to backend: BVH builds, uploads */
    double time_render;          /* waiting for and taking in the backend's segments */
    double time_device;          /* GPU kernels (0 on the CPU) */
    double time_sort, time_copy; /* event sort and device-to-host copy inside the backend */
    double time_write;           /* the writer thread's busy time (overlaps rendering) */
    double time_photons;         /* global illumination: the photon passes (GPU: device time) */
    uint64_t photons_stored, photon_collisions, photon_cells_changed;
    int photon_layers; /* the photon buffer's layers (config's, or made from its photons) */
    uint64_t photons_traced,
        photons_reused;     /* photon paths traced, and those that reused their trail */
    uint64_t device_memory; /* bytes the backend holds on the GPU (0 on the CPU) */
    char backend[16];       /* the backend that ran: "cpu" or "cuda" */
    char device[128];       /* CPU threads or the GPU's name */
    char notice[256];       /* e.g. why auto fell back to the CPU; empty if nothing to say */
    /* What the event files hold: every event with t (seconds, absolute) before complete_until
     * and none after (the run's end when it ran to the end: an interrupted or failed run's
     * files stop earlier). */
    double complete_until;
    /* A failed run (evr_sim_run's error): outputs_kept 1 when the run folder keeps valid files
     * holding every event before complete_until and a run.json saying the run failed, 0 when
     * the run left nothing. */
    int outputs_kept;
    /* set-up, before the first segment renders (seconds; the scene's load is evr_load_times) */
    double time_setup_host; /* before the backend: the renderer's view of the scene, the camera,
                                trackers, tables */
    double time_setup_bvh;  /* of time_setup: the ray tracer's acceleration structures built */
    double time_first_plan; /* the run's start to the first segment's plan (motion keys, skip
                                plan, deformation keys) taken */
    int bvh_trees;          /* bottom-level trees the backend made at set-up (0: not counted) */
    int bvh_trees_cached;   /* of them, read from the BVH cache (evr_config.bvh_cache) */
} evr_stats;

typedef struct evr_sim evr_sim;

/* Called after every segment; return non-zero to stop after it. */
typedef int (*evr_progress_fn)(void *user, const evr_stats *st);

/* The scene must outlive the simulation: evr_sim_new keeps a pointer to it (not a copy), so
 * release the simulation before the scene. The configuration is copied. */
evr_status evr_sim_new(const evr_scene *s, const evr_config *c, evr_sim **out, evr_error *err);
/* Runs to the end (or until progress asks to stop, or evr_sim_cancel) and finalizes every output
 * file. Stopped, it returns EVR_ERR_INTERRUPTED with valid files holding every event before
 * stats.complete_until. Failed (a full disk...), it keeps valid files holding every event the
 * writers had taken, marked as failed in run.json, or nothing (stats.outputs_kept). */
evr_status evr_sim_run(evr_sim *sim, evr_progress_fn progress, void *user, evr_error *err);
/* Asks a running evr_sim_run to stop at once: the segments being rendered are given up and the
 * files completed with every event before stats.complete_until (a progress callback's stop
 * finishes the segments in flight first). Async-signal-safe and callable from any thread. */
void evr_sim_cancel(evr_sim *sim);
const evr_stats *evr_sim_stats(const evr_sim *sim);
void evr_sim_release(evr_sim *sim);

/* ---- streaming ---- */
/* A sink takes the run's events as it goes: the same batches, in the same order, that the event
 * files get (every event once; within a batch sorted by t, and no batch earlier than the one
 * before), each segment's events as soon as no later segment can precede them. It is called on
 * one of the library's writer threads, one call at a time, never after evr_sim_run returns; ev is
 * valid only during the call (copy what you keep). The sink may block: the run goes on rendering
 * until eight batches wait for it, then waits too, so memory stays bounded however slow it is.
 * Return 0 to go on; non-zero stops the run as evr_sim_cancel does (evr_sim_run returns
 * EVR_ERR_INTERRUPTED, the files complete) and the sink is not called again. The files may hold
 * a few batches more than the sink took then (those queued behind it). A run that fails (a full
 * disk...) stops calling it at the failure. */
typedef int (*evr_event_sink_fn)(void *user, const evr_event *ev, size_t n);
/* Gives the run its sink (one at most: a second call fails with EVR_ERR_ARG), between evr_sim_new
 * and evr_sim_run (EVR_ERR_ARG once the run started). With evr_config.formats 0 the sink alone
 * takes the events (no event file; run.json and what else the configuration asks for are
 * written as usual). */
evr_status evr_sim_set_sink(evr_sim *sim, evr_event_sink_fn sink, void *user, evr_error *err);

const char *evr_version(void);

#ifdef __cplusplus
}
#endif
#endif
