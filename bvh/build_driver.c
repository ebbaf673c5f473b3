/*
 * build_driver.c - the build driver of the `bvh` kind: one reference per live
 * primitive, the chosen builder (build_binned.c, build_sah.c, build_mid.c,
 * build_sbvh.c, which may duplicate references),
 * then the final pass that lays the nodes out depth-first, copies the
 * primitives in leaf order and computes the statistics. Also the public
 * builder over boxes (bvh.h's bvh_build_boxes), the same binned build and
 * layout over caller-given boxes.
 */
#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "split_common.h"

/* ---- references, final layout, statistics --------------------------------- */

/* One reference per live primitive. A primitive with a non-finite
 * coordinate is left out: no finite ray can hit it (the reference never
 * reports one), and its box would poison every area and bin above it. */
static uint32_t make_refs(const accel_scene *s, bvh_ref *refs)
{
    uint32_t n = 0;
    float delta = bvh_box_delta(s);
    for (uint32_t i = 0; i < s->live_count; i++) {
        uint32_t prim = s->live[i];
        if (!bvh_prim_finite(s, prim)) continue;
        box3 b = bvh_prim_box(s, prim, delta);
        bvh_ref *r = &refs[n++];
        r->lo[0] = b.min.x, r->lo[1] = b.min.y, r->lo[2] = b.min.z;
        r->hi[0] = b.max.x, r->hi[1] = b.max.y, r->hi[2] = b.max.z;
        r->prim = prim;
        r->pad = 0;
    }
    return n;
}

double bvh_sah_cost(const bvh_node *nodes, uint32_t node_count, double ct, double ci)
{
    if (node_count == 0) return 0.0;
    double root = bvh_half_area(bvh_node_box(&nodes[0]));
    if (!(root > 0.0)) return NAN;
    double sum = 0.0;
    for (uint32_t i = 0; i < node_count; i++) {
        if (i == 1) continue; /* padding */
        double a = bvh_half_area(bvh_node_box(&nodes[i]));
        sum += nodes[i].count ? ci * nodes[i].count * a : ct * a;
    }
    return sum / root;
}

/*
 * Removes the gaps of the region layout in place. The regions put every
 * subtree's child pairs after its own pair, left subtree first (inside a
 * one-thread subtree, packed at its region's start in the same order), so
 * the pairs already lie in depth-first order; visiting them in that order and
 * moving each down to the next free slot never overwrites a pair not yet
 * moved (its new place is at or below its old one, and every pair still to
 * come lies above). Returns the node count; fills the depth and the leaves.
 */
static uint32_t compact_nodes(bvh_node *nodes, int *depth, uint64_t *leaves)
{
    struct {
        uint32_t node;
        int level;
    } stack[BVH_MAX_DEPTH + 1];
    int sp = 0;
    uint32_t next = 2;
    *depth = 0;
    *leaves = 0;
    stack[sp].node = 0, stack[sp].level = 1, sp++;
    while (sp > 0) {
        sp--;
        uint32_t i = stack[sp].node;
        int level = stack[sp].level;
        if (level > *depth) *depth = level;
        bvh_node *n = &nodes[i];
        if (n->count) {
            (*leaves)++;
            continue;
        }
        uint32_t old = n->left_first, pair = next;
        assert(pair <= old);
        next += 2;
        nodes[pair] = nodes[old];
        nodes[pair + 1] = nodes[old + 1];
        n->left_first = pair;
        assert(sp + 2 <= BVH_MAX_DEPTH + 1);
        stack[sp].node = pair + 1, stack[sp].level = level + 1, sp++;
        stack[sp].node = pair, stack[sp].level = level + 1, sp++;
    }
    return next == 2 ? 1 : next;
}

typedef struct {
    const accel_scene *scene; /* the primitives the references name */
    const uint32_t *scene_id; /* their id -> the scene's id; NULL: the same */
    const bvh_ref *refs;
    bvh *out;
} gather_job;

