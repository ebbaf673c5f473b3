/*
 * packet.h - 64-ray packets over a wide BVH (traverse=packet with
 * width=4|8): the coherent mode for primary and shadow rays.
 * A kernel body (C only): included by the .c files of its folder, not part
 * of the interface a C++ program includes.
 *
 * A template: tables.h includes it once per (WIDE_NW, WIDE_LB) pair
 * after kernel.h for the same pair, whose single-ray kernel it falls
 * back to. It defines wide_pclosest_<NW>_<LB> and wide_pany_<NW>_<LB>.
 *
 * A packet is 64 consecutive rays (8x8 screen tiles in the primary sets),
 * stored as arrays so that one child box is tested against 8 rays per AVX
 * sequence, with exactly the operations of the single-ray slab test lane
 * by lane (a ray accepts exactly the boxes it would accept alone). The
 * packet walks the tree together, each stack entry carrying `first`, the
 * first ray that hit the entry's box (rays before it missed the box, and
 * boxes nest), as in bvh_packet.c (Wald, Boulos and Shirley 2007). At a
 * node:
 *   1. a frustum test bounds, by interval arithmetic over the packet's
 *      origins and reciprocal directions, every ray's slab entry and exit
 *      for all W children at once (one W-lane sequence; Boulos, Wald and
 *      Shirley, UUCS-06-010, 2006; the large-packet traversal of
 *      Fuetterling et al., JCGT 4(4), 2015, tests frusta against wide
 *      nodes the same way). Rounding is monotone, so the bounds enclose
 *      each ray's own float values: a child no ray can hit is dropped;
 *   2. for each remaining child, the groups of 8 rays from `first` on are
 *      tested until one ray hits: it is the child's `first`;
 *   3. the hit children are pushed in the node's octant order (all rays of
 *      a packet share the octant), farthest first.
 * Each entry also carries `last`, the last ray that hit its box (found by
 * scanning the groups from the back), and every scan stops there. At a
 * leaf, the rays `first` to `last` that hit the leaf's box (groups of 8
 * again) run the single-ray leaf test (core/block_test.h) on its blocks, block
 * by block (leaf_by_block: rays sharing their origin and axes share the
 * block's relative vertices). An
 * interior entry whose span last - first is below w->hybrid (spec key
 * hybrid=, 0: never) is not walked as a packet: each ray of the span that
 * hits its box walks the subtree alone (walk_oct of kernel.h, the
 * single-ray loop), the hybrid of Benthin et al. (HPG 2012) with the span
 * as a bound on the active rays instead of an exact count. With
 * any hit, an occluded ray leaves the packet. A packet whose valid rays do
 * not share one octant, or has a zero direction component (no finite
 * interval), is traced ray by ray with the single-ray kernel instead.
 *
 * Counters: steps and box tests per packet visit are charged to the rays
 * from `first` on; packet_box_tests counts the frustum tests (W boxes each).
 */
#ifndef WIDE_NW
#define WIDE_NW 4
#endif
#ifndef WIDE_LB /* alone: the pieces for width 4 (or WIDE_NW), blocks of 4 */
#include "kernel.h"
#endif
#include "node.h"
#include "core/simd.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifndef BVH_WIDE_PACKET_TYPES
#define BVH_WIDE_PACKET_TYPES
#define WP_RAYS 64
#ifndef WP_CULL
#define WP_CULL 8 /* the shared-origin leaf cull from this many rays on (0: never) */
#endif
typedef struct {
    /* Aligned for the vector loads of 8 rays (f8_load, an aligned load):
     * every array below is 64 floats, so each stays on a 32-byte line.
     * UBSan (make sanitize) caught the packet on a 16-byte stack slot. */
    float ox[WP_RAYS] __attribute__((aligned(32)));
    float oy[WP_RAYS], oz[WP_RAYS], ix[WP_RAYS], iy[WP_RAYS], iz[WP_RAYS];
    float tn[WP_RAYS], t[WP_RAYS], u[WP_RAYS], v[WP_RAYS];
    uint32_t id[WP_RAYS], steps[WP_RAYS], prims[WP_RAYS];
    accel_ray_prep p[WP_RAYS];
    uint64_t alive; /* valid rays still looking for a hit */
    int octant;
    int shared; /* every valid ray has the same origin and permuted axes */
    /* The cull's record over the batch: groups tried and culled, leaves
     * passed over while it stays under 1 in 4 (then every 16th tries). */
    uint32_t cull_tries, cull_wins, cull_skips;
    /* With shared: each group's rectangle of shears (centre, half sizes,
     * largest |sx| and |sy|) for the leaf cull, made by packet_rects at the
     * first leaf that culls (rects set). */
    int rects;
    float gcx[WP_RAYS / 8], gcy[WP_RAYS / 8], ghx[WP_RAYS / 8], ghy[WP_RAYS / 8], gxa[WP_RAYS / 8],
        gya[WP_RAYS / 8];
    float o_lo[3], o_hi[3], i_lo[3], i_hi[3], tn_min, t_max;
} wide_packet;

