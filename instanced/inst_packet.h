/*
 * inst_packet.h - the packets of the `instanced` kind (traverse=packet),
 * internal to instanced/: the packet and its views (inst_packet.c walks
 * them, inst_packet_rays.c fills them), and the 8-ray pieces both use:
 * the slab test of 8 rays against one child box and the frustum test of
 * a node (bvh/wide/packet.h's, with the pads), the entry cull at a pop,
 * the affine triangle cull of rays that share their origin, and the
 * watertight test's float path on 8 rays. The triangle pieces compute,
 * lane by lane, the very float operations of the single-ray code they
 * stand for (inst_ray.h, core/prim.h), so the packets' answers are the
 * single-ray walk's, bit for bit. A kernel body (C only): it instantiates
 * bvh/wide/'s templates, and is not part of an interface a C++ program
 * includes.
 */
#ifndef INSTANCED_INST_PACKET_H
#define INSTANCED_INST_PACKET_H

#include <math.h>

#include "core/prim.h"
#include "inst_impl.h"
#include "inst_ray.h"
/* bvh/wide/'s packet pieces (8 wide; its blocks of 8 come along unused). */
#define WIDE_NW 8
#define WIDE_LB 8
#include "core/block_test.h"
#include "bvh/wide/kernel.h"
#include "bvh/wide/packet.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { IP_RAYS = 64 };
#define IP_STACK ((INST_WIDE - 1) * BVH_MAX_DEPTH + 1)
#define IP_BIT(r) ((uint64_t)1 << (r))

/* The packet's rays as one walk sees them: the world rays at the top
 * level, one instance's object-space rays (from its box entry) below.
 * Rows of 64 floats, each 32-byte aligned for 8-lane loads. */
typedef struct {
    float ox[IP_RAYS] __attribute__((aligned(32)));
    float oy[IP_RAYS], oz[IP_RAYS], ix[IP_RAYS], iy[IP_RAYS], iz[IP_RAYS];
    float lo[IP_RAYS], hi[IP_RAYS]; /* the range in the walk's parameter */
    float pad[IP_RAYS];             /* each ray's box growth (padded) */
    double shift[IP_RAYS];          /* walk parameter = t - shift */
    float slack;                    /* relative widening of hi (inst_walk_hi) */
    int padded;
    /* The frustum (frustum != 0: one octant, finite reciprocals). */
    int frustum, octant;
    float o_lo[3], o_hi[3], i_lo[3], i_hi[3], t_lo, t_hi, pad_max;
} ip_view;

typedef struct {
    /* The prepared world rays (accel_prep_ray) as rows: origins, inverse
     * directions and t_near are the top view's ox..iz and lo; ip_prep
     * puts one back together for the scalar tests. */
    ip_view top;                /* world rays: shift 0, slack 0, no pad */
    float dx[IP_RAYS] __attribute__((aligned(32))); /* directions */
    float dy[IP_RAYS] __attribute__((aligned(32)));
    float dz[IP_RAYS] __attribute__((aligned(32)));
    float sx[IP_RAYS] __attribute__((aligned(32))); /* shears (shared: the affine cull) */
    float sy[IP_RAYS] __attribute__((aligned(32)));
    float sz[IP_RAYS] __attribute__((aligned(32)));
    float tf[IP_RAYS] __attribute__((aligned(32))); /* their t_far: the whole range's end */
    int32_t kx[IP_RAYS] __attribute__((aligned(32))); /* their permuted axes */
    int32_t ky[IP_RAYS] __attribute__((aligned(32)));
    int32_t kz[IP_RAYS] __attribute__((aligned(32)));
    float t[IP_RAYS], u[IP_RAYS], v[IP_RAYS];
    uint32_t prim[IP_RAYS];
    uint64_t live;              /* valid rays still looking (any hit: until one) */
    int any;
    int shared;                 /* every valid ray has the same origin and axes */
    uint32_t top_steps[IP_RAYS], bottom_steps[IP_RAYS], boxes[IP_RAYS], prims[IP_RAYS];
} ip_packet;

