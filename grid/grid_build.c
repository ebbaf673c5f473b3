/*
 * grid_build.c - parameters, build and bookkeeping of the `grid` kind.
 *
 * The build is the shared grid API end to end: the resolution rule (or an
 * explicit res), the overflow-checked cell count, the frame with its
 * boundary planes, then the count / prefix-sum / fill passes over the live
 * primitives (grid_core.c). Traversal lives in grid_trace.c.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/isa.h"
#include "grid_packet.h"

#define STR_(x) #x
#define STR(x) STR_(x)

static const accel_param_def grid_params[] = {
    {.key = "lambda", .type = ACCEL_PARAM_FLOAT, .def = STR(GRID_DEFAULT_LAMBDA),
     .min = 0.001, .max = 1000.0,
     .help = "cells per primitive: n_i = d_i*cbrt(lambda*N/V) (ignored when res is given); "
             "not given: " STR(GRID_DEFAULT_LAMBDA) ", or " STR(GRID_BLOCKS_LAMBDA)
             " where the cells hold blocks for single rays",
     .offset = offsetof(grid_spec, lambda)},
    {.key = "res", .type = ACCEL_PARAM_STR, .def = "auto",
     .help = "cells per axis: auto (from lambda), N, or NxNyNz (each 1..65536)",
     .offset = offsetof(grid_spec, res)},
    {.key = "overlap", .type = ACCEL_PARAM_ENUM, .def = "exact", .choices = "exact|bbox",
     .help = "cell membership: exact primitive/box overlap, or bounding box only",
     .offset = offsetof(grid_spec, overlap)},
    {.key = "mailbox", .type = ACCEL_PARAM_BOOL, .def = "1",
     .help = "test a primitive spanning several cells once per ray (16-entry per-ray cache)",
     .offset = offsetof(grid_spec, mailbox)},
    {.key = "max_mb", .type = ACCEL_PARAM_FLOAT, .def = "4096", .min = 1.0, .max = 1048576.0,
     .help = "memory limit for cell offsets + references, MiB: larger grids are refused",
     .offset = offsetof(grid_spec, max_mb)},
    {.key = "traverse", .type = ACCEL_PARAM_ENUM, .def = "single", .choices = "single|packet",
     .help = "single rays (3D-DDA), or coherent grid traversal of 64 consecutive rays (8x8 "
             "tiles) slice by slice",
     .offset = offsetof(grid_spec, traverse)},
    {.key = "skip", .type = ACCEL_PARAM_ENUM, .def = "none", .choices = "none|cloud|macro",
     .help = "empty-space skipping: none, proximity clouds (1 byte/cell), macro cells (see macro)",
     .offset = offsetof(grid_spec, skip)},
    {.key = "skip_min", .type = ACCEL_PARAM_INT, .def = "1", .min = 1, .max = 254,
     .help = "skip=cloud: smallest radius worth a jump (cells; a jump costs about two steps)",
     .offset = offsetof(grid_spec, skip_min)},
    {.key = "macro", .type = ACCEL_PARAM_INT, .def = "4", .min = 2, .max = 64,
     .help = "skip=macro: cells per macro cell along each axis, a power of two",
     .offset = offsetof(grid_spec, macro)},
    {.key = "cells", .type = ACCEL_PARAM_ENUM, .def = "blocks", .choices = "ids|blocks",
     .help = "what a cell holds: blocks (its triangles copied 8 to a block, tested 8 at a "
             "time by the block test the wide BVH uses, single rays and packets) or ids (a list "
             "of primitive ids, tested one by one); spheres and tri=naive use ids",
     .offset = offsetof(grid_spec, cells)},
    {.key = "isa", .type = ACCEL_PARAM_ENUM, .def = "auto", .choices = ACCEL_ISA_CHOICES,
     .help = "cells=blocks: the block kernels' instruction set: auto (GRIDBVH_ISA if set, else "
             "AVX-512 where the CPU and the build have it, else AVX2), avx2, or avx512 (an error "
             "where the CPU lacks it); the same hits, bit for bit",
     .offset = offsetof(grid_spec, isa)},
};

static void grid_destroy(void *a)
{
    grid_accel *g = a;
    if (!g) return;
    grid_cells_free(&g->cells);
    grid_cell_blocks_free(&g->blocks);
    free(g->skip_dist);
    free(g->macro_empty);
    free(g->planes);
    free(g->macro);
    accel_prim_store_free(&g->store);
    free(g);
}

/* Bytes of the skipping tables of mode `skip` over res[] cells. */
static size_t skip_bytes(grid_skip_mode skip, const int res[3], int macro_shift)
{
    if (skip == GRID_SKIP_CLOUD) return (size_t)res[0] * res[1] * res[2];
    if (skip != GRID_SKIP_MACRO) return 0;
    int mres[3];
    grid_skip_macro_res(res, macro_shift, mres);
    return (size_t)mres[0] * mres[1] * mres[2];
}

