/* Swept bounds: the world box a motion track's keys carry an object-space box through over a
 * segment, for the GPU's top-level tree and the skip plan. */
#ifndef EVR_PREP_SWEPT_BOUNDS_H
#define EVR_PREP_SWEPT_BOUNDS_H

#include "core/motion.h"

#ifdef __cplusplus
extern "C" {
#endif

/* World box that holds the object-space box [lo, hi] moved by track tr at every time of the
 * segment, f in [0, 1], with the interpolation of evr_motion_eval. Conservative: between
 * samples of the rotation and scaling, the box of the (linear) translation plus the boxes at
 * the two samples widened by a bound on how far a point can turn or stretch in between (slerp
 * at its angular speed, scale/skew change); the union over all steps. Samples are spaced so
 * that the widening is about 1% of the object's size (at most 64 per key interval). */
void evr_swept_bounds(const float lo[3], const float hi[3], evr_motion_track tr, float out_lo[3],
                      float out_hi[3]);

/* Float bounds that hold a double value: the float at or below it, at or above it. */
float evr_round_down(double x);
float evr_round_up(double x);

#ifdef __cplusplus
}
#endif
#endif
