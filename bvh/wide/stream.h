/*
 * stream.h - ray streams over a wide BVH (traverse=stream with width=4|8):
 * the breadth-first mode for incoherent rays (diffuse and shadow rays as
 * they come, in any order).
 * A kernel body (C only): included by the .c files of its folder, not part
 * of the interface a C++ program includes.
 *
 * A template: tables.h includes it once per (WIDE_NW, WIDE_LB) pair after
 * kernel.h for the same pair, whose single-ray pieces it runs (the slab
 * test, the leaf visit, walk_oct). It defines wide_sclosest_<NW>_<LB> and
 * wide_sany_<NW>_<LB>.
 *
 * The stream walks the tree once for many rays, so that a node or a leaf
 * fetched once serves every ray still active in it (Barringer and
 * Akenine-Moller, "Dynamic Ray Stream Traversal", SIGGRAPH 2014;
 * Fuetterling et al., "Efficient Ray Tracing Kernels for Modern CPU
 * Architectures", JCGT 4(4), 2015; Embree's rtcIntersect1M):
 *   1. the batch's rays are grouped by the octant of their direction
 *      (a counting sort of indices; the rays stay where they are) and each
 *      octant's rays are cut into streams of w->stream rays (stream=);
 *   2. a stream is a stack of entries, each a node or leaf with the list
 *      of the stream's rays that hit its box (ray index and entry
 *      distance), the lists kept on one buffer in stack order;
 *   3. at a popped entry, the rays whose box entry lies beyond their
 *      closest hit found since (box3_entry_before, the single-ray pop
 *      test) or that are occluded leave the list;
 *   4. at a node, each remaining ray meets the W child boxes with the
 *      single-ray kernel's W-lane slab test (kernel.h's slab_rows, the same
 *      operations), and is appended to the list of each child it hits
 *      (branch-free: every lane written, the counts advanced by the hit
 *      bits); the children with a list are pushed farthest first in the
 *      node's order for the stream's octant (perm), so the nearest is
 *      popped next;
 *   5. at a leaf, each ray runs the single-ray leaf visit (every block of
 *      the leaf, core/block_test.h) on its own running t; an any-hit ray
 *      that hits is occluded and leaves the stream (its t becomes -inf,
 *      which no box test and no pop test passes);
 *   6. a node entry holding at most w->hybrid rays (hybrid=; 0: never), or
 *      whose children's lists might not fit the buffer, is handed to the
 *      rays one by one: each walks the subtree alone (walk_oct with the
 *      branchy push: the octant order for any number of hit children).
 * Each ray's visits are therefore those of the single-ray kernel with
 * order=branchy, in the same order: every ray of a stream shares its
 * octant, a ray is in an entry exactly when its own slab test accepted
 * the box, its entries are popped depth first in its octant's order, and
 * the pop test is the single kernel's (the child a single ray would enter
 * directly carries entry distance -inf, so that it passes as the direct
 * entry does). So every ray's answer is that kernel's bit for bit, with
 * the same steps, box tests and primitive tests, whatever the other rays
 * of its batch, the stream size or hybrid= (tests/test_bvh_wide_stream.c
 * holds it to that; width 4's order=octant is the same order). Against
 * width 8's default order=octant, which enters the nearer of exactly two
 * hit children by entry distance, the answers differ only where the
 * visit order decides a near-tie (FORMATS.md's agreement; 1 ray of
 * 49152 bunny primaries at 256x192, 0 diffuse and shadow).
 * Rays with t_near < 0 (whose far padding is not folded) go through that
 * single-ray kernel whole, and so does a batch whose buffers cannot be
 * allocated.
 *
 * Counters: per ray as the single kernel counts; packet_steps counts the
 * entries fetched once for the whole stream (rays served per fetch =
 * steps / packet_steps, less the rays walked alone).
 */
#ifndef WIDE_NW
#define WIDE_NW 4
#endif
#ifndef WIDE_LB /* alone: the pieces for width 4 (or WIDE_NW), blocks of 4 */
#include "kernel.h"
#endif
#include <stdlib.h>

#include "node.h"
#include "core/simd.h"