/* Builds the skipping tables of g->skip over the built cells, within
 * max_bytes for cells and tables together. */
static int build_skip(grid_accel *g, int threads, double max_bytes, accel_error *err)
{
    if (g->skip == GRID_SKIP_NONE) return ACCEL_OK;
    size_t bytes = skip_bytes(g->skip, g->frame.res, g->macro_shift);
    double total = ((double)g->cells.cell_count + 1.0 + (double)g->cells.ref_count) * 4.0 + bytes;
    if (total > max_bytes)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "grid: cells, references and the skip=%s table need %.1f MiB, above the "
                          "limit of %.1f MiB (lower lambda or res, or raise max_mb)",
                          g->skip == GRID_SKIP_CLOUD ? "cloud" : "macro", total / 1048576.0,
                          max_bytes / 1048576.0);
    uint8_t *table = malloc(bytes ? bytes : 1);
    if (!table) return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for the skip table");
    if (g->skip == GRID_SKIP_CLOUD) {
        g->skip_dist = table;
        return grid_skip_cloud(&g->frame, g->cells.offsets, table, threads, err);
    }
    g->macro_empty = table;
    grid_skip_macro_res(g->frame.res, g->macro_shift, g->macro_res);
    grid_skip_macro(&g->frame, g->cells.offsets, g->macro_shift, table);
    return ACCEL_OK;
}

static size_t grid_memory(const void *a)
{
    const grid_accel *g = a;
    return sizeof *g + skip_bytes(g->skip, g->frame.res, g->macro_shift) +
           (size_t)(g->cells.cell_count + 1) * sizeof(uint32_t) +
           (size_t)g->cells.ref_count * sizeof(uint32_t) +
           grid_plane_count(g->frame.res) * sizeof(float) + accel_prim_store_bytes(&g->store) +
           grid_cell_blocks_bytes(&g->blocks) +
           (g->macro ? (size_t)g->macro_res[0] * g->macro_res[1] * g->macro_res[2] : 0);
}

static int grid_build(const accel_scene *scene, const accel_params *params, int threads,
                      void **out, accel_build_stats *stats, accel_error *err)
{
    *out = NULL;
    const grid_spec *spec = ACCEL_SPEC(params, grid_spec);
    /* Blocks where the block test applies: triangles with the watertight
     * test, single rays and packets (spheres and tri=naive test ids). */
    int use_blocks = spec->cells == 1 && !params->naive && scene->sphere_count == 0;
    /* The coarser density of blocks was measured for single rays only:
     * packets keep the per-id default (their walk's cost is the culls
     * and filter per triangle and cell, unchanged by blocks). */
    double lambda = use_blocks && spec->traverse != 1 && !ACCEL_GIVEN(params, grid_spec, lambda)
                        ? GRID_BLOCKS_LAMBDA
                        : spec->lambda;
    double max_bytes = spec->max_mb * 1048576.0;
    int res[3];
    int rc = grid_parse_res(spec->res, res, err);
    if (rc) return rc;
    box3 box = grid_frame_box(scene->bounds);
    if (res[0] == 0) grid_resolution(scene->bounds, (double)scene->live_count, lambda, res);
    uint64_t cells;
    rc = grid_cell_count("grid", res, max_bytes, &cells, err);
    if (rc) return rc;

    int isa;
    if (accel_isa_resolve(spec->isa, &isa, err)) return ACCEL_ERR_SPEC;
    grid_accel *g = calloc(1, sizeof *g);
    if (!g) return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory");
    g->naive = params->naive;
    g->isa = isa;
    /* Blocks have no mailbox (grid_blocks.h): their copies are the
     * mailbox=0 ones, so the block test is compiled into half the copies. */
    g->mailbox = spec->mailbox != 0 && !use_blocks;
    /* A packet's mailbox pays with blocks too: it spares the culls and the
     * filter of a triangle met again, which blocks do per triangle. */
    g->packet_mailbox = spec->mailbox != 0;
    g->traverse = spec->traverse == 1 ? GRID_TRAVERSE_PACKET : GRID_TRAVERSE_SINGLE;
    g->has_spheres = scene->sphere_count > 0;
    g->skip = (grid_skip_mode)spec->skip;
    g->skip_min = spec->skip_min;
    int macro = spec->macro;
    while ((1 << g->macro_shift) < macro) g->macro_shift++;
    if ((1 << g->macro_shift) != macro) {
        grid_destroy(g);
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "grid: macro=%d: cells per macro cell must be a power of two in [2, 64]",
                          macro);
    }
    g->planes = malloc(grid_plane_count(res) * sizeof *g->planes);
    if (!g->planes) {
        grid_destroy(g);
        return accel_fail(err, ACCEL_ERR_NOMEM, "grid: out of memory for plane tables");
    }
    grid_frame_init(&g->frame, box, res, g->planes);
    rc = accel_prim_store_build(scene, params->reorder, &g->store, err);
    if (rc) {
        grid_destroy(g);
        return rc;
    }
    grid_overlap mode = spec->overlap == 1 ? GRID_OVERLAP_BBOX : GRID_OVERLAP_EXACT;
    rc = grid_cells_build(&g->frame, &g->store.prims, NULL, g->store.prims.prim_count, mode, threads,
                          max_bytes, &g->cells, err);
    if (!rc) rc = build_skip(g, threads, max_bytes, err);
    if (!rc && use_blocks)
        rc = grid_cell_blocks_build(&g->cells, &g->store.prims, max_bytes, &g->blocks, err);
    if (rc) {
        grid_destroy(g);
        return rc;
    }

    if (g->traverse == GRID_TRAVERSE_PACKET && (rc = grid_macro_build(g, err))) {
        grid_destroy(g);
        return rc;
    }

    memset(stats, 0, sizeof *stats);
    stats->bytes = grid_memory(g);
    stats->nodes = g->cells.cell_count;
    for (uint64_t c = 0; c < g->cells.cell_count; c++)
        stats->leaves += g->cells.offsets[c + 1] != g->cells.offsets[c];
    stats->refs = g->cells.ref_count;
    stats->sah_cost = NAN;
    stats->depth = 1;
    stats->test_lanes = g->blocks.blocks ? 8 : 0;
    stats->isa = g->blocks.blocks ? accel_isa_label(g->isa) : NULL; /* the per-id kernels have one */
    for (int a = 0; a < 3; a++) stats->res[a] = g->frame.res[a];
    *out = g;
    return ACCEL_OK;
}

