/*
 * simd.h - the few float-vector operations the block test and the wide BVH kernels use,
 * for 4 lanes (f4: SSE) and 8 lanes (f8: AVX2), each with a plain-C twin
 * (a struct of floats and a loop per operation) used when the compiler
 * does not target the instruction set, or with -DBVH_NO_SIMD. AVX-512
 * (WIDE_AVX512) only in the kernel units' second copies, compiled with
 * WIDE_AVX512_UNIT and the Makefile's ARCH512 and run where the CPU has
 * it (trace.c, core/isa.h): there the fN operations are the same and
 * kernel.h adds the mask-register forms of its data movement. Never in the
 * baseline units, even under -march=native, so that their tables stay
 * the AVX2 ones.
 * A kernel body (C only): included by the .c files of its folder, not part
 * of the interface a C++ program includes.
 *
 * Semantics every version keeps, lane by lane (the kernels' exactness
 * arguments rest on them):
 *   fN_min(x, acc) = x < acc ? x : acc     (a NaN x keeps acc: minf of geom.h)
 *   fN_max(x, acc) = x > acc ? x : acc     (maxf)
 *   fN_lt / fN_le / fN_gt: ordered, false when either side is NaN
 *   masks are all-ones or all-zero lanes; fN_mask packs their sign bits.
 * fN_fmadd(a, b, c) = a b + c, fN_fnmadd(a, b, c) = c - a b and
 * fN_fmsub(a, b, c) = a b - c are fused (one rounding) where the compiler
 * targets FMA, and a rounded product then a rounded sum elsewhere. Only
 * the leaf test uses them, where the error bounds of core/prim.h assume
 * the two roundings: the fused form errs less, so every bound still
 * holds (block_test.h). The slab test and everything else round every
 * product before the sum, as the scalar tests do.
 */
#ifndef BVH_WIDE_SIMD_H
#define BVH_WIDE_SIMD_H

#include <assert.h>
#include <stdint.h>
#include <string.h>

#include "core/prim.h"

#if defined(__SSE2__) && !defined(BVH_NO_SIMD)
#define WIDE_SSE 1
#include <immintrin.h>
#else
#define WIDE_SSE 0
#endif
#if defined(__AVX2__) && !defined(BVH_NO_SIMD)
#define WIDE_AVX 1
#else
#define WIDE_AVX 0
#endif
#if WIDE_AVX && defined(WIDE_AVX512_UNIT) && defined(__AVX512F__) && defined(__AVX512VL__) &&     \
    defined(__AVX512DQ__) && defined(__AVX512BW__)
#define WIDE_AVX512 1
#else
#define WIDE_AVX512 0
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* The kernels' helpers are forced inline, so that every copy of a kernel
 * (core/variant.h) folds its constant flags. `make sanitize` defines
 * WIDE_NO_FORCE_INLINE: instrumented, the forced copies took 6 minutes
 * (AVX2) to over 19 (plain C lanes) to compile the 4-wide kernels (then one unit), plain
 * `static inline` 11 seconds; the same code, copies the compiler may
 * leave uninlined. */
#ifdef WIDE_NO_FORCE_INLINE
#define WIDE_INLINE static inline
#else
#define WIDE_INLINE static inline __attribute__((always_inline))
#endif

/* ---- plain-C lanes ----------------------------------------------------------- */

/* The multiply-adds as a rounded product then a rounded sum (no FMA). */
#define WIDE_FMA_UNFUSED(N)                                                                 \
    WIDE_INLINE f##N f##N##_fmadd(f##N a, f##N b, f##N c) { return f##N##_add(f##N##_mul(a, b), c); } \
    WIDE_INLINE f##N f##N##_fnmadd(f##N a, f##N b, f##N c) { return f##N##_sub(c, f##N##_mul(a, b)); } \
    WIDE_INLINE f##N f##N##_fmsub(f##N a, f##N b, f##N c) { return f##N##_sub(f##N##_mul(a, b), c); }

