/* The run's previews (evr_config.preview). For each window of preview_window seconds: an event
 * frame (the window's events, io/preview.h's colours) and an intensity frame (every pixel's
 * intensity at the window's end, tone mapped with the run's one exposure), written as two PNG
 * files per window in preview/ (EVR_PREVIEW_PNG) or as one animated PNG, preview.apng, each
 * frame the two side by side, events on the left (EVR_PREVIEW_VIDEO; io/apng.h).
 *
 * The exposure (io/preview.h) is fixed from EVR_PREVIEW_EXPOSURE_FRAMES intensity frames, the
 * first that shows anything and those after it, which are held until then (or the run's end);
 * frames before the first one that shows anything are black under any exposure and go out at
 * once. Event frame k is complete once no
 * event before its window's end can come (evr_preview_out_advance); a video frame goes out when
 * both its halves are there. */
#ifndef EVR_RUN_PREVIEW_OUT_H
#define EVR_RUN_PREVIEW_OUT_H

#include <stddef.h>
#include <stdint.h>

#include "evray.h"
#include "io/preview.h"

#define EVR_PREVIEW_EXPOSURE_FRAMES 3

typedef struct evr_preview_out evr_preview_out;

/* Previews of kind (EVR_PREVIEW_PNG or EVR_PREVIEW_VIDEO) into the run folder run_dir (PNG:
 * its folder preview/ is made here), for width x height images; the run starts at start_us
 * (absolute event time) and each window lasts window_us (>= 1). */
evr_status evr_preview_out_new(int kind, const char *run_dir, int width, int height,
                               int64_t start_us, int64_t window_us, evr_preview_out **out,
                               evr_error *err);
/* Events in time order (those before the run's start are ignored). */
evr_status evr_preview_out_events(evr_preview_out *p, const evr_event *ev, size_t n,
                                  evr_error *err);
/* No event before t_us (absolute) is to come: the event frames of the windows that end by then
 * are complete. */
evr_status evr_preview_out_advance(evr_preview_out *p, int64_t t_us, evr_error *err);
/* The intensity frame of the next window: width * height linear values (copied). */
evr_status evr_preview_out_intensity(evr_preview_out *p, const float *linear, evr_error *err);
/* The run lasted dur_us: completes the event frames of every window that starts before it, the
 * held frames, and the video. */
evr_status evr_preview_out_finish(evr_preview_out *p, int64_t dur_us, evr_error *err);
/* Windows whose event frame is complete. */
int evr_preview_out_windows(const evr_preview_out *p);
/* The run's exposure (scale 0 while undecided, or when nothing was ever visible). */
evr_exposure evr_preview_out_exposure(const evr_preview_out *p);
/* Releases p; an unfinished video's temporary file is removed (NULL: nothing). */
void evr_preview_out_release(evr_preview_out *p);

#endif
