/*
 * block_test.h - one ray against a block (core/block.h) of WIDE_LB (4 or 8)
 * primitives, the one block test of every structure (the wide BVH's leaf
 * blocks, the grids' cell blocks):
 * the watertight test of Woop, Benthin and Wald ("Watertight Ray/Triangle
 * Intersection", JCGT 2(1), 2013) on all lanes at once, with this project's
 * exact fallback.
 * A kernel body (C only): included by the .c files of its folder, not part
 * of the interface a C++ program includes.
 *
 * A template: a kernel unit includes it once per block width, with WIDE_LB
 * defined (4 when included alone). It defines wide_leaf_ray_<LB>,
 * leaf_setup_<LB>() and leaf_block_<LB>().
 *
 * Every lane computes what accel_tri_watertight (core/prim.h) computes,
 * in the same order: the shear, the edge functions U, V, W, their error
 * bounds, the scaled distance T and its bound. Where the target has FMA,
 * each "a - b c" or "a b + c" of those is one fused operation (core/simd.h)
 * where the scalar test rounds twice: 21 vector operations fewer per
 * block. The bounds of ACCEL_EDGE_FILTER count a rounding for the product
 * and one for the sum; a fused step has only the second, so every bound
 * holds as it stands. A lane's U, V, W and T may then differ from the
 * scalar test's in their last bits, never in a decided sign. Each lane
 * then falls in one of three classes, decided as the scalar test decides
 * it:
 *   - sure miss: an edge function is surely negative and another surely
 *     positive, or T lies surely outside [t_near, t] * det;
 *   - sure hit: all edge functions surely of one sign and T surely inside;
 *   - uncertain: anything else, NaN included. These lanes are redone one by
 *     one with accel_tri_fallback, the double-precision test the oracle
 *     itself runs, after the sure hits have lowered t, exactly as the
 *     scalar test would redo them.
 * So a block answers what the scalar test, run on its primitives in turn,
 * would answer: the same hits (t within a few ulps), possibly a different
 * one among primitives hit at the same distance (a tie the FORMATS.md
 * rule accepts).
 * Spheres (lanes with id >= tri_count) go through the scalar sphere test.
 */
#include "core/block.h"
#include "core/simd.h"

#ifndef WIDE_LB
#define WIDE_LB 4
#endif

#define WL_CAT_(a, b) a##_##b
#define WL_CAT(a, b) WL_CAT_(a, b)
#define WL(name) WL_CAT(name, WIDE_LB)
#define LV(op) WIDE_V(WIDE_LB, op)
#define LF WIDE_T(WIDE_LB)
#define LK WIDE_KT(WIDE_LB)
#define KV(op) WIDE_K(WIDE_LB, op)
#define WL_JOIN_(a, b) a##b
#define WL_JOIN(a, b) WL_JOIN_(a, b)
#define LBLOCK WL_JOIN(accel_block, WIDE_LB)

/* Per-ray constants of the leaf test (broadcast once per ray). */
typedef struct {
    LF okx, oky, okz;    /* origin on the permuted axes */
    LF sx, sy, sz;       /* shear constants */
    LF sxa, sya;         /* their magnitudes */
    LF t_near;
    int ofs_x, ofs_y, ofs_z; /* row offsets of kx, ky, kz within a vertex */
} WL(wide_leaf_ray);

WIDE_INLINE void WL(leaf_setup)(WL(wide_leaf_ray) *r, const accel_ray_prep *p)
{
    r->okx = LV(set1)(v3_idx(p->org, p->kx));
    r->oky = LV(set1)(v3_idx(p->org, p->ky));
    r->okz = LV(set1)(v3_idx(p->org, p->kz));
    r->sx = LV(set1)(p->sx), r->sy = LV(set1)(p->sy), r->sz = LV(set1)(p->sz);
    r->sxa = LV(set1)(fabsf(p->sx)), r->sya = LV(set1)(fabsf(p->sy));
    r->t_near = LV(set1)(p->t_near);
    r->ofs_x = p->kx * WIDE_LB, r->ofs_y = p->ky * WIDE_LB, r->ofs_z = p->kz * WIDE_LB;
}

