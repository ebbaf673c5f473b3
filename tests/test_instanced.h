/*
 * test_instanced.h - the stiff instanced scenes and rays of
 * test_instanced.c, shared with test_anybottom.c.
 */
#ifndef TESTS_TEST_INSTANCED_H
#define TESTS_TEST_INSTANCED_H

#include "accel.h"

typedef struct {
    accel_ray *r;
    size_t n, cap;
} ray_list;

/* Mesh source for scene_parse_scene: "quad" is the unit square, anything
 * else a built-in spec. */
int inst_stiff_mesh(void *ctx, const char *source, const char *dir, accel_scene *mesh,
                    accel_error *err);
/* Rays at world vertices and edge midpoints, from inside instances,
 * camera and shadow rays (l->r is malloc'd). */
void inst_make_rays(const accel_scene *s, ray_list *l);
/* A sheet of n x n unit squares, each its own instance (malloc'd text). */
char *inst_sheet(int n, const char *place);

/* Holes + false hits + disagreements + occlusion mismatches of a built
 * structure on the rays against the oracle's hits ref; a test note names
 * the first bad ray unless spec contains "pad=0". holes may be NULL. */
size_t inst_count_bad(const accel_kind *kind, const void *a, const accel_scene *s,
                      const ray_list *l, const accel_hit *ref, const char *spec, size_t *holes);

/* The same for a spec built on s (a build failure fails the test). */
size_t inst_bad_rays(const accel_scene *s, const ray_list *l, const accel_hit *ref,
                     const char *spec, size_t *holes);

extern const char *const inst_scene_mirrored_scaled;
extern const char *const inst_scene_far;
extern const char *const inst_scene_overlap;

#endif
