/* The parts of the eye scenes (demo_eye.c) that the blink scene (demo_blink.c) shares: the
 * textures, the eyeball (sclera and cornea), the lids, the skin around them, the socket, and the
 * shape of a blink. Each is described in demo_eye.c's opening comment; geometry is built in
 * millimetres and stored in metres, the eye centre at the origin, looking along +Z. Internal to
 * the library. */
#ifndef EVR_SCENE_DEMO_EYE_PARTS_H
#define EVR_SCENE_DEMO_EYE_PARTS_H

#include <stdint.h>
#include "scene/demo_scenes.h"

/* A blink (seconds): the upper lid turns down by EVR_EYE_BLINK_UPPER_DEG about the X axis
 * through the eye centre, the lower one up by EVR_EYE_BLINK_LOWER_DEG. */
#define EVR_EYE_BLINK_CLOSE 0.100
#define EVR_EYE_BLINK_HOLD 0.030
#define EVR_EYE_BLINK_OPEN 0.170
#define EVR_EYE_BLINK_LEN (EVR_EYE_BLINK_CLOSE + EVR_EYE_BLINK_HOLD + EVR_EYE_BLINK_OPEN)
#define EVR_EYE_BLINK_UPPER_DEG 38.0
#define EVR_EYE_BLINK_LOWER_DEG 2.5

/* Textures; each returns the texture index (-1 on failure, recorded in g). */
int evr_eye_paint_sclera(evr_gltf *g);
int evr_eye_paint_iris(evr_gltf *g);
int evr_eye_paint_eyelid(evr_gltf *g, const char *name, uint32_t seed, int lashes, double len_lo,
                         double len_hi);
/* The face around the eye, planar over [-outer, outer] mm (size x size texels), row 0 at
 * y = +outer; a few fine wrinkles at the lateral corner (crow's feet). */
int evr_eye_paint_skin(evr_gltf *g, double outer, int size);
/* Skin colour (sRGB, 0..255) at (x, y) mm: blotches and pores. */
void evr_eye_skin_colour(double c[3], double x, double y, uint32_t seed);

/* The eyelashes: dark strands on a transparent ground (RGBA, for an alpha-masked card), u along
 * the lid, v from the roots (row 0) to the tips. */
int evr_eye_paint_lashes(evr_gltf *g, int upper);

/* The globe under node eyeball (the eye centre, looking along +Z): child nodes "sclera",
 * "cornea", "iris" and "pupil" with their textures, materials and meshes. */
void evr_eye_globe(evr_gltf *g, int eyeball);
/* The anatomy the globe is built to (mm, eye centre at the origin, gaze along +Z), for tests and
 * the scene's description. */
#define EVR_EYE_R 12.0       /* the eyeball (sclera) */
#define EVR_EYE_CORNEA_R 7.8 /* the cornea's front surface, a sphere centred on +Z ... */
#define EVR_EYE_CORNEA_C 6.7 /* ... at this z: apex at 14.5 */
#define EVR_EYE_PUPIL_R 1.8  /* the pupil's radius ... */
#define EVR_EYE_PUPIL_Z 11.6 /* ... and its plane: 2.9 behind the apex */
#define EVR_EYE_IRIS_R 5.75  /* the visible iris */
#define EVR_EYE_IRIS_EDGE_Z 11.15
#define EVR_EYE_CORNEA_IOR 1.376f
/* The upper (upper = 1) or lower lid, added to m: a surface of revolution about the X axis, so
 * that turning it about that axis slides it over itself. */
void evr_eye_lid(evr_demo_mesh *m, int upper);
/* The lid's eyelashes, added to m in the lid's frame (move it with the lid): a curved card
 * rooted along the lid's margin, textured by evr_eye_paint_lashes. */
void evr_eye_lashes(evr_demo_mesh *m, int upper);
/* The lashes' material: that texture, alpha-masked, two-sided. */
int evr_eye_lash_material(evr_gltf *g, int upper);
/* The skin from the eye's opening out to a circle of radius outer (mm). */
int evr_eye_skin(evr_gltf *g, int material, double outer);
int evr_eye_orbit(evr_gltf *g, int material);

/* A textured material of the eye scenes. */
int evr_eye_material(evr_gltf *g, const char *name, int texture, float roughness);

/* Position along a saccade, t in [0, 1]: the integral of a velocity profile t (1-t)^1.5,
 * normalized. Its peak comes at 40% of the duration and is 1.63 times the mean velocity, as in
 * real saccades. */
double evr_eye_saccade_profile(double t);
/* Lid closure 0 (open) .. 1 (closed) s seconds into a blink: closing along the saccade profile,
 * held, opening. Exactly 0 outside [0, EVR_EYE_BLINK_LEN] (and where it is below 1e-9, so that a
 * key at a blink's end rounded in time still holds the open pose). */
double evr_eye_blink_closure(double s);

#endif
