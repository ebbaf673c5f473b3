/*
 * grid_packet_kernel.h - the `grid` kind's coherent packet walk (described
 * in grid_packet_trace.c): walk_slice, packet_walk and packet_batch, with
 * the cell visit on ids or on blocks (use_blocks, a constant of the copy).
 * A kernel body (C only), private to grid/: grid_packet_trace.c compiles
 * the copies on ids, the kernel unit k8_packet.c those on blocks, once per
 * ISA (core/isa.h), since they inline the shared block test.
 */
#ifndef GRID_GRID_PACKET_KERNEL_H
#define GRID_GRID_PACKET_KERNEL_H

#include "core/variant.h"
#include "grid_packet_walk.h"

#define P GRID_PACKET_SIZE

_Static_assert(P == 64, "the active-ray mask is one uint64_t");

/* Tests the primitives of slice k's cells [lo, hi] against the packet.
 * Returns 0 when an any-hit packet has no active ray left. */
static inline __attribute__((always_inline)) int
walk_slice(const grid_accel *g, grid_packet *pk, grid_packet_count *cn, accel_counters *c,
           uint32_t *mail, int k, const int lo[2], const int hi[2], const double hull[2][2],
           int naive, int spheres, int mailbox, int any_hit, int use_blocks)
{
    const grid_frame *f = &g->frame;
    const uint32_t *offsets = g->cells.offsets, *refs = g->cells.refs;
    const uint32_t st1 = f->stride[pk->axis[1]], st2 = f->stride[pk->axis[2]];
    /* cells=blocks: built for triangles with the watertight test only; a
     * constant of the copy (k8_packet.c compiles it, once per ISA). */
    const grid_cell_blocks *blocks = use_blocks ? &g->blocks : NULL;
    for (int j = lo[1]; j <= hi[1]; j++) {
        const uint32_t row = (uint32_t)k * f->stride[pk->axis[0]] + (uint32_t)j * st2;
        for (int i = lo[0]; i <= hi[0]; i++) {
            const uint32_t cell = row + (uint32_t)i * st1, r = offsets[cell];
            if (blocks ? !grid_packet_test_blocks(pk, cn, c, mail, blocks->blocks,
                                                  blocks->offsets[cell], offsets[cell + 1] - r,
                                                  g->store.prims.tri_count, hull, mailbox, any_hit)
                       : !grid_packet_test_list(&g->store.prims, pk, cn, c, mail, refs + r,
                                                offsets[cell + 1] - r, hull, naive, spheres,
                                                mailbox, any_hit))
                return 0;
        }
    }
    return 1;
}

static inline __attribute__((always_inline)) void
packet_walk(const grid_accel *g, grid_packet *pk, grid_packet_count *cn, accel_counters *c, int naive,
            int spheres, int mailbox, int any_hit, int use_blocks)
{
    const grid_frame *f = &g->frame;
    const int K = pk->axis[0], nk = f->res[K], M = GRID_MACRO;
    uint32_t mail[GRID_PACKET_MAIL];
    if (mailbox) memset(mail, 0xFF, sizeof mail); /* ACCEL_MISS: no primitive */
    uint32_t slices = 0;
    for (int k = pk->k_start; k >= 0 && k < nk;) {
        /* The slices left in this layer of macro cells, in walk order. */
        const int layer = k / M;
        int k_end = pk->kstep > 0 ? (layer + 1) * M - 1 : layer * M;
        k_end = k_end < nk ? k_end : nk - 1;
        int lo[2], hi[2];
        double hull[2][2];
        /* Tighter bounds once a quarter of the rays have stopped. */
        if (4 * __builtin_popcountll(pk->active) <= 3 * __builtin_popcountll(pk->bounded))
            grid_packet_bound(pk);
        if (k_end != k && (!grid_packet_span(f, pk, k, k_end, lo, hi, hull) ||
                           !grid_macro_any(g, K, pk->axis[1], pk->axis[2], layer, lo, hi))) {
            slices += (uint32_t)(pk->kstep * (k_end - k) + 1);
            if (ACCEL_STEP_BOUND_BROKEN(c, slices, nk)) return;
            if (!grid_packet_leave_slice(f, pk, cn, c, k_end)) return;
            k = k_end + pk->kstep;
            continue;
        }
        for (;; k += pk->kstep) {
            slices++;
            if (ACCEL_STEP_BOUND_BROKEN(c, slices, nk)) return;
            if (grid_packet_span(f, pk, k, k, lo, hi, hull) &&
                !walk_slice(g, pk, cn, c, mail, k, lo, hi, (const double(*)[2])hull, naive,
                            spheres, mailbox, any_hit, use_blocks))
                return;
            if (!grid_packet_leave_slice(f, pk, cn, c, k)) return;
            if (k == k_end) break;
        }
        k += pk->kstep;
    }
}

static inline __attribute__((always_inline)) void
packet_batch(const grid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
             size_t count, accel_counters *c, int naive, int spheres, int mailbox, int use_blocks)
{
    grid_packet pk; /* about 24 KB, aligned by its members */
    grid_packet_count cn;
    for (size_t base = 0; base < count; base += P) {
        const uint32_t n = (uint32_t)(count - base < P ? count - base : P);
        for (size_t i = base + P; i < base + 2 * P && i < count; i += 2)
            __builtin_prefetch(&rays[i]); /* the next packet: 2 rays per cache line */
        const int mode = grid_packet_setup(&g->frame, g->cells.ref_count, GRID_PACKET_MAX_CELLS, &pk, rays + base, n);
        if (mode == GRID_PACKET_SINGLE) {
            grid_packet_trace_single(g, grid_intersect, grid_occluded, rays + base,
                                     hits ? hits + base : NULL, occ ? occ + base : NULL, n, c,
                                     base);
            continue;
        }
        if (c) memset(&cn, 0, sizeof cn);
        if (mode == GRID_PACKET_WALK)
            packet_walk(g, &pk, &cn, c, naive, spheres, mailbox, occ != NULL, use_blocks);
        grid_packet_finish(&g->store, &pk, &cn, hits, occ, c, base, mode == GRID_PACKET_WALK);
    }
}

/* The blocks' tables (k8_packet.c): query 0 closest hit, 1 any hit; the
 * AVX2 copy and, where the build has it, the AVX-512 one. */
const accel_kernel_table *grid_k8_packet(int query);
const accel_kernel_table *grid_k8_packet_avx512(int query);

#undef P

#endif
