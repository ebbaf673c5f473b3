/*
 * collapse.c - the wide BVH (`bvh:width=4|8`): the binary SAH tree
 * collapsed into 4- or 8-wide nodes, and the leaves packed into SoA blocks
 * of 4 or 8 primitives (layout in node.h). Both passes run inside
 * the kind's build, so they are part of the build time it reports.
 *
 * Two collapses. The greedy one (collapse=greedy; Wald et al., "Embree",
 * SIGGRAPH 2014, section 4.2; Pinto, "Fast BVH construction and refit",
 * 2010): a wide node made at binary node n starts from n's two children
 * and repeatedly opens (replaces by its two children) the interior child
 * of largest surface area, until it has W children or none can be opened.
 * Opening the largest box first removes the most expected node visits per
 * opening under the SAH: a child is visited with probability proportional
 * to its area, so the largest one is the costliest to leave as a separate
 * level. Every binary subtree of at most B primitives becomes one leaf
 * (one block): a block test costs about what one box test costs, so under
 * the SAH such a subtree is never worth a node of its own. Larger binary
 * leaves keep their primitives (one leaf of several blocks).
 *
 * The default, collapse=dp, chooses instead for every wide node the forest
 * of at most W subtrees of least SAH cost, leaves counted in blocks
 * (plan_dp below): it may open a small child before a large one, or keep
 * a subtree of two blocks as one leaf where that costs less (its
 * recurrence allows nodes of fewer than W children too). The greedy tree is one of the forests it compares, so its SAH
 * cost under the DP's own measure is never higher (tests/test_bvh_wide_collapse.c
 * checks that).
 *
 * Nodes are numbered in depth-first order (a node before its children, a
 * child's subtree before its next sibling's), leaves' blocks in the order
 * the collapse reaches them, so a depth-first walk streams memory forward.
 * Node and block indices depend only on the binary tree, so the wide tree
 * is as deterministic as the binary one (identical for any thread count).
 * That is layout=dfs; layout=bfs and layout=mixed place the same tree
 * otherwise afterwards (place_bfs, place_mixed; wide.h).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh/split_common.h"
#include "node.h"

#if defined(__AVX__) && !defined(BVH_NO_SIMD)
#include <immintrin.h>
#endif

/* A leaf to pack: its primitive slots in the binary tree's leaf order. */
typedef bvh_wide_pool_leaf leaf_job; /* node.h */

typedef struct {
    const bvh_node *bin;
    const uint32_t *sub_first, *sub_count; /* per binary node: its subtree's slots */
    const float *area;    /* per binary node: half surface area */
    int width, block;
    float *node_box;      /* row 0 of node 0; a node is node_floats floats */
    size_t node_floats;
    uint32_t node_count, node_cap;
    leaf_job *leaves;
    uint32_t leaf_count, leaf_cap;
    uint32_t block_count;
    int depth;
    double node_area, leaf_area; /* sums over the wide tree: nodes' areas, leaves' area x count */
    const char *failure;  /* set when a limit of the layout is exceeded */
    /* collapse=dp: per binary node n, dec[n * width + i - 1] is the choice
     * that gives the cheapest forest of at most i roots for n's subtree
     * (see plan_dp); split[n] the choice for n's own wide node. NULL for
     * the greedy collapse. */
    const uint8_t *dec, *split;
    int any_perm; /* any_order=area|leaf: store their orders in the perm rows */
} collapse_ctx;

static float *node_rows(collapse_ctx *x, uint32_t idx)
{
    return x->node_box + x->node_floats * idx;
}

static uint32_t *node_children(collapse_ctx *x, uint32_t idx)
{
    return (uint32_t *)(node_rows(x, idx) + 6 * x->width);
}

/* The octant orders of a node's k used children (see node.h), the
 * node's rows at `rows` (its child and perm arrays follow them):
 * children sorted by the projection of their box centre on each octant's
 * diagonal, nearest first (ties by slot); unused slots rank last. The
 * opposite octant (7 - o) gets the reverse order of the used slots. */
