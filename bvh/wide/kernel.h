/*
 * kernel.h - single-ray traversal of a wide BVH with WIDE_NW (4 or 8)
 * children per node and leaf blocks of WIDE_LB (4 or 8) primitives:
 * closest hit and any hit.
 * A kernel body (C only): included by the .c files of its folder, not part
 * of the interface a C++ program includes.
 *
 * A template: tables.h (for the k<width>_<row>.c units) includes
 * it once per (WIDE_NW, WIDE_LB) pair after core/block_test.h for WIDE_LB (4 and 4 when included alone). It defines
 * the always-inline kernels wide_closest_<NW>_<LB> and wide_any_<NW>_<LB>
 * in the form core/variant.h's ACCEL_KERNEL_TABLE expects.
 *
 * The loop follows Embree's single-ray BVH4/BVH8 traversal (Wald et al.,
 * "Embree: A Kernel Framework for Efficient CPU Ray Tracing", SIGGRAPH
 * 2014) and the stack discipline of Aila and Laine (HPG 2009):
 *  - one ray against all W child boxes with the robust slab test of
 *    bvh_slab (Ize 2013) lane by lane: the same subtractions, products and
 *    NaN-dropping min/max, and the same far padding folded into the ray
 *    (ACCEL_FAR_PAD, core/geom.h), so a wide node accepts exactly the boxes
 *    the binary kernel would;
 *  - the hit children visited near to far: one hit child is entered
 *    directly; of two, the nearer is entered and the farther pushed with
 *    its entry distance; three or more are pushed, sorted by entry distance
 *    (insertion sort on at most 8 entries, the nearest on top) and the top
 *    popped;
 *  - leaves are children like nodes (pushed and ordered by distance);
 *  - a popped entry whose entry distance lies beyond the closest hit found
 *    since it was pushed is dropped unvisited;
 *  - any hit returns at the first hit.
 * Counters (steps = nodes and leaves visited, box tests = W per node,
 * primitive tests = primitives of the blocks tested) and the step bound
 * (ACCEL_STEP_BOUND_BROKEN: a ray visits each node and leaf at most once)
 * exist in the counted copy only.
 */
#ifndef WIDE_NW
#define WIDE_NW 4
#endif
#ifndef WIDE_LB
#define WIDE_LB 4
#include "core/block_test.h"
#endif
#include "core/variant.h"
#include "node.h"
#include "core/simd.h"

#define WK_CAT_(a, b, c) a##_##b##_##c
#define WK_CAT(a, b, c) WK_CAT_(a, b, c)
#define WK(name) WK_CAT(name, WIDE_NW, WIDE_LB)
#define WL2_(a, b) a##_##b
#define WL2(a, b) WL2_(a, b)
#define KL(name) WL2(name, WIDE_LB)
#define NV(op) WIDE_V(WIDE_NW, op)
#define NF WIDE_T(WIDE_NW)
#define WK_JOIN_(a, b) a##b
#define WK_JOIN(a, b) WK_JOIN_(a, b)
#define KNODE WK_JOIN(wide_node, WIDE_NW)
#define KBLOCK WK_JOIN(wide_block, WIDE_LB)
/* A node and a leaf's first block from their references: indices of the
 * two pools, or, in the unit of layout=mixed (k8_mixed.c defines
 * WIDE_MIXED), 64-byte lines of the one pool (wide.h, node.h). */
#if defined(WIDE_MIXED) && WIDE_MIXED
#define WK_NODE_AT(tree, pool, r) ((void)(pool), (const KNODE *)((const char *)(tree)->nodes + ((size_t)(r) << 6)))
#define WK_LEAF_AT(tree, r) ((const KBLOCK *)((const char *)(tree)->nodes + ((size_t)wide_leaf_first(r) << 6)))
#else
#define WK_NODE_AT(tree, pool, r) (&(pool)[r])
#define WK_LEAF_AT(tree, r) ((const KBLOCK *)(tree)->blocks + wide_leaf_first(r))
#endif

/* Per-ray constants of the slab test: origin, 1/dir (near planes) and the
 * far reciprocals with the padding folded in (ACCEL_FAR_PAD, core/geom.h),
 * and the float offset of each axis's near and far plane row, picked by
 * the direction's sign. */
