/*
 * inst_impl.h - internals of the `instanced` kind (see instanced.h and
 * README.md): the structures over boxes both levels use (the bvh
 * backend's tree over boxes and a uniform grid), the per-mesh bottom
 * levels, the per-instance data the traversal reads.
 */
#ifndef INSTANCED_INST_IMPL_H
#define INSTANCED_INST_IMPL_H

#include <assert.h>
#include "accel.h"
#include "bvh/bvh.h"
#include "core/block.h"
#include "grid/grid_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- structures over boxes ----------------------------------------------- */

/* A BVH over boxes is bvh/bvh.h's bvh_box_tree: the lecture's 32-byte
 * bvh_node pool (node 0 the root, node 1 padding; an interior node's
 * children are left_first and left_first + 1, a leaf's count items are
 * order[left_first ..]; children come after their parent), order holding
 * the leaves' item ids. */

/* A uniform grid over boxes: grid_core.h's frame (boundary planes as
 * floats) and compact cells (cells.refs: item ids, per cell in increasing
 * order), walked with grid_core.h's DDA (distances in double). */
typedef struct {
    grid_frame frame;
    float *planes; /* storage behind frame.planes */
    grid_cells cells;
} inst_grid;

/* bvh_build_boxes (binned SAH, 16 bins) over the n boxes, leaves of at
 * most max_leaf (1..256); boxes that are not finite or are inverted (empty)
 * are left out. out->order holds ids[box index], or the box index itself
 * when ids is NULL. Freed with bvh_box_tree_free. */
int inst_bvh_build(const box3 *boxes, uint32_t n, int max_leaf, int threads, const uint32_t *ids,
                   bvh_box_tree *out, accel_error *err);
/* A grid of about lambda * n cells (grid_resolution) over the boxes, each
 * box grown by pad on every side (rounded outwards to float) before the
 * cells it reaches are listed (grid_cells_build_boxes). */
int inst_grid_build(const box3 *boxes, uint32_t n, double lambda, double pad, inst_grid *out,
                    accel_error *err);
void inst_grid_free(inst_grid *g);

/* The 8-wide form of a bvh_box_tree (inst_wide.c): the binary tree
 * collapsed by bvh/wide/'s greedy collapse into its 8-wide nodes
 * (bvh/wide/node.h's wide_node8: children's boxes in SoA rows, octant
 * orders, leaf references), walked with its node test (bvh/wide/kernel.h,
 * grown by the pad where the walk needs one). Every slot's box is the very
 * box of a binary node, so a walk of it reaches what a walk of the binary
 * tree reaches. The top level's leaves name instances (ids, one per block
 * of one); the bottom level's leaves are blocks of 8 of the mesh's
 * primitives (core/block.h, object space, in leaf order, lanes past a
 * leaf's end repeating its last primitive), shared by the mesh's instances
 * and copied again at every refit. */
enum { INST_WIDE = 8 };
typedef struct {
    void *nodes;          /* wide_node8, 64-byte aligned */
    uint32_t node_count;
    uint32_t root;        /* a node, a leaf reference or WIDE_EMPTY (bvh/wide/node.h) */
    uint32_t *ids;        /* top level: item ids in leaf order */
    accel_block8 *blocks; /* bottom level: the mesh's primitives */
    uint32_t block_count;
} inst_wide;

/* Collapses h (built, kept: the binary tree is what a refit updates) into
 * *out; mesh NULL for the top level (leaves of item ids), else the mesh
 * whose primitives h->order names (leaves of blocks of 8). */
int inst_wide_build(const bvh_box_tree *h, const accel_scene *mesh, inst_wide *out, accel_error *err);
/* After the binary tree's boxes (and the mesh's vertices) changed: the
 * collapse and the blocks made again. */
int inst_wide_refit(const bvh_box_tree *h, const accel_scene *mesh, inst_wide *w, accel_error *err);
void inst_wide_free(inst_wide *w);
size_t inst_wide_memory(const inst_wide *w);

/* ---- the kind ------------------------------------------------------------- */

enum { INST_BVH = 0, INST_GRID = 1, INST_WALK = 2 };
enum { INST_WORLD_BLOCKS = 0, INST_WORLD_COMPUTE = 1 };

/* One per mesh: its bottom level, shared by every instance of the mesh. */
typedef struct {
    const accel_scene *mesh; /* object space (the scene itself for a plain scene) */
    box3 box;                /* every vertex of every primitive, object space */
    double box_lo[3], box_hi[3];
    double abs_max;          /* largest |coordinate| of box */
    double vert_abs_max;     /* largest |coordinate| of any vertex (dead triangles too) */
    double grid_pad;         /* bottom=grid: how far its boxes were grown */
    bvh_box_tree bvh;
    inst_wide wide;          /* bottom=bvh, width=8: bvh collapsed, its blocks */
    inst_grid grid;
    /* bottom=<kind spec>: the kind's structure over the mesh, walked
     * (accel.h's walk); and the mesh's triangles with no area in object
     * space, which the kind leaves out but whose world copies may live. */
    void *walk;
    accel_build_stats walk_stats;
    uint32_t *dead;
    uint32_t dead_count;
} inst_bottom;

