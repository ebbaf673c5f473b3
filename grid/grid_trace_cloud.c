/*
 * grid_trace_cloud.c - the `grid` kernels with skip=cloud (grid_skip.h), in
 * their own translation unit so that they do not share an inlining budget
 * with the plain walk's (see grid_kernel.h).
 */
#include "grid_kernel.h"

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): indices 0 and 6. */
GRID_KERNELS(grid_cloud, GRID_SKIP_CLOUD, (1, 0, 0, 0, 0, 0, 1, 0), (1, 0, 0, 0, 0, 0, 1, 0))

const accel_kernel_table *const grid_cloud_tables[2] = {&grid_cloud_hit_table,
                                                        &grid_cloud_occ_table};
