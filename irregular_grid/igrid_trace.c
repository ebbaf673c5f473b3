/*
 * igrid_trace.c - traversal of the `irregular_grid` kind, closest hit and
 * any hit (Perard-Gayot, Kalojanov & Slusallek, EG 2017, section 5, made
 * exact on the CPU).
 *
 * Per ray: clip to the grid box (box3_slab), then locate the voxel of the
 * lattice the ray is in at its entry distance with grid_dda_init (the
 * regular grid's setup on the lattice's planes). Then repeat:
 *   1. the cell of the current voxel, through the voxel map (top grid entry,
 *      then the octree below it);
 *   2. test the cell's primitives against the whole ray, keeping the
 *      nearest hit even beyond the cell;
 *   3. t_exit, the distance at which the ray leaves the cell's exit box: the
 *      smallest crossing distance of its far planes, (plane - org) * inv_dir
 *      from the lattice's stored planes, in double; stop when t_exit reaches
 *      the nearest hit (or the ray's end);
 *   4. the voxel the ray is in at t_exit, by the DDA's own rule: per axis,
 *      the voxel whose entry plane is crossed at or before t_exit and whose
 *      exit plane after it. On an axis whose far plane gives t_exit that is
 *      the voxel just past the box (the walk leaves the grid when there is
 *      none); on another axis it lies between the current voxel and the
 *      box's far face, guessed from the position and settled on the plane
 *      distances.
 *
 * Why no cell is skipped: the voxel sequence is the regular grid's on the
 * lattice (the same planes, distances and rule), and between two located
 * voxels every voxel the DDA passes lies in the exit box just left; by the
 * expansion's invariant (igrid_impl.h) its primitives are a subset of the
 * cell's, all tested. Membership is padded by 1/1024 voxel as in the
 * regular grid, so a hit on a box boundary belongs to the cell left there.
 * Every iteration moves at least one voxel forward along one axis, so a ray
 * visits at most nx+ny+nz+3 cells of the lattice (the counted runs' bound).
 *
 * Step 2 is grid_core.h's cell visit, the regular grid's: the same per-ray
 * mailbox, on the stack. With cells=blocks it is the regular grid's block
 * visit (grid/grid_blocks.h): the cell's triangles 8 at a time with the
 * shared block test, no mailbox (a triangle met again in a later cell is
 * tested again and gives the same hit), the nearest hit kept as above, so
 * the stopping rule and its argument stand unchanged. Blocks are traced by
 * the mailbox=0 copies only (igrid_build.c), the other copies never
 * compile the block test.
 */
#include "core/variant.h"
#include "grid/grid_blocks.h"
#include "igrid_impl.h"

/* Distance at which the ray leaves box [lo, hi) on axis a (+inf on an axis
 * it does not move along). */
static inline __attribute__((always_inline)) double
exit_t(const grid_dda *d, const grid_frame *f, int a, const igrid_cell *cell)
{
    if (d->step[a] > 0) return grid_plane_t(d, a, f->planes[a][cell->hi[a]]);
    if (d->step[a] < 0) return grid_plane_t(d, a, f->planes[a][cell->lo[a]]);
    return INFINITY;
}

/* Step 4 on axis a: the voxel at t_exit. Returns 0 when the ray leaves the
 * grid there. */
static inline __attribute__((always_inline)) int
settle(grid_dda *d, const grid_frame *f, int a, float dir, const igrid_cell *cell, double t_a,
       double t_exit)
{
    const int step = d->step[a];
    if (step == 0) return 1;
    if (t_a == t_exit) {
        int i = step > 0 ? cell->hi[a] : cell->lo[a] - 1;
        d->idx[a] = i;
        return i != d->out[a];
    }
    const float *pl = f->planes[a];
    const int near = d->idx[a];
    const int lo = step > 0 ? near : cell->lo[a], hi = step > 0 ? cell->hi[a] - 1 : near;
    double g = (d->org[a] + t_exit * dir - f->lo[a]) * f->inv_cell[a];
    int i = g >= hi ? hi : (g > lo ? (int)g : lo);
    /* Planes tied at t_exit (grid_dda_init): the first voxel of the run. */
    if (step > 0) {
        while (i > lo && grid_plane_t(d, a, pl[i]) > t_exit) i--;
        while (i < hi && grid_plane_t(d, a, pl[i + 1]) <= t_exit) i++;
        while (i > lo && grid_plane_t(d, a, pl[i - 1]) == t_exit) i--;
    } else {
        while (i < hi && grid_plane_t(d, a, pl[i + 1]) > t_exit) i++;
        while (i > lo && grid_plane_t(d, a, pl[i]) <= t_exit) i--;
        while (i < hi && grid_plane_t(d, a, pl[i + 2]) == t_exit) i++;
    }
    d->idx[a] = i;
    return 1;
}

