/*
 * grid_core.h - the grid API shared by the regular grid (grid/) and the
 * nested grid (nested_grid/): everything a uniform grid of cells over a box
 * needs, independent of what a cell holds.
 *
 *  - the resolution rule (Cleary & Wyvill 1988; Wald et al., "Ray Tracing
 *    Animated Scenes using Coherent Grid Traversal", SIGGRAPH 2006; Ize et
 *    al., "An Evaluation of Parallel Grid Construction for Ray Tracing
 *    Dynamic Scenes", RT 2006): n_i = d_i * cbrt(lambda * N / V), extended
 *    to flat and thin boxes;
 *  - overflow-safe sizing against a memory limit;
 *  - the cell frame: boundary planes stored once per axis, so that the
 *    builder's cell boxes and the traversal's crossing distances come from
 *    the very same floats;
 *  - the cell range of a box and exact primitive/cell membership (overlap.h);
 *  - the compact cell storage build: count pass, prefix sum, fill pass
 *    (multithreaded, with a result identical to the single-threaded one);
 *  - the 3D-DDA of Amanatides & Woo, "A Fast Voxel Traversal Algorithm for
 *    Ray Tracing", Eurographics 1987: setup at the grid entry and step.
 *
 * Robustness contract (what makes the DDA skip no cell that matters):
 *  1. membership is conservative: a primitive belongs to every cell whose
 *     box, enlarged by frame.pad on every side, it touches;
 *  2. every crossing distance is computed from a stored boundary plane,
 *     t = (plane - org) * inv_dir, never accumulated: the sequence of cells
 *     is then exactly the one these (monotone) distances define;
 *  3. the entry cell is made consistent with those distances: its entry
 *     plane is crossed at or before t_entry, its exit plane after it;
 *  4. the caller keeps the nearest hit of every primitive it tested, even
 *     when that hit lies beyond the current cell, and stops only when the
 *     current cell's exit distance reaches it.
 * A ray through an edge or a corner then visits the cells on one side of it
 * (the 6-connected path), and a primitive it hits exactly there touches
 * those cells too. The walk's distances are doubles, accurate to about
 * 1e-16 of the distance travelled; the padding is a margin over that.
 */
#ifndef GRID_GRID_CORE_H
#define GRID_GRID_CORE_H

#include <float.h>
#include <math.h>
#include <stdint.h>

#include "accel.h"
#include "core/block.h"
#include "core/prim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest resolution along one axis (cells); keeps cell indices exact in
 * float and the per-axis plane tables small. */
#define GRID_MAX_AXIS_RES 65536
/* Membership padding, in cells: a primitive within this fraction of a cell
 * of a cell's box belongs to it. A margin over the walk's rounding (about
 * 1e-16 of the distance travelled, see grid_dda); costs a reference only
 * for primitives that end within 1/1024 of a cell from a boundary. A caller
 * may change frame.pad after grid_frame_init (the passes read it). */
#define GRID_PAD_CELLS (1.0 / 1024.0)
/* Membership padding relative to the magnitude of the coordinates, in
 * float ulps. Zero: membership, planes and the walk are all evaluated in
 * double on the same floats, so far from the origin they stay consistent
 * without a margin; a margin of a few ulps there would be wider than the
 * cells of a small scene and put every primitive in every cell. */
#define GRID_PAD_ULPS 0.0

/* ---- resolution and sizing ------------------------------------------------ */

/*
 * Cells per axis for prim_count primitives in box `bounds` at a density of
 * lambda cells per primitive: n_i = d_i * (lambda*N / prod d_j)^(1/k) over
 * the k axes that are not flat. An axis with zero extent, or one on which
 * the rule gives less than one cell, gets one cell and the rule is redone on
 * the remaining axes (a thin slab becomes a 2D grid of about lambda*N cells,
 * not a 3D one with most cells clamped away). Results are rounded and
 * clamped to [1, GRID_MAX_AXIS_RES].
 */
