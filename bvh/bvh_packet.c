/*
 * bvh_packet.c - 64-ray packet traversal (traverse=packet), the lecture's
 * section 3, after Wald, Boulos and Shirley, "Ray Tracing Deformable Scenes
 * Using Dynamic Bounding Volume Hierarchies", ACM TOG 26(1), 2007.
 *
 * A packet is 64 consecutive rays of the batch (the primary ray sets emit
 * 8x8 screen tiles in that order; the last packet of a batch may be
 * shorter). The whole packet walks the tree together; each node carries
 * `first`, the first ray that may still hit it (every ray before it missed
 * an ancestor's box, and boxes nest, so it misses this one too):
 *   1. early in: test the first active ray; if it hits, descend;
 *   2. otherwise scan for the first ray that hits the box; it becomes the
 *      new `first`; if none does, skip the node;
 *   3. leaf: intersect the primitives with the rays from `first` on;
 *      interior: visit the child nearer along the first active ray's
 *      direction first and push the other with `first`.
 *
 * The packet is stored as arrays (one per ray attribute), so the box test
 * runs on 8 rays at once with AVX: steps 1 and 2 test the group of 8 that
 * holds `first` and then the following groups, and take the lowest ray
 * that hits. The 8-wide test performs, lane by lane, exactly the
 * operations of bvh_slab (Ize 2013), so it accepts exactly the boxes the
 * single-ray kernel accepts: a packet is correct for any rays, mixed
 * direction signs, different origins, invalid rays (they start dead: an
 * empty t range misses every box). At a leaf the same test culls the rays
 * that miss the leaf's box before their primitive tests (the lecture tests
 * all remaining rays; the culling test is 8 rays per instruction sequence,
 * a primitive test is one ray).
 *
 * frustum=1 adds a conservative early-out between steps 1 and 2 (when the
 * group of the first active ray misses the node), by interval
 * arithmetic on the packet (Boulos, Wald and Shirley, "Geometric and
 * Arithmetic Culling Methods for Entire Ray Packets", tech. report
 * UUCS-06-010, 2006; used by Wald et al. 2007): when every live
 * ray has the same direction signs and no zero direction component, the
 * packet's origins and reciprocal directions are bounded per axis, and
 * bounds on every ray's slab entry and exit follow from the box's planes.
 * If even the earliest possible entry lies beyond the latest possible exit,
 * no ray can hit the box and the node is skipped after one test instead of
 * up to 8 groups. Rounding is monotone, so the bounds computed in float
 * enclose the float values each ray's own test computes: the early-out
 * never drops a box that some ray's test would accept.
 *
 * Counters: steps and box tests are per ray (a node visit counts for every
 * ray from `first` on; ray_steps uses a difference array so that counting a
 * visit is O(1)); packet_box_tests counts the interval tests.
 */
#include <string.h>

#include "bvh_node.h"
#include "core/coherence.h"

#if BVH_SSE || BVH_AVX
#include <immintrin.h>
#endif

#define P BVH_PACKET_SIZE
#define GROUP 8 /* rays per box test: one AVX register */
#define GROUPS (P / GROUP)

_Static_assert(P == 64, "the live-ray mask is one uint64_t");

typedef struct {
    /* Slab-test data, one array per attribute. Rays past the packet's end
     * and invalid rays have the empty range [+inf, -inf]. */
    _Alignas(32) float ox[P];
    _Alignas(32) float oy[P];
    _Alignas(32) float oz[P];
    _Alignas(32) float ix[P];
    _Alignas(32) float iy[P];
    _Alignas(32) float iz[P];
    _Alignas(32) float t_near[P];
    _Alignas(32) float t[P]; /* closest hit so far */
    _Alignas(32) int32_t negx[P]; /* -1 when the direction's sign bit is set */
    _Alignas(32) int32_t negy[P];
    _Alignas(32) int32_t negz[P];
    /* The shear constants of the watertight test (with shared: the cull). */
    _Alignas(32) float sx[P];
    _Alignas(32) float sy[P];
    uint64_t alive; /* bit i: ray i is still traced */
    int shared;     /* every live ray has the same origin and watertight axes */
    /* The cull's record over the batch (aff_misses): rays tried and culled,
     * triangles passed over while it stays under 1 in 4 (then every 16th
     * tries). */
    uint32_t cull_tries, cull_wins, cull_skips;
    uint32_t n;
    uint32_t slot[P];
    float u[P], v[P];
    accel_ray_prep prep[P]; /* for the primitive tests */
    /* Interval bounds of the live rays per axis (frustum=1), lane 3 zero. */
    int ia; /* the bounds are usable */
    _Alignas(16) float ia_neg[4]; /* all-ones bits when the rays' direction is negative */
    _Alignas(16) float ia_omin[4];
    _Alignas(16) float ia_omax[4];
    _Alignas(16) float ia_rmin[4]; /* reciprocal directions */
    _Alignas(16) float ia_rmax[4];
    float t_near_min, t_max;
} packet;