typedef struct {
    uint32_t ref;          /* reference */
    uint32_t first, last;  /* first and last ray that hit its box */
    uint32_t parent, lane; /* where its box is (a leaf's box culls rays) */
} wide_packet_entry;

/* The live rays `first` to `last` as a mask of the packet. */
static inline uint64_t wp_span(uint64_t alive, unsigned first, unsigned last)
{
    uint64_t from = first >= WP_RAYS ? 0 : ~(uint64_t)0 << first;
    uint64_t to = last >= WP_RAYS - 1 ? ~(uint64_t)0 : ((uint64_t)2 << last) - 1;
    return alive & from & to;
}

/* The same as a mask of group g (8 rays). */
static inline unsigned wp_range(uint64_t alive, unsigned g, unsigned first, unsigned last)
{
    return (unsigned)(wp_span(alive, first, last) >> (8 * g)) & 0xFFu;
}
#ifdef __cplusplus
}
#endif

#endif

#define PK_CAT_(a, b, c) a##_##b##_##c
#define PK_CAT(a, b, c) PK_CAT_(a, b, c)
#define PK(name) PK_CAT(name, WIDE_NW, WIDE_LB)
#define PKL__(a, b) a##_##b
#define PKL_(a, b) PKL__(a, b)
#define PKL(name) PKL_(name, WIDE_LB)
#define PV(op) WIDE_V(WIDE_NW, op)
#define PF WIDE_T(WIDE_NW)
#define PK_JOIN_(a, b) a##b
#define PK_JOIN(a, b) PK_JOIN_(a, b)
#define PNODE PK_JOIN(wide_node, WIDE_NW)
#define PBLOCK PK_JOIN(wide_block, WIDE_LB)

/* Rays of group g (mask `m` of candidates) that hit child `lane` of a node
 * whose box rows are `rows`: the single-ray slab test on 8 rays at once. */
WIDE_INLINE unsigned PK(group_hits)(const wide_packet *pk, unsigned g, unsigned m, const float *rows,
                                    unsigned lane)
{
    const int o = pk->octant;
    const float nx = rows[(0 + (o & 1)) * WIDE_NW + lane], fx = rows[(1 - (o & 1)) * WIDE_NW + lane];
    const float ny = rows[(2 + (o >> 1 & 1)) * WIDE_NW + lane], fy = rows[(3 - (o >> 1 & 1)) * WIDE_NW + lane];
    const float nz = rows[(4 + (o >> 2 & 1)) * WIDE_NW + lane], fz = rows[(5 - (o >> 2 & 1)) * WIDE_NW + lane];
    const unsigned r = 8 * g;
    f8 ox = f8_load(pk->ox + r), oy = f8_load(pk->oy + r), oz = f8_load(pk->oz + r);
    f8 ix = f8_load(pk->ix + r), iy = f8_load(pk->iy + r), iz = f8_load(pk->iz + r);
    f8 t0 = f8_max(f8_mul(f8_sub(f8_set1(nx), ox), ix), f8_load(pk->tn + r));
    t0 = f8_max(f8_mul(f8_sub(f8_set1(ny), oy), iy), t0);
    t0 = f8_max(f8_mul(f8_sub(f8_set1(nz), oz), iz), t0);
    f8 t1 = f8_min(f8_mul(f8_sub(f8_set1(fx), ox), ix), f8_load(pk->t + r));
    t1 = f8_min(f8_mul(f8_sub(f8_set1(fy), oy), iy), t1);
    t1 = f8_min(f8_mul(f8_sub(f8_set1(fz), oz), iz), t1);
    f8 far = f8_add(t1, f8_mul(f8_abs(t1), f8_set1(ACCEL_SLAB_PAD)));
    return (unsigned)f8_mask(f8_le(t0, far)) & m;
}

