/*
 * builtin.h - the generators of the built-in scene table (builtin.c) that
 * other files define: the SPD scenes (spd.c) and the scenes of many meshes
 * (multi.c). Not a public header: tools and tests reach the generators
 * through scene_generators[] in scene.h.
 */
#ifndef ACCEL_BUILTIN_H
#define ACCEL_BUILTIN_H

#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

extern const scene_generator scene_gen_sphereflake; /* spd.c */
extern const scene_generator scene_gen_tetra;       /* spd.c */
extern const scene_generator scene_gen_mount;       /* spd.c */
extern const scene_generator scene_gen_field;       /* multi.c */
extern const scene_generator scene_gen_animated;    /* multi.c */

#ifdef __cplusplus
}
#endif

#endif
