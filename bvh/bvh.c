/*
 * bvh.c - the "bvh" accelerator kind: parameters, build entry, batch entry
 * points and memory accounting.
 *
 * The kind's table is the only thing the rest of the project sees
 * (registry.c); the build driver is build_driver.c, builders live in
 * build_*.c, traversal in bvh_single.c and bvh_packet.c, saving and
 * loading in bvh_io.c.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/isa.h"
#include "split_common.h"
#include "bvh.h"
#include "wide/wide.h"
#include "core/coherence.h"

/* Named once: the table's choices and a message that names the one chosen. */
#define BVH_BUILD_CHOICES "binned|sah|mid|median|sbvh"

static const accel_param_def bvh_params[] = {
    {.key = "build", .type = ACCEL_PARAM_ENUM, .def = "binned",
     .choices = BVH_BUILD_CHOICES,
     .help = "builder: binned SAH (Wald 2007), exact SAH by full sweep, spatial middle, object "
             "median, binned SAH with spatial splits (Stich et al. 2009)",
     .offset = offsetof(bvh_spec, build)},
    {.key = "bins", .type = ACCEL_PARAM_INT, .def = "16", .min = 2, .max = 256,
     .help = "build=binned|sbvh: bins per axis (count; sbvh: for object and spatial splits)",
     .offset = offsetof(bvh_spec, bins)},
    {.key = "axes", .type = ACCEL_PARAM_ENUM, .def = "3", .choices = "1|3",
     .help = "build=binned: axes binned per node, 1 = largest centroid extent only, 3 = all",
     .offset = offsetof(bvh_spec, axes)},
    {.key = "split_budget", .type = ACCEL_PARAM_FLOAT, .def = "0.3", .min = 0, .max = 4,
     .help = "build=sbvh: most duplicated references, as a fraction of the primitives (0.3 = "
             "+30%)",
     .offset = offsetof(bvh_spec, split_budget)},
    {.key = "alpha", .type = ACCEL_PARAM_FLOAT, .def = "1e-5", .min = 0, .max = 1,
     .help = "build=sbvh: try spatial splits where the object split's children overlap by more "
             "than alpha times the root's area (0: everywhere)",
     .offset = offsetof(bvh_spec, alpha)},
    {.key = "max_mb", .type = ACCEL_PARAM_FLOAT, .def = "4096", .min = 1.0, .max = 1048576.0,
     .help = "memory limit of the build (references, node pool, scratch, final pools), MiB; a "
             "larger tree is refused",
     .offset = offsetof(bvh_spec, max_mb)},
    {.key = "leaf", .type = ACCEL_PARAM_INT, .def = "8", .min = 1, .max = 256,
     .help = "largest leaf (primitives); smaller leaves when the SAH rule says so",
     .offset = offsetof(bvh_spec, leaf)},
    {.key = "ct", .type = ACCEL_PARAM_FLOAT, .def = "1", .min = 0, .max = 1e6,
     .help = "SAH cost of a node visit (same time unit as ci)",
     .offset = offsetof(bvh_spec, ct)},
    {.key = "ci", .type = ACCEL_PARAM_FLOAT, .def = "1", .min = 1e-6, .max = 1e6,
     .help = "SAH cost of a primitive test (same time unit as ct)",
     .offset = offsetof(bvh_spec, ci)},
    {.key = "term", .type = ACCEL_PARAM_ENUM, .def = "sah", .choices = "sah|none",
     .help = "leaf rule: sah (a leaf once splitting does not pay, at most `leaf` primitives) or "
             "none (split every node over `leaf`, as the lecture's lab does)",
     .offset = offsetof(bvh_spec, term)},
    {.key = "traverse", .type = ACCEL_PARAM_ENUM, .def = "single", .choices = "single|packet|stream",
     .help = "single rays, packets of 64 consecutive rays (8x8 tiles), or ray streams "
             "(width=4|8: the tree walked once for a stream of rays in any order, each node "
             "tested by every ray still in it; the single rays' answers, bit for bit)",
     .offset = offsetof(bvh_spec, traverse)},
    {.key = "frustum", .type = ACCEL_PARAM_BOOL, .def = "0", .min = 0, .max = 1,
     .help = "traverse=packet: interval-arithmetic early-out per node (0/1)",
     .offset = offsetof(bvh_spec, frustum)},
    {.key = "width", .type = ACCEL_PARAM_ENUM, .def = "2", .choices = "2|4|8",
     .help = "children per node: 2 = the lecture's binary tree; 4, 8 = collapsed SIMD nodes "
             "(wide/collapse.c)",
     .offset = offsetof(bvh_spec, width)},
    {.key = "block", .type = ACCEL_PARAM_ENUM, .def = "auto", .choices = "auto|4|8",
     .help = "width=4|8: primitives per SIMD leaf block (auto: 8, or 4 when the scene has "
             "spheres)",
     .offset = offsetof(bvh_spec, block)},
    {.key = "order", .type = ACCEL_PARAM_ENUM, .def = "octant", .choices = "dist|octant|branchy",
     .help = "width=4|8: hit children sorted by entry distance per ray, or in the node's octant "
             "order pushed by a compress-store (octant) or by one branch per child (branchy: "
             "single rays)",
     .offset = offsetof(bvh_spec, order)},
    {.key = "collapse", .type = ACCEL_PARAM_ENUM, .def = "dp", .choices = "greedy|dp",
     .help = "width=4|8: binary tree to wide nodes by opening the largest child first, every "
             "subtree of one block a leaf (greedy), or the forests of least SAH cost by dynamic "
             "programming (dp; Ylitie et al. 2017)",
     .offset = offsetof(bvh_spec, collapse)},
    {.key = "leaf_cost", .type = ACCEL_PARAM_FLOAT, .def = "1.5", .min = 0.01, .max = 100,
     .help = "collapse=dp: cost of one leaf block test, in wide node visits",
     .offset = offsetof(bvh_spec, leaf_cost)},
    {.key = "leaf_blocks", .type = ACCEL_PARAM_INT, .def = "2", .min = 1, .max = 64,
     .help = "collapse=dp: most blocks in a leaf the collapse makes (larger binary leaves stay "
             "whole)",
     .offset = offsetof(bvh_spec, leaf_blocks)},
    {.key = "leaf_below", .type = ACCEL_PARAM_INT, .def = "0", .min = 0, .max = 256,
     .help = "width=4|8: the binary build makes every subtree of at most this many primitives a "
             "leaf, unsplit (0: the block size; smaller lets collapse=dp choose smaller leaves, "
             "for more build time)",
     .offset = offsetof(bvh_spec, leaf_below)},
    {.key = "hybrid", .type = ACCEL_PARAM_INT, .def = "16", .min = 0, .max = 64,
     .help = "width=4|8, traverse=packet: a subtree whose hitting rays span at most this many of "
             "the packet's 64 (first to last) is traced ray by ray from there (0: never); "
             "traverse=stream: a subtree entered by at most this many of the stream's rays",
     .offset = offsetof(bvh_spec, hybrid)},
    {.key = "stream", .type = ACCEL_PARAM_INT, .def = "1024", .min = 8, .max = 8192,
     .help = "traverse=stream: rays per stream (count; a batch's rays are grouped by direction "
             "octant, then cut into streams of this many)",
     .offset = offsetof(bvh_spec, stream)},
    {.key = "quant", .type = ACCEL_PARAM_BOOL, .def = "0", .min = 0, .max = 1,
     .help = "width=8, single rays: child boxes as 8-bit steps from the node's corner, rounded "
             "outward (128-byte nodes instead of 256; the octant order pushed by branches, as "
             "order=branchy; update rebuilds) (0/1)",
     .offset = offsetof(bvh_spec, quant)},
    {.key = "layout", .type = ACCEL_PARAM_ENUM, .def = "dfs", .choices = "dfs|bfs|mixed",
     .help = "width=4|8: nodes and leaf blocks in memory: two pools numbered depth-first (dfs), "
             "or level by level (bfs), or (width=8, single rays; update rebuilds) one pool, each "
             "node followed by its leaf children's blocks, then its node children depth-first "
             "(mixed); the same hits and counts",
     .offset = offsetof(bvh_spec, layout)},
    {.key = "any_order", .type = ACCEL_PARAM_ENUM, .def = "near",
     .choices = "near|octant|area|leaf",
     .help = "width=8, single rays, order=octant: the child order of any-hit queries: the "
             "closest-hit one (near), the ray's octant order for every count (octant), the "
             "largest box first (area), or leaf children first, most blocks first (leaf)",
     .offset = offsetof(bvh_spec, any_order)},
    {.key = "isa", .type = ACCEL_PARAM_ENUM, .def = "auto", .choices = ACCEL_ISA_CHOICES,
     .help = "width=4|8: the kernels' instruction set: auto (GRIDBVH_ISA if set, else AVX-512 "
             "where the CPU has it, else AVX2), avx2, or avx512 (an error where the CPU lacks it); "
             "the same hits, bit for bit",
     .offset = offsetof(bvh_spec, isa)},
    {.key = "first", .type = ACCEL_PARAM_ENUM, .def = "near", .choices = "near|left",
     .help = "width=2, single rays: of two hit children visit the nearer first (the lecture's "
             "\"better\"), or always the left one (a control for that claim)",
     .offset = offsetof(bvh_spec, first)},
    {.key = "pairs", .type = ACCEL_PARAM_ENUM, .def = "line", .choices = "line|split|fresh",
     .help = "width=2: sibling pairs in one 64-byte cache line (the lecture's layout); split: "
             "the nodes copied to a fresh pool shifted by 32 bytes, so that every pair "
             "straddles two lines (a control for that claim); fresh: the same copy unshifted "
             "(split's exact control: only the 32 bytes differ)",
     .offset = offsetof(bvh_spec, pairs)},
};
#define BVH_PARAM_COUNT (sizeof bvh_params / sizeof bvh_params[0])

