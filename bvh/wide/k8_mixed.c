/*
 * k8_mixed.c - the 8-wide kernels of single rays on layout=mixed (wide.h:
 * nodes and leaf blocks in one pool, references counting 64-byte lines):
 * kernel.h's kernels with WIDE_MIXED set, a unit of its own (tables.h says
 * why), so that the default units' code stays as it is.
 */
#define WIDE_NW 8
#define WIDE_ROW WIDE_ROW_MIXED
#define WIDE_MIXED 1
#include "tables.h"

const accel_kernel_table *WIDE_UNIT(bvh_wide_k8_mixed)(int any_hit, int block8)
{
    return wide_row[any_hit][block8];
}
