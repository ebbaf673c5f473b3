/*
 * prims.c - primitive bounds and centroids of a scene's primitives, and the
 * primitive store every kind builds over (see accel.h).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel.h"

box3 accel_prim_bounds(const accel_scene *s, uint32_t prim)
{
    box3 b = box3_empty();
    if (prim < s->tri_count) {
        const float *t = s->tris + 9 * (size_t)prim;
        b = box3_grow(b, v3_load(t));
        b = box3_grow(b, v3_load(t + 3));
        b = box3_grow(b, v3_load(t + 6));
    } else {
        const float *sp = s->spheres + 4 * (size_t)(prim - s->tri_count);
        vec3 r = v3(sp[3], sp[3], sp[3]);
        b.min = v3_sub(v3_load(sp), r);
        b.max = v3_add(v3_load(sp), r);
    }
    return b;
}

vec3 accel_prim_centroid(const accel_scene *s, uint32_t prim)
{
    return box3_center(accel_prim_bounds(s, prim));
}

