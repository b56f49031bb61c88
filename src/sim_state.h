/* The simulation object behind evr_sim: the segment loop's state, shared by the segment loop
 * (sim.c), the run folder (run_files.c) and the intensity frames (frames_out.c). It declares no
 * functions, so that each of them includes it without an include loop. */
#ifndef EVR_SIM_STATE_H
#define EVR_SIM_STATE_H

#include <stdio.h>

#include "backend.h"
#include "run/segment_planner.h"
#include "prep/skip_plan.h"
#include "io/event_writer.h"
#include "run/preview_out.h"
#include "run/write_queue.h"
#include "scene/camera_rig.h"

#define EVR_MAX_WRITERS 16 /* formats a run may write (io/event_formats.h) */

/* ON events and timestamp changes (t differing from the one before, prev for the first) of a
 * part of a batch of emitted events. */
typedef struct {
    const evr_event *ev;
    size_t n;
    int64_t prev;
    uint64_t on, changes;
} evr_event_counts;

#define EVR_COUNT_PARTS 8

/* A batch of events pushed to the writers: every event before before_us was in the batches
 * before it; the run's counts once it is counted too. */
typedef struct {
    int64_t before_us;
    uint64_t events, on, unique;
} evr_batch_mark;

/* Marks of the last batches (a ring by batch number): the writer queue holds at most nine
 * batches not yet taken by every writer, so a failed run finds the counts of what the writers
 * took here. */
#define EVR_BATCH_MARKS 32

struct evr_sim {
    const evr_scene *scene;
    evr_config cfg;
    char out_dir[4096];
    int created_dir;
    int dir_ours; /* the folder holds no file of evray's but this run's (new, empty, or cleaned) */
    int camera;
    evr_camera_rig rig;     /* the camera as the run renders it (scene/camera_rig.h) */
    char camera_path[4096]; /* the configuration's camera path, kept */
    char bvh_cache[4096];   /* the GPU BVH cache's folder, resolved ("": none) */
    int num_tracks;         /* motion tracks: the nodes', the world frame, the camera's own */
    FILE *poses;            /* camera_poses.txt being written (run/camera_poses.h), or NULL */
    char *poses_tmp;
    evr_quat poses_last; /* the last pose's rotation written (the next takes its hemisphere) */
    double fps, duration;
    int num_segments;
    int64_t timestamp_slack_us; /* how far jitter and rounding move a timestamp from its crossing */
    evr_render_host host;
    evr_run_setup setup;
    evr_backend *backend;
    evr_event_writer *writers[EVR_MAX_WRITERS];
    const char *writer_names[EVR_MAX_WRITERS];
    int num_writers;
    int writer_lost[EVR_MAX_WRITERS]; /* a failed run could not keep its file */
    evr_write_queue *wq;              /* writes on its own thread */
    evr_event_writer *sink;           /* the caller's sink (run/event_sink.h), or NULL */
    char *config_json;
    /* per-segment motion and plans (segment_planner.h: the tracker is the planner thread's) */
    evr_planner *planner;
    struct evr_par_pool *par; /* threads for the passes over a segment's events (par_pool.h) */
    int *node_used;
    evr_skip_tracker skip;
    evr_deform_tracker deform;     /* the planner thread's, like skip */
    uint32_t *skipped_per_segment; /* pixels that traced nothing, per segment */
    /* events */
    evr_event_vec pending, scratch;
    int64_t last_t;
    /* the last emitted batch, counted on the pool while the loop goes on (count_parts 0: none) */
    evr_event_counts counting[EVR_COUNT_PARTS];
    int count_parts;
    uint64_t batches;         /* batches pushed to the writers */
    uint64_t counting_batch;  /* the batch counted on the pool */
    int64_t emitted_until_us; /* every event before it has gone to the writers */
    evr_batch_mark marks[EVR_BATCH_MARKS];
    int cancel;        /* evr_sim_cancel: stop at once (atomic; the backend reads it) */
    int reserve_made;  /* the run folder's reserve file (run_files.c) is there */
    char failure[512]; /* a failed run's error, for run.json */
    char lost[1024];   /* outputs a failed run could not keep, and why */
    /* previews */
    evr_preview_out *preview; /* NULL: previews off */
    int64_t preview_window_us;
    int64_t intensity_frame; /* index of the next intensity frame due */
    /* intensity frames for other tools (frames_out.h); num_frames 0: none */
    char frames_dir[4096];
    double frames_fps;
    int num_frames;
    double *frame_times; /* absolute time of every frame */
    int *
        seg_first_frame; /* segment i renders frames seg_first_frame[i] .. seg_first_frame[i + 1] - 1 */
    int frames_written; /* frames 0 .. frames_written - 1 are on disk */
    int created_frames_dir;
    uint8_t *frame8;
    uint16_t *frame16;
    /* ground truth (run/labels_out.h); NULL: none wanted */
    struct evr_labels_out *labels;
    /* statistics */
    evr_stats st;
    double wall0;          /* the run's start: its wall time ends when every output is complete */
    double time_motion;    /* motion keys and the skip plan, per segment on the planner's thread */
    double time_plan_wait; /* the segment loop waiting for the planner */
    double time_setup_host, time_first_plan; /* set-up before the backend; the first plan */
    double time_setup, time_render, time_sort, time_write, time_write_thread, time_preview;
    double time_piece_emit; /* of the collect in progress: its pieces written (emit_piece) */
};

#endif