/* Primitive data in leaf order: the leaf loop then reads one contiguous run. */
static void gather_chunk(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    gather_job *j = p;
    const accel_scene *s = j->scene;
    for (size_t i = begin; i < end; i++) {
        uint32_t prim = j->refs[i].prim;
        j->out->prim_ids[i] = j->scene_id ? j->scene_id[prim] : prim;
        bvh_prim_slot(s, prim, j->out->prim_data + BVH_SLOT_FLOATS * i);
    }
}

void bvh_release(bvh *b)
{
    free(b->nodes_block ? b->nodes_block : (void *)b->nodes);
    b->nodes_block = NULL;
    free(b->prim_data);
    free(b->prim_ids);
    b->nodes = NULL;
    b->prim_data = NULL;
    b->prim_ids = NULL;
}

/* Builds over `scene`'s live primitives; scene_id maps their ids to the
 * caller's (NULL: they are the caller's ids). */
static int build_over(const accel_scene *scene, const uint32_t *scene_id, const bvh_build_opts *opts,
                      int threads, bvh *out, accel_build_stats *stats, accel_error *err)
{
    uint32_t live = scene->live_count;
    /* Node indices are uint32 and the temporary pool holds 2N nodes. */
    if (live > 0x7FFFFFFFu)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "bvh: %u primitives exceed the limit of 2^31-1 (uint32 node indices)",
                          live);
    /* The build's peak, known up front: N references (N(1 + split_budget)
     * with sbvh, plus its scratch copy and side bytes), a node pool of
     * twice that, and the final slots (36 + 4 bytes each). */
    double slots = live, scratch = 0.0;
    if (opts->builder == BVH_BUILD_SBVH) {
        slots = live + floor(opts->split_budget * live);
        scratch = slots * (sizeof(bvh_ref) + 1);
    }
    double peak = slots * (sizeof(bvh_ref) + 2 * sizeof(bvh_node) + BVH_SLOT_FLOATS * sizeof(float) +
                           sizeof(uint32_t)) + scratch;
    if (opts->max_mb > 0 && peak > opts->max_mb * 1048576.0)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "bvh: the build needs up to %.1f MiB for %u primitives (%.0f slots), over "
                          "max_mb = %.1f MiB (raise max_mb%s)",
                          peak / 1048576.0, live, slots, opts->max_mb,
                          opts->builder == BVH_BUILD_SBVH ? " or lower split_budget" : "");
    bvh_build_ctx ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.scene = scene;
    ctx.opts = *opts;
    ctx.threads = threads < 1 ? 1 : threads;
    ctx.refs = bvh_alloc_array(live, sizeof(bvh_ref));
    if (!ctx.refs) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for %u references", live);
    ctx.ref_count = make_refs(scene, ctx.refs);
    int rc = 0;
    if (ctx.ref_count > 0) {
        ctx.nodes = bvh_alloc_nodes(2 * (size_t)ctx.ref_count);
        if (!ctx.nodes) {
            free(ctx.refs);
            return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for %u nodes",
                              2 * ctx.ref_count);
        }
        switch (opts->builder) {
        case BVH_BUILD_BINNED: rc = bvh_build_binned(&ctx, err); break;
        case BVH_BUILD_SAH: rc = bvh_build_sah(&ctx, err); break;
        case BVH_BUILD_MID: rc = bvh_build_mid(&ctx, err); break;
        case BVH_BUILD_MEDIAN: rc = bvh_build_median(&ctx, err); break;
        case BVH_BUILD_SBVH: rc = bvh_build_sbvh(&ctx, err); break;
        default: rc = accel_fail(err, ACCEL_ERR_INTERNAL, "bvh: unknown builder %d", opts->builder);
        }
    }
    if (rc == 0 && ctx.ref_count > 0) {
        out->node_count = compact_nodes(ctx.nodes, &out->depth, &stats->leaves);
        if (out->node_count > 1) { /* padding node: an empty box, never referenced */
            memset(&ctx.nodes[1], 0, sizeof(bvh_node));
            bvh_node_set_box(&ctx.nodes[1], box3_empty());
        }
        /* Give back the unused tail of the 2N pool (realloc keeps the
         * contents; should it lose the alignment, copy to an aligned block). */
        out->nodes = realloc(ctx.nodes, (size_t)out->node_count * sizeof(bvh_node));
        if (!out->nodes) {
            out->nodes = ctx.nodes; /* shrinking failed: keep the larger block */
        } else if ((uintptr_t)out->nodes % BVH_NODE_ALIGN != 0) {
            bvh_node *aligned = bvh_alloc_nodes(out->node_count);
            if (aligned) memcpy(aligned, out->nodes, (size_t)out->node_count * sizeof(bvh_node));
            free(out->nodes);
            out->nodes = aligned;
        }
        ctx.nodes = NULL;
        out->prim_data = bvh_alloc_array(ctx.ref_count, BVH_SLOT_FLOATS * sizeof(float));
        out->prim_ids = bvh_alloc_array(ctx.ref_count, sizeof(uint32_t));
        if (!out->nodes || !out->prim_data || !out->prim_ids) {
            rc = accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for the final pools");
        } else {
            out->prim_count = ctx.ref_count;
            gather_job job = {scene, scene_id, ctx.refs, out};
            accel_parallel_for(ctx.ref_count, 16384, ctx.threads, gather_chunk, &job);
        }
    }
    free(ctx.nodes);
    free(ctx.refs);
    if (rc) {
        bvh_release(out);
        return rc;
    }
    stats->nodes = out->node_count;
    stats->refs = out->prim_count;
    stats->depth = out->depth;
    stats->sah_cost = bvh_sah_cost(out->nodes, out->node_count, opts->ct, opts->ci);
    return 0;
}

