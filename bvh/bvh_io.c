/*
 * bvh_io.c - saving a built `bvh` to a file and loading it back. The file
 * is the relocatable pool itself (nodes, primitive ids, primitive slots)
 * behind a 32-byte header; the loader accepts only the builder's exact
 * layout, so a loaded tree obeys every invariant the kernels rely on.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "split_common.h"
#include "bvh.h"

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
    if (!b->path->saveable)
        return accel_fail(err, ACCEL_ERR_SPEC, "%s: only binary trees (width=2) can be saved", path);
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
        b->path = bvh_binary_path(b->traverse);
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
        bvh_release(b);
        free(b);
        return rc;
    }
    *accel_out = b;
    return 0;
}
