/* evray's experimental interface: NOT a stable API. What the evray program needs beyond evray.h
 * (the configuration table for its options and --help, the output formats, event files, the
 * built-in scenes' internals for benchmarks, one-image renders). Names and types here may change
 * in any release without notice; programs that want to keep compiling use evray.h only. */
#ifndef EVRAY_EXPERIMENTAL_H
#define EVRAY_EXPERIMENTAL_H

#include "evray.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- event output formats (the registry: src/io/event_formats.c) ---- */
/* Format i (configuration bit 1 << i): its --format name and its file in the run folder; NULL
 * past the last. */
const char *evr_format_name(int i);
const char *evr_format_file(int i);
/* A comma-separated list of format names (and "all") as configuration bits; opt names the
 * option in the message. */
evr_status evr_formats_parse(const char *opt, const char *text, int *formats, evr_error *err);

/* ---- clock ---- */
/* Monotonic wall-clock seconds (for timing runs). */
double evr_seconds(void);

/* ---- event files (src/io/event_reader.c) ---- */
/* Reads a whole event file written by evray (or in the same layouts by other tools), picking the
 * format by the file name's extension:
 *   .h5 / .hdf5  events/x, events/y, events/t, events/p (any integer types); width and height
 *                from the file attributes when present. Timestamps are returned as stored (DSEC
 *                files keep an offset in t_offset; ours is 0).
 *   .txt         lines "t x y p", t in seconds (decimal); empty lines and lines starting with '#'
 *                are skipped.
 *   .npy         a 1-D structured array with integer fields t (us), x, y, p in any order and of
 *                any integer width, either byte order.
 *   .raw         Prophesee EVT 2.0 or EVT 3.0 (named by the "% evt" / "% format" header line);
 *                width and height from the header.
 *   .dat         Prophesee DAT of CD events; width and height from the header.
 *   .bag         ROS1 bag: the dvs_msgs/EventArray messages of the first such connection (chunks
 *                uncompressed, bz2 or lz4); width and height from the first message.
 *   .aedat4      iniVation AEDAT 4.0 (.aedat too): the first event stream (EVTS), packets
 *                uncompressed or LZ4 or ZSTD; width and height from its sizeX and sizeY.
 * Event ids (evr_event.id) come from events/id (.h5), an id field (.npy) and a fifth column
 * (.txt) where the file has them, else 0.
 * Polarity is returned as 1 (p > 0) or 0 (p <= 0, so -1/1 files read too). Events keep the file's
 * order. *ev is malloc'ed (free() it; NULL when *n is 0). width/height are set to -1 when the
 * format does not store them; either pointer may be NULL. */
evr_status evr_events_read(const char *path, evr_event **ev, size_t *n, int *width, int *height,
                           evr_error *err);

/* Writes n events (sorted by time) to path in the format its name says: .h5/.hdf5, .txt, .npy,
 * .dat (Prophesee DAT), a name ending in "evt2.raw" (Prophesee EVT 2.0) or any other .raw (EVT
 * 3.0), .bag (ROS1 bag), a name ending in "zstd.aedat4" (AEDAT 4.0, ZSTD packets) or any other
 * .aedat4 (AEDAT 4.0, LZ4). width/height <= 0: taken from the largest x/y.
 * Under a temporary name until complete, as the simulation's writers; what the format cannot
 * hold is refused (EVR_ERR_ARG), but event ids (evr_event.id), which .h5, .npy and .txt keep
 * when any is non-zero and the other formats leave out (evr_events_format_holds_ids). */
evr_status evr_events_write(const char *path, const evr_event *ev, size_t n, int width, int height,
                            evr_error *err);
/* 1 when the format path's name asks for keeps event ids, 0 when it has none, -1 when the name
 * asks for no format evray writes. */
int evr_events_format_holds_ids(const char *path);

/* ---- labels.h5 (src/io/labels_read.c; README "Ground truth" has the layout) ---- */
typedef struct {
    int width, height;   /* of each frame */
    size_t frames;       /* >= 1 */
    double *t;           /* each frame's time, seconds, increasing (malloc'ed) */
    double fps, flow_dt; /* the file's attributes (NaN when missing) */
    int complete;        /* the run finished the file */
} evr_labels_info;

/* Reads a labels.h5's frame times and sizes (checked in a child process first: HDF5 crashes on
 * some corrupt files). A file without the t, depth, instance and flow datasets, of inconsistent
 * shapes or without frames is refused (EVR_ERR_FORMAT). Free with evr_labels_info_free. */
evr_status evr_labels_read_info(const char *path, evr_labels_info *info, evr_error *err);
void evr_labels_info_free(evr_labels_info *info);
/* Reads frame k (< info->frames) of the file info was read from: width * height values of depth
 * and instance, twice that of flow; a NULL buffer is not read. */
evr_status evr_labels_read_frame(const char *path, const evr_labels_info *info, size_t k,
                                 float *depth, uint32_t *instance, float *flow, evr_error *err);
