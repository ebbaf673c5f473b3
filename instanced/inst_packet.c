/*
 * inst_packet.c - traverse=packet: the `instanced` kind's rays walked in
 * packets of 64 through both 8-wide levels (top=bvh, bottom=bvh, width=8).
 *
 * The packet walks the top level's wide nodes together: one child box is
 * tested against 8 rays per AVX sequence, lane by lane the very float
 * operations of the single-ray walk's inst_wide_hits (the near and far
 * planes picked per lane by the sign of the reciprocal direction, so rays
 * of several octants may share a packet). At an instance, every ray of the
 * packet that reached it goes to object space as the single-ray walk takes
 * it (inst_ray.h: the same double transform, pad, clip and float ray from
 * the box entry), and the rays that reach the mesh's padded box walk its
 * wide bottom level as a packet, each lane's box grown by its own ray's
 * pad. At a bottom leaf each world triangle is computed once
 * (inst_xform_tri) and decided for every ray of the packet that reached
 * the leaf, with inst_decide on the ray's whole range: so a ray gets the
 * answer the single-ray walk gives it, bit for bit, whatever its packet's
 * other rays (README.md: every walk that reaches the triangles names the
 * same triangle with the same bits).
 *
 * A stack entry holds the mask of the rays that hit its box and the
 * smallest of their entry distances; at the pop, rays whose closest hit
 * now lies before that entry leave the entry. When the walk's rays share
 * one octant (per level: a rotation may split an octant), a frustum test
 * first bounds every ray's slab interval for the node's 8 children at
 * once by interval arithmetic over the rays' origins, reciprocal
 * directions, ranges and pads (the largest), as bvh/wide/packet.h does
 * (Boulos, Wald and Shirley, UUCS-06-010, 2006): a child no ray can hit
 * is dropped before its per-ray tests.
 *
 * Rays reach the packets through core/coherence.h: any ray order, and
 * groups of 64 with no coherence go to the single-ray walk instead.
 */
#include <math.h>
#include <string.h>

#include "core/coherence.h"
#include "core/prim.h"
#include "core/variant.h"
#include "inst_impl.h"
#include "inst_ray.h"
#include "inst_wide.h"

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
    ip_view top;                /* world rays: shift 0, slack 0, no pad */
    accel_ray_prep p[IP_RAYS];  /* world rays for the triangle tests */
    float sx[IP_RAYS] __attribute__((aligned(32))); /* their shears (shared: the affine cull) */
    float sy[IP_RAYS] __attribute__((aligned(32)));
    int32_t kx[IP_RAYS] __attribute__((aligned(32))); /* their permuted axes */
    int32_t ky[IP_RAYS] __attribute__((aligned(32)));
    int32_t kz[IP_RAYS] __attribute__((aligned(32)));
    double o[IP_RAYS][3], d[IP_RAYS][3];
    float t[IP_RAYS], u[IP_RAYS], v[IP_RAYS];
    uint32_t prim[IP_RAYS];
    uint64_t live;              /* valid rays still looking (any hit: until one) */
    int any;
    int shared;                 /* every valid ray has the same origin and axes */
    uint32_t top_steps[IP_RAYS], bottom_steps[IP_RAYS], boxes[IP_RAYS], prims[IP_RAYS];
} ip_packet;

typedef struct {
    uint32_t ref;
    float entry; /* smallest entry distance of the rays in mask */
    uint64_t mask;
} ip_entry;

/* ---- 8 rays against one child box ------------------------------------------------ */

/* Rays of group g (candidates m) whose range meets child c's box grown by
 * their pads; *entry lowered to the smallest entry among them (lane-wise:
 * the caller reduces it). Lane by lane inst_wide_hits (inst_wide.h) on
 * that ray. */
#if INST_WIDE_AVX
typedef __m256 ip_entries;
#else
typedef float ip_entries;
#endif
INST_INLINE unsigned ip_group(const ip_view *v, const inst_wnode *n, unsigned c, unsigned g,
                              unsigned m, ip_entries *entry)
{
    const unsigned r = 8 * g;
#if INST_WIDE_AVX
    const float *org[3] = {v->ox + r, v->oy + r, v->oz + r};
    const float *inv[3] = {v->ix + r, v->iy + r, v->iz + r};
    __m256 t0 = _mm256_load_ps(v->lo + r), t1 = _mm256_load_ps(v->hi + r);
    __m256 p = _mm256_load_ps(v->pad + r);
    for (int a = 0; a < 3; a++) {
        __m256 lo = _mm256_set1_ps(n->box[2 * a][c]), hi = _mm256_set1_ps(n->box[2 * a + 1][c]);
        if (v->padded) lo = _mm256_sub_ps(lo, p), hi = _mm256_add_ps(hi, p);
        __m256 iv = _mm256_load_ps(inv[a]), ov = _mm256_load_ps(org[a]);
        /* The near plane is hi where the direction is negative. */
        __m256 nr = _mm256_blendv_ps(lo, hi, iv), fr = _mm256_blendv_ps(hi, lo, iv);
        t0 = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(nr, ov), iv), t0);
        t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(fr, ov), iv), t1);
    }
    __m256 abs1 = _mm256_andnot_ps(_mm256_set1_ps(-0.0f), t1);
    __m256 lim = _mm256_add_ps(t1, _mm256_mul_ps(abs1, _mm256_set1_ps(ACCEL_SLAB_PAD)));
    __m256 in = _mm256_cmp_ps(t0, lim, _CMP_LE_OQ);
    unsigned h = (unsigned)_mm256_movemask_ps(in) & m;
    if (h) {
        __m256i bits = _mm256_and_si256(_mm256_set1_epi32((int)h), _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128));
        __m256 sel = _mm256_castsi256_ps(_mm256_cmpgt_epi32(bits, _mm256_setzero_si256()));
        *entry = _mm256_min_ps(*entry, _mm256_blendv_ps(_mm256_set1_ps(INFINITY), t0, sel));
    }
    return h;
