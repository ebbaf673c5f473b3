/*
 * grid_packet_trace.c - coherent grid traversal of the `grid` kind
 * (traverse=packet), after Wald, Ize, Kensler, Knoll and Parker, "Ray
 * Tracing Animated Scenes using Coherent Grid Traversal", SIGGRAPH 2006.
 *
 * A packet is up to 64 consecutive rays of the batch (the primary ray sets
 * emit 8x8 screen tiles in that order). When every live ray's direction has
 * the same sign on the packet's dominant axis K (the largest component of
 * the mean direction) the packet walks the grid slice by slice along K
 * (grid_packet_setup.c prepares it; else the single-ray kernel of
 * grid_trace.c traces it, as it does packets too incoherent to pay):
 *   1. Range. Every ray is the line u(z) = u0 + s (z - z0) on the other two
 *      axes a1, a2 (s = d_u / d_K, z0 the K coordinate of the packet's
 *      reference point: a common origin or the point shadow rays converge
 *      on). The cells a slice can touch are bounded in double, by interval
 *      arithmetic over the packet (u0 and s in intervals) when the rays
 *      share their origin, else by the hull of each ray's own segment in the
 *      slice; widened by a bound on the rounding and 1/1024 of a cell.
 *   2. Empty space. A layer of GRID_MACRO slices whose range covers only
 *      empty macro cells (blocks of GRID_MACRO^3 cells) is skipped whole.
 *   3. Tests. Each primitive of the range's cells, unless the per-packet
 *      mailbox holds it: dropped for this slice when its box misses the
 *      slice's range (then not entered in the mailbox: a later slice looks
 *      again); otherwise entered, and dropped for the packet when it lies
 *      beyond the envelope of the packet's lines or an interval bound of
 *      the edge products puts it outside every line; else the 4-ray AVX2
 *      filter in double keeps the rays that may hit it, and each of those
 *      gets the exact test accel_prim_hit (core/prim.h), keeping the
 *      nearest hit (any hit: the ray stops at its first). With
 *      cells=blocks the cell's triangles come 8 to a block: the same
 *      mailbox, culls and filter per triangle, then each ray some
 *      triangle of the block kept gets the shared block test on the
 *      whole block (grid_packet_test_blocks, grid_packet_walk.h).
 *   4. Stop. After a slice a ray stops once its nearest hit lies at or
 *      before the plane where it leaves the slice, or its box exit or t_far
 *      does (all three widened by their rounding); the packet ends when no
 *      ray is active or the slices run out.
 *
 * Why the result is the single-ray grid's and the reference's. Let the
 * exact test accept primitive q for a ray at t, the nearest such t. The
 * point p of the real ray at t lies on q (up to the exact test's own
 * rounding, far below the 1/1024-cell membership padding) inside the grid
 * box, in some slice k and cell c; q belongs to c (conservative membership,
 * grid_core.h), so c's macro cell is not empty. The ray is still active in
 * slice k: it stops earlier only with a hit no farther than p, or beyond its
 * box exit or t_far, which lie beyond p. p lies within slice k's range
 * (step 1 bounds every point of every active ray in the slice), so slice k
 * is not skipped, c is visited, and q's box, which holds p, meets the
 * range. So q is tested against the ray in slice k, unless the mailbox
 * holds it: it then was tested, or shown out of reach of every line, for
 * every ray active at that time, the ray among them (rays never become
 * active again). The filters and culls only drop pairs the exact test would
 * reject (below). Hence the ray ends with the nearest hit; between
 * primitives hit at equal t another one may win, as with any other test
 * order (the suites accept the same t).
 *
 * The filters (triangles). With R the packet's reference point, O' = O-R,
 * M = O' x D, A' = A-R, etc., the triple product D.((A-O)x(B-O)) of edge AB
 * is S_AB = D.(A'xB') + M.(B-A) (Pluecker form; M = 0 when every ray
 * starts at R). The exact test's edge functions U, V, W are these three
 * triple products divided by the ray's dominant component (a factor common
 * to the three), and it accepts only when they have no strictly mixed
 * signs: in its float path because its error filter (ACCEL_EDGE_FILTER)
 * proves the signs, in its double path with U, V, W within
 * 20 u |D|_1 |A-O|_1 |B-O|_1 of the real values (u = 2^-53; the shear
 * factors are at most 1). Our S in double is within about
 * 30 u |D|_1 (Rt + |O'|_1)^2 of the real value (Rt: the largest 1-norm of
 * A', B', C'). Both are below E = 2^-40 |D|_1 (Rt + |O'|_1)^2 (2^-40 =
 * 8192 u), so a lane with some S < -E and another S > E is a pair the
 * exact test rejects: the filter is conservative. The edge cull bounds S
 * over the packet's boxes of D and M (interval products, rounding below the
 * same margin) against the largest E. The envelope and slice culls compare
 * coordinates, with margins over the rounding of u0, s and their products.
 * Spheres: the exact test accepts only when the real squared distance of
 * the centre to the line is at most r^2 + 64 u (r^2 + |O-C|^2); the filter
 * drops a lane when |(C-O) x D|^2 > |D|^2 (r^2 + 2^-38 (r + |C'|_1 +
 * |O'|_1)^2), and the culls widen the sphere's box accordingly. With
 * tri=naive (no error bound to rely on) triangles get no cull or filter.
 *
 * Counters (counted runs): steps / empty_steps = cells the packet visits,
 * counted once for every ray active at the visit (per ray, as the bvh's
 * packet kernel counts node visits; ray_steps likewise); prim_tests = exact
 * tests; mailbox_skips = references skipped, per active ray; box_tests = 1
 * per ray (the grid box); packet_box_tests = 4-ray filter evaluations.
 * Packets traced by the single-ray kernel count as in grid_trace.c. The
 * step bound is res[K] slices per packet (ACCEL_STEP_BOUND_BROKEN).
 */
