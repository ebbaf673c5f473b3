/*
 * igrid_params.c - the parameters of the `irregular_grid` kind: its table
 * (key, type, default, range, help), which the spec parser and --help
 * read, and where each value goes in igrid_spec (igrid_impl.h).
 */
#include "core/isa.h"
#include "igrid_impl.h"

#define STR_(x) #x
#define STR(x) STR_(x)

/* split=adaptive, below the paper's depth: a split whose octants hold more
 * than this many references per primitive of the node duplicates more
 * than it separates: primitives
 * as large as the node (a mesh's triangles around a shared vertex, where
 * the count never drops), crossing or coincident ones. One that leaves
 * every primitive in one octant is kept: it carves empty space around a
 * cluster (the teapot in the stadium). */
#ifndef IGRID_SPLIT_GUARD
#define IGRID_SPLIT_GUARD 3.0
#endif

const accel_param_def igrid_params[IGRID_PARAM_COUNT] = {
    {.key = "top_lambda", .type = ACCEL_PARAM_FLOAT, .def = STR(IGRID_DEFAULT_TOP_LAMBDA),
     .min = 0.0001, .max = 100.0,
     .help = "top grid: cells per primitive, n_i = d_i*cbrt(lambda*N/V)",
     .offset = offsetof(igrid_spec, top_lambda)},
    {.key = "sub_lambda", .type = ACCEL_PARAM_FLOAT, .def = STR(IGRID_DEFAULT_SUB_LAMBDA),
     .min = 0.001, .max = 1000.0,
     .help = "octree density: cells per primitive the resolution rule aims at (see split)",
     .offset = offsetof(igrid_spec, sub_lambda)},
    {.key = "max_depth", .type = ACCEL_PARAM_INT, .def = STR(IGRID_DEFAULT_MAX_DEPTH),
     .min = 0, .max = IGRID_MAX_DEPTH,
     .help = "deepest octree level (levels; the lattice is the top grid times 2^depth per axis, "
             "at most 65536)",
     .offset = offsetof(igrid_spec, max_depth)},
    {.key = "split", .type = ACCEL_PARAM_ENUM, .def = "adaptive", .choices = "adaptive|cell",
     .help = "octree: every non-empty node down to its top cell's depth (cell, the paper), and "
             "below it nodes holding at least split_min primitives while a split separates them "
             "(adaptive)",
     .offset = offsetof(igrid_spec, split)},
    {.key = "subdivide", .type = ACCEL_PARAM_BOOL, .def = "1",
     .help = "step 1: octree subdivision of the top cells (0: top cells only)",
     .offset = offsetof(igrid_spec, subdivide)},
    {.key = "split_min", .type = ACCEL_PARAM_INT, .def = STR(IGRID_DEFAULT_SPLIT_MIN),
     .min = 1, .max = 1000000,
     .help = "split=adaptive: below the paper's depth, only nodes holding at least this many "
             "primitives are split",
     .offset = offsetof(igrid_spec, split_min)},
    {.key = "split_ratio", .type = ACCEL_PARAM_FLOAT, .def = STR(IGRID_SPLIT_GUARD),
     .min = 1.0, .max = 8.0,
     .help = "split=adaptive: a split is undone when its octants hold more than this many "
             "references per primitive of the node (below the paper's depth; above it too for "
             "nodes of 64 or more)",
     .offset = offsetof(igrid_spec, split_ratio)},
    {.key = "merge", .type = ACCEL_PARAM_BOOL, .def = "1",
     .help = "step 2: merge neighbouring cells while the surface-area cost does not grow",
     .offset = offsetof(igrid_spec, merge)},
    {.key = "alpha", .type = ACCEL_PARAM_FLOAT, .def = STR(IGRID_DEFAULT_ALPHA),
     .min = 0.0, .max = 1.0,
     .help = "merge: another round of passes while a round removes at least 1-alpha of the cells",
     .offset = offsetof(igrid_spec, alpha)},
    {.key = "ct", .type = ACCEL_PARAM_FLOAT, .def = "1", .min = 0.0, .max = 1000.0,
     .help = "merge cost: one cell step, in primitive tests",
     .offset = offsetof(igrid_spec, ct)},
    {.key = "expand", .type = ACCEL_PARAM_INT, .def = STR(IGRID_DEFAULT_EXPAND),
     .min = 0, .max = 16,
     .help = "step 3: expansion rounds over the six faces of every cell (0: off)",
     .offset = offsetof(igrid_spec, expand)},
    {.key = "mailbox", .type = ACCEL_PARAM_BOOL, .def = "1",
     .help = "test a primitive spanning several cells once per ray (16-entry per-ray cache)",
     .offset = offsetof(igrid_spec, mailbox)},
    {.key = "max_mb", .type = ACCEL_PARAM_FLOAT, .def = "4096", .min = 1.0, .max = 1048576.0,
     .help = "memory limit for cells, references and voxel map, MiB: larger builds are refused",
     .offset = offsetof(igrid_spec, max_mb)},
    {.key = "cells", .type = ACCEL_PARAM_ENUM, .def = "ids", .choices = "ids|blocks",
     .help = "what a cell holds: ids (a list of primitive ids, tested one by one through the "
             "mailbox) or blocks (its triangles copied 8 to a block, tested 8 at a time by the "
             "block test the wide BVH and the grid use; no mailbox); spheres and tri=naive use ids",
     .offset = offsetof(igrid_spec, cells)},
    {.key = "isa", .type = ACCEL_PARAM_ENUM, .def = "auto", .choices = ACCEL_ISA_CHOICES,
     .help = "cells=blocks: the block kernels' instruction set: auto (GRIDBVH_ISA if set, else "
             "AVX-512 where the CPU and the build have it, else AVX2), avx2, or avx512 (an error "
             "where the CPU lacks it); the same hits, bit for bit",
     .offset = offsetof(igrid_spec, isa)},
};