/*
 * The same test for rays of several octants, each lane's box grown by its
 * own ray's pad: group_hits's operations lane by lane, the near plane of
 * each lane picked by the sign of its reciprocal (hi where negative) and
 * the box grown first (lo - pad, hi + pad). The rays' origins, reciprocals
 * and ranges are 8 floats each at ox..iz, tn (near), tf (far); pad 8
 * floats or NULL. Returns the hit lanes as a mask vector, their entry
 * distances in *t0_out. For instanced/'s packets (a walk in each
 * instance's object space, per-ray pads); group_hits stays as it was, so
 * bvh/wide's own packets compile as before.
 */
WIDE_INLINE f8 PK(group_slab_mixed)(const float *ox_, const float *oy_, const float *oz_, const float *ix_,
                                    const float *iy_, const float *iz_, const float *tn, const float *tf,
                                    const float *pad, const float *rows, unsigned lane, f8 *t0_out)
{
    const float *o3[3] = {ox_, oy_, oz_}, *i3[3] = {ix_, iy_, iz_};
    f8 t0 = f8_load(tn), t1 = f8_load(tf);
    for (int a = 0; a < 3; a++) {
        f8 lo = f8_set1(rows[(2 * a) * WIDE_NW + lane]), hi = f8_set1(rows[(2 * a + 1) * WIDE_NW + lane]);
        if (pad) {
            f8 p = f8_load(pad);
            lo = f8_sub(lo, p), hi = f8_add(hi, p);
        }
        f8 iv = f8_load(i3[a]), ov = f8_load(o3[a]);
        f8 nr = f8_blend(lo, hi, iv), fr = f8_blend(hi, lo, iv);
        t0 = f8_max(f8_mul(f8_sub(nr, ov), iv), t0);
        t1 = f8_min(f8_mul(f8_sub(fr, ov), iv), t1);
    }
    f8 far = f8_add(t1, f8_mul(f8_abs(t1), f8_set1(ACCEL_SLAB_PAD)));
    *t0_out = t0;
    return f8_le(t0, far);
}

/* The first ray of `first`..`last` that hits the child, or WP_RAYS. */
WIDE_INLINE unsigned PK(first_hit)(const wide_packet *pk, unsigned first, unsigned last, const float *rows,
                                   unsigned lane, uint32_t *tests, unsigned *group_mask)
{
    for (unsigned g = first / 8; g <= last / 8; g++) {
        unsigned m = wp_range(pk->alive, g, first, last);
        if (!m) continue;
        (*tests)++;
        unsigned h = PK(group_hits)(pk, g, m, rows, lane);
        if (h) {
            *group_mask = h;
            return 8 * g + (unsigned)__builtin_ctz(h);
        }
    }
    return WP_RAYS;
}

/* The last ray of `first`..`last` that hits the child, given `first`, the
 * first that does, and the hits of its group (first_hit's group_mask). */
WIDE_INLINE unsigned PK(last_hit)(const wide_packet *pk, unsigned first, unsigned last, const float *rows,
                                  unsigned lane, uint32_t *tests, unsigned group_mask)
{
    for (unsigned g = last / 8; g > first / 8; g--) {
        unsigned m = wp_range(pk->alive, g, first, last);
        if (!m) continue;
        (*tests)++;
        unsigned h = PK(group_hits)(pk, g, m, rows, lane);
        if (h) return 8 * g + 31u - (unsigned)__builtin_clz(h);
    }
    return 8 * (first / 8) + 31u - (unsigned)__builtin_clz(group_mask);
}

