/*
 * ngrid_compact.c - the compact two-level layout of the `nested_grid` kind
 * (`nested_grid:layout=compact`), after Kalojanov, Billeter & Slusallek,
 * "Two-Level Grids for Ray Tracing on GPUs", Eurographics 2011: a top
 * grid of 8-byte cells, each with its own sub-grid resolution, the leaf
 * cells of every sub-grid in one array of 4-byte offsets into one array of
 * references. (Their cells hold begin/end pairs, 8 bytes; consecutive leaf
 * cells here share the boundary, as the regular grid's compact offsets do.)
 *
 * Build: the depth-2 nested grid is built as always (ngrid_build.c,
 * ngrid_level.c: same resolutions, membership and padding), then
 * re-laid: the top cells in order, each one's leaf cells right after the
 * previous one's (a sub-grid's cells next to each other, in its own linear
 * order), their references copied in that order. The word layout's arrays
 * (cell words, count-prefixed lists, 104-byte nodes, per-sub-grid planes)
 * are freed.
 *
 * Walk: the top grid's 3D-DDA (grid_core.h); a top cell with a sub-grid
 * remakes the sub-grid's frame from the top cell's box (the top grid's own
 * planes) and its resolution with grid_frame_init, the function the build
 * used, so its planes are the same floats, and walks it with the same DDA
 * from the distance where the ray entered the top cell (a 16-entry cache
 * per batch keeps recently remade frames). Everything else,
 * the counters included, is the word layout's walk (ngrid_trace.c) at
 * depth 2, so both layouts give the same hits and the same counts.
 */
#include <stdlib.h>
#include <string.h>

#include "core/variant.h"
#include "ngrid_impl.h"

static uint32_t pack_res(const int res[3])
{
    return (uint32_t)(res[0] - 1) | (uint32_t)(res[1] - 1) << 8 | (uint32_t)(res[2] - 1) << 16;
}

static inline void unpack_res(uint32_t w, int res[3])
{
    res[0] = (int)(w & 0xFF) + 1;
    res[1] = (int)(w >> 8 & 0xFF) + 1;
    res[2] = (int)(w >> 16 & 0xFF) + 1;
}

void ngrid_compact_free(ngrid_compact *k)
{
    if (!k) return;
    free(k->top_planes);
    free(k->tops);
    free(k->leaf);
    free(k->refs);
    free(k);
}

size_t ngrid_compact_bytes(const ngrid_compact *k)
{
    return sizeof *k + grid_plane_count(k->top.res) * sizeof(float) +
           (size_t)k->top_count * sizeof *k->tops + (size_t)(k->leaf_count + 1) * sizeof *k->leaf +
           (size_t)k->ref_count * sizeof *k->refs;
}

/* The leaf cells (their list words) a top cell word stands for. */
static const uint32_t *leaf_words(const ngrid_accel *g, const uint32_t *word, uint64_t *n,
                                  const ngrid_node **child)
{
    *child = NULL;
    *n = 1;
    if (!(*word & NGRID_CHILD)) return word;
    const ngrid_node *node = &g->nodes[*word & ~NGRID_CHILD];
    *child = node;
    *n = (uint64_t)node->frame.res[0] * node->frame.res[1] * node->frame.res[2];
    return g->cells + node->cell_base;
}