#else
    unsigned h = 0;
    for (unsigned k = m; k; k &= k - 1) {
        unsigned l = (unsigned)__builtin_ctz(k), q = r + l;
        float lo[3] = {n->box[0][c], n->box[2][c], n->box[4][c]};
        float hi[3] = {n->box[1][c], n->box[3][c], n->box[5][c]};
        if (v->padded)
            for (int a = 0; a < 3; a++) lo[a] -= v->pad[q], hi[a] += v->pad[q];
        vec3 o = v3(v->ox[q], v->oy[q], v->oz[q]), iv = v3(v->ix[q], v->iy[q], v->iz[q]);
        int neg[3] = {signbit(iv.x) != 0, signbit(iv.y) != 0, signbit(iv.z) != 0};
        float e;
        if (box3_slab(lo, hi, o, iv, neg, v->lo[q], v->hi[q], &e)) {
            h |= 1u << l;
            if (e < *entry) *entry = e;
        }
    }
    return h;
#endif
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
    return e;
#endif
}

/* Slots of node n that hold a child. */
INST_INLINE unsigned ip_children(const inst_wnode *n)
{
#if INST_WIDE_AVX
    __m256i none = _mm256_cmpeq_epi32(_mm256_load_si256((const __m256i *)n->child),
                                      _mm256_set1_epi32((int)INST_WIDE_NONE));
    return ~(unsigned)_mm256_movemask_ps(_mm256_castsi256_ps(none)) & 0xFFu;
#else
    unsigned cand = 0;
    for (unsigned c = 0; c < INST_WIDE; c++) cand |= (unsigned)(n->child[c] != INST_WIDE_NONE) << c;
    return cand;
#endif
}

/* Children some ray of the view may hit (the frustum test, see above). */
INST_INLINE unsigned ip_frustum(const ip_view *v, const inst_wnode *n)
{
#if INST_WIDE_AVX
    __m256 t0 = _mm256_set1_ps(v->t_lo), t1 = _mm256_set1_ps(v->t_hi);
    __m256 p = _mm256_set1_ps(v->pad_max);
    for (int a = 0; a < 3; a++) {
        __m256 lo = _mm256_sub_ps(_mm256_load_ps(n->box[2 * a]), p);
        __m256 hi = _mm256_add_ps(_mm256_load_ps(n->box[2 * a + 1]), p);
        int neg = v->octant >> a & 1;
        __m256 nr = neg ? hi : lo, fr = neg ? lo : hi;
        __m256 olo = _mm256_set1_ps(v->o_lo[a]), ohi = _mm256_set1_ps(v->o_hi[a]);
        __m256 ilo = _mm256_set1_ps(v->i_lo[a]), ihi = _mm256_set1_ps(v->i_hi[a]);
        __m256 d0 = _mm256_sub_ps(nr, ohi), d1 = _mm256_sub_ps(nr, olo);
        __m256 e0 = _mm256_sub_ps(fr, ohi), e1 = _mm256_sub_ps(fr, olo);
        __m256 l = _mm256_min_ps(_mm256_min_ps(_mm256_mul_ps(d0, ilo), _mm256_mul_ps(d0, ihi)),
                                 _mm256_min_ps(_mm256_mul_ps(d1, ilo), _mm256_mul_ps(d1, ihi)));
        __m256 h = _mm256_max_ps(_mm256_max_ps(_mm256_mul_ps(e0, ilo), _mm256_mul_ps(e0, ihi)),
                                 _mm256_max_ps(_mm256_mul_ps(e1, ilo), _mm256_mul_ps(e1, ihi)));
        t0 = _mm256_max_ps(l, t0);
        t1 = _mm256_min_ps(h, t1);
    }
    __m256 abs1 = _mm256_andnot_ps(_mm256_set1_ps(-0.0f), t1);
    __m256 lim = _mm256_add_ps(t1, _mm256_mul_ps(abs1, _mm256_set1_ps(ACCEL_SLAB_PAD)));
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t0, lim, _CMP_LE_OQ));
#else
    (void)v, (void)n;
    return 0xFFu;
#endif
}

/* The frustum's bounds over the rays m of the view; none unless they
 * share an octant and their reciprocals are finite. */