typedef struct {
    NF ox, oy, oz, ix, iy, iz, fix, fiy, fiz, t_near;
    int nx, fx, ny, fy, nz, fz;
    int folded; /* accel_far_folded: else t1 padded after the minimum */
} WK(node_ray);

WIDE_INLINE void WK(node_setup)(WK(node_ray) *r, const accel_ray_prep *p)
{
    r->ox = NV(set1)(p->org.x), r->oy = NV(set1)(p->org.y), r->oz = NV(set1)(p->org.z);
    r->ix = NV(set1)(p->inv_dir.x), r->iy = NV(set1)(p->inv_dir.y), r->iz = NV(set1)(p->inv_dir.z);
    r->folded = accel_far_folded(p->t_near);
    float pf = accel_far_factor(r->folded);
    r->fix = NV(set1)(p->inv_dir.x * pf), r->fiy = NV(set1)(p->inv_dir.y * pf);
    r->fiz = NV(set1)(p->inv_dir.z * pf);
    r->t_near = NV(set1)(p->t_near);
    r->nx = (0 + p->neg[0]) * WIDE_NW, r->fx = (1 - p->neg[0]) * WIDE_NW;
    r->ny = (2 + p->neg[1]) * WIDE_NW, r->fy = (3 - p->neg[1]) * WIDE_NW;
    r->nz = (4 + p->neg[2]) * WIDE_NW, r->fz = (5 - p->neg[2]) * WIDE_NW;
}

/*
 * The slab test of one ray against the W children of a node, given as the
 * six plane rows the ray's signs pick (near and far on each axis): the
 * entry distances in *t0 and the hit lanes as a mask vector.
 */
WIDE_INLINE NF WK(slab_planes)(NF nx, NF fx, NF ny, NF fy, NF nz, NF fz, const WK(node_ray) *r, float t,
                               NF *t0_out)
{
    NF t0 = NV(max)(NV(mul)(NV(sub)(nx, r->ox), r->ix), r->t_near);
    t0 = NV(max)(NV(mul)(NV(sub)(ny, r->oy), r->iy), t0);
    t0 = NV(max)(NV(mul)(NV(sub)(nz, r->oz), r->iz), t0);
    NF t1 = NV(min)(NV(mul)(NV(sub)(fx, r->ox), r->fix), NV(set1)(accel_far_limit(t, r->folded)));
    t1 = NV(min)(NV(mul)(NV(sub)(fy, r->oy), r->fiy), t1);
    t1 = NV(min)(NV(mul)(NV(sub)(fz, r->oz), r->fiz), t1);
    *t0_out = t0;
    if (!r->folded) t1 = NV(add)(t1, NV(mul)(NV(abs)(t1), NV(set1)(ACCEL_SLAB_PAD)));
    return NV(le)(t0, t1);
}

/* The same on a float node's box rows. */
WIDE_INLINE NF WK(slab_rows)(const float *b, const WK(node_ray) *r, float t, NF *t0)
{
    return WK(slab_planes)(NV(load)(b + r->nx), NV(load)(b + r->fx), NV(load)(b + r->ny),
                           NV(load)(b + r->fy), NV(load)(b + r->nz), NV(load)(b + r->fz), r, t, t0);
}

/*
 * The same with every child box grown by a pad on every side (lo - pad,
 * hi + pad, in float): the conservative walk of a structure whose boxes
 * must also cover a rounding margin known per ray (instanced/README.md,
 * "the pad"). The near plane moves by -pad where the ray's direction is
 * positive and by +pad where it is negative, the far plane the other way.
 * A variant, not a parameter of slab_rows: bvh/wide's own kernels call
 * slab_rows, so nothing is added to their loops.
 */
typedef struct {
    NF nx, fx, ny, fy, nz, fz;
} WK(node_pad);

WIDE_INLINE void WK(pad_setup)(WK(node_pad) *q, const accel_ray_prep *p, float pad)
{
    NF up = NV(set1)(pad), down = NV(set1)(-pad);
    q->nx = p->neg[0] ? up : down, q->fx = p->neg[0] ? down : up;
    q->ny = p->neg[1] ? up : down, q->fy = p->neg[1] ? down : up;
    q->nz = p->neg[2] ? up : down, q->fz = p->neg[2] ? down : up;
}