void grid_resolution(box3 bounds, double prim_count, double lambda, int res[3]);

/* Parses "auto" (res[] = 0), "N" (N cells on every axis) or "NxNyNz". */
int grid_parse_res(const char *text, int res[3], accel_error *err);

/* Cell count of res[] in 64 bits, refused with ACCEL_ERR_RANGE (and a
 * message naming `what`) when the offset array and plane tables alone would
 * exceed max_bytes or when the count does not fit a uint32 cell index. */
int grid_cell_count(const char *what, const int res[3], double max_bytes, uint64_t *cells,
                    accel_error *err);

/* ---- the frame: box, resolution, boundary planes --------------------------- */

typedef struct {
    float lo[3], hi[3];     /* grid box */
    int res[3];             /* cells per axis */
    uint32_t stride[3];     /* 1, nx, nx*ny: linear cell = x + nx*(y + ny*z) */
    float inv_cell[3];      /* res / extent: only for first guesses of a cell */
    float pad[3];           /* membership padding per axis, world units */
    const float *planes[3]; /* res[a]+1 boundary positions per axis, planes[a][0] = lo */
} grid_frame;

/* The box a grid is laid over: `bounds` with every flat (zero-extent) axis
 * widened symmetrically so that cells have positive size. An empty box
 * becomes the unit cube. */
box3 grid_frame_box(box3 bounds);

/* Floats the plane tables of res[] take: sum of (res[a] + 1). */
static inline size_t grid_plane_count(const int res[3])
{
    return (size_t)res[0] + (size_t)res[1] + (size_t)res[2] + 3;
}

/* Fills the frame; `planes` (grid_plane_count floats, owned by the caller)
 * receives the boundary positions lo + extent*k/n, rounded once from double. */
void grid_frame_init(grid_frame *f, box3 box, const int res[3], float *planes);

/* Range of cells (inclusive, per axis) whose padded boxes the box b touches,
 * clamped to the grid. Returns 0 when b misses the padded grid. */
int grid_cell_range(const grid_frame *f, box3 b, int lo[3], int hi[3]);

/* Padded box of cell (x, y, z) in double. */
void grid_cell_box(const grid_frame *f, int x, int y, int z, double lo[3], double hi[3]);

/* ---- compact cell storage --------------------------------------------------- */

typedef enum {
    GRID_OVERLAP_EXACT = 0, /* triangle/box SAT, sphere/box distance (overlap.h) */
    GRID_OVERLAP_BBOX = 1   /* every cell the primitive's bounding box touches */
} grid_overlap;

/* One grid's cells: the references of cell c are refs[offsets[c] ..
 * offsets[c+1]-1], sorted by increasing primitive id. */
typedef struct {
    uint32_t *offsets;  /* cell_count + 1 */
    uint32_t *refs;     /* ref_count primitive ids */
    uint64_t cell_count, ref_count;
} grid_cells;

/* One grid's cells as primitive blocks (core/block.h): cell c's
 * primitives, in the order of its references, copied 8 to a block into
 * blocks[offsets[c] .. offsets[c+1]-1] (the last block of a cell repeats
 * its last primitive), each lane with the reference's id. The cell visit
 * then tests 8 triangles at once with the block test every structure
 * shares (grid_blocks.h), as the wide BVH tests its leaves. Triangles
 * only: a scene with spheres keeps its id lists. */
typedef struct {
    uint32_t *offsets;     /* cell_count + 1 */
    accel_block8 *blocks;  /* block_count blocks, 32-byte aligned */
    uint64_t block_count, cell_count;
} grid_cell_blocks;

/* Builds *out from cells over the triangle-only store scene s (cell ids
 * are local ids of s); ACCEL_ERR_RANGE past max_bytes, ACCEL_ERR_NOMEM. */
int grid_cell_blocks_build(const grid_cells *cells, const accel_scene *s, double max_bytes,
                           grid_cell_blocks *out, accel_error *err);