static void ip_bounds(ip_view *v, uint64_t m)
{
    v->frustum = 0;
    if (!m) return;
    const float *row[9] = {v->ox, v->oy, v->oz, v->ix, v->iy, v->iz, v->lo, v->hi, v->pad};
    unsigned r0 = (unsigned)__builtin_ctzll(m);
    int oct = (signbit(v->ix[r0]) != 0) | (signbit(v->iy[r0]) != 0) << 1 |
              (signbit(v->iz[r0]) != 0) << 2;
    float lo[9], hi[9];
#if INST_WIDE_AVX
    __m256 vlo[9], vhi[9];
    for (int k = 0; k < 9; k++) vlo[k] = _mm256_set1_ps(INFINITY), vhi[k] = _mm256_set1_ps(-INFINITY);
    const __m256 inf = _mm256_set1_ps(INFINITY), sign = _mm256_set1_ps(-0.0f);
    for (unsigned g = 0; g < IP_RAYS / 8; g++) {
        unsigned gm = (unsigned)(m >> (8 * g)) & 0xFFu;
        if (!gm) continue;
        __m256 keep = _mm256_castsi256_ps(_mm256_cmpgt_epi32(
            _mm256_and_si256(_mm256_set1_epi32((int)gm), _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128)),
            _mm256_setzero_si256()));
        for (int k = 0; k < 9; k++) {
            __m256 x = _mm256_load_ps(row[k] + 8 * g);
            vlo[k] = _mm256_min_ps(vlo[k], _mm256_blendv_ps(inf, x, keep));
            vhi[k] = _mm256_max_ps(vhi[k], _mm256_blendv_ps(_mm256_xor_ps(inf, sign), x, keep));
            if (k >= 3 && k < 6) {
                int a = k - 3;
                unsigned neg = (unsigned)_mm256_movemask_ps(x) & gm;
                if (neg != ((oct >> a & 1) ? gm : 0u)) return;
                __m256 fin = _mm256_cmp_ps(_mm256_andnot_ps(sign, x), inf, _CMP_LT_OQ);
                if (((unsigned)_mm256_movemask_ps(fin) & gm) != gm) return;
            }
        }
    }
    for (int k = 0; k < 9; k++) {
        float l[8], h[8];
        _mm256_storeu_ps(l, vlo[k]);
        _mm256_storeu_ps(h, vhi[k]);
        lo[k] = l[0], hi[k] = h[0];
        for (int j = 1; j < 8; j++) lo[k] = minf(lo[k], l[j]), hi[k] = maxf(hi[k], h[j]);
    }
#else
    for (int k = 0; k < 9; k++) lo[k] = hi[k] = row[k][r0];
    for (uint64_t q = m; q; q &= q - 1) {
        unsigned r = (unsigned)__builtin_ctzll(q);
        int o = (signbit(v->ix[r]) != 0) | (signbit(v->iy[r]) != 0) << 1 | (signbit(v->iz[r]) != 0) << 2;
        if (o != oct || !isfinite(v->ix[r]) || !isfinite(v->iy[r]) || !isfinite(v->iz[r])) return;
        for (int k = 0; k < 9; k++) lo[k] = minf(lo[k], row[k][r]), hi[k] = maxf(hi[k], row[k][r]);
    }
#endif
    for (int a = 0; a < 3; a++) {
        v->o_lo[a] = lo[a], v->o_hi[a] = hi[a];
        v->i_lo[a] = lo[3 + a], v->i_hi[a] = hi[3 + a];
    }
    v->t_lo = lo[6], v->t_hi = hi[7], v->pad_max = v->padded ? hi[8] : 0.0f;
    v->octant = oct;
    v->frustum = 1;
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

/* The rays of m that the watertight test's first rule does not rule out
 * for triangle tri: for 8 rays at once, the relative and sheared
 * vertices, the edge functions U, V, W and their cheap bounds, each the
 * same float operation on the same operands as accel_tri_watertight_impl
 * (core/prim.h) computes them (a lane's permuted axes picked by blends);
 * a ray whose edge functions surely mix signs is a miss there, before
 * anything else, so skipping it changes no answer. */