typedef struct {
    int width, block, order; /* width 2: the binary tree */
    int first_left, split_pairs; /* width 2: first=left, pairs (0 line, 1 split, 2 fresh) */
    int quant;                   /* width 8: quantized nodes */
    int hybrid;                  /* wide packets: hand-over span (wide/packet.h); streams: count */
    int stream;                  /* traverse=stream: rays per stream (wide/stream.h) */
    bvh_wide_collapse collapse;  /* wide: greedy or dp */
    int leaf_below;              /* wide: the binary build's leaf_below (0: block) */
    int isa;                     /* wide: ACCEL_ISA_AVX2 or _AVX512, resolved (core/isa.h) */
} wide_opts;

static int options_from_params(const accel_params *p, bvh_build_opts *o, int *traverse,
                               int *frustum, wide_opts *wo, accel_error *err)
{
#define GIVEN(field) ACCEL_GIVEN(p, bvh_spec, field)
    const bvh_spec *s = ACCEL_SPEC(p, bvh_spec);
    memset(o, 0, sizeof *o);
    o->builder = (bvh_builder)s->build;
    o->bins = s->bins;
    o->axes = s->axes;
    o->max_leaf = s->leaf;
    o->ct = (float)s->ct;
    o->ci = (float)s->ci;
    o->term_none = s->term == 1;
    /* The common reorder defaults to 1 (a Morton-ordered store) for every
     * kind but this one: the tree copies the primitives in leaf order, a
     * spatial order of its own, so a Morton copy would only cost build time
     * (bvh_build_run). reorder=1 given explicitly still builds over it. */
    o->reorder = p->reorder_given ? p->reorder : 0;
    o->split_budget = s->split_budget;
    o->alpha = s->alpha;
    o->max_mb = s->max_mb;
    *traverse = s->traverse;
    *frustum = s->frustum;
    /* Options that would be silently ignored are errors. */
    int binned = o->builder == BVH_BUILD_BINNED, sbvh = o->builder == BVH_BUILD_SBVH;
    char build[ACCEL_PARAM_TEXT];
    if ((!binned && GIVEN(axes)) || (!binned && !sbvh && GIVEN(bins)))
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "bvh: bins applies to build=binned|sbvh, axes to build=binned (got build=%s)",
                          accel_param_choice(BVH_BUILD_CHOICES, s->build, build, sizeof build));
    if (!sbvh && (GIVEN(split_budget) || GIVEN(alpha)))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: split_budget and alpha apply to build=sbvh only");
    if (*frustum && *traverse != BVH_TRAVERSE_PACKET)
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: frustum=1 needs traverse=packet");
    wo->width = s->width;
    wo->block = s->block; /* 0 for auto, set by the build */
    wo->order = s->order;
    if (wo->width == 2 && (GIVEN(block) || GIVEN(order)))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: block and order apply to width=4|8 only");
    wo->first_left = s->first == 1;
    wo->split_pairs = s->pairs;
    if (wo->width > 2 && (GIVEN(first) || GIVEN(pairs)))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: first and pairs apply to width=2 only");
    if (GIVEN(first) && *traverse != BVH_TRAVERSE_SINGLE)
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: first applies to traverse=single only");
    wo->quant = s->quant;
    if (wo->quant && (wo->width != 8 || *traverse != BVH_TRAVERSE_SINGLE || GIVEN(order)))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: quant=1 applies to width=8 with single rays and "
                                               "its own order (no order=, no traverse=packet)");
    wo->collapse.dp = s->collapse == 1;
    wo->collapse.leaf_cost = s->leaf_cost;
    wo->collapse.leaf_blocks = s->leaf_blocks;
    wo->leaf_below = s->leaf_below;
    wo->collapse.layout = s->layout;
    wo->collapse.any_order = s->any_order;
    if (wo->width == 2 && (GIVEN(layout) || GIVEN(any_order)))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: layout and any_order apply to width=4|8");
    if (wo->collapse.layout == WIDE_LAYOUT_MIXED &&
        (wo->width != 8 || *traverse != BVH_TRAVERSE_SINGLE || wo->quant || wo->order == WIDE_ORDER_BRANCHY))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: layout=mixed applies to width=8 with single rays "
                                               "(no traverse=packet|stream, quant=1 or order=branchy)");
    if (wo->collapse.any_order != WIDE_ANY_NEAR &&
        (wo->width != 8 || *traverse != BVH_TRAVERSE_SINGLE || wo->quant || wo->order != WIDE_ORDER_OCTANT ||
         wo->collapse.layout == WIDE_LAYOUT_MIXED))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: any_order applies to width=8 with single rays and "
                                               "order=octant (no quant=1, no layout=mixed)");
    if ((wo->width == 2 && (GIVEN(collapse) || GIVEN(leaf_below))) ||
        (!wo->collapse.dp && (GIVEN(leaf_cost) || GIVEN(leaf_blocks))))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: collapse and leaf_below apply to width=4|8, "
                                               "leaf_cost and leaf_blocks to collapse=dp");
    wo->hybrid = s->hybrid;
    if (GIVEN(hybrid) && (wo->width == 2 || *traverse == BVH_TRAVERSE_SINGLE))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: hybrid applies to width=4|8 with traverse=packet|stream");
    wo->stream = s->stream;
    if (*traverse == BVH_TRAVERSE_STREAM && wo->width == 2)
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: traverse=stream applies to width=4|8");
    if (GIVEN(stream) && *traverse != BVH_TRAVERSE_STREAM)
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: stream applies to traverse=stream");
    if (*traverse == BVH_TRAVERSE_STREAM && GIVEN(order) && wo->order != WIDE_ORDER_OCTANT)
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: traverse=stream walks in the octant order (order=octant)");
    if (wo->order == WIDE_ORDER_BRANCHY && *traverse != BVH_TRAVERSE_SINGLE)
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: order=branchy applies to traverse=single only");
    if (wo->width > 2 && *frustum)
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: frustum applies to width=2 (wide packets always use it)");
    if (wo->width == 2 && GIVEN(isa))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: isa applies to width=4|8 (the binary kernels have one)");
    if (wo->width > 2 && accel_isa_resolve(s->isa, &wo->isa, err)) return ACCEL_ERR_SPEC;
    return 0;