typedef struct {
    uint32_t node;
    uint32_t first;
} packet_entry;

static void kill_ray(packet *pk, uint32_t i)
{
    pk->alive &= ~((uint64_t)1 << i);
    pk->t_near[i] = INFINITY;
    pk->t[i] = -INFINITY;
}

/* The largest t of the packet (dead rays have -inf). */
static inline float packet_t_max(const packet *pk)
{
#if BVH_AVX
    __m256 m = _mm256_load_ps(pk->t);
    for (int g = 1; g < GROUPS; g++) m = _mm256_max_ps(m, _mm256_load_ps(pk->t + GROUP * g));
    __m128 h = _mm_max_ps(_mm256_castps256_ps128(m), _mm256_extractf128_ps(m, 1));
    h = _mm_max_ps(h, _mm_movehl_ps(h, h));
    return _mm_cvtss_f32(_mm_max_ss(h, _mm_shuffle_ps(h, h, 1)));
#else
    float tm = -INFINITY;
    for (uint32_t i = 0; i < P; i++) tm = maxf(tm, pk->t[i]);
    return tm;
#endif
}

/* The rays of `rays` (sharing their origin and axes) that surely miss the
 * triangle of relative vertices *q: its edge functions as affine functions
 * of each ray's shear, 8 rays at a time (accel_tri_aff, core/prim.h). */
static __attribute__((noinline)) uint64_t aff_misses(const packet *pk, const accel_tri_rel *q, uint64_t rays)
{
    accel_tri_aff f;
    accel_tri_aff_of(q, &f);
    uint64_t out = 0;
#if BVH_AVX
    const __m256 rel = _mm256_set1_ps(ACCEL_AFF_REL), tiny = _mm256_set1_ps(ACCEL_AFF_ABS);
    const __m256 sign = _mm256_set1_ps(-0.0f);
    for (uint32_t g = 0; g < GROUPS; g++) {
        if (!((rays >> (GROUP * g)) & 0xFFu)) continue;
        __m256 x = _mm256_load_ps(pk->sx + GROUP * g), y = _mm256_load_ps(pk->sy + GROUP * g);
        __m256 xa = _mm256_andnot_ps(sign, x), ya = _mm256_andnot_ps(sign, y);
        __m256 neg = _mm256_setzero_ps(), pos = neg;
        for (int k = 0; k < 3; k++) {
            __m256 e = _mm256_add_ps(_mm256_set1_ps(f.e0[k]), _mm256_mul_ps(x, _mm256_set1_ps(f.e1[k])));
            e = _mm256_add_ps(e, _mm256_mul_ps(y, _mm256_set1_ps(f.e2[k])));
            __m256 mg = _mm256_add_ps(_mm256_set1_ps(f.m0[k]), _mm256_mul_ps(xa, _mm256_set1_ps(f.m1[k])));
            mg = _mm256_add_ps(mg, _mm256_mul_ps(ya, _mm256_set1_ps(f.m2[k])));
            __m256 m = _mm256_add_ps(_mm256_mul_ps(rel, mg), tiny);
            neg = _mm256_or_ps(neg, _mm256_cmp_ps(e, _mm256_xor_ps(m, sign), _CMP_LT_OQ));
            pos = _mm256_or_ps(pos, _mm256_cmp_ps(e, m, _CMP_GT_OQ));
        }
        out |= (uint64_t)(uint32_t)_mm256_movemask_ps(_mm256_and_ps(neg, pos)) << (GROUP * g);
    }
    return out & rays;
#else
    for (uint64_t m = rays; m; m &= m - 1) {
        uint32_t i = (uint32_t)__builtin_ctzll(m);
        if (accel_tri_aff_miss(&f, pk->sx[i], pk->sy[i])) out |= (uint64_t)1 << i;
    }
    return out;
#endif
}