void bvh_wide_set_perm(float *rows, int w, int k)
{
    uint32_t *perm = (uint32_t *)(rows + 6 * w) + w;
    float cen[8][3];
    for (int i = 0; i < k; i++)
        for (int axis = 0; axis < 3; axis++)
            cen[i][axis] = 0.5f * rows[(2 * axis) * w + i] + 0.5f * rows[(2 * axis + 1) * w + i];
    for (int r = 0; r < w; r++) perm[r] = 0;
    for (int o = 0; o < 4; o++) {
        float key[8];
        int order[8];
        for (int i = 0; i < k; i++)
            key[i] = (o & 1 ? -cen[i][0] : cen[i][0]) + (o & 2 ? -cen[i][1] : cen[i][1]) + cen[i][2];
        /* Each child's rank counted without branches: the children before
         * it by (key, slot), which is the stable sort's order (ties keep
         * slot order). No key is a NaN: three finite terms may overflow to
         * an infinity, never to inf - inf. The insertion sort this replaces
         * took 3.2% of an 8-wide build on soup 1M, this 1.1% (perf). */
#if defined(__AVX__) && !defined(BVH_NO_SIMD)
        for (int i = k; i < 8; i++) key[i] = INFINITY; /* unused: after every used slot (j >= k) */
        const __m256 kv = _mm256_loadu_ps(key);
        const __m256i slot = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        for (int i = 0; i < k; i++) {
            __m256 ki = _mm256_set1_ps(key[i]);
            __m256 before = _mm256_or_ps(_mm256_cmp_ps(kv, ki, _CMP_LT_OQ),
                                         _mm256_and_ps(_mm256_cmp_ps(kv, ki, _CMP_EQ_OQ),
                                                       _mm256_castsi256_ps(_mm256_cmpgt_epi32(
                                                           _mm256_set1_epi32(i), slot))));
            /* unused lanes hold +inf: before a used key only if it is
             * +inf too, and then by slot (j >= k > i): never */
            order[__builtin_popcount((unsigned)_mm256_movemask_ps(before))] = i;
        }
#else
        for (int i = 0; i < k; i++) {
            int rank = 0;
            for (int j = 0; j < k; j++) rank += key[j] < key[i] || (key[j] == key[i] && j < i);
            order[rank] = i;
        }
#endif
        for (int r = 0; r < w; r++) {
            int fwd = r < k ? order[r] : r, rev = r < k ? order[k - 1 - r] : r;
            perm[r] |= (uint32_t)fwd << (3 * o) | (uint32_t)rev << (3 * (7 - o));
        }
    }
}

/* A binary node that becomes a leaf: a binary leaf, or a subtree that fits
 * one block. */
static int is_leaf(const collapse_ctx *x, uint32_t n)
{
    return x->bin[n].count > 0 || x->sub_count[n] <= (uint32_t)x->block;
}

static uint32_t make_leaf(collapse_ctx *x, uint32_t n)
{
    uint32_t count = x->sub_count[n];
    uint32_t blocks = (count + (uint32_t)x->block - 1) / (uint32_t)x->block;
    if (blocks > WIDE_LEAF_MAX_BLOCKS) {
        x->failure = "a leaf needs more than 64 blocks";
        return WIDE_EMPTY;
    }
    if (x->block_count + blocks > WIDE_MAX_BLOCKS || x->leaf_count >= x->leaf_cap) {
        x->failure = "more than 2^25 leaf blocks";
        return WIDE_EMPTY;
    }
    x->leaf_area += bvh_half_area(bvh_node_box(&x->bin[n])) * count; /* double: no overflow */
    leaf_job *j = &x->leaves[x->leaf_count++];
    j->first_slot = x->sub_first[n];
    j->count = count;
    j->first_block = x->block_count;
    x->block_count += blocks;
    return wide_leaf_ref(j->first_block, blocks);
}

