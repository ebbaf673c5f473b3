/*
 * grid_packet.c - coherent grid traversal of the `grid` kind
 * (traverse=packet), after Wald, Ize, Kensler, Knoll and Parker, "Ray
 * Tracing Animated Scenes using Coherent Grid Traversal", SIGGRAPH 2006.
 *
 * A packet is up to 64 consecutive rays of the batch (the primary ray sets
 * emit 8x8 screen tiles in that order). When every live ray's direction has
 * the same sign on the packet's dominant axis K (the largest component of
 * the mean direction) the packet walks the grid slice by slice along K:
 *   1. the slice's cell range on the other two axes (a1, a2) is bounded by
 *      interval arithmetic in double: every ray is written as
 *      u(z) = u0 + s (z - z0), u0 its coordinate on the packet's start
 *      plane z0, s = d_u / d_K; over the packet u0 and s lie in intervals,
 *      so over the slice [z_k, z_k+1] u lies in u0 + s * [z_k - z0,
 *      z_k+1 - z0], widened by its rounding bound and 1/1024 of a cell;
 *   2. every primitive of those cells is tested once per packet (a
 *      per-packet mailbox) against the rays still active: a whole-packet
 *      interval cull, then a 4-ray AVX2 filter in double, then the exact
 *      test accel_prim_hit (core/prim.h) on the rays the filter keeps;
 *   3. after the slice a ray stops once its nearest hit lies at or before
 *      the distance where it leaves the slice, or it has left the grid box
 *      or passed t_far. The packet ends when no ray is active or the slices
 *      run out.
 * Packets that do not qualify (mixed signs on K, a zero K component) are
 * traced by the single-ray kernel (grid_trace.c).
 *
 * Why the result is the single-ray grid's (and the oracle's). Let a ray's
 * exact test accept primitive q at t (the nearest such t). The point p of
 * the real ray at t lies on q and in the grid box, in some slice k and some
 * cell c of it; q belongs to c (membership is conservative, grid_core.h).
 * The ray is active during slice k: it stops earlier only with a hit at or
 * before its exit from an earlier slice (a hit no farther than p), or past
 * its box exit or t_far (both beyond t). p's coordinates on a1, a2 lie in
 * the slice's range (step 1 bounds every point of every ray in the slice,
 * rounding included), so c is visited while the ray is active, and q is
 * tested against the ray then or was tested earlier (the mailbox skips a
 * primitive only once it has been tested against every ray active at that
 * time, and rays never become active again). Filters only ever drop a
 * (ray, primitive) pair the exact test would reject (below). Every test is
 * the exact test keeping the nearest, so the ray ends with the nearest hit;
 * ties between primitives at equal t may resolve to another primitive, as
 * in any change of test order. Any hit: the same argument for the first hit.
 *
 * The filters (triangles). With R the packet's first live origin, O' = O-R,
 * M = O' x D, A' = A-R, etc., the triple product D.((A-O)x(B-O)) of edge AB
 * is S_AB = D.(A'xB') + M.(B-A) (Pluecker form; for primary rays M = 0).
 * The exact test's edge functions U, V, W equal these three triple products
 * divided by the ray's K component (a factor common to the three), and it
 * accepts only when they have no strictly mixed signs: in its float path
 * because its error filter (ACCEL_EDGE_FILTER) proves the signs, in its
 * double path with U, V, W within 20 u |D|_1 |A-O|_1 |B-O|_1 of the real
 * values (u = 2^-53; |sx|, |sy| <= 1). Our S computed in double is within
 * about 30 u |D|_1 (Rt + |O'|_1)^2 of the real value (Rt: the largest
 * 1-norm of A', B', C'). Both are below E = 2^-40 |D|_1 (Rt + |O'|_1)^2
 * (2^-40 = 8192 u), so a lane with some S < -E and some S > E is a pair
 * the exact test rejects: the filter is conservative. The whole-packet cull
 * bounds S over the packet's boxes of D and M (interval products, whose
 * rounding is below the same margin) and drops the primitive when some
 * edge's bound is below -E_max and another's above E_max. Spheres: the
 * exact test accepts only when the real squared distance of the centre to
 * the line is at most r^2 + 64 u (r^2 + |O-C|^2); the filter drops a lane
 * when |(C-O) x D|^2 > |D|^2 (r^2 + 2^-38 (r + |C'|_1 + |O'|_1)^2). With
 * tri=naive (no error analysis to rely on) every active ray gets the test.
 *
 * Counters (counted runs): steps / empty_steps = cells the packet visits,
 * counted once for every ray active at the visit (per ray, as the bvh's
 * packet kernel counts node visits; ray_steps likewise); prim_tests = exact
 * tests; mailbox_skips = references skipped, per active ray; box_tests = 1
 * per ray (the grid box); packet_box_tests = 4-ray filter evaluations.
 * The step bound is res[K] slices per packet (ACCEL_STEP_BOUND_BROKEN).
 */
#include <string.h>
#ifdef GP_DEBUG
#include <stdio.h>
#include <stdlib.h>
#endif

#include "core/variant.h"
#include "grid_impl.h"