/* Defines fN as a struct of N floats and every operation as a loop. */
#define WIDE_GENERIC(N)                                                                     \
    typedef struct { float v[N]; } f##N;                                                    \
    WIDE_INLINE uint32_t f##N##_bits_(float x) { uint32_t u; memcpy(&u, &x, 4); return u; } \
    WIDE_INLINE float f##N##_float_(uint32_t u) { float x; memcpy(&x, &u, 4); return x; }   \
    WIDE_INLINE f##N f##N##_load(const float *p) { f##N r; memcpy(r.v, p, sizeof r.v); return r; } \
    WIDE_INLINE void f##N##_store(float *p, f##N a) { memcpy(p, a.v, sizeof a.v); }         \
    WIDE_INLINE f##N f##N##_set1(float x) { f##N r; for (int i = 0; i < N; i++) r.v[i] = x; return r; } \
    WIDE_INLINE f##N f##N##_add(f##N a, f##N b) { for (int i = 0; i < N; i++) a.v[i] += b.v[i]; return a; } \
    WIDE_INLINE f##N f##N##_sub(f##N a, f##N b) { for (int i = 0; i < N; i++) a.v[i] -= b.v[i]; return a; } \
    WIDE_INLINE f##N f##N##_mul(f##N a, f##N b) { for (int i = 0; i < N; i++) a.v[i] *= b.v[i]; return a; } \
    WIDE_INLINE f##N f##N##_div(f##N a, f##N b) { for (int i = 0; i < N; i++) a.v[i] /= b.v[i]; return a; } \
    WIDE_FMA_UNFUSED(N)                                                                     \
    WIDE_INLINE f##N f##N##_min(f##N x, f##N acc)                                           \
    { for (int i = 0; i < N; i++) acc.v[i] = x.v[i] < acc.v[i] ? x.v[i] : acc.v[i]; return acc; } \
    WIDE_INLINE f##N f##N##_max(f##N x, f##N acc)                                           \
    { for (int i = 0; i < N; i++) acc.v[i] = x.v[i] > acc.v[i] ? x.v[i] : acc.v[i]; return acc; } \
    WIDE_INLINE f##N f##N##_bitop_(f##N a, f##N b, int op)                                  \
    {                                                                                       \
        for (int i = 0; i < N; i++) {                                                       \
            uint32_t x = f##N##_bits_(a.v[i]), y = f##N##_bits_(b.v[i]);                    \
            a.v[i] = f##N##_float_(op == 0 ? x & y : op == 1 ? x | y : op == 2 ? x ^ y : ~x & y); \
        }                                                                                   \
        return a;                                                                           \
    }                                                                                       \
    WIDE_INLINE f##N f##N##_and(f##N a, f##N b) { return f##N##_bitop_(a, b, 0); }         \
    WIDE_INLINE f##N f##N##_or(f##N a, f##N b) { return f##N##_bitop_(a, b, 1); }          \
    WIDE_INLINE f##N f##N##_xor(f##N a, f##N b) { return f##N##_bitop_(a, b, 2); }         \
    WIDE_INLINE f##N f##N##_andnot(f##N a, f##N b) { return f##N##_bitop_(a, b, 3); }      \
    WIDE_INLINE f##N f##N##_cmp_(f##N a, f##N b, int op)                                    \
    {                                                                                       \
        for (int i = 0; i < N; i++) {                                                       \
            int r = op == 0 ? a.v[i] < b.v[i] : op == 1 ? a.v[i] <= b.v[i] : a.v[i] > b.v[i]; \
            a.v[i] = f##N##_float_(r ? 0xFFFFFFFFu : 0u);                                   \
        }                                                                                   \
        return a;                                                                           \
    }                                                                                       \
    WIDE_INLINE f##N f##N##_lt(f##N a, f##N b) { return f##N##_cmp_(a, b, 0); }            \
    WIDE_INLINE f##N f##N##_le(f##N a, f##N b) { return f##N##_cmp_(a, b, 1); }            \
    WIDE_INLINE f##N f##N##_gt(f##N a, f##N b) { return f##N##_cmp_(a, b, 2); }            \
    WIDE_INLINE int f##N##_mask(f##N a)                                                     \
    { int m = 0; for (int i = 0; i < N; i++) m |= (int)(f##N##_bits_(a.v[i]) >> 31) << i; return m; } \
    WIDE_INLINE f##N f##N##_blend(f##N a, f##N b, f##N m)                                   \
    { for (int i = 0; i < N; i++) if (f##N##_bits_(m.v[i]) >> 31) a.v[i] = b.v[i]; return a; } \
    WIDE_INLINE float f##N##_hmin(f##N a)                                                   \
    { float m = a.v[0]; for (int i = 1; i < N; i++) m = a.v[i] < m ? a.v[i] : m; return m; }

/* ---- 4 lanes ----------------------------------------------------------------- */

#if WIDE_SSE
typedef __m128 f4;
WIDE_INLINE f4 f4_load(const float *p) { return _mm_load_ps(p); }
WIDE_INLINE void f4_store(float *p, f4 a) { _mm_store_ps(p, a); }
WIDE_INLINE f4 f4_set1(float x) { return _mm_set1_ps(x); }
WIDE_INLINE f4 f4_add(f4 a, f4 b) { return _mm_add_ps(a, b); }
WIDE_INLINE f4 f4_sub(f4 a, f4 b) { return _mm_sub_ps(a, b); }
WIDE_INLINE f4 f4_mul(f4 a, f4 b) { return _mm_mul_ps(a, b); }
WIDE_INLINE f4 f4_div(f4 a, f4 b) { return _mm_div_ps(a, b); }
#ifdef __FMA__
WIDE_INLINE f4 f4_fmadd(f4 a, f4 b, f4 c) { return _mm_fmadd_ps(a, b, c); }
WIDE_INLINE f4 f4_fnmadd(f4 a, f4 b, f4 c) { return _mm_fnmadd_ps(a, b, c); }
WIDE_INLINE f4 f4_fmsub(f4 a, f4 b, f4 c) { return _mm_fmsub_ps(a, b, c); }
#else
WIDE_FMA_UNFUSED(4)
#endif
/* minps/maxps return their second operand when either is NaN. */
WIDE_INLINE f4 f4_min(f4 x, f4 acc) { return _mm_min_ps(x, acc); }
WIDE_INLINE f4 f4_max(f4 x, f4 acc) { return _mm_max_ps(x, acc); }
WIDE_INLINE f4 f4_and(f4 a, f4 b) { return _mm_and_ps(a, b); }
WIDE_INLINE f4 f4_or(f4 a, f4 b) { return _mm_or_ps(a, b); }
WIDE_INLINE f4 f4_xor(f4 a, f4 b) { return _mm_xor_ps(a, b); }
WIDE_INLINE f4 f4_andnot(f4 a, f4 b) { return _mm_andnot_ps(a, b); }
WIDE_INLINE f4 f4_lt(f4 a, f4 b) { return _mm_cmplt_ps(a, b); }
WIDE_INLINE f4 f4_le(f4 a, f4 b) { return _mm_cmple_ps(a, b); }
WIDE_INLINE f4 f4_gt(f4 a, f4 b) { return _mm_cmpgt_ps(a, b); }
WIDE_INLINE int f4_mask(f4 a) { return _mm_movemask_ps(a); }
WIDE_INLINE f4 f4_blend(f4 a, f4 b, f4 m)
{
#ifdef __SSE4_1__
    return _mm_blendv_ps(a, b, m);
#else
    return _mm_or_ps(_mm_and_ps(m, b), _mm_andnot_ps(m, a));
#endif
}
WIDE_INLINE float f4_hmin(f4 a)
{
    a = _mm_min_ps(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(1, 0, 3, 2)));
    a = _mm_min_ps(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(2, 3, 0, 1)));
    return _mm_cvtss_f32(a);
}
#else
WIDE_GENERIC(4)
#endif

/* ---- 8 lanes ----------------------------------------------------------------- */

#if WIDE_AVX
typedef __m256 f8;
WIDE_INLINE f8 f8_load(const float *p) { return _mm256_load_ps(p); }
WIDE_INLINE void f8_store(float *p, f8 a) { _mm256_store_ps(p, a); }
WIDE_INLINE f8 f8_set1(float x) { return _mm256_set1_ps(x); }
WIDE_INLINE f8 f8_add(f8 a, f8 b) { return _mm256_add_ps(a, b); }
WIDE_INLINE f8 f8_sub(f8 a, f8 b) { return _mm256_sub_ps(a, b); }
WIDE_INLINE f8 f8_mul(f8 a, f8 b) { return _mm256_mul_ps(a, b); }
WIDE_INLINE f8 f8_div(f8 a, f8 b) { return _mm256_div_ps(a, b); }
#ifdef __FMA__
WIDE_INLINE f8 f8_fmadd(f8 a, f8 b, f8 c) { return _mm256_fmadd_ps(a, b, c); }
WIDE_INLINE f8 f8_fnmadd(f8 a, f8 b, f8 c) { return _mm256_fnmadd_ps(a, b, c); }
WIDE_INLINE f8 f8_fmsub(f8 a, f8 b, f8 c) { return _mm256_fmsub_ps(a, b, c); }
#else
WIDE_FMA_UNFUSED(8)
#endif
WIDE_INLINE f8 f8_min(f8 x, f8 acc) { return _mm256_min_ps(x, acc); }
WIDE_INLINE f8 f8_max(f8 x, f8 acc) { return _mm256_max_ps(x, acc); }
WIDE_INLINE f8 f8_and(f8 a, f8 b) { return _mm256_and_ps(a, b); }
WIDE_INLINE f8 f8_or(f8 a, f8 b) { return _mm256_or_ps(a, b); }
WIDE_INLINE f8 f8_xor(f8 a, f8 b) { return _mm256_xor_ps(a, b); }
WIDE_INLINE f8 f8_andnot(f8 a, f8 b) { return _mm256_andnot_ps(a, b); }
WIDE_INLINE f8 f8_lt(f8 a, f8 b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
WIDE_INLINE f8 f8_le(f8 a, f8 b) { return _mm256_cmp_ps(a, b, _CMP_LE_OQ); }
WIDE_INLINE f8 f8_gt(f8 a, f8 b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
WIDE_INLINE int f8_mask(f8 a) { return _mm256_movemask_ps(a); }
WIDE_INLINE f8 f8_blend(f8 a, f8 b, f8 m) { return _mm256_blendv_ps(a, b, m); }
WIDE_INLINE float f8_hmin(f8 a)
{
    __m128 m = _mm_min_ps(_mm256_castps256_ps128(a), _mm256_extractf128_ps(a, 1));
    m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
    m = _mm_min_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
    return _mm_cvtss_f32(m);
}
/* Lane i (< 8) of a by one variable permute (the two-hit path of
 * kernel.h, AVX2 only). */
WIDE_INLINE float f8_lane(f8 a, unsigned i)
{
    return _mm256_cvtss_f32(_mm256_permutevar8x32_ps(a, _mm256_castsi128_si256(_mm_cvtsi32_si128((int)i))));
}
#else
WIDE_GENERIC(8)
#endif

/* Eight unsigned bytes as eight floats (exact): quantized node rows. */
#if WIDE_AVX
WIDE_INLINE f8 f8_from_u8(const uint8_t *p)
{
    return _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)p)));
}
#else
WIDE_INLINE f8 f8_from_u8(const uint8_t *p)
{
    float x[8];
    for (int i = 0; i < 8; i++) x[i] = (float)p[i];
    return f8_load(x);
}
#endif

