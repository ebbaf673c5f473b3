/*
 * inst_wide.c - the 8-wide form of the `instanced` kind's BVHs (both
 * levels; inst_impl.h's inst_wide): a bvh_box_tree collapsed by the wide
 * BVH's own greedy collapse (bvh/wide/collapse.c, bvh_wide_collapse_pool)
 * into its 8-wide nodes, which the traversal tests with the wide BVH's
 * node test (bvh/wide/kernel.h). This file only fills the leaves: the top
 * level's with item ids (blocks of one), the bottom level's with the
 * mesh's primitives in blocks of 8 (core/block.h), object space (a
 * sphere's lane, plain scenes only, holds its centre and radius as
 * bvh/wide's blocks do). A plain scene's blocks are its world blocks;
 * an instance's are made from them (inst_world_blocks, or per leaf at
 * trace time with world=compute).
 *
 * Each slot keeps its binary node's box exactly, so the wide tree holds the
 * same boxes over the same leaves: a walk of it with a conservative slab
 * test reaches every leaf a walk of the binary tree reaches, which is all
 * the exactness argument of README.md asks of the bottom level. A refit
 * refits the binary tree and collapses it again (the collapse and the
 * copy are linear in the tree, as the refit is).
 */
#include <stdlib.h>
#include <string.h>

#include "bvh/wide/node.h"
#include "inst_impl.h"

int inst_wide_build(const bvh_box_tree *h, const accel_scene *mesh, inst_wide *out, accel_error *err)
{
    memset(out, 0, sizeof *out);
    out->root = WIDE_EMPTY;
    if (!h->node_count) return 0;
    const int block = mesh ? 8 : 1;
    bvh_wide_pool pool;
    int rc = bvh_wide_collapse_pool(h->nodes, h->node_count, INST_WIDE, block, &pool, err);
    if (rc) return rc;
    out->nodes = pool.nodes;
    out->node_count = pool.node_count;
    out->root = pool.root;
    out->block_count = pool.block_count;
    size_t n = pool.block_count ? pool.block_count : 1;
    if (mesh)
        out->blocks = aligned_alloc(64, n * sizeof *out->blocks);
    else
        out->ids = malloc(n * sizeof *out->ids);
    if (!out->blocks && !out->ids) {
        free(pool.leaves);
        inst_wide_free(out);
        return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory for a wide BVH's leaves");
    }
    for (uint32_t l = 0; l < pool.leaf_count; l++) {
        const bvh_wide_pool_leaf *leaf = &pool.leaves[l];
        const uint32_t *order = h->order + leaf->first_slot;
        if (!mesh) {
            memcpy(out->ids + leaf->first_block, order, leaf->count * sizeof *order);
            continue;
        }
        for (uint32_t k = 0; 8 * k < leaf->count; k++) {
            int count = leaf->count - 8 * k < 8 ? (int)(leaf->count - 8 * k) : 8;
            const float *tris[8];
            float sph[8][9] = {{0}}; /* a sphere's lane (plain scenes): centre, radius */
            for (int i = 0; i < count; i++) {
                uint32_t q = order[8 * k + (uint32_t)i];
                if (q < mesh->tri_count) {
                    tris[i] = mesh->tris + 9 * (size_t)q;
                } else {
                    memcpy(sph[i], mesh->spheres + 4 * (size_t)(q - mesh->tri_count), 4 * sizeof(float));
                    tris[i] = sph[i];
                }
            }
            accel_block8 *blk = &out->blocks[leaf->first_block + k];
            accel_block_fill(blk->v[0][0], blk->id, 8, tris, order + 8 * k, count);
        }
    }
    free(pool.leaves);
    return 0;
}

int inst_wide_refit(const bvh_box_tree *h, const accel_scene *mesh, inst_wide *w, accel_error *err)
{
    inst_wide_free(w);
    return inst_wide_build(h, mesh, w, err);
}

void inst_wide_free(inst_wide *w)
{
    free(w->nodes);
    free(w->ids);
    free(w->blocks);
    memset(w, 0, sizeof *w);
    w->root = WIDE_EMPTY;
}

size_t inst_wide_memory(const inst_wide *w)
{
    return (size_t)w->node_count * sizeof(wide_node8) +
           (size_t)w->block_count * (w->blocks ? sizeof(accel_block8) : sizeof(uint32_t));
}