void grid_get_view(const void *accel, grid_view *v)
{
    const grid_accel *g = accel;
    v->frame = &g->frame;
    v->offsets = g->cells.offsets;
    v->refs = g->cells.refs;
    v->prim_id = g->store.scene_id;
    v->prim_count = g->store.prims.prim_count;
    v->cell_count = g->cells.cell_count;
    v->ref_count = g->cells.ref_count;
}

/* The batch entries: single rays or packets (grid_packet_trace.c). */
static void grid_trace_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                                 size_t count, accel_counters *counters)
{
    const grid_accel *g = accel;
    if (g->traverse == GRID_TRAVERSE_PACKET)
        grid_packet_intersect(accel, rays, hits, count, counters);
    else
        grid_intersect(accel, rays, hits, count, counters);
}

static void grid_trace_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded,
                                size_t count, accel_counters *counters)
{
    const grid_accel *g = accel;
    if (g->traverse == GRID_TRAVERSE_PACKET)
        grid_packet_occluded(accel, rays, occluded, count, counters);
    else
        grid_occluded(accel, rays, occluded, count, counters);
}

/* The conformance suite runs each: defaults, a single cell (the brute force
 * limit), a very fine grid, bounding-box membership, no mailbox, the naive
 * triangle test, the two ends of the density range, empty-space skipping
 * (both kinds, on coarse, flat and fine grids), and the packet traversal
 * with and without its mailbox, on a fine and a flat grid (blocks, the
 * default, at lambda 8 and 1, and ids). */
static const char *const grid_variants[] = {
    "", "res=1", "res=128", "res=7x1x13", "overlap=bbox", "mailbox=0", "tri=naive",
    "lambda=0.05", "lambda=64", "overlap=bbox,mailbox=0", "reorder=0", "skip=cloud",
    "skip=cloud,res=7x1x13", "skip=cloud,lambda=64,mailbox=0", "skip=macro", "skip=macro,macro=2",
    "skip=macro,lambda=64,macro=8", "traverse=packet", "traverse=packet,mailbox=0",
    "traverse=packet,res=128", "traverse=packet,res=7x1x13", "traverse=packet,tri=naive",
    "cells=ids", "cells=ids,lambda=1", "traverse=packet,cells=ids",
    "traverse=packet,cells=ids,res=7x1x13", "traverse=packet,lambda=1",
    /* the baseline units where auto picks AVX-512 (core/isa.h; tests/test_isa.c) */
    "isa=avx2", "traverse=packet,isa=avx2", NULL,
};

const accel_kind accel_kind_grid = {
    .name = "grid",
    .summary = "uniform grid, compact cells, exact overlap, 3D-DDA with mailboxing",
    .step_name = "cells",
    .params = grid_params,
    .param_count = sizeof grid_params / sizeof grid_params[0],
    .spec_size = sizeof(grid_spec),
    .variants = grid_variants,
    .build = grid_build,
    .intersect = grid_trace_intersect,
    .occluded = grid_trace_occluded,
    .memory = grid_memory,
    .destroy = grid_destroy,
    .walk = grid_walk,
};