#if defined(__AVX2__) && defined(__FMA__) && !defined(GRID_NO_SIMD)
#define GP_AVX 1
#include <immintrin.h>
#else
#define GP_AVX 0
#endif

#define P 64
#define GP_MAIL 256         /* per-packet mailbox entries (power of two) */
#define GP_REL 0x1p-40      /* filter margin relative to the magnitudes (8192 u) */
#define GP_SPHERE_REL 0x1p-38

_Static_assert(P == 64, "the active-ray mask is one uint64_t");

typedef struct {
    /* Filter data, one array per attribute, relative to ref (dead rays:
     * zeros, never tested: lanes are masked by `active`). */
    _Alignas(32) double dx[P];
    _Alignas(32) double dy[P];
    _Alignas(32) double dz[P];
    _Alignas(32) double mx[P]; /* M = (O - ref) x D */
    _Alignas(32) double my[P];
    _Alignas(32) double mz[P];
    _Alignas(32) double emag[P]; /* GP_REL * |D|_1 */
    _Alignas(32) double omag[P]; /* |O - ref|_1 */
    _Alignas(32) double d2[P];   /* |D|_2^2 */
    /* The slice walk. */
    _Alignas(32) double ok[P];     /* origin on K */
    _Alignas(32) double inv_k[P];  /* 1 / d_K */
    _Alignas(32) double t_stop[P]; /* box exit or t_far, widened by its rounding */
    _Alignas(32) double u0[2][P]; /* coordinate on a1, a2 at z0 */
    _Alignas(32) double s[2][P];  /* d_a / d_K */
    _Alignas(32) double zr[P];    /* where the ray starts on K, minus z0, widened */
    double umag[2][P];
    float t[P], u[P], v[P];
    uint32_t prim[P];
    accel_ray_prep prep[P];
    uint64_t live, active, bounded; /* bounds below hold over `bounded` >= active */
    uint32_t n, boxes;              /* boxes: grid-box tests (counters) */
    double ref[3];
    int axis[3]; /* K, a1, a2 */
    int kstep, k_start;
    double z0;
    /* Bounds over the rays of `bounded`. */
    double u0_lo[2], u0_hi[2], s_lo[2], s_hi[2], umag_max[2];
    double d_lo[3], d_hi[3], m_lo[3], m_hi[3], emag_max, omag_max;
    int common; /* all of them start at ref: M = 0 */
} gpacket;

enum { GP_EMPTY, GP_WALK, GP_SINGLE };

static inline double dmin(double a, double b) { return a < b ? a : b; }
static inline double dmax(double a, double b) { return a > b ? a : b; }

/* Bounds of the packet's rays over `active` (step 1 and the cull). */
static void packet_bound(gpacket *pk)
{
    uint64_t m = pk->active;
    pk->bounded = m;
    for (int j = 0; j < 2; j++) {
        pk->u0_lo[j] = pk->s_lo[j] = INFINITY;
        pk->u0_hi[j] = pk->s_hi[j] = -INFINITY;
        pk->umag_max[j] = 0.0;
    }
    for (int a = 0; a < 3; a++) {
        pk->d_lo[a] = pk->m_lo[a] = INFINITY;
        pk->d_hi[a] = pk->m_hi[a] = -INFINITY;
    }
    pk->emag_max = pk->omag_max = 0.0;
    for (; m; m &= m - 1) {
        int i = __builtin_ctzll(m);
        for (int j = 0; j < 2; j++) {
            pk->u0_lo[j] = dmin(pk->u0_lo[j], pk->u0[j][i]);
            pk->u0_hi[j] = dmax(pk->u0_hi[j], pk->u0[j][i]);
            pk->s_lo[j] = dmin(pk->s_lo[j], pk->s[j][i]);
            pk->s_hi[j] = dmax(pk->s_hi[j], pk->s[j][i]);
            pk->umag_max[j] = dmax(pk->umag_max[j], pk->umag[j][i]);
        }
        const double d[3] = {pk->dx[i], pk->dy[i], pk->dz[i]};
        const double mm[3] = {pk->mx[i], pk->my[i], pk->mz[i]};
        for (int a = 0; a < 3; a++) {
            pk->d_lo[a] = dmin(pk->d_lo[a], d[a]);
            pk->d_hi[a] = dmax(pk->d_hi[a], d[a]);
            pk->m_lo[a] = dmin(pk->m_lo[a], mm[a]);
            pk->m_hi[a] = dmax(pk->m_hi[a], mm[a]);
        }
        pk->emag_max = dmax(pk->emag_max, pk->emag[i]);
        pk->omag_max = dmax(pk->omag_max, pk->omag[i]);
    }
    pk->common = pk->omag_max == 0.0;
}

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

/* Prepares the packet; GP_EMPTY when no ray can hit anything, GP_SINGLE
 * when the packet does not qualify for the slice walk. */
