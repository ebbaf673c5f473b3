/*
 * layout.c - where the wide tree's nodes and leaf blocks sit in memory
 * (layout=bfs|mixed) and the stored any-hit orders (any_order=area|leaf):
 * wide.h says what each parameter means. The collapse (collapse.c) makes
 * the tree in its depth-first numbering (layout=dfs) and calls these
 * afterwards; the kernels read the result (layout=mixed: k8_mixed.c;
 * any_order: k8_anyord.c).
 */
#include <stdlib.h>
#include <string.h>

#include "node.h"

static size_t wide_node_bytes(int width) { return width == 8 ? sizeof(wide_node8) : sizeof(wide_node4); }
static size_t wide_block_bytes(int block) { return block == 8 ? sizeof(wide_block8) : sizeof(wide_block4); }

/* any_order=area|leaf (wide.h): the orders any-hit queries visit a node's
 * k used children in, stored in bits 24..26 (area: the largest box first)
 * and 27..29 (leaf: leaf children first, most blocks first, then the
 * largest box; then node children, largest box first) of perm[rank]; ties
 * by slot, unused slots last. The node's child references must be set. */
void bvh_wide_set_any_perm(float *rows, int w, int k)
{
    uint32_t *child = (uint32_t *)(rows + 6 * w), *perm = child + w;
    double area[8];
    for (int i = 0; i < k; i++) {
        double d[3];
        for (int axis = 0; axis < 3; axis++)
            d[axis] = (double)rows[(2 * axis + 1) * w + i] - (double)rows[(2 * axis) * w + i];
        area[i] = d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
    }
    int by_area[8], by_leaf[8];
    for (int i = 0; i < k; i++) {
        int ra = 0, rl = 0;
        uint32_t bi = child[i] & WIDE_LEAF ? wide_leaf_blocks(child[i]) : 0;
        for (int j = 0; j < k; j++) {
            if (j == i) continue;
            int a_before = area[j] > area[i] || (area[j] == area[i] && j < i);
            uint32_t bj = child[j] & WIDE_LEAF ? wide_leaf_blocks(child[j]) : 0;
            /* leaves (bj > 0) before nodes, more blocks first, then by area */
            ra += a_before;
            rl += bj > bi || (bj == bi && a_before);
        }
        by_area[ra] = i, by_leaf[rl] = i;
    }
    for (int r = 0; r < w; r++) {
        uint32_t a = r < k ? (uint32_t)by_area[r] : (uint32_t)r, l = r < k ? (uint32_t)by_leaf[r] : (uint32_t)r;
        perm[r] = (perm[r] & ~(63u << WIDE_PERM_AREA_SHIFT)) | a << WIDE_PERM_AREA_SHIFT |
                  l << WIDE_PERM_LEAF_SHIFT;
    }
}



/* layout=bfs: the collapse's depth-first nodes (src, n of them, root 0)
 * copied to dst level by level (a node's children after every node of
 * its level), and the leaves' blocks renumbered in the order that walk
 * reaches them; leaves[].first_block follows. Children stay after their
 * parent, which the refit's backward pass needs. */
int bvh_wide_place_bfs(const float *src, float *dst, uint32_t n, int width, bvh_wide_pool_leaf *leaves,
                       uint32_t leaf_count, uint32_t block_count)
{
    const size_t nf = wide_node_bytes(width) / sizeof(float);
    uint32_t *order = malloc((size_t)(n ? n : 1) * sizeof *order);
    uint32_t *new_idx = malloc((size_t)(n ? n : 1) * sizeof *new_idx);
    uint32_t *new_first = malloc((size_t)(block_count ? block_count : 1) * sizeof *new_first);
    if (!order || !new_idx || !new_first) {
        free(order), free(new_idx), free(new_first);
        return 1;
    }
    uint32_t head = 0, tail = 0, blocks = 0;
    order[tail++] = 0;
    while (head < tail) {
        uint32_t o = order[head];
        new_idx[o] = head++;
        const uint32_t *child = (const uint32_t *)(src + nf * o + 6 * width);
        for (int c = 0; c < width; c++) {
            if (child[c] == WIDE_EMPTY) continue;
            if (child[c] & WIDE_LEAF) {
                new_first[wide_leaf_first(child[c])] = blocks;
                blocks += wide_leaf_blocks(child[c]);
            } else {
                order[tail++] = child[c];
            }
        }
    }
    for (uint32_t o = 0; o < n; o++) {
        float *d = dst + nf * new_idx[o];
        memcpy(d, src + nf * o, nf * sizeof(float));
        uint32_t *child = (uint32_t *)(d + 6 * width);
        for (int c = 0; c < width; c++) {
            uint32_t r = child[c];
            if (r == WIDE_EMPTY) continue;
            child[c] = r & WIDE_LEAF ? wide_leaf_ref(new_first[wide_leaf_first(r)], wide_leaf_blocks(r))
                                     : new_idx[r];
        }
    }
    for (uint32_t l = 0; l < leaf_count; l++) leaves[l].first_block = new_first[leaves[l].first_block];
    free(order), free(new_idx), free(new_first);
    return 0;
}

