/*
 * ngrid_trace.c - traversal of the `nested_grid` kind: a hierarchical
 * 3D-DDA (Amanatides & Woo, Eurographics 1987, at every level; the
 * descent follows Jevans & Wyvill, Graphics Interface 1989), closest-hit
 * and any-hit.
 *
 * Per ray: clip to the top grid's box (robust slab test, geom.h) and set up
 * the top walk at the entry distance. Each level keeps its own DDA state on
 * a small stack. Entering a cell that holds a sub-grid sets up the sub-grid's
 * walk at the distance where the ray entered that cell; when the sub-grid's
 * walk leaves its box, the parent's walk takes its next step (and so on up).
 * A sub-grid's box is its parent cell's box, bounded by the parent's own
 * boundary planes, so the sub-walk leaves at exactly the distance the
 * parent's walk would have left the cell.
 *
 * The stopping rule is the regular grid's, applied to whichever cell is
 * current, at any level: every primitive tested keeps its nearest hit even
 * beyond the current cell, and the walk stops once the current cell's exit
 * distance reaches that hit. Every later cell, at any level, starts at or
 * beyond that exit, so the hit kept is the nearest one, and a primitive
 * tested in one cell never needs testing again: the per-ray mailbox
 * (grid_core.h's cell visit, on the stack) is shared by all levels.
 *
 * Kernels are written once (ngrid_kernel) and compiled into one variant
 * table per query (core/variant.h): spheres, naive triangles and mailbox
 * (ACCEL_V_OPT) as constants. The uncounted copies contain no counting code and
 * no step-bound check; counted runs check the build's bound on the cells one
 * ray can visit over all levels. The walk itself is ngrid_kernel.h's; its
 * copies on blocks (cells=blocks) are the kernel unit k8_cells.c's, one
 * per ISA (core/isa.h).
 */
#include "core/isa.h"
#include "ngrid_kernel.h"

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): index 0, the default on triangles (4) and spheres (6), and
 * closest hits with the naive test (5). */
static inline __attribute__((always_inline)) void
ngrid_kernel_ids(const ngrid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
                 size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    ngrid_kernel(g, rays, hits, occ, count, c, naive, spheres, mailbox, 0);
}
ACCEL_KERNEL_PAIR_SEL(ngrid, ngrid_kernel_ids, (1, 0, 0, 0, 1, 1, 1, 0), (1, 0, 0, 0, 1, 0, 1, 0))

/* The table of g (query 0 closest hit, 1 any hit): with cells=blocks the
 * kernel unit's (k8_cells.c) of g's isa. */
static const accel_kernel_table *ngrid_table(const ngrid_accel *g, int query)
{
    if (g->blocks.first) {
#ifdef GRIDBVH_AVX512
        if (g->isa == ACCEL_ISA_AVX512) return ngrid_k8_cells_avx512(query);
#endif
        return ngrid_k8_cells(query);
    }
    return query ? &ngrid_occ_table : &ngrid_hit_table;
}

void ngrid_single_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                            size_t count, accel_counters *counters)
{
    const ngrid_accel *g = accel;
    if (g->compact) {
        ngrid_compact_intersect(g, rays, hits, count, counters);
        return;
    }
    accel_run_kernel(ngrid_table(g, 0), accel, rays, hits, count, counters, ngrid_flags(accel));
}

void ngrid_single_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded,
                           size_t count, accel_counters *counters)
{
    const ngrid_accel *g = accel;
    if (g->compact) {
        ngrid_compact_occluded(g, rays, occluded, count, counters);
        return;
    }
    accel_run_kernel(ngrid_table(g, 1), accel, rays, occluded, count, counters, ngrid_flags(accel));
}

/* ---- accel.h's conservative walk --------------------------------------------
 * grid_core.h's fat walk at every level: the top grid's cells whose boxes
 * grown by the pad the ray reaches, and in a cell holding a sub-grid the
 * same walk of the sub-grid over the piece of the ray that reached the
 * cell (a sub-grid's box is its parent cell's, so a primitive within the
 * pad of the ray lies in a reached cell at every level). The primitives of
 * every reached list go to the visitor, through the cell visit's mailbox. */
typedef struct {
    const ngrid_accel *g;
    const accel_ray_prep *p;
    const ngrid_node *node; /* the grid being walked */
    float pad, t_max;
    accel_walk_visit visit;
    void *ctx;
    uint32_t *steps;
    uint32_t mailbox[GRID_MAILBOX];
} ngrid_walker;

/* One primitive (a local id) to the visitor; 0 once the walk is over. */
static inline __attribute__((always_inline)) int walk_prim(void *ctx, uint32_t prim)
{
    ngrid_walker *w = ctx;
    w->t_max = w->visit(w->ctx, w->g->store.scene_id[prim], w->t_max);
    return !(w->t_max < w->p->t_near);
}

static int walk_cell(void *ctx, uint32_t cell, double ta, double tb)
{
    ngrid_walker *w = ctx;
    const ngrid_node *node = w->node;
    uint32_t word = w->g->cells[node->cell_base + cell];
    (*w->steps)++;
    if (word & NGRID_CHILD) {
        w->node = &w->g->nodes[word & ~NGRID_CHILD];
        int go = grid_fat_walk(&w->node->frame, w->p, ta, tb, w->pad, &w->t_max, walk_cell, w);
        w->node = node;
        return go;
    }
    const uint32_t *list = w->g->lists + word;
    uint32_t skips = 0; /* not reported: the walk counts cells only */
    return grid_cell_visit(list + 1, list[0], w->mailbox, &skips, walk_prim, w);
}

int ngrid_walk(const void *accel, const accel_ray *ray, float pad, accel_walk_visit visit,
               void *ctx, uint32_t *steps)
{
    const ngrid_accel *g = accel;
    /* The compact layout keeps no nodes to walk: the store's padded-box walk
     * (correct, not fast; a compact fat walk is not written). */
    if (g->compact) return accel_prim_store_walk(&g->store, ray, pad, visit, ctx, steps);
    accel_ray_prep p;
    if (!visit || g->ref_count == 0 || !accel_prep_ray(ray, &p)) return 0;
    ngrid_walker w = {g, &p, &g->nodes[0], pad, p.t_far, visit, ctx, steps, {0}};
    grid_mailbox_clear(w.mailbox);
    grid_fat_walk(&g->nodes[0].frame, &p, p.t_near, p.t_far, pad, &w.t_max, walk_cell, &w);
    return 0;
}
