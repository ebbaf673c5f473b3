/*
 * ngrid_build.c - parameters, build and bookkeeping of the `nested_grid`
 * kind.
 *
 * The build goes level by level. Every grid, the top one and each
 * sub-grid, is made by the shared grid API (grid/grid_core.h): resolution
 * rule, overflow-checked cell count, frame and boundary planes, then the
 * count / prefix-sum / fill passes over its primitives. A sub-grid is laid
 * over one parent cell's box (the parent's own boundary planes, so that
 * both walks compute the very same crossing distances at the shared
 * boundary) and built over that cell's reference list only.
 *
 * Which cells get a sub-grid: with fixed parameters, every cell holding
 * more than `threshold` primitives, at the resolution the rule gives for
 * sub_lambda on the cell's own count and box (or sub_res), as long as the
 * sub-grid separates anything; in auto mode, the cost model decides
 * (ngrid_cost.c).
 *
 * Then everything is flattened into the compact form the traversal reads
 * (ngrid.h): one array of cell words for all grids, one array of
 * count-prefixed primitive lists, one plane table, one node array. No
 * per-cell allocation survives the build.
 *
 * Threads: the top grid's passes run on all threads; the sub-grids of a
 * level are planned, checked against max_mb and built as independent jobs
 * in ngrid_level.c. Every job's result depends on its inputs alone and
 * results are gathered in job order, so any thread count builds the same
 * arrays.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/isa.h"
#include "ngrid_impl.h"

#define STR_(x) #x
#define STR(x) STR_(x)


/* The kind's parameters as parsed, one field per key (auto: is_auto);
 * choices hold their position in the table's list. */
typedef struct {
    double lambda, sub_lambda, c_step, c_isect, max_mb;
    char res[ACCEL_PARAM_TEXT];
    int sub_res, threshold, depth, is_auto, lookahead, overlap, mailbox, layout, traverse, cells;
    int isa; /* ACCEL_ISA_AUTO, _AVX2, _AVX512 (core/isa.h) */
} ngrid_spec;