#undef GIVEN
}

/* What update needs to build the tree again (refit=0, or a scene whose set
 * of traced primitives changed). */
struct bvh_rebuild {
    bvh_build_opts opts;
    int traverse, frustum, threads;
    wide_opts wo;
};

/* ---- the two trees' code paths (bvh_node.h's bvh_path) ------------------- */

static size_t binary_memory(const bvh *b)
{
    return (size_t)b->node_count * sizeof(bvh_node) +
           (size_t)b->prim_count * (BVH_SLOT_FLOATS * sizeof(float) + sizeof(uint32_t));
}

const bvh_path bvh_path_single = {bvh_trace_intersect, bvh_trace_occluded, bvh_walk_binary,
                                  bvh_mark_ids_binary, bvh_refit_binary,   binary_memory,
                                  bvh_release,         1,                  1};
const bvh_path bvh_path_packet = {bvh_packet_intersect, bvh_packet_occluded, bvh_walk_binary,
                                  bvh_mark_ids_binary,  bvh_refit_binary,    binary_memory,
                                  bvh_release,          1,                   1};

const bvh_path *bvh_binary_path(int traverse)
{
    return traverse == BVH_TRAVERSE_PACKET ? &bvh_path_packet : &bvh_path_single;
}

/* The wide path: the tree in b->wide; the binary pools were freed by the
 * collapse. The kernels take the scene flags the kind keeps. */