WIDE_INLINE NF WK(slab_rows_pad)(const float *b, const WK(node_ray) *r, const WK(node_pad) *q, float t,
                                 NF *t0)
{
    return WK(slab_planes)(NV(add)(NV(load)(b + r->nx), q->nx), NV(add)(NV(load)(b + r->fx), q->fx),
                           NV(add)(NV(load)(b + r->ny), q->ny), NV(add)(NV(load)(b + r->fy), q->fy),
                           NV(add)(NV(load)(b + r->nz), q->nz), NV(add)(NV(load)(b + r->fz), q->fz), r, t,
                           t0);
}

/*
 * One interior node: all children's boxes at once, then the hit children
 * near to far. Sets *ref to the child to visit next and returns 1, or
 * returns 0 when no child is hit (the caller pops).
 */
WIDE_INLINE int WK(visit_node)(const KNODE *n, const WK(node_ray) *r, float t, uint32_t *ref,
                               wide_stack_entry *stack, int *sp_io)
{
    NF t0;
    unsigned mask = (unsigned)NV(mask)(WK(slab_rows)(n->box[0], r, t, &t0));
    if (!mask) return 0;
    unsigned i = (unsigned)__builtin_ctz(mask);
    mask &= mask - 1;
    if (!mask) { /* one hit child: enter it */
        *ref = n->child[i];
        return 1;
    }
    float te[WIDE_NW] __attribute__((aligned(32)));
    NV(store)(te, t0);
    unsigned j = (unsigned)__builtin_ctz(mask);
    mask &= mask - 1;
    int sp = *sp_io;
    if (!mask) { /* two: enter the nearer, push the farther */
        int swap = te[j] < te[i];
        unsigned near = swap ? j : i, far_i = swap ? i : j;
        stack[sp].ref = n->child[far_i];
        stack[sp].t_entry = te[far_i];
        *sp_io = sp + 1;
        *ref = n->child[near];
        return 1;
    }
    /* Three or more: push all, sort the run far to near (insertion sort),
     * enter the nearest. */
    int base = sp;
    stack[sp].ref = n->child[i], stack[sp].t_entry = te[i], sp++;
    stack[sp].ref = n->child[j], stack[sp].t_entry = te[j], sp++;
    do {
        unsigned k = (unsigned)__builtin_ctz(mask);
        mask &= mask - 1;
        stack[sp].ref = n->child[k], stack[sp].t_entry = te[k], sp++;
    } while (mask);
    for (int a = base + 1; a < sp; a++) {
        wide_stack_entry e = stack[a];
        int k = a;
        while (k > base && stack[k - 1].t_entry < e.t_entry) {
            stack[k] = stack[k - 1];
            k--;
        }
        stack[k] = e;
    }
    *ref = stack[--sp].ref;
    *sp_io = sp;
    return 1;
}

/* One leaf: its blocks are consecutive. Returns 1 when any_hit found a hit. */
WIDE_INLINE int WK(visit_leaf)(const bvh_wide *w, uint32_t ref, const KL(wide_leaf_ray) *lr,
                               const accel_ray_prep *p, float *t, float *u, float *v,
                               uint32_t *hit_id, uint32_t *prims, int counted, unsigned flags,
                               int any_hit)
{
    const int naive = (flags & ACCEL_V_NAIVE) != 0, has_spheres = (flags & ACCEL_V_SPHERES) != 0;
    const KBLOCK *blk = WK_LEAF_AT(w, ref);
    uint32_t nb = wide_leaf_blocks(ref);
    for (uint32_t k = 0; k < nb; k++) {
        if (counted) {
            (*prims)++;
            for (int lane = 1; lane < WIDE_LB; lane++) *prims += blk[k].id[lane] != blk[k].id[lane - 1];
        }
        if (KL(leaf_block)(&blk[k], lr, p, t, u, v, hit_id, w->tri_count, naive, has_spheres, any_hit) &&
            any_hit) {
            *hit_id = 0; /* occluded: which primitive does not matter */
            return 1;
        }
    }
    return 0;
}

/* Pops the next entry that can still hold a hit closer than t into *ref;
 * 0 when the stack is exhausted. */
WIDE_INLINE int WK(pop)(const wide_stack_entry *stack, int *sp_io, float t, uint32_t *ref)
{
    int sp = *sp_io;
    while (sp > 0) {
        sp--;
        if (box3_entry_before(stack[sp].t_entry, t)) {
            *ref = stack[sp].ref;
            *sp_io = sp;
            return 1;
        }
    }
    *sp_io = 0;
    return 0;
}