/* ---- collapse=dp ------------------------------------------------------------- */

/*
 * The optimal collapse under a SAH cost (Ylitie, Karras and Laine,
 * "Efficient incoherent ray traversal on GPUs through compressed wide
 * BVHs", HPG 2017, section 3.1), with a leaf cost counted in blocks.
 * With A the half area, W the width, B the block size, for binary node n:
 *
 *   C(n, 1) = min(leaf(n), node(n))        n as one child: a leaf or a wide node
 *   C(n, i) = min(C(n, i - 1), dist(n, i))  at most i roots, i = 2..W
 *   dist(n, j) = min over 0 < k < j of C(left, k) + C(right, j - k)
 *   node(n) = A(n) + dist(n, W)            a wide node visit costs 1
 *   leaf(n) = A(n) * leaf_cost * ceil(N(n) / B)  (infinite over leaf_blocks blocks)
 *
 * A binary leaf is always a leaf: C(n, i) = leaf(n) for every i. Each
 * binary node costs (W - 1) W / 2 sums; one backward pass (children after
 * their parent) fills the table. dec[n][i - 1] records the choice: for
 * i = 1, 1 = wide node and 0 = leaf; for i > 1, 0 = "as i - 1" and k =
 * "k roots from the left child, i - k from the right". split[n] is the k
 * of dist(n, W) for n's own wide node.
 */
static void plan_dp(const bvh_node *bin, uint32_t nc, const uint32_t *sub_count, const float *area,
                    int width, int block, double leaf_cost, int leaf_blocks, float *cost, uint8_t *dec,
                    uint8_t *split)
{
    const int w = width;
    for (uint32_t n = nc; n-- > 0;) {
        float *c = cost + (size_t)n * w;
        uint8_t *d = dec + (size_t)n * w;
        uint32_t blocks = (sub_count[n] + (uint32_t)block - 1) / (uint32_t)block;
        float leaf = blocks <= (uint32_t)leaf_blocks || bin[n].count
                         ? (float)((double)area[n] * leaf_cost * blocks) : INFINITY;
        split[n] = 0;
        if (bin[n].count || (n == 1 && nc > 1)) { /* a binary leaf, or the padding node */
            for (int i = 0; i < w; i++) c[i] = leaf, d[i] = 0;
            continue;
        }
        const float *cl = cost + (size_t)bin[n].left_first * w, *cr = cl + w;
        float dist[9] = {0};
        uint8_t arg[9] = {0};
        for (int j = 2; j <= w; j++) {
            dist[j] = INFINITY, arg[j] = 1;
            for (int k = 1; k < j; k++) {
                float s = cl[k - 1] + cr[j - k - 1];
                if (s < dist[j]) dist[j] = s, arg[j] = (uint8_t)k;
            }
        }
        float node = area[n] + dist[w];
        split[n] = arg[w];
        /* Ties (and two infinities) go to the leaf when one is allowed. */
        int as_node = node < leaf || leaf == INFINITY;
        c[0] = as_node ? node : leaf, d[0] = (uint8_t)as_node;
        for (int i = 2; i <= w; i++) {
            int spread = dist[i] < c[i - 2];
            c[i - 1] = spread ? dist[i] : c[i - 2];
            d[i - 1] = spread ? arg[i] : 0;
        }
    }
}

/* Appends to set the roots of the cheapest forest of at most i roots for
 * binary node n's subtree (plan_dp's choices). */
static void dp_roots(const collapse_ctx *x, uint32_t n, int i, uint32_t *set, int *k)
{
    while (i > 1 && x->dec[(size_t)n * x->width + i - 1] == 0) i--;
    if (i == 1) {
        set[(*k)++] = n;
        return;
    }
    int left = x->dec[(size_t)n * x->width + i - 1];
    dp_roots(x, x->bin[n].left_first, left, set, k);
    dp_roots(x, x->bin[n].left_first + 1, i - left, set, k);
}