static int packet_setup(const grid_accel *g, gpacket *pk, const accel_ray *rays, uint32_t n)
{
    const grid_frame *f = &g->frame;
    pk->n = n;
    pk->live = 0;
    pk->boxes = 0;
    double mean[3] = {0.0, 0.0, 0.0};
    for (uint32_t i = 0; i < P; i++) {
        pk->prim[i] = ACCEL_MISS;
        pk->u[i] = pk->v[i] = 0.0f;
        pk->t[i] = -INFINITY;
        if (i >= n || g->cells.ref_count == 0) continue;
        accel_ray_prep *p = &pk->prep[i];
        float t_entry;
        if (!accel_prep_ray(&rays[i], p)) continue;
        pk->boxes++;
        if (!box3_slab(f->lo, f->hi, p->org, p->inv_dir, p->neg, p->t_near, p->t_far, &t_entry))
            continue;
        pk->live |= (uint64_t)1 << i;
        pk->t[i] = p->t_far;
        mean[0] += p->dir.x, mean[1] += p->dir.y, mean[2] += p->dir.z;
    }
    if (!pk->live) return GP_EMPTY;
    int K = fabs(mean[0]) >= fabs(mean[1]) && fabs(mean[0]) >= fabs(mean[2])
                ? 0
                : (fabs(mean[1]) >= fabs(mean[2]) ? 1 : 2);
    const int dir = mean[K] < 0.0 ? -1 : 1;
    const int a1 = K == 0 ? 1 : 0, a2 = K == 2 ? 1 : 2;
    pk->axis[0] = K, pk->axis[1] = a1, pk->axis[2] = a2;
    pk->kstep = dir;
    const accel_ray_prep *first = &pk->prep[__builtin_ctzll(pk->live)];
    pk->ref[0] = first->org.x, pk->ref[1] = first->org.y, pk->ref[2] = first->org.z;
    /* Per ray: filter data, start slice, stop distance. */
    int k_start = dir > 0 ? f->res[K] - 1 : 0;
    for (uint64_t m = pk->live; m; m &= m - 1) {
        int i = __builtin_ctzll(m);
        const accel_ray_prep *p = &pk->prep[i];
        const double o[3] = {p->org.x, p->org.y, p->org.z};
        const double d[3] = {p->dir.x, p->dir.y, p->dir.z};
        if (!(d[K] * dir > 0.0)) return GP_SINGLE; /* mixed signs or zero on K */
        const double q[3] = {o[0] - pk->ref[0], o[1] - pk->ref[1], o[2] - pk->ref[2]};
        pk->dx[i] = d[0], pk->dy[i] = d[1], pk->dz[i] = d[2];
        pk->mx[i] = q[1] * d[2] - q[2] * d[1];
        pk->my[i] = q[2] * d[0] - q[0] * d[2];
        pk->mz[i] = q[0] * d[1] - q[1] * d[0];
        pk->emag[i] = GP_REL * (fabs(d[0]) + fabs(d[1]) + fabs(d[2]));
        pk->omag[i] = fabs(q[0]) + fabs(q[1]) + fabs(q[2]);
        pk->d2[i] = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        /* The ray's extent in the box, in double (as grid_dda_init). */
        double t_in = p->t_near, t_out = p->t_far;
        for (int a = 0; a < 3; a++) {
            if (d[a] == 0.0) continue;
            double inv = 1.0 / d[a];
            double t0 = ((double)f->lo[a] - o[a]) * inv, t1 = ((double)f->hi[a] - o[a]) * inv;
            if (d[a] < 0.0) { double x = t0; t0 = t1; t1 = x; }
            t_in = dmax(t_in, t0);
            t_out = dmin(t_out, t1);
        }
        pk->ok[i] = o[K];
        pk->inv_k[i] = 1.0 / d[K];
        /* A hit lies at or before t_out; rounding of t_out and of a
         * slice's exit distance (3 u each) is below this margin. */
        pk->t_stop[i] = t_out + GP_REL * fabs(t_out);
        double zs = o[K] + t_in * d[K];
        double zm = f->pad[K] + GP_REL * (fabs(o[K]) + fabs(t_in * d[K]));
        pk->zr[i] = zs - dir * zm; /* made relative to z0 below */
        int ks = slice_of(f, K, pk->zr[i], dir);
        k_start = dir > 0 ? (ks < k_start ? ks : k_start) : (ks > k_start ? ks : k_start);
    }
    pk->k_start = k_start;
    pk->z0 = f->planes[K][dir > 0 ? k_start : k_start + 1];
    for (uint64_t m = pk->live; m; m &= m - 1) {
        int i = __builtin_ctzll(m);
        const accel_ray_prep *p = &pk->prep[i];
        const double o[3] = {p->org.x, p->org.y, p->org.z};
        const double d[3] = {p->dir.x, p->dir.y, p->dir.z};
        double dz = pk->z0 - o[K];
        pk->zr[i] -= pk->z0;
        for (int j = 0; j < 2; j++) {
            int a = pk->axis[1 + j];
            double s = d[a] / d[K];
            pk->s[j][i] = s;
            pk->u0[j][i] = o[a] + s * dz;
            pk->umag[j][i] = fabs(o[a]) + fabs(s * dz);
        }
    }
    pk->active = pk->live;
    packet_bound(pk);
    return GP_WALK;
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

#if GP_AVX
/* Lane masks of 4 activity bits. */
static inline __m256d lane_mask(uint64_t bits)
{
    const __m256i sel = _mm256_setr_epi64x(1, 2, 4, 8);
    __m256i b = _mm256_and_si256(_mm256_set1_epi64x((long long)bits), sel);
    return _mm256_castsi256_pd(_mm256_cmpeq_epi64(b, sel));
}
#endif

/* Hull of the active rays' segments in the slice between z_a and z_b (both
 * relative to z0, z_a the entry side) on a1 and a2: each ray from where it
 * enters the slice or starts, rays that start beyond the slice left out. */
static void ray_hull(const gpacket *pk, double z_a, double z_b, double lo[2], double hi[2])
{
    const int dir = pk->kstep;
#if GP_AVX
    const __m256d inf = _mm256_set1_pd(INFINITY), ninf = _mm256_set1_pd(-INFINITY);
    const __m256d za = _mm256_set1_pd(z_a), zb = _mm256_set1_pd(z_b);
    __m256d l0 = inf, l1 = inf, h0 = ninf, h1 = ninf;
    for (uint64_t a = pk->active; a;) {
        int o = 4 * (__builtin_ctzll(a) >> 2);
        a &= ~((uint64_t)0xF << o);
        __m256d zr = _mm256_load_pd(pk->zr + o), z, in;
        if (dir > 0) {
            z = _mm256_max_pd(za, zr);
            in = _mm256_cmp_pd(zr, zb, _CMP_LE_OQ);
        } else {
            z = _mm256_min_pd(za, zr);
            in = _mm256_cmp_pd(zr, zb, _CMP_GE_OQ);
        }
        in = _mm256_and_pd(in, lane_mask(pk->active >> o));
        __m256d u0 = _mm256_load_pd(pk->u0[0] + o), s = _mm256_load_pd(pk->s[0] + o);
        __m256d ua = _mm256_fmadd_pd(s, z, u0), ub = _mm256_fmadd_pd(s, zb, u0);
        l0 = _mm256_min_pd(l0, _mm256_blendv_pd(inf, _mm256_min_pd(ua, ub), in));
        h0 = _mm256_max_pd(h0, _mm256_blendv_pd(ninf, _mm256_max_pd(ua, ub), in));
        u0 = _mm256_load_pd(pk->u0[1] + o), s = _mm256_load_pd(pk->s[1] + o);
        ua = _mm256_fmadd_pd(s, z, u0), ub = _mm256_fmadd_pd(s, zb, u0);
        l1 = _mm256_min_pd(l1, _mm256_blendv_pd(inf, _mm256_min_pd(ua, ub), in));
        h1 = _mm256_max_pd(h1, _mm256_blendv_pd(ninf, _mm256_max_pd(ua, ub), in));
    }
    double b[4][4];
    _mm256_storeu_pd(b[0], l0), _mm256_storeu_pd(b[1], l1);
    _mm256_storeu_pd(b[2], h0), _mm256_storeu_pd(b[3], h1);
    for (int j = 0; j < 2; j++) {
        lo[j] = dmin(dmin(b[j][0], b[j][1]), dmin(b[j][2], b[j][3]));
        hi[j] = dmax(dmax(b[2 + j][0], b[2 + j][1]), dmax(b[2 + j][2], b[2 + j][3]));
    }
#else
    lo[0] = lo[1] = INFINITY;
    hi[0] = hi[1] = -INFINITY;
    for (uint64_t m = pk->active; m; m &= m - 1) {
        int i = __builtin_ctzll(m);
        double zr = pk->zr[i];
        if (dir > 0 ? !(zr <= z_b) : !(zr >= z_b)) continue;
        double z = dir > 0 ? dmax(z_a, zr) : dmin(z_a, zr);
        for (int j = 0; j < 2; j++) {
            double ua = pk->u0[j][i] + pk->s[j][i] * z, ub = pk->u0[j][i] + pk->s[j][i] * z_b;
            lo[j] = dmin(lo[j], dmin(ua, ub));
            hi[j] = dmax(hi[j], dmax(ua, ub));
        }
    }
#endif
}

/* Ranges of cells on a1 and a2 that slice k can touch: interval arithmetic
 * over the packet when every ray starts at ref (the hull of the lines is
 * then exactly u0 + s * [z_k - z0, z_k+1 - z0]), else the hull of the
 * rays' own segments. */
static inline int slice_span(const grid_frame *f, const gpacket *pk, int k, int lo[2], int hi[2])
{
    const int K = pk->axis[0];
    const int in_k = pk->kstep > 0 ? k : k + 1;
    double z_a = (double)f->planes[K][in_k] - pk->z0;
    double z_b = (double)f->planes[K][2 * k + 1 - in_k] - pk->z0;
    double ulo[2], uhi[2];
    if (pk->common) {
        for (int j = 0; j < 2; j++) {
            double p0 = pk->s_lo[j] * z_a, p1 = pk->s_lo[j] * z_b;
            double p2 = pk->s_hi[j] * z_a, p3 = pk->s_hi[j] * z_b;
            ulo[j] = pk->u0_lo[j] + dmin(dmin(p0, p1), dmin(p2, p3));
            uhi[j] = pk->u0_hi[j] + dmax(dmax(p0, p1), dmax(p2, p3));
        }
    } else {
        ray_hull(pk, z_a, z_b, ulo, uhi);
    }
    const double zm = dmax(fabs(z_a), fabs(z_b));
    for (int j = 0; j < 2; j++) {
        const int a = pk->axis[1 + j];
        /* Rounding of u0 (bounded by umag), of the products and sums: far
         * below GP_REL of the magnitudes; plus 1/1024 of a cell. */
        double sm = dmax(fabs(pk->s_lo[j]), fabs(pk->s_hi[j]));
        double pad = f->pad[a] + GP_REL * (pk->umag_max[j] + sm * zm + fabs(ulo[j]) + fabs(uhi[j]));
        if (!cell_span(f, a, ulo[j] - pad, uhi[j] + pad, &lo[j], &hi[j])) return 0;
    }
    return 1;
}

/* ---- filters: which active rays may hit a primitive ------------------------ */

typedef struct {
    double m[3][3]; /* per edge AB, BC, CA: A' x B' etc. */
    double e[3][3]; /* per edge: B - A etc. */
    double rt;      /* largest 1-norm of A', B', C' */
} tri_data;

static inline void tri_setup(const gpacket *pk, const float *tri, tri_data *t)
{
    double v[3][3];
    t->rt = 0.0;
    for (int k = 0; k < 3; k++) {
        double r = 0.0;
        for (int a = 0; a < 3; a++) {
            v[k][a] = (double)tri[3 * k + a] - pk->ref[a];
            r += fabs(v[k][a]);
        }
        t->rt = dmax(t->rt, r);
    }
    for (int k = 0; k < 3; k++) {
        const double *a = v[k], *b = v[k == 2 ? 0 : k + 1];
        const float *ta = tri + 3 * k, *tb = tri + 3 * (k == 2 ? 0 : k + 1);
        t->m[k][0] = a[1] * b[2] - a[2] * b[1];
        t->m[k][1] = a[2] * b[0] - a[0] * b[2];
        t->m[k][2] = a[0] * b[1] - a[1] * b[0];
        for (int c = 0; c < 3; c++) t->e[k][c] = (double)tb[c] - (double)ta[c];
    }
}

/* 1 when no ray of `bounded` can hit the triangle: interval bounds of the
 * three edge products over the packet's boxes of D and M. */
static inline int tri_culled(const gpacket *pk, const tri_data *t)
{
    double x = t->rt + pk->omag_max;
    double e = 2.0 * pk->emag_max * x * x;
    int below = 0, above = 0;
    for (int k = 0; k < 3; k++) {
        double lo = 0.0, hi = 0.0;
        for (int c = 0; c < 3; c++) {
            double a = t->m[k][c] * pk->d_lo[c], b = t->m[k][c] * pk->d_hi[c];
            lo += dmin(a, b), hi += dmax(a, b);
            if (!pk->common) {
                a = t->e[k][c] * pk->m_lo[c], b = t->e[k][c] * pk->m_hi[c];
                lo += dmin(a, b), hi += dmax(a, b);
            }
        }
        below |= hi < -e;
        above |= lo > e;
    }
    return below && above;
}

/* Active rays of the packet the triangle filter keeps. */
static inline uint64_t tri_filter(const gpacket *pk, const tri_data *t, uint64_t *evals)
{
    uint64_t keep = 0;
#if GP_AVX
    __m256d m[3][3], e[3][3];
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 3; c++) {
            m[k][c] = _mm256_set1_pd(t->m[k][c]);
            e[k][c] = _mm256_set1_pd(t->e[k][c]);
        }
    const __m256d rt = _mm256_set1_pd(t->rt), sign = _mm256_set1_pd(-0.0);
#endif
    for (uint64_t a = pk->active; a;) {
        int g = __builtin_ctzll(a) >> 2, o = 4 * g;
        a &= ~((uint64_t)0xF << o);
        (*evals)++;
#if GP_AVX
        __m256d dx = _mm256_load_pd(pk->dx + o), dy = _mm256_load_pd(pk->dy + o),
                dz = _mm256_load_pd(pk->dz + o);
        __m256d s[3];
        for (int k = 0; k < 3; k++)
            s[k] = _mm256_fmadd_pd(dz, m[k][2], _mm256_fmadd_pd(dy, m[k][1], _mm256_mul_pd(dx, m[k][0])));
        if (!pk->common) {
            __m256d mx = _mm256_load_pd(pk->mx + o), my = _mm256_load_pd(pk->my + o),
                    mz = _mm256_load_pd(pk->mz + o);
            for (int k = 0; k < 3; k++)
                s[k] = _mm256_fmadd_pd(mz, e[k][2], _mm256_fmadd_pd(my, e[k][1], _mm256_fmadd_pd(mx, e[k][0], s[k])));
        }
        __m256d x = _mm256_add_pd(rt, _mm256_load_pd(pk->omag + o));
        __m256d lim = _mm256_mul_pd(_mm256_mul_pd(x, x), _mm256_load_pd(pk->emag + o));
        __m256d nlim = _mm256_xor_pd(lim, sign);
        __m256d neg = _mm256_or_pd(_mm256_or_pd(_mm256_cmp_pd(s[0], nlim, _CMP_LT_OQ),
                                                _mm256_cmp_pd(s[1], nlim, _CMP_LT_OQ)),
                                   _mm256_cmp_pd(s[2], nlim, _CMP_LT_OQ));
        __m256d pos = _mm256_or_pd(_mm256_or_pd(_mm256_cmp_pd(s[0], lim, _CMP_GT_OQ),
                                                _mm256_cmp_pd(s[1], lim, _CMP_GT_OQ)),
                                   _mm256_cmp_pd(s[2], lim, _CMP_GT_OQ));
        uint64_t rej = (uint64_t)_mm256_movemask_pd(_mm256_and_pd(neg, pos));
        keep |= (~rej & 0xFu) << o;
#else
        for (int l = o; l < o + 4; l++) {
            double x = t->rt + pk->omag[l], lim = pk->emag[l] * x * x;
            int neg = 0, pos = 0;
            for (int k = 0; k < 3; k++) {
                double s = pk->dx[l] * t->m[k][0] + pk->dy[l] * t->m[k][1] + pk->dz[l] * t->m[k][2] +
                           pk->mx[l] * t->e[k][0] + pk->my[l] * t->e[k][1] + pk->mz[l] * t->e[k][2];
                neg |= s < -lim;
                pos |= s > lim;
            }
            keep |= (uint64_t)!(neg && pos) << l;
        }
#endif
    }
    return keep & pk->active;
}