static void wide_hit_rays(const void *a, const accel_ray *rays, accel_hit *hits, size_t count,
                          accel_counters *c)
{
    const bvh *b = a;
    bvh_wide_intersect(b->wide, rays, hits, count, c, b->naive, b->has_spheres);
}

static void wide_occ_rays(const void *a, const accel_ray *rays, uint8_t *occ, size_t count,
                          accel_counters *c)
{
    const bvh *b = a;
    bvh_wide_occluded(b->wide, rays, occ, count, c, b->naive, b->has_spheres);
}

static void wide_hit_single(const void *a, const accel_ray *rays, accel_hit *hits, size_t count,
                            accel_counters *c)
{
    const bvh *b = a;
    bvh_wide_single_intersect(b->wide, rays, hits, count, c, b->naive, b->has_spheres);
}

static void wide_occ_single(const void *a, const accel_ray *rays, uint8_t *occ, size_t count,
                            accel_counters *c)
{
    const bvh *b = a;
    bvh_wide_single_occluded(b->wide, rays, occ, count, c, b->naive, b->has_spheres);
}

/* Wide packets take their rays through the packet layer (core/coherence.h):
 * packets in any ray order, incoherent groups ray by ray. */
static void wide_intersect(const bvh *b, const accel_ray *rays, accel_hit *hits, size_t count,
                           accel_counters *c)
{
    if (b->wide->packets)
        accel_coherent_intersect(b, rays, hits, count, c, wide_hit_rays, wide_hit_single);
    else
        wide_hit_rays(b, rays, hits, count, c);
}