static void packet_setup(packet *pk, const accel_ray *rays, uint32_t n, int frustum)
{
    pk->n = n;
    pk->alive = 0;
    pk->shared = 1;
    for (uint32_t i = 0; i < P; i++) {
        pk->slot[i] = ACCEL_MISS;
        pk->u[i] = pk->v[i] = 0.0f;
        accel_ray_prep *p = &pk->prep[i];
        if (i < n && accel_prep_ray(&rays[i], p)) {
            if (pk->alive) pk->shared &= accel_prep_same_frame(p, &pk->prep[__builtin_ctzll(pk->alive)]);
            pk->alive |= (uint64_t)1 << i;
            pk->ox[i] = p->org.x, pk->oy[i] = p->org.y, pk->oz[i] = p->org.z;
            pk->ix[i] = p->inv_dir.x, pk->iy[i] = p->inv_dir.y, pk->iz[i] = p->inv_dir.z;
            pk->negx[i] = -p->neg[0], pk->negy[i] = -p->neg[1], pk->negz[i] = -p->neg[2];
            pk->t_near[i] = p->t_near;
            pk->t[i] = p->t_far;
            pk->sx[i] = p->sx, pk->sy[i] = p->sy;
        } else {
            pk->ox[i] = pk->oy[i] = pk->oz[i] = 0.0f;
            pk->ix[i] = pk->iy[i] = pk->iz[i] = 0.0f;
            pk->negx[i] = pk->negy[i] = pk->negz[i] = 0;
            pk->sx[i] = pk->sy[i] = 0.0f;
            kill_ray(pk, i);
        }
    }
    pk->ia = 0;
    if (!frustum || pk->alive == 0) return;
    int first = 1;
    for (uint32_t i = 0; i < n; i++) {
        if (!(pk->alive >> i & 1)) continue;
        const accel_ray_prep *p = &pk->prep[i];
        float o[3] = {p->org.x, p->org.y, p->org.z};
        float r[3] = {p->inv_dir.x, p->inv_dir.y, p->inv_dir.z};
        for (int a = 0; a < 3; a++) {
            if (!isfinite(r[a])) return; /* a zero direction component */
            if (first) {
                uint32_t bits = p->neg[a] ? 0xFFFFFFFFu : 0u;
                memcpy(&pk->ia_neg[a], &bits, sizeof bits);
                pk->ia_omin[a] = pk->ia_omax[a] = o[a];
                pk->ia_rmin[a] = pk->ia_rmax[a] = r[a];
            } else {
                if (p->neg[a] != pk->prep[__builtin_ctzll(pk->alive)].neg[a]) return; /* mixed signs */
                pk->ia_omin[a] = minf(pk->ia_omin[a], o[a]);
                pk->ia_omax[a] = maxf(pk->ia_omax[a], o[a]);
                pk->ia_rmin[a] = minf(pk->ia_rmin[a], r[a]);
                pk->ia_rmax[a] = maxf(pk->ia_rmax[a], r[a]);
            }
        }
        pk->t_near_min = first ? p->t_near : minf(pk->t_near_min, p->t_near);
        first = 0;
    }
    pk->ia_neg[3] = pk->ia_omin[3] = pk->ia_omax[3] = pk->ia_rmin[3] = pk->ia_rmax[3] = 0.0f;
    pk->t_max = packet_t_max(pk);
    pk->ia = 1;
}