/* The wide node made at binary node n (or its leaf), at wide level `level`. */
static uint32_t collapse(collapse_ctx *x, uint32_t n, int level)
{
    if (level > x->depth) x->depth = level;
    if (x->failure) return WIDE_EMPTY;
    uint32_t set[8];
    int k = 0;
    if (x->dec) {
        if (x->bin[n].count || x->dec[(size_t)n * x->width] == 0) return make_leaf(x, n);
        int left = x->split[n];
        dp_roots(x, x->bin[n].left_first, left, set, &k);
        dp_roots(x, x->bin[n].left_first + 1, x->width - left, set, &k);
    } else {
        if (is_leaf(x, n)) return make_leaf(x, n);
        k = 2;
        set[0] = x->bin[n].left_first;
        set[1] = set[0] + 1;
    }
    /* Greedy: open the interior child of largest area until the node is
     * full (collapse=dp has chosen its k roots already). */
    while (!x->dec && k < x->width) {
        int best = -1;
        float best_area = -1.0f;
        for (int i = 0; i < k; i++) {
            if (is_leaf(x, set[i])) continue;
            if (x->area[set[i]] > best_area) best_area = x->area[set[i]], best = i;
        }
        if (best < 0) break;
        uint32_t m = set[best];
        set[best] = x->bin[m].left_first;
        set[k++] = x->bin[m].left_first + 1;
    }
    if (x->node_count >= x->node_cap) {
        x->failure = "node pool overflow";
        return WIDE_EMPTY;
    }
    uint32_t idx = x->node_count++;
    x->node_area += bvh_half_area(bvh_node_box(&x->bin[n]));
    const int w = x->width;
    for (int i = 0; i < w; i++) {
        float *rows = node_rows(x, idx);
        uint32_t *child = node_children(x, idx);
        if (i < k) {
            const bvh_node *c = &x->bin[set[i]];
            for (int axis = 0; axis < 3; axis++) {
                rows[(2 * axis) * w + i] = c->bmin[axis];
                rows[(2 * axis + 1) * w + i] = c->bmax[axis];
            }
        } else {
            for (int axis = 0; axis < 3; axis++) {
                rows[(2 * axis) * w + i] = INFINITY;
                rows[(2 * axis + 1) * w + i] = -INFINITY;
            }
            child[i] = WIDE_EMPTY;
        }
    }
    bvh_wide_set_perm(node_rows(x, idx), w, k);
    /* Children after their parent, each subtree in one run. */
    for (int i = 0; i < k; i++) {
        uint32_t ref = collapse(x, set[i], level + 1);
        node_children(x, idx)[i] = ref;
    }
    if (x->any_perm) bvh_wide_set_any_perm(node_rows(x, idx), w, k);
    return idx;
}

typedef struct {
    const bvh *b;
    bvh_wide *w;
    const leaf_job *leaves;
} pack_job;

/* Leaves to SoA blocks; the last block of a leaf is padded with copies of
 * the leaf's last primitive. */
static void pack_chunk(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    pack_job *j = p;
    const int bs = j->w->block;
    for (size_t l = begin; l < end; l++) {
        const leaf_job *leaf = &j->leaves[l];
        uint32_t blocks = (leaf->count + (uint32_t)bs - 1) / (uint32_t)bs;
        for (uint32_t k = 0; k < blocks; k++) {
            float *v;
            uint32_t *id;
            wide_block_rows(j->w, leaf->first_block + k, &v, &id);
            for (int lane = 0; lane < bs; lane++) {
                uint32_t i = k * (uint32_t)bs + (uint32_t)lane;
                uint32_t slot = leaf->first_slot + (i < leaf->count ? i : leaf->count - 1);
                wide_put_lane(v, bs, lane, j->b->prim_data + (size_t)BVH_SLOT_FLOATS * slot);
                id[lane] = j->b->prim_ids[slot];
            }
        }
    }
}