static const accel_param_def ngrid_params[] = {
    {.key = "lambda", .type = ACCEL_PARAM_FLOAT, .def = STR(NGRID_DEFAULT_LAMBDA),
     .min = 0.001, .max = 1000.0,
     .help = "top level: cells per primitive, n_i = d_i*cbrt(lambda*N/V)",
     .offset = offsetof(ngrid_spec, lambda)},
    {.key = "res", .type = ACCEL_PARAM_STR, .def = "auto",
     .help = "top level: cells per axis, auto (from lambda or the cost model), N or NxNyNz",
     .offset = offsetof(ngrid_spec, res)},
    {.key = "sub_lambda", .type = ACCEL_PARAM_FLOAT, .def = STR(NGRID_DEFAULT_SUB_LAMBDA),
     .min = 0.001, .max = 1000.0,
     .help = "sub-grids: cells per primitive, on the cell's own primitive count and box",
     .offset = offsetof(ngrid_spec, sub_lambda)},
    {.key = "sub_res", .type = ACCEL_PARAM_INT, .def = "0", .min = 0, .max = 256,
     .help = "sub-grids: cells per axis of every sub-grid (0: from sub_lambda)",
     .offset = offsetof(ngrid_spec, sub_res)},
    {.key = "threshold", .type = ACCEL_PARAM_INT, .def = STR(NGRID_DEFAULT_THRESHOLD),
     .min = 0, .max = 1e9,
     .help = "a cell holding more than this many primitives gets a sub-grid (primitives; "
             "not given with cells=blocks and single rays: " STR(NGRID_BLOCKS_THRESHOLD) ")",
     .offset = offsetof(ngrid_spec, threshold)},
    {.key = "depth", .type = ACCEL_PARAM_INT, .def = STR(NGRID_DEFAULT_DEPTH),
     .min = 1, .max = NGRID_MAX_LEVELS,
     .help = "most levels, the top included (1: a regular grid)",
     .offset = offsetof(ngrid_spec, depth)},
    {.key = "auto", .type = ACCEL_PARAM_BOOL, .def = "0",
     .help = "cost model picks the top resolution and every sub-grid (ignores lambda, "
             "sub_lambda, sub_res, threshold)",
     .offset = offsetof(ngrid_spec, is_auto)},
    {.key = "lookahead", .type = ACCEL_PARAM_BOOL, .def = "0",
     .help = "auto: price a cell that may still get a sub-grid by its best sub-grid's estimate "
             "(0: as a leaf)",
     .offset = offsetof(ngrid_spec, lookahead)},
    {.key = "c_step", .type = ACCEL_PARAM_FLOAT, .def = STR(NGRID_DEFAULT_C_STEP),
     .min = 1e-3, .max = 1e6,
     .help = "auto: cost of one cell step, ns",
     .offset = offsetof(ngrid_spec, c_step)},
    {.key = "c_isect", .type = ACCEL_PARAM_FLOAT, .def = STR(NGRID_DEFAULT_C_ISECT),
     .min = 1e-3, .max = 1e6,
     .help = "auto: cost of one primitive test, ns (not given: " STR(NGRID_DEFAULT_C_ISECT)
             ", or " STR(NGRID_BLOCKS_C_ISECT) " per triangle where leaf cells hold blocks)",
     .offset = offsetof(ngrid_spec, c_isect)},
    {.key = "overlap", .type = ACCEL_PARAM_ENUM, .def = "exact", .choices = "exact|bbox",
     .help = "cell membership: exact primitive/box overlap, or bounding box only",
     .offset = offsetof(ngrid_spec, overlap)},
    {.key = "mailbox", .type = ACCEL_PARAM_BOOL, .def = "1",
     .help = "test a primitive spanning several cells once per ray, across levels (16-entry "
             "cache)",
     .offset = offsetof(ngrid_spec, mailbox)},
    {.key = "max_mb", .type = ACCEL_PARAM_FLOAT, .def = "4096", .min = 1.0, .max = 1048576.0,
     .help = "memory limit for all levels (cells, references, planes), MiB",
     .offset = offsetof(ngrid_spec, max_mb)},
    {.key = "layout", .type = ACCEL_PARAM_ENUM, .def = "words", .choices = "words|compact",
     .help = "words: cell words and count-prefixed lists, any depth; compact: two levels, 8-byte "
             "top cells with their own sub-grid resolution (at most 256 per axis), 4-byte leaf "
             "cells, one reference array (Kalojanov et al. 2011; depth defaults to 2, others "
             "refused)",
     .offset = offsetof(ngrid_spec, layout)},
    {.key = "traverse", .type = ACCEL_PARAM_ENUM, .def = "single", .choices = "single|packet",
     .help = "single rays (hierarchical 3D-DDA), or coherent grid traversal of 64 consecutive "
             "rays (8x8 tiles) slice by slice through every level, as grid:traverse=packet",
     .offset = offsetof(ngrid_spec, traverse)},
    {.key = "cells", .type = ACCEL_PARAM_ENUM, .def = "ids", .choices = "ids|blocks",
     .help = "what a leaf cell holds with layout=words, single rays and packets: ids (tested "
             "one by one) or blocks (its triangles copied 8 to a block, tested 8 at a time by "
             "the block test the wide BVH uses; the levels' cost model is still priced for ids, "
             "so ids stay the default); layout=compact, spheres and tri=naive use ids",
     .offset = offsetof(ngrid_spec, cells)},
    {.key = "isa", .type = ACCEL_PARAM_ENUM, .def = "auto", .choices = ACCEL_ISA_CHOICES,
     .help = "cells=blocks: the block kernels' instruction set: auto (GRIDBVH_ISA if set, else "
             "AVX-512 where the CPU and the build have it, else AVX2), avx2, or avx512 (an error "
             "where the CPU lacks it); the same hits, bit for bit",
     .offset = offsetof(ngrid_spec, isa)},
};

/* ---- the flat structure ------------------------------------------------------------ */

static void ngrid_destroy(void *a)
{
    ngrid_accel *g = a;
    if (!g) return;
    free(g->nodes);
    free(g->cells);
    free(g->lists);
    grid_list_blocks_free(&g->blocks);
    free(g->planes);
    ngrid_compact_free(g->compact);
    accel_prim_store_free(&g->store);
    free(g);
}

