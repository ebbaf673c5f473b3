/*
 * teapot.h - Newell's teapot (teapot.c): its control net and its
 * tessellation into a scene_builder, for the built-in scenes that place it
 * (teapot_stadium in builtin.c, field and animated in multi.c) and tests.
 */
#ifndef ACCEL_SCENE_TEAPOT_H
#define ACCEL_SCENE_TEAPOT_H

#include <stdint.h>

#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Triangles scene_teapot_add emits for n x n quads per patch: 32 patches of
 * 2 n^2 triangles, less the n zero-area triangles each of the 8 patches with
 * a collapsed edge (lid knob and bottom centre) would give: 64 n^2 - 8 n. */
uint64_t scene_teapot_tri_count(int n);
/* Control point `col` of row `row` of patch 0..31 (x, y, z). */
const float *scene_teapot_control(int patch, int row, int col);
/* Newell's teapot (z up, standing on z = 0, about 6.5 x 4 x 3.15 units)
 * tessellated into n x n quads per Bezier patch, two triangles each. */
int scene_teapot_add(scene_builder *b, int n, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
