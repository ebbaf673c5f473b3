/*
 * k8_cells.c - the `grid` kind's kernel unit: the single-ray kernels on
 * blocks (cells=blocks, grid_kernel.h's GRID_BLOCK_KERNELS), which inline
 * the shared block test (core/block_test.h, 8 lanes), for each skipping
 * mode and query. Compiled twice like bvh/wide/'s units (the Makefile's
 * k<digit>_*.c rule): for AVX2 and, where the build has ARCH512, for
 * AVX-512, whose entry ends in _avx512 (core/isa.h, ACCEL_ISA_UNIT);
 * grid_trace.c picks the one of the grid's isa. The per-id kernels stay in
 * grid_trace*.c (one ISA: they test one primitive at a time).
 */
#include "core/isa.h"
#include "grid_kernel.h"

GRID_BLOCK_KERNELS(grid_blocks_none, GRID_SKIP_NONE)
GRID_BLOCK_KERNELS(grid_blocks_cloud, GRID_SKIP_CLOUD)
GRID_BLOCK_KERNELS(grid_blocks_macro, GRID_SKIP_MACRO)

const accel_kernel_table *ACCEL_ISA_UNIT(grid_k8_cells)(int skip, int query)
{
    static const accel_kernel_table *const tables[3][2] = {
        {&grid_blocks_none_hit_table, &grid_blocks_none_occ_table},
        {&grid_blocks_cloud_hit_table, &grid_blocks_cloud_occ_table},
        {&grid_blocks_macro_hit_table, &grid_blocks_macro_occ_table},
    };
    return tables[skip == GRID_SKIP_CLOUD ? 1 : skip == GRID_SKIP_MACRO ? 2 : 0][query != 0];
}