static size_t ngrid_memory(const void *a)
{
    const ngrid_accel *g = a;
    if (g->compact) return sizeof *g + ngrid_compact_bytes(g->compact) + accel_prim_store_bytes(&g->store);
    return sizeof *g + (size_t)g->node_count * sizeof *g->nodes +
           (size_t)g->cell_count * sizeof *g->cells + (size_t)g->list_len * sizeof *g->lists +
           g->plane_count * sizeof *g->planes + accel_prim_store_bytes(&g->store) +
           grid_list_blocks_bytes(&g->blocks);
}

/* Is cell c of grid g one that holds a sub-grid? `next` walks g's children
 * in cell order. */
static int is_child_cell(const ngrid_builder *b, const ngrid_bgrid *g, uint32_t *next, uint64_t c)
{
    return *next < g->first_child + g->child_count && b->grids[*next]->parent_cell == c;
}

/* The most cells (all levels) one ray can visit: every cell of a grid
 * crossed, each one possibly holding the most expensive child. Children
 * come after their parents. */
static int step_bound(const ngrid_builder *b, uint64_t *out, accel_error *err)
{
    uint64_t *bound = calloc(b->grid_count, sizeof *bound);
    if (!bound) return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory");
    for (uint32_t i = b->grid_count; i-- > 0;) {
        const ngrid_bgrid *q = b->grids[i];
        uint64_t worst = 0;
        for (uint32_t k = 0; k < q->child_count; k++)
            if (bound[q->first_child + k] > worst) worst = bound[q->first_child + k];
        uint64_t walk = (uint64_t)q->frame.res[0] + q->frame.res[1] + q->frame.res[2] + 3;
        bound[i] = worst >= UINT64_MAX / 2 / walk ? UINT64_MAX / 2 : walk * (1 + worst);
    }
    *out = bound[0];
    free(bound);
    return ACCEL_OK;
}

static int flatten(const ngrid_builder *b, ngrid_accel *g, accel_error *err)
{
    uint64_t cells = 0, list_len = 1, refs = 0, leaves = 0;
    size_t planes = 0;
    for (uint32_t i = 0; i < b->grid_count; i++) {
        const ngrid_bgrid *q = b->grids[i];
        uint32_t next = q->first_child;
        for (uint64_t c = 0; c < q->cells.cell_count; c++) {
            if (is_child_cell(b, q, &next, c)) {
                next++;
                continue;
            }
            uint32_t n = ngrid_cell_prims(q, (uint32_t)c);
            if (n) {
                list_len += 1 + (uint64_t)n;
                refs += n;
                leaves++;
            }
        }
        cells += q->cells.cell_count;
        planes += grid_plane_count(q->frame.res);
    }
    if (cells >= UINT32_MAX || list_len >= NGRID_CHILD)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "nested_grid: %llu cells and %llu list words exceed the 32-bit index "
                          "limits (raise threshold, lower lambda or sub_lambda)",
                          (unsigned long long)cells, (unsigned long long)list_len);
    double bytes = (double)sizeof *g + (double)b->grid_count * sizeof(ngrid_node) +
                   ((double)cells + (double)list_len) * sizeof(uint32_t) +
                   (double)planes * sizeof(float);
    if (bytes > b->max_bytes)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "nested_grid: %llu cells and %llu references need %.1f MiB, above the "
                          "limit of %.1f MiB (raise max_mb or threshold)",
                          (unsigned long long)cells, (unsigned long long)refs, bytes / 1048576.0,
                          b->max_bytes / 1048576.0);
    g->nodes = malloc((size_t)b->grid_count * sizeof *g->nodes);
    g->cells = accel_alloc_large(cells, sizeof *g->cells, sizeof(void *));
    g->lists = accel_alloc_large(list_len, sizeof *g->lists, sizeof(void *));
    g->planes = malloc(planes * sizeof *g->planes);
    if (!g->nodes || !g->cells || !g->lists || !g->planes)
        return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory for %.1f MiB",
                          bytes / 1048576.0);
    g->node_count = b->grid_count;
    g->cell_count = cells;
    g->list_len = list_len;
    g->plane_count = planes;
    g->ref_count = refs;
    g->leaf_count = leaves;
    g->lists[0] = 0;
    uint64_t cell_at = 0, list_at = 1;
    size_t plane_at = 0;
    for (uint32_t i = 0; i < b->grid_count; i++) {
        const ngrid_bgrid *q = b->grids[i];
        ngrid_node *node = &g->nodes[i];
        node->frame = q->frame;
        node->cell_base = (uint32_t)cell_at;
        node->level = (uint32_t)q->level;
        for (int a = 0; a < 3; a++) {
            size_t np = (size_t)q->frame.res[a] + 1;
            memcpy(g->planes + plane_at, q->frame.planes[a], np * sizeof(float));
            node->frame.planes[a] = g->planes + plane_at;
            plane_at += np;
        }
        uint32_t next = q->first_child;
        for (uint64_t c = 0; c < q->cells.cell_count; c++) {
            uint32_t *word = &g->cells[cell_at + c];
            if (is_child_cell(b, q, &next, c)) {
                *word = NGRID_CHILD | next++;
                continue;
            }
            uint32_t n = ngrid_cell_prims(q, (uint32_t)c);
            if (!n) {
                *word = 0;
                continue;
            }
            *word = (uint32_t)list_at;
            g->lists[list_at] = n;
            memcpy(g->lists + list_at + 1, q->cells.refs + q->cells.offsets[c], n * sizeof(uint32_t));
            list_at += 1 + (uint64_t)n;
        }
        cell_at += q->cells.cell_count;
        if (q->level + 1 > g->levels) g->levels = q->level + 1;
    }
    return step_bound(b, &g->step_bound, err);
}

