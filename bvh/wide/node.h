/*
 * node.h - the memory layout of the wide BVHs (`bvh:width=4|8`),
 * shared by the collapse (collapse.c) and the kernels (trace.c,
 * k*_*.c, tables.h, kernel.h, core/block_test.h), the walk and the refit. Internal
 * to bvh/wide/ (the kind sees wide.h).
 *
 * A wide node holds the boxes of its up to W children in SoA form, one row
 * of W floats per box plane, so that one ray meets all W boxes in one
 * sequence of W-lane vector instructions (the layout of Embree's BVH4/BVH8
 * nodes; Wald et al., "Embree: A Kernel Framework for Efficient CPU Ray
 * Tracing", SIGGRAPH 2014):
 *
 *   width 8 (256 bytes, 4 cache lines, 64-byte aligned)
 *     offset   0  float box[6][8]   192 bytes: rows lo_x, hi_x, lo_y, hi_y, lo_z, hi_z
 *     offset 192  uint32 child[8]    32 bytes: child references (below)
 *     offset 224  uint32 perm[8]     32 bytes: child order per ray octant (below)
 *   width 4 (128 bytes, 2 cache lines)
 *     offset   0  float box[6][4]    96 bytes
 *     offset  96  uint32 child[4]    16 bytes
 *     offset 112  uint32 perm[4]     16 bytes
 *
 * perm serves order=octant: for each of the 8 octants of ray directions
 * (o = sign bits of x, y, z), bits 3o..3o+2 of perm[r] name the child of
 * rank r when the children are sorted by their box centres along the
 * octant's diagonal direction (nearest first), the precomputed order of
 * Fuetterling et al., "Accelerated Single Ray Tracing for Wide Vector
 * Units", HPG 2017. Bits 24..26 and 27..29 hold the orders of
 * any_order=area and any_order=leaf (wide.h) when the tree was built with
 * one of them, and are 0 otherwise.
 *
 * An unused child slot has the empty box lo = +inf, hi = -inf, which the
 * slab test rejects for every ray (its far distance is -inf or NaN).
 *
 * A child reference is a node index (bit 31 clear) or a leaf (bit 31 set):
 *
 *   bit 31      1
 *   bits 25..30 number of leaf blocks - 1 (1..64 blocks)
 *   bits  0..24 first leaf block (at most 2^25 blocks in a tree)
 *
 * With layout=mixed (wide.h) nodes and blocks share one pool and both a
 * node index and a first block count 64-byte lines from its start.
 *
 * A leaf block holds B = 4 or 8 primitives in SoA form, the three vertices'
 * coordinates as rows of B floats, followed by the B scene ids:
 *
 *   block of 4 (160 bytes)  float v[3][3][4] 144 bytes, uint32 id[4] 16 bytes
 *   block of 8 (320 bytes)  float v[3][3][8] 288 bytes, uint32 id[8] 32 bytes
 *
 * v[vertex][axis][lane], so the watertight test (Woop et al. 2013) reads
 * the rows of the ray's permuted axes kx, ky, kz by offset, exactly as the
 * scalar test picks components. A sphere lane holds its centre in vertex 0
 * and its radius in v[1][0]; its id (>= the scene's tri_count) marks it.
 * A leaf's last block is padded with copies of its last primitive: a
 * duplicate lane answers like its original (same t, same id), so the
 * kernels need no lane mask.
 */
#ifndef BVH_WIDE_NODE_H
#define BVH_WIDE_NODE_H

#include <assert.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "bvh/bvh_node.h"
#include "core/block.h"
#include "core/variant.h"
#include "wide.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    float box[6][8];
    uint32_t child[8];
    uint32_t perm[8];
} wide_node8;

typedef struct {
    float box[6][4];
    uint32_t child[4];
    uint32_t perm[4];
} wide_node4;

/* The leaf blocks are the shared primitive blocks (core/block.h). */
typedef accel_block8 wide_block8;
typedef accel_block4 wide_block4;

/*
 * quant=1 (width 8, single rays): the node's child boxes as 8-bit offsets
 * from the node's own lower corner org, in steps of 2^ex[axis] per axis,
 * rounded outward (a decoded box always holds the child's box: the build
 * checks every decoded plane with the kernel's own float operations,
 * org + q * 2^ex, whose product is exact). 128 bytes, two cache lines:
 *   offset  0  uint8 q[6][8]   rows lo_x, hi_x, lo_y, hi_y, lo_z, hi_z
 *   offset 48  float org[3]
 *   offset 60  int8 ex[3], uint8 count (used child slots, the first ones)
 *   offset 64  uint32 child[8], offset 96 uint32 perm[8] (as wide_node8)
 * After the collapse the float nodes are freed: the quantized pool is the
 * only one (refit rebuilds such a tree; the walk decodes the boxes).
 */
typedef struct {
    uint8_t q[6][8];
    float org[3];
    int8_t ex[3];
    uint8_t count;
    uint32_t child[8];
    uint32_t perm[8];
} wide_qnode8;

static_assert(sizeof(wide_qnode8) == 128, "a quantized 8-wide node is two cache lines");