static void wide_occluded(const bvh *b, const accel_ray *rays, uint8_t *occ, size_t count,
                          accel_counters *c)
{
    if (b->wide->packets)
        accel_coherent_occluded(b, rays, occ, count, c, wide_occ_rays, wide_occ_single);
    else
        wide_occ_rays(b, rays, occ, count, c);
}

static void wide_walk(const bvh *b, const accel_ray_prep *p, float pad, accel_walk_visit visit,
                      void *ctx, uint32_t *steps)
{
    bvh_wide_walk(b->wide, p, pad, visit, ctx, steps);
}

static int wide_mark_ids(const bvh *b, uint8_t *mark, size_t total)
{
    return bvh_wide_mark_ids(b->wide, mark, total);
}

static int wide_refit(bvh *b, const accel_scene *s, int threads, int boxes, accel_error *err)
{
    return bvh_wide_refit(b->wide, s, threads, boxes, err);
}

static size_t wide_memory(const bvh *b) { return bvh_wide_memory(b->wide); }

static void wide_release(bvh *b)
{
    bvh_wide_free(b->wide);
    b->wide = NULL;
    bvh_release(b); /* the binary pools, freed by the collapse already */
}

const bvh_path bvh_path_wide = {wide_intersect, wide_occluded, wide_walk,    wide_mark_ids,
                                wide_refit,     wide_memory,   wide_release, 1,
                                0};
