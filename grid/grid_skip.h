/*
 * grid_skip.h - empty-space skipping for the regular grid (grid:skip=...).
 *
 * Two ways of knowing, in an empty cell, a box of cells around it that are
 * all empty, so that the walk can jump to where the ray leaves that box
 * instead of stepping through its cells one by one:
 *
 *  - proximity clouds (Cohen & Sheffer, "Proximity clouds - an acceleration
 *    technique for 3D grid traversal", The Visual Computer 11, 1994): per
 *    cell the Chebyshev distance, in cells, to the nearest non-empty cell
 *    (0 for a non-empty cell), one byte capped at 255. With distance d every
 *    cell within Chebyshev radius d-1 is empty: the cube of radius d-1 around
 *    the current cell (clipped to the grid) is the box;
 *  - macro cells (a coarse grid of empty flags, e.g. Devillers, "The macro-
 *    regions: an efficient space subdivision structure for ray tracing",
 *    Eurographics 1989): blocks of M^3 cells with one byte saying whether
 *    all of them are empty; the block around the current cell is the box.
 *
 * Exactness of a jump (grid_dda_leave_box). The walk's cell sequence is the
 * one defined by the crossing distances t = (plane - org) * inv_dir of the
 * stored planes, in double (grid_core.h, contract point 2); these distances
 * are monotone in the plane index. The jump computes the distance at which
 * the ray crosses the box's far plane on each axis, from the same planes,
 * takes the smallest (t_exit), and puts the walk in the cell the DDA itself
 * would occupy at t_exit: per axis the cell whose entry plane is crossed at
 * or before t_exit and whose exit plane after it (grid_dda_init's rule). At
 * every distance between the current cell and t_exit the walk's per-axis
 * indices lie between the current cell's and the box's far planes, so every
 * cell the DDA would have visited in between is a cell of the box: empty.
 * No position is rounded into a cell, so no margin beyond the box is needed
 * (the cube of radius d-1, not d-2). Where t_exit is a tie between axes the
 * DDA would visit, at that single point, cells beside the box that the jump
 * does not; a primitive hit at that point touches the closed box and so
 * belongs to one of the box's cells (padded membership), which are empty.
 * If the ray ends before t_exit (t_exit >= the nearest hit or t_far) or
 * leaves the grid there, nothing lies ahead: the walk ends.
 */
#ifndef GRID_GRID_SKIP_H
#define GRID_GRID_SKIP_H

#include "grid_core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    GRID_SKIP_NONE = 0,  /* plain 3D-DDA */
    GRID_SKIP_CLOUD = 1, /* proximity clouds */
    GRID_SKIP_MACRO = 2  /* macro cells */
} grid_skip_mode;

/* Largest stored distance (cells): the byte's range. */
#define GRID_SKIP_CAP 255

/*
 * Per-cell Chebyshev distance to the nearest non-empty cell of `cells`,
 * capped at GRID_SKIP_CAP (all GRID_SKIP_CAP when every cell is empty), in
 * dist[cell_count] (caller-owned). Separable: the 1D distance along x, then
 * the min-max transform f(u) = min_i max(|u - i|, g(i)) along y and z in
 * linear time per line (Meijster, Roerdink & Hesselink, "A General Algorithm
 * for Computing Distance Transforms in Linear Time", ISMM 2000, chessboard
 * case). Capping commutes with it, so bytes suffice. Lines are independent:
 * any thread count gives the same bytes. Returns ACCEL_ERR_NOMEM or 0.
 */
int grid_skip_cloud(const grid_frame *f, const uint32_t *offsets, uint8_t *dist, int threads,
                    accel_error *err);

/* Macro-cell resolution for blocks of 2^shift cells per axis. */
static inline void grid_skip_macro_res(const int res[3], int shift, int mres[3])
{
    for (int a = 0; a < 3; a++) mres[a] = ((res[a] - 1) >> shift) + 1;
}

/* empty[m] = 1 when every cell of macro cell m (blocks of 2^shift cells per
 * axis, the last block per axis clipped to the grid) is empty. */
void grid_skip_macro(const grid_frame *f, const uint32_t *offsets, int shift, uint8_t *empty);

/* Distance at which the ray crosses the far plane of the box on axis a
 * (+inf on an axis it does not move along); *far gets the box's last cell
 * index along the ray on that axis. */
static inline __attribute__((always_inline)) double
grid_box_far_t(const grid_dda *d, const grid_frame *f, int a, const int lo[3], const int hi[3],
               int *far)
{
    if (d->step[a] > 0) {
        *far = hi[a];
        return grid_plane_t(d, a, f->planes[a][hi[a] + 1]);
    }
    *far = lo[a];
    return d->step[a] < 0 ? grid_plane_t(d, a, f->planes[a][lo[a]]) : INFINITY;
}

/* Puts axis a of the walk in the cell it occupies at t_exit (grid_dda_init's
 * rule: entry plane crossed at or before t_exit, exit plane after), given
 * the box's far plane distance t_far and last cell `far` on that axis.
 * Returns 0 when that cell is outside the grid. */
static inline __attribute__((always_inline)) int
grid_dda_settle(grid_dda *d, const grid_frame *f, int a, double t_exit, double t_far, int far)
{
    const int step = d->step[a];
    if (step == 0) return 1;
    const float *pl = f->planes[a];
    int i = d->idx[a];
    double t = d->t_next[a];
    if (t_far == t_exit) {
        i = far + step; /* the box's far plane is crossed at t_exit */
        if (i == d->out[a]) return 0;
        t = grid_plane_t(d, a, pl[step > 0 ? i + 1 : i]);
    } else {
        /* Inside the box on this axis: cross the planes the walk itself
         * crosses by t_exit (t_far > t_exit bounds the loop by the box),
         * each one DDA step along this axis without the cell lookups. */
        while (t <= t_exit) {
            i += step;
            t = grid_plane_t(d, a, pl[step > 0 ? i + 1 : i]);
        }
    }
    d->cell += (uint32_t)(i - d->idx[a]) * f->stride[a];
    d->idx[a] = i;
    d->t_next[a] = t;
    return 1;
}

/*
 * Moves the walk out of the box of cells lo[a]..hi[a] (inclusive; it holds
 * the current cell and only empty cells): to the cell the DDA occupies at
 * the distance t_exit where the ray leaves the box.
 * Returns 0 when the walk is over: the ray ends (t_end, the nearest hit or
 * t_far) at or before t_exit, or leaves the grid there. Written axis by
 * axis with constant axes, so that the walk's state stays in registers.
 */
static inline __attribute__((always_inline)) int
grid_dda_leave_box(grid_dda *d, const grid_frame *f, const int lo[3], const int hi[3],
                   double t_end)
{
    int far0, far1, far2;
    double t0 = grid_box_far_t(d, f, 0, lo, hi, &far0);
    double t1 = grid_box_far_t(d, f, 1, lo, hi, &far1);
    double t2 = grid_box_far_t(d, f, 2, lo, hi, &far2);
    double t_exit = t0 < t1 ? t0 : t1;
    t_exit = t_exit < t2 ? t_exit : t2;
    if (t_exit >= t_end) return 0;
    /* Leaving through the grid's own boundary on any axis (also at a tie
     * with an inner face): nothing of the grid lies beyond. */
    return grid_dda_settle(d, f, 0, t_exit, t0, far0) & grid_dda_settle(d, f, 1, t_exit, t1, far1) &
           grid_dda_settle(d, f, 2, t_exit, t2, far2);
}

#ifdef __cplusplus
}
#endif

#endif