/* A quantized axis's step 2^e as a float, e in [-126, 127]. */
static inline float wide_qstep(int e)
{
    uint32_t u = (uint32_t)(e + 127) << 23;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* A decoded plane, as the kernel computes it lane by lane: q * step is
 * exact (8 bits times a power of two), the sum is rounded once. */
static inline float wide_qdecode(float org, int q, float step)
{
    float prod = (float)q * step;
    return org + prod;
}
static_assert(offsetof(wide_qnode8, child) == 64, "child references start the second line");
static_assert(sizeof(wide_node8) == 256, "an 8-wide node is four cache lines");
static_assert(offsetof(wide_node8, child) == 192, "child references follow the 6 box rows");
static_assert(sizeof(wide_node4) == 128, "a 4-wide node is two cache lines");
static_assert(offsetof(wide_node4, child) == 96, "child references follow the 6 box rows");

/* Child references. */
#define WIDE_LEAF 0x80000000u
#define WIDE_LEAF_SHIFT 25
#define WIDE_LEAF_MAX_BLOCKS 64u              /* blocks in one leaf */
#define WIDE_MAX_BLOCKS (1u << WIDE_LEAF_SHIFT) /* blocks in one tree */
#define WIDE_EMPTY 0xFFFFFFFFu                /* no tree (empty scene); also unused slots */

static inline uint32_t wide_leaf_ref(uint32_t first_block, uint32_t blocks)
{
    return WIDE_LEAF | (blocks - 1) << WIDE_LEAF_SHIFT | first_block;
}
static inline uint32_t wide_leaf_first(uint32_t ref) { return ref & (WIDE_MAX_BLOCKS - 1); }
static inline uint32_t wide_leaf_blocks(uint32_t ref)
{
    return ((ref & ~WIDE_LEAF) >> WIDE_LEAF_SHIFT) + 1;
}

/* The collapsed tree is never deeper than the binary one (BVH_MAX_DEPTH
 * levels), and a node pushes at most W-1 entries, so a traversal stack of
 * WIDE_STACK entries cannot overflow. */
#define WIDE_STACK(w) (BVH_MAX_DEPTH * ((w) - 1) + 1)

typedef struct {
    uint32_t ref;
    float t_entry;
} wide_stack_entry;

/*
 * The greedy collapse (collapse.c) of a node pool laid out as bvh's (node
 * 0 the root, node 1 padding, children after their parent, each subtree's
 * leaves one run of slots) into nodes of `width` children, for a structure
 * other than the kind (instanced/: both of its BVH levels). A subtree of at
 * most `block` slots, and every binary leaf, becomes one leaf; each leaf's
 * slots take ceil(count / block) consecutive blocks of the caller's pool,
 * which the caller fills (leaves[k]: slots first_slot.. of the pool's leaf
 * order, count of them, from block first_block). nodes is 64-byte aligned,
 * each node's boxes the very boxes of its binary children, with the octant
 * orders (perm) set; freed with free(), as leaves.
 */
typedef struct {
    uint32_t first_slot, count, first_block;
} bvh_wide_pool_leaf;
typedef struct {
    void *nodes;          /* wide_node4 or wide_node8 */
    uint32_t node_count;
    uint32_t root;        /* node, leaf reference or WIDE_EMPTY (no nodes) */
    bvh_wide_pool_leaf *leaves;
    uint32_t leaf_count, block_count;
    int depth;
} bvh_wide_pool;
int bvh_wide_collapse_pool(const bvh_node *bin, uint32_t nc, int width, int block, bvh_wide_pool *out,
                           accel_error *err);

/* Recomputes a node's octant orders (perm) from its box rows; its first k
 * child slots are used (collapse.c; bvh_refit.c calls it after a refit). */
void bvh_wide_set_perm(float *rows, int width, int k);
/* Stores any_order=area's and any_order=leaf's child orders in a node's
 * perm rows (bits 24..29, wide.h); its k used slots' boxes and child
 * references must be set (collapse.c). */
void bvh_wide_set_any_perm(float *rows, int width, int k);
/* layout=bfs (layout.c): the depth-first nodes src (n, root 0) copied to
 * dst level by level, the leaves' blocks renumbered in that order
 * (leaves[].first_block follows). Returns 1 when out of memory. */
int bvh_wide_place_bfs(const float *src, float *dst, uint32_t n, int width, bvh_wide_pool_leaf *leaves,
                       uint32_t leaf_count, uint32_t block_count);
/* layout=mixed (layout.c): the one pool of w (w->nodes == w->blocks) with
 * the depth-first nodes (node_count of them, root 0, references to block
 * indices) placed in it, references rewritten to 64-byte lines, w->root,
 * w->pool_bytes and w->block_at set; the blocks are left to pack. */
int bvh_wide_place_mixed(bvh_wide *w, const float *nodes, uint32_t node_count, uint32_t block_count,
                         accel_error *err);
/* The decoded box of child c of a quantized node (lo[3], hi[3]). */
void bvh_wide_qbox(const wide_qnode8 *n, int c, float *lo, float *hi);
/* Block k of w's pool as its rows (v[(3 * vertex + axis) * block + lane])
 * and ids, for either block size. */
static inline void wide_block_rows(const bvh_wide *w, uint32_t k, float **v, uint32_t **id)
{
    if (w->block_at) { /* layout=mixed: the block's place in the one pool */
        char *at = (char *)w->nodes + w->block_at[k];
        *v = (float *)at;
        *id = (uint32_t *)(at + (w->block == 8 ? offsetof(wide_block8, id) : offsetof(wide_block4, id)));
        return;
    }
    if (w->block == 8) {
        wide_block8 *blk = (wide_block8 *)w->blocks + k;
        *v = blk->v[0][0], *id = blk->id;
    } else {
        wide_block4 *blk = (wide_block4 *)w->blocks + k;
        *v = blk->v[0][0], *id = blk->id;
    }
}

/* The bytes of node reference ref and of leaf reference ref's first block,
 * for every layout (layout=mixed: both count 64-byte lines of the one
 * pool); the walk's and the tests' form (the kernels compile their own). */
#define WIDE_LINE_SHIFT 6
static inline const char *wide_node_addr(const bvh_wide *w, uint32_t ref)
{
    size_t bytes = w->quant ? sizeof(wide_qnode8) : w->width == 8 ? sizeof(wide_node8) : sizeof(wide_node4);
    return (const char *)w->nodes + (w->layout == WIDE_LAYOUT_MIXED ? (size_t)ref << WIDE_LINE_SHIFT
                                                                     : bytes * ref);
}
static inline const char *wide_leaf_addr(const bvh_wide *w, uint32_t ref)
{
    size_t bytes = w->block == 8 ? sizeof(wide_block8) : sizeof(wide_block4);
    return w->layout == WIDE_LAYOUT_MIXED
               ? (const char *)w->nodes + ((size_t)wide_leaf_first(ref) << WIDE_LINE_SHIFT)
               : (const char *)w->blocks + bytes * wide_leaf_first(ref);
}

/* One lane of a block's rows from a primitive slot (9 floats). */
static inline void wide_put_lane(float *v, int block, int lane, const float *slot)
{
    accel_block_put_lane(v, block, lane, slot);
}

/* The kernel tables' rows: single rays (order=octant or dist), packets,
 * order=branchy, quant=1 (width 8 only), streams (traverse=stream). */
#define WIDE_ROW_SINGLE 0
#define WIDE_ROW_PACKET 1
#define WIDE_ROW_BRANCHY 2
#define WIDE_ROW_QUANT 3
#define WIDE_ROW_STREAM 4
#define WIDE_ROW_MIXED 5 /* layout=mixed (width 8): single rays on the one pool */
#define WIDE_ROW_ANY 6   /* any_order=octant|area|leaf (width 8): any-hit queries only */

/* One row's kernel table of one width, for a query and a block size: each
 * defined by its own unit, k<width>_<row>.c (tables.h; the packet row one
 * unit per query, k<width>_packet_<query>.c), and dispatched by trace.c.
 * Every unit is compiled twice (Makefile): for the baseline (AVX2) and,
 * with WIDE_AVX512_UNIT defined, for AVX-512, whose functions carry the
 * suffix _avx512 (WIDE_UNIT names a unit's own function). */
#ifdef WIDE_AVX512_UNIT
#define WIDE_UNIT(name) name##_avx512
#else
#define WIDE_UNIT(name) name
#endif
typedef const accel_kernel_table *(*wide_row_fn)(int any_hit, int block8);
#define WIDE_UNITS_DECLARE(sfx)                                                                     \
    const accel_kernel_table *bvh_wide_k4_single##sfx(int any_hit, int block8);                    \
    const accel_kernel_table *bvh_wide_k4_packet_hit##sfx(int block8);                             \
    const accel_kernel_table *bvh_wide_k4_packet_any##sfx(int block8);                             \
    const accel_kernel_table *bvh_wide_k4_branchy##sfx(int any_hit, int block8);                   \
    const accel_kernel_table *bvh_wide_k8_single##sfx(int any_hit, int block8);                    \
    const accel_kernel_table *bvh_wide_k8_packet_hit##sfx(int block8);                             \
    const accel_kernel_table *bvh_wide_k8_packet_any##sfx(int block8);                             \
    const accel_kernel_table *bvh_wide_k8_branchy##sfx(int any_hit, int block8);                   \
    const accel_kernel_table *bvh_wide_k8_quant##sfx(int any_hit, int block8);                     \
    const accel_kernel_table *bvh_wide_k8_mixed##sfx(int any_hit, int block8);                     \
    const accel_kernel_table *bvh_wide_k8_anyord##sfx(int any_hit, int block8);                    \
    const accel_kernel_table *bvh_wide_k4_stream_hit##sfx(int block8);                             \
    const accel_kernel_table *bvh_wide_k4_stream_any##sfx(int block8);                             \
    const accel_kernel_table *bvh_wide_k8_stream_hit##sfx(int block8);                             \
    const accel_kernel_table *bvh_wide_k8_stream_any##sfx(int block8);
WIDE_UNITS_DECLARE()
WIDE_UNITS_DECLARE(_avx512)

#ifdef __cplusplus
}
#endif

#endif