static size_t node_size(int width) { return width == 8 ? sizeof(wide_node8) : sizeof(wide_node4); }
static size_t tree_node_size(const bvh_wide *w)
{
    return w->quant ? sizeof(wide_qnode8) : node_size(w->width);
}

/* ---- quantized nodes (quant=1) -------------------------------------------------- */

void bvh_wide_qbox(const wide_qnode8 *n, int c, float *lo, float *hi)
{
    for (int a = 0; a < 3; a++) {
        float step = wide_qstep(n->ex[a]);
        lo[a] = wide_qdecode(n->org[a], n->q[2 * a][c], step);
        hi[a] = wide_qdecode(n->org[a], n->q[2 * a + 1][c], step);
    }
}

/* One axis of a node: the smallest step 2^e whose 255 steps from org reach
 * every child's upper plane after rounding, and each child's planes rounded
 * outward. Returns 0 when no exponent up to 127 fits (not for finite boxes). */
static int quantize_axis(const float *lo, const float *hi, int k, float org, uint8_t *qlo,
                         uint8_t *qhi, int8_t *ex_out)
{
    double top = -INFINITY;
    for (int i = 0; i < k; i++) top = hi[i] > top ? hi[i] : top;
    double ext = top - (double)org;
    int e = -126;
    if (ext > 0) {
        e = (int)ceil(log2(ext / 255.0));
        if (e < -126) e = -126;
    }
    for (; e <= 127; e++) {
        float step = wide_qstep(e);
        int ok = 1;
        for (int i = 0; i < k && ok; i++) {
            double fl = floor(((double)lo[i] - org) / step), fh = ceil(((double)hi[i] - org) / step);
            int a = fl < 0 ? 0 : fl > 255 ? 255 : (int)fl;
            int b = fh < 0 ? 0 : fh > 255 ? 255 : (int)fh;
            while (a > 0 && !(wide_qdecode(org, a, step) <= lo[i])) a--;
            while (b < 255 && !(wide_qdecode(org, b, step) >= hi[i])) b++;
            if (!(wide_qdecode(org, a, step) <= lo[i]) || !(wide_qdecode(org, b, step) >= hi[i])) ok = 0;
            qlo[i] = (uint8_t)a, qhi[i] = (uint8_t)b;
        }
        if (ok) {
            *ex_out = (int8_t)e;
            return 1;
        }
    }
    return 0;
}

/* The float node f (k used slots) as a quantized node. */
static int quantize_node(const wide_node8 *f, wide_qnode8 *q)
{
    int k = 0;
    while (k < 8 && f->child[k] != WIDE_EMPTY) k++;
    memset(q, 0, sizeof *q);
    q->count = (uint8_t)k;
    memcpy(q->child, f->child, sizeof q->child);
    memcpy(q->perm, f->perm, sizeof q->perm);
    for (int a = 0; a < 3; a++) {
        const float *lo = f->box[2 * a], *hi = f->box[2 * a + 1];
        float org = INFINITY;
        for (int i = 0; i < k; i++) org = lo[i] < org ? lo[i] : org;
        if (k == 0) org = 0.0f;
        q->org[a] = org;
        if (!quantize_axis(lo, hi, k, org, q->q[2 * a], q->q[2 * a + 1], &q->ex[a])) return 0;
    }
    return 1;
}
static size_t block_size(int block) { return block == 8 ? sizeof(wide_block8) : sizeof(wide_block4); }

static void *alloc_aligned(size_t n, size_t size)
{
    return accel_alloc_large(n ? n : 1, size, BVH_NODE_ALIGN);
}

/* The collapse's memory against the build's limit (max_mb, MiB; 0: none):
 * the binary tree it reads (nodes and leaf-order slots) plus `more` bytes
 * of its own. Fails with the whole account in the message. */