/* Ray r's prepared form, as accel_prep_ray made it (ip_load). */
INST_INLINE void ip_prep(const ip_packet *pk, unsigned r, accel_ray_prep *p)
{
    p->org = v3(pk->top.ox[r], pk->top.oy[r], pk->top.oz[r]);
    p->dir = v3(pk->dx[r], pk->dy[r], pk->dz[r]);
    p->inv_dir = v3(pk->top.ix[r], pk->top.iy[r], pk->top.iz[r]);
    p->neg[0] = signbit(pk->dx[r]) != 0, p->neg[1] = signbit(pk->dy[r]) != 0;
    p->neg[2] = signbit(pk->dz[r]) != 0;
    p->kx = pk->kx[r], p->ky = pk->ky[r], p->kz = pk->kz[r];
    p->sx = pk->sx[r], p->sy = pk->sy[r], p->sz = pk->sz[r];
    p->t_near = pk->top.lo[r], p->t_far = pk->tf[r];
}

typedef struct {
    uint32_t ref;
    float entry; /* smallest entry distance of the rays in mask */
    uint64_t mask;
} ip_entry;

/* ---- 8 rays against one child box ------------------------------------------------ */

#if INST_WIDE_AVX
/* The lanes of bits m (8 rays) as an AVX mask. */
INST_INLINE __m256 ip_lanes(unsigned m)
{
    return _mm256_castsi256_ps(_mm256_cmpgt_epi32(
        _mm256_and_si256(_mm256_set1_epi32((int)m), _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128)),
        _mm256_setzero_si256()));
}
#else
INST_INLINE f8 ip_lanes(unsigned m)
{
    f8 r;
    for (int i = 0; i < 8; i++) r.v[i] = f8_float_(m >> i & 1 ? 0xFFFFFFFFu : 0u);
    return r;
}
#endif

/* Rays of group g (candidates m) whose range meets child c's box grown by
 * their pads; *entry lowered to the smallest entry among them (lane-wise:
 * the caller reduces it). bvh/wide/packet.h's 8-ray slab test, each lane
 * with its own octant and pad. */
typedef f8 ip_entries;
INST_INLINE unsigned ip_group(const ip_view *v, const wide_node8 *n, unsigned c, unsigned g,
                              unsigned m, ip_entries *entry)
{
    const unsigned r = 8 * g;
    f8 t0, in = group_slab_mixed_8_8(v->ox + r, v->oy + r, v->oz + r, v->ix + r, v->iy + r, v->iz + r,
                                     v->lo + r, v->hi + r, v->padded ? v->pad + r : NULL, n->box[0], c, &t0);
    unsigned h = (unsigned)f8_mask(in) & m;
    if (h) *entry = f8_min(*entry, f8_blend(f8_set1(INFINITY), t0, ip_lanes(h)));
    return h;
}

/* The smallest of the lanes ip_group lowered. */
INST_INLINE float ip_entry_min(ip_entries e)
{
#if INST_WIDE_AVX
    __m128 x = _mm_min_ps(_mm256_castps256_ps128(e), _mm256_extractf128_ps(e, 1));
    x = _mm_min_ps(x, _mm_movehl_ps(x, x));
    x = _mm_min_ss(x, _mm_shuffle_ps(x, x, 1));
    return _mm_cvtss_f32(x);
#else
    return f8_hmin(e);
#endif
}

/* Slots of node n that hold a child. */
INST_INLINE unsigned ip_children(const wide_node8 *n)
{
#if INST_WIDE_AVX
    __m256i none = _mm256_cmpeq_epi32(_mm256_load_si256((const __m256i *)n->child),
                                      _mm256_set1_epi32((int)WIDE_EMPTY));
    return ~(unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(none)) & 0xFFu;
#else
    unsigned cand = 0;
    for (unsigned c = 0; c < INST_WIDE; c++) cand |= (unsigned)(n->child[c] != WIDE_EMPTY) << c;
    return cand;
#endif
}

/* Children some ray of the view may hit (the frustum test, see above):
 * bvh/wide/packet.h's, with every box grown by the view's largest pad. */
INST_INLINE unsigned ip_frustum(const ip_view *v, const wide_node8 *n)
{
#if INST_WIDE_AVX
    return frustum_rows_8_8(v->octant, v->o_lo, v->o_hi, v->i_lo, v->i_hi, v->t_lo, v->t_hi, n->box[0],
                            v->pad_max, 1);
#else
    (void)v, (void)n;
    return 0xFFu;
#endif
}

/* The rays of m whose range still reaches an entry at `entry`
 * (box3_entry_before on each ray's current end). */