/* Children that some ray may hit, by interval arithmetic (see above). */
/* The same for any set of rays of one octant o: origins within [o_lo,
 * o_hi], reciprocals within [i_lo, i_hi], ranges within [tn_min, t_max]
 * (per axis), every box grown by pad on every side when padded (the near
 * plane moved by -pad where the octant's direction is positive, +pad where
 * negative, the far plane the other way: lo - pad and hi + pad in float).
 * bvh/wide's own packets pass padded = 0, a constant: nothing is added to
 * their loop; instanced/'s packets pass their largest pad. */
WIDE_INLINE unsigned PK(frustum_rows)(int o, const float *o_lo, const float *o_hi, const float *i_lo,
                                      const float *i_hi, float tn_min, float t_max, const float *rows,
                                      float pad, int padded)
{
    PF t0 = PV(set1)(tn_min), t1 = PV(set1)(t_max);
    for (int a = 0; a < 3; a++) {
        int neg = o >> a & 1;
        PF nr = PV(load)(rows + (2 * a + neg) * WIDE_NW), fr = PV(load)(rows + (2 * a + 1 - neg) * WIDE_NW);
        if (padded) {
            PF q = PV(set1)(neg ? pad : -pad);
            nr = PV(add)(nr, q), fr = PV(sub)(fr, q);
        }
        PF olo = PV(set1)(o_lo[a]), ohi = PV(set1)(o_hi[a]);
        PF ilo = PV(set1)(i_lo[a]), ihi = PV(set1)(i_hi[a]);
        PF d0 = PV(sub)(nr, ohi), d1 = PV(sub)(nr, olo), e0 = PV(sub)(fr, ohi), e1 = PV(sub)(fr, olo);
        PF lo = PV(min)(PV(min)(PV(mul)(d0, ilo), PV(mul)(d0, ihi)), PV(min)(PV(mul)(d1, ilo), PV(mul)(d1, ihi)));
        PF hi = PV(max)(PV(max)(PV(mul)(e0, ilo), PV(mul)(e0, ihi)), PV(max)(PV(mul)(e1, ilo), PV(mul)(e1, ihi)));
        t0 = PV(max)(lo, t0);
        t1 = PV(min)(hi, t1);
    }
    PF far = PV(add)(t1, PV(mul)(PV(abs)(t1), PV(set1)(ACCEL_SLAB_PAD)));
    return (unsigned)PV(mask)(PV(le)(t0, far));
}

WIDE_INLINE unsigned PK(frustum)(const wide_packet *pk, const float *rows)
{
    return PK(frustum_rows)(pk->octant, pk->o_lo, pk->o_hi, pk->i_lo, pk->i_hi, pk->tn_min, pk->t_max, rows,
                            0.0f, 0);
}

/* Loads rays [0, n) into the packet; returns 0 when the packet cannot be
 * traced as one (mixed octants or a zero direction component). */