/* Bit k set when ray 8g+k hits the node's box: bvh_slab, lane by lane. */
static inline uint32_t group_hits(const packet *pk, const bvh_node *node, uint32_t g)
{
    const float *b = (const float *)node;
    uint32_t o = GROUP * g;
#if BVH_AVX
    /* vmaxps(x, acc) is x > acc ? x : acc, as maxf(acc, x): a NaN x keeps acc */
    __m256 t0 = _mm256_load_ps(pk->t_near + o), t1 = _mm256_load_ps(pk->t + o);
    const float *org[3] = {pk->ox + o, pk->oy + o, pk->oz + o};
    const float *inv[3] = {pk->ix + o, pk->iy + o, pk->iz + o};
    const int32_t *neg[3] = {pk->negx + o, pk->negy + o, pk->negz + o};
    for (int a = 0; a < 3; a++) {
        __m256 lo = _mm256_set1_ps(b[a]), hi = _mm256_set1_ps(b[a + BVH_BMAX_OFS]);
        __m256 m = _mm256_load_ps((const float *)neg[a]);
        __m256 near = _mm256_blendv_ps(lo, hi, m), far = _mm256_blendv_ps(hi, lo, m);
        __m256 oa = _mm256_load_ps(org[a]), ia = _mm256_load_ps(inv[a]);
        t0 = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(near, oa), ia), t0);
        t1 = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(far, oa), ia), t1);
    }
    const __m256 sign = _mm256_set1_ps(-0.0f);
    __m256 lim = _mm256_add_ps(t1, _mm256_mul_ps(_mm256_andnot_ps(sign, t1), _mm256_set1_ps(ACCEL_SLAB_PAD)));
    return (uint32_t)_mm256_movemask_ps(_mm256_cmp_ps(t0, lim, _CMP_LE_OQ));
#else
    uint32_t mask = 0;
    for (uint32_t k = 0; k < GROUP; k++) {
        uint32_t i = o + k;
        float t0 = pk->t_near[i], t1 = pk->t[i];
        int nx = pk->negx[i] ? BVH_BMAX_OFS : 0, ny = pk->negy[i] ? BVH_BMAX_OFS : 0,
            nz = pk->negz[i] ? BVH_BMAX_OFS : 0;
        t0 = maxf(t0, (b[nx] - pk->ox[i]) * pk->ix[i]);
        t0 = maxf(t0, (b[1 + ny] - pk->oy[i]) * pk->iy[i]);
        t0 = maxf(t0, (b[2 + nz] - pk->oz[i]) * pk->iz[i]);
        t1 = minf(t1, (b[BVH_BMAX_OFS - nx] - pk->ox[i]) * pk->ix[i]);
        t1 = minf(t1, (b[1 + BVH_BMAX_OFS - ny] - pk->oy[i]) * pk->iy[i]);
        t1 = minf(t1, (b[2 + BVH_BMAX_OFS - nz] - pk->oz[i]) * pk->iz[i]);
        mask |= (uint32_t)(t0 <= t1 + fabsf(t1) * ACCEL_SLAB_PAD) << k;
    }
    return mask;
#endif
}

/* Rays from `first` on, within the packet, as a mask of group g. */
static inline uint32_t group_range(const packet *pk, uint32_t g, uint32_t first)
{
    uint64_t from = first >= P ? 0 : ~(uint64_t)0 << first;
    uint64_t to = pk->n >= P ? ~(uint64_t)0 : ((uint64_t)1 << pk->n) - 1;
    return (uint32_t)((from & to & pk->alive) >> (GROUP * g)) & 0xFFu;
}

#if !BVH_SSE /* the scalar cull below; the SSE one takes four lanes at once */
static inline float min4(float a, float b, float c, float d) { return minf(minf(a, b), minf(c, d)); }
static inline float max4(float a, float b, float c, float d) { return maxf(maxf(a, b), maxf(c, d)); }
#endif

/* 1 when no live ray of the packet can hit the node's box. Corner products
 * bound fl((plane - o) * r) over the box of (o, r): the product is monotone
 * in each factor, and so is its rounding. The SSE version runs the same
 * operations with the three axes in three lanes. */