/* Active rays the sphere filter keeps: X = (C - O) x D = C' x D - M. */
static inline uint64_t sphere_filter(const gpacket *pk, const float *sph, uint64_t *evals)
{
    const double c[3] = {(double)sph[0] - pk->ref[0], (double)sph[1] - pk->ref[1],
                         (double)sph[2] - pk->ref[2]};
    const double r = sph[3], rc = r + fabs(c[0]) + fabs(c[1]) + fabs(c[2]);
    uint64_t keep = 0;
    for (uint64_t a = pk->active; a;) {
        int g = __builtin_ctzll(a) >> 2, o = 4 * g;
        a &= ~((uint64_t)0xF << o);
        (*evals)++;
#if GP_AVX
        __m256d dx = _mm256_load_pd(pk->dx + o), dy = _mm256_load_pd(pk->dy + o),
                dz = _mm256_load_pd(pk->dz + o);
        __m256d cx = _mm256_set1_pd(c[0]), cy = _mm256_set1_pd(c[1]), cz = _mm256_set1_pd(c[2]);
        __m256d x = _mm256_sub_pd(_mm256_fmsub_pd(cy, dz, _mm256_mul_pd(cz, dy)), _mm256_load_pd(pk->mx + o));
        __m256d y = _mm256_sub_pd(_mm256_fmsub_pd(cz, dx, _mm256_mul_pd(cx, dz)), _mm256_load_pd(pk->my + o));
        __m256d z = _mm256_sub_pd(_mm256_fmsub_pd(cx, dy, _mm256_mul_pd(cy, dx)), _mm256_load_pd(pk->mz + o));
        __m256d x2 = _mm256_fmadd_pd(z, z, _mm256_fmadd_pd(y, y, _mm256_mul_pd(x, x)));
        __m256d q = _mm256_add_pd(_mm256_set1_pd(rc), _mm256_load_pd(pk->omag + o));
        __m256d lim = _mm256_mul_pd(_mm256_load_pd(pk->d2 + o),
                                    _mm256_fmadd_pd(_mm256_mul_pd(q, q), _mm256_set1_pd(GP_SPHERE_REL),
                                                    _mm256_set1_pd(r * r)));
        uint64_t rej = (uint64_t)_mm256_movemask_pd(_mm256_cmp_pd(x2, lim, _CMP_GT_OQ));
        keep |= (~rej & 0xFu) << o;
#else
        for (int l = o; l < o + 4; l++) {
            double x = c[1] * pk->dz[l] - c[2] * pk->dy[l] - pk->mx[l];
            double y = c[2] * pk->dx[l] - c[0] * pk->dz[l] - pk->my[l];
            double z = c[0] * pk->dy[l] - c[1] * pk->dx[l] - pk->mz[l];
            double q = rc + pk->omag[l];
            keep |= (uint64_t)!(x * x + y * y + z * z > pk->d2[l] * (r * r + GP_SPHERE_REL * q * q)) << l;
        }
#endif
    }
    return keep & pk->active;
}

