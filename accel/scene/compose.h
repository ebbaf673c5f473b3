/*
 * compose.h - scenes of many meshes: meshes placed by instances with affine
 * transforms, flattened into one accel_scene that keeps the description
 * (accel_scene.instances, see accel.h).
 *
 * Two producers fill a scene_compose: the `.scene` reader (load_scene.c,
 * FORMATS.md) and the built-in multi-mesh scenes (field, animated). Both
 * then call scene_compose_finish, the one flattener, so the primitive ids
 * (instances in order, each its mesh's primitives in the mesh's order) and
 * the world coordinates (accel_xform_vertex: double, fused, rounded once)
 * are defined in one place.
 *
 * Transforms are 3x4 matrices in double, rows: world = M * (x, y, z, 1).
 */
#ifndef ACCEL_SCENE_COMPOSE_H
#define ACCEL_SCENE_COMPOSE_H

#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The largest flattened scene: ids are uint32 and 0xFFFFFFFF means miss. */
#define SCENE_COMPOSE_MAX_PRIMS 0xFFFFFFFEull

typedef struct scene_compose {
    accel_instances set;      /* meshes and instances collected so far */
    uint32_t mesh_cap, instance_cap;
    box3 *mesh_vert_bounds;   /* per mesh: bounds of every vertex (degenerate triangles too) */
    uint64_t prim_total;      /* primitives of the flattened scene so far */
    uint64_t max_prims;       /* limit on prim_total (0: SCENE_COMPOSE_MAX_PRIMS) */
} scene_compose;

/* Takes the mesh (object space, triangles only: a mesh with spheres is an
 * error) and empties *mesh; *index gets its index. */
int scene_compose_add_mesh(scene_compose *c, accel_scene *mesh, uint32_t *index,
                           accel_error *err);
/* Places mesh `mesh` with transform m. Fails (nothing added) when m is not
 * finite or singular, when a transformed vertex overflows float, or when the
 * flattened scene would exceed the primitive limit; checked before anything
 * is allocated for it. Messages carry no location: callers prefix theirs. */
int scene_compose_add_instance(scene_compose *c, uint32_t mesh, const double m[12],
                               accel_error *err);
/* Builds the flattened scene into *out (live list, bounds, default camera)
 * and moves the description into out->instances; *c is left empty. */
int scene_compose_finish(scene_compose *c, const char *name, accel_scene *out, accel_error *err);
void scene_compose_free(scene_compose *c);

/* ---- transforms ---------------------------------------------------------- */

void scene_xform_identity(double m[12]);
/* m = t * m: t applied after m (the `.scene` order: left to right). */
void scene_xform_then(double m[12], const double t[12]);
void scene_xform_translate(double t[12], double x, double y, double z);
void scene_xform_scale(double t[12], double sx, double sy, double sz);
/* Right-handed rotation by `deg` degrees about the axis (ax, ay, az) through
 * the origin (Rodrigues' formula); multiples of 90 degrees are exact.
 * Returns nonzero for a zero or non-finite axis. */
int scene_xform_rotate(double t[12], double ax, double ay, double az, double deg);
/* Determinant of the linear part. */
double scene_xform_det(const double m[12]);
/* inv = m^-1. Returns nonzero (inv undefined) when m has a non-finite entry
 * or is singular: determinant zero, or below 2^-40 of the product of its
 * rows' lengths (so that a uniform scale by 1e-20 is fine and a matrix with
 * two nearly parallel rows is not). */
int scene_xform_invert(const double m[12], double inv[12]);

#ifdef __cplusplus
}
#endif

#endif