/* Lane `lane` of a block as the 9 (triangle) or 4 (sphere) floats of the
 * scalar tests. */
static inline void WL(lane_gather)(const LBLOCK *blk, int lane, float *out)
{
    for (int vtx = 0; vtx < 3; vtx++)
        for (int axis = 0; axis < 3; axis++) out[3 * vtx + axis] = blk->v[vtx][axis][lane];
}

/* Scalar tests of the lanes in `mask` (fallback triangles, spheres or the
 * naive test), in lane order. Returns 1 when one of them hit. */
static inline __attribute__((always_inline)) int
WL(lanes_scalar)(const LBLOCK *blk, int mask, const accel_ray_prep *p, float *t, float *u, float *v,
                 uint32_t *id, uint32_t tri_count, int naive, int has_spheres, int any_hit)
{
    int hit = 0;
    while (mask) {
        int lane = __builtin_ctz((unsigned)mask);
        mask &= mask - 1;
        float prim[9];
        WL(lane_gather)(blk, lane, prim);
        int h;
        if (has_spheres && blk->id[lane] >= tri_count)
            h = accel_sphere_hit(p, prim, t, u, v);
        else if (naive)
            h = accel_tri_naive(p, prim, t, u, v);
        else
            h = accel_tri_fallback(p, prim, t, u, v);
        if (h) {
            *id = blk->id[lane];
            hit = 1;
            if (any_hit) return 1;
        }
    }
    return hit;
}

/* A block's vertices relative to the ray's origin, on its permuted axes,
 * and their magnitudes: the part of the leaf test that depends on the ray
 * only through its origin and axes, so that rays sharing both (the primary
 * rays of a pinhole camera, in a packet) compute it once per block. */
typedef struct {
    LF ax_, ay_, az_, bx_, by_, bz_, cx_, cy_, cz_;
    LF aax_, aay_, aaz, abx_, aby_, abz, acx_, acy_, acz;
} WL(wide_leaf_rel);

WIDE_INLINE void WL(leaf_rel)(const LBLOCK *blk, const WL(wide_leaf_ray) *r, WL(wide_leaf_rel) *q)
{
    const float *v0 = blk->v[0][0], *v1 = blk->v[1][0], *v2 = blk->v[2][0];
    q->ax_ = LV(sub)(LV(load)(v0 + r->ofs_x), r->okx), q->ay_ = LV(sub)(LV(load)(v0 + r->ofs_y), r->oky);
    q->az_ = LV(sub)(LV(load)(v0 + r->ofs_z), r->okz);
    q->bx_ = LV(sub)(LV(load)(v1 + r->ofs_x), r->okx), q->by_ = LV(sub)(LV(load)(v1 + r->ofs_y), r->oky);
    q->bz_ = LV(sub)(LV(load)(v1 + r->ofs_z), r->okz);
    q->cx_ = LV(sub)(LV(load)(v2 + r->ofs_x), r->okx), q->cy_ = LV(sub)(LV(load)(v2 + r->ofs_y), r->oky);
    q->cz_ = LV(sub)(LV(load)(v2 + r->ofs_z), r->okz);
}

/* The magnitudes of *q, for leaf_block_rel with `mags` set. */
WIDE_INLINE void WL(leaf_rel_mags)(WL(wide_leaf_rel) *q)
{
    q->aax_ = LV(abs)(q->ax_), q->aay_ = LV(abs)(q->ay_), q->aaz = LV(abs)(q->az_);
    q->abx_ = LV(abs)(q->bx_), q->aby_ = LV(abs)(q->by_), q->abz = LV(abs)(q->bz_);
    q->acx_ = LV(abs)(q->cx_), q->acy_ = LV(abs)(q->cy_), q->acz = LV(abs)(q->cz_);
}

