/*
 * grid_packet_setup.c - the packet of the coherent grid traversal
 * (grid_packet_trace.c): which rays are live, the axis of the walk, the arrays
 * the filters read, and the range of cells each slice can touch.
 *
 * Liveness is decided exactly as by the single-ray kernel (grid_trace.c):
 * the rays accel_prep_ray accepts, against the grid box by box3_slab; the
 * AVX2 path runs box3_slab's float operations lane by lane on 8 rays, so
 * it accepts the same rays. Everything else is computed in double.
 */
#include <stdlib.h>
#include <string.h>

#include "grid_packet.h"

#define P GRID_PACKET_SIZE

static inline double dmin(double a, double b) { return a < b ? a : b; }
static inline double dmax(double a, double b) { return a > b ? a : b; }

/* Slice of coordinate z on axis K: the lowest slice whose far plane reaches
 * z (dir > 0) or the highest whose near plane does (dir < 0), so that a
 * point on a plane starts in the earlier slice of the walk. */
static int slice_of(const grid_frame *f, int K, double z, int dir)
{
    const int n = f->res[K];
    const float *pl = f->planes[K];
    double g = (z - f->lo[K]) * f->inv_cell[K];
    int k = g >= n ? n - 1 : (g > 0.0 ? (int)g : 0);
    if (dir > 0) {
        while (k > 0 && pl[k] >= z) k--;
        while (k < n - 1 && pl[k + 1] < z) k++;
    } else {
        while (k < n - 1 && pl[k + 1] <= z) k++;
        while (k > 0 && pl[k] > z) k--;
    }
    return k;
}

/* Float data of the live rays (zeros in the other lanes). */
typedef struct {
    _Alignas(32) float o[3][P];
    _Alignas(32) float d[3][P];
    _Alignas(32) float inv[3][P];
    _Alignas(32) float te[P]; /* box3_slab's entry (clamped to t_near) */
    _Alignas(32) float tf[P];
} ray_floats;

#if GRID_PACKET_AVX
/* Rows r[0..7] (8 rays of 8 floats) become columns (8 attributes of 8 rays). */
static inline void transpose8(__m256 r[8])
{
    __m256 t[8], s[8];
    for (int i = 0; i < 4; i++) {
        t[2 * i] = _mm256_unpacklo_ps(r[2 * i], r[2 * i + 1]);
        t[2 * i + 1] = _mm256_unpackhi_ps(r[2 * i], r[2 * i + 1]);
    }
    for (int h = 0; h < 2; h++) {
        __m256 a = t[4 * h], b = t[4 * h + 1], c = t[4 * h + 2], d = t[4 * h + 3];
        s[4 * h] = _mm256_shuffle_ps(a, c, _MM_SHUFFLE(1, 0, 1, 0));
        s[4 * h + 1] = _mm256_shuffle_ps(a, c, _MM_SHUFFLE(3, 2, 3, 2));
        s[4 * h + 2] = _mm256_shuffle_ps(b, d, _MM_SHUFFLE(1, 0, 1, 0));
        s[4 * h + 3] = _mm256_shuffle_ps(b, d, _MM_SHUFFLE(3, 2, 3, 2));
    }
    for (int i = 0; i < 4; i++) {
        r[i] = _mm256_permute2f128_ps(s[i], s[i + 4], 0x20);
        r[i + 4] = _mm256_permute2f128_ps(s[i], s[i + 4], 0x31);
    }
}