/* Writes a ray's answer and its counts. */
WIDE_INLINE void WK(finish)(accel_hit hit, uint32_t hit_id, float t, void *out, accel_counters *c,
                            size_t ray_idx, uint32_t steps, uint32_t boxes, uint32_t prims, int any_hit)
{
    if (hit_id != ACCEL_MISS) {
        hit.t = t;
        hit.prim = hit_id;
    } else {
        hit = accel_hit_miss();
    }
    if (any_hit)
        ((uint8_t *)out)[ray_idx] = hit.prim != ACCEL_MISS;
    else
        ((accel_hit *)out)[ray_idx] = hit;
    if (c) accel_count_ray(c, ray_idx, steps, 0, boxes, prims, 0);
}

/* One ray from root to answer. */
WIDE_INLINE void WK(trace_ray)(const bvh_wide *w, const accel_ray *ray, void *out, accel_counters *c,
                               size_t ray_idx, unsigned flags, int any_hit)
{
    accel_hit hit = accel_hit_miss();
    uint32_t steps = 0, boxes = 0, prims = 0, hit_id = ACCEL_MISS;
    float t = INFINITY;
    accel_ray_prep p;
    if (w->root != WIDE_EMPTY && wide_prep_ray(ray, &p)) {
        WK(node_ray) nr;
        WK(node_setup)(&nr, &p);
        KL(wide_leaf_ray) lr;
        KL(leaf_setup)(&lr, &p);
        const KNODE *nodes = w->nodes;
        wide_stack_entry stack[WIDE_STACK(WIDE_NW)];
        int sp = 0;
        uint32_t ref = w->root;
        t = p.t_far;
        for (;;) {
            steps++;
            if (ACCEL_STEP_BOUND_BROKEN(c, steps, w->step_bound)) break;
            if (!(ref & WIDE_LEAF)) {
                boxes += WIDE_NW;
                if (WK(visit_node)(WK_NODE_AT(w, nodes, ref), &nr, t, &ref, stack, &sp)) continue;
            } else if (WK(visit_leaf)(w, ref, &lr, &p, &t, &hit.u, &hit.v, &hit_id, &prims, c != NULL,
                                      flags, any_hit)) {
                break;
            }
            if (!WK(pop)(stack, &sp, t, &ref)) break;
        }
    }
    WK(finish)(hit, hit_id, t, out, c, ray_idx, steps, boxes, prims, any_hit);
}

/*
 * The hit children (mask; hit, its vector form, must hold exactly those
 * lanes when !branchy) of a node pushed in the node's octant order for the
 * ray (bits `shift`.. of perm[]), farthest first, and the nearest entered:
 * a branch on "exactly one", then either (the default) exactly two
 * ordered by their entry distances and three or more by a compress-store,
 * or one branch per child (branchy). Returns 0 when none is hit.
 */
