/*
 * grid_packet_walk.h - the pieces of the coherent grid traversal that every
 * slice walk shares: the regular grid's (grid_packet_trace.c) and the nested
 * grid's, whose levels are walked with the same packet (nested_grid/
 * ngrid_packet.c). A kernel body (C only): included by .c files, not part
 * of the interface a C++ program includes.
 *
 * Testing a primitive against the packet (the culls, the 4-ray filter and
 * the exact test of each remaining ray), or a cell's blocks (cells=blocks:
 * the same culls and filter per triangle, then the shared block test for
 * each ray a triangle of the block kept), retiring the rays that need
 * nothing past a slice, the per-ray counter shares, tracing a packet that
 * does not qualify with a single-ray kernel, and writing the answers. The
 * correctness argument of the walk is in grid_packet_trace.c's header.
 */
#ifndef GRID_GRID_PACKET_WALK_H
#define GRID_GRID_PACKET_WALK_H

#include <string.h>

#include "grid_blocks.h"
#include "grid_packet_filter.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Per-packet mailbox entries (power of two). */
#define GRID_PACKET_MAIL 256

/* Counted runs: packet totals so far, and each ray's share when it stops. */
typedef struct {
    uint64_t visits, empty, skips, evals;
    uint32_t r_visits[GRID_PACKET_SIZE], r_empty[GRID_PACKET_SIZE], r_skips[GRID_PACKET_SIZE],
        r_tests[GRID_PACKET_SIZE];
} grid_packet_count;

static inline void grid_packet_retire(grid_packet *pk, grid_packet_count *cn, int i,
                                      const accel_counters *c)
{
    pk->active &= ~((uint64_t)1 << i);
    if (c) {
        cn->r_visits[i] = (uint32_t)cn->visits;
        cn->r_empty[i] = (uint32_t)cn->empty;
        cn->r_skips[i] = (uint32_t)cn->skips;
    }
}

/* Tests primitive `prim` (a local id of store s) against the packet's
 * active rays. */
static inline __attribute__((always_inline)) void
grid_packet_test_prim(const accel_scene *s, grid_packet *pk, grid_packet_count *cn,
                      accel_counters *c, uint32_t prim, int naive, int spheres, int any_hit)
{
    uint64_t cand;
    if (spheres && prim >= s->tri_count) {
        const float *sph = s->spheres + 4 * (size_t)(prim - s->tri_count);
        if (grid_packet_sphere_outside(pk, sph)) return;
        cand = grid_packet_sphere_filter(pk, sph, &cn->evals);
    } else if (naive) {
        cand = pk->active; /* no error analysis of Moller-Trumbore to filter by */
    } else {
        const float *tri = s->tris + 9 * (size_t)prim;
        if (grid_packet_tri_outside(pk, tri)) return;
        grid_packet_tri t;
        grid_packet_tri_prepare(pk, tri, &t);
        if (grid_packet_tri_culled(pk, &t)) return;
        cand = grid_packet_tri_filter(pk, &t, &cn->evals);
    }
    for (; cand; cand &= cand - 1) {
        const int l = __builtin_ctzll(cand);
        if (c) cn->r_tests[l]++;
        if (!(pk->prepped >> l & 1)) {
            accel_prep_ray(&pk->rays[l], &pk->prep[l]); /* live: accepted */
            pk->prepped |= (uint64_t)1 << l;
        }
        if (!accel_prim_hit(s, prim, &pk->prep[l], &pk->t[l], &pk->u[l], &pk->v[l], naive, spheres))
            continue;
        pk->prim[l] = prim;
        if (any_hit)
            grid_packet_retire(pk, cn, l, c);
        else
            grid_packet_hit_end(pk, l);
    }
}

/* Tests the primitives ids[0..n) of a cell met in a slice whose rays lie
 * within hull, through the packet's mailbox. Returns 0 when an any-hit
 * packet has no active ray left. */