WIDE_INLINE int PK(packet_load)(wide_packet *pk, const bvh_wide *w, const accel_ray *rays, unsigned n)
{
    pk->alive = 0;
    pk->octant = -1;
    pk->shared = 1;
    int ok = 1;
    for (unsigned r = 0; r < WP_RAYS; r++) {
        accel_ray_prep *p = &pk->p[r];
        int valid = r < n && w->root != WIDE_EMPTY && wide_prep_ray(&rays[r], p);
        pk->id[r] = ACCEL_MISS, pk->u[r] = pk->v[r] = 0.0f, pk->steps[r] = pk->prims[r] = 0;
        if (!valid) { /* dead: an empty t range misses every box */
            pk->ox[r] = pk->oy[r] = pk->oz[r] = 0.0f, pk->ix[r] = pk->iy[r] = pk->iz[r] = 1.0f;
            pk->tn[r] = INFINITY, pk->t[r] = -INFINITY;
            continue;
        }
        pk->ox[r] = p->org.x, pk->oy[r] = p->org.y, pk->oz[r] = p->org.z;
        pk->ix[r] = p->inv_dir.x, pk->iy[r] = p->inv_dir.y, pk->iz[r] = p->inv_dir.z;
        pk->tn[r] = p->t_near, pk->t[r] = p->t_far;
        int oct = p->neg[0] | p->neg[1] << 1 | p->neg[2] << 2;
        const float o3[3] = {p->org.x, p->org.y, p->org.z}, i3[3] = {p->inv_dir.x, p->inv_dir.y, p->inv_dir.z};
        if (pk->alive) {
            pk->shared &= accel_prep_same_frame(p, &pk->p[__builtin_ctzll(pk->alive)]);
        } else {
            pk->octant = oct;
            for (int a = 0; a < 3; a++) pk->o_lo[a] = pk->o_hi[a] = o3[a], pk->i_lo[a] = pk->i_hi[a] = i3[a];
            pk->tn_min = p->t_near, pk->t_max = p->t_far;
        }
        ok &= oct == pk->octant && isfinite(i3[0]) && isfinite(i3[1]) && isfinite(i3[2]);
        for (int a = 0; a < 3; a++) {
            pk->o_lo[a] = minf(pk->o_lo[a], o3[a]), pk->o_hi[a] = maxf(pk->o_hi[a], o3[a]);
            pk->i_lo[a] = minf(pk->i_lo[a], i3[a]), pk->i_hi[a] = maxf(pk->i_hi[a], i3[a]);
        }
        pk->tn_min = minf(pk->tn_min, p->t_near), pk->t_max = maxf(pk->t_max, p->t_far);
        pk->alive |= (uint64_t)1 << r;
    }
    pk->rects = 0;
    return ok;
}

/* With shared: each group's rectangle of shear constants as centre and
 * half sizes, rounded up so that it holds every valid ray's (sx, sy)
 * (aff_cull_rect, core/block_test.h). Made at the first leaf that culls. */
WIDE_INLINE void PK(packet_rects)(wide_packet *pk)
{
    for (unsigned g = 0; g < WP_RAYS / 8; g++) {
        float xl = INFINITY, xh = -INFINITY, yl = INFINITY, yh = -INFINITY;
        for (unsigned m = (unsigned)(pk->alive >> (8 * g)) & 0xFFu; m; m &= m - 1) {
            const accel_ray_prep *p = &pk->p[8 * g + (unsigned)__builtin_ctz(m)];
            xl = minf(xl, p->sx), xh = maxf(xh, p->sx), yl = minf(yl, p->sy), yh = maxf(yh, p->sy);
        }
        float cx = 0.5f * (xl + xh), cy = 0.5f * (yl + yh);
        pk->gcx[g] = cx, pk->gcy[g] = cy;
        pk->ghx[g] = maxf(xh - cx, cx - xl) * (1.0f + 0x1p-20f) + 0x1p-100f;
        pk->ghy[g] = maxf(yh - cy, cy - yl) * (1.0f + 0x1p-20f) + 0x1p-100f;
        pk->gxa[g] = maxf(fabsf(xl), fabsf(xh)), pk->gya[g] = maxf(fabsf(yl), fabsf(yh));
    }
    pk->rects = 1;
}

/* Charges one visit to the rays `first` to `last`. */
WIDE_INLINE void PK(charge)(wide_packet *pk, unsigned first, unsigned last)
{
    uint64_t m = wp_span(pk->alive, first, last);
    while (m) {
        pk->steps[__builtin_ctzll(m)]++;
        m &= m - 1;
    }
}

/* Charges a block's distinct primitives to the rays of mask m (a block the
 * leaf cull answered for them is tested all the same). */
WIDE_INLINE void PK(charge_prims)(wide_packet *pk, const PBLOCK *blk, uint64_t m)
{
    uint32_t n = 1;
    for (int l = 1; l < WIDE_LB; l++) n += blk->id[l] != blk->id[l - 1];
    for (; m; m &= m - 1) pk->prims[__builtin_ctzll(m)] += n;
}

/* Ray r of the packet against one block: with q, whose relative vertices
 * and magnitudes are *q (the shared origin's), else by leaf_block. With
 * any hit, a ray that hits leaves the packet and *rays. */
