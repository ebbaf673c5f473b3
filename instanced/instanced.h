/*
 * instanced.h - the `instanced` kind: a two-level acceleration structure
 * for scenes of many meshes (accel_scene.instances, from a .scene file or
 * the built-in field and animated scenes). See README.md.
 *
 *   instanced                          top=bvh, bottom=bvh
 *   instanced:top=grid,bottom=grid     uniform grids at both levels
 *   instanced:world=flat               world triangles read from the
 *                                      flattened scene, not recomputed
 *
 * One bottom level per mesh, in object space, shared by all the mesh's
 * instances; one top level over the instances' world bounds. Rays go to
 * object space in double to walk a bottom level whose boxes are grown by a
 * pad covering the flattening's rounding; every triangle reached is
 * decided in world space on the very floats of the flattened scene, so the
 * hits are those of any kind on the flattened scene (ids base + local id,
 * t the world parameter, u and v of the world triangle).
 *
 * Parameters (bin/trace --help): top, bottom (bvh|grid), leaf (bottom BVH
 * leaf size), lambda and top_lambda (grid cells per primitive / instance),
 * world (compute|flat), and the common tri=watertight|naive.
 *
 * A plain scene is one identity instance of itself. The kind is reached
 * through the registry only (registry.c): accel_kind_instanced.
 */
#ifndef INSTANCED_INSTANCED_H
#define INSTANCED_INSTANCED_H

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

extern const accel_kind accel_kind_instanced;

#ifdef __cplusplus
}
#endif

#endif