static inline int packet_misses(const packet *pk, const bvh_node *node)
{
    const float *b = (const float *)node;
#if BVH_SSE
    const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
    /* lane 3 holds left_first / count bits: cleared before any arithmetic */
    __m128 lo3 = _mm_and_ps(_mm_loadu_ps(b), xyz), hi3 = _mm_and_ps(_mm_loadu_ps(b + BVH_BMAX_OFS), xyz);
    __m128 neg = _mm_load_ps(pk->ia_neg);
    __m128 pn = _mm_or_ps(_mm_and_ps(neg, hi3), _mm_andnot_ps(neg, lo3));
    __m128 pf = _mm_or_ps(_mm_and_ps(neg, lo3), _mm_andnot_ps(neg, hi3));
    __m128 omin = _mm_load_ps(pk->ia_omin), omax = _mm_load_ps(pk->ia_omax);
    __m128 r0 = _mm_load_ps(pk->ia_rmin), r1 = _mm_load_ps(pk->ia_rmax);
    __m128 n0 = _mm_sub_ps(pn, omax), n1 = _mm_sub_ps(pn, omin);
    __m128 f0 = _mm_sub_ps(pf, omax), f1 = _mm_sub_ps(pf, omin);
    __m128 near = _mm_min_ps(_mm_min_ps(_mm_mul_ps(n0, r0), _mm_mul_ps(n0, r1)),
                             _mm_min_ps(_mm_mul_ps(n1, r0), _mm_mul_ps(n1, r1)));
    __m128 far = _mm_max_ps(_mm_max_ps(_mm_mul_ps(f0, r0), _mm_mul_ps(f0, r1)),
                            _mm_max_ps(_mm_mul_ps(f1, r0), _mm_mul_ps(f1, r1)));
    /* lane 3 becomes the packet's t range, then reduce over the lanes */
    near = _mm_or_ps(_mm_and_ps(xyz, near), _mm_andnot_ps(xyz, _mm_set1_ps(pk->t_near_min)));
    far = _mm_or_ps(_mm_and_ps(xyz, far), _mm_andnot_ps(xyz, _mm_set1_ps(pk->t_max)));
    near = _mm_max_ps(near, _mm_movehl_ps(near, near));
    far = _mm_min_ps(far, _mm_movehl_ps(far, far));
    float lo = _mm_cvtss_f32(_mm_max_ss(near, _mm_shuffle_ps(near, near, 1)));
    float hi = _mm_cvtss_f32(_mm_min_ss(far, _mm_shuffle_ps(far, far, 1)));
#else
    float lo = pk->t_near_min, hi = pk->t_max;
    for (int a = 0; a < 3; a++) {
        int neg = pk->ia_neg[a] != 0.0f;
        float pn = b[a + (neg ? BVH_BMAX_OFS : 0)], pf = b[a + (neg ? 0 : BVH_BMAX_OFS)];
        float n0 = pn - pk->ia_omax[a], n1 = pn - pk->ia_omin[a];
        float f0 = pf - pk->ia_omax[a], f1 = pf - pk->ia_omin[a];
        float r0 = pk->ia_rmin[a], r1 = pk->ia_rmax[a];
        lo = maxf(lo, min4(n0 * r0, n0 * r1, n1 * r0, n1 * r1));
        hi = minf(hi, max4(f0 * r0, f0 * r1, f1 * r0, f1 * r1));
    }
#endif
    return lo > hi + fabsf(hi) * ACCEL_SLAB_PAD;
}

/* trace_packet stays one function of about 140 lines on purpose: it is the
 * forced-inline body of every packet kernel copy, and its node loop keeps
 * the packet's live mask, stack and first-active index in registers across
 * the box test, the leaf loop and the frustum cull; split into calls, a
 * copy's code (and speed) would depend on what the compiler inlines. */
