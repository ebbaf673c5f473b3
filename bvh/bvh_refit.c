/*
 * bvh_refit.c - the `bvh` kind from one animation frame to the next
 * (accel_kind.update): the tree's topology is kept, the primitives it
 * copied at build are copied again from the new scene, and every box is
 * recomputed bottom-up (refitting; Wald, Boulos and Shirley, "Ray Tracing
 * Deformable Scenes Using Dynamic Bounding Volume Hierarchies", ACM TOG
 * 26(1), 2007).
 *
 * What the tree copies at build, and so what a refit copies again:
 *   - binary tree (width=2): the 9-float slots in leaf order (prim_data),
 *     each from the scene id prim_ids[slot] names;
 *   - wide tree (width=4|8; the binary pools are freed after the collapse):
 *     the SoA leaf blocks, each lane from the scene id the lane holds (a
 *     padding lane repeats its leaf's last primitive and id, so it is
 *     copied again the same way).
 * The boxes are then what the build computes: a leaf's box is the union of
 * bvh_prim_box of its primitives (the references' boxes of bvh_build.c's
 * make_refs, grown as build_common.h explains), an interior box the union of its
 * children's. A spatial-split tree (build=sbvh) clipped its references to
 * split planes; refit boxes hold whole primitives, so they are larger
 * (still conservative, the tree only gets slower).
 *
 * A wide node's octant child orders (perm) are recomputed from the new
 * boxes as the collapse computes them.
 *
 * Nodes come before their children in both layouts (bvh_build.c's
 * compact_nodes, wide_build.c's depth-first numbering), so one backward
 * pass over the node pool sees every child before its parent.
 *
 * The new scene must hold the same primitive counts; a scene whose set of
 * traced primitives changed (a triangle that became degenerate or stopped
 * being degenerate, a non-finite coordinate) cannot be refit with the same
 * topology and is rebuilt by the caller (bvh.c).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "build_common.h"
#include "bvh.h"
#include "wide_node.h"

/* Marks the scene ids a tree holds (mark[id] = 1); 0 when one is not an id
 * of a scene of `total` primitives (a tree loaded from a file does not know
 * its scene's sphere count). */
static int mark_ids(const bvh *b, uint8_t *mark, size_t total)
{
    if (!b->wide) {
        for (uint32_t i = 0; i < b->prim_count; i++) {
            if (b->prim_ids[i] >= total) return 0;
            mark[b->prim_ids[i]] = 1;
        }
        return 1;
    }
    const bvh_wide *w = b->wide;
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

int bvh_refit_compatible(const bvh *b, const accel_scene *s, accel_error *err)
{
    if (s->tri_count != b->tri_count || (s->sphere_count > 0) != b->has_spheres ||
        (b->scene_prims && s->tri_count + s->sphere_count != b->scene_prims))
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "bvh: update from %u triangles and %u spheres to %u and %u (refit keeps the "
                          "topology: same primitive counts and ids)",
                          b->tri_count, b->scene_prims ? b->scene_prims - b->tri_count : 0, s->tri_count,
                          s->sphere_count);
    size_t total = (size_t)s->tri_count + s->sphere_count;
    uint8_t *mark = calloc(total ? total : 1, 1);
    if (!mark) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory");
    if (!mark_ids(b, mark, total)) {
        free(mark);
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "bvh: the tree holds primitive ids beyond the new scene's %zu (refit keeps "
                          "the topology: same primitive counts and ids)",
                          total);
    }
    int same = 1;
    for (uint32_t i = 0; same && i < s->live_count; i++) {
        uint32_t id = s->live[i];
        if (!bvh_prim_finite(s, id)) continue; /* left out by the build as well */
        if (mark[id] != 1) same = 0;       /* not in the tree */
        mark[id] = 2;
    }
    for (size_t i = 0; same && i < total; i++)
        if (mark[i] == 1) same = 0; /* in the tree, no longer live and finite */
    free(mark);
    return same ? 0 : -1;
}

/* ---- binary tree ------------------------------------------------------------ */

typedef struct {
    bvh *b;
    const accel_scene *s;
} copy_job;

static void copy_slots(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    copy_job *j = p;
    for (size_t i = begin; i < end; i++)
        bvh_prim_slot(j->s, j->b->prim_ids[i], j->b->prim_data + BVH_SLOT_FLOATS * i);
}

static void refit_binary(bvh *b, const accel_scene *s, int threads, int boxes)
{
    copy_job job = {b, s};
    accel_parallel_for(b->prim_count, 16384, threads, copy_slots, &job);
    if (!boxes) return;
    float delta = bvh_box_delta(s);
    for (uint32_t i = b->node_count; i-- > 0;) {
        if (i == 1) continue; /* padding */
        bvh_node *n = &b->nodes[i];
        box3 box = box3_empty();
        if (n->count) {
            for (uint32_t k = 0; k < n->count; k++)
                box = box3_union(box, bvh_prim_box(s, b->prim_ids[n->left_first + k], delta));
        } else {
            box = box3_union(bvh_node_box(&b->nodes[n->left_first]),
                             bvh_node_box(&b->nodes[n->left_first + 1]));
        }
        bvh_node_set_box(n, box);
    }
}

/* ---- wide tree ---------------------------------------------------------------- */

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

static int refit_wide(bvh_wide *w, const accel_scene *s, int threads, int boxes, accel_error *err)
{
    /* The blocks' boxes come with the (parallel) copy. Allocated before
     * anything changes, so a failure leaves the tree as it was. */
    box3 *block_box = NULL;
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
    }
    free(block_box);
    return 0;
}

int bvh_refit_run(bvh *b, const accel_scene *s, int threads, int boxes, accel_error *err)
{
    if (threads < 1) threads = 1;
    if (b->wide) return refit_wide(b->wide, s, threads, boxes, err);
    refit_binary(b, s, threads, boxes);
    return 0;
}