/*
 * Culling a block for rays that share an origin (packets of primary rays;
 * the scalar form, with the same margins, is accel_tri_aff in core/prim.h).
 *
 * With the origin and axes fixed, an edge function of the watertight test
 * is affine in the ray's shear (sx, sy): for the edge of vertices P, Q
 * (relative, on the permuted axes),
 *   (px - sx pz)(qy - sy qz) - (py - sy pz)(qx - sx qz)
 *     = (px qy - py qx) + sx (py qz - pz qy) + sy (pz qx - px qz),
 * the sx sy terms cancelling. So one set of coefficients per block gives
 * each edge function for every ray of the packet, and its range over a
 * rectangle of (sx, sy) by interval arithmetic. A lane whose edge functions
 * are surely of mixed signs over the rectangle is missed by every ray whose
 * shear lies in it (the exact test's first rule: mixed signs are a miss).
 *
 * "Surely" is decided with a margin of 2^-16 times the edge function's
 * magnitude, m0 + |sx| m1 + |sy| m2 (the same sums taken of absolute
 * values), plus 2^-120 for underflow: far above what separates these float
 * values from the double test's own (its vertices relative to the origin
 * rounded once in float here, its shear rounded once in float by the ray
 * setup, about 10 roundings of u = 2^-24 in all), and still far below the
 * size of any edge function that decides a miss. A NaN or an infinity
 * anywhere fails every comparison: such a lane is never culled. Culling
 * only lanes the exact test misses leaves every answer as it was, bit for
 * bit: the kernel's float test would have rejected them anyway. Spheres
 * are never culled (the caller leaves them out).
 */
typedef struct {
    LF e0[3], e1[3], e2[3]; /* U, V, W = e0 + sx e1 + sy e2 */
    LF a1[3], a2[3];        /* |e1|, |e2| */
    LF m0[3], m1[3], m2[3]; /* the margin: m0 + |sx| m1 + |sy| m2 (ACCEL_AFF_REL, ACCEL_AFF_ABS in) */
} WL(wide_leaf_aff);

/* The edge (P, Q)'s coefficients into slot k of *f. */
WIDE_INLINE void WL(aff_edge)(WL(wide_leaf_aff) *f, int k, LF px, LF py, LF pz, LF qx, LF qy, LF qz, LF apx,
                              LF apy, LF apz, LF aqx, LF aqy, LF aqz)
{
    const LF rel = LV(set1)(ACCEL_AFF_REL);
    f->e0[k] = LV(fmsub)(px, qy, LV(mul)(py, qx));
    f->e1[k] = LV(fmsub)(py, qz, LV(mul)(pz, qy));
    f->e2[k] = LV(fmsub)(pz, qx, LV(mul)(px, qz));
    f->a1[k] = LV(abs)(f->e1[k]), f->a2[k] = LV(abs)(f->e2[k]);
    f->m0[k] = LV(fmadd)(rel, LV(fmadd)(apx, aqy, LV(mul)(apy, aqx)), LV(set1)(ACCEL_AFF_ABS));
    f->m1[k] = LV(mul)(rel, LV(fmadd)(apy, aqz, LV(mul)(apz, aqy)));
    f->m2[k] = LV(mul)(rel, LV(fmadd)(apz, aqx, LV(mul)(apx, aqz)));
}

/* The coefficients of a block's three edge functions, from leaf_rel and
 * leaf_rel_mags (U: C, B; V: A, C; W: B, A, as leaf_block_rel). */
WIDE_INLINE void WL(leaf_aff)(const WL(wide_leaf_rel) *q, WL(wide_leaf_aff) *f)
{
    WL(aff_edge)(f, 0, q->cx_, q->cy_, q->cz_, q->bx_, q->by_, q->bz_, q->acx_, q->acy_, q->acz, q->abx_,
                 q->aby_, q->abz);
    WL(aff_edge)(f, 1, q->ax_, q->ay_, q->az_, q->cx_, q->cy_, q->cz_, q->aax_, q->aay_, q->aaz, q->acx_,
                 q->acy_, q->acz);
    WL(aff_edge)(f, 2, q->bx_, q->by_, q->bz_, q->ax_, q->ay_, q->az_, q->abx_, q->aby_, q->abz, q->aax_,
                 q->aay_, q->aaz);
}