INST_INLINE uint64_t ip_edge_keep(const ip_packet *pk, const float *tri, uint64_t m)
{
#if INST_WIDE_AVX
    uint64_t keep = 0;
    const __m256 sign = _mm256_set1_ps(-0.0f), filt = _mm256_set1_ps(ACCEL_EDGE_FILTER);
    const __m256 tiny = _mm256_set1_ps(ACCEL_EDGE_TINY);
    const __m256i one = _mm256_set1_epi32(1), two = _mm256_set1_epi32(2);
    for (unsigned g = 0; g < IP_RAYS / 8; g++) {
        unsigned gm = (unsigned)(m >> (8 * g)) & 0xFFu;
        if (!gm) continue;
        const unsigned r = 8 * g;
        __m256 o[3] = {_mm256_load_ps(pk->top.ox + r), _mm256_load_ps(pk->top.oy + r),
                       _mm256_load_ps(pk->top.oz + r)};
        __m256i kx = _mm256_load_si256((const __m256i *)(pk->kx + r));
        __m256i ky = _mm256_load_si256((const __m256i *)(pk->ky + r));
        __m256i kz = _mm256_load_si256((const __m256i *)(pk->kz + r));
        __m256 x1 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kx, one)), x2 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kx, two));
        __m256 y1 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(ky, one)), y2 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(ky, two));
        __m256 z1 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kz, one)), z2 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kz, two));
        __m256 sx = _mm256_load_ps(pk->sx + r), sy = _mm256_load_ps(pk->sy + r);
        __m256 sxa = _mm256_andnot_ps(sign, sx), sya = _mm256_andnot_ps(sign, sy);
        __m256 px[3], py[3], mx[3], my[3]; /* sheared x, y and their magnitudes, per vertex */
        for (int j = 0; j < 3; j++) {
            __m256 e0 = _mm256_sub_ps(_mm256_set1_ps(tri[3 * j]), o[0]);
            __m256 e1 = _mm256_sub_ps(_mm256_set1_ps(tri[3 * j + 1]), o[1]);
            __m256 e2 = _mm256_sub_ps(_mm256_set1_ps(tri[3 * j + 2]), o[2]);
            __m256 vx = _mm256_blendv_ps(_mm256_blendv_ps(e0, e1, x1), e2, x2);
            __m256 vy = _mm256_blendv_ps(_mm256_blendv_ps(e0, e1, y1), e2, y2);
            __m256 vz = _mm256_blendv_ps(_mm256_blendv_ps(e0, e1, z1), e2, z2);
            px[j] = _mm256_sub_ps(vx, _mm256_mul_ps(sx, vz));
            py[j] = _mm256_sub_ps(vy, _mm256_mul_ps(sy, vz));
            __m256 az = _mm256_andnot_ps(sign, vz);
            mx[j] = _mm256_add_ps(_mm256_andnot_ps(sign, vx), _mm256_mul_ps(sxa, az));
            my[j] = _mm256_add_ps(_mm256_andnot_ps(sign, vy), _mm256_mul_ps(sya, az));
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
        keep |= (uint64_t)(gm & ~miss) << (8 * g);
    }
    return keep;
#else
    (void)pk, (void)tri;
    return m;
#endif
}

/* A bottom leaf: its triangles (mesh ids qs) decided in world space for
 * the rays m, each world triangle computed once for all of them. */
INST_INLINE void ip_leaf(const inst_accel *a, ip_packet *pk, ip_view *v, const inst_item *it,
                         const uint32_t *qs, const float *lt, uint32_t count, uint64_t m,
                         int naive, int spheres, int counted)
{
    const accel_scene *s = a->scene;
    for (uint32_t i = 0; i < count && (m &= pk->live); i++) {
        uint32_t q = qs[i], id = it->base + q;
        float w[12];
        const float *tri = NULL, *sphere = NULL;
        if (spheres && id >= s->tri_count) { /* only plain scenes hold spheres */
            sphere = s->spheres + 4 * (size_t)(id - s->tri_count);
        } else if (a->world_flat || (it->identity && s->instances)) {
            tri = s->tris + 9 * (size_t)id;
        } else if (it->identity) { /* a plain scene: its own triangles */
            tri = lt + 9 * (size_t)i;
        } else {
            inst_xform_tri(it, lt + 9 * (size_t)i, w);
            tri = w;
        }
        /* Rays that share their origin and axes (a pinhole camera's)
         * share the triangle's relative vertices, and skip it where its
         * edge functions, affine in their shear, surely mix signs: the
         * exact test's first rule (core/prim.h), so the answer stands. */
        accel_tri_rel rel;
        const int shared = pk->shared && tri && !naive;
        uint64_t todo = m;
        if (shared) {
            accel_tri_aff f;
            accel_tri_rel_of(&pk->p[__builtin_ctzll(m)], tri, &rel);
            accel_tri_aff_of(&rel, &f);
            todo = ip_aff_keep(pk, &f, m);
        } else if (tri && !naive) {
            todo = ip_edge_keep(pk, tri, m);
        }
        if (counted)
            for (uint64_t k = m; k; k &= k - 1) {
                unsigned r = (unsigned)__builtin_ctzll(k);
                pk->prims[r] += id != pk->prim[r];
            }
        for (uint64_t k = todo; k; k &= k - 1) {
            unsigned r = (unsigned)__builtin_ctzll(k);
            if (id == pk->prim[r]) continue;
            if (inst_decide(&pk->p[r], tri, shared ? &rel : NULL, sphere, id, naive, &pk->t[r],
                            &pk->u[r], &pk->v[r], &pk->prim[r]) &&
                pk->any)
                pk->live &= ~IP_BIT(r);
        }
    }
    for (uint64_t k = m; k; k &= k - 1) {
        unsigned r = (unsigned)__builtin_ctzll(k);
        v->hi[r] = inst_walk_hi(pk->t[r], v->shift[r], v->slack);
        pk->top.hi[r] = pk->t[r];
    }
}

static void ip_instance(const inst_accel *a, ip_packet *pk, uint32_t k, uint64_t m, int naive,
                        int spheres, int counted);

/* ---- the walk of one level ------------------------------------------------------- */

/* The packet's rays m through the wide tree (h, w): the top level (it ==
 * NULL, view pk->top, leaves are instances) or instance it's bottom level
 * (view v; lt its leaf-ordered triangles). */