WIDE_INLINE int WK(push_octant)(const uint32_t *child, const uint32_t *perm, NF hit, NF t0, unsigned mask,
                                uint32_t *ref, uint32_t *sref, float *st, int *sp_io, int shift, int branchy)
{
    if (!mask) return 0;
    if (!(mask & (mask - 1))) {
        *ref = child[__builtin_ctz(mask)];
        return 1;
    }
    int sp = *sp_io;
#if WIDE_AVX && WIDE_NW == 8
    unsigned rest = mask & (mask - 1);
    if (!branchy && !(rest & (rest - 1))) {
        /* Two hit children: the nearer entered, the farther pushed. The
         * two entry distances come out of the register by a permute each,
         * so the next address waits for a compare and a predicted branch
         * (gcc's form; a choice by masks measured 0.81-0.93x) instead of
         * the compress-store's shuffles and a store forwarded to a load
         * (2026-12-03: 1.00-1.18x primary and shadow, 0.98-1.13x diffuse;
         * order=branchy and width 4 lose on coherent rays with it, so their
         * predicted branches stay; bvh/README, "each idea"). */
        unsigned i = (unsigned)__builtin_ctz(mask), j = (unsigned)__builtin_ctz(rest);
        float ti = f8_lane(t0, i), tj = f8_lane(t0, j);
        int j_near = tj < ti;
        sref[sp] = child[j_near ? i : j], st[sp] = j_near ? ti : tj;
        *sp_io = sp + 1;
        *ref = child[j_near ? j : i];
        return 1;
    }
#if WIDE_AVX512
    if (!branchy) {
        /* AVX-512 (VL, DQ): the ranks farthest first (the perm row read
         * backwards, off the critical path like the child row), the hit
         * lanes in that order as a mask register, and the children and
         * their entry distances compressed in registers (vpcompressd/ps;
         * the register form: the store form is microcoded on Zen 4) and
         * stored whole onto the stack's slack: the same slots, in the same
         * order, as the table form below, without its table load and
         * shifts on the path from the slab test to the next address. */
        const __m256i back = _mm256_setr_epi32(7, 6, 5, 4, 3, 2, 1, 0);
        __m256i pv = _mm256_and_si256(_mm256_srl_epi32(_mm256_permutevar8x32_epi32(
                                                           _mm256_load_si256((const __m256i *)perm), back),
                                                       _mm_cvtsi32_si128(shift)),
                                      _mm256_set1_epi32(7));
        __mmask8 m = _mm256_movepi32_mask(_mm256_permutevar8x32_epi32(_mm256_castps_si256(hit), pv));
        __m256i kids = _mm256_permutevar8x32_epi32(_mm256_load_si256((const __m256i *)child), pv);
        _mm256_storeu_si256((__m256i *)(sref + sp), _mm256_maskz_compress_epi32(m, kids));
        _mm256_storeu_ps(st + sp, _mm256_maskz_compress_ps(m, _mm256_permutevar8x32_ps(t0, pv)));
        sp += __builtin_popcount(mask);
        *ref = sref[--sp];
        *sp_io = sp;
        return 1;
    }
#endif
    if (!branchy) {
        /* rank -> child lane for this octant; hit bits in rank order; the
         * ranks of the hits, farthest first (the compress table); composed,
         * the child lane of each stack slot. */
        __m256i pv = _mm256_and_si256(_mm256_srl_epi32(_mm256_load_si256((const __m256i *)perm),
                                                       _mm_cvtsi32_si128(shift)),
                                      _mm256_set1_epi32(7));
        unsigned ranked = (unsigned)_mm256_movemask_ps(_mm256_permutevar8x32_ps(hit, pv));
        __m256i sel = _mm256_and_si256(_mm256_srlv_epi32(_mm256_set1_epi32((int)wide_compress_lut[ranked]),
                                                         _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28)),
                                       _mm256_set1_epi32(15));
        __m256i lane = _mm256_permutevar8x32_epi32(pv, sel);
        _mm256_storeu_si256((__m256i *)(sref + sp),
                            _mm256_permutevar8x32_epi32(_mm256_load_si256((const __m256i *)child), lane));
        _mm256_storeu_ps(st + sp, _mm256_permutevar8x32_ps(t0, lane));
        sp += __builtin_popcount(mask);
        *ref = sref[--sp];
        *sp_io = sp;
        return 1;
    }
#endif
    /* order=branchy (and every build without AVX2): the ranks farthest
     * first, one branch per child on "hit". The next node's address then
     * hangs on predicted branches instead of the compress-store's chain of
     * dependent shuffles (the form of W. Jakob's kernels in tinybvh): it
     * pays where consecutive rays hit the same children (primary and
     * shadow rays) and loses to mispredictions on incoherent ones. */
    (void)branchy, (void)hit;
    float te[WIDE_NW] __attribute__((aligned(32)));
    NV(store)(te, t0);
    for (int rank = WIDE_NW - 1; rank >= 0; rank--) {
        unsigned l = (perm[rank] >> shift) & 7u;
        if (mask >> l & 1u) sref[sp] = child[l], st[sp] = te[l], sp++;
    }
    *ref = sref[--sp];
    *sp_io = sp;
    return 1;
}

/*
 * any_order= (wide.h): the hit children pushed in the order of perm's bits
 * `shift`.. for every count of them, two included (no entry-distance
 * compare), by push_octant's compress-store; a function of its own so that
 * push_octant's code stays as it is (gcc lays the default kernels out
 * otherwise when push_octant's conditions change).
 */