static inline __attribute__((always_inline)) int
grid_packet_test_list(const accel_scene *s, grid_packet *pk, grid_packet_count *cn,
                      accel_counters *c, uint32_t *mail, const uint32_t *ids, uint32_t n,
                      const double hull[2][2], int naive, int spheres, int mailbox, int any_hit)
{
    if (c) {
        cn->visits++;
        cn->empty += n == 0;
    }
    for (uint32_t r = 0; r < n; r++) {
        const uint32_t prim = ids[r];
        uint32_t *slot = &mail[prim & (GRID_PACKET_MAIL - 1)];
        if (mailbox && *slot == prim) {
            if (c) cn->skips++;
            continue;
        }
        /* Out of every ray's reach in this slice: left out of the mailbox,
         * so that a later slice looks again. */
        if (!naive && grid_packet_slice_outside(pk, s, prim, spheres, hull)) continue;
        if (mailbox) *slot = prim;
        grid_packet_test_prim(s, pk, cn, c, prim, naive, spheres, any_hit);
        if (any_hit && !pk->active) return 0;
    }
    return 1;
}

/*
 * The cell visit on blocks (cells=blocks, grid_blocks.h): the cell's n
 * triangles in blocks[first ..], 8 to a block. Per block, each real lane
 * goes through what grid_packet_test_list does to an id (the packet's
 * mailbox, the slice cull, which leaves a lane out of the mailbox, the
 * envelope and edge culls, the 4-ray filter), read from the block's own
 * rows; the rays some lane kept then get the shared block test
 * (core/block_test.h, 8 lanes), which keeps their nearest hit as the exact
 * test does. A ray kept by one lane is tested against all 8: a lane its
 * filter dropped is a miss or, with a block test's rounding, the same
 * answer (a hit counts whichever cell tests it: grid_packet_trace.c's
 * argument needs only that the lane the ray hits is tested, which the
 * filter's conservativeness gives). A lane in the mailbox was tested, or
 * shown out of reach, for every ray active then, as with ids. Counted
 * runs count a block's real lanes as tests, per ray tested. Triangles and
 * the watertight test only (the caller's choice). Returns 0 when an
 * any-hit packet has no active ray left.
 */
static inline __attribute__((always_inline)) int
grid_packet_test_blocks(grid_packet *pk, grid_packet_count *cn, accel_counters *c, uint32_t *mail,
                        const accel_block8 *blocks, uint32_t first, uint32_t n, uint32_t tri_count,
                        const double hull[2][2], int mailbox, int any_hit)
{
    if (c) {
        cn->visits++;
        cn->empty += n == 0;
    }
    for (uint32_t k = 0; k < n; k += 8) {
        const accel_block8 *blk = &blocks[first + k / 8];
        const int lanes = n - k < 8 ? (int)(n - k) : 8;
        uint64_t cand = 0;
        for (int lane = 0; lane < lanes; lane++) {
            const uint32_t prim = blk->id[lane];
            uint32_t *slot = &mail[prim & (GRID_PACKET_MAIL - 1)];
            if (mailbox && *slot == prim) {
                if (c) cn->skips++;
                continue;
            }
            float tri[9];
            lane_gather_8(blk, lane, tri);
            if (grid_packet_tri_slice_outside(pk, tri, hull)) continue;
            if (mailbox) *slot = prim;
            if (grid_packet_tri_outside(pk, tri)) continue;
            grid_packet_tri t;
            grid_packet_tri_prepare(pk, tri, &t);
            if (grid_packet_tri_culled(pk, &t)) continue;
            cand |= grid_packet_tri_filter(pk, &t, &cn->evals);
        }
        for (cand &= pk->active; cand; cand &= cand - 1) {
            const int l = __builtin_ctzll(cand);
            if (c) cn->r_tests[l] += (uint32_t)lanes;
            if (!(pk->prepped >> l & 1)) {
                accel_prep_ray(&pk->rays[l], &pk->prep[l]); /* live: accepted */
                pk->prepped |= (uint64_t)1 << l;
            }
            wide_leaf_ray_8 lr;
            leaf_setup_8(&lr, &pk->prep[l]);
            uint32_t id = ACCEL_MISS;
            if (!leaf_block_8(blk, &lr, &pk->prep[l], &pk->t[l], &pk->u[l], &pk->v[l], &id,
                              tri_count, 0, 0, any_hit))
                continue;
            if (any_hit) { /* the block test names no lane then: only "hit" counts */
                pk->prim[l] = blk->id[0];
                grid_packet_retire(pk, cn, l, c);
            } else {
                pk->prim[l] = id;
                grid_packet_hit_end(pk, l);
            }
        }
        if (any_hit && !pk->active) return 0;
    }
    return 1;
}

