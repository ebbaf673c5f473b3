/*
 * instanced.h - the `instanced` kind: a two-level acceleration structure
 * for scenes of many meshes (accel_scene.instances, from a .scene file or
 * the built-in field and animated scenes). See README.md.
 *
 *   instanced                          top=bvh, bottom=bvh
 *   instanced:top=grid,bottom=grid     uniform grids at both levels
 *   instanced:bottom=nested_grid       any kind with a walk (accel.h) as the
 *                                      bottom level: bottom=<kind> or
 *                                      bottom=<kind>:k=v;k=v (';' for ',')
 *   instanced:world=compute            each leaf's world blocks computed
 *                                      when a ray reaches it (default:
 *                                      per-instance copies, world=blocks)
 *   instanced:traverse=packet          64 rays walk both 8-wide levels
 *                                      together (the same answers, bit for bit)
 *
 * One bottom level per mesh, in object space, shared by all the mesh's
 * instances; one top level over the instances' world bounds. Rays go to
 * object space in double to walk a bottom level whose boxes are grown by a
 * pad covering the flattening's rounding; every triangle reached is
 * decided in world space on the very floats of the flattened scene, so the
 * hits are those of any kind on the flattened scene (ids base + local id,
 * t the world parameter, u and v of the world triangle).
 *
 * Parameters (bin/trace --help): top, bottom (bvh|grid or a kind spec), leaf (bottom BVH
 * leaf size), width (BVH levels walked 8-wide, or 2: the binary tree), lambda and top_lambda (grid cells per primitive / instance),
 * world (blocks|compute), traverse (single|packet), and the common tri=watertight|naive.
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

/* Builds `instanced` (parameters kv, as after "instanced:") with the kind
 * `bottom` (registered or not, e.g. the lab's; parameters bottom_kv) as the
 * bottom level of every mesh, walked through its accel.h walk; the result
 * is traced and destroyed through accel_kind_instanced. The same as
 * bottom=<spec>, for a kind the registry does not list. */
int instanced_build_with_bottom(const accel_scene *scene, const char *kv, const accel_kind *bottom,
                                const char *bottom_kv, int threads, void **out,
                                accel_build_stats *stats, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