/*
 * Lane masks of compares, for the leaf test's classes (block_test.h): kN holds
 * one lane's truth per lane; fN_ltk / _gtk / _lek compare as fN_lt / _gt /
 * _le (ordered), kN_or / _and / _andnot (~a & b) combine, kN_bits gives
 * the bits fN_mask would, fN_blendk(a, b, m) takes b where m holds. In the
 * AVX-512 units a kN is a mask register (__mmask8: vcmpps into k, kor,
 * vblendmps); elsewhere it is the vector mask itself and every operation
 * is its fN twin, so the AVX2 code is the same instructions as before.
 */
#if WIDE_AVX512
#define WIDE_KMASK(N, P, SFX)                                                                       \
    typedef __mmask8 k##N;                                                                          \
    WIDE_INLINE k##N f##N##_ltk(f##N a, f##N b) { return P##_cmp_ps_mask(a, b, _CMP_LT_OQ); }       \
    WIDE_INLINE k##N f##N##_gtk(f##N a, f##N b) { return P##_cmp_ps_mask(a, b, _CMP_GT_OQ); }       \
    WIDE_INLINE k##N f##N##_lek(f##N a, f##N b) { return P##_cmp_ps_mask(a, b, _CMP_LE_OQ); }       \
    WIDE_INLINE k##N k##N##_or(k##N a, k##N b) { return (k##N)(a | b); }                           \
    WIDE_INLINE k##N k##N##_and(k##N a, k##N b) { return (k##N)(a & b); }                          \
    WIDE_INLINE k##N k##N##_andnot(k##N a, k##N b) { return (k##N)(~a & b); }                      \
    WIDE_INLINE int k##N##_bits(k##N a) { return (int)a; }                                         \
    WIDE_INLINE f##N f##N##_blendk(f##N a, f##N b, k##N m) { return P##_mask_blend_##SFX(m, a, b); }