/*
 * Lanes surely missed by every ray whose shear lies in the rectangle
 * centred at (cx, cy) with half sizes (hx, hy), and |sx| <= xa, |sy| <= ya
 * in it (a bit per lane). Over the rectangle an edge function lies within
 * e0 + cx e1 + cy e2 +- (hx |e1| + hy |e2|); the caller rounds the half
 * sizes up (packet.h), and the margin takes the few roundings of
 * these sums with room to spare.
 */
WIDE_INLINE int WL(aff_cull_rect)(const WL(wide_leaf_aff) *f, float cx, float cy, float hx, float hy, float xa,
                                  float ya)
{
    const LF x = LV(set1)(cx), y = LV(set1)(cy), vhx = LV(set1)(hx), vhy = LV(set1)(hy);
    const LF vxa = LV(set1)(xa), vya = LV(set1)(ya), zero = LV(set1)(0.0f);
    LF neg = LV(lt)(zero, zero), pos = neg; /* all false */
    for (int k = 0; k < 3; k++) {
        LF e = LV(fmadd)(y, f->e2[k], LV(fmadd)(x, f->e1[k], f->e0[k]));
        LF d = LV(fmadd)(vya, f->m2[k], LV(fmadd)(vxa, f->m1[k], f->m0[k]));
        d = LV(fmadd)(vhy, f->a2[k], LV(fmadd)(vhx, f->a1[k], d));
        neg = LV(or)(neg, LV(lt)(e, LV(sub)(zero, d)));
        pos = LV(or)(pos, LV(gt)(e, d));
    }
    return LV(mask)(LV(and)(neg, pos));
}

/*
 * Intersects one block whose relative vertices are *q (leaf_rel of the
 * same origin and axes as r; with `mags`, a constant, their magnitudes
 * too, from leaf_rel_mags). On a hit closer than *t (within [t_near,
 * *t]) updates *t, *u, *v, *id and returns 1; with any_hit it returns 1 at
 * the first hit found. The watertight test (leaf_block takes tri=naive
 * apart); has_spheres is a constant in every copy.
 *
 * About 130 lines on purpose: the steps of the watertight test (shear,
 * edge functions and their error bounds, det and T with theirs, the
 * nearest sure hit, the uncertain lanes in double, the spheres) share
 * their vector masks, and this one forced-inline body is what every
 * kernel copy's leaf loop runs; split, a copy's code would depend on
 * what the compiler chooses to inline.
 */
