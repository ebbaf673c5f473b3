/*
 * ngrid_packet.c - coherent grid traversal of the nested grid
 * (`nested_grid:traverse=packet`, both layouts), the packet walk of
 * grid/grid_packet_trace.c (Wald, Ize, Kensler, Knoll and Parker, SIGGRAPH 2006)
 * carried into the levels.
 *
 * The packet (grid_packet_setup over the top grid) walks the top grid slice
 * by slice along its axis K. In each top slice, the cells of the slice's
 * range are visited: a cell holding a list has it tested against the packet
 * as in the regular grid (mailbox, slice cull, 4-ray filter, exact tests;
 * with cells=blocks the list's blocks, grid_packet_test_blocks, the
 * block test for the rays a triangle of a block kept);
 * a cell holding a sub-grid has the sub-grid walked slice by slice along the
 * same axis and direction (its slices subdivide the top slice: its box is
 * the top cell's, bounded by the top grid's own planes), each sub-slice with
 * its own, narrower range of sub-cells, recursively at every level. Rays are
 * retired only after a whole top slice, with the regular grid's rule on the
 * top slice's exit plane. A sub-slice is skipped when its entry plane lies
 * beyond the end of every active ray (w_end: nearest hit so far, box exit or
 * t_far, each widened by its rounding). A packet too wide for a sub-grid's
 * cells, or over its visit budget, gives up (below): its active rays are
 * traced again from the start by the single-ray walk, whose answers replace
 * theirs; retired rays keep theirs, which are final.
 *
 * Why the answer is the single-ray walk's and the reference's: the argument
 * of grid_packet_trace.c, level by level. Let the ray's nearest accepted hit p
 * (on primitive q) lie in top slice k, top cell c and, if c holds a
 * sub-grid, in its sub-slice k' and sub-cell c' (and so on down). The ray is
 * active in top slice k (it is retired only after a top slice, by a hit no
 * farther than p or an end beyond p). The range of top slice k bounds every
 * point of every active ray in the slice, so c is visited; the range of
 * sub-slice k' bounds every point of those rays in the sub-slice, so c' is
 * visited; and k' is not skipped, since its entry plane lies at or before p,
 * which lies at or before the ray's w_end. q belongs to c' (conservative
 * membership at every level, ngrid_impl.h's padding), and q's box holds p,
 * so the slice cull keeps q: q is tested against the ray unless the mailbox
 * holds it, and then it was tested (or shown out of reach) for every ray
 * active at the time, this one among them. The pads of the ranges are the
 * top grid's (1/1024 of a top cell plus the rounding bounds), wider than any
 * level's own. Every level's cells are visited with the packet's one
 * mailbox, as the single-ray walk shares its mailbox across levels.
 *
 * Counters (counted runs): steps = cells visited at any level (a top cell
 * holding a sub-grid included, as in the single-ray walk), per ray active at
 * the visit; prim_tests, mailbox_skips and packet_box_tests as in
 * grid_packet_trace.c; level_steps are not split by level in packet mode. The
 * step bound is the top grid's slice count per packet.
 */
#define NGRID_PACKET_BLOCKS 0 /* the walk on ids; k8_packet.c's is on blocks */
#include "core/coherence.h"
#include "core/isa.h"
#include "ngrid_packet_kernel.h"

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): the default on triangles (4) and spheres (6), and closest hits
 * with the naive test (5). */
ACCEL_KERNEL_PAIR_SEL(npacket, npacket_batch, (0, 0, 0, 0, 1, 1, 1, 0), (0, 0, 0, 0, 1, 0, 1, 0))

/* The packet table of g: with cells=blocks the kernel unit's (k8_packet.c)
 * of g's isa. */
static const accel_kernel_table *npacket_table(const ngrid_accel *g, int query)
{
    if (g->blocks.first) {
#ifdef GRIDBVH_AVX512
        if (g->isa == ACCEL_ISA_AVX512) return ngrid_k8_packet_avx512(query);
#endif
        return ngrid_k8_packet(query);
    }
    return query ? &npacket_occ_table : &npacket_hit_table;
}

static void packets_hit(const void *a, const accel_ray *r, accel_hit *h, size_t n, accel_counters *c)
{
    accel_run_kernel(npacket_table(a, 0), a, r, h, n, c, ngrid_packet_flags(a));
}

static void packets_occ(const void *a, const accel_ray *r, uint8_t *o, size_t n, accel_counters *c)
{
    accel_run_kernel(npacket_table(a, 1), a, r, o, n, c, ngrid_packet_flags(a));
}

/* Packets in any ray order (core/coherence.h, ACCEL_COHERENT_ENTRIES's
 * entries with the table chosen per grid); incoherent packets fall back to
 * the single-ray nested grid in npacket_batch, on the walk's criterion. */
void ngrid_packet_intersect(const ngrid_accel *g, const accel_ray *rays, accel_hit *hits,
                            size_t count, accel_counters *c)
{
    accel_coherent_intersect(g, rays, hits, count, c, packets_hit, (accel_hit_batch_fn)NULL);
}

void ngrid_packet_occluded(const ngrid_accel *g, const accel_ray *rays, uint8_t *occ,
                           size_t count, accel_counters *c)
{
    accel_coherent_occluded(g, rays, occ, count, c, packets_occ, (accel_occ_batch_fn)NULL);
}
