/* Framing: where the automatic camera looks from and how far, and camera poses from a position
 * and a target. The automatic camera (a scene without one) frames the box that holds the scene
 * over its whole animation, from the candidate direction that sees the most of its surfaces. */
#ifndef EVR_SCENE_FRAMING_H
#define EVR_SCENE_FRAMING_H

#include "scene/scene.h"

/* The box that holds every instance over times [t0, t1] (t1 <= t0: at t0 alone): each rigid
 * instance's mesh box placed by its node at the curves' key times and 65 times spread over the
 * range, each deforming instance's vertices at up to 17 of those times. Returns 0 when there
 * is nothing to bound (lo and hi then hold the rest bounds) or out of memory. */
int evr_frame_swept_bounds(const evr_scene *s, double t0, double t1, evr_v3 *lo, evr_v3 *hi);

/* The direction (unit, from the scene towards the camera) that sees the most of the scene's
 * surfaces at time t: among horizontal, 30-degree-high and vertical views around it, the one
 * with the largest projected area of the triangles that face it (both faces of a double-sided
 * material's); the first in evr_frame_direction's order of preference among those within 1% of
 * the best, so a symmetric model is seen from the front (+Z, glTF's front) and a flat model
 * face-on, never edge-on. */
evr_v3 evr_frame_direction(const evr_scene *s, double t);

/* A camera pose (camera space -Z along look, +Y towards up) at pos. */
evr_m34 evr_frame_look_along(evr_v3 pos, evr_v3 look, evr_v3 up);
/* A camera pose at from looking at to with world +Y up (straight down: -Z up; straight up: +Z
 * up, so that the scene's front is at the image's bottom). */
evr_m34 evr_frame_look_at(evr_v3 from, evr_v3 to);

/* The pose that frames box [lo, hi] from direction dir (unit, towards the camera) with a
 * perspective camera of vertical field of view yfov (radians) on an image of the given aspect
 * (width / height): looking at the box's centre from the nearest distance at which every corner
 * lies within 90% of the image's half width and height. all_around: the distance that does so
 * from every direction around the vertical axis at dir's elevation too (a camera that orbits
 * the box). *dist gets the distance (may be NULL). */
evr_m34 evr_frame_box(evr_v3 lo, evr_v3 hi, evr_v3 dir, float yfov, float aspect, int all_around,
                      float *dist);

#endif
