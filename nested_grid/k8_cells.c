/*
 * k8_cells.c - the `nested_grid` kind's kernel unit: the single-ray walk
 * on leaf lists as blocks (cells=blocks, ngrid_kernel.h), which inlines the
 * shared block test (core/block_test.h, 8 lanes). Compiled twice like
 * bvh/wide/'s units (the Makefile's k<digit>_*.c rule): for AVX2 and, where
 * the build has ARCH512, for AVX-512 (entry suffixed _avx512, core/isa.h);
 * ngrid_trace.c picks the grid's. Blocks hold triangles with the watertight
 * test and no mailbox, so the flags are always 0 (the timed copy 0 and the
 * counted one).
 */
#include "core/isa.h"
#include "ngrid_kernel.h"

static inline __attribute__((always_inline)) void
ngrid_kernel_blocks(const ngrid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
                    size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    (void)naive, (void)spheres, (void)mailbox;
    ngrid_kernel(g, rays, hits, occ, count, c, 0, 0, 0, 1);
}

ACCEL_KERNEL_PAIR_SEL(ngrid_blocks, ngrid_kernel_blocks, (1, 0, 0, 0, 0, 0, 0, 0),
                      (1, 0, 0, 0, 0, 0, 0, 0))

const accel_kernel_table *ACCEL_ISA_UNIT(ngrid_k8_cells)(int query)
{
    return query ? &ngrid_blocks_occ_table : &ngrid_blocks_hit_table;
}
