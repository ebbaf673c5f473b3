/*
 * grid_trace_macro.c - the `grid` kernels with skip=macro (grid_skip.h), in
 * their own translation unit so that they do not share an inlining budget
 * with the plain walk's (see grid_kernel.h).
 */
#include "grid_kernel.h"

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): indices 0 and 6, and closest hits with the naive test (5). */
GRID_KERNELS(grid_macro, GRID_SKIP_MACRO, (1, 0, 0, 0, 0, 1, 1, 0), (1, 0, 0, 0, 0, 0, 1, 0))

const accel_kernel_table *const grid_macro_tables[2] = {&grid_macro_hit_table,
                                                        &grid_macro_occ_table};
