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

extern const char *const inst_scene_mirrored_scaled;
extern const char *const inst_scene_far;
extern const char *const inst_scene_overlap;

#endif