static inline __attribute__((always_inline)) void
trace_packet(const bvh *b, packet *pk, accel_counters *c, uint32_t *ray_steps,
             uint32_t *ray_prims, int naive, int has_spheres, int any_hit, int frustum)
{
    const bvh_node *nodes = b->nodes;
    const uint32_t n = pk->n, groups = (n + GROUP - 1) / GROUP;
    int32_t step_diff[P + 1];
    uint64_t steps = 0, boxes = 0, prims = 0, packet_boxes = 0;
    uint32_t visits = 0;
    if (c) memset(step_diff, 0, sizeof step_diff);
    if (b->node_count == 0 || pk->alive == 0) goto out;

    packet_entry stack[BVH_MAX_DEPTH];
    int sp = 0;
    uint32_t node_idx = 0, first = (uint32_t)__builtin_ctzll(pk->alive);
    for (;;) {
        const bvh_node *node = &nodes[node_idx];
        /* Early in on the group of the first active ray; if none of its
         * rays hits, the frustum test (when on) may reject the node for the
         * whole packet; otherwise scan the following groups. f = the first
         * ray that hits. */
        uint32_t f = n;
        for (uint32_t g = first / GROUP; g < groups; g++) {
            uint32_t range = group_range(pk, g, first);
            if (!range) continue;
            uint32_t m = group_hits(pk, node, g) & range;
            if (c) boxes += (uint64_t)__builtin_popcount(range);
            if (m) {
                f = GROUP * g + (uint32_t)__builtin_ctz(m);
                break;
            }
            if (frustum && pk->ia && g == first / GROUP) {
                packet_boxes++;
                if (packet_misses(pk, node)) break;
            }
        }
        if (f == n) goto pop;
        visits++;
        if (ACCEL_STEP_BOUND_BROKEN(c, visits, b->node_count)) goto out;
        if (c) {
            steps += n - f;
            step_diff[f]++;
        }
        if (node->count) {
            /* Leaf: the rays from f on that hit its box, primitive by
             * primitive, each ray in turn with its own t (each ray tests the
             * primitives in their order, as it would alone). When the rays
             * share their origin and axes (pk->shared), each triangle's
             * vertices relative to the origin are computed once for all of
             * them (accel_tri_watertight_rel), and the rays whose edge
             * functions, affine in their shear, are surely of mixed signs
             * skip it (aff_misses: the exact test's first rule, so every
             * answer stays as it was). */
            uint64_t rays = 0;
            for (uint32_t g = f / GROUP; g < groups; g++) {
                uint32_t range = group_range(pk, g, f);
                if (!range) continue;
                rays |= (uint64_t)(group_hits(pk, node, g) & range) << (GROUP * g);
                if (c) boxes += (uint64_t)__builtin_popcount(range);
            }
            for (uint32_t k = node->left_first, end = k + node->count; k < end && rays; k++) {
                const float *data = b->prim_data + (size_t)BVH_SLOT_FLOATS * k;
                const int rel = pk->shared && !naive && !(has_spheres && b->prim_ids[k] >= b->tri_count);
                accel_tri_rel q;
                uint64_t todo = rays;
                if (rel) {
                    accel_tri_rel_of(&pk->prep[__builtin_ctzll(rays)], data, &q);
                    if (pk->cull_tries < 256 || 4 * pk->cull_wins >= pk->cull_tries ||
                        (++pk->cull_skips & 15) == 0) {
                        uint64_t culled = aff_misses(pk, &q, rays);
                        pk->cull_tries += (uint32_t)__builtin_popcountll(rays);
                        pk->cull_wins += (uint32_t)__builtin_popcountll(culled);
                        todo &= ~culled;
                    }
                    if (c) {
                        uint64_t culled = rays & ~todo;
                        prims += (uint64_t)__builtin_popcountll(culled);
                        for (; ray_prims && culled; culled &= culled - 1)
                            ray_prims[__builtin_ctzll(culled)]++;
                    }
                }
                for (uint64_t m = todo; m; m &= m - 1) {
                    uint32_t i = (uint32_t)__builtin_ctzll(m);
                    if (c) {
                        prims++;
                        if (ray_prims) ray_prims[i]++;
                    }
                    if (!(rel ? accel_tri_watertight_rel(&pk->prep[i], data, &q, &pk->t[i], &pk->u[i], &pk->v[i])
                              : bvh_slot_hit(b, k, &pk->prep[i], &pk->t[i], &pk->u[i], &pk->v[i], naive,
                                             has_spheres)))
                        continue;
                    pk->slot[i] = k;
                    if (any_hit) {
                        kill_ray(pk, i);
                        rays &= ~((uint64_t)1 << i);
                        if (!pk->alive) goto out;
                    }
                }
            }
            if (frustum && pk->ia) pk->t_max = packet_t_max(pk);
            goto pop;
        }
        /* Interior: the child whose centre lies nearer along the first
         * active ray goes first; the other waits with the same `first`. */
        {
            uint32_t near = node->left_first, far = near + 1;
            const bvh_node *c0 = &nodes[near], *c1 = &nodes[far];
            const accel_ray_prep *p = &pk->prep[f];
            float d = (c1->bmin[0] + c1->bmax[0] - c0->bmin[0] - c0->bmax[0]) * p->dir.x +
                      (c1->bmin[1] + c1->bmax[1] - c0->bmin[1] - c0->bmax[1]) * p->dir.y +
                      (c1->bmin[2] + c1->bmax[2] - c0->bmin[2] - c0->bmax[2]) * p->dir.z;
            if (d < 0.0f) {
                near = far;
                far = node->left_first;
            }
            stack[sp].node = far;
            stack[sp].first = f;
            sp++;
            node_idx = near;
            first = f;
            continue;
        }
    pop:
        if (sp == 0) break;
        sp--;
        node_idx = stack[sp].node;
        first = stack[sp].first;
    }
out:
    if (c) {
        c->rays += n;
        c->steps += steps;
        c->box_tests += boxes;
        c->prim_tests += prims;
        c->packet_box_tests += packet_boxes;
        c->packet_steps += visits;
        if (ray_steps) {
            int32_t run = 0;
            for (uint32_t i = 0; i < n; i++) {
                run += step_diff[i];
                ray_steps[i] = (uint32_t)run;
            }
        }
    }
}

