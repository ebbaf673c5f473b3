/*
 * packet.c - 64-ray packet traversal (traverse=packet), the lecture's
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
 *   3. leaf: intersect every primitive with every ray from `first` on;
 *      interior: visit the child nearer along the first active ray's
 *      direction first and push the other with `first`.
 * Per-ray box tests are bvh_slab, the same robust test as single rays, so
 * a packet is correct for any rays: mixed direction signs, different
 * origins, invalid rays (they start dead and never hit a box).
 *
 * frustum=1 adds a conservative early-out before step 1, by interval
 * arithmetic on the packet (Wald et al. 2007, section 4.3): when every live
 * ray has the same direction signs and no zero direction component, the
 * packet's origins and reciprocal directions are bounded per axis, and
 * bounds on every ray's slab entry and exit follow from the box's planes.
 * If even the earliest possible entry lies beyond the latest possible exit,
 * no ray can hit the box and the node is skipped after one test instead of
 * up to 64. Rounding is monotone, so the bounds computed in float enclose
 * the float values each ray's own test computes: the early-out never drops
 * a box that some ray's bvh_slab would accept.
 *
 * Counters: steps and box tests are per ray (a node visit counts for every
 * ray from `first` on; ray_steps uses a difference array so that counting a
 * visit is O(1)); packet_box_tests counts the interval tests.
 */
#include <string.h>

#include "bvh_node.h"

#define P BVH_PACKET_SIZE

typedef struct {
    uint32_t n;
    uint32_t alive_count;
    float t_near[P], t[P];     /* t: closest hit so far; a dead ray has [+inf, -inf] */
    uint32_t slot[P];
    float u[P], v[P];
    uint8_t alive[P];
    bvh_slab_ray sr[P];
    accel_ray_prep prep[P];
    /* Interval bounds of the live rays (frustum=1). */
    int ia;                    /* the bounds are usable */
    int ia_near[3], ia_far[3]; /* shared plane offsets */
    float omin[3], omax[3], rmin[3], rmax[3];
    float t_near_min, t_max;
} packet;

typedef struct {
    uint32_t node;
    uint32_t first;
} packet_entry;

static void packet_setup(packet *pk, const accel_ray *rays, uint32_t n, int frustum)
{
    pk->n = n;
    pk->alive_count = 0;
    for (uint32_t i = 0; i < n; i++) {
        pk->slot[i] = ACCEL_MISS;
        pk->u[i] = pk->v[i] = 0.0f;
        if (accel_prep_ray(&rays[i], &pk->prep[i])) {
            pk->alive[i] = 1;
            pk->alive_count++;
            bvh_slab_setup(&pk->sr[i], &pk->prep[i]);
            pk->t_near[i] = pk->prep[i].t_near;
            pk->t[i] = pk->prep[i].t_far;
        } else {
            pk->alive[i] = 0;
            memset(&pk->sr[i], 0, sizeof pk->sr[i]);
            pk->t_near[i] = INFINITY;
            pk->t[i] = -INFINITY;
        }
    }
    pk->ia = 0;
    if (!frustum || pk->alive_count == 0) return;
    int first = 1;
    for (uint32_t i = 0; i < n; i++) {
        if (!pk->alive[i]) continue;
        const accel_ray_prep *p = &pk->prep[i];
        float o[3] = {p->org.x, p->org.y, p->org.z};
        float r[3] = {p->inv_dir.x, p->inv_dir.y, p->inv_dir.z};
        for (int a = 0; a < 3; a++) {
            if (!isfinite(r[a])) return; /* a zero direction component */
            if (first) {
                pk->ia_near[a] = a + (p->neg[a] ? BVH_BMAX_OFS : 0);
                pk->ia_far[a] = a + (p->neg[a] ? 0 : BVH_BMAX_OFS);
                pk->omin[a] = pk->omax[a] = o[a];
                pk->rmin[a] = pk->rmax[a] = r[a];
            } else {
                if (pk->ia_near[a] != a + (p->neg[a] ? BVH_BMAX_OFS : 0)) return; /* mixed signs */
                pk->omin[a] = minf(pk->omin[a], o[a]);
                pk->omax[a] = maxf(pk->omax[a], o[a]);
                pk->rmin[a] = minf(pk->rmin[a], r[a]);
                pk->rmax[a] = maxf(pk->rmax[a], r[a]);
            }
        }
        pk->t_near_min = first ? p->t_near : minf(pk->t_near_min, p->t_near);
        first = 0;
    }
    pk->t_max = -INFINITY;
    for (uint32_t i = 0; i < n; i++) pk->t_max = maxf(pk->t_max, pk->t[i]);
    pk->ia = 1;
}

static inline float min4(float a, float b, float c, float d) { return minf(minf(a, b), minf(c, d)); }
static inline float max4(float a, float b, float c, float d) { return maxf(maxf(a, b), maxf(c, d)); }

/* 1 when no live ray of the packet can hit the node's box. Corner products
 * bound fl((plane - o) * r) over the box of (o, r): the product is monotone
 * in each factor, and so is its rounding. */
