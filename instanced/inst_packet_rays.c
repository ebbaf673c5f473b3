/*
 * inst_packet_rays.c - the rays of an `instanced` packet (traverse=packet,
 * inst_packet.h): loaded and prepared in world space, taken to an
 * instance's object space (4 at a time in AVX double, each lane the
 * scalar code's operations: inst_ray.h), and the frustum's bounds of a
 * view.
 */
#include <math.h>
#include <string.h>

#include "inst_packet.h"

/* The frustum's bounds: none unless the rays share an octant and their
 * reciprocals are finite. */
void ip_bounds(ip_view *v, uint64_t m)
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
        __m256 keep = ip_lanes(gm);
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

/* Ray r of the packet in instance it's object space (inst_ray.h), into
 * the view ov; 1 when it reaches the mesh's padded box. */
static int ip_object1(const inst_accel *a, const inst_item *it, const inst_bottom *b, ip_packet *pk,
                      ip_view *ov, unsigned r, int counted)
{
    inst_oray o;
    const double wo[3] = {pk->top.ox[r], pk->top.oy[r], pk->top.oz[r]};
    const double wd[3] = {pk->dx[r], pk->dy[r], pk->dz[r]};
    int clip = inst_object_ray(a, it, b, wo, wd, pk->top.lo[r], pk->t[r], &o);
    if (clip >= 0 && counted) pk->boxes[r]++;
    if (clip <= 0) return 0;
    vec3 of, df;
    float padf;
    inst_object_float(a, b, &o, &of, &df, &padf);
    ov->ox[r] = of.x, ov->oy[r] = of.y, ov->oz[r] = of.z;
    ov->ix[r] = 1.0f / df.x, ov->iy[r] = 1.0f / df.y, ov->iz[r] = 1.0f / df.z;
    ov->pad[r] = padf;
    ov->shift[r] = o.s0;
    ov->lo[r] = inst_walk_lo(pk->top.lo[r], o.s0, ov->slack);
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
/* Long on purpose (104 lines): it mirrors ip_object1 operation by
 * operation over four lanes (above), which is what keeps the bits equal;
 * split, that line-by-line correspondence would be lost. */
static uint64_t ip_object4(const inst_accel *a, const inst_item *it, const inst_bottom *b,
                           ip_packet *pk, ip_view *ov, const unsigned *rr, int n, int counted)
{
    const double *m = it->inverse;
    const __m256d sign = _mm256_set1_pd(-0.0), inf = _mm256_set1_pd(INFINITY), zero = _mm256_setzero_pd();
#define IP_DABS(x) _mm256_andnot_pd(sign, (x))
    __m256d wo[3], wd[3], o[3], d[3];
    for (int k = 0; k < 3; k++) {
        const float *ro = k == 0 ? pk->top.ox : k == 1 ? pk->top.oy : pk->top.oz;
        const float *rd = k == 0 ? pk->dx : k == 1 ? pk->dy : pk->dz;
        wo[k] = _mm256_cvtps_pd(_mm_set_ps(ro[rr[3]], ro[rr[2]], ro[rr[1]], ro[rr[0]]));
        wd[k] = _mm256_cvtps_pd(_mm_set_ps(rd[rr[3]], rd[rr[2]], rd[rr[1]], rd[rr[0]]));
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
    const float *ptn = pk->top.lo;
    __m256d tn = _mm256_set_pd(ptn[rr[3]], ptn[rr[2]], ptn[rr[1]], ptn[rr[0]]);
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

uint64_t ip_objects(const inst_accel *a, const inst_item *it, const inst_bottom *b, ip_packet *pk,
                    ip_view *ov, uint64_t m, int counted)
{
    ov->slack = 0x1p-20f;
    ov->padded = !a->no_pad;
    uint64_t keep = 0;
#if INST_WIDE_AVX
    unsigned rr[4];
    int n = 0;
    for (uint64_t q = m; q; q &= q - 1) {
        rr[n++] = (unsigned)__builtin_ctzll(q);
        if (n == 4 || !(q & (q - 1))) {
            for (int l = n; l < 4; l++) rr[l] = rr[0]; /* lanes beyond n: ignored */
            keep |= ip_object4(a, it, b, pk, ov, rr, n, counted);
            n = 0;
        }
    }
#else
    for (uint64_t q = m; q; q &= q - 1)
        if (ip_object1(a, it, b, pk, ov, (unsigned)__builtin_ctzll(q), counted))
            keep |= IP_BIT(__builtin_ctzll(q));
#endif
    if (!keep) return 0;
    /* Lanes of the groups in use that hold no ray: an empty range. */
    for (unsigned g = 0; g < IP_RAYS / 8; g++) {
        unsigned gm = (unsigned)(keep >> (8 * g)) & 0xFFu;
        if (!gm || gm == 0xFFu) continue;
        for (unsigned l = 0; l < 8; l++) {
            unsigned r = 8 * g + l;
            if (gm >> l & 1u) continue;
            ov->ox[r] = ov->oy[r] = ov->oz[r] = 0.0f, ov->ix[r] = ov->iy[r] = ov->iz[r] = 1.0f;
            ov->pad[r] = 0.0f, ov->lo[r] = INFINITY, ov->hi[r] = -INFINITY, ov->shift[r] = 0.0;
        }
    }
    ip_bounds(ov, keep);
    return keep;
}

/* Ray r of the packet from its prepared form p (valid), or dead (p NULL:
 * an empty range). */
static void ip_put(ip_packet *pk, unsigned r, const accel_ray_prep *p)
{
    ip_view *v = &pk->top;
    if (!p) {
        v->ox[r] = v->oy[r] = v->oz[r] = 0.0f, v->ix[r] = v->iy[r] = v->iz[r] = 1.0f;
        v->lo[r] = INFINITY, v->hi[r] = -INFINITY, pk->t[r] = -INFINITY;
        pk->dx[r] = pk->dy[r] = pk->dz[r] = 0.0f;
        pk->sx[r] = pk->sy[r] = pk->sz[r] = 0.0f, pk->tf[r] = -INFINITY;
        pk->kx[r] = 0, pk->ky[r] = 1, pk->kz[r] = 2;
        pk->live &= ~IP_BIT(r);
        return;
    }
    v->ox[r] = p->org.x, v->oy[r] = p->org.y, v->oz[r] = p->org.z;
    v->ix[r] = p->inv_dir.x, v->iy[r] = p->inv_dir.y, v->iz[r] = p->inv_dir.z;
    v->lo[r] = p->t_near, v->hi[r] = pk->t[r] = p->t_far;
    pk->dx[r] = p->dir.x, pk->dy[r] = p->dir.y, pk->dz[r] = p->dir.z;
    pk->sx[r] = p->sx, pk->sy[r] = p->sy, pk->sz[r] = p->sz, pk->tf[r] = p->t_far;
    pk->kx[r] = p->kx, pk->ky[r] = p->ky, pk->kz[r] = p->kz;
    pk->live |= IP_BIT(r);
}

#if INST_WIDE_AVX
/* accel_prep_ray (core/prim.h) for the 8 rays of group g at once, into
 * the packet's rows: the same IEEE operations (the reciprocals and shears
 * are divisions, exactly rounded in both), the same choice of axes. A
 * lane the scalar code would reject (a ray that can hit nothing) goes to
 * it. Writing rows, not 8 prepared structures, halves the load's stores. */
static void ip_prep8(ip_packet *pk, const accel_ray *rays, unsigned g)
{
    __m256 row[8], t[8], u[8], f[8];
    for (int i = 0; i < 8; i++) row[i] = _mm256_loadu_ps(&rays[i].ox);
    /* 8x8 transpose: f[k] holds field k (ox, oy, oz, t_near, dx, dy, dz, t_far) of the 8 rays */
    for (int i = 0; i < 8; i += 2) {
        t[i] = _mm256_unpacklo_ps(row[i], row[i + 1]);
        t[i + 1] = _mm256_unpackhi_ps(row[i], row[i + 1]);
    }
    for (int i = 0; i < 8; i += 4) {
        u[i] = _mm256_shuffle_ps(t[i], t[i + 2], _MM_SHUFFLE(1, 0, 1, 0));
        u[i + 1] = _mm256_shuffle_ps(t[i], t[i + 2], _MM_SHUFFLE(3, 2, 3, 2));
        u[i + 2] = _mm256_shuffle_ps(t[i + 1], t[i + 3], _MM_SHUFFLE(1, 0, 1, 0));
        u[i + 3] = _mm256_shuffle_ps(t[i + 1], t[i + 3], _MM_SHUFFLE(3, 2, 3, 2));
    }
    for (int i = 0; i < 4; i++) {
        f[i] = _mm256_permute2f128_ps(u[i], u[i + 4], 0x20);
        f[i + 4] = _mm256_permute2f128_ps(u[i], u[i + 4], 0x31);
    }
    const __m256 sign = _mm256_set1_ps(-0.0f), inf = _mm256_set1_ps(INFINITY), one = _mm256_set1_ps(1.0f);
    const __m256 zero = _mm256_setzero_ps();
    const __m256 *o = f, *d = f + 4;
    const __m256 tn = f[3], tf = f[7];
    __m256 ok = _mm256_cmp_ps(tn, tf, _CMP_LE_OQ);
    for (int k = 0; k < 3; k++) {
        ok = _mm256_and_ps(ok, _mm256_cmp_ps(_mm256_andnot_ps(sign, o[k]), inf, _CMP_LT_OQ));
        ok = _mm256_and_ps(ok, _mm256_cmp_ps(_mm256_andnot_ps(sign, d[k]), inf, _CMP_LT_OQ));
    }
    __m256 ax = _mm256_andnot_ps(sign, d[0]), ay = _mm256_andnot_ps(sign, d[1]), az = _mm256_andnot_ps(sign, d[2]);
    /* kz = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2); then kx, ky
     * (kz 0: 1, 2; kz 1: 2, 0; kz 2: 0, 1), swapped where d[kz] < 0 */
    __m256 c0 = _mm256_and_ps(_mm256_cmp_ps(ax, ay, _CMP_GE_OQ), _mm256_cmp_ps(ax, az, _CMP_GE_OQ));
    __m256 c1 = _mm256_cmp_ps(ay, az, _CMP_GE_OQ);
    __m256 dkz = _mm256_blendv_ps(_mm256_blendv_ps(d[2], d[1], c1), d[0], c0);
    __m256 dkx = _mm256_blendv_ps(_mm256_blendv_ps(d[0], d[2], c1), d[1], c0);
    __m256 dky = _mm256_blendv_ps(_mm256_blendv_ps(d[1], d[0], c1), d[2], c0);
    __m256 swap = _mm256_cmp_ps(dkz, zero, _CMP_LT_OQ);
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(dkz, zero, _CMP_NEQ_UQ));
    __m256i kz = _mm256_castps_si256(_mm256_blendv_ps(_mm256_blendv_ps(_mm256_castsi256_ps(_mm256_set1_epi32(2)),
                                                                      _mm256_castsi256_ps(_mm256_set1_epi32(1)), c1),
                                                     _mm256_castsi256_ps(_mm256_setzero_si256()), c0));
    __m256i kx0 = _mm256_castps_si256(_mm256_blendv_ps(_mm256_blendv_ps(_mm256_castsi256_ps(_mm256_setzero_si256()),
                                                                       _mm256_castsi256_ps(_mm256_set1_epi32(2)), c1),
                                                      _mm256_castsi256_ps(_mm256_set1_epi32(1)), c0));
    __m256i ky0 = _mm256_castps_si256(_mm256_blendv_ps(_mm256_blendv_ps(_mm256_castsi256_ps(_mm256_set1_epi32(1)),
                                                                       _mm256_castsi256_ps(_mm256_setzero_si256()), c1),
                                                      _mm256_castsi256_ps(_mm256_set1_epi32(2)), c0));
    __m256 kxs = _mm256_blendv_ps(_mm256_castsi256_ps(kx0), _mm256_castsi256_ps(ky0), swap);
    __m256 kys = _mm256_blendv_ps(_mm256_castsi256_ps(ky0), _mm256_castsi256_ps(kx0), swap);
    __m256 sxn = _mm256_blendv_ps(dkx, dky, swap), syn = _mm256_blendv_ps(dky, dkx, swap);
    const unsigned r = 8 * g;
    ip_view *v = &pk->top;
    _mm256_store_ps(v->ox + r, o[0]), _mm256_store_ps(v->oy + r, o[1]), _mm256_store_ps(v->oz + r, o[2]);
    _mm256_store_ps(pk->dx + r, d[0]), _mm256_store_ps(pk->dy + r, d[1]), _mm256_store_ps(pk->dz + r, d[2]);
    _mm256_store_ps(v->ix + r, _mm256_div_ps(one, d[0]));
    _mm256_store_ps(v->iy + r, _mm256_div_ps(one, d[1]));
    _mm256_store_ps(v->iz + r, _mm256_div_ps(one, d[2]));
    _mm256_store_ps(v->lo + r, tn), _mm256_store_ps(v->hi + r, tf);
    _mm256_storeu_ps(pk->t + r, tf), _mm256_store_ps(pk->tf + r, tf);
    _mm256_store_ps(pk->sx + r, _mm256_div_ps(sxn, dkz));
    _mm256_store_ps(pk->sy + r, _mm256_div_ps(syn, dkz));
    _mm256_store_ps(pk->sz + r, _mm256_div_ps(one, dkz));
    _mm256_store_si256((__m256i *)(pk->kx + r), _mm256_castps_si256(kxs));
    _mm256_store_si256((__m256i *)(pk->ky + r), _mm256_castps_si256(kys));
    _mm256_store_si256((__m256i *)(pk->kz + r), kz);
    unsigned valid = (unsigned)_mm256_movemask_ps(ok);
    pk->live |= (uint64_t)valid << r;
    for (unsigned bad = ~valid & 0xFFu; bad; bad &= bad - 1) { /* the scalar code decides */
        unsigned l = (unsigned)__builtin_ctz(bad);
        accel_ray_prep p;
        ip_put(pk, r + l, accel_prep_ray(&rays[l], &p) ? &p : NULL);
    }
}
#endif

void ip_load(ip_packet *pk, const accel_ray *rays, unsigned n, int any, int counted)
{
    ip_view *v = &pk->top;
    pk->live = 0;
    pk->any = any;
    pk->rects = 0;
    v->slack = 0.0f, v->padded = 0;
    /* The top view's pads and shifts stay 0 (ip_kernel); u, v are read
     * only where a hit set them; the counters only when counted. */
    if (counted)
        for (unsigned r = 0; r < IP_RAYS; r++)
            pk->top_steps[r] = pk->bottom_steps[r] = pk->boxes[r] = pk->prims[r] = 0;
    for (unsigned r = 0; r < IP_RAYS; r++) pk->prim[r] = ACCEL_MISS;
    for (unsigned g = 0; g < IP_RAYS / 8; g++) {
#if INST_WIDE_AVX
        if (8 * g + 8 <= n) {
            ip_prep8(pk, rays + 8 * g, g);
            continue;
        }
#endif
        for (unsigned r = 8 * g; r < 8 * g + 8; r++) {
            accel_ray_prep p;
            ip_put(pk, r, r < n && accel_prep_ray(&rays[r], &p) ? &p : NULL);
        }
    }
    /* shared: every live ray has the first one's origin (bits) and axes */
    pk->shared = 1;
    if (pk->live) {
        const unsigned r0 = (unsigned)__builtin_ctzll(pk->live);
        for (uint64_t k = pk->live & (pk->live - 1); k && pk->shared; k &= k - 1) {
            const unsigned r = (unsigned)__builtin_ctzll(k);
            pk->shared = !memcmp(&v->ox[r], &v->ox[r0], sizeof(float)) &&
                         !memcmp(&v->oy[r], &v->oy[r0], sizeof(float)) &&
                         !memcmp(&v->oz[r], &v->oz[r0], sizeof(float)) && pk->kx[r] == pk->kx[r0] &&
                         pk->ky[r] == pk->ky[r0] && pk->kz[r] == pk->kz[r0];
        }
    }
    ip_bounds(v, pk->live);
}