void grid_cell_blocks_free(grid_cell_blocks *b);
size_t grid_cell_blocks_bytes(const grid_cell_blocks *b);

/* In the passes below, prims lists the scene primitives to place (ids into
 * s); NULL stands for 0..prim_count-1. */

/* Count pass: counts[c] += number of prims[] overlapping cell c (counts has
 * one entry per cell). With threads > 1 the increments are atomic. */
void grid_count_pass(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                     uint32_t prim_count, grid_overlap mode, uint32_t *counts, int threads);

/* The count pass on one thread that also totals the references, and stops
 * once the total exceeds stop_above (counts are then partial, and the
 * result is only known to be above it). Returns the total. */
uint64_t grid_count_pass_upto(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                              uint32_t prim_count, grid_overlap mode, uint32_t *counts,
                              uint64_t stop_above);

/* The number of references the passes would make, without any cell array:
 * the same membership test, totalled. Stops counting once the total
 * exceeds stop_above (the result is then only known to be above it). */
uint64_t grid_count_refs(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                         uint32_t prim_count, grid_overlap mode, uint64_t stop_above);

/* Prefix sum: turns counts a[0..n-1] into exclusive offsets and sets a[n] to
 * the total (*total). Fails, leaving a[] untouched, when the total does not
 * fit a uint32. */
int grid_prefix_sum(uint32_t *a, uint64_t n, int threads, uint64_t *total, accel_error *err);

/* Fill pass: writes every overlapping (prim, cell) into refs at the cell's
 * offsets, then sorts each cell's list so that any thread count gives the
 * same arrays. offsets must come from grid_prefix_sum of the count pass
 * with the same arguments; it is left unchanged on return. */
void grid_fill_pass(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                    uint32_t prim_count, grid_overlap mode, uint32_t *offsets, uint32_t *refs,
                    int threads);

/* All three passes, with allocation and the reference-count checks: the
 * references (4 bytes each) plus offsets must stay within max_bytes. On
 * failure nothing is left allocated. */
int grid_cells_build(const grid_frame *f, const accel_scene *s, const uint32_t *prims,
                     uint32_t prim_count, grid_overlap mode, int threads, double max_bytes,
                     grid_cells *out, accel_error *err);
void grid_cells_free(grid_cells *c);

/* The same storage over boxes (grid_boxes.c): cell c lists, in increasing
 * index, every non-empty box of boxes[0..n) that grid_cell_range puts in
 * it (the box against the cells grown by frame.pad). Single-threaded. */
int grid_cells_build_boxes(const grid_frame *f, const box3 *boxes, uint32_t n, grid_cells *out,
                           accel_error *err);

/* ---- 3D-DDA (Amanatides & Woo 1987) ---------------------------------------- */

/*
 * The walk's distances are kept in double. (plane - org) of two floats is
 * exact in double and the product with 1/dir loses about 1e-16 relative, so
 * the walk follows the float ray to within 1e-16 of its length: far below
 * the membership padding even for an origin 10^6 grid sizes away, where
 * float distances would be off by several cells. Scalar double arithmetic
 * costs the same as float on current CPUs; a step is one subtraction, one
 * multiplication and three comparisons either way.
 */
typedef struct {
    int idx[3];            /* current cell per axis */
    int step[3];           /* +1 / -1, or 0 on an axis the ray does not move along */
    int out[3];            /* idx value meaning "left the grid" (idx itself when step = 0) */
    uint32_t cell_step[3]; /* change of the linear index per step (mod 2^32) */
    uint32_t cell;         /* linear index of the current cell */
    double t_next[3];      /* distance of the next crossing per axis (+inf: none) */
    const float *next_plane[3]; /* next_plane[a][idx[a]] is the plane crossed next */
    double org[3], inv_dir[3];
} grid_dda;

/* Distance along the ray to a boundary plane of axis a (finite: inv_dir is
 * finite in double for every nonzero float direction). */