WIDE_INLINE void PK(ray_block)(wide_packet *pk, unsigned r, const PBLOCK *blk, const PKL(wide_leaf_rel) *q,
                               uint32_t tri_count, accel_counters *c, int naive, int has_spheres, int any_hit,
                               uint64_t *rays)
{
    if (c) {
        pk->prims[r]++;
        for (int l = 1; l < WIDE_LB; l++) pk->prims[r] += blk->id[l] != blk->id[l - 1];
    }
    PKL(wide_leaf_ray) lr;
    PKL(leaf_setup)(&lr, &pk->p[r]);
    int hit = q ? PKL(leaf_block_rel)(blk, q, &lr, 1, &pk->p[r], &pk->t[r], &pk->u[r], &pk->v[r], &pk->id[r],
                                      tri_count, has_spheres, any_hit)
                : PKL(leaf_block)(blk, &lr, &pk->p[r], &pk->t[r], &pk->u[r], &pk->v[r], &pk->id[r], tri_count,
                                  naive, has_spheres, any_hit);
    if (hit && any_hit) {
        pk->id[r] = 0;
        pk->alive &= ~((uint64_t)1 << r);
        *rays &= ~((uint64_t)1 << r);
    }
}

/*
 * The leaf cull of a packet whose rays share their origin and axes: the
 * rays of `rays` whose group's rectangle of shears surely misses every lane
 * of the block (aff_cull_rect, leaf.h: lanes the exact test misses for
 * each of them) skip it; returns the others. A separate function, so that
 * the leaf loop around it compiles as it did without it. Measured on its
 * own in bvh/README.md: it pays where a packet's rays miss whole blocks
 * (large or long triangles), and on fine meshes, where one group in 15 to
 * 40 is culled, the record kept in the packet (cull_tries, cull_wins) turns
 * it off but for every 16th leaf.
 */
static __attribute__((noinline)) uint64_t PK(leaf_cull)(wide_packet *pk, const PKL(wide_leaf_rel) *q,
                                                      const PBLOCK *blk, uint64_t rays, accel_counters *c)
{
    if (!pk->rects) PK(packet_rects)(pk);
    PKL(wide_leaf_aff) f;
    PKL(leaf_aff)(q, &f);
    for (unsigned g = 0; g < WP_RAYS / 8; g++) {
        uint64_t gm = rays & ((uint64_t)0xFF << (8 * g));
        if (!gm) continue;
        pk->cull_tries++;
        if (PKL(aff_cull_rect)(&f, pk->gcx[g], pk->gcy[g], pk->ghx[g], pk->ghy[g], pk->gxa[g], pk->gya[g]) ==
            (1 << WIDE_LB) - 1) {
            pk->cull_wins++;
            if (c) PK(charge_prims)(pk, blk, gm);
            rays &= ~gm;
        }
    }
    return rays;
}

/*
 * A leaf for the packet: the rays `first` to `last` that hit its box
 * (prow, lane: its parent's box row, or NULL at the root) test its blocks
 * block by block, every ray in turn, instead of ray by ray. When the rays
 * share their origin and permuted axes (pk->shared: the primary rays of a
 * pinhole camera), each block's vertices relative to the origin and their
 * magnitudes (leaf_rel, the part of the test that depends on the ray only
 * through them) are computed once for all of them. Every ray still tests
 * the blocks in their order with its own t. Its primitive is the
 * single-ray kernel's; its t, u, v are too but for rare near-ties, where
 * the watertight test's float or double step (core/prim.h) depends on
 * what the ray tested before. Measured (2026-12-05, armadillo, 786k
 * primaries, hybrid=0 against the single kernel, AVX2 and AVX-512 alike):
 * 1611 rays differ in t (at most 4 float steps) and 963 in u, v only
 * (at most 4e-5), none in the primitive; with block=4, 244 and 180; the 4-wide packets (block=4) and
 * hybrid=64 on none. The leaf cull is not the cause (WP_CULL=0: the
 * same counts). Which visit differs is not known yet.
 */