/* Retires the rays that need nothing past slice k of frame f (the walk's
 * frame on K); 0 when none is left. */
static inline int grid_packet_leave_slice(const grid_frame *f, grid_packet *pk,
                                          grid_packet_count *cn, const accel_counters *c, int k)
{
    const double w_out = pk->kstep * (double)f->planes[pk->axis[0]][pk->kstep > 0 ? k + 1 : k];
    if (w_out >= pk->w_next)
        for (uint64_t m = grid_packet_leaving(pk, w_out); m; m &= m - 1)
            grid_packet_retire(pk, cn, __builtin_ctzll(m), c);
    return pk->active != 0;
}

/* Packets that do not qualify: a single-ray kernel (`hit` or `occ`, the
 * kind's entry points), with the per-ray counter arrays shifted to the
 * packet. */
typedef void (*grid_packet_hit_fn)(const void *, const accel_ray *, accel_hit *, size_t,
                                   accel_counters *);
typedef void (*grid_packet_occ_fn)(const void *, const accel_ray *, uint8_t *, size_t,
                                   accel_counters *);

static inline void grid_packet_trace_single(const void *accel, grid_packet_hit_fn hit,
                                            grid_packet_occ_fn occ_fn, const accel_ray *rays,
                                            accel_hit *hits, uint8_t *occ, size_t n,
                                            accel_counters *c, size_t base)
{
    accel_counters sub, *cs = NULL;
    if (c) {
        memset(&sub, 0, sizeof sub);
        sub.ray_steps = c->ray_steps ? c->ray_steps + base : NULL;
        sub.ray_prims = c->ray_prims ? c->ray_prims + base : NULL;
        cs = &sub;
    }
    if (occ)
        occ_fn(accel, rays, occ, n, cs);
    else
        hit(accel, rays, hits, n, cs);
    if (c) accel_counters_add(c, &sub);
}

/* The packet's answers (local ids mapped back through the store), and in
 * counted runs each ray's share of the counters. */
static inline void grid_packet_finish(const accel_prim_store *store, grid_packet *pk,
                                      grid_packet_count *cn, accel_hit *hits, uint8_t *occ,
                                      accel_counters *c, size_t base, int walked)
{
    for (uint32_t i = 0; i < pk->n; i++) {
        const uint32_t prim = pk->prim[i];
        if (occ) {
            occ[base + i] = prim != ACCEL_MISS;
        } else if (prim != ACCEL_MISS) {
            const accel_hit h = {pk->t[i], store->scene_id[prim], pk->u[i], pk->v[i]};
            hits[base + i] = h;
        } else {
            hits[base + i] = accel_hit_miss();
        }
    }
    if (!c) return;
    for (uint64_t m = pk->active; walked && m; m &= m - 1)
        grid_packet_retire(pk, cn, __builtin_ctzll(m), c);
    c->rays += pk->n;
    c->box_tests += pk->boxes;
    c->packet_box_tests += cn->evals;
    for (uint32_t i = 0; i < pk->n; i++) {
        const int on = walked && (pk->live >> i & 1);
        const uint32_t steps = on ? cn->r_visits[i] : 0, tests = on ? cn->r_tests[i] : 0;
        c->steps += steps;
        c->empty_steps += on ? cn->r_empty[i] : 0;
        c->mailbox_skips += on ? cn->r_skips[i] : 0;
        c->prim_tests += tests;
        if (c->ray_steps) c->ray_steps[base + i] = steps;
        if (c->ray_prims) c->ray_prims[base + i] = tests;
    }
}

#ifdef __cplusplus
}
#endif

#endif