/* layout=mixed: byte offsets in the one pool, depth-first from node o:
 * the node, then the blocks of its leaf children (each leaf from a 64-byte
 * line), then its node children's subtrees in slot order. node_at[o] and
 * block_at[first block..] receive the offsets; *end the pool's size. */
typedef struct {
    const float *src;
    size_t nf, node_bytes, block_bytes;
    int width;
    uint64_t *node_at, *block_at;
    uint64_t end;
} mixed_place;

static uint64_t line_up(uint64_t b) { return (b + 63u) & ~(uint64_t)63u; }

static void place_leaf(mixed_place *m, uint32_t ref)
{
    uint32_t first = wide_leaf_first(ref), nb = wide_leaf_blocks(ref);
    for (uint32_t k = 0; k < nb; k++) m->block_at[first + k] = m->end + k * m->block_bytes;
    m->end = line_up(m->end + nb * m->block_bytes);
}

static void place_mixed(mixed_place *m, uint32_t o)
{
    m->node_at[o] = m->end;
    m->end += m->node_bytes;
    const uint32_t *child = (const uint32_t *)(m->src + m->nf * o + 6 * m->width);
    for (int c = 0; c < m->width; c++)
        if (child[c] != WIDE_EMPTY && (child[c] & WIDE_LEAF)) place_leaf(m, child[c]);
    for (int c = 0; c < m->width; c++)
        if (child[c] != WIDE_EMPTY && !(child[c] & WIDE_LEAF)) place_mixed(m, child[c]);
}

/* The nodes copied into the pool at their places, references rewritten to
 * 64-byte lines. Fails (1) when a line number exceeds a reference's field. */
static int fill_mixed(const mixed_place *m, char *pool, uint32_t n)
{
    for (uint32_t o = 0; o < n; o++) {
        float *d = (float *)(pool + m->node_at[o]);
        memcpy(d, m->src + m->nf * o, m->node_bytes);
        uint32_t *child = (uint32_t *)(d + 6 * m->width);
        for (int c = 0; c < m->width; c++) {
            uint32_t r = child[c];
            if (r == WIDE_EMPTY) continue;
            uint64_t line = (r & WIDE_LEAF ? m->block_at[wide_leaf_first(r)] : m->node_at[r]) >> WIDE_LINE_SHIFT;
            if (line >= (r & WIDE_LEAF ? (uint64_t)WIDE_MAX_BLOCKS : (uint64_t)WIDE_LEAF)) return 1;
            child[c] = r & WIDE_LEAF ? wide_leaf_ref((uint32_t)line, wide_leaf_blocks(r)) : (uint32_t)line;
        }
    }
    return 0;
}

int bvh_wide_place_mixed(bvh_wide *w, const float *nodes, uint32_t node_count, uint32_t block_count,
                         accel_error *err)
{
    mixed_place m = {nodes, wide_node_bytes(w->width) / sizeof(float), wide_node_bytes(w->width),
                     wide_block_bytes(w->block), w->width, NULL, NULL, 0};
    m.node_at = malloc((size_t)(node_count ? node_count : 1) * sizeof *m.node_at);
    w->block_at = malloc((size_t)(block_count ? block_count : 1) * sizeof *w->block_at);
    m.block_at = w->block_at;
    if (!m.node_at || !w->block_at) {
        free(m.node_at);
        return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for layout=mixed");
    }
    if (w->root == WIDE_EMPTY) {
    } else if (w->root & WIDE_LEAF) {
        place_leaf(&m, w->root);
        w->root = wide_leaf_ref(0, wide_leaf_blocks(w->root));
    } else {
        place_mixed(&m, w->root);
        w->root = 0;
    }
    w->pool_bytes = (size_t)m.end;
    char *pool = accel_alloc_large(m.end / 64 ? (size_t)(m.end / 64) : 1, 64, BVH_NODE_ALIGN);
    int rc = 0;
    if (!pool) {
        rc = accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for the layout=mixed pool");
    } else {
        memset(pool, 0, (size_t)m.end); /* the padding after a leaf of blocks of 4 */
        w->nodes = w->blocks = pool;
        if (fill_mixed(&m, pool, node_count))
            rc = accel_fail(err, ACCEL_ERR_RANGE, "bvh: layout=mixed: a pool over 2 GiB (leaf "
                                                  "references count 2^25 lines)");
    }
    free(m.node_at);
    return rc;
}

/* The pools by layout (layout=mixed: one pool, and the block offsets). */
size_t bvh_wide_memory(const bvh_wide *w)
{
    if (w->layout == WIDE_LAYOUT_MIXED)
        return sizeof *w + w->pool_bytes + (size_t)w->block_count * sizeof *w->block_at;
    return sizeof *w + (size_t)w->node_count * (w->quant ? sizeof(wide_qnode8) : wide_node_bytes(w->width)) +
           (size_t)w->block_count * wide_block_bytes(w->block);
}

void bvh_wide_free(bvh_wide *w)
{
    if (!w) return;
    if (w->blocks != w->nodes) free(w->blocks); /* layout=mixed: one pool */
    free(w->nodes);
    free(w->block_at);
    free(w);
}
