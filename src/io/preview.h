/* Preview images: event frames (what the sensor fired in a time window) and tone-mapped
 * intensity frames (what it saw). All images are row-major with y = 0 the top row, written as
 * 8-bit PNG through evr_png_write (temporary name, then rename). */
#ifndef EVR_IO_PREVIEW_H
#define EVR_IO_PREVIEW_H

#include <stddef.h>
#include <stdint.h>
#include "evray.h"

/* ---- event frames ---- */

/* Per-pixel ON and OFF counts over a window. Colours follow the DSEC previews: white background,
 * ON blue (0,0,255), OFF red (255,0,0); where a pixel has both, the larger count wins and a tie
 * takes the polarity of the pixel's latest event. */
typedef struct {
    int width, height;
    uint32_t *on, *off; /* width * height counts */
    int8_t *last;       /* polarity of the latest event per pixel */
    uint64_t events;    /* events added since the last clear (inside the image) */
} evr_event_frame;

evr_status evr_event_frame_init(evr_event_frame *f, int width, int height, evr_error *err);
void evr_event_frame_clear(evr_event_frame *f);
/* Events outside the image are ignored. */
void evr_event_frame_add(evr_event_frame *f, const evr_event *ev, size_t n);
/* Fills rgb (width * height * 3 bytes) with the frame's colours. */
void evr_event_frame_render(const evr_event_frame *f, uint8_t *rgb);
/* Writes the frame as an RGB8 PNG. */
evr_status evr_event_frame_write_png(const evr_event_frame *f, const char *path, evr_error *err);
void evr_event_frame_release(evr_event_frame *f);

/* A series of event frames over consecutive windows: frame k shows the events with
 * k*window_us <= t < (k+1)*window_us and is written to "<dir>/<prefix>_<k, 6 digits>.png".
 * Windows without events are written too (white), so frame numbers map to time. Events before
 * t = 0 are ignored; events must come in time order (a late one is counted in the open window). */
typedef struct evr_event_preview evr_event_preview;

evr_status evr_event_preview_new(int width, int height, int64_t window_us, const char *dir,
                                 const char *prefix, evr_event_preview **out, evr_error *err);
/* Adds events, writing every window that ends at or before the time of an added event. */
evr_status evr_event_preview_add(evr_event_preview *p, const evr_event *ev, size_t n,
                                 evr_error *err);
/* Says no event before t_us is to come (call after each segment with its end time): writes every
 * window that ends at or before t_us. */
evr_status evr_event_preview_advance(evr_event_preview *p, int64_t t_us, evr_error *err);
/* Writes the remaining windows that start before end_us (the last one may be partial). */
evr_status evr_event_preview_finish(evr_event_preview *p, int64_t end_us, evr_error *err);
/* Frames written so far. */
int evr_event_preview_frames(const evr_event_preview *p);
void evr_event_preview_release(evr_event_preview *p);

/* ---- intensity frames ---- */

/* An exposure: linear luminance L is shown as sRGB(min(1, R(L * scale))), with R the extended
 * Reinhard curve l (1 + l / white^2) / (1 + l), which is the identity below 1 when white is 1.
 *
 * It is made from the visible scene only: pixels above 0 (where rays meet nothing, the
 * intensity is 0: a black background must not count, or a small object on it comes out white).
 * Of those, the median is shown at EVR_EXPOSURE_KEY of white (linear), unless that puts more
 * than 1% of them above white: then the 99th percentile is white. The white point is the 99.9th
 * percentile's scaled value when that is above 1 (those pixels compressed, not clipped), else
 * 1. A run fixes one exposure from its first frames (src/run/preview_out.c), so that a pixel
 * that keeps its intensity keeps its gray level: previews cannot flicker. */
typedef struct {
    double scale, white; /* scale 0: nothing visible yet (every pixel shows black) */
} evr_exposure;

#define EVR_EXPOSURE_KEY 0.3

/* The exposure of n values (one frame, or several frames' values one after another); negative
 * and NaN values count as 0, +infinity as the largest float. Out of memory is the only error. */
evr_status evr_exposure_of(const float *linear, size_t n, evr_exposure *e, evr_error *err);
/* Tone maps n values to 8-bit sRGB gray with exposure e (monotonic; 0 stays 0). */
void evr_tonemap_exposed(const float *linear, size_t n, const evr_exposure *e, uint8_t *out);
/* One frame tone mapped with its own exposure (evr_exposure_of, then evr_tonemap_exposed). */
evr_status evr_tonemap_frame(const float *linear, size_t n, uint8_t *out, evr_error *err);

#endif