INST_INLINE void ip_walk(const inst_accel *a, ip_packet *pk, ip_view *v, const bvh_box_tree *h,
                         const inst_wide *w, const inst_item *it, const float *lt,
                         uint64_t m, int naive, int spheres, int counted)
{
    if (w->root == INST_WIDE_NONE || !m) return;
    const int top = it == NULL;
    ip_entry stack[IP_STACK];
    int sp = 0;
    stack[sp++] = (ip_entry){w->root, -INFINITY, m};
    while (sp > 0) {
        ip_entry e = stack[--sp];
        uint64_t em = e.mask & pk->live;
        if (em && e.entry > -INFINITY) em = ip_still(v, em, e.entry);
        if (!em) continue;
        if (e.ref & INST_WIDE_LEAF) {
            const bvh_node *n = &h->nodes[e.ref & ~INST_WIDE_LEAF];
            if (top) {
                for (uint32_t i = 0; i < n->count && (em &= pk->live); i++)
                    ip_instance(a, pk, h->order[n->left_first + i], em, naive, spheres, counted);
            } else {
                ip_leaf(a, pk, v, it, h->order + n->left_first, lt + 9 * (size_t)n->left_first,
                        n->count, em, naive, spheres, counted);
            }
            continue;
        }
        const inst_wnode *nd = &w->nodes[e.ref];
        if (counted)
            for (uint64_t k = em; k; k &= k - 1) {
                unsigned r = (unsigned)__builtin_ctzll(k);
                if (top)
                    pk->top_steps[r]++;
                else
                    pk->bottom_steps[r]++;
                pk->boxes[r] += INST_WIDE;
            }
        unsigned cand = v->frustum ? ip_frustum(v, nd) : ip_children(nd); /* empty slots fail both */
        ip_entry hit[INST_WIDE];
        int nh = 0;
        for (; cand; cand &= cand - 1) {
            unsigned c = (unsigned)__builtin_ctz(cand);
            uint64_t cm = 0;
#if INST_WIDE_AVX
            ip_entries es = _mm256_set1_ps(INFINITY);
#else
            ip_entries es = INFINITY;
#endif
            for (unsigned g = 0; g < IP_RAYS / 8; g++) {
                unsigned gm = (unsigned)(em >> (8 * g)) & 0xFFu;
                if (gm) cm |= (uint64_t)ip_group(v, nd, c, g, gm, &es) << (8 * g);
            }
            if (!cm) continue;
            float entry = ip_entry_min(es);
            int j = nh++; /* insertion, farthest first */
            while (j > 0 && hit[j - 1].entry < entry) hit[j] = hit[j - 1], j--;
            hit[j] = (ip_entry){nd->child[c], entry, cm};
        }
        /* The nearest child is tested again at its pop: its entry is
         * already known to be reached. */
        for (int j = 0; j < nh; j++) stack[sp++] = hit[j];
        if (nh) stack[sp - 1].entry = -INFINITY;
    }
}

/* Ray r of the packet in instance it's object space (inst_ray.h), into
 * the view ov; 1 when it reaches the mesh's padded box. */
static int ip_object1(const inst_accel *a, const inst_item *it, const inst_bottom *b, ip_packet *pk,
                      ip_view *ov, unsigned r, int counted)
{
    inst_oray o;
    int clip = inst_object_ray(a, it, b, pk->o[r], pk->d[r], pk->p[r].t_near, pk->t[r], &o);
    if (clip >= 0 && counted) pk->boxes[r]++;
    if (clip <= 0) return 0;
    vec3 of, df;
    float padf;
    inst_object_float(a, b, &o, &of, &df, &padf);
    ov->ox[r] = of.x, ov->oy[r] = of.y, ov->oz[r] = of.z;
    ov->ix[r] = 1.0f / df.x, ov->iy[r] = 1.0f / df.y, ov->iz[r] = 1.0f / df.z;
    ov->pad[r] = padf;
    ov->shift[r] = o.s0;
    ov->lo[r] = inst_walk_lo(pk->p[r].t_near, o.s0, ov->slack);
    ov->hi[r] = inst_walk_hi(pk->t[r], o.s0, ov->slack);
    return 1;
}

#if INST_WIDE_AVX
/* ip_object1 for the 4 rays rr[0..n) at once: inst_object_ray and
 * inst_object_float written in 4-lane double operations, each the same
 * IEEE operation on the same operands in the same order as the scalar
 * code (its compare-and-selects are max_pd/min_pd, which select as
 * inst_dmax/inst_dmin do, and its swap a blend on t0 > t1), so every lane
 * gets the scalar code's bits. A lane the scalar code would branch on (an
 * object-space direction component that is zero or has no finite
 * reciprocal) is left to ip_object1. Returns the mask of kept rays. */
