/*
 * bvh.c - the "bvh" accelerator kind: parameters, build entry, batch entry
 * points, memory accounting, and saving / loading a built tree.
 *
 * The kind's table is the only thing the rest of the project sees
 * (registry.c); builders live in build_*.c, traversal in trace.c and
 * packet.c.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "build_common.h"
#include "bvh.h"

static const accel_param_def bvh_params[] = {
    {"build", ACCEL_PARAM_ENUM, "binned", 0, 0, "binned|sah|mid|median",
     "builder: binned SAH (Wald 2007), exact SAH by full sweep, spatial middle, object median"},
    {"bins", ACCEL_PARAM_INT, "16", 2, 256, NULL, "build=binned: bins per axis (count)"},
    {"axes", ACCEL_PARAM_ENUM, "3", 0, 0, "1|3",
     "build=binned: axes binned per node, 1 = largest centroid extent only, 3 = all"},
    {"leaf", ACCEL_PARAM_INT, "8", 1, 256, NULL,
     "largest leaf (primitives); smaller leaves when the SAH rule says so"},
    {"ct", ACCEL_PARAM_FLOAT, "1", 0, 1e6, NULL,
     "SAH cost of a node visit (same time unit as ci)"},
    {"ci", ACCEL_PARAM_FLOAT, "1", 1e-6, 1e6, NULL,
     "SAH cost of a primitive test (same time unit as ct)"},
    {"traverse", ACCEL_PARAM_ENUM, "single", 0, 0, "single|packet",
     "single rays, or packets of 64 consecutive rays (8x8 tiles)"},
    {"frustum", ACCEL_PARAM_BOOL, "0", 0, 1, NULL,
     "traverse=packet: interval-arithmetic early-out per node (0/1)"},
};
#define BVH_PARAM_COUNT (sizeof bvh_params / sizeof bvh_params[0])

static int options_from_params(const accel_params *p, bvh_build_opts *o, int *traverse,
                               int *frustum, accel_error *err)
{
    o->builder = (bvh_builder)(int)accel_param_num(p, "build");
    o->bins = (int)accel_param_num(p, "bins");
    o->axes = atoi(accel_param_str(p, "axes"));
    o->max_leaf = (int)accel_param_num(p, "leaf");
    o->ct = (float)accel_param_num(p, "ct");
    o->ci = (float)accel_param_num(p, "ci");
    *traverse = (int)accel_param_num(p, "traverse");
    *frustum = (int)accel_param_num(p, "frustum");
    /* Options that would be silently ignored are errors. */
    if (o->builder != BVH_BUILD_BINNED && (accel_param_given(p, "bins") || accel_param_given(p, "axes")))
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: bins and axes apply to build=binned only (got build=%s)",
                          accel_param_str(p, "build"));
    if (*frustum && *traverse != BVH_TRAVERSE_PACKET)
        return accel_fail(err, ACCEL_ERR_SPEC, "bvh: frustum=1 needs traverse=packet");
    return 0;
}

static size_t bvh_memory(const void *a)
{
    const bvh *b = a;
    return sizeof *b + (size_t)b->node_count * sizeof(bvh_node) +
           (size_t)b->prim_count * (BVH_SLOT_FLOATS * sizeof(float) + sizeof(uint32_t));
}

static void bvh_destroy(void *a)
{
    if (!a) return;
    bvh_release(a);
    free(a);
}

static int bvh_kind_build(const accel_scene *scene, const accel_params *params, int threads,
                          void **out, accel_build_stats *stats, accel_error *err)
{
    bvh_build_opts opts;
    int traverse, frustum;
    int rc = options_from_params(params, &opts, &traverse, &frustum, err);
    if (rc) return rc;
    bvh *b = calloc(1, sizeof *b);
    if (!b) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory");
    rc = bvh_build_run(scene, &opts, threads, b, stats, err);
    if (rc) {
        free(b);
        return rc;
    }
    b->naive = params->naive;
    b->traverse = traverse;
    b->frustum = frustum;
    stats->bytes = bvh_memory(b);
    *out = b;
    return 0;
}

