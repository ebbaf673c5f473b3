/*
 * grid_packet_filter.h - the conservative filters of the coherent grid
 * traversal (grid_packet_trace.c): which active rays of a packet may hit a
 * primitive.
 * A kernel body (C only): included by the .c files of its folder, not part
 * of the interface a C++ program includes.
 * A filter only drops a (ray, primitive) pair that the exact test
 * accel_prim_hit (core/prim.h) would reject; the argument for each bound is
 * in grid_packet_trace.c's header. Private to grid/, but for nested_grid/ through
 * grid_packet_walk.h.
 */
#ifndef GRID_GRID_PACKET_FILTER_H
#define GRID_GRID_PACKET_FILTER_H

#include "grid_packet.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A triangle seen from the packet: per edge AB, BC, CA the Pluecker
 * moments A'xB' (A' = A - ref) and the edge vectors B - A. */
typedef struct {
    double m[3][3];
    double e[3][3];
    double rt; /* largest 1-norm of A', B', C' */
} grid_packet_tri;

static inline void grid_packet_tri_prepare(const grid_packet *pk, const float *tri,
                                           grid_packet_tri *t)
{
    double v[3][3];
    t->rt = 0.0;
    for (int k = 0; k < 3; k++) {
        double r = 0.0;
        for (int a = 0; a < 3; a++) {
            v[k][a] = (double)tri[3 * k + a] - pk->ref[a];
            r += fabs(v[k][a]);
        }
        t->rt = r > t->rt ? r : t->rt;
    }
    for (int k = 0; k < 3; k++) {
        const int k2 = k == 2 ? 0 : k + 1;
        const double *a = v[k], *b = v[k2];
        t->m[k][0] = a[1] * b[2] - a[2] * b[1];
        t->m[k][1] = a[2] * b[0] - a[0] * b[2];
        t->m[k][2] = a[0] * b[1] - a[1] * b[0];
        for (int c = 0; c < 3; c++) t->e[k][c] = (double)tri[3 * k2 + c] - (double)tri[3 * k + c];
    }
}

/* 1 when the triangle lies wholly on one side of every line of `bounded`
 * on axis a1 or a2: each line is u = u0 + s (z - z0), so over the packet
 * u(z) lies between the concave L(z) = u0_lo + min(s_lo dz, s_hi dz) and the
 * convex H(z); a triangle whose three vertices lie below L (above H) lies
 * below L (above H) everywhere, by convexity. */
static inline int grid_packet_tri_outside(const grid_packet *pk, const float *tri)
{
    const int K = pk->axis[0];
    for (int j = 0; j < 2; j++) {
        const int a = pk->axis[1 + j];
        const double lo = pk->u0_lo[j] - pk->pad_env[j], hi = pk->u0_hi[j] + pk->pad_env[j];
        int below = 1, above = 1;
        for (int k = 0; k < 3 && (below || above); k++) {
            const double dz = (double)tri[3 * k + K] - pk->z0, u = tri[3 * k + a];
            const double p = pk->s_lo[j] * dz, q = pk->s_hi[j] * dz;
            below &= u < lo + (p < q ? p : q);
            above &= u > hi + (p > q ? p : q);
        }
        if (below || above) return 1;
    }
    return 0;
}

/* The same for a sphere (centre c, radius r): its bounding box lies below L
 * or above H over its extent on K (L concave, H convex: their extremes over
 * an interval of z are at its ends). The exact test accepts lines passing
 * up to sqrt(64 u (r^2 + |O - c|^2)) beyond r (see the sphere filter), so
 * the box is widened by 2^-19 (r + |c - ref|_1 + |O - ref|_1). */
static inline int grid_packet_sphere_outside(const grid_packet *pk, const float *sph)
{
    const int K = pk->axis[0];
    const double cr = fabs(sph[0] - pk->ref[0]) + fabs(sph[1] - pk->ref[1]) + fabs(sph[2] - pk->ref[2]);
    const double r = sph[3] + 0x1p-19 * (sph[3] + cr + pk->omag_max);
    const double z_a = (double)sph[K] - r - pk->z0, z_b = (double)sph[K] + r - pk->z0;
    for (int j = 0; j < 2; j++) {
        const double u = sph[pk->axis[1 + j]];
        const double pa = pk->s_lo[j] * z_a, qa = pk->s_hi[j] * z_a;
        const double pb = pk->s_lo[j] * z_b, qb = pk->s_hi[j] * z_b;
        const double lo = pk->u0_lo[j] - pk->pad_env[j], hi = pk->u0_hi[j] + pk->pad_env[j];
        const double l = lo + (pa < qa ? pa : qa), l2 = lo + (pb < qb ? pb : qb);
        const double h = hi + (pa > qa ? pa : qa), h2 = hi + (pb > qb ? pb : qb);
        if (u + r < (l < l2 ? l : l2) || u - r > (h > h2 ? h : h2)) return 1;
    }
    return 0;
}

/* 1 when no active ray can meet the triangle (9 floats) within the
 * current slice: its bounding box misses the slice's hull on a1 or a2. */
static inline int grid_packet_tri_slice_outside(const grid_packet *pk, const float *tri,
                                                const double hull[2][2])
{
    for (int j = 0; j < 2; j++) {
        const int a = pk->axis[1 + j];
        const float u0 = tri[a], u1 = tri[3 + a], u2 = tri[6 + a];
        const float lo = u0 < u1 ? (u0 < u2 ? u0 : u2) : (u1 < u2 ? u1 : u2);
        const float hi = u0 > u1 ? (u0 > u2 ? u0 : u2) : (u1 > u2 ? u1 : u2);
        if (hi < hull[j][0] || lo > hull[j][1]) return 1;
    }
    return 0;
}

/* 1 when no active ray can meet the primitive within the current slice:
 * its bounding box misses the slice's hull on a1 or a2 (spheres widened as
 * in grid_packet_sphere_outside). */
static inline int grid_packet_slice_outside(const grid_packet *pk, const accel_scene *s,
                                            uint32_t prim, int spheres, const double hull[2][2])
{
    if (spheres && prim >= s->tri_count) {
        const float *sph = s->spheres + 4 * (size_t)(prim - s->tri_count);
        const double cr = fabs(sph[0] - pk->ref[0]) + fabs(sph[1] - pk->ref[1]) + fabs(sph[2] - pk->ref[2]);
        const double r = sph[3] + 0x1p-19 * (sph[3] + cr + pk->omag_max);
        for (int j = 0; j < 2; j++) {
            const double u = sph[pk->axis[1 + j]];
            if (u + r < hull[j][0] || u - r > hull[j][1]) return 1;
        }
        return 0;
    }
    return grid_packet_tri_slice_outside(pk, s->tris + 9 * (size_t)prim, hull);
}

/* 1 when no ray of `bounded` can hit the triangle: interval bounds of the
 * three edge products over the packet's boxes of D and M, one below -E and
 * one above E (E the largest per-ray margin, doubled for the interval
 * sums' own rounding). */
static inline int grid_packet_tri_culled(const grid_packet *pk, const grid_packet_tri *t)
{
    const double x = t->rt + pk->omag_max, e = 2.0 * pk->emag_max * x * x;
    int below = 0, above = 0;
    for (int k = 0; k < 3; k++) {
        double lo = 0.0, hi = 0.0;
        for (int c = 0; c < 3; c++) {
            double a = t->m[k][c] * pk->d_lo[c], b = t->m[k][c] * pk->d_hi[c];
            lo += a < b ? a : b, hi += a > b ? a : b;
            if (!pk->common) {
                a = t->e[k][c] * pk->m_lo[c], b = t->e[k][c] * pk->m_hi[c];
                lo += a < b ? a : b, hi += a > b ? a : b;
            }
        }
        below |= hi < -e;
        above |= lo > e;
    }
    return below && above;
}

/* Active rays the triangle filter keeps (4 rays per step): a lane goes
 * when some edge product is below -E and another above E,
 * E = GRID_PACKET_REL |D|_1 (rt + |O'|_1)^2. */
static inline uint64_t grid_packet_tri_filter(const grid_packet *pk, const grid_packet_tri *t,
                                              uint64_t *evals)
{
    uint64_t keep = 0;
#if GRID_PACKET_AVX
    __m256d m[3][3], e[3][3];
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++) {
            m[k][c] = _mm256_set1_pd(t->m[k][c]);
            e[k][c] = _mm256_set1_pd(t->e[k][c]);
        }
    const __m256d rt = _mm256_set1_pd(t->rt), sign = _mm256_set1_pd(-0.0);
#endif
    for (uint64_t a = pk->active; a;) {
        const int o = 4 * (__builtin_ctzll(a) >> 2);
        a &= ~((uint64_t)0xF << o);
        (*evals)++;
#if GRID_PACKET_AVX
        const __m256d dx = _mm256_load_pd(pk->dx + o), dy = _mm256_load_pd(pk->dy + o),
                      dz = _mm256_load_pd(pk->dz + o);
        __m256d s[3];
        for (int k = 0; k < 3; k++)
            s[k] = _mm256_fmadd_pd(dz, m[k][2], _mm256_fmadd_pd(dy, m[k][1], _mm256_mul_pd(dx, m[k][0])));
        if (!pk->common) {
            const __m256d mx = _mm256_load_pd(pk->mx + o), my = _mm256_load_pd(pk->my + o),
                          mz = _mm256_load_pd(pk->mz + o);
            for (int k = 0; k < 3; k++)
                s[k] = _mm256_fmadd_pd(mz, e[k][2], _mm256_fmadd_pd(my, e[k][1], _mm256_fmadd_pd(mx, e[k][0], s[k])));
        }
        const __m256d x = _mm256_add_pd(rt, _mm256_load_pd(pk->omag + o));
        const __m256d lim = _mm256_mul_pd(_mm256_mul_pd(x, x), _mm256_load_pd(pk->emag + o));
        const __m256d nlim = _mm256_xor_pd(lim, sign);
        const __m256d neg = _mm256_or_pd(_mm256_or_pd(_mm256_cmp_pd(s[0], nlim, _CMP_LT_OQ),
                                                      _mm256_cmp_pd(s[1], nlim, _CMP_LT_OQ)),
                                         _mm256_cmp_pd(s[2], nlim, _CMP_LT_OQ));
        const __m256d pos = _mm256_or_pd(_mm256_or_pd(_mm256_cmp_pd(s[0], lim, _CMP_GT_OQ),
                                                      _mm256_cmp_pd(s[1], lim, _CMP_GT_OQ)),
                                         _mm256_cmp_pd(s[2], lim, _CMP_GT_OQ));
        const uint64_t rej = (uint64_t)_mm256_movemask_pd(_mm256_and_pd(neg, pos));
        keep |= (~rej & 0xFu) << o;
#else
        for (int l = o; l < o + 4; l++) {
            const double x = t->rt + pk->omag[l], lim = pk->emag[l] * x * x;
            int neg = 0, pos = 0;
            for (int k = 0; k < 3; k++) {
                const double s = pk->dx[l] * t->m[k][0] + pk->dy[l] * t->m[k][1] +
                                 pk->dz[l] * t->m[k][2] + pk->mx[l] * t->e[k][0] +
                                 pk->my[l] * t->e[k][1] + pk->mz[l] * t->e[k][2];
                neg |= s < -lim;
                pos |= s > lim;
            }
            keep |= (uint64_t)!(neg && pos) << l;
        }
#endif
    }
    return keep & pk->active;
}