static uint64_t ip_object4(const inst_accel *a, const inst_item *it, const inst_bottom *b,
                           ip_packet *pk, ip_view *ov, const unsigned *rr, int n, int counted)
{
    const double *m = it->inverse;
    const __m256d sign = _mm256_set1_pd(-0.0), inf = _mm256_set1_pd(INFINITY), zero = _mm256_setzero_pd();
#define IP_DABS(x) _mm256_andnot_pd(sign, (x))
    __m256d wo[3], wd[3], o[3], d[3];
    for (int k = 0; k < 3; k++) {
        wo[k] = _mm256_set_pd(pk->o[rr[3]][k], pk->o[rr[2]][k], pk->o[rr[1]][k], pk->o[rr[0]][k]);
        wd[k] = _mm256_set_pd(pk->d[rr[3]][k], pk->d[rr[2]][k], pk->d[rr[1]][k], pk->d[rr[0]][k]);
    }
    __m256d eo = zero, oa = zero, ed = zero, da = zero;
    for (int i = 0; i < 3; i++) {
        const double *row = m + 4 * i;
        __m256d r0 = _mm256_set1_pd(row[0]), r1 = _mm256_set1_pd(row[1]), r2 = _mm256_set1_pd(row[2]);
        __m256d r3 = _mm256_set1_pd(row[3]);
        __m256d p0 = _mm256_mul_pd(r0, wo[0]), p1 = _mm256_mul_pd(r1, wo[1]), p2 = _mm256_mul_pd(r2, wo[2]);
        o[i] = _mm256_add_pd(_mm256_add_pd(_mm256_add_pd(p0, p1), p2), r3);
        eo = _mm256_max_pd(eo, _mm256_add_pd(_mm256_add_pd(_mm256_add_pd(IP_DABS(p0), IP_DABS(p1)), IP_DABS(p2)),
                                             IP_DABS(r3)));
        oa = _mm256_max_pd(oa, IP_DABS(o[i]));
        __m256d q0 = _mm256_mul_pd(r0, wd[0]), q1 = _mm256_mul_pd(r1, wd[1]), q2 = _mm256_mul_pd(r2, wd[2]);
        d[i] = _mm256_add_pd(_mm256_add_pd(q0, q1), q2);
        ed = _mm256_max_pd(ed, _mm256_add_pd(_mm256_add_pd(IP_DABS(q0), IP_DABS(q1)), IP_DABS(q2)));
        da = _mm256_max_pd(da, IP_DABS(d[i]));
    }
    __m256d valid = _mm256_and_pd(_mm256_cmp_pd(da, zero, _CMP_GT_OQ),
                                  _mm256_and_pd(_mm256_cmp_pd(IP_DABS(oa), inf, _CMP_LT_OQ),
                                                _mm256_cmp_pd(IP_DABS(da), inf, _CMP_LT_OQ)));
    __m256d reach = _mm256_add_pd(
        _mm256_add_pd(_mm256_add_pd(oa, _mm256_set1_pd(b->abs_max)), _mm256_set1_pd(4.0 * it->pad)),
        _mm256_set1_pd(1.0));
    __m256d e_ray = _mm256_mul_pd(_mm256_set1_pd(0x1p-50),
                                  _mm256_add_pd(eo, _mm256_div_pd(_mm256_mul_pd(ed, reach), da)));
    __m256d pad = a->no_pad ? zero : _mm256_add_pd(_mm256_set1_pd(2.0 * it->pad), e_ray);
    __m256d tn = _mm256_set_pd(pk->p[rr[3]].t_near, pk->p[rr[2]].t_near, pk->p[rr[1]].t_near, pk->p[rr[0]].t_near);
    __m256d s0 = tn, s1 = _mm256_set_pd(pk->t[rr[3]], pk->t[rr[2]], pk->t[rr[1]], pk->t[rr[0]]);
    __m256d branch = zero; /* lanes the scalar code would take apart */
    for (int i = 0; i < 3; i++) {
        __m256d lo = _mm256_sub_pd(_mm256_set1_pd(b->box_lo[i]), pad);
        __m256d hi = _mm256_add_pd(_mm256_set1_pd(b->box_hi[i]), pad);
        __m256d inv = _mm256_div_pd(_mm256_set1_pd(1.0), d[i]);
        branch = _mm256_or_pd(branch, _mm256_or_pd(_mm256_cmp_pd(d[i], zero, _CMP_EQ_OQ),
                                                   _mm256_cmp_pd(IP_DABS(inv), inf, _CMP_NLT_UQ)));
        __m256d t0 = _mm256_mul_pd(_mm256_sub_pd(lo, o[i]), inv);
        __m256d t1 = _mm256_mul_pd(_mm256_sub_pd(hi, o[i]), inv);
        __m256d sw = _mm256_cmp_pd(t0, t1, _CMP_GT_OQ);
        __m256d u0 = _mm256_blendv_pd(t0, t1, sw), u1 = _mm256_blendv_pd(t1, t0, sw);
        __m256d slack = _mm256_mul_pd(_mm256_set1_pd(0x1p-40), _mm256_add_pd(IP_DABS(u0), IP_DABS(u1)));
        s0 = _mm256_max_pd(s0, _mm256_sub_pd(u0, slack));
        s1 = _mm256_min_pd(s1, _mm256_add_pd(u1, slack));
    }
    unsigned ok = (unsigned)_mm256_movemask_pd(valid), apart = (unsigned)_mm256_movemask_pd(branch);
    unsigned in = (unsigned)_mm256_movemask_pd(_mm256_cmp_pd(s0, s1, _CMP_LE_OQ));
    /* The float ray from the box entry, its pad, its range. */
    __m128 of[3], df[3];
    for (int i = 0; i < 3; i++) {
        of[i] = _mm256_cvtpd_ps(_mm256_add_pd(o[i], _mm256_mul_pd(s0, d[i])));
        df[i] = _mm256_cvtpd_ps(d[i]);
    }
    __m256d pf = a->no_pad ? zero
                           : _mm256_add_pd(_mm256_add_pd(pad, _mm256_mul_pd(_mm256_set1_pd(0x1p-20),
                                                                            _mm256_add_pd(_mm256_set1_pd(b->abs_max),
                                                                                          _mm256_mul_pd(_mm256_set1_pd(2.0), pad)))),
                                           _mm256_mul_pd(_mm256_set1_pd(0x1p-50),
                                                         _mm256_add_pd(oa, _mm256_mul_pd(IP_DABS(s0), da))));
    __m128 padf = _mm256_cvtpd_ps(_mm256_mul_pd(pf, _mm256_set1_pd(1.0 + 0x1p-20)));
    __m128 lo = _mm256_cvtpd_ps(_mm256_sub_pd(tn, s0));
    __m128 sl = _mm_set1_ps(ov->slack), fsign = _mm_set1_ps(-0.0f);
    lo = _mm_sub_ps(lo, _mm_mul_ps(_mm_andnot_ps(fsign, lo), sl));
    __m128 tt = _mm256_cvtpd_ps(_mm256_sub_pd(_mm256_set_pd(pk->t[rr[3]], pk->t[rr[2]], pk->t[rr[1]], pk->t[rr[0]]), s0));
    tt = _mm_add_ps(tt, _mm_mul_ps(_mm_andnot_ps(fsign, tt), sl));
    float fo[3][4], fd[3][4], fp[4], flo[4], fhi[4];
    double ds0[4];
    for (int i = 0; i < 3; i++) {
        _mm_storeu_ps(fo[i], of[i]);
        _mm_storeu_ps(fd[i], _mm_div_ps(_mm_set1_ps(1.0f), df[i]));
    }
    _mm_storeu_ps(fp, padf);
    _mm_storeu_ps(flo, lo);
    _mm_storeu_ps(fhi, tt);
    _mm256_storeu_pd(ds0, s0);
#undef IP_DABS
    uint64_t keep = 0;
    for (int l = 0; l < n; l++) {
        unsigned r = rr[l];
        if (apart >> l & 1u) {
            if (ip_object1(a, it, b, pk, ov, r, counted)) keep |= IP_BIT(r);
            continue;
        }
        if (!(ok >> l & 1u)) continue;
        if (counted) pk->boxes[r]++;
        if (!(in >> l & 1u)) continue;
        ov->ox[r] = fo[0][l], ov->oy[r] = fo[1][l], ov->oz[r] = fo[2][l];
        ov->ix[r] = fd[0][l], ov->iy[r] = fd[1][l], ov->iz[r] = fd[2][l];
        ov->pad[r] = fp[l];
        ov->shift[r] = ds0[l];
        ov->lo[r] = flo[l];
        ov->hi[r] = fhi[l];
        keep |= IP_BIT(r);
    }
    return keep;
}
#endif

