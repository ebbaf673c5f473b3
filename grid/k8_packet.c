/*
 * k8_packet.c - the `grid` kind's kernel unit for packets on blocks
 * (traverse=packet with cells=blocks, grid_packet_kernel.h), which inline
 * the shared block test (core/block_test.h, 8 lanes). Compiled twice like
 * bvh/wide/'s units (the Makefile's k<digit>_*.c rule): for AVX2 and, where
 * the build has ARCH512, for AVX-512 (entry suffixed _avx512, core/isa.h);
 * grid_packet_trace.c picks the grid's. Blocks hold triangles with the
 * watertight test, so the flags are 0 or the packet mailbox (ACCEL_V_OPT).
 */
#include "core/isa.h"
#include "grid_packet_kernel.h"

static inline __attribute__((always_inline)) void
packet_batch_blocks(const grid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
                    size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    (void)naive, (void)spheres;
    packet_batch(g, rays, hits, occ, count, c, 0, 0, mailbox, 1);
}

/* The copy the experiments time: the mailbox (index 4, the default). */
ACCEL_KERNEL_PAIR_SEL(grid_packet_blocks, packet_batch_blocks, (0, 0, 0, 0, 1, 0, 0, 0),
                      (0, 0, 0, 0, 1, 0, 0, 0))

const accel_kernel_table *ACCEL_ISA_UNIT(grid_k8_packet)(int query)
{
    return query ? &grid_packet_blocks_occ_table : &grid_packet_blocks_hit_table;
}
