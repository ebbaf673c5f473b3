/*
 * k8_anyord.c - the 8-wide any-hit kernel of any_order=octant|area|leaf
 * (wide.h): the octant push for every count of hit children, in the
 * ray's octant order or the node's stored area or leaf-first order; a unit
 * of its own (tables.h says why).
 */
#define WIDE_NW 8
#define WIDE_ROW WIDE_ROW_ANY
#include "tables.h"

const accel_kernel_table *WIDE_UNIT(bvh_wide_k8_anyord)(int any_hit, int block8)
{
    (void)any_hit; /* any-hit queries only (trace.c) */
    return wide_row[1][block8];
}