/* The rays m of the packet through instance k (see the file's comment). */
static __attribute__((noinline)) void ip_instance(const inst_accel *a, ip_packet *pk, uint32_t k,
                                                  uint64_t m, int naive, int spheres, int counted)
{
    const inst_item *it = &a->items[k];
    const inst_bottom *b = &a->bottoms[it->bottom];
    if (it->identity) { /* the world rays themselves, no pad */
        ip_walk(a, pk, &pk->top, &b->bvh, &b->wide, it, b->leaf_tris, m, naive, spheres, counted);
        return;
    }
    ip_view ov;
    ov.slack = 0x1p-20f;
    ov.padded = !a->no_pad;
    uint64_t keep = 0;
#if INST_WIDE_AVX
    unsigned rr[4];
    int n = 0;
    for (uint64_t q = m; q; q &= q - 1) {
        rr[n++] = (unsigned)__builtin_ctzll(q);
        if (n == 4 || !(q & (q - 1))) {
            for (int l = n; l < 4; l++) rr[l] = rr[0]; /* lanes beyond n: ignored */
            keep |= ip_object4(a, it, b, pk, &ov, rr, n, counted);
            n = 0;
        }
    }
#else
    for (uint64_t q = m; q; q &= q - 1)
        if (ip_object1(a, it, b, pk, &ov, (unsigned)__builtin_ctzll(q), counted))
            keep |= IP_BIT(__builtin_ctzll(q));
#endif
    if (!keep) return;
    /* Lanes of the groups in use that hold no ray: an empty range. */
    for (unsigned g = 0; g < IP_RAYS / 8; g++) {
        unsigned gm = (unsigned)(keep >> (8 * g)) & 0xFFu;
        if (!gm || gm == 0xFFu) continue;
        for (unsigned l = 0; l < 8; l++) {
            unsigned r = 8 * g + l;
            if (gm >> l & 1u) continue;
            ov.ox[r] = ov.oy[r] = ov.oz[r] = 0.0f, ov.ix[r] = ov.iy[r] = ov.iz[r] = 1.0f;
            ov.pad[r] = 0.0f, ov.lo[r] = INFINITY, ov.hi[r] = -INFINITY, ov.shift[r] = 0.0;
        }
    }
    ip_bounds(&ov, keep);
    ip_walk(a, pk, &ov, &b->bvh, &b->wide, it, b->leaf_tris, keep, naive, spheres, counted);
}

/* ---- the batch kernel --------------------------------------------------------------- */