static int collapse_within(const bvh *b, const bvh_wide *w, double max_mb, double more, const char *what,
                           accel_error *err)
{
    double binary = (double)b->node_count * sizeof(bvh_node) +
                    (double)b->prim_count * (BVH_SLOT_FLOATS * sizeof(float) + sizeof(uint32_t));
    if (max_mb <= 0 || binary + more <= max_mb * 1048576.0) return 0;
    return accel_fail(err, ACCEL_ERR_RANGE,
                      "bvh: the width=%d,block=%d tree needs %.1f MiB (binary tree %.1f, %s %.1f), over "
                      "max_mb = %.1f MiB (raise max_mb, or larger leaves: leaf=, leaf_below=)",
                      w->width, w->block, (binary + more) / 1048576.0, binary / 1048576.0, what,
                      more / 1048576.0, max_mb);
}

/* Every binary node's run of primitive slots (sub_first, sub_count) and
 * half area; counts the interior nodes and leaves. Children come after
 * their parent, so one backward pass sees them first. Node 1 is padding. */
static void subtree_table(const bvh_node *bin, uint32_t nc, uint32_t *sub_first, uint32_t *sub_count,
                          float *area, uint32_t *interior, uint32_t *leaves)
{
    for (uint32_t i = nc; i-- > 0;) {
        area[i] = (float)bvh_half_area(bvh_node_box(&bin[i]));
        if (i == 1 && nc > 1) {
            sub_first[i] = sub_count[i] = 0;
        } else if (bin[i].count) {
            sub_first[i] = bin[i].left_first, sub_count[i] = bin[i].count;
            (*leaves)++;
        } else {
            uint32_t l = bin[i].left_first;
            sub_first[i] = sub_first[l], sub_count[i] = sub_count[l] + sub_count[l + 1];
            (*interior)++;
        }
    }
}