/* Active rays the sphere filter keeps: a lane goes when
 * |X|^2 > |D|^2 (r^2 + 2^-38 (r + |C'|_1 + |O'|_1)^2), X = (C - O) x D
 * = C' x D - M, |X| / |D| the distance of the centre to the line. */
static inline uint64_t grid_packet_sphere_filter(const grid_packet *pk, const float *sph,
                                                 uint64_t *evals)
{
    const double c[3] = {(double)sph[0] - pk->ref[0], (double)sph[1] - pk->ref[1],
                         (double)sph[2] - pk->ref[2]};
    const double r = sph[3], rc = r + fabs(c[0]) + fabs(c[1]) + fabs(c[2]);
    const double rel = 4.0 * GRID_PACKET_REL;
    uint64_t keep = 0;
    for (uint64_t a = pk->active; a;) {
        const int o = 4 * (__builtin_ctzll(a) >> 2);
        a &= ~((uint64_t)0xF << o);
        (*evals)++;
#if GRID_PACKET_AVX
        const __m256d dx = _mm256_load_pd(pk->dx + o), dy = _mm256_load_pd(pk->dy + o),
                      dz = _mm256_load_pd(pk->dz + o);
        const __m256d cx = _mm256_set1_pd(c[0]), cy = _mm256_set1_pd(c[1]), cz = _mm256_set1_pd(c[2]);
        const __m256d x = _mm256_sub_pd(_mm256_fmsub_pd(cy, dz, _mm256_mul_pd(cz, dy)), _mm256_load_pd(pk->mx + o));
        const __m256d y = _mm256_sub_pd(_mm256_fmsub_pd(cz, dx, _mm256_mul_pd(cx, dz)), _mm256_load_pd(pk->my + o));
        const __m256d z = _mm256_sub_pd(_mm256_fmsub_pd(cx, dy, _mm256_mul_pd(cy, dx)), _mm256_load_pd(pk->mz + o));
        const __m256d x2 = _mm256_fmadd_pd(z, z, _mm256_fmadd_pd(y, y, _mm256_mul_pd(x, x)));
        const __m256d q = _mm256_add_pd(_mm256_set1_pd(rc), _mm256_load_pd(pk->omag + o));
        const __m256d lim = _mm256_mul_pd(_mm256_load_pd(pk->d2 + o),
                                          _mm256_fmadd_pd(_mm256_mul_pd(q, q), _mm256_set1_pd(rel),
                                                          _mm256_set1_pd(r * r)));
        const uint64_t rej = (uint64_t)_mm256_movemask_pd(_mm256_cmp_pd(x2, lim, _CMP_GT_OQ));
        keep |= (~rej & 0xFu) << o;
#else
        for (int l = o; l < o + 4; l++) {
            const double x = c[1] * pk->dz[l] - c[2] * pk->dy[l] - pk->mx[l];
            const double y = c[2] * pk->dx[l] - c[0] * pk->dz[l] - pk->my[l];
            const double z = c[0] * pk->dy[l] - c[1] * pk->dx[l] - pk->mz[l];
            const double q = rc + pk->omag[l];
            keep |= (uint64_t)!(x * x + y * y + z * z > pk->d2[l] * (r * r + rel * q * q)) << l;
        }
#endif
    }
    return keep & pk->active;
}