int ngrid_compact_build(ngrid_accel *g, double max_bytes, accel_error *err)
{
    const grid_frame *tf = &g->nodes[0].frame;
    const uint64_t tops = (uint64_t)tf->res[0] * tf->res[1] * tf->res[2];
    uint64_t leaves = 0;
    for (uint64_t c = 0; c < tops; c++) {
        uint64_t n;
        const ngrid_node *child;
        leaf_words(g, &g->cells[c], &n, &child);
        for (int a = 0; child && a < 3; a++)
            if (child->level != 1 || child->frame.res[a] > NGRID_COMPACT_MAX_RES)
                return accel_fail(err, ACCEL_ERR_RANGE,
                                  "nested_grid:layout=compact: a sub-grid of %dx%dx%d cells at "
                                  "level %u (at most two levels, %d cells per axis)",
                                  child->frame.res[0], child->frame.res[1], child->frame.res[2],
                                  child->level, NGRID_COMPACT_MAX_RES);
        leaves += n;
    }
    ngrid_compact probe = {.top = *tf, .top_count = tops, .leaf_count = leaves,
                           .ref_count = g->ref_count};
    const double bytes = (double)ngrid_compact_bytes(&probe);
    if (leaves >= UINT32_MAX || g->ref_count >= UINT32_MAX)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "nested_grid:layout=compact: %llu leaf cells and %llu references exceed "
                          "the 32-bit offsets (raise threshold, lower lambda or sub_lambda)",
                          (unsigned long long)leaves, (unsigned long long)g->ref_count);
    if (bytes > max_bytes)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "nested_grid:layout=compact: %llu top cells, %llu leaf cells and %llu "
                          "references need %.1f MiB, above the limit of %.1f MiB (raise max_mb, "
                          "or lower lambda, res or sub_lambda)",
                          (unsigned long long)tops, (unsigned long long)leaves,
                          (unsigned long long)g->ref_count, bytes / 1048576.0,
                          max_bytes / 1048576.0);
    ngrid_compact *k = calloc(1, sizeof *k);
    if (!k) return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory");
    k->top_planes = malloc(grid_plane_count(tf->res) * sizeof *k->top_planes);
    k->tops = malloc((size_t)tops * sizeof *k->tops);
    k->leaf = accel_alloc_large((size_t)leaves + 1, sizeof *k->leaf, sizeof(void *));
    k->refs = accel_alloc_large(g->ref_count ? g->ref_count : 1, sizeof *k->refs, sizeof(void *));
    if (!k->top_planes || !k->tops || !k->leaf || !k->refs) {
        ngrid_compact_free(k);
        return accel_fail(err, ACCEL_ERR_NOMEM, "nested_grid: out of memory for %.1f MiB",
                          bytes / 1048576.0);
    }
    k->top = *tf;
    float *pl = k->top_planes;
    for (int a = 0; a < 3; a++) {
        memcpy(pl, tf->planes[a], ((size_t)tf->res[a] + 1) * sizeof *pl);
        k->top.planes[a] = pl;
        pl += tf->res[a] + 1;
    }
    k->top_count = tops;
    k->leaf_count = leaves;
    k->ref_count = g->ref_count;
    uint64_t at = 0, ref_at = 0;
    for (uint64_t c = 0; c < tops; c++) {
        uint64_t n;
        const ngrid_node *child;
        const uint32_t *words = leaf_words(g, &g->cells[c], &n, &child);
        k->tops[c].first = (uint32_t)at;
        k->tops[c].res = child ? pack_res(child->frame.res) : 0;
        for (uint64_t j = 0; j < n; j++) {
            const uint32_t *list = g->lists + words[j];
            k->leaf[at++] = (uint32_t)ref_at;
            memcpy(k->refs + ref_at, list + 1, (size_t)list[0] * sizeof *k->refs);
            ref_at += list[0];
        }
    }
    k->leaf[at] = (uint32_t)ref_at;
    free(g->nodes);
    free(g->cells);
    free(g->lists);
    free(g->planes);
    g->nodes = NULL;
    g->cells = g->lists = NULL;
    g->planes = NULL;
    g->node_count = 0;
    g->cell_count = g->list_len = 0;
    g->plane_count = 0;
    g->compact = k;
    return ACCEL_OK;
}

/* ---- the walk ---------------------------------------------------------------------- */

/*
 * Sub-grid frames of the batch's recent descents: consecutive rays of a
 * batch (8x8 tiles of primary rays) cross the same top cells, and remaking
 * a frame (grid_frame_init fills its planes, one division each) was 40% of
 * the compact walk's extra instructions. Direct-mapped by top cell, for
 * sub-grids of at most NC_CACHE_RES cells per axis; a frame from the cache
 * is the same floats as a new one, so results do not depend on it.
 */
#define NC_CACHE 16
#define NC_CACHE_RES 32
typedef struct {
    uint32_t key; /* top cell, UINT32_MAX: empty */
    grid_frame f;
    float planes[3 * (NC_CACHE_RES + 1)];
} nc_slot;