/* Collapses b's binary tree; fills w (nodes, blocks, counts, root). */
static int collapse_tree(const bvh *b, bvh_wide *w, const bvh_wide_collapse *cc, int threads, double ct,
                         double ci, double *sah, accel_error *err)
{
    const uint32_t nc = b->node_count;
    const bvh_node *bin = b->nodes;
    uint32_t *sub = bvh_alloc_array(nc, 3 * sizeof(uint32_t));
    if (!sub) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for the collapse");
    uint32_t *sub_first = sub, *sub_count = sub + nc;
    float *area = (float *)(sub + 2 * (size_t)nc);
    uint32_t interior = 0, leaves = 0;
    subtree_table(bin, nc, sub_first, sub_count, area, &interior, &leaves);
    /* The scratch, known before it is taken: the subtree table, the DP's
     * table, the wide nodes' upper bound and the leaf list. */
    const double scratch = (double)nc * 3 * sizeof(uint32_t) +
                           (cc->dp ? (double)nc * (w->width * sizeof(float) + w->width + 1) : 0.0) +
                           (double)(interior > 0 ? interior : 1) * node_size(w->width) +
                           (double)leaves * sizeof(leaf_job);
    if (collapse_within(b, w, cc->max_mb, scratch, "collapse tables", err)) {
        free(sub);
        return ACCEL_ERR_RANGE;
    }
    collapse_ctx x;
    memset(&x, 0, sizeof x);
    x.bin = bin, x.sub_first = sub_first, x.sub_count = sub_count, x.area = area;
    x.width = w->width, x.block = w->block;
    x.any_perm = w->any_order == WIDE_ANY_AREA || w->any_order == WIDE_ANY_LEAF;
    float *dp_cost = NULL;
    uint8_t *dp_dec = NULL;
    if (cc->dp) {
        dp_cost = bvh_alloc_array(nc, (size_t)w->width * sizeof(float));
        dp_dec = bvh_alloc_array(nc, (size_t)w->width + 1);
        if (!dp_cost || !dp_dec) {
            free(dp_cost), free(dp_dec), free(sub);
            return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for the collapse");
        }
        plan_dp(bin, nc, sub_count, area, w->width, w->block, cc->leaf_cost, cc->leaf_blocks, dp_cost,
                dp_dec, dp_dec + (size_t)nc * w->width);
        free(dp_cost);
        x.dec = dp_dec, x.split = dp_dec + (size_t)nc * w->width;
    }
    x.node_floats = node_size(w->width) / sizeof(float);
    /* A wide node has at least two children, so there are fewer wide nodes
     * than binary interior nodes, and fewer leaves than binary leaves. */
    x.node_cap = interior > 0 ? interior : 1;
    x.leaf_cap = leaves;
    x.node_box = alloc_aligned(x.node_cap, node_size(w->width));
    x.leaves = bvh_alloc_array(x.leaf_cap, sizeof(leaf_job));
    int rc = 0;
    if (!x.node_box || !x.leaves) {
        rc = accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for %u wide nodes", x.node_cap);
    } else {
        w->root = collapse(&x, 0, 1);
        /* The SAH cost of the wide tree, bvh_sah_cost's formula over its
         * nodes and leaves (a wide node visit counts ct, like a binary one). */
        const double root = bvh_half_area(bvh_node_box(&bin[0]));
        *sah = root > 0.0 ? (ct * x.node_area + ci * x.leaf_area) / root : NAN;
        if (x.failure)
            rc = accel_fail(err, ACCEL_ERR_RANGE, "bvh: width=%d,block=%d: %s", w->width, w->block,
                            x.failure);
    }
    /* Before the final pools are taken: all of the scratch counted, an
     * upper bound (the DP's table is already freed). */
    if (rc == 0)
        rc = collapse_within(b, w, cc->max_mb,
                             scratch + (double)x.node_count * tree_node_size(w) +
                                 (double)x.block_count * block_size(w->block) +
                                 (w->layout == WIDE_LAYOUT_MIXED
                                      ? (double)x.block_count * sizeof(uint64_t) + 64.0 * x.leaf_count
                                  : w->layout == WIDE_LAYOUT_BFS /* the renumbered copy */
                                      ? (double)x.node_count * node_size(w->width)
                                      : 0.0),
                             "collapse tables, wide nodes and leaf blocks", err);
    if (rc == 0 && w->layout == WIDE_LAYOUT_BFS && x.node_count) {
        /* the depth-first nodes renumbered level by level, into a copy */
        float *bfs = alloc_aligned(x.node_count, node_size(w->width));
        if (!bfs || bvh_wide_place_bfs(x.node_box, bfs, x.node_count, w->width, x.leaves, x.leaf_count, x.block_count)) {
            free(bfs);
            rc = accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for layout=bfs");
        } else {
            free(x.node_box);
            x.node_box = bfs;
        }
    }
    if (rc == 0 && w->layout == WIDE_LAYOUT_MIXED) {
        rc = bvh_wide_place_mixed(w, x.node_box, x.node_count, x.block_count, err); /* layout.c */
    } else if (rc == 0) {
        /* Keep exactly the nodes used, aligned. */
        w->nodes = alloc_aligned(x.node_count, tree_node_size(w));
        w->blocks = alloc_aligned(x.block_count, block_size(w->block));
        if (!w->nodes || !w->blocks) {
            rc = accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for %u leaf blocks",
                            x.block_count);
        } else if (w->quant) {
            const wide_node8 *f = (const wide_node8 *)x.node_box;
            wide_qnode8 *q = w->nodes;
            for (uint32_t i = 0; i < x.node_count && rc == 0; i++)
                if (!quantize_node(&f[i], &q[i]))
                    rc = accel_fail(err, ACCEL_ERR_RANGE, "bvh: quant=1: a node's boxes do not fit "
                                                          "8-bit steps of 2^127");
        } else {
            memcpy(w->nodes, x.node_box, (size_t)x.node_count * node_size(w->width));
        }
    }
    if (rc == 0 && w->nodes && w->blocks) {
        w->node_count = x.node_count;
        w->leaf_count = x.leaf_count;
        w->block_count = x.block_count;
        w->depth = x.depth;
        pack_job job = {b, w, x.leaves};
        accel_parallel_for(x.leaf_count, 1024, threads, pack_chunk, &job);
    }
    free(x.node_box);
    free(x.leaves);
    free(dp_dec);
    free(sub);
    return rc;
}

