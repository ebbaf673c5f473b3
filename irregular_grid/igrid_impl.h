/*
 * igrid_impl.h - the built irregular grid and the build's internal
 * interface, shared by igrid_build.c (subdivision, flattening), igrid_opt.c
 * (merge, expansion) and igrid_trace.c. Private to irregular_grid/.
 */
#ifndef IRREGULAR_GRID_IGRID_IMPL_H
#define IRREGULAR_GRID_IGRID_IMPL_H

#include "igrid.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The kind's parameters as parsed, one field per key (igrid_params.c's
 * table: ACCEL_SPEC(params, igrid_spec)); choices hold their position in
 * the table's list (split: adaptive 0, cell 1). */
typedef struct {
    double top_lambda, sub_lambda, split_ratio, alpha, ct, max_mb;
    int max_depth, split, subdivide, split_min, merge, expand, mailbox, cells;
    int isa; /* ACCEL_ISA_AUTO, _AVX2, _AVX512 (core/isa.h) */
} igrid_spec;

#define IGRID_PARAM_COUNT 15
extern const accel_param_def igrid_params[IGRID_PARAM_COUNT];

typedef struct {
    /* The primitive store (accel.h): cells hold its local ids. */
    accel_prim_store store;
    grid_frame frame;    /* the virtual lattice */
    float *planes;       /* storage behind frame.planes */
    int top_res[3], shift;
    uint32_t *map;       /* voxel map (igrid.h) */
    uint64_t map_len;
    igrid_cell *cells;
    uint32_t cell_count;
    uint32_t *refs;
    uint64_t ref_count;
    /* cells=blocks (triangles, the watertight test): cell c's references
     * copied 8 to a block into blocks.blocks[blocks.offsets[c] ..
     * blocks.offsets[c + 1]) for the shared block test (grid/grid_blocks.h);
     * offsets NULL when not built. */
    grid_cell_blocks blocks;
    uint64_t step_bound; /* most cells one ray can visit: voxels per axis summed, + 3 */
    int naive, mailbox, has_spheres;
    int isa; /* ACCEL_ISA_AVX2 or _AVX512 (core/isa.h): whose block kernels run */
} igrid_accel;

/*
 * The cells while they are built: original boxes (voxels lo..hi-1, the
 * voxels the map sends to the cell), exit boxes, and one sorted reference
 * list per cell (pointing into a pool, or owned once a merge made it).
 * The map's leaves hold cell ids throughout.
 */
typedef struct {
    const grid_frame *frame; /* virtual lattice */
    int top_res[3], shift;
    uint32_t *map;
    uint64_t map_len;
    uint32_t count;          /* cells */
    int32_t (*box)[6];       /* original box: lo[3], hi[3] */
    int32_t (*exit)[6];      /* exit box (expansion grows it) */
    uint32_t **list;         /* sorted local primitive ids */
    uint32_t *len;
    uint8_t *owned;          /* list[c] was malloc'd by a merge */
    uint32_t *pool;          /* the subdivision's lists */
} igrid_bcells;

static inline uint32_t igrid_bcell_at(const igrid_bcells *b, int x, int y, int z)
{
    return igrid_lookup(b->map, b->top_res, b->shift, x, y, z);
}

/*
 * The top grid (igrid_top.c): the resolution rule at `lambda` cells per
 * primitive over `count` primitives in `bounds`, with no cell longer than
 * twice its middle side (`box`, the frame's box with flat axes widened,
 * gives the sides): the octree refines a cell's axes together.
 */
void igrid_top_resolution(box3 bounds, box3 box, uint32_t count, double lambda, int t[3]);

/*
 * Coincident copies (igrid_top.c): primitives with the same geometry, bit
 * for bit, grouped; the subdivision runs on one representative per group
 * (the smallest local id) and a leaf's list holds every copy of its
 * representatives. All distinct: *reps = NULL, *rep_count = prim_count.
 * Otherwise reps[0..*rep_count) ascending, and representative r's group is
 * copies[copy_off[r] .. copy_off[r+1]) (empty for the others). Returns
 * ACCEL_ERR_NOMEM or 0.
 */
int igrid_group_copies(const accel_scene *s, uint32_t **reps, uint32_t *rep_count,
                       uint32_t **copy_off, uint32_t **copies);

/* Frees everything b owns (map included, unless moved out: set to NULL). */
void igrid_bcells_free(igrid_bcells *b);

/*
 * Step 2, merge (igrid_opt.c): passes along x, y, z merge a cell with its
 * neighbour across the high face when both have the same cross-section and
 * the surface-area cost does not grow:
 *   A(union) * (|refs union| + ct) <= A(c1) * (|refs c1| + ct) + A(c2) * (|refs c2| + ct),
 * A the half surface area in world units. Each cell merges at most once per
 * axis pass (greedy in cell order: deterministic); passes repeat while they
 * remove at least 1-alpha of the cells. The map's leaves are renumbered.
 * A merged list is never longer than the two it replaces, so the merge
 * needs no memory check. Returns ACCEL_ERR_NOMEM or 0.
 */
int igrid_merge(igrid_bcells *b, double alpha, double ct, accel_error *err);

/*
 * Step 3, expansion (igrid_opt.c): `passes` rounds over the six faces of
 * every cell's exit box; a face moves outwards by the largest depth that
 * stays inside every neighbouring cell across it (their exit boxes), when
 * each of those neighbours' primitives is a subset of the cell's own
 * (empty neighbours always are). Invariant: every voxel of a cell's exit
 * box belongs to a cell whose references are a subset of its own, so a
 * ray inside the exit box meets no primitive the cell did not test.
 * Returns ACCEL_ERR_NOMEM or 0.
 */
int igrid_expand(igrid_bcells *b, int passes, accel_error *err);

/* Traversal entry points (igrid_trace.c). */
void igrid_intersect(const void *accel, const accel_ray *rays, accel_hit *hits, size_t count,
                     accel_counters *counters);
void igrid_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded, size_t count,
                    accel_counters *counters);

/* accel.h's conservative walk (igrid_trace.c). */
int igrid_walk(const void *a, const accel_ray *ray, float pad, accel_walk_visit visit,
               void *ctx, uint32_t *steps);

#ifdef __cplusplus
}
#endif

#endif