static void builder_free(ngrid_builder *b)
{
    for (uint32_t i = 0; i < b->grid_count; i++) ngrid_bgrid_free(b->grids[i]);
    free(b->grids);
}

/* ---- the kind -------------------------------------------------------------------- */

/* The top grid over box at resolution res, then level by level the
 * sub-grids the builder's rules give (every grid pushed onto b). */
static int build_grids(ngrid_builder *b, box3 box, const int res[3], int threads,
                       accel_error *err)
{
    const accel_scene *scene = b->scene;
    ngrid_bgrid *top;
    int rc = ngrid_bgrid_new(box, res, 0, &top, err);
    if (rc) return rc;
    rc = grid_cells_build(&top->frame, scene, scene->live, scene->live_count, b->mode, threads,
                          b->max_bytes, &top->cells, err);
    if (rc) {
        ngrid_bgrid_free(top);
        return ngrid_wrap_error(err, rc, "top level");
    }
    rc = ngrid_push_grid(b, top, err);
    if (rc) {
        ngrid_bgrid_free(top);
        return rc;
    }
    /* Level by level: the grids of level L are grids[begin, end). */
    uint32_t begin = 0, end = 1;
    for (int level = 0; !rc && level + 1 < b->depth && begin < end; level++) {
        rc = ngrid_build_level(b, begin, end, threads, err);
        begin = end;
        end = b->grid_count;
    }
    return rc;
}

