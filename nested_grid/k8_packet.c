/*
 * k8_packet.c - the `nested_grid` kind's kernel unit for packets on blocks
 * (traverse=packet with cells=blocks, ngrid_packet_kernel.h), whose cell
 * visit inlines the shared block test (core/block_test.h, 8 lanes).
 * Compiled twice like bvh/wide/'s units (the Makefile's k<digit>_*.c rule):
 * for AVX2 and, where the build has ARCH512, for AVX-512 (entry suffixed
 * _avx512, core/isa.h); ngrid_packet.c picks the grid's. Blocks hold
 * triangles with the watertight test, so the flags are 0 or the packet
 * mailbox (ACCEL_V_OPT).
 */
#define NGRID_PACKET_BLOCKS 1
#include "core/isa.h"
#include "ngrid_packet_kernel.h"

static inline __attribute__((always_inline)) void
npacket_batch_blocks(const ngrid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
                     size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    (void)naive, (void)spheres;
    npacket_batch(g, rays, hits, occ, count, c, 0, 0, mailbox);
}

/* The copy the experiments time: the mailbox (index 4, the default). */
ACCEL_KERNEL_PAIR_SEL(npacket_blocks, npacket_batch_blocks, (0, 0, 0, 0, 1, 0, 0, 0),
                      (0, 0, 0, 0, 1, 0, 0, 0))

const accel_kernel_table *ACCEL_ISA_UNIT(ngrid_k8_packet)(int query)
{
    return query ? &npacket_blocks_occ_table : &npacket_blocks_hit_table;
}
