/*
 * wide_trace8.c - the 8-wide BVH's kernel tables (wide_tables.h with
 * WIDE_NW 8), a translation unit apart from the 4-wide ones (wide_trace.c)
 * so that the two compile in parallel: each takes about half a minute of
 * forced inlining.
 */
#include "wide_node.h"

#define WIDE_NW 8
#include "wide_tables.h"

const accel_kernel_table *bvh_wide_kernels8(int row, int any_hit, int block8)
{
    return wide_tables[row][any_hit][block8];
}