WIDE_KMASK(4, _mm, ps)
WIDE_KMASK(8, _mm256, ps)
#else
#define WIDE_KMASK(N)                                                                               \
    typedef f##N k##N;                                                                              \
    WIDE_INLINE k##N f##N##_ltk(f##N a, f##N b) { return f##N##_lt(a, b); }                        \
    WIDE_INLINE k##N f##N##_gtk(f##N a, f##N b) { return f##N##_gt(a, b); }                        \
    WIDE_INLINE k##N f##N##_lek(f##N a, f##N b) { return f##N##_le(a, b); }                        \
    WIDE_INLINE k##N k##N##_or(k##N a, k##N b) { return f##N##_or(a, b); }                         \
    WIDE_INLINE k##N k##N##_and(k##N a, k##N b) { return f##N##_and(a, b); }                       \
    WIDE_INLINE k##N k##N##_andnot(k##N a, k##N b) { return f##N##_andnot(a, b); }                 \
    WIDE_INLINE int k##N##_bits(k##N a) { return f##N##_mask(a); }                                 \
    WIDE_INLINE f##N f##N##_blendk(f##N a, f##N b, k##N m) { return f##N##_blend(a, b, m); }
WIDE_KMASK(4)
WIDE_KMASK(8)
#endif
#undef WIDE_KMASK