static inline int packet_misses(const packet *pk, const bvh_node *node)
{
    const float *b = (const float *)node;
    float lo = pk->t_near_min, hi = pk->t_max;
    for (int a = 0; a < 3; a++) {
        float pn = b[pk->ia_near[a]], pf = b[pk->ia_far[a]];
        float n0 = pn - pk->omax[a], n1 = pn - pk->omin[a];
        float f0 = pf - pk->omax[a], f1 = pf - pk->omin[a];
        float r0 = pk->rmin[a], r1 = pk->rmax[a];
        lo = maxf(lo, min4(n0 * r0, n0 * r1, n1 * r0, n1 * r1));
        hi = minf(hi, max4(f0 * r0, f0 * r1, f1 * r0, f1 * r1));
    }
    return lo > hi + fabsf(hi) * ACCEL_SLAB_PAD;
}

static inline __attribute__((always_inline)) void
trace_packet(const bvh *b, packet *pk, accel_counters *c, uint32_t *ray_steps,
             uint32_t *ray_prims, int naive, int has_spheres, int any_hit, int frustum)
{
    const bvh_node *nodes = b->nodes;
    const uint32_t n = pk->n;
    int32_t step_diff[P + 1];
    uint64_t steps = 0, boxes = 0, prims = 0, packet_boxes = 0;
    uint32_t visits = 0;
    if (c) memset(step_diff, 0, sizeof step_diff);
    if (b->node_count == 0 || pk->alive_count == 0) goto out;

    packet_entry stack[BVH_MAX_DEPTH];
    int sp = 0;
    uint32_t node_idx = 0, first = 0;
    for (;;) {
        const bvh_node *node = &nodes[node_idx];
        if (frustum && pk->ia) {
            packet_boxes++;
            if (packet_misses(pk, node)) goto pop;
        }
        /* Early in on the first active ray, else scan for one that hits. */
        uint32_t f = first;
        float entry;
        while (f < n && !bvh_slab(node, &pk->sr[f], pk->t_near[f], pk->t[f], &entry)) f++;
        if (c) boxes += (f < n ? f + 1 : n) - first;
        if (f == n) goto pop;
        visits++;
        ACCEL_STEP_BOUND_CHECK(visits, b->node_count);
        if (c) {
            steps += n - f;
            step_diff[f]++;
        }
        if (node->count) {
            /* Leaf: every primitive against every live ray from f on. */
            uint32_t end = node->left_first + node->count;
            for (uint32_t k = node->left_first; k < end; k++) {
                for (uint32_t i = f; i < n; i++) {
                    if (!pk->alive[i]) continue;
                    if (c) {
                        prims++;
                        if (ray_prims) ray_prims[i]++;
                    }
                    if (!bvh_slot_hit(b, k, &pk->prep[i], &pk->t[i], &pk->u[i], &pk->v[i], naive,
                                      has_spheres))
                        continue;
                    pk->slot[i] = k;
                    if (any_hit) {
                        pk->alive[i] = 0;
                        pk->t_near[i] = INFINITY;
                        pk->t[i] = -INFINITY;
                        if (--pk->alive_count == 0) goto out;
                    }
                }
            }
            if (frustum && pk->ia) {
                float tm = -INFINITY;
                for (uint32_t i = 0; i < n; i++) tm = maxf(tm, pk->t[i]);
                pk->t_max = tm;
            }
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
             accel_counters *c, int naive, int has_spheres, int any_hit, int frustum)
{
    packet pk;
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

#define PACKET_DISPATCH(b, rays, hits, occ, n, c, any_hit)                                      \
    do {                                                                                        \
        if (c)                                                                                  \
            packet_batch(b, rays, hits, occ, n, c, (b)->naive, (b)->has_spheres, any_hit,       \
                         (b)->frustum);                                                         \
        else if ((b)->naive)                                                                    \
            packet_batch(b, rays, hits, occ, n, NULL, 1, (b)->has_spheres, any_hit,             \
                         (b)->frustum);                                                         \
        else if ((b)->has_spheres)                                                              \
            packet_batch(b, rays, hits, occ, n, NULL, 0, 1, any_hit, (b)->frustum);             \
        else if ((b)->frustum)                                                                  \
            packet_batch(b, rays, hits, occ, n, NULL, 0, 0, any_hit, 1);                        \
        else                                                                                    \
            packet_batch(b, rays, hits, occ, n, NULL, 0, 0, any_hit, 0);                        \
    } while (0)

void bvh_packet_intersect(const bvh *b, const accel_ray *rays, accel_hit *hits, size_t count,
                          accel_counters *c)
{
    PACKET_DISPATCH(b, rays, hits, (uint8_t *)NULL, count, c, 0);
}

void bvh_packet_occluded(const bvh *b, const accel_ray *rays, uint8_t *occ, size_t count,
                         accel_counters *c)
{
    PACKET_DISPATCH(b, rays, (accel_hit *)NULL, occ, count, c, 1);
}
