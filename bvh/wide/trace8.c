/*
 * trace8.c - the 8-wide BVH's kernel tables (tables.h with
 * WIDE_NW 8), a translation unit apart from the 4-wide ones (trace4.c)
 * so that the two compile in parallel: each takes about half a minute of
 * forced inlining.
 */
#include "node.h"

#define WIDE_NW 8
#include "tables.h"

const accel_kernel_table *bvh_wide_kernels8(int row, int any_hit, int block8)
{
    return wide_tables[row][any_hit][block8];
}