static inline double grid_plane_t(const grid_dda *d, int a, float plane)
{
    return ((double)plane - d->org[a]) * d->inv_dir[a];
}

/*
 * Sets up the walk for a prepared ray that overlaps the grid box (box3_slab
 * said so), starting no earlier than t_start (the ray's t_near, or where a
 * parent cell is entered). The entry distance is recomputed in double from
 * the box's near planes; the cell per axis is guessed from the entry point
 * and then corrected against the plane distances (contract point 3), so that
 * neither rounding in the entry point nor an origin exactly on a boundary
 * can start the walk past a cell the ray passes through. Where several
 * planes give the very same distance t_entry (cells thinner than the
 * rounding of plane - org: a paper-thin box seen from afar, whose planes
 * the ray crosses all "at once") the walk starts in the first cell of that
 * run, not the last: the steps then visit every cell of it at t_entry
 * (their primitives, resolved by the exact membership, are not covered by
 * any padding). An axis with a zero direction component (+0 or -0) does
 * not move: its cell is the one whose planes bracket the origin. Returns
 * the entry distance. grid_dda_init_d takes the ray in double (instanced's
 * object-space rays): then plane - org rounds once more, about 1e-16 of
 * the distance, still far inside the padding; grid_dda_init gives it a
 * float ray's exact values.
 */
static inline __attribute__((always_inline)) double
grid_dda_init_d(grid_dda *d, const grid_frame *f, const double o[3], const double dir[3],
                double t_start)
{
    double t_entry = t_start;
    for (int a = 0; a < 3; a++) {
        d->org[a] = o[a];
        d->inv_dir[a] = dir[a] != 0.0 ? 1.0 / dir[a] : 0.0;
        if (dir[a] != 0.0) {
            double t = grid_plane_t(d, a, dir[a] > 0.0 ? f->lo[a] : f->hi[a]);
            t_entry = t > t_entry ? t : t_entry;
        }
    }
    d->cell = 0;
    for (int a = 0; a < 3; a++) {
        const int n = f->res[a];
        const float *pl = f->planes[a];
        double pos = dir[a] != 0.0 ? o[a] + t_entry * dir[a] : o[a];
        double g = (pos - f->lo[a]) * f->inv_cell[a];
        int i = g >= n ? n - 1 : (g > 0.0 ? (int)g : 0);
        if (dir[a] == 0.0) {
            /* The ray stays in the slab of its origin: pick the cell whose
             * planes bracket it (either one when it lies on a plane). */
            while (i > 0 && o[a] < pl[i]) i--;
            while (i < n - 1 && o[a] > pl[i + 1]) i++;
            d->step[a] = 0;
            d->out[a] = i;
            d->cell_step[a] = 0;
            d->t_next[a] = INFINITY;
            d->next_plane[a] = pl;
        } else if (dir[a] > 0.0) {
            /* Entry plane pl[i] crossed at or before t_entry, exit plane after. */
            while (i > 0 && grid_plane_t(d, a, pl[i]) > t_entry) i--;
            while (i < n - 1 && grid_plane_t(d, a, pl[i + 1]) <= t_entry) i++;
            /* Planes tied at t_entry: start in the first cell of the run. */
            while (i > 0 && grid_plane_t(d, a, pl[i - 1]) == t_entry) i--;
            d->step[a] = 1;
            d->out[a] = n;
            d->cell_step[a] = f->stride[a];
            d->next_plane[a] = pl + 1;
            d->t_next[a] = grid_plane_t(d, a, pl[i + 1]);
        } else {
            while (i < n - 1 && grid_plane_t(d, a, pl[i + 1]) > t_entry) i++;
            while (i > 0 && grid_plane_t(d, a, pl[i]) <= t_entry) i--;
            while (i < n - 1 && grid_plane_t(d, a, pl[i + 2]) == t_entry) i++;
            d->step[a] = -1;
            d->out[a] = -1;
            d->cell_step[a] = 0u - f->stride[a];
            d->next_plane[a] = pl;
            d->t_next[a] = grid_plane_t(d, a, pl[i]);
        }
        d->idx[a] = i;
        d->cell += (uint32_t)i * f->stride[a];
    }
    return t_entry;
}