/* One per instance: what the traversal reads, packed together. */
typedef struct {
    double inverse[12];   /* world -> object */
    double xform[12];     /* object -> world (for the world triangles) */
    double pad;           /* object-space distance covering the flattening's rounding */
    uint32_t bottom;      /* mesh index */
    uint32_t base;        /* id of its first primitive */
    int identity;         /* object space == world space: no transform at all */
    int has_dead;         /* some of its flattened triangles have no area */
    /* world=blocks (bottom=bvh, width=8, a scene of instances): its mesh's
     * leaf blocks in world space, the flattened triangles (ids base + q)
     * in the bottom level's block order; a lane dead in the flattened
     * scene holds a point (never hit). Made at build, made again by the
     * update for instances that moved or whose mesh changed. */
    accel_block8 *world;
} inst_item;

typedef struct {
    const accel_scene *scene; /* the flattened scene */
    int top;                  /* INST_BVH or INST_GRID */
    int bottom_kind;          /* INST_BVH, INST_GRID or INST_WALK */
    const accel_kind *walk_kind; /* INST_WALK: the bottom kind, and its parameters */
    char walk_kv[64];
    int threads;
    int naive, spheres;
    int world;                /* INST_WORLD_BLOCKS or INST_WORLD_COMPUTE */
    int plain;                /* a plain scene: the bottom blocks are world blocks */
    int no_pad;               /* pad=0: boxes not grown (shows what the pad is for) */
    int leaf;                 /* bottom=bvh: largest leaf */
    int width;                /* BVH levels walked as the binary tree (2) or 8-wide (8) */
    int packets;              /* traverse=packet (inst_packet.c) */
    int isa;                  /* ACCEL_ISA_AVX2 or _AVX512 (core/isa.h): the single-ray unit that runs */
    double lambda, top_lambda;
    uint32_t bottom_count, item_count;
    inst_bottom *bottoms;
    inst_item *items;
    box3 *item_boxes;         /* world bounds per instance (top level) */
    bvh_box_tree top_bvh;
    inst_wide top_wide;       /* top=bvh, width=8 */
    inst_grid top_grid;
} inst_accel;

/* Building blocks (inst_kind.c), shared with the per-frame update (inst_update.c). */
int inst_set_items(inst_accel *a, const accel_scene *scene, double *grid_pad, accel_error *err);
int inst_build_bottom(inst_accel *a, uint32_t i, double grid_pad, accel_error *err);
int inst_build_top(inst_accel *a, accel_error *err);
/* world=blocks: item k's world blocks made (again) from the flattened
 * scene, after its bottom level's blocks (inst_kind.c). */
int inst_world_blocks(inst_accel *a, uint32_t k, accel_error *err);
void inst_fill_stats(const inst_accel *a, accel_build_stats *stats);
size_t inst_memory(const void *a);
void inst_destroy(void *a);
/* The build, with `bottom` (when not NULL) as the walked bottom kind
 * instead of the parameter's; and the choice of a walked bottom kind. */
int inst_build_with(const accel_scene *scene, const accel_params *params, int threads,
                    const accel_kind *bottom, const char *bottom_kv, void **out,
                    accel_build_stats *stats, accel_error *err);
int inst_use_bottom_kind(inst_accel *a, const accel_kind *k, accel_error *err);
/* accel_kind.update (inst_update.c). */
int inst_update(void *a, const accel_scene *scene, int refit, accel_update_stats *st,
                accel_error *err);

/* The kind's entries (inst_packet.c): packets with traverse=packet, else
 * ray by ray (k8_trace.c, in the structure's ISA: inst_single_*
 * dispatch to its AVX2 or AVX-512 unit, inst_trace_*[_avx512]). */
#define INST_TRACE_ENTRIES(sfx)                                                                     \
    void inst_trace_intersect##sfx(const void *a, const accel_ray *rays, accel_hit *hits, size_t n,  \
                                   accel_counters *c);                                             \
    void inst_trace_occluded##sfx(const void *a, const accel_ray *rays, uint8_t *occ, size_t n,      \
                                  accel_counters *c);
INST_TRACE_ENTRIES()
INST_TRACE_ENTRIES(_avx512)
void inst_intersect(const void *a, const accel_ray *rays, accel_hit *hits, size_t n,
                    accel_counters *c);
void inst_occluded(const void *a, const accel_ray *rays, uint8_t *occ, size_t n,
                   accel_counters *c);
void inst_single_intersect(const void *a, const accel_ray *rays, accel_hit *hits, size_t n,
                           accel_counters *c);
void inst_single_occluded(const void *a, const accel_ray *rays, uint8_t *occ, size_t n,
                          accel_counters *c);
void inst_packet_intersect(const void *a, const accel_ray *rays, accel_hit *hits, size_t n,
                           accel_counters *c);
void inst_packet_occluded(const void *a, const accel_ray *rays, uint8_t *occ, size_t n,
                          accel_counters *c);

#ifdef __cplusplus
}
#endif

#endif