static inline __attribute__((always_inline)) int
WL(leaf_block_rel)(const LBLOCK *blk, const WL(wide_leaf_rel) *q, const WL(wide_leaf_ray) *r,
                   int mags, const accel_ray_prep *p, float *t, float *u, float *v, uint32_t *id,
                   uint32_t tri_count, int has_spheres, int any_hit)
{
    const int all = (1 << WIDE_LB) - 1;
    int spheres = 0;
    if (has_spheres)
        for (int lane = 0; lane < WIDE_LB; lane++) spheres |= (blk->id[lane] >= tri_count) << lane;

    const LF ax_ = q->ax_, ay_ = q->ay_, az_ = q->az_, bx_ = q->bx_, by_ = q->by_, bz_ = q->bz_;
    const LF cx_ = q->cx_, cy_ = q->cy_, cz_ = q->cz_;
    /* Shear and the edge functions, fused where the target has FMA (the
     * header: each fused step rounds once where the bound counts two). */
    LF ax = LV(fnmadd)(r->sx, az_, ax_), ay = LV(fnmadd)(r->sy, az_, ay_);
    LF bx = LV(fnmadd)(r->sx, bz_, bx_), by = LV(fnmadd)(r->sy, bz_, by_);
    LF cx = LV(fnmadd)(r->sx, cz_, cx_), cy = LV(fnmadd)(r->sy, cz_, cy_);
    LF U = LV(fmsub)(cx, by, LV(mul)(cy, bx));
    LF V = LV(fmsub)(ax, cy, LV(mul)(ay, cx));
    LF W = LV(fmsub)(bx, ay, LV(mul)(by, ax));
    /* Their error bounds (ACCEL_EDGE_FILTER, as in accel_tri_watertight;
     * 16u leaves room for the bound's own rounding, fused or not). */
    LF aaz = mags ? q->aaz : LV(abs)(az_), abz = mags ? q->abz : LV(abs)(bz_);
    LF acz = mags ? q->acz : LV(abs)(cz_);
    LF max_ = LV(fmadd)(r->sxa, aaz, mags ? q->aax_ : LV(abs)(ax_));
    LF may_ = LV(fmadd)(r->sya, aaz, mags ? q->aay_ : LV(abs)(ay_));
    LF mbx_ = LV(fmadd)(r->sxa, abz, mags ? q->abx_ : LV(abs)(bx_));
    LF mby_ = LV(fmadd)(r->sya, abz, mags ? q->aby_ : LV(abs)(by_));
    LF mcx_ = LV(fmadd)(r->sxa, acz, mags ? q->acx_ : LV(abs)(cx_));
    LF mcy_ = LV(fmadd)(r->sya, acz, mags ? q->acy_ : LV(abs)(cy_));
    /* The cheap bound first: 16u (M_cx M_by + M_cy M_bx), valid too (the
     * sheared coordinates are at most about M). Lanes it leaves uncertain
     * get the tight bound of ACCEL_EDGE_FILTER (accel_tri_watertight)
     * before the double test; the smaller of the two is kept. */
    LF filter = LV(set1)(ACCEL_EDGE_FILTER);
    LF tiny = LV(set1)(ACCEL_EDGE_TINY); /* underflow (core/prim.h) */
    LF eu = LV(fmadd)(filter, LV(fmadd)(mcx_, mby_, LV(mul)(mcy_, mbx_)), tiny);
    LF ev = LV(fmadd)(filter, LV(fmadd)(max_, mcy_, LV(mul)(may_, mcx_)), tiny);
    LF ew = LV(fmadd)(filter, LV(fmadd)(mbx_, may_, LV(mul)(mby_, max_)), tiny);
    /* The classes as lane masks (core/simd.h's kN: mask registers in the
     * AVX-512 units, vector masks elsewhere) and as bits. */
    LK sure_neg, sure_pos, edge_ok;
    int miss, ok, unsure;
    for (int pass = 0;; pass++) {
        LF zero = LV(set1)(0.0f);
        LF neu = LV(sub)(zero, eu), nev = LV(sub)(zero, ev), new_ = LV(sub)(zero, ew);
        /* Ordered compares: a NaN lane is neither, so uncertain. |U| > eu
         * is "surely negative or surely positive". */
        LK nu = LV(ltk)(U, neu), nv = LV(ltk)(V, nev), nw = LV(ltk)(W, new_);
        LK pu = LV(gtk)(U, eu), pv = LV(gtk)(V, ev), pw = LV(gtk)(W, ew);
        sure_neg = KV(or)(KV(or)(nu, nv), nw);
        sure_pos = KV(or)(KV(or)(pu, pv), pw);
        edge_ok = KV(and)(KV(and)(KV(or)(nu, pu), KV(or)(nv, pv)), KV(or)(nw, pw));
        miss = KV(bits)(KV(and)(sure_neg, sure_pos)) | spheres;
        ok = KV(bits)(edge_ok) & ~miss;
        unsure = all & ~miss & ~KV(bits)(edge_ok);
        if (!unsure || pass) break;
        LF f2 = LV(set1)(ACCEL_EDGE_FILTER2 / ACCEL_EDGE_FILTER);
        LF aax = LV(abs)(ax), aay = LV(abs)(ay), abx = LV(abs)(bx), aby = LV(abs)(by);
        LF acx = LV(abs)(cx), acy = LV(abs)(cy);
        LF tu = LV(fmadd)(filter, LV(add)(LV(fmadd)(acx, mby_, LV(mul)(aby, mcx_)),
                                          LV(fmadd)(acy, mbx_, LV(mul)(abx, mcy_))),
                          LV(fmadd)(f2, eu, tiny));
        LF tv = LV(fmadd)(filter, LV(add)(LV(fmadd)(aax, mcy_, LV(mul)(acy, max_)),
                                          LV(fmadd)(aay, mcx_, LV(mul)(acx, may_))),
                          LV(fmadd)(f2, ev, tiny));
        LF tw = LV(fmadd)(filter, LV(add)(LV(fmadd)(abx, may_, LV(mul)(aay, mbx_)),
                                          LV(fmadd)(aby, max_, LV(mul)(aax, mby_))),
                          LV(fmadd)(f2, ew, tiny));
        /* The smaller on the uncertain lanes only, as the scalar test does
         * (a NaN bound stays NaN: the lane stays uncertain). */
        LK keep = KV(or)(KV(and)(sure_neg, sure_pos), edge_ok);
        eu = LV(blendk)(LV(min)(tu, eu), eu, keep);
        ev = LV(blendk)(LV(min)(tv, ev), ev, keep);
        ew = LV(blendk)(LV(min)(tw, ew), ew, keep);
    }
    int hit = 0;
    if (ok) {
        /* det and T, and T's bound; compared against [t_near, t] * |det|. */
        LF det = LV(add)(LV(add)(U, V), W);
        LF zaz = LV(mul)(r->sz, az_), zbz = LV(mul)(r->sz, bz_), zcz = LV(mul)(r->sz, cz_);
        LF T = LV(fmadd)(U, zaz, LV(fmadd)(V, zbz, LV(mul)(W, zcz)));
        LF sgn = LV(signs)(det);
        det = LV(xor)(det, sgn);
        T = LV(xor)(T, sgn);
        LF za = LV(abs)(zaz), zb = LV(abs)(zbz), zc = LV(abs)(zcz);
        LF sum = LV(fmadd)(LV(abs)(U), za, LV(fmadd)(LV(abs)(V), zb, LV(mul)(LV(abs)(W), zc)));
        LF et = LV(fmadd)(filter, sum, LV(fmadd)(eu, za, LV(fmadd)(ev, zb, LV(fmadd)(ew, zc, tiny))));
        /* det's own error moves the range ends (accel_tri_watertight). */
        LF ed = LV(add)(LV(add)(eu, ev), ew), dlo = LV(sub)(det, ed), dhi = LV(add)(det, ed);
        int near_pos = p->t_near >= 0.0f, far_pos = *t >= 0.0f;
        LF tc = LV(set1)(*t);
        LF lo_out = LV(mul)(r->t_near, near_pos ? dlo : dhi), lo_in = LV(mul)(r->t_near, near_pos ? dhi : dlo);
        LF hi_out = LV(mul)(tc, far_pos ? dhi : dlo), hi_in = LV(mul)(tc, far_pos ? dlo : dhi);
        /* A subnormal det has no finite reciprocal and underflows the
         * range products: such lanes are neither in nor out, so the double
         * test decides them (accel_tri_watertight). */
        LK det_ok = LV(lek)(LV(set1)(0x1p-126f), det);
        LK t_out = KV(and)(det_ok, KV(or)(LV(ltk)(T, LV(sub)(lo_out, et)), LV(gtk)(T, LV(add)(hi_out, et))));
        LK t_in = KV(and)(det_ok, KV(and)(LV(gtk)(T, LV(add)(lo_in, et)), LV(ltk)(T, LV(sub)(hi_in, et))));
        /* The same classes as lane masks (sure_v) and as bits. */
        LK sure_v = KV(and)(KV(andnot)(t_out, KV(andnot)(KV(and)(sure_neg, sure_pos), edge_ok)), t_in);
        int live = ok & ~KV(bits)(t_out);
        int sure = live & KV(bits)(t_in);
        unsure |= live & ~sure;
        LF rcp = LV(set1)(1.0f), tt = rcp;
        if (sure && !any_hit) {
            /* Sure hits whose t, u, v float cannot give to FORMATS.md's
             * tolerance go to the double test too (accel_tri_imprecise,
             * core/prim.h: the same bounds, lane by lane). */
            rcp = LV(div)(LV(set1)(1.0f), det);
            tt = LV(mul)(T, rcp);
            LF aax = LV(abs)(ax), aay = LV(abs)(ay), abx = LV(abs)(bx), aby = LV(abs)(by);
            LF acx = LV(abs)(cx), acy = LV(abs)(cy);
            LF e_u = LV(fmadd)(acx, mby_, LV(fmadd)(aby, mcx_, LV(fmadd)(acy, mbx_, LV(mul)(abx, mcy_))));
            LF e_v = LV(fmadd)(aax, mcy_, LV(fmadd)(acy, max_, LV(fmadd)(aay, mcx_, LV(mul)(acx, may_))));
            LF e_w = LV(fmadd)(abx, may_, LV(fmadd)(aay, mbx_, LV(fmadd)(aby, max_, LV(mul)(aax, mby_))));
            LF m1 = LV(max)(LV(abs)(tt), LV(set1)(1.0f));
            LF prec_t = LV(fmadd)(LV(set1)(4.0f), sum,
                                  LV(fmadd)(e_u, LV(abs)(LV(sub)(zaz, tt)),
                                            LV(fmadd)(e_v, LV(abs)(LV(sub)(zbz, tt)),
                                                      LV(mul)(e_w, LV(abs)(LV(sub)(zcz, tt))))));
            LK fine = KV(and)(LV(lek)(LV(add)(LV(add)(e_u, e_v), e_w), LV(mul)(LV(set1)(0x1p13f), det)),
                              LV(lek)(prec_t, LV(mul)(LV(mul)(LV(set1)(0x1p9f), det), m1)));
            int coarse = sure & ~KV(bits)(fine);
            if (coarse) {
                sure &= ~coarse;
                unsure |= coarse;
                sure_v = KV(and)(sure_v, fine);
            }
        }
        if (sure) {
            if (any_hit) return 1;
            /* The nearest sure hit; ties go to the lowest lane. */
            LF masked = LV(blendk)(LV(set1)(INFINITY), tt, sure_v);
            if (has_spheres && spheres) {
                float lane_t[WIDE_LB] __attribute__((aligned(32)));
                LV(store)(lane_t, masked);
                for (int lane = 0; lane < WIDE_LB; lane++)
                    if (spheres >> lane & 1) lane_t[lane] = INFINITY;
                masked = LV(load)(lane_t);
            }
            float t_min = LV(hmin)(masked);
            int lane = __builtin_ctz((unsigned)(KV(bits)(LV(lek)(masked, LV(set1)(t_min))) & sure));
            float lane_u[WIDE_LB] __attribute__((aligned(32))), lane_v[WIDE_LB] __attribute__((aligned(32)));
            LV(store)(lane_u, LV(mul)(LV(xor)(V, sgn), rcp));
            LV(store)(lane_v, LV(mul)(LV(xor)(W, sgn), rcp));
            *t = t_min;
            *u = lane_u[lane];
            *v = lane_v[lane];
            *id = blk->id[lane];
            hit = 1;
        }
    }
    /* Uncertain lanes in double, then the spheres, with the t found so far. */
    if (unsure && WL(lanes_scalar)(blk, unsure, p, t, u, v, id, tri_count, 0, 0, any_hit)) {
        if (any_hit) return 1;
        hit = 1;
    }
    if (has_spheres && spheres && WL(lanes_scalar)(blk, spheres, p, t, u, v, id, tri_count, 0, 1, any_hit))
        hit = 1;
    return hit;
}

/* One block against one ray: leaf_rel, then leaf_block_rel. */
static inline __attribute__((always_inline)) int
WL(leaf_block)(const LBLOCK *blk, const WL(wide_leaf_ray) *r, const accel_ray_prep *p, float *t,
               float *u, float *v, uint32_t *id, uint32_t tri_count, int naive, int has_spheres,
               int any_hit)
{
    if (naive)
        return WL(lanes_scalar)(blk, (1 << WIDE_LB) - 1, p, t, u, v, id, tri_count, 1, has_spheres, any_hit);
    WL(wide_leaf_rel) q;
    WL(leaf_rel)(blk, r, &q);
    return WL(leaf_block_rel)(blk, &q, r, 0, p, t, u, v, id, tri_count, has_spheres, any_hit);
}

#undef WL_CAT_
#undef WL_CAT
#undef WL
#undef LV
#undef LF
#undef LK
#undef KV
#undef LBLOCK
#undef WL_JOIN_
#undef WL_JOIN