WIDE_INLINE int WK(push_fixed)(const uint32_t *child, const uint32_t *perm, NF hit, NF t0, unsigned mask,
                               uint32_t *ref, uint32_t *sref, float *st, int *sp_io, int shift)
{
#if WIDE_AVX && WIDE_NW == 8
    if (!mask) return 0;
    if (!(mask & (mask - 1))) {
        *ref = child[__builtin_ctz(mask)];
        return 1;
    }
    int sp = *sp_io;
#if WIDE_AVX512
    const __m256i back = _mm256_setr_epi32(7, 6, 5, 4, 3, 2, 1, 0);
    __m256i pv = _mm256_and_si256(_mm256_srl_epi32(_mm256_permutevar8x32_epi32(
                                                       _mm256_load_si256((const __m256i *)perm), back),
                                                   _mm_cvtsi32_si128(shift)),
                                  _mm256_set1_epi32(7));
    __mmask8 m = _mm256_movepi32_mask(_mm256_permutevar8x32_epi32(_mm256_castps_si256(hit), pv));
    __m256i kids = _mm256_permutevar8x32_epi32(_mm256_load_si256((const __m256i *)child), pv);
    _mm256_storeu_si256((__m256i *)(sref + sp), _mm256_maskz_compress_epi32(m, kids));
    _mm256_storeu_ps(st + sp, _mm256_maskz_compress_ps(m, _mm256_permutevar8x32_ps(t0, pv)));
#else
    __m256i pv = _mm256_and_si256(_mm256_srl_epi32(_mm256_load_si256((const __m256i *)perm),
                                                   _mm_cvtsi32_si128(shift)),
                                  _mm256_set1_epi32(7));
    unsigned ranked = (unsigned)_mm256_movemask_ps(_mm256_permutevar8x32_ps(hit, pv));
    __m256i sel = _mm256_and_si256(_mm256_srlv_epi32(_mm256_set1_epi32((int)wide_compress_lut[ranked]),
                                                     _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28)),
                                   _mm256_set1_epi32(15));
    __m256i lane = _mm256_permutevar8x32_epi32(pv, sel);
    _mm256_storeu_si256((__m256i *)(sref + sp),
                        _mm256_permutevar8x32_epi32(_mm256_load_si256((const __m256i *)child), lane));
    _mm256_storeu_ps(st + sp, _mm256_permutevar8x32_ps(t0, lane));
#endif
    sp += __builtin_popcount(mask);
    *ref = sref[--sp];
    *sp_io = sp;
    return 1;
#else
    /* no AVX2: branchy's push (perm order for every count already) */
    return WK(push_octant)(child, perm, hit, t0, mask, ref, sref, st, sp_io, shift, 1);
#endif
}

/*
 * order=octant (and branchy): one interior node, its hit children pushed
 * in the node's precomputed order for the ray's octant (push_octant),
 * instead of the per-count branches and the sort of visit_node;
 * branchy = 2 (any_order=): push_fixed.
 */
WIDE_INLINE int WK(visit_node_oct)(const KNODE *n, const WK(node_ray) *r, float t, uint32_t *ref,
                                   uint32_t *sref, float *st, int *sp_io, int shift, int branchy)
{
    NF t0, hit = WK(slab_rows)(n->box[0], r, t, &t0);
    if (branchy == 2) /* any_order= */
        return WK(push_fixed)(n->child, n->perm, hit, t0, (unsigned)NV(mask)(hit), ref, sref, st, sp_io, shift);
    return WK(push_octant)(n->child, n->perm, hit, t0, (unsigned)NV(mask)(hit), ref, sref, st, sp_io, shift,
                           branchy);
}

/* order=octant on boxes grown by the pad q (slab_rows_pad): for walks
 * that must be conservative (instanced/). */
WIDE_INLINE int WK(visit_node_oct_pad)(const KNODE *n, const WK(node_ray) *r, const WK(node_pad) *q, float t,
                                       uint32_t *ref, uint32_t *sref, float *st, int *sp_io, int shift)
{
    NF t0, hit = WK(slab_rows_pad)(n->box[0], r, q, t, &t0);
    return WK(push_octant)(n->child, n->perm, hit, t0, (unsigned)NV(mask)(hit), ref, sref, st, sp_io, shift,
                           0);
}

#if WIDE_NW == 8
/*
 * quant=1: each plane row decoded as org + q * 2^ex (wide_qdecode: the
 * product exact, the sum rounded as the build checked it), then the same
 * slab test; the lanes past the node's count are masked off, and the
 * children pushed by branches (the mask then decides alone).
 */
WIDE_INLINE NF WK(qplane)(const uint8_t *row, float org, float step)
{
    return NV(add)(NV(set1)(org), NV(mul)(f8_from_u8(row), NV(set1)(step)));
}

