/*
 * k4_branchy.c - the 4-wide kernels of single rays with order=branchy: tables.h for one
 * width and row, a unit of its own (tables.h says why).
 */
#define WIDE_NW 4
#define WIDE_ROW WIDE_ROW_BRANCHY
#include "tables.h"

const accel_kernel_table *WIDE_UNIT(bvh_wide_k4_branchy)(int any_hit, int block8)
{
    return wide_row[any_hit][block8];
}