static inline __attribute__((always_inline)) void
packet_batch(const bvh *b, const accel_ray *rays, accel_hit *hits, uint8_t *occ, size_t count,
             accel_counters *c, int naive, int has_spheres, int frustum)
{
    const int any_hit = occ != NULL;
    packet pk; /* about 10 KB, aligned by its members */
    pk.cull_tries = pk.cull_wins = pk.cull_skips = 0;
    for (size_t base = 0; base < count; base += P) {
        uint32_t n = (uint32_t)(count - base < P ? count - base : P);
        packet_setup(&pk, rays + base, n, frustum);
        uint32_t *ray_steps = c && c->ray_steps ? c->ray_steps + base : NULL;
        uint32_t *ray_prims = c && c->ray_prims ? c->ray_prims + base : NULL;
        if (ray_prims) memset(ray_prims, 0, n * sizeof *ray_prims);
        trace_packet(b, &pk, c, ray_steps, ray_prims, naive, has_spheres, any_hit, frustum);
        for (uint32_t i = 0; i < n; i++) {
            if (any_hit) {
                occ[base + i] = pk.slot[i] != ACCEL_MISS;
            } else if (pk.slot[i] != ACCEL_MISS) {
                accel_hit h = {pk.t[i], b->prim_ids[pk.slot[i]], pk.u[i], pk.v[i]};
                hits[base + i] = h;
            } else {
                hits[base + i] = accel_hit_miss();
            }
        }
    }
}

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): frustum=0|1 on triangles (0, 4) and spheres (2, 6). */
ACCEL_KERNEL_PAIR_SEL(packet, packet_batch, (1, 0, 1, 0, 1, 0, 1, 0), (1, 0, 1, 0, 1, 0, 1, 0))

static void single_hit(const void *b, const accel_ray *r, accel_hit *h, size_t n, accel_counters *c)
{
    bvh_trace_intersect(b, r, h, n, c);
}

static void single_occ(const void *b, const accel_ray *r, uint8_t *o, size_t n, accel_counters *c)
{
    bvh_trace_occluded(b, r, o, n, c);
}

/* Packets in any ray order (core/coherence.h): incoherent groups go to the
 * single-ray traversal of the same tree. */
ACCEL_COHERENT_ENTRIES(bvh_packet_intersect, bvh_packet_occluded, const bvh, packet_hit_table,
                       packet_occ_table, bvh_variant_flags, single_hit, single_occ)
