/*
 * grid_packet.c - coherent grid traversal of the `grid` kind
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
 *      nearest hit (any hit: the ray stops at its first).
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
#include <string.h>

#include "grid_packet_filter.h"

#define P GRID_PACKET_SIZE
#define GRID_PACKET_MAIL 256 /* per-packet mailbox entries (power of two) */

_Static_assert(P == 64, "the active-ray mask is one uint64_t");

/* Counted runs: packet totals so far, and each ray's share when it stops. */
typedef struct {
    uint64_t visits, empty, skips, evals;
    uint32_t r_visits[P], r_empty[P], r_skips[P], r_tests[P];
} packet_count;

static inline void retire(grid_packet *pk, packet_count *cn, int i, const accel_counters *c)
{
    pk->active &= ~((uint64_t)1 << i);
    if (c) {
        cn->r_visits[i] = (uint32_t)cn->visits;
        cn->r_empty[i] = (uint32_t)cn->empty;
        cn->r_skips[i] = (uint32_t)cn->skips;
    }
}

/* Tests primitive `prim` against the packet's active rays. */
static inline __attribute__((always_inline)) void
test_prim(const accel_scene *s, grid_packet *pk, packet_count *cn, accel_counters *c,
          uint32_t prim, int naive, int spheres, int any_hit)
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
            retire(pk, cn, l, c);
        else
            grid_packet_hit_end(pk, l);
    }
}

/* Tests the primitives of slice k's cells [lo, hi] against the packet.
 * Returns 0 when an any-hit packet has no active ray left. */
static inline __attribute__((always_inline)) int
walk_slice(const grid_accel *g, grid_packet *pk, packet_count *cn, accel_counters *c,
           uint32_t *mail, int k, const int lo[2], const int hi[2], const double hull[2][2],
           int naive, int spheres, int mailbox, int any_hit)
{
    const grid_frame *f = &g->frame;
    const accel_scene *s = &g->store.prims;
    const uint32_t *offsets = g->cells.offsets, *refs = g->cells.refs;
    const uint32_t st1 = f->stride[pk->axis[1]], st2 = f->stride[pk->axis[2]];
    for (int j = lo[1]; j <= hi[1]; j++) {
        const uint32_t row = (uint32_t)k * f->stride[pk->axis[0]] + (uint32_t)j * st2;
        for (int i = lo[0]; i <= hi[0]; i++) {
            const uint32_t cell = row + (uint32_t)i * st1;
            uint32_t r = offsets[cell];
            const uint32_t end = offsets[cell + 1];
            if (c) {
                cn->visits++;
                cn->empty += r == end;
            }
            for (; r < end; r++) {
                const uint32_t prim = refs[r];
                uint32_t *slot = &mail[prim & (GRID_PACKET_MAIL - 1)];
                if (mailbox && *slot == prim) {
                    if (c) cn->skips++;
                    continue;
                }
                /* Out of every ray's reach in this slice: left out of the
                 * mailbox, so that a later slice looks again. */
                if (!naive && grid_packet_slice_outside(pk, s, prim, spheres, hull)) continue;
                if (mailbox) *slot = prim;
                test_prim(s, pk, cn, c, prim, naive, spheres, any_hit);
                if (any_hit && !pk->active) return 0;
            }
        }
    }
    return 1;
}

/* Retires the rays that need nothing past slice k; 0 when none is left. */
static inline int leave_slice(const grid_frame *f, grid_packet *pk, packet_count *cn,
                              const accel_counters *c, int k)
{
    const double w_out = pk->kstep * (double)f->planes[pk->axis[0]][pk->kstep > 0 ? k + 1 : k];
    if (w_out >= pk->w_next)
        for (uint64_t m = grid_packet_leaving(pk, w_out); m; m &= m - 1)
            retire(pk, cn, __builtin_ctzll(m), c);
    return pk->active != 0;
}