/* Builds over the primitive store's scene (every primitive live, local ids). */
static int build_over(const accel_scene *scene, const accel_params *params, int threads,
                      ngrid_accel **out, accel_build_stats *stats, accel_error *err)
{
    *out = NULL;
    ngrid_builder b;
    memset(&b, 0, sizeof b);
    b.scene = scene;
    const ngrid_spec *spec = ACCEL_SPEC(params, ngrid_spec);
    b.mode = spec->overlap == 1 ? GRID_OVERLAP_BBOX : GRID_OVERLAP_EXACT;
    b.is_auto = spec->is_auto != 0;
    b.lookahead = spec->lookahead != 0;
    b.depth = spec->depth;
    b.sub_res = spec->sub_res;
    b.sub_lambda = spec->sub_lambda;
    b.threshold = (uint32_t)spec->threshold;
    b.costs.c_step = spec->c_step;
    b.costs.c_isect = spec->c_isect;
    /* cells=blocks where the block test applies: auto mode prices a test
     * at the block test's cost per triangle unless c_isect is given
     * (NGRID_BLOCKS_C_ISECT, ngrid.h: not fitted on this kernel). */
    const int blocks = spec->cells == 1 && spec->layout != 1 && !params->naive &&
                       scene->sphere_count == 0;
    if (blocks && !ACCEL_GIVEN(params, ngrid_spec, c_isect)) b.costs.c_isect = NGRID_BLOCKS_C_ISECT;
    /* single rays only, as the grid's coarser lambda for blocks: it was
     * measured on them; packets keep the per-id densities */
    if (blocks && spec->traverse != 1 && !ACCEL_GIVEN(params, ngrid_spec, threshold))
        b.threshold = NGRID_BLOCKS_THRESHOLD;
    b.max_bytes = spec->max_mb * 1048576.0;
    const int compact = spec->layout == 1;
    if (compact) {
        if (ACCEL_GIVEN(params, ngrid_spec, depth) && b.depth != 2)
            return accel_fail(err, ACCEL_ERR_RANGE,
                              "nested_grid: layout=compact has exactly two levels (depth=2), "
                              "not depth=%d (use layout=words for other depths)",
                              b.depth);
        b.depth = 2;
        b.max_sub_res = NGRID_COMPACT_MAX_RES;
    }
    if (b.sub_res == 1)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "nested_grid: sub_res=1 makes sub-grids of one cell (use 0 or 2..256)");

    int isa;
    if (accel_isa_resolve(spec->isa, &isa, err)) return ACCEL_ERR_SPEC;
    int res[3];
    int rc = grid_parse_res(spec->res, res, err);
    if (rc) return ngrid_wrap_error(err, rc, "top level");
    box3 box = grid_frame_box(scene->bounds);
    if (res[0] == 0) {
        if (b.is_auto) {
            rc = ngrid_auto_top_res(scene, box, b.mode, b.lookahead && b.depth > 1, &b.costs,
                                    b.max_bytes, res, err);
            if (rc) return rc;
        } else {
            grid_resolution(scene->bounds, (double)scene->live_count, spec->lambda, res);
        }
    }
    uint64_t cells;
    rc = grid_cell_count("nested_grid", res, b.max_bytes, &cells, err);
    if (rc) return rc;

    rc = build_grids(&b, box, res, threads, err);

    ngrid_accel *g = NULL;
    if (!rc) {
        g = calloc(1, sizeof *g);
        if (!g) rc = accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory");
    }
    if (!rc) {
        g->naive = params->naive;
        g->isa = isa;
        /* lists as blocks have no mailbox in single rays: traced by the
         * mailbox=0 copies; a packet's mailbox pays with blocks too */
        g->mailbox = spec->mailbox != 0 &&
                     !(spec->cells == 1 && !compact && !params->naive && scene->sphere_count == 0);
        g->packet_mailbox = spec->mailbox != 0;
        g->traverse = spec->traverse == 1 ? NGRID_TRAVERSE_PACKET : NGRID_TRAVERSE_SINGLE;
        g->has_spheres = scene->sphere_count > 0;
        rc = flatten(&b, g, err);
    }
    if (!rc && compact) rc = ngrid_compact_build(g, b.max_bytes, err);
    /* cells=blocks where the block test applies (layout=words, single rays
     * and packets, triangles, the watertight test). */
    if (!rc && !compact && spec->cells == 1 && !g->naive && !g->has_spheres)
        rc = grid_list_blocks_build(g->lists, g->list_len, scene, b.max_bytes,
                                    &g->blocks, err);
    builder_free(&b);
    if (rc) {
        ngrid_destroy(g);
        return rc;
    }

    memset(stats, 0, sizeof *stats);
    stats->bytes = ngrid_memory(g);
    stats->nodes = g->compact ? g->compact->top_count + g->compact->leaf_count : g->cell_count;
    stats->leaves = g->leaf_count;
    stats->refs = g->ref_count;
    stats->sah_cost = NAN;
    stats->depth = g->levels;
    stats->test_lanes = g->blocks.first ? 8 : 0;
    stats->isa = g->blocks.first ? accel_isa_label(g->isa) : NULL; /* the per-id walks have one */
    for (int a = 0; a < 3; a++) stats->res[a] = res[a];
    *out = g;
    return ACCEL_OK;
}