/* ---- the walk ---------------------------------------------------------------- */

/* Counted runs: packet totals so far, and each ray's share when it stops. */
typedef struct {
    uint64_t visits, empty, skips, evals;
    uint32_t r_visits[P], r_empty[P], r_skips[P], r_tests[P];
} gp_count;

static inline void retire(gpacket *pk, gp_count *cn, int i, const accel_counters *c)
{
    pk->active &= ~((uint64_t)1 << i);
    if (c) {
        cn->r_visits[i] = (uint32_t)cn->visits;
        cn->r_empty[i] = (uint32_t)cn->empty;
        cn->r_skips[i] = (uint32_t)cn->skips;
    }
}

/* Active rays that leave slice k across plane z_out: their nearest hit lies
 * at or before it (t <= t_exit), or they have left the box or passed t_far. */
static inline uint64_t leaving(const gpacket *pk, double z_out)
{
    uint64_t out = 0;
    for (uint64_t a = pk->active; a;) {
        int o = 4 * (__builtin_ctzll(a) >> 2);
        a &= ~((uint64_t)0xF << o);
#if GP_AVX
        __m256d tx = _mm256_mul_pd(_mm256_sub_pd(_mm256_set1_pd(z_out), _mm256_load_pd(pk->ok + o)),
                                   _mm256_load_pd(pk->inv_k + o));
        __m256d tb = _mm256_cvtps_pd(_mm_loadu_ps(pk->t + o));
        __m256d m = _mm256_or_pd(_mm256_cmp_pd(tb, tx, _CMP_LE_OQ),
                                 _mm256_cmp_pd(tx, _mm256_load_pd(pk->t_stop + o), _CMP_GT_OQ));
        out |= (uint64_t)_mm256_movemask_pd(m) << o;
#else
        for (int l = o; l < o + 4; l++) {
            double tx = (z_out - pk->ok[l]) * pk->inv_k[l];
            out |= (uint64_t)((double)pk->t[l] <= tx || tx > pk->t_stop[l]) << l;
        }
#endif
    }
    return out & pk->active;
}