/* Rays [0, n) into the packet; the rest of its 64 lanes dead. */
static void ip_load(ip_packet *pk, const accel_ray *rays, unsigned n, int any)
{
    ip_view *v = &pk->top;
    pk->live = 0;
    pk->any = any;
    pk->shared = 1;
    v->slack = 0.0f, v->padded = 0;
    for (unsigned r = 0; r < IP_RAYS; r++) {
        accel_ray_prep *p = &pk->p[r];
        pk->prim[r] = ACCEL_MISS, pk->u[r] = pk->v[r] = 0.0f;
        pk->top_steps[r] = pk->bottom_steps[r] = pk->boxes[r] = pk->prims[r] = 0;
        v->pad[r] = 0.0f, v->shift[r] = 0.0;
        pk->sx[r] = pk->sy[r] = 0.0f;
        pk->kx[r] = 0, pk->ky[r] = 1, pk->kz[r] = 2;
        if (!(r < n && accel_prep_ray(&rays[r], p))) { /* dead: an empty range */
            v->ox[r] = v->oy[r] = v->oz[r] = 0.0f, v->ix[r] = v->iy[r] = v->iz[r] = 1.0f;
            v->lo[r] = INFINITY, v->hi[r] = -INFINITY, pk->t[r] = -INFINITY;
            continue;
        }
        v->ox[r] = p->org.x, v->oy[r] = p->org.y, v->oz[r] = p->org.z;
        v->ix[r] = p->inv_dir.x, v->iy[r] = p->inv_dir.y, v->iz[r] = p->inv_dir.z;
        v->lo[r] = p->t_near, v->hi[r] = pk->t[r] = p->t_far;
        pk->sx[r] = p->sx, pk->sy[r] = p->sy;
        pk->kx[r] = p->kx, pk->ky[r] = p->ky, pk->kz[r] = p->kz;
        pk->o[r][0] = p->org.x, pk->o[r][1] = p->org.y, pk->o[r][2] = p->org.z;
        pk->d[r][0] = p->dir.x, pk->d[r][1] = p->dir.y, pk->d[r][2] = p->dir.z;
        if (pk->live) pk->shared &= accel_prep_same_frame(p, &pk->p[__builtin_ctzll(pk->live)]);
        pk->live |= IP_BIT(r);
    }
    ip_bounds(v, pk->live);
}

INST_INLINE void ip_kernel(const void *acc, const accel_ray *rays, void *out, size_t count,
                           accel_counters *c, unsigned flags, int any)
{
    const inst_accel *a = acc;
    const int naive = (flags & ACCEL_V_NAIVE) != 0, spheres = (flags & ACCEL_V_SPHERES) != 0;
    ip_packet pk;
    for (size_t base = 0; base < count; base += IP_RAYS) {
        unsigned n = count - base < IP_RAYS ? (unsigned)(count - base) : IP_RAYS;
        ip_load(&pk, rays + base, n, any);
        ip_walk(a, &pk, &pk.top, &a->top_bvh, &a->top_wide, NULL, NULL, pk.live, naive, spheres,
                c != NULL);
        for (unsigned r = 0; r < n; r++) {
            size_t i = base + r;
            if (any) {
                ((uint8_t *)out)[i] = pk.prim[r] != ACCEL_MISS;
            } else {
                accel_hit hh = accel_hit_miss();
                if (pk.prim[r] != ACCEL_MISS)
                    hh.t = pk.t[r], hh.prim = pk.prim[r], hh.u = pk.u[r], hh.v = pk.v[r];
                ((accel_hit *)out)[i] = hh;
            }
            if (c) {
                accel_count_ray(c, i, pk.top_steps[r] + pk.bottom_steps[r], 0, pk.boxes[r],
                                pk.prims[r], 0);
                c->level_steps[0] += pk.top_steps[r];
                c->level_steps[1] += pk.bottom_steps[r];
            }
        }
    }
}

#define IP_CLOSEST(a, r, o, n, c, f) ip_kernel(a, r, o, n, c, f, 0)
#define IP_ANY(a, r, o, n, c, f) ip_kernel(a, r, o, n, c, f, 1)
ACCEL_KERNEL_TABLE(ip_closest_table, IP_CLOSEST)
ACCEL_KERNEL_TABLE(ip_any_table, IP_ANY)

static unsigned ip_flags(const inst_accel *a)
{
    return accel_variant_flags(a->naive, a->spheres, 0);
}

ACCEL_COHERENT_ENTRIES(inst_packet_intersect, inst_packet_occluded, const void, ip_closest_table,
                       ip_any_table, ip_flags, inst_single_intersect, inst_single_occluded)

void inst_intersect(const void *acc, const accel_ray *rays, accel_hit *hits, size_t n,
                    accel_counters *c)
{
    const inst_accel *a = acc;
    if (a->packets)
        inst_packet_intersect(acc, rays, hits, n, c);
    else
        inst_single_intersect(acc, rays, hits, n, c);
}

void inst_occluded(const void *acc, const accel_ray *rays, uint8_t *occ, size_t n,
                   accel_counters *c)
{
    const inst_accel *a = acc;
    if (a->packets)
        inst_packet_occluded(acc, rays, occ, n, c);
    else
        inst_single_occluded(acc, rays, occ, n, c);
}