INST_INLINE uint64_t ip_still(const ip_view *v, uint64_t m, float entry)
{
    uint64_t keep = 0;
    for (unsigned g = 0; g < IP_RAYS / 8; g++) {
        unsigned gm = (unsigned)(m >> (8 * g)) & 0xFFu;
        if (!gm) continue;
#if INST_WIDE_AVX
        __m256 hi = _mm256_load_ps(v->hi + 8 * g);
        __m256 lim = _mm256_add_ps(
            hi, _mm256_mul_ps(_mm256_andnot_ps(_mm256_set1_ps(-0.0f), hi), _mm256_set1_ps(ACCEL_SLAB_PAD)));
        gm &= (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(_mm256_set1_ps(entry), lim, _CMP_LE_OQ));
#else
        for (unsigned k = gm; k; k &= k - 1) {
            unsigned l = (unsigned)__builtin_ctz(k);
            if (!box3_entry_before(entry, v->hi[8 * g + l])) gm &= ~(1u << l);
        }
#endif
        keep |= (uint64_t)gm << (8 * g);
    }
    return keep;
}

/* ---- leaves ----------------------------------------------------------------------- */

/* The rays of m (sharing their origin and axes) that the affine cull of
 * *f does not rule out: accel_tri_aff_miss on 8 rays at once, the same
 * float operations lane by lane. */
INST_INLINE uint64_t ip_aff_keep(const ip_packet *pk, const accel_tri_aff *f, uint64_t m)
{
#if INST_WIDE_AVX
    uint64_t keep = 0;
    const __m256 sign = _mm256_set1_ps(-0.0f);
    for (unsigned g = 0; g < IP_RAYS / 8; g++) {
        unsigned gm = (unsigned)(m >> (8 * g)) & 0xFFu;
        if (!gm) continue;
        __m256 sx = _mm256_load_ps(pk->sx + 8 * g), sy = _mm256_load_ps(pk->sy + 8 * g);
        __m256 sxa = _mm256_andnot_ps(sign, sx), sya = _mm256_andnot_ps(sign, sy);
        __m256 neg = _mm256_setzero_ps(), pos = _mm256_setzero_ps();
        for (int k = 0; k < 3; k++) {
            __m256 e = _mm256_add_ps(_mm256_add_ps(_mm256_set1_ps(f->e0[k]), _mm256_mul_ps(sx, _mm256_set1_ps(f->e1[k]))),
                                     _mm256_mul_ps(sy, _mm256_set1_ps(f->e2[k])));
            __m256 mg = _mm256_add_ps(_mm256_add_ps(_mm256_set1_ps(f->m0[k]), _mm256_mul_ps(sxa, _mm256_set1_ps(f->m1[k]))),
                                      _mm256_mul_ps(sya, _mm256_set1_ps(f->m2[k])));
            mg = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(ACCEL_AFF_REL), mg), _mm256_set1_ps(ACCEL_AFF_ABS));
            neg = _mm256_or_ps(neg, _mm256_cmp_ps(e, _mm256_xor_ps(mg, sign), _CMP_LT_OQ));
            pos = _mm256_or_ps(pos, _mm256_cmp_ps(e, mg, _CMP_GT_OQ));
        }
        unsigned miss = (unsigned)_mm256_movemask_ps(_mm256_and_ps(neg, pos));
        keep |= (uint64_t)(gm & ~miss) << (8 * g);
    }
    return keep;
#else
    uint64_t keep = m;
    for (uint64_t k = m; k; k &= k - 1) {
        unsigned r = (unsigned)__builtin_ctzll(k);
        if (accel_tri_aff_miss(f, pk->sx[r], pk->sy[r])) keep &= ~IP_BIT(r);
    }
    return keep;
#endif
}

#if INST_WIDE_AVX
/* A triangle's vertices relative to 8 rays' origins, on each ray's
 * permuted axes (x: kx, y: ky, z: kz), as accel_tri_watertight_impl
 * (core/prim.h) names them: vertex j's are x[j], y[j], z[j]. */
typedef struct {
    __m256 x[3], y[3], z[3];
} ip_rel8;

/* ... computed per lane for the rays of group g (v - org, then each
 * lane's axes picked by blends), as the scalar test computes them. */