WIDE_INLINE void PK(leaf_by_block)(wide_packet *pk, const wide_packet_entry *e, const PBLOCK *blk,
                                   uint32_t nb, const float *prow, uint32_t tri_count, accel_counters *c,
                                   int naive, int has_spheres, int any_hit, uint32_t *tests)
{
    uint64_t rays = 0;
    for (unsigned g = e->first / 8; g <= e->last / 8; g++) {
        unsigned m = wp_range(pk->alive, g, e->first, e->last);
        if (!m) continue;
        if (prow) {
            (*tests)++;
            m = PK(group_hits)(pk, g, m, prow, e->lane);
        }
        rays |= (uint64_t)m << (8 * g);
    }
    if (!rays) return;
    if (pk->shared && !naive) {
        PKL(wide_leaf_ray) lr0; /* the origin and axes of every ray */
        PKL(leaf_setup)(&lr0, &pk->p[__builtin_ctzll(rays)]);
        for (uint32_t k = 0; k < nb && rays; k++) {
            PKL(wide_leaf_rel) q;
            PKL(leaf_rel)(&blk[k], &lr0, &q);
            PKL(leaf_rel_mags)(&q);
            uint64_t todo = rays;
            if (!has_spheres && WP_CULL != 0 && __builtin_popcountll(rays) >= WP_CULL &&
                (pk->cull_tries < 64 || 4 * pk->cull_wins >= pk->cull_tries ||
                 (++pk->cull_skips & 15) == 0))
                todo = PK(leaf_cull)(pk, &q, &blk[k], todo, c);
            for (uint64_t m = todo; m; m &= m - 1)
                PK(ray_block)(pk, (unsigned)__builtin_ctzll(m), &blk[k], &q, tri_count, c, 0, has_spheres,
                              any_hit, &rays);
        }
        return;
    }
    for (uint32_t k = 0; k < nb && rays; k++)
        for (uint64_t m = rays; m; m &= m - 1)
            PK(ray_block)(pk, (unsigned)__builtin_ctzll(m), &blk[k], NULL, tri_count, c, naive, has_spheres,
                          any_hit, &rays);
}

/* The packet from the root to every ray's answer. */
WIDE_INLINE void PK(packet_trace)(wide_packet *pk, const bvh_wide *w, accel_counters *c, unsigned flags,
                                  int any_hit)
{
    const int naive = (flags & ACCEL_V_NAIVE) != 0, has_spheres = (flags & ACCEL_V_SPHERES) != 0;
    const PNODE *nodes = w->nodes;
    const PBLOCK *blocks = w->blocks;
    const int shift = 3 * pk->octant;
    wide_packet_entry stack[WIDE_STACK(WIDE_NW)];
    int sp = 0;
    uint32_t visits = 0, tests = 0;
    uint64_t single_boxes = 0;
    if (!pk->alive) return;
    stack[sp++] = (wide_packet_entry){w->root, (uint32_t)__builtin_ctzll(pk->alive),
                                      63u - (uint32_t)__builtin_clzll(pk->alive), WIDE_EMPTY, 0};
    const uint32_t hybrid = (uint32_t)w->hybrid;
    while (sp > 0 && pk->alive) {
        wide_packet_entry e = stack[--sp];
        const int single = !(e.ref & WIDE_LEAF) && e.last - e.first < hybrid;
        if (!single) {
            visits++;
            if (ACCEL_STEP_BOUND_BROKEN(c, visits, w->step_bound)) break;
            if (c) PK(charge)(pk, e.first, e.last);
        }
        if (!(e.ref & WIDE_LEAF) && !single) {
            const PNODE *n = &nodes[e.ref];
            const float *rows = n->box[0];
            unsigned cand = PK(frustum)(pk, rows);
            if (c) c->packet_box_tests += WIDE_NW;
            uint32_t first_of[WIDE_NW], last_of[WIDE_NW];
            unsigned hit = 0;
            while (cand) {
                unsigned l = (unsigned)__builtin_ctz(cand);
                cand &= cand - 1;
                unsigned gm = 0;
                first_of[l] = PK(first_hit)(pk, e.first, e.last, rows, l, &tests, &gm);
                if (first_of[l] < WP_RAYS) {
                    hit |= 1u << l;
                    last_of[l] = PK(last_hit)(pk, first_of[l], e.last, rows, l, &tests, gm);
                }
            }
            for (int rank = WIDE_NW - 1; rank >= 0; rank--) { /* farthest first */
                unsigned l = (n->perm[rank] >> shift) & 7u;
                if (hit >> l & 1u)
                    stack[sp++] = (wide_packet_entry){n->child[l], first_of[l], last_of[l], e.ref, l};
            }
            continue;
        }
        if (!single) {
            PK(leaf_by_block)(pk, &e, &blocks[wide_leaf_first(e.ref)], wide_leaf_blocks(e.ref),
                              e.parent == WIDE_EMPTY ? NULL : nodes[e.parent].box[0], w->tri_count, c, naive,
                              has_spheres, any_hit, &tests);
            continue;
        }
        /* A subtree handed to single rays: each ray `first` to `last` that
         * hits its box walks it alone. */
        const float *prow = e.parent == WIDE_EMPTY ? NULL : nodes[e.parent].box[0];
        for (unsigned g = e.first / 8; g <= e.last / 8; g++) {
            unsigned m = wp_range(pk->alive, g, e.first, e.last);
            if (!m) continue;
            if (prow) {
                tests++;
                m = PK(group_hits)(pk, g, m, prow, e.lane);
            }
            for (; m; m &= m - 1) {
                unsigned r = 8 * g + (unsigned)__builtin_ctz(m);
                uint32_t boxes = 0;
                if (PK_CAT(walk_oct, WIDE_NW, WIDE_LB)(w, &pk->p[r], e.ref, &pk->t[r], &pk->u[r], &pk->v[r],
                                                       &pk->id[r], &pk->steps[r], &boxes, &pk->prims[r], c, flags,
                                                       any_hit, 0, 0) &&
                    any_hit && pk->id[r] != ACCEL_MISS) /* occluded (not a broken step bound) */
                    pk->alive &= ~((uint64_t)1 << r);
                single_boxes += boxes;
            }
        }
    }
    if (c) c->box_tests += 8 * (uint64_t)tests + single_boxes;
}

