/*
 * bvh_node.h - the BVH's memory layout, shared by the builders and the
 * traversal kernels (internal to bvh/; the public header is bvh.h).
 *
 * The node is the lecture's 32-byte node (see ../shared/LECTURE.md, 2):
 *
 *   offset  0  float bmin[3]     12 bytes
 *   offset 12  uint32 left_first  4 bytes: leaf: first primitive slot;
 *                                          interior: left child (right = left + 1)
 *   offset 16  float bmax[3]     12 bytes
 *   offset 28  uint32 count       4 bytes: > 0 for a leaf, 0 for an interior node
 *
 * All nodes live in one 64-byte aligned pool. The root is node 0, node 1 is
 * padding, and every child pair starts at an even index, so the two children
 * an interior node tests together always share one 64-byte cache line. A
 * tree over N primitives has at most N leaves, hence at most N-1 interior
 * nodes and 2 + 2(N-1) = 2N nodes with the padding: the lecture's "2N".
 *
 * Nothing in the structure is a pointer: nodes name their children and
 * primitives by index, so the pools can be written to a file and read back
 * anywhere (bvh_save / bvh_load in bvh.c).
 *
 * Primitives are stored in leaf order: slot i holds the 9 floats of a
 * triangle (v0, v1, v2) or the 4 floats of a sphere (centre, radius) in the
 * first 4 of its 9, and prim_ids[i] the scene id reported in hits. A leaf's
 * primitives are then one contiguous run of memory.
 */
#ifndef BVH_BVH_NODE_H
#define BVH_BVH_NODE_H

#include <assert.h>
#include <stddef.h>
#include <stdint.h>

#include "core/prim.h"
#include "core/variant.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    float bmin[3];
    uint32_t left_first;
    float bmax[3];
    uint32_t count;
} bvh_node;

static_assert(sizeof(bvh_node) == 32, "bvh_node must be the lecture's 32-byte node");
static_assert(offsetof(bvh_node, left_first) == 12, "left_first follows bmin");
static_assert(offsetof(bvh_node, bmax) == 16, "bmax starts the second 16 bytes");
static_assert(offsetof(bvh_node, count) == 28, "count closes the node");

/* Index of bmax[0] in the node seen as 8 floats: the slab test picks a
 * plane as ((const float *)node)[axis + (near or far offset)]. */
#define BVH_BMAX_OFS 4

/* Alignment of the node pool: one cache line holds a sibling pair. */
#define BVH_NODE_ALIGN 64

/* Floats per primitive slot (a triangle's three vertices). */
#define BVH_SLOT_FLOATS 9

/* The builders never make a tree deeper than this (the root is level 1),
 * so a traversal stack of BVH_MAX_DEPTH entries cannot overflow: each entry
 * is a far child of one node on the current root-to-node path. */
#define BVH_MAX_DEPTH 64

/* Traversal modes (parameter traverse=). */
enum { BVH_TRAVERSE_SINGLE = 0, BVH_TRAVERSE_PACKET = 1 };

/* Rays per packet: the 8x8 screen tiles the primary ray sets emit. */
#define BVH_PACKET_SIZE 64

/* SIMD paths (SSE in the binned builder, AVX in the packet kernel); build
 * with -DBVH_NO_SIMD to compare against their scalar twins. */
#if defined(__SSE2__) && !defined(BVH_NO_SIMD)
#define BVH_SSE 1
#else
#define BVH_SSE 0
#endif
#if defined(__AVX__) && !defined(BVH_NO_SIMD)
#define BVH_AVX 1
#else
#define BVH_AVX 0
#endif

/* The built structure. Immutable after build, but for the kind's update
 * (bvh_refit.c), which copies the primitives again and refits the boxes. */
typedef struct bvh {
    bvh_node *nodes;      /* node_count nodes, BVH_NODE_ALIGN-aligned */
    uint32_t node_count;  /* 0 for an empty scene */
    uint32_t prim_count;  /* primitive slots (live primitives with finite bounds) */
    float *prim_data;     /* BVH_SLOT_FLOATS floats per slot, in leaf order */
    uint32_t *prim_ids;   /* scene id of each slot */
    uint32_t tri_count;   /* scene ids >= tri_count are spheres */
    int has_spheres;
    int naive;            /* tri=naive: Moller-Trumbore instead of watertight */
    int traverse;         /* BVH_TRAVERSE_* */
    int frustum;          /* packets: interval-arithmetic early-out */
    int depth;            /* levels of the tree (a lone leaf is 1) */
    struct bvh_wide *wide; /* width=4|8: the collapsed tree (wide_node.h), else NULL */
    uint32_t scene_prims; /* the scene's triangles + spheres at build (0: loaded from a file) */
    struct bvh_rebuild *rebuild; /* the build's options, for update's rebuild (bvh.c); NULL if loaded */
    int first_left;       /* first=left: single rays always visit the left hit child first */
    void *nodes_block;    /* pairs=split: the allocation nodes points 32 bytes into, else NULL */
} bvh;

/* ---- pieces of the traversal kernels -------------------------------------- */

/* Per-ray slab-test constants: plane offsets picked once per ray by the
 * direction's sign bit, so the box test has no per-node branch. */
typedef struct {
    float ox, oy, oz;
    float ix, iy, iz;     /* 1/dir, IEEE: +-inf for a +-0 component */
    float fix, fiy, fiz;  /* far planes: 1/dir accel_far_factor (core/geom.h) */
    int nx, ny, nz;       /* float index of the near plane on each axis: 0 or BVH_BMAX_OFS */
    int fx, fy, fz;       /* ... and of the far plane: the other one */
    int folded;           /* accel_far_folded: else the far distance padded after the minimum */
} bvh_slab_ray;