/* Active rays that need no slice beyond w_out (w = kstep * z): their
 * nearest hit, box exit or t_far lies at or before it. Also refreshes
 * w_next over the rays that stay. */
static inline uint64_t grid_packet_leaving(grid_packet *pk, double w_out)
{
    uint64_t out = 0;
    double next = INFINITY;
#if GRID_PACKET_AVX
    const __m256d w = _mm256_set1_pd(w_out);
    __m256d nx = _mm256_set1_pd(INFINITY);
#endif
    for (uint64_t a = pk->active; a;) {
        const int o = 4 * (__builtin_ctzll(a) >> 2);
        a &= ~((uint64_t)0xF << o);
#if GRID_PACKET_AVX
        const __m256d e = _mm256_load_pd(pk->w_end + o), le = _mm256_cmp_pd(e, w, _CMP_LE_OQ);
        out |= (uint64_t)_mm256_movemask_pd(le) << o;
        const __m256d stay = _mm256_andnot_pd(le, grid_packet_lanes(pk->active >> o));
        nx = _mm256_min_pd(nx, _mm256_blendv_pd(_mm256_set1_pd(INFINITY), e, stay));
#else
        for (int l = o; l < o + 4; l++) {
            const int on = (int)(pk->active >> l & 1);
            out |= (uint64_t)(pk->w_end[l] <= w_out) << l;
            next = on && pk->w_end[l] > w_out && pk->w_end[l] < next ? pk->w_end[l] : next;
        }
#endif
    }
    out &= pk->active;
#if GRID_PACKET_AVX
    double b[4];
    _mm256_storeu_pd(b, nx);
    next = b[0] < b[1] ? b[0] : b[1];
    next = next < b[2] ? next : b[2];
    next = next < b[3] ? next : b[3];
#endif
    pk->w_next = next;
    return out;
}

/* After a hit of ray l at its nearest t: the ray needs no slice past it. */
static inline void grid_packet_hit_end(grid_packet *pk, int l)
{
    const double t = pk->t[l], ok = pk->ok[l], dz = t * pk->dk[l];
    const double w = pk->kstep * (ok + dz) + GRID_PACKET_REL * (fabs(ok) + fabs(dz));
    if (w < pk->w_end[l]) pk->w_end[l] = w;
    if (w < pk->w_next) pk->w_next = w;
}

#ifdef __cplusplus
}
#endif

#endif