static int ngrid_build(const accel_scene *scene, const accel_params *params, int threads,
                       void **out, accel_build_stats *stats, accel_error *err)
{
    *out = NULL;
    accel_prim_store store;
    int rc = accel_prim_store_build(scene, params->reorder, &store, err);
    if (rc) return rc;
    ngrid_accel *g;
    rc = build_over(&store.prims, params, threads, &g, stats, err);
    if (rc) {
        accel_prim_store_free(&store);
        return rc;
    }
    g->store = store;
    stats->bytes = ngrid_memory(g);
    *out = g;
    return ACCEL_OK;
}

void ngrid_get_view(const void *accel, ngrid_view *v)
{
    const ngrid_accel *g = accel;
    v->nodes = g->nodes;
    v->node_count = g->node_count;
    v->cells = g->cells;
    v->cell_count = g->cell_count;
    v->lists = g->lists;
    v->prim_id = g->store.scene_id;
    v->prim_count = g->store.prims.prim_count;
    v->list_len = g->list_len;
    v->ref_count = g->ref_count;
    v->levels = g->levels;
}

/* The batch entries: the packet walk (ngrid_packet.c) or the single-ray
 * walk of the layout (ngrid_trace.c, ngrid_compact.c). */
static void ngrid_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                            size_t count, accel_counters *counters)
{
    const ngrid_accel *g = accel;
    if (g->traverse == NGRID_TRAVERSE_PACKET)
        ngrid_packet_intersect(g, rays, hits, count, counters);
    else
        ngrid_single_intersect(g, rays, hits, count, counters);
}

static void ngrid_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded,
                           size_t count, accel_counters *counters)
{
    const ngrid_accel *g = accel;
    if (g->traverse == NGRID_TRAVERSE_PACKET)
        ngrid_packet_occluded(g, rays, occluded, count, counters);
    else
        ngrid_single_occluded(g, rays, occluded, count, counters);
}

/* The conformance suite runs each: defaults, the cost model, a single
 * level (the regular grid), subdividing almost every cell (with a small
 * depth), never subdividing, bounding-box membership, no mailbox; the
 * packet walk on both layouts, deep, without its mailbox, with naive
 * triangles, and with sub-grids so fine that packets give up. */
static const char *const ngrid_variants[] = {
    "", "auto", "depth=1", "threshold=1,depth=2", "threshold=100000", "overlap=bbox,mailbox=0",
    "layout=compact", "layout=compact,auto", "layout=compact,threshold=1,sub_res=6",
    "traverse=packet", "traverse=packet,threshold=1,depth=4,sub_res=3",
    "traverse=packet,mailbox=0", "traverse=packet,tri=naive", "traverse=packet,layout=compact",
    "traverse=packet,threshold=2,sub_res=24", "cells=blocks", "cells=blocks,threshold=1,depth=4,sub_res=3",
    "traverse=packet,cells=blocks", "traverse=packet,cells=blocks,threshold=1,depth=4,sub_res=3",
    "traverse=packet,cells=blocks,mailbox=0",
    /* the baseline units where auto picks AVX-512 (core/isa.h; tests/test_isa.c) */
    "cells=blocks,isa=avx2", "traverse=packet,cells=blocks,isa=avx2", NULL,
};

const accel_kind accel_kind_nested_grid = {
    .name = "nested_grid",
    .summary = "nested uniform grids: dense cells hold sub-grids, hierarchical 3D-DDA, auto mode "
               "from the step/intersect cost model",
    .step_name = "cells",
    .params = ngrid_params,
    .param_count = sizeof ngrid_params / sizeof ngrid_params[0],
    .spec_size = sizeof(ngrid_spec),
    .variants = ngrid_variants,
    .build = ngrid_build,
    .intersect = ngrid_intersect,
    .occluded = ngrid_occluded,
    .memory = ngrid_memory,
    .destroy = ngrid_destroy,
    .walk = ngrid_walk,
};