#ifndef BVH_WIDE_STREAM_TYPES
#define BVH_WIDE_STREAM_TYPES
/* One stream ray as the node test reads it: kernel.h's node_ray scalars
 * (the far reciprocals with the padding folded in) and its running t; one
 * cache line (the buffers are 64-byte aligned). */
typedef struct {
    float ox, oy, oz, ix, iy, iz, fix, fiy, fiz, tn;
    float t; /* the closest hit so far; -inf once occluded (any hit) */
    float pad_[5];
} wide_sray;
static_assert(sizeof(wide_sray) == 64, "a stream ray is one cache line");

/* A ray in an entry's list: its index in the stream and its entry distance
 * into the entry's box (-inf: passes every pop test). */
typedef struct {
    uint32_t ray;
    float t_entry;
} wide_sitem;

typedef struct {
    uint32_t ref, begin, count; /* node or leaf; its list in the buffer */
} wide_sentry;

/* Items of list buffer per stream ray: the root's list and a node's W
 * lists of at most a stream each fit at the bottom (W <= 8). */
#define WIDE_STREAM_ITEMS 16

/* A batch's buffers: the octant order of the batch's rays, one stream's
 * rays (prepared, running answers, counts), the entries' lists and one
 * node's child lists (W of `size` items each). One allocation. */
typedef struct {
    uint32_t size;
    uint32_t *order;
    wide_sray *ray;
    accel_ray_prep *p;
    float *u, *v;
    uint32_t *id, *steps, *boxes, *prims, *gidx;
    wide_sitem *items, *scratch;
    size_t items_cap;
    void *mem;
} wide_stream_ws;

static inline size_t wide_stream_round(size_t bytes) { return (bytes + 63) & ~(size_t)63; }

/* Returns 0, or 1 when the memory cannot be had (the caller then traces
 * ray by ray). */
static inline int wide_stream_alloc(wide_stream_ws *ws, size_t count, int stream, int width)
{
    size_t s = (size_t)stream < count ? (size_t)stream : count;
    if (s < 1) s = 1;
    ws->size = (uint32_t)s;
    ws->items_cap = WIDE_STREAM_ITEMS * s;
    size_t sizes[13] = {count * sizeof(uint32_t), s * sizeof(wide_sray), s * sizeof(accel_ray_prep),
                        s * sizeof(float), s * sizeof(float), s * sizeof(uint32_t), s * sizeof(uint32_t),
                        s * sizeof(uint32_t), s * sizeof(uint32_t), s * sizeof(uint32_t),
                        ws->items_cap * sizeof(wide_sitem), (size_t)width * s * sizeof(wide_sitem), 0};
    size_t total = 0;
    for (int i = 0; i < 12; i++) total += wide_stream_round(sizes[i]);
    char *m = aligned_alloc(64, total); /* total: a multiple of 64 */
    ws->mem = m;
    if (!m) return 1;
    ws->order = (uint32_t *)m, m += wide_stream_round(sizes[0]);
    ws->ray = (wide_sray *)m, m += wide_stream_round(sizes[1]);
    ws->p = (accel_ray_prep *)m, m += wide_stream_round(sizes[2]);
    ws->u = (float *)m, m += wide_stream_round(sizes[3]);
    ws->v = (float *)m, m += wide_stream_round(sizes[4]);
    ws->id = (uint32_t *)m, m += wide_stream_round(sizes[5]);
    ws->steps = (uint32_t *)m, m += wide_stream_round(sizes[6]);
    ws->boxes = (uint32_t *)m, m += wide_stream_round(sizes[7]);
    ws->prims = (uint32_t *)m, m += wide_stream_round(sizes[8]);
    ws->gidx = (uint32_t *)m, m += wide_stream_round(sizes[9]);
    ws->items = (wide_sitem *)m, m += wide_stream_round(sizes[10]);
    ws->scratch = (wide_sitem *)m;
    return 0;
}

/* The octant of a direction as wide_prep_ray's neg bits make it. */
static inline int wide_stream_octant(const accel_ray *r)
{
    return (signbit(r->dx) != 0) | (signbit(r->dy) != 0) << 1 | (signbit(r->dz) != 0) << 2;
}
#endif