/* Rays [8b, 8b+8): validity and box3_slab, 8 lanes at once. */
static uint64_t live_block(const grid_frame *f, const accel_ray *rays, uint32_t n, int b,
                           ray_floats *rf, __m256 mean[3], uint32_t *boxes)
{
    const int o = 8 * b;
    accel_ray tmp[8];
    const accel_ray *src = rays + o;
    if ((uint32_t)o + 8 > n) { /* zero rays (zero direction) are invalid */
        memset(tmp, 0, sizeof tmp);
        if ((uint32_t)o < n) memcpy(tmp, rays + o, (n - (uint32_t)o) * sizeof *tmp);
        src = tmp;
    }
    __m256 r[8];
    for (int i = 0; i < 8; i++) r[i] = _mm256_loadu_ps(&src[i].ox);
    transpose8(r); /* ox oy oz t_near dx dy dz t_far */
    const __m256i expo = _mm256_set1_epi32(0x7f800000);
    __m256i bad = _mm256_setzero_si256();
    for (int a = 0; a < 7; a++)
        if (a != 3)
            bad = _mm256_or_si256(bad, _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_castps_si256(r[a]), expo), expo));
    const __m256 zero = _mm256_setzero_ps();
    __m256 valid = _mm256_andnot_ps(_mm256_castsi256_ps(bad), _mm256_cmp_ps(r[3], r[7], _CMP_LE_OQ));
    valid = _mm256_and_ps(valid, _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(r[4], zero, _CMP_NEQ_OQ),
                                                           _mm256_cmp_ps(r[5], zero, _CMP_NEQ_OQ)),
                                              _mm256_cmp_ps(r[6], zero, _CMP_NEQ_OQ)));
    *boxes += (uint32_t)__builtin_popcount((unsigned)_mm256_movemask_ps(valid));
    /* box3_slab, lane by lane: max_ps(x, acc) keeps acc when x is NaN,
     * as maxf(acc, x) does. */
    const __m256 one = _mm256_set1_ps(1.0f);
    __m256 t0 = r[3], t1 = r[7], inv[3];
    for (int a = 0; a < 3; a++) {
        inv[a] = _mm256_div_ps(one, r[4 + a]);
        __m256 lo = _mm256_set1_ps(f->lo[a]), hi = _mm256_set1_ps(f->hi[a]);
        __m256 near = _mm256_blendv_ps(lo, hi, r[4 + a]), far = _mm256_blendv_ps(hi, lo, r[4 + a]);
        t0 = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(near, r[a]), inv[a]), t0);
        t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(far, r[a]), inv[a]), t1);
    }
    const __m256 sign = _mm256_set1_ps(-0.0f);
    __m256 lim = _mm256_add_ps(t1, _mm256_mul_ps(_mm256_andnot_ps(sign, t1), _mm256_set1_ps(ACCEL_SLAB_PAD)));
    __m256 m = _mm256_and_ps(valid, _mm256_cmp_ps(t0, lim, _CMP_LE_OQ));
    for (int a = 0; a < 3; a++) {
        _mm256_store_ps(rf->o[a] + o, _mm256_and_ps(r[a], m));
        _mm256_store_ps(rf->d[a] + o, _mm256_and_ps(r[4 + a], m));
        _mm256_store_ps(rf->inv[a] + o, _mm256_and_ps(inv[a], m));
        mean[a] = _mm256_add_ps(mean[a], _mm256_and_ps(r[4 + a], m));
    }
    _mm256_store_ps(rf->te + o, _mm256_and_ps(t0, m));
    _mm256_store_ps(rf->tf + o, _mm256_and_ps(r[7], m));
    return (uint64_t)_mm256_movemask_ps(m) << o;
}
#endif

