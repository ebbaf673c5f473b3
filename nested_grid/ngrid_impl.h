/*
 * ngrid_impl.h - the built nested grid and the build's internal interface,
 * shared by ngrid_build.c, ngrid_cost.c and ngrid_trace.c. Private to
 * nested_grid/.
 */
#ifndef NESTED_GRID_NGRID_IMPL_H
#define NESTED_GRID_NGRID_IMPL_H

#include "core/variant.h"
#include "grid/grid_blocks.h"
#include "ngrid.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * The compact two-level layout (`layout=compact`, ngrid_compact.c), after
 * Kalojanov, Billeter & Slusallek, "Two-Level Grids for Ray Tracing on
 * GPUs", EG 2011: one 8-byte word per top cell, one 4-byte offset per leaf
 * cell, one reference array. A top cell's leaf cells are leaf[first ..
 * first + rx*ry*rz) (one of them when the cell is a plain leaf); leaf cell k
 * holds refs[leaf[k] .. leaf[k+1]). The sub-grid's box is the top cell's
 * box (the top grid's planes) and its planes are remade from it by
 * grid_frame_init during the walk, the very floats the build used.
 */
typedef struct {
    uint32_t first; /* index of the cell's first leaf cell */
    uint32_t res;   /* (rx-1) | (ry-1) << 8 | (rz-1) << 16; 0: a plain leaf */
} ngrid_top_cell;

#define NGRID_COMPACT_MAX_RES 256 /* sub-grid cells per axis (8 bits of res - 1) */

typedef struct {
    grid_frame top;       /* the top grid; planes in top_planes */
    float *top_planes;
    ngrid_top_cell *tops; /* one per top cell */
    uint64_t top_count;
    uint32_t *leaf;       /* leaf_count + 1 offsets into refs */
    uint64_t leaf_count;
    uint32_t *refs;       /* local primitive ids, every leaf's sorted list in leaf order */
    uint64_t ref_count;
} ngrid_compact;

typedef struct {
    /* The primitive store (accel.h): lists hold its local ids, and
     * store.scene_id maps a hit back to the scene's id. */
    accel_prim_store store;
    ngrid_node *nodes;   /* node_count grids, breadth-first, top first */
    uint32_t node_count;
    uint32_t *cells;     /* cell words (ngrid.h) */
    uint64_t cell_count;
    uint32_t *lists;     /* count-prefixed primitive lists; lists[0] = 0 */
    uint64_t list_len;
    float *planes;       /* storage behind every node's frame.planes */
    size_t plane_count;
    uint64_t ref_count;
    uint64_t leaf_count; /* cells holding a non-empty primitive list */
    uint64_t step_bound; /* most cells (all levels) one ray can visit */
    int levels;
    int naive, mailbox, has_spheres; /* mailbox: the single-ray walks' (off with blocks) */
    int isa;                /* ACCEL_ISA_AVX2 or _AVX512 (core/isa.h): whose block kernels run */
    int packet_mailbox;     /* traverse=packet: the packets' mailbox (mailbox=1) */
    int traverse;           /* NGRID_TRAVERSE_SINGLE / NGRID_TRAVERSE_PACKET */
    ngrid_compact *compact; /* layout=compact: the only arrays kept (nodes etc. freed) */
    grid_list_blocks blocks; /* cells=blocks: the lists as blocks (first NULL: not built) */
} ngrid_accel;

/*
 * Membership padding of a sub-grid. The regular grid pads a cell by
 * GRID_PAD_CELLS of a cell plus GRID_PAD_ULPS float ulps of the coordinates'
 * magnitude (grid_core.h). A sub-grid keeps the first part, at its own cell
 * size, and leaves out the second: the walk's distances are doubles that
 * follow the ray to about 1e-16 of its length (grid_core.h), far inside a
 * 1/1024-cell margin, while 16 ulps of the coordinates would exceed the
 * cells of a deep sub-grid in a scene far from the origin (0.02 units at
 * 1e4) and put every primitive in all of them. The result is clamped to the
 * parent's padding, so each padded sub-cell lies inside its padded parent
 * cell, whose list is therefore complete for it.
 */
static inline void ngrid_sub_pad(grid_frame *f, const float parent_pad[3])
{
    for (int a = 0; a < 3; a++) {
        double cell = ((double)f->hi[a] - f->lo[a]) / f->res[a];
        f->pad[a] = minf(parent_pad[a], (float)(cell * GRID_PAD_CELLS));
    }
}

/* Cost model constants (ns) and the choices the build leaves to it. */
typedef struct {
    double c_step, c_isect;
} ngrid_costs;

/* A sub-grid storing more than this many references per primitive costs
 * memory without saving tests and is not kept (ngrid_level.c). */
#define NGRID_MAX_COPIES 8
/* The auto mode's guard of the same kind (ngrid_cost.c): a sub-grid
 * candidate with more references per primitive than this is not priced,
 * and neither are finer ones. A guard against primitives as large as the
 * cell, not a tuning: at 128 every auto structure of the study's scenes is
 * unchanged (at 32 one changes, at 8 most do: the cost model does choose
 * sub-grids of 8-32 copies per primitive, and that is its call). */
#define NGRID_AUTO_MAX_COPIES 128

/*
 * Auto mode, top level: the resolution (among the rule's results for a
 * ladder of lambdas) with the least expected cost c_step*E[cells] +
 * c_isect*E[tests] of a ray crossing the scene box, cells that may get
 * sub-grids (deeper) priced with the lookahead of ngrid_cost.c. Counts
 * references on a deterministic subset of at most NGRID_AUTO_SAMPLE
 * primitives.
 */
int ngrid_auto_top_res(const accel_scene *s, box3 box, grid_overlap mode, int deeper,
                       const ngrid_costs *m, double max_bytes, int res[3], accel_error *err);

/*
 * Auto mode, one cell: the sub-grid resolution whose expected cost for a
 * ray crossing the cell beats testing the cell's prim_count primitives, or
 * res = {0,0,0} when none does (the cell stays a leaf). parent_pad: the
 * padding of the grid the cell belongs to (ngrid_sub_pad); deeper: whether
 * the sub-grid's cells may get sub-grids in turn. A candidate with more
 * than NGRID_AUTO_MAX_COPIES references per primitive ends the ladder
 * unpriced.
 */
int ngrid_auto_sub_res(const accel_scene *s, box3 box, const float parent_pad[3],
                       const uint32_t *prims, uint32_t prim_count, grid_overlap mode, int deeper,
                       const ngrid_costs *m, double max_bytes, int res[3], accel_error *err);

/* ---- the build's grids (ngrid_build.c, ngrid_level.c) ----------------------------- */

/* One grid under construction. */
typedef struct {
    int level;
    uint32_t parent_cell;   /* linear cell index in the parent grid */
    grid_frame frame;
    float *planes;          /* storage behind frame.planes */
    grid_cells cells;
    uint32_t first_child;   /* children: grids[first_child .. +child_count), by cell */
    uint32_t child_count;
} ngrid_bgrid;

/* The build's parameters and every grid built so far. */
typedef struct {
    const accel_scene *scene;
    grid_overlap mode;
    int is_auto, lookahead, depth, sub_res;
    double sub_lambda;
    uint32_t threshold;
    ngrid_costs costs;
    int max_sub_res;     /* cap on a sub-grid's cells per axis (0: none) */
    double max_bytes;
    ngrid_bgrid **grids; /* breadth-first */
    uint32_t grid_count, grid_cap;
    double bytes;        /* offsets, references and planes of every grid so far */
    uint64_t cells;      /* cells of every grid so far */
} ngrid_builder;

static inline uint32_t ngrid_cell_prims(const ngrid_bgrid *g, uint32_t cell)
{
    return g->cells.offsets[cell + 1] - g->cells.offsets[cell];
}

/* A grid with its frame over box at resolution res (cells not built). */
int ngrid_bgrid_new(box3 box, const int res[3], int level, ngrid_bgrid **out, accel_error *err);
void ngrid_bgrid_free(ngrid_bgrid *g);
/* Offsets, references and planes of a built grid. */
double ngrid_bgrid_bytes(const ngrid_bgrid *g);
/* Appends a built grid to b (its bytes and cells counted). */
int ngrid_push_grid(ngrid_builder *b, ngrid_bgrid *g, accel_error *err);
/* Puts "nested_grid: <context>: " before a message from the grid API. */
int ngrid_wrap_error(accel_error *err, int rc, const char *context);
/* Plans, checks and builds the sub-grids of grids[begin, end), all of one
 * level (ngrid_level.c). */
int ngrid_build_level(ngrid_builder *b, uint32_t begin, uint32_t end, int threads,
                      accel_error *err);

/* Turns a flattened two-level g into the compact layout (g->compact) and
 * frees the word layout's arrays (ngrid_compact.c). */
int ngrid_compact_build(ngrid_accel *g, double max_bytes, accel_error *err);
void ngrid_compact_free(ngrid_compact *k);
size_t ngrid_compact_bytes(const ngrid_compact *k);

/* Traversal modes (parameter traverse=). */
enum { NGRID_TRAVERSE_SINGLE = 0, NGRID_TRAVERSE_PACKET = 1 };

/* The kernel-variant flags of a built nested grid (core/variant.h). */
static inline unsigned ngrid_flags(const ngrid_accel *g)
{
    return accel_variant_flags(g->naive, g->has_spheres, g->mailbox);
}

/* The packet walk's flags: its own mailbox switch (a packet's mailbox
 * pays with blocks too; the single-ray walk's does not). */
static inline unsigned ngrid_packet_flags(const ngrid_accel *g)
{
    return accel_variant_flags(g->naive, g->has_spheres, g->packet_mailbox);
}

/* The single-ray walks of either layout (ngrid_trace.c; the compact
 * layout's in ngrid_compact.c). The kind's entries (ngrid_build.c) pick
 * these or the packet walk (traverse=packet). */
void ngrid_single_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                            size_t count, accel_counters *counters);
void ngrid_single_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded,
                           size_t count, accel_counters *counters);
/* Coherent grid traversal over the levels, 64-ray packets (ngrid_packet.c);
 * packets that do not qualify go to the single-ray walks. */
void ngrid_packet_intersect(const ngrid_accel *g, const accel_ray *rays, accel_hit *hits,
                            size_t count, accel_counters *counters);
void ngrid_packet_occluded(const ngrid_accel *g, const accel_ray *rays, uint8_t *occluded,
                           size_t count, accel_counters *counters);
void ngrid_compact_intersect(const ngrid_accel *g, const accel_ray *rays, accel_hit *hits,
                             size_t count, accel_counters *counters);
void ngrid_compact_occluded(const ngrid_accel *g, const accel_ray *rays, uint8_t *occluded,
                            size_t count, accel_counters *counters);

/* accel.h's conservative walk (ngrid_trace.c): the fat walk at every level. */
int ngrid_walk(const void *accel, const accel_ray *ray, float pad, accel_walk_visit visit,
               void *ctx, uint32_t *steps);

#ifdef __cplusplus
}
#endif

#endif