static inline __attribute__((always_inline)) void
packet_walk(const grid_accel *g, gpacket *pk, gp_count *cn, accel_counters *c, int naive,
            int spheres, int mailbox, int any_hit)
{
    const grid_frame *f = &g->frame;
    const accel_scene *s = &g->store.prims;
    const uint32_t *offsets = g->cells.offsets, *refs = g->cells.refs;
    const int K = pk->axis[0], nk = f->res[K];
    const uint32_t st1 = f->stride[pk->axis[1]], st2 = f->stride[pk->axis[2]];
    uint32_t mail[GP_MAIL];
    if (mailbox) memset(mail, 0xFF, sizeof mail); /* ACCEL_MISS: no primitive */
    uint32_t slices = 0;
#ifdef GP_DEBUG
    uint64_t dbg_cells = 0;
#endif
    for (int k = pk->k_start; k >= 0 && k < nk; k += pk->kstep) {
        slices++;
        if (ACCEL_STEP_BOUND_BROKEN(c, slices, nk)) return;
        /* Tighter bounds once a quarter of the rays have stopped. */
        if (4 * __builtin_popcountll(pk->active) <= 3 * __builtin_popcountll(pk->bounded))
            packet_bound(pk);
        int lo[2], hi[2];
        if (slice_span(f, pk, k, lo, hi)) {
            const int i0 = lo[0], i1 = hi[0], j0 = lo[1], j1 = hi[1];
#ifdef GP_DEBUG
            dbg_cells += (uint64_t)(i1 - i0 + 1) * (uint64_t)(j1 - j0 + 1);
            if (getenv("GP_DEBUG") && slices < 4) fprintf(stderr, "  k=%d [%d,%d]x[%d,%d] active %d u0 %g..%g s %g..%g u0b %g..%g s %g..%g\n", k, i0, i1, j0, j1, __builtin_popcountll(pk->active), pk->u0_lo[0], pk->u0_hi[0], pk->s_lo[0], pk->s_hi[0], pk->u0_lo[1], pk->u0_hi[1], pk->s_lo[1], pk->s_hi[1]);
#endif
            for (int j = j0; j <= j1; j++) {
                uint32_t row = (uint32_t)k * f->stride[K] + (uint32_t)j * st2;
                for (int i = i0; i <= i1; i++) {
                    uint32_t cell = row + (uint32_t)i * st1;
                    uint32_t r = offsets[cell], end = offsets[cell + 1];
                    if (c) {
                        cn->visits++;
                        cn->empty += r == end;
                    }
                    for (; r < end; r++) {
                        uint32_t prim = refs[r];
                        if (mailbox) {
                            uint32_t *slot = &mail[prim & (GP_MAIL - 1)];
                            if (*slot == prim) {
                                if (c) cn->skips++;
                                continue;
                            }
                            *slot = prim;
                        }
                        uint64_t cand;
                        if (spheres && prim >= s->tri_count) {
                            cand = sphere_filter(pk, s->spheres + 4 * (size_t)(prim - s->tri_count),
                                                 &cn->evals);
                        } else if (naive) {
                            cand = pk->active;
                        } else {
                            tri_data td;
                            tri_setup(pk, s->tris + 9 * (size_t)prim, &td);
                            if (tri_culled(pk, &td)) continue;
                            cand = tri_filter(pk, &td, &cn->evals);
                        }
                        for (; cand; cand &= cand - 1) {
                            int l = __builtin_ctzll(cand);
                            if (c) cn->r_tests[l]++;
                            if (!accel_prim_hit(s, prim, &pk->prep[l], &pk->t[l], &pk->u[l],
                                                &pk->v[l], naive, spheres))
                                continue;
                            pk->prim[l] = prim;
                            if (any_hit) retire(pk, cn, l, c);
                        }
                        if (any_hit && !pk->active) return;
                    }
                }
            }
        }
        double z_out = f->planes[K][pk->kstep > 0 ? k + 1 : k];
        for (uint64_t m = leaving(pk, z_out); m; m &= m - 1) retire(pk, cn, __builtin_ctzll(m), c);
        if (!pk->active) break;
    }
#ifdef GP_DEBUG
    if (getenv("GP_DEBUG")) fprintf(stderr, "packet K=%d dir=%d k0=%d slices %u cells %llu\n", K, pk->kstep, pk->k_start, slices, (unsigned long long)dbg_cells);
#endif
}