/* quantized nodes keep no float boxes to refit, and layout=mixed's nodes
 * are not numbered for the refit's backward pass: their path rebuilds */
static const bvh_path bvh_path_wide_quant = {wide_intersect, wide_occluded, wide_walk,    wide_mark_ids,
                                             wide_refit,     wide_memory,   wide_release, 0,
                                             0};

/* ---- the kind ------------------------------------------------------------- */

static size_t bvh_memory(const void *a)
{
    const bvh *b = a;
    return sizeof *b + b->path->memory(b);
}

static void bvh_destroy(void *a)
{
    if (!a) return;
    bvh *b = a;
    free(b->rebuild);
    b->path->release(b);
    free(b);
}

/* The tree over `scene` with the given options: the binary build, then
 * pairs=split or the collapse to width 4|8 (block 0: auto, 4 with spheres,
 * else 8). Used by the build and by update's rebuild. On failure nothing
 * is left allocated in out. */
static int build_tree(const accel_scene *scene, const bvh_build_opts *opts, const wide_opts *wo,
                      int traverse, int threads, bvh *out, accel_build_stats *stats, accel_error *err)
{
    const int block = wo->block ? wo->block : scene->sphere_count ? 4 : 8;
    bvh_build_opts o = *opts;
    /* The greedy collapse makes every subtree of at most one block one
     * leaf, so the binary build does not split those (the same wide tree,
     * about a fifth less build time on bunny). collapse=dp keeps every
     * binary leaf a leaf: leaf_below < block lets it choose smaller ones. */
    if (wo->width > 2) o.leaf_below = wo->leaf_below ? wo->leaf_below : block;
    bvh_wide_collapse cc = wo->collapse;
    cc.max_mb = o.max_mb;
    int rc = bvh_build_run(scene, &o, threads, out, stats, err);
    out->path = bvh_binary_path(traverse);
    if (rc == 0 && wo->width == 2 && wo->split_pairs) rc = bvh_split_pairs(out, wo->split_pairs == 1, err);
    if (rc == 0 && wo->width > 2) {
        rc = bvh_wide_build(out, &out->wide, wo->width, block, wo->order, wo->quant, &cc,
                            threads < 1 ? 1 : threads, o.ct, o.ci, stats, err);
        if (rc == 0) out->wide->packets = traverse == BVH_TRAVERSE_PACKET, out->wide->hybrid = wo->hybrid;
        if (rc == 0) out->wide->stream = traverse == BVH_TRAVERSE_STREAM ? wo->stream : 0;
        if (rc == 0) out->wide->isa = wo->isa, stats->isa = accel_isa_label(wo->isa);
        if (rc == 0) stats->test_lanes = block;
        if (rc == 0)
            out->path = out->wide->quant || out->wide->layout == WIDE_LAYOUT_MIXED ? &bvh_path_wide_quant
                                                                                 : &bvh_path_wide;
        if (rc) bvh_release(out);
    }
    return rc;
}