INST_INLINE void ip_rel8_lanes(const ip_packet *pk, const float *tri, unsigned g, ip_rel8 *q)
{
    const unsigned r = 8 * g;
    const __m256i one = _mm256_set1_epi32(1), two = _mm256_set1_epi32(2);
    __m256 o[3] = {_mm256_load_ps(pk->top.ox + r), _mm256_load_ps(pk->top.oy + r),
                   _mm256_load_ps(pk->top.oz + r)};
    __m256i kx = _mm256_load_si256((const __m256i *)(pk->kx + r));
    __m256i ky = _mm256_load_si256((const __m256i *)(pk->ky + r));
    __m256i kz = _mm256_load_si256((const __m256i *)(pk->kz + r));
    __m256 x1 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kx, one)), x2 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kx, two));
    __m256 y1 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(ky, one)), y2 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(ky, two));
    __m256 z1 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kz, one)), z2 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kz, two));
    for (int j = 0; j < 3; j++) {
        __m256 e0 = _mm256_sub_ps(_mm256_set1_ps(tri[3 * j]), o[0]);
        __m256 e1 = _mm256_sub_ps(_mm256_set1_ps(tri[3 * j + 1]), o[1]);
        __m256 e2 = _mm256_sub_ps(_mm256_set1_ps(tri[3 * j + 2]), o[2]);
        q->x[j] = _mm256_blendv_ps(_mm256_blendv_ps(e0, e1, x1), e2, x2);
        q->y[j] = _mm256_blendv_ps(_mm256_blendv_ps(e0, e1, y1), e2, y2);
        q->z[j] = _mm256_blendv_ps(_mm256_blendv_ps(e0, e1, z1), e2, z2);
    }
}

/* ... or the same for every lane (rays that share origin and axes). */
INST_INLINE void ip_rel8_shared(const accel_tri_rel *t, ip_rel8 *q)
{
    q->x[0] = _mm256_set1_ps(t->ax_), q->y[0] = _mm256_set1_ps(t->ay_), q->z[0] = _mm256_set1_ps(t->az_);
    q->x[1] = _mm256_set1_ps(t->bx_), q->y[1] = _mm256_set1_ps(t->by_), q->z[1] = _mm256_set1_ps(t->bz_);
    q->x[2] = _mm256_set1_ps(t->cx_), q->y[2] = _mm256_set1_ps(t->cy_), q->z[2] = _mm256_set1_ps(t->cz_);
}

/* 8 rays (group g, candidates gm) against one triangle: the watertight
 * test's path that decides in float (accel_tri_watertight_impl, core/prim.h),
 * on the whole range [t_near, t_far] of each ray as inst_decide gives it,
 * each operation the scalar test's on the same operands in the same
 * order (no fused multiply-add). Lane by lane: `miss` where the scalar test
 * returns 0 on that path, `hit` with t, u, v where it returns a hit on it,
 * `scalar` where it would go on (a second, tighter bound on the edge
 * functions, or its double-precision fallback): those rays run the scalar
 * test. So every ray gets the scalar test's answer, bit for bit. */
typedef struct {
    unsigned hit, scalar;
    float t[8], u[8], v[8];
} ip_tri8_out;