static inline __attribute__((always_inline)) void
ncompact_kernel(const ngrid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
                size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    const accel_scene *s = &g->store.prims;
    const ngrid_compact *k = g->compact;
    const grid_frame *top = &k->top;
    nc_slot cache[NC_CACHE];
    for (int j = 0; j < NC_CACHE; j++) cache[j].key = UINT32_MAX;
    for (size_t i = 0; i < count; i++) {
        accel_ray_prep p;
        accel_hit h = accel_hit_miss();
        uint32_t steps = 0, empty = 0, tests = 0, skips = 0, boxes = 0, sub_steps = 0;
        if (grid_ray_enter(top, &rays[i], k->ref_count > 0, &p, &boxes)) {
            grid_dda d;
            double t_cell = grid_dda_init(&d, top, &p, p.t_near);
            uint32_t box[GRID_MAILBOX];
            if (mailbox) grid_mailbox_clear(box);
            float t = p.t_far, u = 0.0f, v = 0.0f;
            for (;;) {
                if (c) steps++;
                if (ACCEL_STEP_BOUND_BROKEN(c, steps, g->step_bound)) break;
                const ngrid_top_cell tc = k->tops[d.cell];
                double t_exit;
                if (tc.res == 0) {
                    uint32_t b = k->leaf[tc.first], n = k->leaf[tc.first + 1] - b;
                    if (c && n == 0) empty++;
                    if (grid_cell_hit(s, k->refs + b, n, &p, &h, &t, &u, &v, box, &tests, &skips,
                                      c, occ != NULL, naive, spheres, mailbox))
                        goto done;
                    t_exit = grid_dda_exit(&d);
                    if (t_exit >= t) break;
                } else {
                    /* The sub-grid over this top cell's box, its planes
                     * remade as the build made them. */
                    nc_slot *slot = &cache[d.cell & (NC_CACHE - 1)];
                    const grid_frame *sf = &slot->f;
                    float sub_planes[3 * (NGRID_COMPACT_MAX_RES + 1)];
                    grid_frame big;
                    if (slot->key != d.cell) {
                        int res[3];
                        unpack_res(tc.res, res);
                        const box3 cb = {
                            {top->planes[0][d.idx[0]], top->planes[1][d.idx[1]],
                             top->planes[2][d.idx[2]]},
                            {top->planes[0][d.idx[0] + 1], top->planes[1][d.idx[1] + 1],
                             top->planes[2][d.idx[2] + 1]}};
                        if (res[0] <= NC_CACHE_RES && res[1] <= NC_CACHE_RES &&
                            res[2] <= NC_CACHE_RES) {
                            grid_frame_init(&slot->f, cb, res, slot->planes);
                            slot->key = d.cell;
                        } else {
                            grid_frame_init(&big, cb, res, sub_planes);
                            sf = &big;
                        }
                    }
                    grid_dda sd;
                    grid_dda_init(&sd, sf, &p, t_cell);
                    const uint32_t *leaf = k->leaf + tc.first;
                    for (;;) {
                        if (c) steps++, sub_steps++;
                        if (ACCEL_STEP_BOUND_BROKEN(c, steps, g->step_bound)) goto done;
                        uint32_t b = leaf[sd.cell], n = leaf[sd.cell + 1] - b;
                        if (c && n == 0) empty++;
                        if (grid_cell_hit(s, k->refs + b, n, &p, &h, &t, &u, &v, box, &tests,
                                          &skips, c, occ != NULL, naive, spheres, mailbox))
                            goto done;
                        t_exit = grid_dda_exit(&sd);
                        if (t_exit >= t) goto done;
                        if (!grid_dda_step(&sd)) break;
                    }
                }
                /* Left the top cell (at the sub-grid's last exit, which is
                 * the top cell's): the top walk's next cell. */
                if (!grid_dda_step(&d)) break;
                t_cell = t_exit;
            }
        }
    done:
        accel_prim_store_answer(&g->store, h, hits, occ, i);
        if (c) {
            accel_count_ray(c, i, steps, empty, boxes, tests, skips);
            c->level_steps[0] += steps - sub_steps;
            c->level_steps[1] += sub_steps;
        }
    }
}

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): the default on triangles (4) and spheres (6). */
ACCEL_KERNEL_PAIR_SEL(ncompact, ncompact_kernel, (0, 0, 0, 0, 1, 0, 1, 0), (0, 0, 0, 0, 1, 0, 1, 0))

ACCEL_KERNEL_ENTRIES(ngrid_compact_intersect, ngrid_compact_occluded, const ngrid_accel,
                     ncompact_hit_table, ncompact_occ_table, ngrid_flags)