/* The live rays and their float data; sums their directions into mean. */
static uint64_t live_rays(const grid_frame *f, uint64_t ref_count, const accel_ray *rays,
                          uint32_t n, ray_floats *rf, double mean[3], uint32_t *boxes)
{
    uint64_t live = 0;
    *boxes = 0;
    mean[0] = mean[1] = mean[2] = 0.0;
    if (ref_count == 0) n = 0; /* nothing to hit: no ray is traced */
#if GRID_PACKET_AVX
    __m256 sum[3] = {_mm256_setzero_ps(), _mm256_setzero_ps(), _mm256_setzero_ps()};
    for (int b = 0; b < P / 8; b++) live |= live_block(f, rays, n, b, rf, sum, boxes);
    for (int a = 0; a < 3; a++) {
        float s[8];
        _mm256_storeu_ps(s, sum[a]);
        for (int i = 0; i < 8; i++) mean[a] += s[i];
    }
#else
    memset(rf, 0, sizeof *rf);
    for (uint32_t i = 0; i < n; i++) {
        const accel_ray *r = &rays[i];
        if (!(isfinite(r->ox) && isfinite(r->oy) && isfinite(r->oz) && isfinite(r->dx) &&
              isfinite(r->dy) && isfinite(r->dz) && r->t_near <= r->t_far) ||
            (r->dx == 0.0f && r->dy == 0.0f && r->dz == 0.0f))
            continue;
        (*boxes)++;
        const vec3 o = v3(r->ox, r->oy, r->oz), iv = v3(1.0f / r->dx, 1.0f / r->dy, 1.0f / r->dz);
        const int neg[3] = {signbit(r->dx) != 0, signbit(r->dy) != 0, signbit(r->dz) != 0};
        float t_entry;
        if (!box3_slab(f->lo, f->hi, o, iv, neg, r->t_near, r->t_far, &t_entry)) continue;
        live |= (uint64_t)1 << i;
        const float ov[3] = {r->ox, r->oy, r->oz}, dv[3] = {r->dx, r->dy, r->dz};
        const float ivv[3] = {iv.x, iv.y, iv.z};
        for (int a = 0; a < 3; a++) {
            rf->o[a][i] = ov[a], rf->d[a][i] = dv[a], rf->inv[a][i] = ivv[a];
            mean[a] += dv[a];
        }
        rf->te[i] = t_entry;
        rf->tf[i] = r->t_far;
    }
#endif
    return live;
}

/* Largest 1-norm of (O - p) x D / |D|_1 over the live rays: how far p is
 * from the packet's lines. */
static double line_spread(const grid_packet *pk, const ray_floats *rf, const double p[3])
{
    double m = 0.0;
    for (uint64_t b = pk->live; b; b &= b - 1) {
        const int i = __builtin_ctzll(b);
        const double q[3] = {rf->o[0][i] - p[0], rf->o[1][i] - p[1], rf->o[2][i] - p[2]};
        const double d[3] = {rf->d[0][i], rf->d[1][i], rf->d[2][i]};
        const double x = fabs(q[1] * d[2] - q[2] * d[1]) + fabs(q[2] * d[0] - q[0] * d[2]) +
                         fabs(q[0] * d[1] - q[1] * d[0]);
        m = dmax(m, x / (fabs(d[0]) + fabs(d[1]) + fabs(d[2])));
    }
    return m;
}

/* The packet's reference point: the first live origin, or, when the rays
 * end (finite t_far) nearer to each other's lines than they start (shadow
 * rays converging on a light), the first live ray's end. Moments and the
 * coordinates u0 are taken there, so that a packet of rays through one
 * point (a camera, a light) has nearly equal u0 and moments near zero: its
 * interval bounds are then nearly the hull of its rays. */
static void choose_ref(grid_packet *pk, const ray_floats *rf, int first)
{
    for (int a = 0; a < 3; a++) pk->ref[a] = rf->o[a][first];
    const double tf = rf->tf[first];
    if (!isfinite(tf)) return;
    const double spread = line_spread(pk, rf, pk->ref);
    if (spread == 0.0) return;
    double end[3];
    for (int a = 0; a < 3; a++) end[a] = rf->o[a][first] + tf * rf->d[a][first];
    if (line_spread(pk, rf, end) < 0.5 * spread) memcpy(pk->ref, end, sizeof end);
}