/* |a| and the sign bits of a, both widths. */
WIDE_INLINE f4 f4_abs(f4 a) { return f4_andnot(f4_set1(-0.0f), a); }
WIDE_INLINE f4 f4_signs(f4 a) { return f4_and(f4_set1(-0.0f), a); }
WIDE_INLINE f8 f8_abs(f8 a) { return f8_andnot(f8_set1(-0.0f), a); }
WIDE_INLINE f8 f8_signs(f8 a) { return f8_and(f8_set1(-0.0f), a); }

/*
 * accel_prep_ray (core/prim.h) with vector instructions: the same fields,
 * bit for bit (every quotient is one correctly rounded IEEE division, lane
 * by lane), and the same rays refused. The finiteness test is one compare
 * of |x| < inf (false for inf and NaN) over the six components, and the
 * six divisions are two 4-lane divisions. Tested against accel_prep_ray in
 * tests/test_bvh_wide.c.
 */
static inline int wide_prep_ray(const accel_ray *r, accel_ray_prep *p)
{
#if WIDE_SSE
    __m128 o = _mm_loadu_ps(&r->ox), d = _mm_loadu_ps(&r->dx); /* lane 3: t_near, t_far */
    __m128 inf = _mm_set1_ps(INFINITY), sign = _mm_set1_ps(-0.0f);
    int finite = _mm_movemask_ps(_mm_cmplt_ps(_mm_andnot_ps(sign, o), inf)) &
                 _mm_movemask_ps(_mm_cmplt_ps(_mm_andnot_ps(sign, d), inf));
    p->org = v3(r->ox, r->oy, r->oz);
    p->dir = v3(r->dx, r->dy, r->dz);
    p->t_near = r->t_near;
    p->t_far = r->t_far;
    if ((finite & 7) != 7 || !(r->t_near <= r->t_far)) return 0;
    float ax = fabsf(r->dx), ay = fabsf(r->dy), az = fabsf(r->dz);
    int kz = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
    const float dk[3] = {r->dx, r->dy, r->dz};
    if (dk[kz] == 0.0f) return 0;
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (dk[kz] < 0.0f) { int t = kx; kx = ky; ky = t; }
    float q[4] __attribute__((aligned(16)));
    _mm_store_ps(q, _mm_div_ps(_mm_set1_ps(1.0f), d));
    p->inv_dir = v3(q[0], q[1], q[2]);
    _mm_store_ps(q, _mm_div_ps(_mm_setr_ps(dk[kx], dk[ky], 1.0f, 1.0f), _mm_set1_ps(dk[kz])));
    p->sx = q[0], p->sy = q[1], p->sz = q[2];
    int neg = _mm_movemask_ps(d);
    p->neg[0] = neg & 1, p->neg[1] = (neg >> 1) & 1, p->neg[2] = (neg >> 2) & 1;
    p->kx = kx, p->ky = ky, p->kz = kz;
    return 1;
#else
    return accel_prep_ray(r, p);
#endif
}