WIDE_INLINE int WK(visit_node_q)(const wide_qnode8 *n, const WK(node_ray) *r, float t, uint32_t *ref,
                                 uint32_t *sref, float *st, int *sp_io, int shift)
{
    /* node_ray's row offsets count floats of 8-lane rows: here bytes of 8-byte rows */
    const uint8_t *q = n->q[0];
    float sx = wide_qstep(n->ex[0]), sy = wide_qstep(n->ex[1]), sz = wide_qstep(n->ex[2]);
    NF t0, hit = WK(slab_planes)(WK(qplane)(q + r->nx, n->org[0], sx), WK(qplane)(q + r->fx, n->org[0], sx),
                                 WK(qplane)(q + r->ny, n->org[1], sy), WK(qplane)(q + r->fy, n->org[1], sy),
                                 WK(qplane)(q + r->nz, n->org[2], sz), WK(qplane)(q + r->fz, n->org[2], sz),
                                 r, t, &t0);
    unsigned mask = (unsigned)NV(mask)(hit) & ((1u << n->count) - 1u);
    return WK(push_octant)(n->child, n->perm, hit, t0, mask, ref, sref, st, sp_io, shift, 1);
}
#endif

/*
 * The walk of one prepared ray with order=octant (and branchy, quant) from
 * `ref` down, on the ray's running answer (*t, *u, *v, *hit_id): the
 * whole trace from the root, or a subtree the packet kernel hands to single
 * rays (packet.h). Returns 1 when any_hit found a hit or the step
 * bound broke (the caller stops).
 */
WIDE_INLINE int WK(walk_oct)(const bvh_wide *w, const accel_ray_prep *p, uint32_t ref, float *t_io, float *u,
                             float *v, uint32_t *hit_id, uint32_t *steps_io, uint32_t *boxes_io,
                             uint32_t *prims, accel_counters *c, unsigned flags, int any_hit, int branchy,
                             int quant)
{
    (void)quant; /* used by width 8 only */
    /* *p is read field by field, not copied whole: a struct copy loads in
     * vectors what the prep just stored as scalars, and the failed store
     * forwarding cost about a tenth of the kernel's time on primary rays
     * (perf). */
    WK(node_ray) nr;
    WK(node_setup)(&nr, p);
    KL(wide_leaf_ray) lr;
    KL(leaf_setup)(&lr, p);
    const KNODE *nodes = w->nodes;
    /* W slack: a node stores all W lanes at the top of the stack */
    uint32_t sref[WIDE_STACK(WIDE_NW) + WIDE_NW];
    float st[WIDE_STACK(WIDE_NW) + WIDE_NW];
    int sp = 0, shift = 3 * (p->neg[0] | p->neg[1] << 1 | p->neg[2] << 2), stop = 0;
    if (branchy == 2 && w->any_shift >= 0) shift = w->any_shift; /* any_order=area|leaf */
    uint32_t steps = *steps_io, boxes = *boxes_io;
    float t = *t_io;
    for (;;) {
        steps++;
        if (ACCEL_STEP_BOUND_BROKEN(c, steps, w->step_bound)) {
            stop = 1;
            break;
        }
        if (!(ref & WIDE_LEAF)) {
            boxes += WIDE_NW;
#if WIDE_NW == 8
            if (quant) {
                if (WK(visit_node_q)((const wide_qnode8 *)w->nodes + ref, &nr, t, &ref, sref, st, &sp, shift))
                    continue;
            } else
#endif
            if (WK(visit_node_oct)(WK_NODE_AT(w, nodes, ref), &nr, t, &ref, sref, st, &sp, shift, branchy))
                continue;
        } else if (WK(visit_leaf)(w, ref, &lr, p, &t, u, v, hit_id, prims, c != NULL, flags, any_hit)) {
            stop = 1;
            break;
        }
        /* Pop the next entry that can still hold a closer hit. */
        int more = 0;
        while (sp > 0) {
            sp--;
            if (box3_entry_before(st[sp], t)) {
                ref = sref[sp];
                more = 1;
                break;
            }
        }
        if (!more) break;
    }
    *t_io = t, *steps_io = steps, *boxes_io = boxes;
    return stop;
}

