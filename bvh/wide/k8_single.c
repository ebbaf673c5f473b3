/*
 * k8_single.c - the 8-wide kernels of single rays (order=octant and order=dist): tables.h for one
 * width and row, a unit of its own (tables.h says why).
 */
#define WIDE_NW 8
#define WIDE_ROW WIDE_ROW_SINGLE
#include "tables.h"

const accel_kernel_table *WIDE_UNIT(bvh_wide_k8_single)(int any_hit, int block8)
{
    return wide_row[any_hit][block8];
}