static int bvh_kind_build(const accel_scene *scene, const accel_params *params, int threads,
                          void **out, accel_build_stats *stats, accel_error *err)
{
    bvh_build_opts opts;
    int traverse, frustum;
    wide_opts wo = {.width = 2, .block = 4, .order = WIDE_ORDER_OCTANT,
                    .collapse = {.dp = 1, .leaf_cost = 1.5, .leaf_blocks = 2},
                    .isa = ACCEL_ISA_AVX2}; /* the rest 0; options_from_params sets them */
    int rc = options_from_params(params, &opts, &traverse, &frustum, &wo, err);
    if (rc) return rc;
    bvh *b = calloc(1, sizeof *b);
    if (!b) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory");
    rc = build_tree(scene, &opts, &wo, traverse, threads, b, stats, err);
    if (rc) {
        free(b);
        return rc;
    }
    b->naive = params->naive;
    b->traverse = traverse;
    b->frustum = frustum;
    b->first_left = wo.first_left;
    b->rebuild = malloc(sizeof *b->rebuild);
    if (!b->rebuild) {
        bvh_destroy(b);
        return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory");
    }
    b->rebuild->opts = opts;
    b->rebuild->traverse = traverse;
    b->rebuild->frustum = frustum;
    b->rebuild->threads = threads < 1 ? 1 : threads;
    b->rebuild->wo = wo;
    stats->bytes = bvh_memory(b);
    *out = b;
    return 0;
}

/* Builds the tree again over `scene` with the options of its first build,
 * in place (a failure leaves the old tree). */
static int bvh_rebuild_on(bvh *b, const accel_scene *scene, accel_error *err)
{
    const struct bvh_rebuild *r = b->rebuild;
    if (!r)
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: a tree loaded from a file cannot be rebuilt "
                                               "(its build options are not stored)");
    bvh nb;
    accel_build_stats st;
    memset(&st, 0, sizeof st);
    int rc = build_tree(scene, &r->opts, &r->wo, r->traverse, r->threads, &nb, &st, err);
    if (rc) return rc;
    nb.naive = b->naive, nb.traverse = b->traverse, nb.frustum = b->frustum;
    nb.first_left = b->first_left;
    nb.rebuild = b->rebuild;
    b->path->release(b);
    *b = nb;
    return 0;
}

/* accel_kind.update (accel.h): refit = 1 copies the primitives again from
 * the new scene and refits every box (bvh_refit.c), refit = 0 rebuilds. A
 * scene with other primitive counts is refused; one whose set of traced
 * primitives changed (a triangle became or stopped being degenerate, a
 * coordinate became non-finite) is rebuilt even with refit = 1 (the stats
 * say so). Nothing of the scene is kept after return. */
static int bvh_update(void *a, const accel_scene *scene, int refit, accel_update_stats *st,
                      accel_error *err)
{
    bvh *b = a;
    memset(st, 0, sizeof *st);
    double t0 = accel_now_ms();
    int rc = bvh_refit_compatible(b, scene, err);
    if (rc > 0) return rc;
    /* quantized nodes keep no float boxes to refit: rebuilt (the stats say so) */
    if (refit && rc == 0 && b->path->refit_boxes) {
        rc = bvh_refit_run(b, scene, b->rebuild ? b->rebuild->threads : 1, 1, err);
        if (rc) return rc;
        st->meshes_refit = 1;
    } else {
        rc = bvh_rebuild_on(b, scene, err);
        if (rc) return rc;
        st->meshes_rebuilt = 1;
    }
    st->bottom_ms = accel_now_ms() - t0;
    return 0;
}

void bvh_refit_stale(void *accel, const accel_scene *scene)
{
    bvh_refit_run(accel, scene, 1, 0, NULL);
}

static void bvh_intersect(const void *a, const accel_ray *rays, accel_hit *hits, size_t count,
                          accel_counters *c)
{
    const bvh *b = a;
    b->path->intersect(b, rays, hits, count, c);
}

static void bvh_occluded(const void *a, const accel_ray *rays, uint8_t *occ, size_t count,
                         accel_counters *c)
{
    const bvh *b = a;
    b->path->occluded(b, rays, occ, count, c);
}

/* accel.h's conservative walk, which lets a bvh serve as instanced's bottom
 * level (bvh_walk.c, wide/walk.c). */
static int bvh_kind_walk(const void *accel, const accel_ray *ray, float pad, accel_walk_visit visit,
                         void *ctx, uint32_t *steps)
{
    const bvh *b = accel;
    if (!visit) return 0;
    accel_ray_prep p;
    if (!accel_prep_ray(ray, &p)) return 0;
    b->path->walk(b, &p, pad, visit, ctx, steps);
    return 0;
}