/* One prepared ray (p == NULL: a ray that cannot hit) with order=octant. */
WIDE_INLINE void WK(trace_prepped_oct_)(const bvh_wide *w, const accel_ray_prep *pp, void *out,
                                        accel_counters *c, size_t ray_idx, unsigned flags, int any_hit,
                                        int branchy, int quant)
{
    accel_hit hit = accel_hit_miss();
    uint32_t steps = 0, boxes = 0, prims = 0, hit_id = ACCEL_MISS;
    float t = INFINITY;
    if (pp && w->root != WIDE_EMPTY) {
        t = pp->t_far;
        WK(walk_oct)(w, pp, w->root, &t, &hit.u, &hit.v, &hit_id, &steps, &boxes, &prims, c, flags, any_hit,
                     branchy, quant);
    }
    WK(finish)(hit, hit_id, t, out, c, ray_idx, steps, boxes, prims, any_hit);
}

WIDE_INLINE void WK(trace_prepped_oct)(const bvh_wide *w, const accel_ray_prep *pp, void *out,
                                       accel_counters *c, size_t ray_idx, unsigned flags, int any_hit)
{
    WK(trace_prepped_oct_)(w, pp, out, c, ray_idx, flags, any_hit, 0, 0);
}

WIDE_INLINE void WK(trace_ray_oct)(const bvh_wide *w, const accel_ray *ray, void *out, accel_counters *c,
                                   size_t ray_idx, unsigned flags, int any_hit, int branchy, int quant)
{
    accel_ray_prep p;
    int ok = w->root != WIDE_EMPTY && wide_prep_ray(ray, &p);
    WK(trace_prepped_oct_)(w, ok ? &p : NULL, out, c, ray_idx, flags, any_hit, branchy, quant);
}

/* The kernels of the variant tables; ACCEL_V_OPT selects order=octant. */
WIDE_INLINE void WK(wide_closest)(const void *a, const accel_ray *rays, void *out, size_t count,
                                  accel_counters *c, unsigned flags)
{
    if (flags & ACCEL_V_OPT)
        for (size_t i = 0; i < count; i++) WK(trace_ray_oct)(a, &rays[i], out, c, i, flags, 0, 0, 0);
    else
        for (size_t i = 0; i < count; i++) WK(trace_ray)(a, &rays[i], out, c, i, flags, 0);
}

WIDE_INLINE void WK(wide_any)(const void *a, const accel_ray *rays, void *out, size_t count,
                              accel_counters *c, unsigned flags)
{
    if (flags & ACCEL_V_OPT)
        for (size_t i = 0; i < count; i++) WK(trace_ray_oct)(a, &rays[i], out, c, i, flags, 1, 0, 0);
    else
        for (size_t i = 0; i < count; i++) WK(trace_ray)(a, &rays[i], out, c, i, flags, 1);
}

/* The single-ray batches of the octant kernels other than the default:
 * order=branchy, and quant=1 (width 8; its push is branchy's). */
#define WK_OCT_BATCHES(closest, any, branchy, quant)                                                     \
    WIDE_INLINE void WK(closest)(const void *a, const accel_ray *rays, void *out, size_t count,         \
                                 accel_counters *c, unsigned flags)                                    \
    {                                                                                                  \
        for (size_t i = 0; i < count; i++) WK(trace_ray_oct)(a, &rays[i], out, c, i, flags, 0, branchy, quant); \
    }                                                                                                  \
    WIDE_INLINE void WK(any)(const void *a, const accel_ray *rays, void *out, size_t count,            \
                             accel_counters *c, unsigned flags)                                        \
    {                                                                                                  \
        for (size_t i = 0; i < count; i++) WK(trace_ray_oct)(a, &rays[i], out, c, i, flags, 1, branchy, quant); \
    }
WK_OCT_BATCHES(wide_closest_br, wide_any_br, 1, 0)
WK_OCT_BATCHES(wide_closest_q, wide_any_q, 1, 1)
WK_OCT_BATCHES(wide_closest_fix, wide_any_fix, 2, 0) /* any_order= (only its any-hit table is used) */
#undef WK_OCT_BATCHES
#undef WK_NODE_AT
#undef WK_LEAF_AT

#undef WK_CAT_
#undef WK_CAT
#undef WK
#undef WL2_
#undef WL2
#undef KL
#undef NV
#undef NF
#undef KNODE
#undef KBLOCK
#undef WK_JOIN_
#undef WK_JOIN
