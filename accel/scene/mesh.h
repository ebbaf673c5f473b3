/*
 * mesh.h - pieces every built-in generator shares (mesh.c): the
 * primitive-count limit, deterministic random numbers, quads, and closed
 * indexed meshes kept in double precision. Not a public header: tools and
 * tests reach the generators through scene_generators[] in scene.h.
 *
 * Every generator is deterministic: its random numbers come from
 * scene_rng (SplitMix64, seeded from the scene's parameters), never rand().
 */
#ifndef ACCEL_SCENE_MESH_H
#define ACCEL_SCENE_MESH_H

#include <stdint.h>

#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The largest scene scene_finish accepts (ids are uint32, 0xFFFFFFFF = miss).
 * Generators check their primitive count against it before allocating. */
#define SCENE_BUILTIN_MAX_PRIMS 0xFFFFFFFEull

/* Fails with a message naming the scene when count is above the limit. */
int scene_check_count(const char *scene, uint64_t count, accel_error *err);

/* ---- random numbers ------------------------------------------------------ */

/* SplitMix64 (Steele, Lea and Flood, "Fast Splittable Pseudorandom Number
 * Generators", OOPSLA 2014): one 64-bit add and a bit mixer per draw. */
typedef struct {
    uint64_t state;
} scene_rng;

static inline uint64_t scene_rng_next(scene_rng *r)
{
    uint64_t z = (r->state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1) with 53 random bits. */
static inline double scene_rng_uniform(scene_rng *r)
{
    return (double)(scene_rng_next(r) >> 11) * 0x1p-53;
}

/* ---- meshes: vertices in double, triangles as indices --------------------- */

typedef struct { double x, y, z; } dvec3;

/*
 * An indexed triangle mesh kept in double precision so that it can be placed
 * (centre + radius * vertex) and rounded to float once. A vertex may be
 * stored more than once (along cube-face edges), but every copy is computed
 * by the same expression from the same integers, so the copies are
 * bit-identical and the placed mesh stays closed and watertight.
 */
typedef struct {
    dvec3 *verts;
    size_t vert_count;
    uint32_t *tris; /* 3 indices per triangle, counter-clockwise seen from outside */
    size_t tri_count;
} scene_mesh;

/* Cube [-1,1]^3, each face cut into n x n squares of two triangles:
 * 12 n^2 triangles, outward-facing. */
int scene_mesh_cube(scene_mesh *m, int n, accel_error *err);
/* Unit sphere as a cube projected onto the sphere along equally spaced great
 * circles (the tessellation the SPD uses for its spheres): n x n squares per
 * cube face, 12 n^2 triangles, no poles. */
int scene_mesh_cube_sphere(scene_mesh *m, int n, accel_error *err);
/* Unit sphere by latitude and longitude: `segments` meridians, segments/2
 * bands, poles on +-z: 2 * segments * (segments/2 - 1) triangles. */
int scene_mesh_uv_sphere(scene_mesh *m, int segments, accel_error *err);
/* Adds the mesh scaled by `scale` and moved to `centre` (computed in double,
 * rounded once). */
int scene_mesh_add(const scene_mesh *m, scene_builder *b, dvec3 centre, double scale,
                   accel_error *err);
void scene_mesh_free(scene_mesh *m);

/* ---- shared scene pieces ------------------------------------------------- */

/* Triangles counter-clockwise: the fan (a,c,d), (a,d,e) of FORMATS.md. */
int scene_add_quad(scene_builder *b, vec3 a, vec3 c, vec3 d, vec3 e, accel_error *err);

static inline vec3 dvec3_to_float(dvec3 p) { return v3((float)p.x, (float)p.y, (float)p.z); }

#ifdef __cplusplus
}
#endif

#endif