/*
 * Compress-store table: for an 8-bit mask m, entry m lists the positions
 * of its set bits from the highest to the lowest, 4 bits each, in the low
 * nibbles first (entry 0b00100110 = 0x125: positions 5, 2, 1). Built by
 * the preprocessor: the position j of a set bit goes to nibble
 * popcount(m >> (j + 1)), the number of set bits above it.
 */
#define WIDE_POP8(x) (((x) & 1) + ((x) >> 1 & 1) + ((x) >> 2 & 1) + ((x) >> 3 & 1) + \
                      ((x) >> 4 & 1) + ((x) >> 5 & 1) + ((x) >> 6 & 1) + ((x) >> 7 & 1))
#define WIDE_LUT_BIT(m, j) (((m) >> (j) & 1u) * ((uint32_t)(j) << (4 * WIDE_POP8((m) >> ((j) + 1)))))
#define WIDE_LUT(m) (WIDE_LUT_BIT(m, 0) | WIDE_LUT_BIT(m, 1) | WIDE_LUT_BIT(m, 2) | WIDE_LUT_BIT(m, 3) | \
                     WIDE_LUT_BIT(m, 4) | WIDE_LUT_BIT(m, 5) | WIDE_LUT_BIT(m, 6) | WIDE_LUT_BIT(m, 7))
#define WIDE_LUT4(m) WIDE_LUT(m), WIDE_LUT((m) + 1), WIDE_LUT((m) + 2), WIDE_LUT((m) + 3)
#define WIDE_LUT16(m) WIDE_LUT4(m), WIDE_LUT4((m) + 4), WIDE_LUT4((m) + 8), WIDE_LUT4((m) + 12)
#define WIDE_LUT64(m) WIDE_LUT16(m), WIDE_LUT16((m) + 16), WIDE_LUT16((m) + 32), WIDE_LUT16((m) + 48)
static const uint32_t wide_compress_lut[256] = {WIDE_LUT64(0u), WIDE_LUT64(64u), WIDE_LUT64(128u),
                                                WIDE_LUT64(192u)};
static_assert(WIDE_LUT(0x26u) == 0x125u, "compress table: positions 5, 2, 1");

/* fN_op for a width given as a macro: WIDE_V(8, mul) is f8_mul. */
#define WIDE_V_(n, op) f##n##_##op
#define WIDE_V(n, op) WIDE_V_(n, op)
#define WIDE_T_(n) f##n
#define WIDE_T(n) WIDE_T_(n)
/* kN_op and kN for a width given as a macro: WIDE_K(8, or) is k8_or. */
#define WIDE_K_(n, op) k##n##_##op
#define WIDE_K(n, op) WIDE_K_(n, op)
#define WIDE_KT_(n) k##n
#define WIDE_KT(n) WIDE_KT_(n)

#ifdef __cplusplus
}
#endif

#endif
