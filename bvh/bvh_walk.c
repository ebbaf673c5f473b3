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
 * tree the same way (wide/walk.c); bvh.c's kind entry picks the path.
 */
#include "bvh_node.h"

static void walk_binary(const bvh *b, const accel_ray_prep *p, float pad, accel_walk_visit visit,
                        void *ctx, uint32_t *steps)
{
    const bvh_node *nodes = b->nodes;
    float t_max = p->t_far, e;
    bvh_walk_entry stack[BVH_MAX_DEPTH];
    int sp = 0;
    const bvh_node *node = bvh_padded_slab(nodes[0].bmin, nodes[0].bmax, pad, p, t_max, &e)
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
            int h0 = bvh_padded_slab(nodes[left].bmin, nodes[left].bmax, pad, p, t_max, &e0);
            int h1 = bvh_padded_slab(nodes[left + 1].bmin, nodes[left + 1].bmax, pad, p, t_max, &e1);
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

void bvh_walk_binary(const bvh *b, const accel_ray_prep *p, float pad, accel_walk_visit visit,
                     void *ctx, uint32_t *steps)
{
    if (b->node_count > 0) walk_binary(b, p, pad, visit, ctx, steps);
}