/* The setup for a prepared float ray (the grid family's kernels). */
static inline __attribute__((always_inline)) double
grid_dda_init(grid_dda *d, const grid_frame *f, const accel_ray_prep *p, double t_start)
{
    const double o[3] = {p->org.x, p->org.y, p->org.z};
    const double dir[3] = {p->dir.x, p->dir.y, p->dir.z};
    return grid_dda_init_d(d, f, o, dir, t_start);
}

/* A ray's entry into a grid-family kernel: prepares it in *p and clips it
 * to the frame box (one box test, counted in *boxes). 0 when the ray is
 * invalid, the grid holds no reference (nonempty == 0) or the box is
 * missed; then the kernel records a miss. */
static inline __attribute__((always_inline)) int
grid_ray_enter(const grid_frame *f, const accel_ray *r, int nonempty, accel_ray_prep *p,
               uint32_t *boxes)
{
    float t_entry; /* unused: grid_dda_init recomputes it in double */
    int live = accel_prep_ray(r, p) && nonempty;
    if (live) {
        *boxes = 1;
        live = box3_slab(f->lo, f->hi, p->org, p->inv_dir, p->neg, p->t_near, p->t_far, &t_entry);
    }
    return live;
}

/* Distance at which the ray leaves the current cell. */
static inline double grid_dda_exit(const grid_dda *d)
{
    double t = d->t_next[0] < d->t_next[1] ? d->t_next[0] : d->t_next[1];
    return t < d->t_next[2] ? t : d->t_next[2];
}

/* Advances along axis a (a constant after inlining, so that the walk's
 * state can live in registers). */
static inline __attribute__((always_inline)) int grid_dda_advance(grid_dda *d, int a)
{
    int i = d->idx[a] + d->step[a];
    if (i == d->out[a]) return 0;
    d->idx[a] = i;
    d->cell += d->cell_step[a];
    d->t_next[a] = grid_plane_t(d, a, d->next_plane[a][i]);
    return 1;
}

/* Moves to the next cell along the ray: across the nearest crossing, ties
 * going to the higher axis, so that a ray through an edge or a corner steps
 * one axis at a time and visits the cells between. Returns 0 once the ray
 * leaves the grid (or when asked to step along an axis it does not move on). */
static inline __attribute__((always_inline)) int grid_dda_step(grid_dda *d)
{
    if (d->t_next[0] < d->t_next[1] && d->t_next[0] < d->t_next[2]) return grid_dda_advance(d, 0);
    if (d->t_next[1] < d->t_next[2]) return grid_dda_advance(d, 1);
    return grid_dda_advance(d, 2);
}

/* ---- the cell visit: one cell's references, through the per-ray mailbox ------
 * Every single-ray walk of the grid family (grid, nested_grid in both
 * layouts, irregular_grid, instanced's grid levels, the conservative walks
 * of grid_walk.c and ngrid_trace.c) visits a cell the same way: its
 * references in order, each skipped when the per-ray mailbox already holds
 * it, else entered and tested. The mailbox is a direct-mapped cache of
 * GRID_MAILBOX primitive ids (the slot of id q is q mod GRID_MAILBOX): a
 * miss only repeats a test, never drops one, so it changes counters, never
 * answers. It is valid for one ray: a primitive tested for the ray keeps
 * its nearest hit for the ray, even beyond the cell (contract point 4). */

/* Entries of the per-ray mailbox (a power of two). */
#define GRID_MAILBOX 16

/* Empties a mailbox: ACCEL_MISS (all bits set) is no primitive's id. */
static inline void grid_mailbox_clear(uint32_t mail[GRID_MAILBOX])
{
    for (int i = 0; i < GRID_MAILBOX; i++) mail[i] = ACCEL_MISS;
}