#include "core/coherence.h"
#include "core/isa.h"
#include "grid_packet_kernel.h"

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): the mailbox on triangles (4) and spheres (6), and closest hits
 * with the naive test (5). The copies on blocks are k8_packet.c's. */
static inline __attribute__((always_inline)) void
packet_batch_ids(const grid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
                 size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    packet_batch(g, rays, hits, occ, count, c, naive, spheres, mailbox, 0);
}
ACCEL_KERNEL_PAIR_SEL(grid_packet, packet_batch_ids, (0, 0, 0, 0, 1, 1, 1, 0), (0, 0, 0, 0, 1, 0, 1, 0))

/* The packet table of g: with cells=blocks the kernel unit's of g's isa. */
static const accel_kernel_table *packet_table(const grid_accel *g, int query)
{
    if (g->blocks.offsets) {
#ifdef GRIDBVH_AVX512
        if (g->isa == ACCEL_ISA_AVX512) return grid_k8_packet_avx512(query);
#endif
        return grid_k8_packet(query);
    }
    return query ? &grid_packet_occ_table : &grid_packet_hit_table;
}

static void packets_hit(const void *a, const accel_ray *r, accel_hit *h, size_t n, accel_counters *c)
{
    accel_run_kernel(packet_table(a, 0), a, r, h, n, c, grid_packet_variant_flags(a));
}

static void packets_occ(const void *a, const accel_ray *r, uint8_t *o, size_t n, accel_counters *c)
{
    accel_run_kernel(packet_table(a, 1), a, r, o, n, c, grid_packet_variant_flags(a));
}

/* Packets in any ray order (core/coherence.h, ACCEL_COHERENT_ENTRIES's
 * entries with the table chosen per grid); incoherent packets fall back to
 * the single-ray grid in packet_batch, on the walk's criterion. */
void grid_packet_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                           size_t count, accel_counters *c)
{
    accel_coherent_intersect(accel, rays, hits, count, c, packets_hit, (accel_hit_batch_fn)NULL);
}

void grid_packet_occluded(const void *accel, const accel_ray *rays, uint8_t *occ, size_t count,
                          accel_counters *c)
{
    accel_coherent_occluded(accel, rays, occ, count, c, packets_occ, (accel_occ_batch_fn)NULL);
}