int grid_packet_setup(const grid_frame *f, uint64_t ref_count, double max_cells, grid_packet *pk,
                      const accel_ray *rays, uint32_t n)
{
    ray_floats rf;
    double mean[3];
    pk->rays = rays;
    pk->n = n;
    pk->prepped = 0;
    pk->live = live_rays(f, ref_count, rays, n, &rf, mean, &pk->boxes);
    for (int i = 0; i < P; i++) {
        pk->prim[i] = ACCEL_MISS;
        pk->t[i] = pk->live >> i & 1 ? rf.tf[i] : -INFINITY;
        pk->u[i] = pk->v[i] = 0.0f;
    }
    if (!pk->live) return GRID_PACKET_EMPTY;
    const int K = fabs(mean[0]) >= fabs(mean[1]) && fabs(mean[0]) >= fabs(mean[2])
                      ? 0
                      : (fabs(mean[1]) >= fabs(mean[2]) ? 1 : 2);
    const int dir = mean[K] < 0.0 ? -1 : 1;
    const int a1 = K == 0 ? 1 : 0, a2 = K == 2 ? 1 : 2;
    for (uint64_t m = pk->live; m; m &= m - 1)
        if (!(rf.d[K][__builtin_ctzll(m)] * (float)dir > 0.0f)) return GRID_PACKET_SINGLE;
    pk->axis[0] = K, pk->axis[1] = a1, pk->axis[2] = a2;
    pk->kstep = dir;
    const int first = __builtin_ctzll(pk->live);
    choose_ref(pk, &rf, first);
    const double z0 = pk->ref[K];
    pk->z0 = z0;
    pk->zext = dmax(fabs((double)f->planes[K][0] - z0), fabs((double)f->planes[K][f->res[K]] - z0));
    for (int j = 0; j < 2; j++) {
        const int a = pk->axis[1 + j];
        pk->umax[j] = dmax(fabs((double)f->lo[a]), fabs((double)f->hi[a])) + f->pad[a];
        pk->pad_cell[j] = f->pad[a];
    }
    const double rx = pk->ref[0], ry = pk->ref[1], rz = pk->ref[2], pad_k = f->pad[K];
    const double lo[3] = {f->lo[0], f->lo[1], f->lo[2]}, hi[3] = {f->hi[0], f->hi[1], f->hi[2]};
    /* Every lane: dead ones hold zeros (and infinities and NaNs derived
     * from them), masked wherever read. */
    for (int i = 0; i < P; i++) {
        const double ox = rf.o[0][i], oy = rf.o[1][i], oz = rf.o[2][i];
        const double dx = rf.d[0][i], dy = rf.d[1][i], dz = rf.d[2][i];
        const double qx = ox - rx, qy = oy - ry, qz = oz - rz;
        pk->dx[i] = dx, pk->dy[i] = dy, pk->dz[i] = dz;
        pk->mx[i] = qy * dz - qz * dy;
        pk->my[i] = qz * dx - qx * dz;
        pk->mz[i] = qx * dy - qy * dx;
        pk->emag[i] = GRID_PACKET_REL * (fabs(dx) + fabs(dy) + fabs(dz));
        pk->omag[i] = fabs(qx) + fabs(qy) + fabs(qz);
        pk->d2[i] = dx * dx + dy * dy + dz * dz;
        const double ok = rf.o[K][i], dk = rf.d[K][i], te = rf.te[i];
        const double ik = 1.0 / dk, dzk = z0 - ok;
        pk->ok[i] = ok;
        const double s1 = rf.d[a1][i] * ik, s2 = rf.d[a2][i] * ik;
        const double o1 = rf.o[a1][i], o2 = rf.o[a2][i];
        pk->s[0][i] = s1, pk->s[1][i] = s2;
        pk->u0[0][i] = o1 + s1 * dzk, pk->u0[1][i] = o2 + s2 * dzk;
        pk->umag[0][i] = fabs(o1) + fabs(s1 * dzk);
        pk->umag[1][i] = fabs(o2) + fabs(s2 * dzk);
        /* Where the ray starts on K, moved back by a margin over the float
         * slab's rounding; relative to z0. */
        const double zm = pad_k + GRID_PACKET_REL_F * (fabs(ok) + fabs(te * dk));
        pk->zr[i] = ok + te * dk - dir * zm - z0;
        /* Where it leaves the box or ends: a hit lies no farther. A zero
         * direction component gives inf or NaN, which the minimum skips. */
        double t_out = rf.tf[i];
        for (int a = 0; a < 3; a++) {
            const double far = signbit(rf.d[a][i]) ? lo[a] : hi[a];
            const double t = (far - rf.o[a][i]) * (double)rf.inv[a][i];
            t_out = t < t_out ? t : t_out;
        }
        const double t_stop = t_out + GRID_PACKET_REL_F * fabs(t_out);
        pk->w_end[i] = dir * (ok + t_stop * dk) + GRID_PACKET_REL * (fabs(ok) + fabs(t_stop * dk));
    }
    pk->dk = K == 0 ? pk->dx : (K == 1 ? pk->dy : pk->dz);
    pk->w_next = INFINITY;
    double z_first = dir > 0 ? INFINITY : -INFINITY;
    for (uint64_t m = pk->live; m; m &= m - 1) {
        const int i = __builtin_ctzll(m);
        z_first = dir > 0 ? dmin(z_first, pk->zr[i]) : dmax(z_first, pk->zr[i]);
        pk->w_next = dmin(pk->w_next, pk->w_end[i]);
    }
    pk->k_start = slice_of(f, K, z0 + z_first, dir);
    pk->active = pk->live;
    grid_packet_bound(pk);
    /* An incoherent packet (diffuse bounces that happen to share a sign)
     * would sweep wide ranges of cells: the single-ray kernel does better.
     * The widest range it could take within the grid, in cells: */
    for (int j = 0; j < 2; j++) {
        const int a = pk->axis[1 + j];
        const double w = pk->u0_hi[j] - pk->u0_lo[j] + (pk->s_hi[j] - pk->s_lo[j]) * pk->zext;
        if (w * f->inv_cell[a] > max_cells) return GRID_PACKET_SINGLE;
    }
    return GRID_PACKET_WALK;
}