/* The slot rule: 1 when the mailbox holds prim (skip it), else enters it
 * and returns 0. */
static inline __attribute__((always_inline)) int grid_mailbox_seen(uint32_t *mail, uint32_t prim)
{
    uint32_t *slot = &mail[prim & (GRID_MAILBOX - 1)];
    if (*slot == prim) return 1;
    *slot = prim;
    return 0;
}

/*
 * The cell visit of the closest-hit and any-hit kernels: tests ids[0..n)
 * (local ids of store scene s) against the prepared ray p with the shared
 * kernels (accel_prim_hit), each at most once per ray when `mailbox` is
 * set. *t, *u, *v are the running nearest hit (t starts at t_far); a hit
 * records t, u, v and the id in *h. Counted runs (c not NULL) add to
 * *tests and *skips. Returns 1 when `any` (an any-hit query) found a hit
 * and the ray is done. Callers pass any, naive, spheres and mailbox as
 * compile-time constants: inlined, each copy keeps only its own branches.
 */
static inline __attribute__((always_inline)) int
grid_cell_hit(const accel_scene *s, const uint32_t *ids, uint32_t n, const accel_ray_prep *p,
              accel_hit *h, float *t, float *u, float *v, uint32_t *mail, uint32_t *tests,
              uint32_t *skips, const accel_counters *c, int any, int naive, int spheres,
              int mailbox)
{
    for (uint32_t k = 0; k < n; k++) {
        uint32_t prim = ids[k];
        if (mailbox && grid_mailbox_seen(mail, prim)) {
            if (c) (*skips)++;
            continue;
        }
        if (c) (*tests)++;
        if (accel_prim_hit(s, prim, p, t, u, v, naive, spheres)) {
            h->t = *t, h->u = *u, h->v = *v, h->prim = prim;
            if (any) return 1;
        }
    }
    return 0;
}

/*
 * The cell visit of walks whose test is not accel_prim_hit (instanced's
 * world-space decision, accel.h's walk visitors): visit(ctx, prim) for
 * every id of ids[0..n) the mailbox does not hold (always on: these walks
 * allow repeats, so the mailbox only saves work), *skips counting the
 * others. The visitor returns 0 to end the walk; the visit then returns 0,
 * else 1. Inlined with a constant visitor, the call is direct (and inlined
 * when the visitor is).
 */
typedef int (*grid_prim_visit_fn)(void *ctx, uint32_t prim);
static inline __attribute__((always_inline)) int
grid_cell_visit(const uint32_t *ids, uint32_t n, uint32_t *mail, uint32_t *skips,
                grid_prim_visit_fn visit, void *ctx)
{
    for (uint32_t k = 0; k < n; k++) {
        if (grid_mailbox_seen(mail, ids[k])) {
            (*skips)++;
            continue;
        }
        if (!visit(ctx, ids[k])) return 0;
    }
    return 1;
}

/* ---- the fat walk (grid_fat.c) ------------------------------------------------
 * accel.h's conservative walk over one grid: calls fn(ctx, cell, ta, tb)
 * for every cell (linear index) whose box, grown by pad and the membership
 * padding, the segment [ta, tb] of the ray reaches before *t_max (read
 * again after every call: the caller shrinks it). [ta, tb] is the piece of
 * the segment that made the cell a candidate (a parent may walk a
 * sub-grid over it). Pieces come along the ray; a cell may be reported
 * more than once. Returns 0 when fn returned 0 (the walk is over), else 1. */
typedef int (*grid_fat_cell_fn)(void *ctx, uint32_t cell, double ta, double tb);
int grid_fat_walk(const grid_frame *f, const accel_ray_prep *p, double ta, double tb, float pad,
                  const float *t_max, grid_fat_cell_fn fn, void *ctx);

#ifdef __cplusplus
}
#endif

#endif
