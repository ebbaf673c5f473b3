/*
 * test_ngrid.h - what the nested-grid test files share, defined in
 * test_ngrid.c.
 */
#ifndef TESTS_TEST_NESTED_GRID_H
#define TESTS_TEST_NESTED_GRID_H

#include "nested_grid/ngrid.h"
#include "support.h"

/*
 * A dense cluster in a sparse scene: `cluster` small triangles in the unit
 * cube at (50,50,50) and 300 large ones spread over [0,100]^3 (the teapot in
 * a stadium, in miniature), plus `spheres` spheres in the cluster. Returns 1
 * on success (a failure is a failed check).
 */
int test_ngrid_cluster_scene(accel_scene *s, int cluster, int spheres);

/* Rays for the cluster scene: 2500 from outside towards the cluster, 2000
 * from inside it in every direction (some with finite t ranges), 1200
 * axis-parallel ones through it with +0/-0 in the other components. */
void test_ngrid_cluster_rays(test_rays *r);

/* accel_build_spec without the kind: the status, and *err on failure. */
int test_ngrid_build(const char *spec, const accel_scene *s, int threads, void **accel,
                     accel_build_stats *st, accel_error *err);

#endif