#if GRID_PACKET_AVX
static inline double hmin(__m256d v)
{
    __m128d h = _mm_min_pd(_mm256_castpd256_pd128(v), _mm256_extractf128_pd(v, 1));
    return _mm_cvtsd_f64(_mm_min_sd(h, _mm_unpackhi_pd(h, h)));
}

static inline double hmax(__m256d v)
{
    __m128d h = _mm_max_pd(_mm256_castpd256_pd128(v), _mm256_extractf128_pd(v, 1));
    return _mm_cvtsd_f64(_mm_max_sd(h, _mm_unpackhi_pd(h, h)));
}
#endif

void grid_packet_bound(grid_packet *pk)
{
    enum { N = 10, NM = 4 };
    const uint64_t act = pk->active;
    pk->bounded = act;
    const double *const arr[N] = {pk->u0[0], pk->u0[1], pk->s[0], pk->s[1], pk->dx,
                                  pk->dy,    pk->dz,    pk->mx,   pk->my,   pk->mz};
    const double *const mags[NM] = {pk->umag[0], pk->umag[1], pk->emag, pk->omag};
    double lo[N], hi[N], mag[NM];
#if GRID_PACKET_AVX
    const __m256d inf = _mm256_set1_pd(INFINITY), ninf = _mm256_set1_pd(-INFINITY);
    __m256d l[N], h[N], g[NM];
    for (int q = 0; q < N; q++) l[q] = inf, h[q] = ninf;
    for (int q = 0; q < NM; q++) g[q] = _mm256_setzero_pd();
    for (uint64_t a = act; a;) {
        const int o = 4 * (__builtin_ctzll(a) >> 2);
        a &= ~((uint64_t)0xF << o);
        const __m256d m = grid_packet_lanes(act >> o);
        for (int q = 0; q < N; q++) {
            const __m256d x = _mm256_load_pd(arr[q] + o);
            l[q] = _mm256_min_pd(l[q], _mm256_blendv_pd(inf, x, m));
            h[q] = _mm256_max_pd(h[q], _mm256_blendv_pd(ninf, x, m));
        }
        for (int q = 0; q < NM; q++) g[q] = _mm256_max_pd(g[q], _mm256_and_pd(_mm256_load_pd(mags[q] + o), m));
    }
    for (int q = 0; q < N; q++) lo[q] = hmin(l[q]), hi[q] = hmax(h[q]);
    for (int q = 0; q < NM; q++) mag[q] = hmax(g[q]);
#else
    for (int q = 0; q < N; q++) lo[q] = INFINITY, hi[q] = -INFINITY;
    for (int q = 0; q < NM; q++) mag[q] = 0.0;
    for (uint64_t a = act; a; a &= a - 1) {
        const int i = __builtin_ctzll(a);
        for (int q = 0; q < N; q++) lo[q] = dmin(lo[q], arr[q][i]), hi[q] = dmax(hi[q], arr[q][i]);
        for (int q = 0; q < NM; q++) mag[q] = dmax(mag[q], mags[q][i]);
    }
#endif
    for (int j = 0; j < 2; j++) {
        pk->u0_lo[j] = lo[j], pk->u0_hi[j] = hi[j];
        pk->s_lo[j] = lo[2 + j], pk->s_hi[j] = hi[2 + j];
        pk->umag_max[j] = mag[j];
    }
    for (int a = 0; a < 3; a++) {
        pk->d_lo[a] = lo[4 + a], pk->d_hi[a] = hi[4 + a];
        pk->m_lo[a] = lo[7 + a], pk->m_hi[a] = hi[7 + a];
    }
    pk->emag_max = mag[2];
    pk->omag_max = mag[3];
    pk->common = pk->omag_max == 0.0;
    /* Rounding of u0 (scale umag), of s (2 u) and of the products and sums
     * of a slice range or an envelope: far below GRID_PACKET_REL of these
     * bounds on their magnitudes. The slice ranges add 1/1024 of a cell. */
    for (int j = 0; j < 2; j++) {
        const double sz = dmax(fabs(pk->s_lo[j]), fabs(pk->s_hi[j])) * pk->zext;
        const double u0 = dmax(fabs(pk->u0_lo[j]), fabs(pk->u0_hi[j]));
        pk->pad_env[j] = GRID_PACKET_REL * (pk->umag_max[j] + sz + pk->umax[j]);
        pk->pad_span[j] = pk->pad_cell[j] + GRID_PACKET_REL * (pk->umag_max[j] + 3.0 * sz + 2.0 * u0);
    }
}