static inline void bvh_slab_setup(bvh_slab_ray *s, const accel_ray_prep *p)
{
    s->ox = p->org.x, s->oy = p->org.y, s->oz = p->org.z;
    s->ix = p->inv_dir.x, s->iy = p->inv_dir.y, s->iz = p->inv_dir.z;
    s->folded = accel_far_folded(p->t_near);
    float pf = accel_far_factor(s->folded);
    s->fix = s->ix * pf, s->fiy = s->iy * pf, s->fiz = s->iz * pf;
    s->nx = p->neg[0] ? BVH_BMAX_OFS : 0;
    s->ny = p->neg[1] ? BVH_BMAX_OFS : 0;
    s->nz = p->neg[2] ? BVH_BMAX_OFS : 0;
    s->fx = BVH_BMAX_OFS - s->nx, s->fy = BVH_BMAX_OFS - s->ny, s->fz = BVH_BMAX_OFS - s->nz;
}

/*
 * The robust slab test of geom.h's box3_slab (Ize, "Robust BVH Ray
 * Traversal", JCGT 2(2), 2013) with the planes addressed by offset: the same
 * products (plane - origin) * inv_dir, the same NaN handling (a 0*inf from a
 * zero direction component with the origin on a plane is dropped by
 * maxf/minf, so the ray counts as inside that slab). The far distance's
 * padding is folded into the ray (ACCEL_FAR_PAD, core/geom.h: the far
 * planes' reciprocals and t_far scaled before the minimum, off the path
 * from the node's load to the answer), or for a ray with t_near < 0 the
 * 2*gamma(3) padding after it. Returns nonzero when the box overlaps
 * [t_near, t_far]; *t_entry gets the entry distance.
 */
static inline __attribute__((always_inline)) int
bvh_slab(const bvh_node *node, const bvh_slab_ray *r, float t_near, float t_far, float *t_entry)
{
    const float *b = (const float *)node;
    float t0 = t_near, t1 = accel_far_limit(t_far, r->folded);
    t0 = maxf(t0, (b[r->nx] - r->ox) * r->ix);
    t0 = maxf(t0, (b[1 + r->ny] - r->oy) * r->iy);
    t0 = maxf(t0, (b[2 + r->nz] - r->oz) * r->iz);
    t1 = minf(t1, (b[r->fx] - r->ox) * r->fix);
    t1 = minf(t1, (b[1 + r->fy] - r->oy) * r->fiy);
    t1 = minf(t1, (b[2 + r->fz] - r->oz) * r->fiz);
    *t_entry = t0;
    if (!r->folded) t1 += fabsf(t1) * ACCEL_SLAB_PAD;
    return t0 <= t1;
}

/* Intersects slot `slot` (flags are constants in every kernel copy). */
static inline __attribute__((always_inline)) int
bvh_slot_hit(const bvh *b, uint32_t slot, const accel_ray_prep *p, float *t, float *u, float *v,
             int naive, int has_spheres)
{
    const float *data = b->prim_data + (size_t)BVH_SLOT_FLOATS * slot;
    if (has_spheres && b->prim_ids[slot] >= b->tri_count) return accel_sphere_hit(p, data, t, u, v);
    return naive ? accel_tri_naive(p, data, t, u, v) : accel_tri_watertight(p, data, t, u, v);
}

/* A node's box as a box3, and back (builders and the statistics pass). */
static inline void bvh_node_set_box(bvh_node *n, box3 b)
{
    n->bmin[0] = b.min.x, n->bmin[1] = b.min.y, n->bmin[2] = b.min.z;
    n->bmax[0] = b.max.x, n->bmax[1] = b.max.y, n->bmax[2] = b.max.z;
}

static inline box3 bvh_node_box(const bvh_node *n)
{
    box3 b = {{n->bmin[0], n->bmin[1], n->bmin[2]}, {n->bmax[0], n->bmax[1], n->bmax[2]}};
    return b;
}

/* The kernel-variant flags of a built tree (core/variant.h); ACCEL_V_OPT is
 * the packet frustum. */
static inline unsigned bvh_variant_flags(const bvh *b)
{
    /* ACCEL_V_OPT: frustum for packets, first=left for single rays */
    return accel_variant_flags(b->naive, b->has_spheres,
                               b->traverse == BVH_TRAVERSE_PACKET ? b->frustum : b->first_left);
}

/* Kernels in bvh_single.c (single rays) and bvh_packet.c (64-ray packets). */
void bvh_trace_intersect(const bvh *b, const accel_ray *rays, accel_hit *hits, size_t count,
                         accel_counters *c);
void bvh_trace_occluded(const bvh *b, const accel_ray *rays, uint8_t *occ, size_t count,
                        accel_counters *c);
void bvh_packet_intersect(const bvh *b, const accel_ray *rays, accel_hit *hits, size_t count,
                          accel_counters *c);
void bvh_packet_occluded(const bvh *b, const accel_ray *rays, uint8_t *occ, size_t count,
                         accel_counters *c);

/* accel.h's conservative walk (bvh_walk.c): binary and wide trees. */
int bvh_walk(const void *accel, const accel_ray *ray, float pad, accel_walk_visit visit, void *ctx,
             uint32_t *steps);

#ifdef __cplusplus
}
#endif

#endif