/* ---- a node pool collapsed for another structure ------------------------------ */

/* The greedy collapse of any pool laid out as bvh's (node 0 the root, node
 * 1 padding, children after their parent, each subtree's leaves one run of
 * slots): node.h's bvh_wide_pool. */
int bvh_wide_collapse_pool(const bvh_node *bin, uint32_t nc, int width, int block, bvh_wide_pool *out,
                           accel_error *err)
{
    memset(out, 0, sizeof *out);
    out->root = WIDE_EMPTY;
    if (!nc) return 0;
    uint32_t *sub = bvh_alloc_array(nc, 3 * sizeof(uint32_t));
    if (!sub) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for the collapse");
    uint32_t *sub_first = sub, *sub_count = sub + nc;
    float *area = (float *)(sub + 2 * (size_t)nc);
    uint32_t interior = 0, leaves = 0;
    subtree_table(bin, nc, sub_first, sub_count, area, &interior, &leaves);
    collapse_ctx x;
    memset(&x, 0, sizeof x);
    x.bin = bin, x.sub_first = sub_first, x.sub_count = sub_count, x.area = area;
    x.width = width, x.block = block;
    x.node_floats = node_size(width) / sizeof(float);
    x.node_cap = interior > 0 ? interior : 1;
    x.leaf_cap = leaves > 0 ? leaves : 1;
    x.node_box = alloc_aligned(x.node_cap, node_size(width));
    x.leaves = bvh_alloc_array(x.leaf_cap, sizeof(leaf_job));
    int rc = 0;
    if (!x.node_box || !x.leaves) {
        rc = accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory for %u wide nodes", x.node_cap);
    } else {
        uint32_t root = collapse(&x, 0, 1);
        if (x.failure)
            rc = accel_fail(err, ACCEL_ERR_RANGE, "bvh: width=%d,block=%d: %s", width, block, x.failure);
        else
            out->root = root;
    }
    free(sub);
    if (rc) {
        free(x.node_box);
        free(x.leaves);
        return rc;
    }
    out->nodes = x.node_box;
    out->node_count = x.node_count;
    out->leaves = x.leaves;
    out->leaf_count = x.leaf_count;
    out->block_count = x.block_count;
    out->depth = x.depth;
    return 0;
}

int bvh_wide_build(bvh *b, bvh_wide **out, int width, int block, int order, int quant,
                   const bvh_wide_collapse *cc, int threads, double ct, double ci, accel_build_stats *stats, accel_error *err)
{
    bvh_wide *w = calloc(1, sizeof *w);
    if (!w) return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: out of memory");
    w->quant = quant && width == 8;
    w->layout = cc->layout;
    w->any_order = cc->any_order;
    w->any_shift = cc->any_order == WIDE_ANY_AREA   ? WIDE_PERM_AREA_SHIFT
                   : cc->any_order == WIDE_ANY_LEAF ? WIDE_PERM_LEAF_SHIFT
                                                    : -1;
    w->width = width;
    w->block = block;
    w->order = order;
    w->tri_count = b->tri_count;
    w->prim_count = b->prim_count;
    w->root = WIDE_EMPTY;
    if (b->node_count > 0) {
        int rc = collapse_tree(b, w, cc, threads, ct, ci, &stats->sah_cost, err);
        if (rc) {
            bvh_wide_free(w);
            return rc;
        }
    }
    w->step_bound = w->node_count + w->leaf_count;
    /* The wide kernels never read the binary pools. */
    bvh_release(b);
    b->node_count = 0;
    b->depth = w->depth;
    *out = w;
    stats->nodes = w->node_count;
    stats->leaves = w->leaf_count;
    stats->depth = w->depth;
    return 0;
}