/* Cells [*lo, *hi] of axis a whose closed boxes cover [ulo, uhi]; 0 when
 * the interval misses the grid. */
static inline int cell_span(const grid_frame *f, int a, double ulo, double uhi, int *lo, int *hi)
{
    const int n = f->res[a];
    const float *pl = f->planes[a];
    if (!(uhi >= pl[0] && ulo <= pl[n])) return 0;
    double g0 = (ulo - f->lo[a]) * f->inv_cell[a], g1 = (uhi - f->lo[a]) * f->inv_cell[a];
    int i0 = g0 >= n ? n - 1 : (g0 > 0.0 ? (int)g0 : 0);
    int i1 = g1 >= n ? n - 1 : (g1 > 0.0 ? (int)g1 : 0);
    while (i0 > 0 && pl[i0] > ulo) i0--;
    while (i0 < n - 1 && pl[i0 + 1] < ulo) i0++;
    while (i1 < n - 1 && pl[i1 + 1] < uhi) i1++;
    while (i1 > 0 && pl[i1] > uhi) i1--;
    *lo = i0;
    *hi = i1;
    return i0 <= i1;
}

/* Hull on a1, a2 of the active rays' segments in the slice between z_a and
 * z_b (relative to z0, z_a on the entry side): each ray from where it
 * enters the slice or starts; rays that start beyond the slice left out. */