/* The frame nearest time t (seconds); EVR_ERR_ARG, naming the frames' range, when t is more
 * than half a frame interval (1 / fps) before the first or after the last. */
evr_status evr_labels_nearest_frame(const evr_labels_info *info, double t, size_t *k,
                                    evr_error *err);

/* ---- accuracy of an event stream against a reference (src/compare.c) ---- */
/* One-to-one matching of events at the same pixel with the same polarity within a time
 * tolerance, in time order. */
typedef struct {
    uint64_t ref_on, ref_off, test_on, test_off;
    uint64_t matched;
    double precision, recall, f1;   /* matched / test, matched / ref, harmonic mean */
    double count_ratio;             /* test events / reference events */
    double median_dt_us, p95_dt_us; /* |t_test - t_ref| of matched pairs */
    double pixel_count_correlation; /* Pearson correlation of per-pixel event counts */
} evr_compare_result;

/* Both streams sorted by time. tol_us >= 0. tol_level in [0, 0.5]: a reference event also
 * matches within tol_level times its gap, the time since the previous reference event of its
 * pixel and polarity (the group's first event: the time to the next one). The log intensity
 * moves one threshold over a gap, so that is the timing error a level error of tol_level
 * thresholds makes: an event of a slowly changing pixel is placed by its level to within a
 * fraction of its gap, not of a fixed time. 0: the fixed tolerance alone. */
evr_status evr_compare_events(const evr_event *ref, size_t nref, const evr_event *test,
                              size_t ntest, int64_t tol_us, double tol_level,
                              evr_compare_result *out, evr_error *err);

/* ---- charts and images (src/io/plot.c, src/io/png.c) ---- */
/* One line series: n points (x[i], y[i]) joined in order. */
typedef struct {
    const double *x, *y;
    size_t n;
    uint8_t color[3];
    const char *label; /* legend entry; NULL: none */
    int markers;       /* draw a small square at each point */
} evr_plot_series;

typedef struct {
    int width, height; /* image size in pixels */
    const char *title, *xlabel, *ylabel;
    int y_from_zero; /* the y axis starts at 0 (else at the data's minimum) */
} evr_plot_spec;

/* Draws the series on shared axes (range from the data, "nice" ticks) and writes an RGB8 PNG. */
evr_status evr_plot_lines_png(const char *path, const evr_plot_spec *spec,
                              const evr_plot_series *series, int nseries, evr_error *err);
/* Draws per-pixel counts (w x h, row-major, y = 0 the top row) with a log colour map
 * (log(1 + count) / log(1 + max)), scaled up by a whole factor when the image is small, with a
 * title and a colour bar labelled in counts, and writes an RGB8 PNG. *out_w and *out_h (may be NULL)
 * receive the image size. */
evr_status evr_plot_heatmap_png(const char *path, const uint32_t *counts, int w, int h,
                                const char *title, int *out_w, int *out_h, evr_error *err);
/* Draws an optical flow field (w x h, 2 floats per pixel: px/s, x right, y down; a pixel that is
 * not finite has no surface) with the optical-flow colour wheel of Baker et al. (Middlebury):
 * hue the direction (+x red, +y yellow, -x cyan-blue), saturation the magnitude over *max_px_s
 * (white: no motion; beyond the maximum full colour at 3/4 brightness), no surface black; with a
 * title and the wheel as a legend. *max_px_s <= 0: the 99th percentile of the finite magnitudes, returned
 * there. Each flow pixel is scale x scale image pixels (the largest whole factor keeping the
 * field within 640x640), the field's top-left corner at (EVR_PLOT_LABEL_X, EVR_PLOT_LABEL_Y);
 * *scale (may be NULL) receives it. Writes an RGB8 PNG. */
#define EVR_PLOT_LABEL_X 10
#define EVR_PLOT_LABEL_Y 40
evr_status evr_plot_flow_png(const char *path, const float *flow, int w, int h, const char *title,
                             double *max_px_s, int *scale, evr_error *err);
/* Draws a depth map (w x h; not finite: no surface) in the heat map's colours over the finite
 * range, near white and bright, far black; no surface teal (0, 128, 128); with a title and a
 * colour bar. Layout and *scale as evr_plot_flow_png; *near and *far (may be NULL) receive the
 * range (NaN when no pixel has a surface). Writes an RGB8 PNG. */
evr_status evr_plot_depth_png(const char *path, const float *depth, int w, int h, const char *title,
                              double *near, double *far, int *scale, evr_error *err);
/* channels: 1 (gray), 3 (RGB) or 4 (RGBA); bit_depth 8 or 16 (16-bit samples in native order).
 * Rows are top to bottom. Writes under path + ".tmp" and renames when complete. */
evr_status evr_png_write(const char *path, const void *pixels, int width, int height, int channels,
                         int bit_depth, evr_error *err);
/* The luminance the renderer uses, of linear RGB. */
float evr_rgb_luminance(const float rgb[3]);

