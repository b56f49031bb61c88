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

/* Tone maps n linear luminance values to 8-bit sRGB gray. Reinhard's photographic operator:
 * the frame is scaled so that its log-average maps to the key 0.18, then the extended Reinhard
 * curve L*(1 + L/Lw^2)/(1 + L) with the white point Lw = the 99.5th percentile of the scaled
 * values (so a few hot pixels do not darken the frame), then the sRGB transfer curve. The map is
 * monotonic within a frame. Negative and NaN values count as 0. */
evr_status evr_tonemap_reinhard(const float *linear, size_t n, uint8_t *out, evr_error *err);
/* Tone maps a w x h linear luminance frame as above and writes an 8-bit gray PNG. */
evr_status evr_preview_intensity_png(const char *path, const float *linear, int w, int h,
                                     evr_error *err);

#endif