WIDE_INLINE void PK(packet_batch)(const void *a, const accel_ray *rays, void *out, size_t count,
                                  accel_counters *c, unsigned flags, int any_hit)
{
    const bvh_wide *w = a;
    wide_packet pk;
    pk.cull_tries = pk.cull_wins = pk.cull_skips = 0;
    for (size_t base = 0; base < count; base += WP_RAYS) {
        unsigned n = count - base < WP_RAYS ? (unsigned)(count - base) : WP_RAYS;
        if (!PK(packet_load)(&pk, w, rays + base, n)) { /* ray by ray, already prepared */
            for (unsigned r = 0; r < n; r++)
                PK_CAT(trace_prepped_oct, WIDE_NW, WIDE_LB)(w, pk.alive >> r & 1 ? &pk.p[r] : NULL, out, c,
                                                            base + r, flags, any_hit);
            continue;
        }
        PK(packet_trace)(&pk, w, c, flags, any_hit);
        for (unsigned r = 0; r < n; r++) {
            accel_hit h = accel_hit_miss();
            if (pk.id[r] != ACCEL_MISS) h.t = pk.t[r], h.prim = pk.id[r], h.u = pk.u[r], h.v = pk.v[r];
            PK_CAT(finish, WIDE_NW, WIDE_LB)(h, pk.id[r], pk.t[r], out, c, base + r, pk.steps[r], 0,
                                             pk.prims[r], any_hit);
        }
    }
}

WIDE_INLINE void PK(wide_pclosest)(const void *a, const accel_ray *rays, void *out, size_t count,
                                   accel_counters *c, unsigned flags)
{
    PK(packet_batch)(a, rays, out, count, c, flags, 0);
}

WIDE_INLINE void PK(wide_pany)(const void *a, const accel_ray *rays, void *out, size_t count,
                               accel_counters *c, unsigned flags)
{
    PK(packet_batch)(a, rays, out, count, c, flags, 1);
}

#undef PK_CAT_
#undef PK_CAT
#undef PK
#undef PKL__
#undef PKL_
#undef PKL
#undef PV
#undef PF
#undef PK_JOIN_
#undef PK_JOIN
#undef PNODE
#undef PBLOCK
