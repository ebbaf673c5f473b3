/*
 * stiff.h - the stiff and extreme cases of the stability study.
 *
 * Each case is a scene plus a ray set built to hit a known weakness:
 * rays aimed exactly at shared vertices and edges of closed meshes (from
 * outside, and from inside, where a miss is a leak whatever the reference
 * says), rays along the axes and along cell diagonals with +0/-0
 * components starting exactly on cell boundaries and split planes, rays
 * grazing faces, origins inside primitives' boxes, scenes far from the
 * origin, tiny and huge, flat, degenerate, coincident and same-centroid
 * geometry, closed meshes that touch or interpenetrate. Deterministic:
 * case i is always the same scene and rays; stiff_case_make_n makes the
 * same scene with more rays of the same kinds (a million and more, each
 * distinct) for rates of a few per million.
 */
#ifndef ACCEL_STIFF_H
#define ACCEL_STIFF_H

#include "rays/rays.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    char name[96];
    char what[160];          /* one line: what the case probes */
    accel_scene scene;
    rays_set rays;
    /* Rays [leak_begin, rays.count) start inside a closed mesh: each must
     * hit something (a miss is a leak), whatever any tracer says. */
    size_t leak_begin;
    /* Any-hit (shadow) rays from inside a closed convex mesh to 1.25 times
     * the distance to a point of its surface: each must be occluded (the
     * closed and contact cases; empty otherwise). */
    rays_set shadow;
} stiff_case;

/* Number of built-in cases. */
int stiff_case_count(void);
/* Makes case i (0 <= i < stiff_case_count()). */
int stiff_case_make(int i, stiff_case *c, accel_error *err);
/* Case i with at least min_rays rays (0 or few: the base case), none
 * repeated: every random count scaled up, lattices refined. */
int stiff_case_make_n(int i, size_t min_rays, stiff_case *c, accel_error *err);
/* Index of the case named `name`, or -1. */
int stiff_case_index(const char *name);
/* Case on a closed convex mesh `s` (taken: *s is zeroed) with at least
 * min_rays distinct rays: vertex/edge rays from outside, leak and shadow
 * rays from inside. */
int stiff_case_closed(accel_scene *s, const char *name, size_t min_rays, stiff_case *c,
                      accel_error *err);
/* Case from any scene (a mesh file): vertex/edge rays from outside and,
 * when `closed`, from the centre of its bounds (leak rays). */
int stiff_case_from_scene(const char *spec, int closed, stiff_case *c, accel_error *err);
void stiff_case_free(stiff_case *c);

/* accel_reference_trace's answer, bitwise; for a triangle scene far from
 * the origin (its centre over 1e3 times its size away) traced on a copy
 * moved to the origin when every coordinate moves exactly (stiff_post.c
 * says why that is the same answer, and fast). */
void stiff_reference(const accel_scene *s, const accel_ray *rays, accel_hit *hits, size_t n,
                     int threads);

/* Rays from `eye` aimed exactly at vertices and edge midpoints of `count`
 * deterministic random live triangles (appends to *r, growing it). */
int stiff_add_vertex_rays(const accel_scene *s, vec3 eye, size_t count, uint64_t seed,
                          rays_set *r, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
