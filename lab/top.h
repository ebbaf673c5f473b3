/*
 * top.h - the optional step 7 (LAB.md): the top level of a two-level scene
 * written by you, as the lecture's step 3 means it. The check builds your
 * kind once per mesh, in the mesh's object space, and hands you this; your
 * lab_top_...() function in student.c traces one world ray through it.
 */
#ifndef LAB_TOP_H
#define LAB_TOP_H

#include "accel.h"

typedef struct {
    const accel_kind *kind;         /* your kind */
    void *const *mesh_accel;        /* your kind built over each mesh (object space) */
    const accel_instance *instances; /* mesh, base id, xform and inverse (world -> object) */
    uint32_t instance_count;
} lab_top;

/* Traces one world ray through every instance; *hit gets the nearest hit,
 * its t in the world ray's units and its id in the flattened scene (the
 * instance's base + the mesh's local id), or accel_hit_miss(). */
typedef void (*lab_top_fn)(const lab_top *top, const accel_ray *ray, accel_hit *hit);

#endif