static const char *const bvh_variants[] = {
    "",
    "build=mid",
    "build=median",
    "build=sah",
    "build=binned,bins=2",
    "build=binned,bins=256,axes=3",
    "build=binned,bins=8,axes=1",
    "leaf=1",
    "build=sah,leaf=1",
    "ct=0,ci=1,leaf=256",
    "traverse=packet",
    "traverse=packet,frustum=1",
    "build=median,traverse=packet,frustum=1",
    "width=4",
    "width=8",
    "width=4,block=4",
    "width=8,block=4",
    "width=8,leaf=1",
    "width=4,build=sah,leaf=256,ct=0",
    "width=8,build=median",
    "width=8,order=dist",
    "width=8,order=branchy",
    "width=8,collapse=greedy",
    "width=8,leaf_below=4,order=branchy",
    "width=4,collapse=dp,leaf_below=2,leaf_blocks=4,leaf_cost=0.3",
    "width=8,block=4,collapse=dp,leaf_below=1,leaf_cost=5,order=branchy",
    "width=4,block=4,order=branchy",
    "width=4,block=8,order=dist",
    "width=8,traverse=packet",
    "width=8,traverse=packet,hybrid=0",
    "width=4,block=8,traverse=packet,hybrid=64",
    "width=4,block=4,traverse=packet",
    "build=median,term=none,leaf=4",
    "build=sbvh",
    "build=sbvh,traverse=packet",
    "build=sbvh,width=4",
    "build=sbvh,width=8",
    "build=sbvh,width=4,traverse=packet",
    "build=sbvh,width=8,traverse=packet",
    "width=8,quant=1",
    "width=8,quant=1,block=4,build=sbvh",
    /* placement in memory and the any-hit order (issue 50): the default's hits (and, for
     * layout, counts; tests/test_bvh_wide_layout.c: bit for bit) */
    "width=8,layout=bfs",
    "width=4,block=4,layout=bfs,traverse=packet",
    "width=8,layout=mixed",
    "width=8,block=4,layout=mixed,order=dist,build=sbvh",
    "width=8,any_order=octant",
    "width=8,any_order=area",
    "width=8,block=4,any_order=leaf,build=sbvh",
    /* the baseline tables where auto picks AVX-512 (core/isa.h; tests/test_isa.c: same bits) */
    "width=8,isa=avx2",
    "width=4,block=4,isa=avx2",
    "width=8,traverse=packet,isa=avx2",
    /* ray streams: the single rays' answers (tests/test_bvh_wide_stream.c: bit for bit) */
    "width=8,traverse=stream",
    "width=4,block=4,traverse=stream,stream=64,hybrid=0",
    "width=8,block=4,traverse=stream,stream=8,hybrid=2,build=sbvh",
    "first=left",
    "pairs=split",
    "first=left,pairs=split,traverse=single",
    "pairs=split,traverse=packet",
    "pairs=fresh",
    NULL,
};

const accel_kind accel_kind_bvh = {
    .name = "bvh",
    .summary = "BVH, binary (32-byte nodes) or 4-/8-wide (width=4|8, AVX2/AVX-512 kernels): "
               "binned/sweep SAH, median, mid or SBVH builds; single rays, 64-ray packets or ray "
               "streams",
    .step_name = "nodes",
    .params = bvh_params,
    .param_count = BVH_PARAM_COUNT,
    .spec_size = sizeof(bvh_spec),
    .variants = bvh_variants,
    .build = bvh_kind_build,
    .intersect = bvh_intersect,
    .occluded = bvh_occluded,
    .memory = bvh_memory,
    .destroy = bvh_destroy,
    .update = bvh_update,
    .walk = bvh_kind_walk,
};

/* ---- inspection ---------------------------------------------------------- */

const bvh_node *bvh_nodes(const void *accel, uint32_t *node_count)
{
    const bvh *b = accel;
    *node_count = b->node_count;
    return b->nodes;
}

const uint32_t *bvh_prim_ids(const void *accel, uint32_t *prim_count)
{
    const bvh *b = accel;
    *prim_count = b->prim_count;
    return b->prim_ids;
}