/* ---- scenes: figures and the scaling city (src/scene/demo_city.c) ---- */
int evr_scene_num_instances(const evr_scene *s);
/* The names of instance i's node and mesh. */
const char *evr_scene_instance_node(const evr_scene *s, int i);
const char *evr_scene_instance_mesh(const evr_scene *s, int i);
/* Triangles of the distinct meshes, and of the scene (every instance's). */
void evr_scene_triangles(const evr_scene *s, uint64_t *mesh_triangles, uint64_t *scene_triangles);

/* The city at a tessellation detail (>= 1; a building's triangles grow as detail^2, its shape
 * unchanged) and a building count (the lots nearest the centre); the built-in scene "city" is
 * the defaults. For scaling sweeps (evray bench --sweep). */
#define EVR_CITY_DETAIL 1
#define EVR_CITY_BUILDINGS 4096
evr_status evr_demo_city_load(int detail, int count, evr_scene **out, evr_error *err);

/* ---- one image at one time (evray still: src/still.h, src/cpu/still.c) ---- */
typedef enum { EVR_GI_NONE = 0, EVR_GI_PHOTON = 1, EVR_GI_PATH = 2 } evr_gi_mode;

typedef struct {
    int width, height;
    double time;        /* seconds into the animation */
    const char *camera; /* NULL: the first */
    evr_gi_mode gi;
    int spp;          /* path: paths per pixel */
    uint32_t photons; /* photon: photons per pass (0: 8 per pixel) */
    float
        gather_radius; /* photon: distance filter r, world units (<= 0: 2% of the scene's diagonal) */
    int gather_max;    /* photon: photons per estimate at most */
    int gather_window;       /* photon: the window's half size at most, pixels */
    float gather_normal_cos; /* photon: normals must agree to this cosine */
    int photon_layers;       /* photon: photons per pixel of the buffer */
    int gather_area; /* photon: normalize over the surface the camera sees (evr_photon_gbuffer) */
    int auto_layers; /* photon: double the layers (up to 64) while > 3% of the photons collide */
    int max_bounces; /* indirect bounces (both methods) */
    float ambient;
    uint64_t seed;
    int threads; /* 0: all cores */
} evr_still_params;

void evr_still_defaults(evr_still_params *p);

/* A rendered image and its figures. */
typedef struct {
    int width, height;
    float *rgb;    /* width * height * 3 linear radiance, rows top to bottom */
    float *direct; /* the direct term alone (same layout) */
    int *instance; /* scene instance seen at each pixel's centre, -1: none */
    /* photon mode: the pass */
    uint64_t photon_paths, photons_stayed, photons_visible, photons_inserted, photon_collisions;
    float gather_radius;         /* the radius used */
    int photon_layers;           /* the layers used */
    double photons_per_estimate; /* mean photons per gather over hit pixels */
    double seconds_setup, seconds_photons, seconds_shading;
    int threads;
    void *result; /* the library's own */
} evr_still_image;

evr_status evr_still_image_render(const evr_scene *s, const evr_still_params *p,
                                  evr_still_image *out, evr_error *err);
void evr_still_image_free(evr_still_image *im);

/* ---- numbers and sizes as options give them ---- */
/* Each returns EVR_ERR_ARG with "OPT expects ..., got 'TEXT'" when text is not a whole valid
 * value (finite numbers; integers within their type; size WIDTHxHEIGHT, 1 to 65535 a side). */
evr_status evr_parse_double(const char *opt, const char *text, double *out, evr_error *err);
evr_status evr_parse_float(const char *opt, const char *text, float *out, evr_error *err);
evr_status evr_parse_int(const char *opt, const char *text, int *out, evr_error *err);
evr_status evr_parse_u64(const char *opt, const char *text, uint64_t *out, evr_error *err);
evr_status evr_parse_size(const char *opt, const char *text, int *w, int *h, evr_error *err);

/* ---- the configuration's options (the table: src/config/config_table.c) ---- */
typedef struct evr_config_option evr_config_option;
/* The option that arg starts ("--res", "--res=640x480", "-o"); *name is set to the name it used
 * (the option or its short alias). NULL when arg is none of them. */
const evr_config_option *evr_config_option_find(const char *arg, const char **name);
int evr_config_option_takes_value(const evr_config_option *o);
/* Sets what the option sets from value (NULL for an option without one); strings are kept as
 * given, not copied. EVR_ERR_ARG with a one-line message when value is not valid for it. */
evr_status evr_config_option_set(evr_config *c, const evr_config_option *o, const char *value,
                                 evr_error *err);
/* The i-th option (0, 1, ... in --help order; NULL past the last): its name ("--res"), whether
 * it takes a value, and its help text (lines separated by '\n'; "" for one written by a
 * function of its own). For bindings that mirror the options (the Python package). */
const char *evr_config_option_name(int i, int *takes_value, const char **help);
/* The options' help, by section, as `evray render --help` shows it (malloc'ed; NULL: no memory). */
char *evr_config_options_help(void);

#ifdef __cplusplus
}
#endif
#endif
