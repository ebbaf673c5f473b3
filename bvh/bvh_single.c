/*
 * bvh_single.c - single-ray BVH traversal: closest hit and any hit.
 *
 * A stack-based loop in the style of pbrt-v3's BVHAccel::Intersect and of
 * Aila and Laine, "Understanding the Efficiency of Ray Traversal on GPUs",
 * HPG 2009: at an interior node both children (one cache line) are tested
 * at once, the nearer one is visited next and the farther one is pushed
 * with its entry distance; a popped node whose entry lies beyond the
 * closest hit found so far is dropped without touching it again. The box
 * test is bvh_slab (Ize 2013, see bvh_node.h).
 *
 * Counters follow STYLE.md: the kernel is written once as an always-inline
 * function and compiled into one variant table per query (core/variant.h),
 * so the timed copies contain no counting code. Counted runs check the step
 * bound: a ray visits each node at most once, so more steps than nodes means
 * a broken tree or loop.
 */
#include "bvh_node.h"
#include "core/variant.h"

typedef struct {
    uint32_t node;
    float t_entry;
} stack_entry;

static inline __attribute__((always_inline)) void
trace_ray(const bvh *b, const accel_ray *ray, accel_hit *hit_out, uint8_t *occ_out,
          accel_counters *c, size_t ray_idx, int naive, int has_spheres, int any_hit, int left_first)
{
    accel_hit hit = accel_hit_miss();
    uint32_t steps = 0, boxes = 0, prims = 0;
    accel_ray_prep p;
    if (b->node_count > 0 && accel_prep_ray(ray, &p)) {
        bvh_slab_ray r;
        bvh_slab_setup(&r, &p);
        const bvh_node *nodes = b->nodes;
        float t = p.t_far, t_entry;
        uint32_t slot = ACCEL_MISS;
        stack_entry stack[BVH_MAX_DEPTH];
        int sp = 0;
        boxes++;
        const bvh_node *node = bvh_slab(&nodes[0], &r, p.t_near, t, &t_entry) ? &nodes[0] : NULL;
        while (node) {
            steps++;
            if (ACCEL_STEP_BOUND_BROKEN(c, steps, b->node_count)) break;
            if (node->count) {
                /* Leaf: its primitives are one contiguous run of slots. */
                uint32_t end = node->left_first + node->count;
                for (uint32_t i = node->left_first; i < end; i++) {
                    prims++;
                    if (bvh_slot_hit(b, i, &p, &t, &hit.u, &hit.v, naive, has_spheres)) {
                        slot = i;
                        if (any_hit) goto done;
                    }
                }
            } else {
                /* Interior: test both children, near one first. The
                 * choice is made with selects rather than branches: which
                 * child is nearer is the least predictable decision here. */
                uint32_t left = node->left_first;
                float e0, e1;
                int hits = bvh_slab(&nodes[left], &r, p.t_near, t, &e0) |
                           bvh_slab(&nodes[left + 1], &r, p.t_near, t, &e1) << 1;
                boxes += 2;
                if (hits) {
                    /* first=left (a control): the left one whenever it is hit */
                    int second = hits == 2 || (!left_first && hits == 3 && e1 < e0);
                    stack[sp].node = left + !second;
                    stack[sp].t_entry = second ? e0 : e1;
                    sp += hits == 3;
                    node = &nodes[left + second];
                    continue;
                }
            }
            /* Pop the next far child that can still hold a closer hit. */
            node = NULL;
            while (sp > 0) {
                sp--;
                if (box3_entry_before(stack[sp].t_entry, t)) {
                    node = &nodes[stack[sp].node];
                    break;
                }
            }
        }
    done:
        if (slot != ACCEL_MISS) {
            hit.t = t;
            hit.prim = b->prim_ids[slot];
        } else {
            hit.u = hit.v = 0.0f;
        }
    }
    if (any_hit)
        occ_out[ray_idx] = hit.prim != ACCEL_MISS;
    else
        hit_out[ray_idx] = hit;
    if (c) accel_count_ray(c, ray_idx, steps, 0, boxes, prims, 0);
}

/* The query is passed as a literal (not derived from occ, as
 * ACCEL_KERNEL_PAIR's kernels do): the any-hit copy then holds one
 * trace_ray specialized for it, which measured about 0.5% fewer
 * instructions on shadow rays than either a per-ray or a per-batch test. */
static inline __attribute__((always_inline)) void
trace_batch(const bvh *b, const accel_ray *rays, accel_hit *hits, uint8_t *occ, size_t count,
            accel_counters *c, int naive, int has_spheres, int any_hit, int left_first)
{
    for (size_t i = 0; i < count; i++)
        trace_ray(b, &rays[i], hits, occ, c, i, naive, has_spheres, any_hit, left_first);
}

/* ACCEL_V_OPT selects first=left (bvh_variant_flags). */
#define SINGLE_HIT(a, r, o, n, c, f)                                                        \
    trace_batch(a, r, o, NULL, n, c, ((f) & ACCEL_V_NAIVE) != 0, ((f) & ACCEL_V_SPHERES) != 0, 0, \
                ((f) & ACCEL_V_OPT) != 0)
#define SINGLE_OCC(a, r, o, n, c, f)                                                        \
    trace_batch(a, r, NULL, o, n, c, ((f) & ACCEL_V_NAIVE) != 0, ((f) & ACCEL_V_SPHERES) != 0, 1, \
                ((f) & ACCEL_V_OPT) != 0)
/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): first=near|left on triangles (0, 4) and spheres (2, 6), and
 * closest hits with the naive test (1). */
ACCEL_KERNEL_TABLE_SEL(single_hit_table, SINGLE_HIT, (1, 1, 1, 0, 1, 0, 1, 0))
ACCEL_KERNEL_TABLE_SEL(single_occ_table, SINGLE_OCC, (1, 0, 1, 0, 1, 0, 1, 0))

ACCEL_KERNEL_ENTRIES(bvh_trace_intersect, bvh_trace_occluded, const bvh, single_hit_table,
                     single_occ_table, bvh_variant_flags)