static inline __attribute__((always_inline)) void
igrid_kernel(const igrid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
             size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    const accel_scene *s = &g->store.prims;
    const grid_frame *f = &g->frame;
    const igrid_cell *cells = g->cells;
    const uint32_t *refs = g->refs, *map = g->map;
    const int shift = g->shift;
    const grid_cell_blocks *blocks =
        !naive && !spheres && !mailbox && g->blocks.offsets ? &g->blocks : NULL;
    for (size_t i = 0; i < count; i++) {
        accel_ray_prep p;
        accel_hit h = accel_hit_miss();
        uint32_t steps = 0, empty = 0, tests = 0, skips = 0, boxes = 0;
        if (grid_ray_enter(f, &rays[i], g->ref_count > 0, &p, &boxes)) {
            grid_dda d;
            grid_dda_init(&d, f, &p, p.t_near);
            uint32_t mail[GRID_MAILBOX];
            if (mailbox) grid_mailbox_clear(mail);
            wide_leaf_ray_8 lr; /* a few broadcasts: set always, used by blocks */
            leaf_setup_8(&lr, &p);
            float t = p.t_far, u = 0.0f, v = 0.0f;
            for (;;) {
                if (c) steps++;
                if (ACCEL_STEP_BOUND_BROKEN(c, steps, g->step_bound)) break;
                /* 1. The cell of the current voxel. */
                const igrid_cell *cell =
                    &cells[igrid_lookup(map, g->top_res, shift, d.idx[0], d.idx[1], d.idx[2])];
                /* 2. Its primitives. */
                uint32_t k = cell->begin, end = cell->end;
                if (c && k == end) empty++;
                if (blocks) {
                    /* Cell ids index the blocks' offsets (cells are
                     * numbered as their lists lie in refs). */
                    const uint32_t cid = (uint32_t)(cell - cells);
                    if (c) tests += end - k;
                    if (k != end && grid_cell_hit_blocks(blocks, cid, s->tri_count, &lr, &p, &h,
                                                         &t, &u, &v, occ != NULL))
                        goto done;
                } else if (grid_cell_hit(s, refs + k, end - k, &p, &h, &t, &u, &v, mail, &tests,
                                         &skips, c, occ != NULL, naive, spheres, mailbox)) {
                    goto done;
                }
                /* 3. Where the ray leaves the exit box. */
                double t0 = exit_t(&d, f, 0, cell), t1 = exit_t(&d, f, 1, cell);
                double t2 = exit_t(&d, f, 2, cell);
                double t_exit = t0 < t1 ? t0 : t1;
                t_exit = t_exit < t2 ? t_exit : t2;
                if (t_exit >= t) break;
                /* 4. The voxel there. */
                if (!(settle(&d, f, 0, p.dir.x, cell, t0, t_exit) &
                      settle(&d, f, 1, p.dir.y, cell, t1, t_exit) &
                      settle(&d, f, 2, p.dir.z, cell, t2, t_exit)))
                    break;
            }
        }
    done:
        accel_prim_store_answer(&g->store, h, hits, occ, i);
        if (c) accel_count_ray(c, i, steps, empty, boxes, tests, skips);
    }
}

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): mailbox=0 (0), the default on triangles (4) and spheres (6), and
 * closest hits with the naive test (5). */
ACCEL_KERNEL_PAIR_SEL(igrid, igrid_kernel, (1, 0, 0, 0, 1, 1, 1, 0), (1, 0, 0, 0, 1, 0, 1, 0))

static unsigned igrid_flags(const igrid_accel *g)
{
    return accel_variant_flags(g->naive, g->has_spheres, g->mailbox);
}

ACCEL_KERNEL_ENTRIES(igrid_intersect, igrid_occluded, const void, igrid_hit_table,
                     igrid_occ_table, igrid_flags)

/* accel.h's conservative walk: the simplest correct one, every primitive
 * whose bounding box grown by the pad the ray reaches (the primitive
 * store's walk, in store order; README.md says why not a padded walk of
 * the cells). */
int igrid_walk(const void *a, const accel_ray *ray, float pad, accel_walk_visit visit,
               void *ctx, uint32_t *steps)
{
    return accel_prim_store_walk(&((const igrid_accel *)a)->store, ray, pad, visit, ctx, steps);
}
