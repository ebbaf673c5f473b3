/*
 * inst_wide.h - the SIMD pieces of the `instanced` traversal, internal to
 * instanced/ (inst_trace.c): the slab test of one 8-wide node (inst_impl.h's
 * inst_wnode) against one ray, every child box grown by a pad; and the
 * world triangle of an instance, as the flattener computes it.
 *
 * Lane by lane it is box3_slab (core/geom.h, Ize's robust test) on the box
 * grown as inst_trace.c's binary walk grows it (lo - pad, hi + pad, in
 * float), with the very float operations in the same order: products
 * rounded before sums (no fused multiply-add), t0 = max(max(max(t_near,
 * x), y), z) with maxf's NaN rule (_mm256_max_ps(x, acc) is x > acc ? x :
 * acc), the far side padded by ACCEL_SLAB_PAD. So a lane answers exactly as
 * the scalar test on that box, and the binary walk's conservative argument
 * (README.md: the pad) carries over unchanged. An empty slot (lo +inf, hi
 * -inf) gives t0 = +inf against t1 = -inf (or NaN): never a hit.
 */
#ifndef INSTANCED_INST_WIDE_H
#define INSTANCED_INST_WIDE_H

#include "inst_impl.h"

#if defined(__AVX2__) && !defined(INST_NO_SIMD)
#include <immintrin.h>
#define INST_WIDE_AVX 1
#else
#define INST_WIDE_AVX 0
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Bit c set when child c's box grown by pad meets [t_near, t_far] of the ray
 * (org, inv = 1/dir, neg = sign bits of dir); entry[c] its entry distance.
 * padded = 0 skips the growth (pad 0: the top level, identity instances). */
static inline __attribute__((always_inline)) unsigned
inst_wide_hits(const inst_wnode *n, vec3 org, vec3 inv, const int *neg, float pad, float t_near,
               float t_far, int padded, float *entry)
{
#if INST_WIDE_AVX
    const float o[3] = {org.x, org.y, org.z}, iv[3] = {inv.x, inv.y, inv.z};
    __m256 p = _mm256_set1_ps(pad);
    __m256 t0 = _mm256_set1_ps(t_near), t1 = _mm256_set1_ps(t_far);
    for (int a = 0; a < 3; a++) {
        __m256 lo = _mm256_load_ps(n->box[2 * a]), hi = _mm256_load_ps(n->box[2 * a + 1]);
        if (padded) lo = _mm256_sub_ps(lo, p), hi = _mm256_add_ps(hi, p);
        __m256 nr = neg[a] ? hi : lo, fr = neg[a] ? lo : hi;
        __m256 ov = _mm256_set1_ps(o[a]), ivv = _mm256_set1_ps(iv[a]);
        t0 = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(nr, ov), ivv), t0);
        t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(fr, ov), ivv), t1);
    }
    __m256 abs1 = _mm256_andnot_ps(_mm256_set1_ps(-0.0f), t1);
    __m256 lim = _mm256_add_ps(t1, _mm256_mul_ps(abs1, _mm256_set1_ps(ACCEL_SLAB_PAD)));
    _mm256_storeu_ps(entry, t0);
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t0, lim, _CMP_LE_OQ));
#else
    unsigned m = 0;
    for (int c = 0; c < INST_WIDE; c++) {
        float lo[3] = {n->box[0][c], n->box[2][c], n->box[4][c]};
        float hi[3] = {n->box[1][c], n->box[3][c], n->box[5][c]};
        if (padded)
            for (int a = 0; a < 3; a++) lo[a] -= pad, hi[a] += pad;
        m |= (unsigned)box3_slab(lo, hi, org, inv, neg, t_near, t_far, &entry[c]) << c;
    }
    return m;
#endif
}

/* The world triangle of mesh triangle m: accel_xform_vertex, the
 * flattener's expression, bit for bit (per row fma(r0, x, fma(r1, y,
 * fma(r2, z, r3))) rounded once to float), with the three rows as the
 * lanes of one 4-double vector. w gets 12 floats (the last unused). */
static inline __attribute__((always_inline)) void
inst_xform_tri(const inst_item *it, const float *m, float *w)
{
#if INST_WIDE_AVX && defined(__FMA__)
    __m256d c0 = _mm256_loadu_pd(it->cols), c1 = _mm256_loadu_pd(it->cols + 4);
    __m256d c2 = _mm256_loadu_pd(it->cols + 8), c3 = _mm256_loadu_pd(it->cols + 12);
    for (int k = 0; k < 3; k++) {
        const float *p = m + 3 * k;
        __m256d acc = _mm256_fmadd_pd(c2, _mm256_set1_pd((double)p[2]), c3);
        acc = _mm256_fmadd_pd(c1, _mm256_set1_pd((double)p[1]), acc);
        acc = _mm256_fmadd_pd(c0, _mm256_set1_pd((double)p[0]), acc);
        _mm_storeu_ps(w + 3 * k, _mm256_cvtpd_ps(acc));
    }
#else
    for (int k = 0; k < 3; k++) accel_xform_vertex(it->xform, m + 3 * k, w + 3 * k);
#endif
}

#ifdef __cplusplus
}
#endif

#endif
