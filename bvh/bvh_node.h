/*
 * bvh_node.h - the binary BVH's internals, shared by the builders and the
 * traversal kernels (internal to bvh/; the public header bvh.h holds the
 * node type and its layout): the built structure, the kind's code paths,
 * the slab test and the primitive test the kernels share.
 */
#ifndef BVH_BVH_NODE_H
#define BVH_BVH_NODE_H

#include <assert.h>
#include <stddef.h>
#include <stdint.h>

#include "bvh.h"
#include "core/prim.h"
#include "core/variant.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Index of bmax[0] in the node seen as 8 floats: the slab test picks a
 * plane as ((const float *)node)[axis + (near or far offset)]. */
#define BVH_BMAX_OFS 4

/* Traversal modes (parameter traverse=). */
enum { BVH_TRAVERSE_SINGLE = 0, BVH_TRAVERSE_PACKET = 1, BVH_TRAVERSE_STREAM = 2 };

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
    const struct bvh_path *path; /* the kind's code path, chosen at build or load (below) */
    struct bvh_wide *wide; /* bvh_path_wide's tree (wide/wide.h), else NULL: only that path reads it */
    uint32_t scene_prims; /* the scene's triangles + spheres at build (0: loaded from a file) */
    struct bvh_rebuild *rebuild; /* the build's options, for update's rebuild (bvh.c); NULL if loaded */
    int first_left;       /* first=left: single rays always visit the left hit child first */
    void *nodes_block;    /* pairs=split: the allocation nodes points 32 bytes into, else NULL */
} bvh;

/* The kind's code paths (bvh.c): the binary tree traced one ray at a time
 * or in 64-ray packets, or the wide tree (bvh/wide/). One is chosen once,
 * at build (or load), so that no entry point asks which tree it holds. */
typedef struct bvh_path {
    void (*intersect)(const bvh *b, const accel_ray *rays, accel_hit *hits, size_t count,
                      accel_counters *c);
    void (*occluded)(const bvh *b, const accel_ray *rays, uint8_t *occ, size_t count,
                     accel_counters *c);
    void (*walk)(const bvh *b, const accel_ray_prep *p, float pad, accel_walk_visit visit, void *ctx,
                 uint32_t *steps);
    int (*mark_ids)(const bvh *b, uint8_t *mark, size_t total); /* bvh_refit.c's contract */
    int (*refit)(bvh *b, const accel_scene *s, int threads, int boxes, accel_error *err);
    size_t (*memory)(const bvh *b); /* bytes of the tree's pools (not the struct) */
    void (*release)(bvh *b);        /* frees the tree's pools */
    int refit_boxes;                /* 0: update rebuilds (quantized nodes keep no float boxes) */
    int saveable;                   /* bvh_save writes it (binary trees only) */
} bvh_path;

/* bvh.c: binary single rays, binary packets, the wide tree; and the path
 * of a binary tree traced with traverse (BVH_TRAVERSE_*). */
extern const bvh_path bvh_path_single, bvh_path_packet, bvh_path_wide;
const bvh_path *bvh_binary_path(int traverse);

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

/* The conservative walks (bvh_walk.c, wide/walk.c): a box given as lo/hi
 * triples, grown by pad, and a stack entry. */
static inline __attribute__((always_inline)) int bvh_padded_slab(const float *lo, const float *hi,
                                                             float pad, const accel_ray_prep *p,
                                                             float t_max, float *entry)
{
    float l[3] = {lo[0] - pad, lo[1] - pad, lo[2] - pad};
    float h[3] = {hi[0] + pad, hi[1] + pad, hi[2] + pad};
    return box3_slab(l, h, p->org, p->inv_dir, p->neg, p->t_near, t_max, entry);
}

typedef struct {
    uint32_t node;
    float entry;
} bvh_walk_entry;

/* The binary tree's conservative walk (bvh_walk.c; accel.h's contract, for
 * a prepared ray), id marks and refit (bvh_refit.c; its contracts). */
void bvh_walk_binary(const bvh *b, const accel_ray_prep *p, float pad, accel_walk_visit visit,
                     void *ctx, uint32_t *steps);
int bvh_mark_ids_binary(const bvh *b, uint8_t *mark, size_t total);
int bvh_refit_binary(bvh *b, const accel_scene *s, int threads, int boxes, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