static void ray_hull(const grid_packet *pk, double z_a, double z_b, double lo[2], double hi[2])
{
    const int dir = pk->kstep;
    lo[0] = lo[1] = INFINITY;
    hi[0] = hi[1] = -INFINITY;
#if GRID_PACKET_AVX
    const __m256d inf = _mm256_set1_pd(INFINITY), ninf = _mm256_set1_pd(-INFINITY);
    const __m256d za = _mm256_set1_pd(z_a), zb = _mm256_set1_pd(z_b);
    __m256d l[2] = {inf, inf}, h[2] = {ninf, ninf};
    for (uint64_t a = pk->active; a;) {
        const int o = 4 * (__builtin_ctzll(a) >> 2);
        a &= ~((uint64_t)0xF << o);
        __m256d zr = _mm256_load_pd(pk->zr + o), z, in;
        if (dir > 0) {
            z = _mm256_max_pd(za, zr);
            in = _mm256_cmp_pd(zr, zb, _CMP_LE_OQ);
        } else {
            z = _mm256_min_pd(za, zr);
            in = _mm256_cmp_pd(zr, zb, _CMP_GE_OQ);
        }
        in = _mm256_and_pd(in, grid_packet_lanes(pk->active >> o));
        for (int j = 0; j < 2; j++) {
            __m256d u0 = _mm256_load_pd(pk->u0[j] + o), s = _mm256_load_pd(pk->s[j] + o);
            __m256d ua = _mm256_fmadd_pd(s, z, u0), ub = _mm256_fmadd_pd(s, zb, u0);
            l[j] = _mm256_min_pd(l[j], _mm256_blendv_pd(inf, _mm256_min_pd(ua, ub), in));
            h[j] = _mm256_max_pd(h[j], _mm256_blendv_pd(ninf, _mm256_max_pd(ua, ub), in));
        }
    }
    for (int j = 0; j < 2; j++) {
        double bl[4], bh[4];
        _mm256_storeu_pd(bl, l[j]);
        _mm256_storeu_pd(bh, h[j]);
        lo[j] = dmin(dmin(bl[0], bl[1]), dmin(bl[2], bl[3]));
        hi[j] = dmax(dmax(bh[0], bh[1]), dmax(bh[2], bh[3]));
    }
#else
    for (uint64_t m = pk->active; m; m &= m - 1) {
        const int i = __builtin_ctzll(m);
        const double zr = pk->zr[i];
        if (dir > 0 ? !(zr <= z_b) : !(zr >= z_b)) continue;
        const double z = dir > 0 ? dmax(z_a, zr) : dmin(z_a, zr);
        for (int j = 0; j < 2; j++) {
            double ua = pk->u0[j][i] + pk->s[j][i] * z, ub = pk->u0[j][i] + pk->s[j][i] * z_b;
            lo[j] = dmin(lo[j], dmin(ua, ub));
            hi[j] = dmax(hi[j], dmax(ua, ub));
        }
    }
#endif
}

/* Interval arithmetic over the packet when every ray starts at ref (the
 * hull of the lines is then exactly u0 + s * [z_k - z0, z_k+1 - z0]), else
 * the hull of the rays' own segments. */
int grid_packet_span(const grid_frame *f, const grid_packet *pk, int k, int k_end, int lo[2],
                     int hi[2], double hull[2][2])
{
    const int K = pk->axis[0];
    const double z_a = (double)f->planes[K][pk->kstep > 0 ? k : k + 1] - pk->z0;
    const double z_b = (double)f->planes[K][pk->kstep > 0 ? k_end + 1 : k_end] - pk->z0;
    double ulo[2], uhi[2];
    if (pk->common) {
        for (int j = 0; j < 2; j++) {
            const double p0 = pk->s_lo[j] * z_a, p1 = pk->s_lo[j] * z_b;
            const double p2 = pk->s_hi[j] * z_a, p3 = pk->s_hi[j] * z_b;
            ulo[j] = pk->u0_lo[j] + dmin(dmin(p0, p1), dmin(p2, p3));
            uhi[j] = pk->u0_hi[j] + dmax(dmax(p0, p1), dmax(p2, p3));
        }
    } else {
        ray_hull(pk, z_a, z_b, ulo, uhi);
    }
    for (int j = 0; j < 2; j++) {
        hull[j][0] = ulo[j] - pk->pad_span[j];
        hull[j][1] = uhi[j] + pk->pad_span[j];
        if (!cell_span(f, pk->axis[1 + j], hull[j][0], hull[j][1], &lo[j], &hi[j])) return 0;
    }
    return 1;
}