#define SK_CAT_(a, b, c) a##_##b##_##c
#define SK_CAT(a, b, c) SK_CAT_(a, b, c)
#define SK(name) SK_CAT(name, WIDE_NW, WIDE_LB)
#define SKL__(a, b) a##_##b
#define SKL_(a, b) SKL__(a, b)
#define SKL(name) SKL_(name, WIDE_LB)
#define SV(op) WIDE_V(WIDE_NW, op)
#define SF WIDE_T(WIDE_NW)
#define SK_JOIN_(a, b) a##b
#define SK_JOIN(a, b) SK_JOIN_(a, b)
#define SNODE SK_JOIN(wide_node, WIDE_NW)
#define SNR SK(node_ray)

/* The child lanes of a node by rank for the octant (bits `shift` of perm),
 * and each ray's hit mask in rank order: the lowest set bit names the child
 * a single ray would enter directly. */
typedef struct {
    unsigned lane[WIDE_NW];
#if WIDE_AVX && WIDE_NW == 8
    __m256i pv;
#elif WIDE_AVX && WIDE_NW == 4
    __m128i pv;
#endif
} SK(ranks);

WIDE_INLINE void SK(ranks_of)(SK(ranks) *k, const uint32_t *perm, int shift)
{
    for (int rank = 0; rank < WIDE_NW; rank++) k->lane[rank] = (perm[rank] >> shift) & 7u;
#if WIDE_AVX && WIDE_NW == 8
    k->pv = _mm256_and_si256(_mm256_srl_epi32(_mm256_load_si256((const __m256i *)perm), _mm_cvtsi32_si128(shift)),
                             _mm256_set1_epi32(7));
#elif WIDE_AVX && WIDE_NW == 4
    k->pv = _mm_and_si128(_mm_srl_epi32(_mm_load_si128((const __m128i *)perm), _mm_cvtsi32_si128(shift)),
                          _mm_set1_epi32(3));
#endif
}

WIDE_INLINE unsigned SK(ranked)(const SK(ranks) *k, SF hit, unsigned mask)
{
#if WIDE_AVX && WIDE_NW == 8
    (void)mask;
    return (unsigned)_mm256_movemask_ps(_mm256_permutevar8x32_ps(hit, k->pv));
#elif WIDE_AVX && WIDE_NW == 4
    (void)mask;
    return (unsigned)_mm_movemask_ps(_mm_permutevar_ps(hit, k->pv));
#else
    (void)hit;
    unsigned r = 0;
    for (int rank = 0; rank < WIDE_NW; rank++) r |= (mask >> k->lane[rank] & 1u) << rank;
    return r;
#endif
}

/* Ray r leaves the stream (occluded, or over its step bound). */
WIDE_INLINE void SK(retire)(wide_stream_ws *ws, uint32_t r, uint32_t *alive)
{
    ws->ray[r].t = -INFINITY;
    (*alive)--;
}

/* One stream of n prepared rays (ws->ray, p, items[0..n) the root's list),
 * all of octant `oct`, from the root to every ray's answer. */
