/* Intensity frames for frame-based tools (v2e and the like): the --frames-out folder. Frame k is
 * every pixel's intensity at exactly t_k = start + k / frames_fps, for every t_k from the start up
 * to and including the end of the run (floor(duration * frames_fps) + 1 frames); the backend
 * renders it with the segment that holds t_k. Each frame is written as frame_NNNNNN.png (8-bit
 * gray, sRGB-encoded, intensity * frames_exposure clamped to [0, 1]) and frame_NNNNNN_linear16.png
 * (16-bit gray, linear, round(intensity * 65535 / frames_max) clamped); frames.csv lists them. */
#ifndef EVR_FRAMES_OUT_H
#define EVR_FRAMES_OUT_H

#include <stddef.h>
#include <stdint.h>
#include "sim_state.h"

/* Plans the frames of the run (times, and which segment renders which); needs sim->fps,
 * duration and num_segments. Does nothing when no frames are asked for. */
evr_status evr_frames_plan(evr_sim *sim, evr_error *err);
/* Fails when the folder already holds frames (frame_*.png, frames.csv) and --force is not set;
 * creates nothing (call before the run folder is made). */
evr_status evr_frames_check(const evr_sim *sim, evr_error *err);
/* Creates the folder (with --force, first removes the frames already in it). */
evr_status evr_frames_prepare(evr_sim *sim, evr_error *err);
/* The frames segment i renders: times seg frame_times[first .. first + count). */
void evr_frames_of_segment(const evr_sim *sim, int i, int *first, int *count);
/* Writes frame k (linear intensities, row-major, top row first) as its two PNGs. */
evr_status evr_frames_write(evr_sim *sim, int k, const float *linear, evr_error *err);
/* Writes frames.csv listing every frame written (temporary name, then rename). */
evr_status evr_frames_finish(evr_sim *sim, evr_error *err);
/* Removes the frames this run wrote (and the folder if it made it). */
void evr_frames_discard(evr_sim *sim);
void evr_frames_free(evr_sim *sim);

/* The encodings, exposed for tests: 8-bit sRGB of intensity * exposure clamped to [0, 1], and
 * 16-bit linear round(intensity * 65535 / max) clamped; NaN and negative values give 0. */
void evr_frame_to_srgb8(const float *linear, size_t n, float exposure, uint8_t *out);
void evr_frame_to_linear16(const float *linear, size_t n, float max, uint16_t *out);

#endif
