/*
 * refit.c - the wide tree from one animation frame to the next (the kind's
 * update, ../bvh_refit.c explains the refit): the SoA leaf blocks are
 * copied again from the new scene, each lane from the scene id the lane
 * holds (a padding lane repeats its leaf's last primitive and id, so it is
 * copied again the same way), and every box row is recomputed bottom-up
 * (nodes come before their children in collapse.c's depth-first
 * numbering, so one backward pass sees every child before its parent).
 * A wide node's octant child orders (perm) are recomputed from the new
 * boxes as the collapse computes them.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh/split_common.h"
#include "node.h"

int bvh_wide_mark_ids(const bvh_wide *w, uint8_t *mark, size_t total)
{
    for (uint32_t k = 0; k < w->block_count; k++) {
        float *v;
        uint32_t *id;
        wide_block_rows(w, k, &v, &id);
        for (int lane = 0; lane < w->block; lane++) {
            if (id[lane] >= total) return 0;
            mark[id[lane]] = 1;
        }
    }
    return 1;
}

typedef struct {
    bvh_wide *w;
    const accel_scene *s;
    box3 *block_box; /* per block: its lanes' primitive boxes (bvh_prim_box) */
    float delta;     /* bvh_box_delta */
} block_job;

/* accel_prim_bounds of scene id `id` from its copied slot (the same
 * operations on the same floats). */
static void copy_blocks(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    block_job *j = p;
    const int bs = j->w->block;
    for (size_t k = begin; k < end; k++) {
        float *v;
        uint32_t *id;
        wide_block_rows(j->w, (uint32_t)k, &v, &id);
        box3 box = box3_empty();
        for (int lane = 0; lane < bs; lane++) {
            float slot[BVH_SLOT_FLOATS];
            bvh_prim_slot(j->s, id[lane], slot);
            wide_put_lane(v, bs, lane, slot);
            box = box3_union(box, bvh_prim_box(j->s, id[lane], j->delta));
        }
        if (j->block_box) j->block_box[k] = box;
    }
}

/* The box of a leaf reference: its blocks' boxes (padding lanes repeat a
 * primitive already counted). */
static box3 leaf_box(const box3 *block_box, uint32_t ref)
{
    box3 box = box3_empty();
    uint32_t first = wide_leaf_first(ref), blocks = wide_leaf_blocks(ref);
    for (uint32_t k = first; k < first + blocks; k++) box = box3_union(box, block_box[k]);
    return box;
}

int bvh_wide_refit(bvh_wide *w, const accel_scene *s, int threads, int boxes, accel_error *err)
{
    /* The blocks' boxes come with the (parallel) copy. Allocated before
     * anything changes, so a failure leaves the tree as it was. */
    box3 *block_box = NULL;
    if (boxes && w->layout == WIDE_LAYOUT_MIXED) /* its path rebuilds instead (bvh.c) */
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: layout=mixed trees are rebuilt, not refit");
    if (boxes) {
        block_box = malloc((w->block_count ? w->block_count : 1) * sizeof *block_box);
        if (!block_box) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for the refit");
    }
    block_job job = {w, s, block_box, bvh_box_delta(s)};
    accel_parallel_for(w->block_count, 1024, threads, copy_blocks, &job);
    if (!boxes || w->root == WIDE_EMPTY) {
        free(block_box);
        return 0;
    }
    const int wd = w->width;
    const size_t floats = (wd == 8 ? sizeof(wide_node8) : sizeof(wide_node4)) / sizeof(float);
    float *pool = w->nodes;
    for (uint32_t i = w->node_count; i-- > 0;) {
        float *rows = pool + floats * i;
        const uint32_t *child = (const uint32_t *)(rows + 6 * wd);
        int used = 0;
        for (int c = 0; c < wd; c++) {
            uint32_t ref = child[c];
            if (ref == WIDE_EMPTY) continue; /* keeps its empty box */
            used = c + 1;
            box3 box;
            if (ref & WIDE_LEAF) {
                box = leaf_box(block_box, ref);
            } else {
                const float *cr = pool + floats * ref;
                box = box3_empty();
                for (int k = 0; k < wd; k++) { /* unused slots are +inf/-inf */
                    box3 cb = {{cr[0 * wd + k], cr[2 * wd + k], cr[4 * wd + k]},
                               {cr[1 * wd + k], cr[3 * wd + k], cr[5 * wd + k]}};
                    box = box3_union(box, cb);
                }
            }
            const float lo[3] = {box.min.x, box.min.y, box.min.z};
            const float hi[3] = {box.max.x, box.max.y, box.max.z};
            for (int axis = 0; axis < 3; axis++) {
                rows[(2 * axis) * wd + c] = lo[axis];
                rows[(2 * axis + 1) * wd + c] = hi[axis];
            }
        }
        /* The children's octant order follows their moved centres (it only
         * orders the traversal: stale, it is slower, never wrong). */
        bvh_wide_set_perm(rows, wd, used);
        if (w->any_shift >= 0) bvh_wide_set_any_perm(rows, wd, used);
    }
    free(block_box);
    return 0;
}