WIDE_INLINE void SK(stream_walk)(const bvh_wide *w, wide_stream_ws *ws, uint32_t n, int oct,
                                 accel_counters *c, unsigned flags, int any_hit)
{
    const SNODE *nodes = w->nodes;
    const int shift = 3 * oct, nx = oct & 1, ny = oct >> 1 & 1, nz = oct >> 2 & 1;
    const uint32_t size = ws->size, hybrid = (uint32_t)w->hybrid;
    SNR base; /* what every ray of the stream shares: its plane rows, folded padding */
    base.nx = (0 + nx) * WIDE_NW, base.fx = (1 - nx) * WIDE_NW;
    base.ny = (2 + ny) * WIDE_NW, base.fy = (3 - ny) * WIDE_NW;
    base.nz = (4 + nz) * WIDE_NW, base.fz = (5 - nz) * WIDE_NW;
    base.folded = 1;
    wide_sentry stack[WIDE_STACK(WIDE_NW)];
    int sp = 0;
    uint32_t alive = n;
    stack[sp++] = (wide_sentry){w->root, 0, n};
    while (sp > 0 && alive) {
        const wide_sentry e = stack[--sp];
        const uint32_t top = e.begin;
        wide_sitem *it = ws->items + e.begin;
        /* The pop test of each ray on its own t (occluded rays: -inf). */
        uint32_t m = 0;
        for (uint32_t k = 0; k < e.count; k++) {
            wide_sitem x = it[k];
            it[m] = x;
            m += box3_entry_before(x.t_entry, ws->ray[x.ray].t);
        }
        if (!m) continue;
        if (e.ref & WIDE_LEAF) {
            if (c) c->packet_steps++;
            for (uint32_t k = 0; k < m; k++) {
                uint32_t r = it[k].ray;
                if (c && (++ws->steps[r], ACCEL_STEP_BOUND_BROKEN(c, ws->steps[r], w->step_bound))) {
                    SK(retire)(ws, r, &alive);
                    continue;
                }
                SKL(wide_leaf_ray) lr;
                SKL(leaf_setup)(&lr, &ws->p[r]);
                float t = ws->ray[r].t;
                if (SK(visit_leaf)(w, e.ref, &lr, &ws->p[r], &t, &ws->u[r], &ws->v[r], &ws->id[r], &ws->prims[r],
                                   c != NULL, flags, any_hit))
                    SK(retire)(ws, r, &alive);
                else
                    ws->ray[r].t = t;
            }
            continue;
        }
        if (m <= hybrid || top + (size_t)WIDE_NW * m > ws->items_cap) {
            /* Ray by ray from here: the single-ray walk of the subtree. */
            for (uint32_t k = 0; k < m; k++) {
                uint32_t r = it[k].ray;
                float t = ws->ray[r].t;
                if (SK(walk_oct)(w, &ws->p[r], e.ref, &t, &ws->u[r], &ws->v[r], &ws->id[r], &ws->steps[r],
                                 &ws->boxes[r], &ws->prims[r], c, flags, any_hit, 1, 0))
                    SK(retire)(ws, r, &alive); /* occluded (or over its step bound) */
                else
                    ws->ray[r].t = t;
            }
            continue;
        }
        if (c) c->packet_steps++;
        const SNODE *nd = &nodes[e.ref];
        const float *rows = nd->box[0];
        SK(ranks) rk;
        SK(ranks_of)(&rk, nd->perm, shift);
        uint32_t cnt[WIDE_NW] = {0};
        wide_sitem *sc = ws->scratch;
        for (uint32_t k = 0; k < m; k++) {
            const uint32_t r = it[k].ray;
            const wide_sray *s = &ws->ray[r];
            if (c) {
                ws->boxes[r] += WIDE_NW;
                if (++ws->steps[r], ACCEL_STEP_BOUND_BROKEN(c, ws->steps[r], w->step_bound)) {
                    SK(retire)(ws, r, &alive);
                    continue;
                }
            }
            SNR nr = base;
            nr.ox = SV(set1)(s->ox), nr.oy = SV(set1)(s->oy), nr.oz = SV(set1)(s->oz);
            nr.ix = SV(set1)(s->ix), nr.iy = SV(set1)(s->iy), nr.iz = SV(set1)(s->iz);
            nr.fix = SV(set1)(s->fix), nr.fiy = SV(set1)(s->fiy), nr.fiz = SV(set1)(s->fiz);
            nr.t_near = SV(set1)(s->tn);
            SF t0, hit = SK(slab_rows)(rows, &nr, s->t, &t0);
            unsigned mask = (unsigned)SV(mask)(hit);
            float te[WIDE_NW] __attribute__((aligned(32)));
            SV(store)(te, t0);
            /* The nearest hit child in the octant order is the one a single
             * ray enters without the pop test (with no hit, rank W-1's
             * lane is written but not counted). */
            te[rk.lane[__builtin_ctz(SK(ranked)(&rk, hit, mask) | 1u << (WIDE_NW - 1))]] = -INFINITY;
            for (int l = 0; l < WIDE_NW; l++) {
                sc[(size_t)l * size + cnt[l]] = (wide_sitem){r, te[l]};
                cnt[l] += mask >> l & 1u;
            }
        }
        uint32_t at = top;
        for (int rank = WIDE_NW - 1; rank >= 0; rank--) { /* farthest first: the nearest on top */
            unsigned l = rk.lane[rank];
            if (!cnt[l]) continue;
            memcpy(ws->items + at, sc + (size_t)l * size, cnt[l] * sizeof *sc);
            stack[sp++] = (wide_sentry){nd->child[l], at, cnt[l]};
            at += cnt[l];
        }
    }
}

