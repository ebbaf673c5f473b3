/*
 * bvh_walk.c - accel.h's conservative walk for the bvh kind, which lets a
 * bvh serve as instanced's bottom level (instanced:bottom=bvh:...).
 *
 * The single-ray traversal of bvh_single.c with two changes: every box is
 * grown by the pad before the robust slab test (Ize 2013, geom.h's
 * box3_slab), and a leaf hands its primitives' scene ids to the visitor
 * instead of testing them; the visitor's answer is the new end of the ray,
 * against which later boxes and popped entries are tested. The nearer
 * child is visited first, as in the kernel. width=4|8 walk the collapsed
 * tree the same way, one child lane at a time (scalar; their SIMD kernels
 * stay the timed path): the hit children are ordered by entry distance
 * and pushed far to near; a leaf visits every lane of its blocks (padding
 * lanes repeat their leaf's last primitive: a repeated visit, which the
 * contract allows).
 */
#include "bvh_node.h"
#include "wide_node.h"

/* A box given as lo/hi triples, grown by pad. */
static inline __attribute__((always_inline)) int padded_slab(const float *lo, const float *hi,
                                                             float pad, const accel_ray_prep *p,
                                                             float t_max, float *entry)
{
    float l[3] = {lo[0] - pad, lo[1] - pad, lo[2] - pad};
    float h[3] = {hi[0] + pad, hi[1] + pad, hi[2] + pad};
    return box3_slab(l, h, p->org, p->inv_dir, p->neg, p->t_near, t_max, entry);
}

typedef struct {
    uint32_t node;
    float entry;
} walk_entry;

static void walk_binary(const bvh *b, const accel_ray_prep *p, float pad, accel_walk_visit visit,
                        void *ctx, uint32_t *steps)
{
    const bvh_node *nodes = b->nodes;
    float t_max = p->t_far, e;
    walk_entry stack[BVH_MAX_DEPTH];
    int sp = 0;
    const bvh_node *node = padded_slab(nodes[0].bmin, nodes[0].bmax, pad, p, t_max, &e)
                               ? &nodes[0]
                               : NULL;
    while (node) {
        (*steps)++;
        if (node->count) {
            uint32_t end = node->left_first + node->count;
            for (uint32_t i = node->left_first; i < end; i++) {
                t_max = visit(ctx, b->prim_ids[i], t_max);
                if (t_max < p->t_near) return;
            }
        } else {
            uint32_t left = node->left_first;
            float e0, e1;
            int h0 = padded_slab(nodes[left].bmin, nodes[left].bmax, pad, p, t_max, &e0);
            int h1 = padded_slab(nodes[left + 1].bmin, nodes[left + 1].bmax, pad, p, t_max, &e1);
            if (h0 && h1) {
                int near0 = e0 <= e1;
                stack[sp].node = near0 ? left + 1 : left;
                stack[sp++].entry = near0 ? e1 : e0;
                node = &nodes[near0 ? left : left + 1];
                continue;
            }
            if (h0 || h1) {
                node = &nodes[h0 ? left : left + 1];
                continue;
            }
        }
        node = NULL;
        while (sp > 0) {
            sp--;
            if (box3_entry_before(stack[sp].entry, t_max)) {
                node = &nodes[stack[sp].node];
                break;
            }
        }
    }
}

/* One wide node seen through its rows (width 4 or 8). */
static void walk_wide(const bvh_wide *w, const accel_ray_prep *p, float pad,
                      accel_walk_visit visit, void *ctx, uint32_t *steps)
{
    const int W = w->width;
    const size_t node_bytes = W == 8 ? sizeof(wide_node8) : sizeof(wide_node4);
    const size_t block_bytes = w->block == 8 ? sizeof(wide_block8) : sizeof(wide_block4);
    const size_t id_ofs = w->block == 8 ? offsetof(wide_block8, id) : offsetof(wide_block4, id);
    float t_max = p->t_far;
    walk_entry stack[WIDE_STACK(8)];
    int sp = 0;
    stack[sp].node = w->root;
    stack[sp++].entry = -INFINITY;
    while (sp > 0) {
        walk_entry top = stack[--sp];
        if (!box3_entry_before(top.entry, t_max)) continue;
        (*steps)++;
        if (top.node & WIDE_LEAF) {
            const char *blk = (const char *)w->blocks + block_bytes * wide_leaf_first(top.node);
            for (uint32_t k = 0; k < wide_leaf_blocks(top.node); k++, blk += block_bytes) {
                const uint32_t *ids = (const uint32_t *)(blk + id_ofs);
                for (int lane = 0; lane < w->block; lane++) {
                    t_max = visit(ctx, ids[lane], t_max);
                    if (t_max < p->t_near) return;
                }
            }
            continue;
        }
        const char *nd = (const char *)w->nodes + (w->quant ? sizeof(wide_qnode8) : node_bytes) * top.node;
        const float *rows = (const float *)nd;
        const uint32_t *child = w->quant ? ((const wide_qnode8 *)nd)->child
                                         : (const uint32_t *)(nd + (size_t)6 * W * sizeof(float));
        walk_entry hit[8];
        int n = 0;
        for (int c = 0; c < W; c++) {
            if (child[c] == WIDE_EMPTY) continue;
            float lo[3], hi[3];
            if (w->quant) {
                bvh_wide_qbox((const wide_qnode8 *)nd, c, lo, hi);
            } else {
                lo[0] = rows[0 * W + c], lo[1] = rows[2 * W + c], lo[2] = rows[4 * W + c];
                hi[0] = rows[1 * W + c], hi[1] = rows[3 * W + c], hi[2] = rows[5 * W + c];
            }
            float e;
            if (!padded_slab(lo, hi, pad, p, t_max, &e)) continue;
            /* Insertion by entry, farthest first: the nearest is pushed last. */
            int j = n++;
            while (j > 0 && hit[j - 1].entry < e) hit[j] = hit[j - 1], j--;
            hit[j].node = child[c];
            hit[j].entry = e;
        }
        for (int c = 0; c < n; c++) stack[sp++] = hit[c];
    }
}

int bvh_walk(const void *accel, const accel_ray *ray, float pad, accel_walk_visit visit, void *ctx,
             uint32_t *steps)
{
    const bvh *b = accel;
    if (!visit) return 0;
    accel_ray_prep p;
    if (!accel_prep_ray(ray, &p)) return 0;
    if (b->wide) {
        if (b->wide->root != WIDE_EMPTY) walk_wide(b->wide, &p, pad, visit, ctx, steps);
    } else if (b->node_count > 0) {
        walk_binary(b, &p, pad, visit, ctx, steps);
    }
    return 0;
}
