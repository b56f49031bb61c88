/* labels.h5: dense ground truth per label frame (README "Ground truth" has the layout):
 *
 *   /t             float64 [N]          seconds, scene time of each frame
 *   /depth         float32 [N, H, W]    along the optical axis; NaN: background
 *   /instance      uint32  [N, H, W]    1 + the scene instance a pixel sees; 0: background
 *   /flow          float32 [N, H, W, 2] image velocity (x right, y down), px/s; NaN: background
 *   /displacement  float32 [N, H, W, 2] image displacement over flow_dt, px; NaN: background
 *   /normal        float32 [N, H, W, 3] (with --label-normals) optical frame; NaN: background
 *   /instances     compound [M]: id uint32, node (node path, '/' between names), mesh (name)
 *   attributes on /: width, height (int32), fps, flow_dt (float64), config (JSON text),
 *   complete (int8, 1 once finished)
 *
 * Every frame dataset is chunked one frame per chunk (shuffle + deflate), extendible along N.
 * Written under the temporary name labels.h5.tmp and flushed after every segment; finish()
 * marks it complete and renames it. */
#ifndef EVR_IO_LABELS_H5_H
#define EVR_IO_LABELS_H5_H

#include <stdint.h>
#include "evray.h"

typedef struct evr_labels_h5 evr_labels_h5;

typedef struct {
    int width, height, normals;
    double fps, flow_dt;
    const char *config_json;
    /* id i + 1 is instance i: its node's path and its mesh's name (io/h5_instances.h) */
    const char *const *inst_node, *const *inst_mesh;
    int num_instances;
} evr_labels_h5_meta;

evr_status evr_labels_h5_open(const char *path, const evr_labels_h5_meta *m, evr_labels_h5 **out,
                              evr_error *err);
/* Appends one frame: width * height values each (flow, displacement 2 and normal 3 per pixel;
 * normal ignored without normals). */
evr_status evr_labels_h5_append(evr_labels_h5 *w, double t, const float *depth,
                                const uint32_t *instance, const float *flow, const float *disp,
                                const float *normal, evr_error *err);
/* Makes what was appended durable (an interrupted run keeps it in the temporary file). */
evr_status evr_labels_h5_flush(evr_labels_h5 *w, evr_error *err);
/* Marks it complete, closes and renames it into place; frees w whatever the result. */
evr_status evr_labels_h5_finish(evr_labels_h5 *w, evr_error *err);
/* Removes the temporary file and frees w (NULL is fine). */
void evr_labels_h5_abort(evr_labels_h5 *w);

#endif