INST_INLINE void ip_tri8(const ip_packet *pk, const ip_rel8 *q, unsigned g, unsigned gm, ip_tri8_out *out)
{
    const unsigned r = 8 * g;
    const __m256 sign = _mm256_set1_ps(-0.0f), filt = _mm256_set1_ps(ACCEL_EDGE_FILTER);
    const __m256 tiny = _mm256_set1_ps(ACCEL_EDGE_TINY), zero = _mm256_setzero_ps();
#define IP_ABS(x) _mm256_andnot_ps(sign, (x))
    __m256 sx = _mm256_load_ps(pk->sx + r), sy = _mm256_load_ps(pk->sy + r), sz = _mm256_load_ps(pk->sz + r);
    __m256 sxa = IP_ABS(sx), sya = IP_ABS(sy);
    __m256 px[3], py[3], mx[3], my[3]; /* sheared x, y and the magnitudes M of each vertex */
    for (int j = 0; j < 3; j++) {
        px[j] = _mm256_sub_ps(q->x[j], _mm256_mul_ps(sx, q->z[j]));
        py[j] = _mm256_sub_ps(q->y[j], _mm256_mul_ps(sy, q->z[j]));
        __m256 az = IP_ABS(q->z[j]);
        mx[j] = _mm256_add_ps(IP_ABS(q->x[j]), _mm256_mul_ps(sxa, az));
        my[j] = _mm256_add_ps(IP_ABS(q->y[j]), _mm256_mul_ps(sya, az));
    }
    /* U = cx by - cy bx, V = ax cy - ay cx, W = bx ay - by ax (a, b, c: vertices 0, 1, 2) */
    __m256 U = _mm256_sub_ps(_mm256_mul_ps(px[2], py[1]), _mm256_mul_ps(py[2], px[1]));
    __m256 V = _mm256_sub_ps(_mm256_mul_ps(px[0], py[2]), _mm256_mul_ps(py[0], px[2]));
    __m256 W = _mm256_sub_ps(_mm256_mul_ps(px[1], py[0]), _mm256_mul_ps(py[1], px[0]));
    __m256 eu = _mm256_add_ps(_mm256_mul_ps(filt, _mm256_add_ps(_mm256_mul_ps(mx[2], my[1]), _mm256_mul_ps(my[2], mx[1]))), tiny);
    __m256 ev = _mm256_add_ps(_mm256_mul_ps(filt, _mm256_add_ps(_mm256_mul_ps(mx[0], my[2]), _mm256_mul_ps(my[0], mx[2]))), tiny);
    __m256 ew = _mm256_add_ps(_mm256_mul_ps(filt, _mm256_add_ps(_mm256_mul_ps(mx[1], my[0]), _mm256_mul_ps(my[1], mx[0]))), tiny);
    __m256 neg = _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(U, _mm256_xor_ps(eu, sign), _CMP_LT_OQ),
                                           _mm256_cmp_ps(V, _mm256_xor_ps(ev, sign), _CMP_LT_OQ)),
                              _mm256_cmp_ps(W, _mm256_xor_ps(ew, sign), _CMP_LT_OQ));
    __m256 pos = _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(U, eu, _CMP_GT_OQ), _mm256_cmp_ps(V, ev, _CMP_GT_OQ)),
                              _mm256_cmp_ps(W, ew, _CMP_GT_OQ));
    unsigned miss = (unsigned)_mm256_movemask_ps(_mm256_and_ps(neg, pos));
    __m256 cert = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(IP_ABS(U), eu, _CMP_GT_OQ),
                                              _mm256_cmp_ps(IP_ABS(V), ev, _CMP_GT_OQ)),
                                _mm256_cmp_ps(IP_ABS(W), ew, _CMP_GT_OQ));
    unsigned sure = (unsigned)_mm256_movemask_ps(cert) & gm & ~miss;
    out->scalar = gm & ~miss & ~sure; /* uncertain signs: the tighter bound, maybe the fallback */
    out->hit = 0;
    if (!sure) return;
    __m256 det = _mm256_add_ps(_mm256_add_ps(U, V), W);
    __m256 za = _mm256_mul_ps(sz, q->z[0]), zb = _mm256_mul_ps(sz, q->z[1]), zc = _mm256_mul_ps(sz, q->z[2]);
    __m256 T = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(U, za), _mm256_mul_ps(V, zb)), _mm256_mul_ps(W, zc));
    __m256 sgn = _mm256_blendv_ps(_mm256_set1_ps(1.0f), _mm256_set1_ps(-1.0f), _mm256_cmp_ps(det, zero, _CMP_LT_OQ));
    det = _mm256_mul_ps(det, sgn);
    T = _mm256_mul_ps(T, sgn);
    unsigned small = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(det, _mm256_set1_ps(0x1p-126f), _CMP_NGE_UQ));
    za = IP_ABS(za), zb = IP_ABS(zb), zc = IP_ABS(zc);
    __m256 et = _mm256_mul_ps(filt, _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(IP_ABS(U), za), _mm256_mul_ps(IP_ABS(V), zb)),
                                                  _mm256_mul_ps(IP_ABS(W), zc)));
    et = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_add_ps(et, _mm256_mul_ps(eu, za)), _mm256_mul_ps(ev, zb)),
                                     _mm256_mul_ps(ew, zc)), tiny);
    __m256 ed = _mm256_add_ps(_mm256_add_ps(eu, ev), ew);
    __m256 dlo = _mm256_sub_ps(det, ed), dhi = _mm256_add_ps(det, ed);
    __m256 tn = _mm256_load_ps(pk->top.lo + r), tf = _mm256_load_ps(pk->tf + r);
    __m256 np = _mm256_cmp_ps(tn, zero, _CMP_GE_OQ), fp = _mm256_cmp_ps(tf, zero, _CMP_GE_OQ);
    __m256 lo_out = _mm256_mul_ps(tn, _mm256_blendv_ps(dhi, dlo, np)), lo_in = _mm256_mul_ps(tn, _mm256_blendv_ps(dlo, dhi, np));
    __m256 hi_out = _mm256_mul_ps(tf, _mm256_blendv_ps(dlo, dhi, fp)), hi_in = _mm256_mul_ps(tf, _mm256_blendv_ps(dhi, dlo, fp));
    __m256 outside = _mm256_or_ps(_mm256_cmp_ps(T, _mm256_sub_ps(lo_out, et), _CMP_LT_OQ),
                                  _mm256_cmp_ps(T, _mm256_add_ps(hi_out, et), _CMP_GT_OQ));
    __m256 inside = _mm256_and_ps(_mm256_cmp_ps(T, _mm256_add_ps(lo_in, et), _CMP_GT_OQ),
                                  _mm256_cmp_ps(T, _mm256_sub_ps(hi_in, et), _CMP_LT_OQ));
    unsigned out_m = (unsigned)_mm256_movemask_ps(outside), in_m = (unsigned)_mm256_movemask_ps(inside);
    out->scalar |= sure & (small | (~out_m & ~in_m));
    out->hit = sure & ~small & ~out_m & in_m;
    if (!out->hit) return;
    __m256 rcp = _mm256_div_ps(_mm256_set1_ps(1.0f), det), tt = _mm256_mul_ps(T, rcp);
    /* accel_tri_imprecise, operation for operation: its hits go on to the
     * scalar test, which sends them to the double test. */
    {
        __m256 e[3], s3 = _mm256_setzero_ps(), pt, one = _mm256_set1_ps(1.0f);
        static const int iu[3][4][2] = {{{2, 1}, {1, 2}, {2, 1}, {1, 2}}, /* U: cx M_by, by M_cx, cy M_bx, bx M_cy */
                                        {{0, 2}, {2, 0}, {0, 2}, {2, 0}}, /* V: ax M_cy, cy M_ax, ay M_cx, cx M_ay */
                                        {{1, 0}, {0, 1}, {1, 0}, {0, 1}}}; /* W: bx M_ay, ay M_bx, by M_ax, ax M_by */
        for (int k = 0; k < 3; k++) {
            const int (*w)[2] = iu[k];
            e[k] = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(IP_ABS(px[w[0][0]]), my[w[0][1]]),
                                                             _mm256_mul_ps(IP_ABS(py[w[1][0]]), mx[w[1][1]])),
                                               _mm256_mul_ps(IP_ABS(py[w[2][0]]), mx[w[2][1]])),
                                 _mm256_mul_ps(IP_ABS(px[w[3][0]]), my[w[3][1]]));
        }
        __m256 zs[3] = {_mm256_mul_ps(sz, q->z[0]), _mm256_mul_ps(sz, q->z[1]), _mm256_mul_ps(sz, q->z[2])};
        __m256 m1 = _mm256_max_ps(IP_ABS(tt), one);
        s3 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(IP_ABS(U), IP_ABS(zs[0])), _mm256_mul_ps(IP_ABS(V), IP_ABS(zs[1]))),
                           _mm256_mul_ps(IP_ABS(W), IP_ABS(zs[2])));
        pt = _mm256_mul_ps(_mm256_set1_ps(4.0f), s3);
        for (int k = 0; k < 3; k++)
            pt = _mm256_add_ps(pt, _mm256_mul_ps(e[k], IP_ABS(_mm256_sub_ps(zs[k], tt))));
        __m256 fine = _mm256_and_ps(
            _mm256_cmp_ps(_mm256_add_ps(_mm256_add_ps(e[0], e[1]), e[2]), _mm256_mul_ps(_mm256_set1_ps(0x1p13f), det), _CMP_LE_OQ),
            _mm256_cmp_ps(pt, _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(0x1p9f), det), m1), _CMP_LE_OQ));
        unsigned coarse = out->hit & ~(unsigned)_mm256_movemask_ps(fine);
        out->hit &= ~coarse;
        out->scalar |= coarse;
        if (!out->hit) return;
    }
    _mm256_storeu_ps(out->t, tt);
    _mm256_storeu_ps(out->u, _mm256_mul_ps(_mm256_mul_ps(V, sgn), rcp));
    _mm256_storeu_ps(out->v, _mm256_mul_ps(_mm256_mul_ps(W, sgn), rcp));
#undef IP_ABS
}
#endif

/* inst_packet_rays.c: rays [0, n) into the packet (the rest of its 64
 * lanes dead); the rays m of the packet in instance it's object space,
 * into the view ov (returns the rays that reach its mesh's padded box,
 * with the frustum's bounds set); the frustum's bounds of a view. */
void ip_load(ip_packet *pk, const accel_ray *rays, unsigned n, int any, int counted);
uint64_t ip_objects(const inst_accel *a, const inst_item *it, const inst_bottom *b, ip_packet *pk,
                    ip_view *ov, uint64_t m, int counted);
void ip_bounds(ip_view *v, uint64_t m);

#ifdef __cplusplus
}
#endif

#endif