/* The batch: its rays by octant, each octant's cut into streams. */
WIDE_INLINE void SK(stream_batch)(const void *a, const accel_ray *rays, void *out, size_t count,
                                  accel_counters *c, unsigned flags, int any_hit)
{
    const bvh_wide *w = a;
    wide_stream_ws ws;
    if (!count) return;
    if (w->root == WIDE_EMPTY || count > UINT32_MAX || wide_stream_alloc(&ws, count, w->stream, WIDE_NW)) {
        for (size_t i = 0; i < count; i++)
            SK_CAT(trace_ray_oct, WIDE_NW, WIDE_LB)(w, &rays[i], out, c, i, flags, any_hit, 1, 0);
        return;
    }
    size_t start[9] = {0};
    for (size_t i = 0; i < count; i++) start[wide_stream_octant(&rays[i]) + 1]++;
    for (int o = 0; o < 8; o++) start[o + 1] += start[o];
    size_t at[8];
    memcpy(at, start, sizeof at);
    for (size_t i = 0; i < count; i++) ws.order[at[wide_stream_octant(&rays[i])]++] = (uint32_t)i;
    const float pf = accel_far_factor(1);
    for (int o = 0; o < 8; o++) {
        for (size_t b = start[o]; b < start[o + 1]; b += ws.size) {
            size_t nb = start[o + 1] - b < ws.size ? start[o + 1] - b : ws.size;
            uint32_t n = 0;
            for (size_t j = 0; j < nb; j++) {
                const size_t gi = ws.order[b + j];
                accel_ray_prep *p = &ws.p[n];
                int ok = wide_prep_ray(&rays[gi], p);
                if (!ok || !accel_far_folded(p->t_near) || (p->neg[0] | p->neg[1] << 1 | p->neg[2] << 2) != o) {
                    /* no hit possible, t_near < 0 (unfolded padding), or
                     * (never seen) another octant: the single-ray kernel */
                    SK_CAT(trace_prepped_oct_, WIDE_NW, WIDE_LB)(w, ok ? p : NULL, out, c, gi, flags, any_hit, 1,
                                                                 0);
                    continue;
                }
                wide_sray *s = &ws.ray[n];
                s->ox = p->org.x, s->oy = p->org.y, s->oz = p->org.z;
                s->ix = p->inv_dir.x, s->iy = p->inv_dir.y, s->iz = p->inv_dir.z;
                s->fix = p->inv_dir.x * pf, s->fiy = p->inv_dir.y * pf, s->fiz = p->inv_dir.z * pf;
                s->tn = p->t_near, s->t = p->t_far;
                ws.u[n] = ws.v[n] = 0.0f;
                ws.id[n] = ACCEL_MISS, ws.steps[n] = ws.boxes[n] = ws.prims[n] = 0;
                ws.gidx[n] = (uint32_t)gi;
                ws.items[n] = (wide_sitem){n, -INFINITY};
                n++;
            }
            if (!n) continue;
            SK(stream_walk)(w, &ws, n, o, c, flags, any_hit);
            for (uint32_t i = 0; i < n; i++) {
                accel_hit h = accel_hit_miss();
                h.u = ws.u[i], h.v = ws.v[i];
                SK_CAT(finish, WIDE_NW, WIDE_LB)(h, ws.id[i], ws.ray[i].t, out, c, ws.gidx[i], ws.steps[i],
                                                 ws.boxes[i], ws.prims[i], any_hit);
            }
        }
    }
    free(ws.mem);
}

WIDE_INLINE void SK(wide_sclosest)(const void *a, const accel_ray *rays, void *out, size_t count,
                                   accel_counters *c, unsigned flags)
{
    SK(stream_batch)(a, rays, out, count, c, flags, 0);
}

WIDE_INLINE void SK(wide_sany)(const void *a, const accel_ray *rays, void *out, size_t count,
                               accel_counters *c, unsigned flags)
{
    SK(stream_batch)(a, rays, out, count, c, flags, 1);
}

#undef SK_CAT_
#undef SK_CAT
#undef SK
#undef SKL__
#undef SKL_
#undef SKL
#undef SV
#undef SF
#undef SK_JOIN_
#undef SK_JOIN
#undef SNODE
#undef SNR