int bvh_build_run(const accel_scene *scene, const bvh_build_opts *opts, int threads, bvh *out,
                  accel_build_stats *stats, accel_error *err)
{
    memset(out, 0, sizeof *out);
    /* The tree keeps its own copy of the primitives, in leaf order, so the
     * builders need no copy of their own. With reorder=1 they work on the
     * Morton-ordered primitive store (accel.h), whose order then decides
     * ties among equal costs and equal centroids, and the gather pass maps
     * its local ids back; the store is freed here. With reorder=0 (bvh's
     * default) they read the scene's live primitives in place: the same
     * tree as the store in scene order would give, without copying every
     * primitive and faulting in its pages (8-wide build time about -4% on
     * armadillo, -10% to -20% on a 1M-triangle soup whose Morton sort
     * reads the scene at random; measured 2026-12-03, bvh/README). */
    int rc;
    if (opts->reorder) {
        accel_prim_store store;
        rc = accel_prim_store_build(scene, 1, &store, err);
        if (rc) return rc;
        rc = build_over(&store.prims, store.scene_id, opts, threads, out, stats, err);
        accel_prim_store_free(&store);
    } else {
        rc = build_over(scene, NULL, opts, threads, out, stats, err);
    }
    if (rc) return rc;
    out->tri_count = scene->tri_count;
    out->has_spheres = scene->sphere_count > 0;
    out->scene_prims = scene->tri_count + scene->sphere_count;
    return 0;
}

/* pairs=split (shift 1): the nodes moved into a fresh pool that starts 32
 * bytes past a 64-byte boundary, so that every sibling pair (nodes 2k and
 * 2k+1, 64 bytes together) straddles two cache lines; pairs=fresh (shift 0):
 * the same move without the shift, so that the two differ in nothing but
 * the 32 bytes (issue 38: the control of a fresh allocation, not of the
 * builder's). The tree and its answers are unchanged (exp_sah's layout
 * verdict). */
