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
 * the mailbox=0 copies only (igrid_build.c); those copies are the kernel
 * unit k8_cells.c's, compiled once per ISA (core/isa.h), and the walk
 * itself is igrid_kernel.h's.
 */
#include "core/isa.h"
#include "igrid_kernel.h"

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): mailbox=0 (0), the default on triangles (4) and spheres (6), and
 * closest hits with the naive test (5). */
static inline __attribute__((always_inline)) void
igrid_kernel_ids(const igrid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
                 size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    igrid_kernel(g, rays, hits, occ, count, c, naive, spheres, mailbox, 0);
}
ACCEL_KERNEL_PAIR_SEL(igrid, igrid_kernel_ids, (1, 0, 0, 0, 1, 1, 1, 0), (1, 0, 0, 0, 1, 0, 1, 0))

static unsigned igrid_flags(const igrid_accel *g)
{
    return accel_variant_flags(g->naive, g->has_spheres, g->mailbox);
}

/* The table of g (query 0 closest hit, 1 any hit): with cells=blocks the
 * kernel unit's (k8_cells.c) of g's isa. */
static const accel_kernel_table *igrid_table(const igrid_accel *g, int query)
{
    if (g->blocks.offsets) {
#ifdef GRIDBVH_AVX512
        if (g->isa == ACCEL_ISA_AVX512) return igrid_k8_cells_avx512(query);
#endif
        return igrid_k8_cells(query);
    }
    return query ? &igrid_occ_table : &igrid_hit_table;
}

void igrid_intersect(const void *accel, const accel_ray *rays, accel_hit *hits, size_t count,
                     accel_counters *c)
{
    accel_run_kernel(igrid_table(accel, 0), accel, rays, hits, count, c, igrid_flags(accel));
}

void igrid_occluded(const void *accel, const accel_ray *rays, uint8_t *occ, size_t count,
                    accel_counters *c)
{
    accel_run_kernel(igrid_table(accel, 1), accel, rays, occ, count, c, igrid_flags(accel));
}

/* accel.h's conservative walk: the simplest correct one, every primitive
 * whose bounding box grown by the pad the ray reaches (the primitive
 * store's walk, in store order; README.md says why not a padded walk of
 * the cells). */
int igrid_walk(const void *a, const accel_ray *ray, float pad, accel_walk_visit visit,
               void *ctx, uint32_t *steps)
{
    return accel_prim_store_walk(&((const igrid_accel *)a)->store, ray, pad, visit, ctx, steps);
}