static inline __attribute__((always_inline)) void
packet_walk(const grid_accel *g, grid_packet *pk, packet_count *cn, accel_counters *c, int naive,
            int spheres, int mailbox, int any_hit)
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
            if (!leave_slice(f, pk, cn, c, k_end)) return;
            k = k_end + pk->kstep;
            continue;
        }
        for (;; k += pk->kstep) {
            slices++;
            if (ACCEL_STEP_BOUND_BROKEN(c, slices, nk)) return;
            if (grid_packet_span(f, pk, k, k, lo, hi, hull) &&
                !walk_slice(g, pk, cn, c, mail, k, lo, hi, hull, naive, spheres, mailbox, any_hit))
                return;
            if (!leave_slice(f, pk, cn, c, k)) return;
            if (k == k_end) break;
        }
        k += pk->kstep;
    }
}

/* Packets that do not qualify: the single-ray kernel, with the per-ray
 * counter arrays shifted to the packet. */
static void trace_single(const grid_accel *g, const accel_ray *rays, accel_hit *hits,
                         uint8_t *occ, size_t n, accel_counters *c, size_t base)
{
    accel_counters sub, *cs = NULL;
    if (c) {
        memset(&sub, 0, sizeof sub);
        sub.ray_steps = c->ray_steps ? c->ray_steps + base : NULL;
        sub.ray_prims = c->ray_prims ? c->ray_prims + base : NULL;
        cs = &sub;
    }
    if (occ)
        grid_occluded(g, rays, occ, n, cs);
    else
        grid_intersect(g, rays, hits, n, cs);
    if (c) accel_counters_add(c, &sub);
}

static void count_packet(const grid_packet *pk, packet_count *cn, accel_counters *c, size_t base,
                         int walked)
{
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

static inline __attribute__((always_inline)) void
packet_batch(const grid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
             size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    grid_packet pk; /* about 24 KB, aligned by its members */
    packet_count cn;
    for (size_t base = 0; base < count; base += P) {
        const uint32_t n = (uint32_t)(count - base < P ? count - base : P);
        for (size_t i = base + P; i < base + 2 * P && i < count; i += 2)
            __builtin_prefetch(&rays[i]); /* the next packet: 2 rays per cache line */
        const int mode = grid_packet_setup(g, &pk, rays + base, n);
        if (mode == GRID_PACKET_SINGLE) {
            trace_single(g, rays + base, hits ? hits + base : NULL, occ ? occ + base : NULL, n, c,
                         base);
            continue;
        }
        if (c) memset(&cn, 0, sizeof cn);
        if (mode == GRID_PACKET_WALK)
            packet_walk(g, &pk, &cn, c, naive, spheres, mailbox, occ != NULL);
        for (uint32_t i = 0; i < n; i++) {
            const uint32_t prim = pk.prim[i];
            if (occ) {
                occ[base + i] = prim != ACCEL_MISS;
            } else if (prim != ACCEL_MISS) {
                const accel_hit h = {pk.t[i], g->store.scene_id[prim], pk.u[i], pk.v[i]};
                hits[base + i] = h;
            } else {
                hits[base + i] = accel_hit_miss();
            }
        }
        if (!c) continue;
        for (uint64_t m = pk.active; mode == GRID_PACKET_WALK && m; m &= m - 1)
            retire(&pk, &cn, __builtin_ctzll(m), c);
        count_packet(&pk, &cn, c, base, mode == GRID_PACKET_WALK);
    }
}

ACCEL_KERNEL_PAIR(grid_packet, packet_batch)

void grid_packet_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                           size_t count, accel_counters *counters)
{
    accel_run_kernel(&grid_packet_hit_table, accel, rays, hits, count, counters,
                     grid_variant_flags(accel));
}

void grid_packet_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded,
                          size_t count, accel_counters *counters)
{
    accel_run_kernel(&grid_packet_occ_table, accel, rays, occluded, count, counters,
                     grid_variant_flags(accel));
}