int bvh_split_pairs(bvh *b, int shift, accel_error *err)
{
    if (b->node_count == 0 || b->nodes_block) return 0;
    bvh_node *block = bvh_alloc_nodes((size_t)b->node_count + 2);
    if (!block) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for pairs=%s",
                                  shift ? "split" : "fresh");
    memcpy(block + (shift ? 1 : 0), b->nodes, (size_t)b->node_count * sizeof(bvh_node));
    free(b->nodes);
    b->nodes = block + (shift ? 1 : 0);
    b->nodes_block = block;
    return 0;
}

/* ---- the public builder over boxes (bvh.h) -------------------------------------- */

int bvh_build_boxes(const float *boxes, uint32_t n, int max_leaf, int threads, bvh_box_tree *out,
                    accel_error *err)
{
    memset(out, 0, sizeof *out);
    if (max_leaf < 1 || max_leaf > 256)
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh_build_boxes: max_leaf %d outside 1..256", max_leaf);
    if (n > 0x7FFFFFFFu)
        return accel_fail(err, ACCEL_ERR_RANGE, "bvh_build_boxes: %u boxes exceed 2^31-1", n);
    for (uint32_t i = 0; i < n; i++) {
        const float *b = boxes + 6 * (size_t)i;
        for (int a = 0; a < 3; a++)
            if (!(isfinite(b[a]) && isfinite(b[3 + a]) && b[a] <= b[3 + a]))
                return accel_fail(err, ACCEL_ERR_SPEC, "bvh_build_boxes: box %u is not finite or inverted", i);
    }
    out->count = n;
    if (n == 0) return 0;
    /* The default builder's options (binned SAH, 16 bins, 3 axes, ct = ci = 1). */
    bvh_build_ctx ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.opts.builder = BVH_BUILD_BINNED;
    ctx.opts.bins = 16, ctx.opts.axes = 3, ctx.opts.max_leaf = max_leaf;
    ctx.opts.ct = 1.0f, ctx.opts.ci = 1.0f;
    ctx.threads = threads < 1 ? 1 : threads;
    ctx.refs = bvh_alloc_array(n, sizeof(bvh_ref));
    ctx.nodes = bvh_alloc_nodes(2 * (size_t)n);
    out->order = bvh_alloc_array(n, sizeof(uint32_t));
    int rc = 0;
    if (!ctx.refs || !ctx.nodes || !out->order) {
        rc = accel_fail(err, ACCEL_ERR_NOMEM, "bvh_build_boxes: out of memory for %u boxes", n);
    } else {
        for (uint32_t i = 0; i < n; i++) {
            const float *b = boxes + 6 * (size_t)i;
            bvh_ref *r = &ctx.refs[i];
            memcpy(r->lo, b, 3 * sizeof(float));
            memcpy(r->hi, b + 3, 3 * sizeof(float));
            r->prim = i, r->pad = 0;
        }
        ctx.ref_count = n;
        rc = bvh_build_binned(&ctx, err);
    }
    if (rc == 0) {
        uint64_t leaves;
        out->node_count = compact_nodes(ctx.nodes, &out->depth, &leaves);
        if (out->node_count > 1) { /* padding node: an empty box, never referenced */
            memset(&ctx.nodes[1], 0, sizeof(bvh_node));
            bvh_node_set_box(&ctx.nodes[1], box3_empty());
        }
        for (uint32_t i = 0; i < n; i++) out->order[i] = ctx.refs[i].prim;
        out->nodes = ctx.nodes; /* the 2n pool, of which node_count are used */
        ctx.nodes = NULL;
    } else {
        free(out->order);
        out->order = NULL;
        out->count = 0;
    }
    free(ctx.nodes);
    free(ctx.refs);
    return rc;
}

void bvh_box_tree_free(bvh_box_tree *t)
{
    free(t->nodes);
    free(t->order);
    memset(t, 0, sizeof *t);
}