static void bvh_intersect(const void *a, const accel_ray *rays, accel_hit *hits, size_t count,
                          accel_counters *c)
{
    const bvh *b = a;
    c = ACCEL_COUNTERS_ON(c);
    if (b->traverse == BVH_TRAVERSE_PACKET)
        bvh_packet_intersect(b, rays, hits, count, c);
    else
        bvh_trace_intersect(b, rays, hits, count, c);
}

static void bvh_occluded(const void *a, const accel_ray *rays, uint8_t *occ, size_t count,
                         accel_counters *c)
{
    const bvh *b = a;
    c = ACCEL_COUNTERS_ON(c);
    if (b->traverse == BVH_TRAVERSE_PACKET)
        bvh_packet_occluded(b, rays, occ, count, c);
    else
        bvh_trace_occluded(b, rays, occ, count, c);
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
    NULL,
};

const accel_kind accel_kind_bvh = {
    .name = "bvh",
    .summary = "binary BVH, 32-byte nodes: binned/sweep SAH or median builds; single rays or 64-ray packets",
    .step_name = "nodes",
    .params = bvh_params,
    .param_count = BVH_PARAM_COUNT,
    .variants = bvh_variants,
    .build = bvh_kind_build,
    .intersect = bvh_intersect,
    .occluded = bvh_occluded,
    .memory = bvh_memory,
    .destroy = bvh_destroy,
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

/* ---- saving and loading -------------------------------------------------- */

/* File header: 32 bytes, then nodes, prim ids, prim data. */
typedef struct {
    char magic[4];
    uint32_t version;
    uint32_t node_count;
    uint32_t prim_count;
    uint32_t tri_count;
    uint32_t flags; /* 1 has_spheres, 2 naive, 4 packet traversal, 8 frustum */
    int32_t depth;
    uint32_t reserved;
} bvh_file_header;

_Static_assert(sizeof(bvh_file_header) == 32, "the file header is 32 bytes");

static int host_little_endian(void)
{
    const uint32_t one = 1;
    unsigned char c;
    memcpy(&c, &one, 1);
    return c == 1;
}

int bvh_save(const void *accel, const char *path, accel_error *err)
{
    const bvh *b = accel;
    if (!host_little_endian())
        return accel_fail(err, ACCEL_ERR_IO, "%s: bvh files are little-endian; this host is not", path);
    FILE *f = fopen(path, "wb");
    if (!f) return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open for writing", path);
    bvh_file_header h;
    memset(&h, 0, sizeof h);
    memcpy(h.magic, "BVH1", 4);
    h.version = 1;
    h.node_count = b->node_count;
    h.prim_count = b->prim_count;
    h.tri_count = b->tri_count;
    h.flags = (b->has_spheres ? 1u : 0u) | (b->naive ? 2u : 0u) |
              (b->traverse == BVH_TRAVERSE_PACKET ? 4u : 0u) | (b->frustum ? 8u : 0u);
    h.depth = b->depth;
    int ok = fwrite(&h, sizeof h, 1, f) == 1;
    if (ok && b->node_count)
        ok = fwrite(b->nodes, sizeof(bvh_node), b->node_count, f) == b->node_count;
    if (ok && b->prim_count)
        ok = fwrite(b->prim_ids, sizeof(uint32_t), b->prim_count, f) == b->prim_count &&
             fwrite(b->prim_data, BVH_SLOT_FLOATS * sizeof(float), b->prim_count, f) == b->prim_count;
    if (fclose(f) != 0) ok = 0;
    return ok ? 0 : accel_fail(err, ACCEL_ERR_IO, "%s: write failed", path);
}

/* A file must describe a tree the kernels can walk safely: exactly the
 * layout the builder writes (child pairs numbered 2, 4, 6, ... in
 * depth-first order, so no node has two parents and none is its own
 * ancestor), leaves inside the slot array, no deeper than the traversal
 * stack, every node used. */
static int check_tree(const bvh *b, const char *path, accel_error *err)
{
    if (b->node_count == 0) return b->prim_count == 0 ? 0 : accel_fail(err, ACCEL_ERR_PARSE,
                                                                       "%s: primitives without nodes", path);
    struct { uint32_t node; int level; } stack[BVH_MAX_DEPTH + 1];
    int sp = 0, depth = 0;
    uint32_t next = 2;
    stack[sp].node = 0, stack[sp].level = 1, sp++;
    while (sp > 0) {
        sp--;
        uint32_t i = stack[sp].node;
        int level = stack[sp].level;
        if (level > BVH_MAX_DEPTH)
            return accel_fail(err, ACCEL_ERR_PARSE, "%s: tree deeper than %d levels", path, BVH_MAX_DEPTH);
        if (level > depth) depth = level;
        const bvh_node *n = &b->nodes[i];
        if (n->count) {
            if ((uint64_t)n->left_first + n->count > b->prim_count)
                return accel_fail(err, ACCEL_ERR_PARSE, "%s: node %u: leaf beyond the %u primitives",
                                  path, i, b->prim_count);
            continue;
        }
        uint32_t l = n->left_first;
        if (l != next || (uint64_t)l + 1 >= b->node_count)
            return accel_fail(err, ACCEL_ERR_PARSE, "%s: node %u: bad child index %u (expected %u)",
                              path, i, l, next);
        next += 2;
        stack[sp].node = l + 1, stack[sp].level = level + 1, sp++;
        stack[sp].node = l, stack[sp].level = level + 1, sp++;
    }
    if (b->node_count != (next == 2 ? 1 : next))
        return accel_fail(err, ACCEL_ERR_PARSE, "%s: %u nodes, the tree uses %u", path,
                          b->node_count, next == 2 ? 1 : next);
    if (depth != b->depth)
        return accel_fail(err, ACCEL_ERR_PARSE, "%s: header says depth %d, tree has %d", path,
                          b->depth, depth);
    return 0;
}

int bvh_load(const char *path, void **accel_out, accel_error *err)
{
    if (!host_little_endian())
        return accel_fail(err, ACCEL_ERR_IO, "%s: bvh files are little-endian; this host is not", path);
    FILE *f = fopen(path, "rb");
    if (!f) return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open", path);
    bvh_file_header h;
    int rc = 0;
    bvh *b = calloc(1, sizeof *b);
    if (!b) rc = accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory", path);
    if (!rc && fread(&h, sizeof h, 1, f) != 1)
        rc = accel_fail(err, ACCEL_ERR_PARSE, "%s: shorter than the 32-byte header", path);
    if (!rc && (memcmp(h.magic, "BVH1", 4) != 0 || h.version != 1))
        rc = accel_fail(err, ACCEL_ERR_PARSE, "%s: not a version 1 bvh file", path);
    if (!rc && (h.prim_count > 0x7FFFFFFFu || h.node_count > 2 * h.prim_count ||
                (h.prim_count > 0 && h.node_count == 0)))
        rc = accel_fail(err, ACCEL_ERR_PARSE, "%s: %u nodes for %u primitives", path, h.node_count,
                        h.prim_count);
    if (!rc) {
        b->node_count = h.node_count;
        b->prim_count = h.prim_count;
        b->tri_count = h.tri_count;
        b->has_spheres = (h.flags & 1) != 0;
        b->naive = (h.flags & 2) != 0;
        b->traverse = (h.flags & 4) ? BVH_TRAVERSE_PACKET : BVH_TRAVERSE_SINGLE;
        b->frustum = (h.flags & 8) != 0;
        b->depth = h.depth;
        b->nodes = bvh_alloc_nodes(h.node_count);
        b->prim_ids = bvh_alloc_array(h.prim_count, sizeof(uint32_t));
        b->prim_data = bvh_alloc_array(h.prim_count, BVH_SLOT_FLOATS * sizeof(float));
        if (!b->nodes || !b->prim_ids || !b->prim_data)
            rc = accel_fail(err, ACCEL_ERR_NOMEM, "%s: out of memory for %u nodes", path, h.node_count);
    }
    if (!rc && (fread(b->nodes, sizeof(bvh_node), h.node_count, f) != h.node_count ||
                fread(b->prim_ids, sizeof(uint32_t), h.prim_count, f) != h.prim_count ||
                fread(b->prim_data, BVH_SLOT_FLOATS * sizeof(float), h.prim_count, f) != h.prim_count))
        rc = accel_fail(err, ACCEL_ERR_PARSE, "%s: truncated", path);
    if (!rc) rc = check_tree(b, path, err);
    fclose(f);
    if (rc) {
        bvh_destroy(b);
        return rc;
    }
    *accel_out = b;
    return 0;
}