/* Packets that do not qualify: the single-ray kernel, with the per-ray
 * counter arrays shifted to the packet. */
static void trace_single(const grid_accel *g, const accel_ray *rays, accel_hit *hits,
                         uint8_t *occ, size_t n, accel_counters *c, size_t base)
{
    accel_counters sub, *cs = NULL;
    if (c) {
        memset(&sub, 0, sizeof sub);
        sub.ray_steps = c->ray_steps ? c->ray_steps + base : NULL;
        sub.ray_prims = c->ray_prims ? c->ray_prims + base : NULL;
        cs = &sub;
    }
    if (occ)
        grid_occluded(g, rays, occ, n, cs);
    else
        grid_intersect(g, rays, hits, n, cs);
    if (c) accel_counters_add(c, &sub);
}

static inline __attribute__((always_inline)) void
packet_batch(const grid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
             size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    gpacket pk; /* about 16 KB, aligned by its members */
    gp_count cn;
    for (size_t base = 0; base < count; base += P) {
        uint32_t n = (uint32_t)(count - base < P ? count - base : P);
        int mode = packet_setup(g, &pk, rays + base, n);
        if (mode == GP_SINGLE) {
            trace_single(g, rays + base, hits ? hits + base : NULL, occ ? occ + base : NULL, n, c,
                         base);
            continue;
        }
        if (c) memset(&cn, 0, sizeof cn);
        if (mode == GP_WALK) packet_walk(g, &pk, &cn, c, naive, spheres, mailbox, occ != NULL);
        for (uint32_t i = 0; i < n; i++) {
            uint32_t prim = pk.prim[i];
            if (occ) {
                occ[base + i] = prim != ACCEL_MISS;
            } else if (prim != ACCEL_MISS) {
                accel_hit h = {pk.t[i], g->store.scene_id[prim], pk.u[i], pk.v[i]};
                hits[base + i] = h;
            } else {
                hits[base + i] = accel_hit_miss();
            }
        }
        if (!c) continue;
        for (uint64_t m = pk.active; mode == GP_WALK && m; m &= m - 1) retire(&pk, &cn, __builtin_ctzll(m), c);
        c->rays += n;
        c->packet_box_tests += cn.evals;
        for (uint32_t i = 0; i < n; i++) {
            int live = mode == GP_WALK && (pk.live >> i & 1);
            uint32_t steps = live ? cn.r_visits[i] : 0, tests = live ? cn.r_tests[i] : 0;
            c->steps += steps;
            c->empty_steps += live ? cn.r_empty[i] : 0;
            c->mailbox_skips += live ? cn.r_skips[i] : 0;
            c->prim_tests += tests;
            if (c->ray_steps) c->ray_steps[base + i] = steps;
            if (c->ray_prims) c->ray_prims[base + i] = tests;
        }
        c->box_tests += pk.boxes;
    }
}

static inline __attribute__((always_inline)) void
packet_hit_kernel(const void *a, const accel_ray *rays, void *out, size_t count,
                  accel_counters *c, unsigned f)
{
    packet_batch(a, rays, out, NULL, count, c, (f & ACCEL_V_NAIVE) != 0,
                 (f & ACCEL_V_SPHERES) != 0, (f & ACCEL_V_OPT) != 0);
}

static inline __attribute__((always_inline)) void
packet_occ_kernel(const void *a, const accel_ray *rays, void *out, size_t count,
                  accel_counters *c, unsigned f)
{
    packet_batch(a, rays, NULL, out, count, c, (f & ACCEL_V_NAIVE) != 0,
                 (f & ACCEL_V_SPHERES) != 0, (f & ACCEL_V_OPT) != 0);
}

ACCEL_KERNEL_TABLE(grid_packet_hit_table, packet_hit_kernel)
ACCEL_KERNEL_TABLE(grid_packet_occ_table, packet_occ_kernel)

void grid_packet_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                           size_t count, accel_counters *counters)
{
    accel_run_kernel(&grid_packet_hit_table, accel, rays, hits, count, counters,
                     grid_variant_flags(accel));
}

void grid_packet_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded,
                          size_t count, accel_counters *counters)
{
    accel_run_kernel(&grid_packet_occ_table, accel, rays, occluded, count, counters,
                     grid_variant_flags(accel));
}
