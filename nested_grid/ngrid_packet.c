/*
 * ngrid_packet.c - coherent grid traversal of the nested grid
 * (`nested_grid:traverse=packet`, both layouts), the packet walk of
 * grid/grid_packet_trace.c (Wald, Ize, Kensler, Knoll and Parker, SIGGRAPH 2006)
 * carried into the levels.
 *
 * The packet (grid_packet_setup over the top grid) walks the top grid slice
 * by slice along its axis K. In each top slice, the cells of the slice's
 * range are visited: a cell holding a list has it tested against the packet
 * as in the regular grid (mailbox, slice cull, 4-ray filter, exact tests;
 * with cells=blocks the list's blocks, grid_packet_test_blocks, the
 * block test for the rays a triangle of a block kept);
 * a cell holding a sub-grid has the sub-grid walked slice by slice along the
 * same axis and direction (its slices subdivide the top slice: its box is
 * the top cell's, bounded by the top grid's own planes), each sub-slice with
 * its own, narrower range of sub-cells, recursively at every level. Rays are
 * retired only after a whole top slice, with the regular grid's rule on the
 * top slice's exit plane. A sub-slice is skipped when its entry plane lies
 * beyond the end of every active ray (w_end: nearest hit so far, box exit or
 * t_far, each widened by its rounding). A packet too wide for a sub-grid's
 * cells, or over its visit budget, gives up (below): its active rays are
 * traced again from the start by the single-ray walk, whose answers replace
 * theirs; retired rays keep theirs, which are final.
 *
 * Why the answer is the single-ray walk's and the reference's: the argument
 * of grid_packet_trace.c, level by level. Let the ray's nearest accepted hit p
 * (on primitive q) lie in top slice k, top cell c and, if c holds a
 * sub-grid, in its sub-slice k' and sub-cell c' (and so on down). The ray is
 * active in top slice k (it is retired only after a top slice, by a hit no
 * farther than p or an end beyond p). The range of top slice k bounds every
 * point of every active ray in the slice, so c is visited; the range of
 * sub-slice k' bounds every point of those rays in the sub-slice, so c' is
 * visited; and k' is not skipped, since its entry plane lies at or before p,
 * which lies at or before the ray's w_end. q belongs to c' (conservative
 * membership at every level, ngrid_impl.h's padding), and q's box holds p,
 * so the slice cull keeps q: q is tested against the ray unless the mailbox
 * holds it, and then it was tested (or shown out of reach) for every ray
 * active at the time, this one among them. The pads of the ranges are the
 * top grid's (1/1024 of a top cell plus the rounding bounds), wider than any
 * level's own. Every level's cells are visited with the packet's one
 * mailbox, as the single-ray walk shares its mailbox across levels.
 *
 * Counters (counted runs): steps = cells visited at any level (a top cell
 * holding a sub-grid included, as in the single-ray walk), per ray active at
 * the visit; prim_tests, mailbox_skips and packet_box_tests as in
 * grid_packet_trace.c; level_steps are not split by level in packet mode. The
 * step bound is the top grid's slice count per packet.
 */
#include "core/coherence.h"
#include "grid/grid_packet_walk.h"
#include "ngrid_impl.h"

#define P GRID_PACKET_SIZE

/* The walk's state, shared by every level. Flags are runtime values here:
 * the sub-grid walk is recursive and cannot be specialized by inlining. */
typedef struct {
    const ngrid_accel *g;
    const accel_scene *s;
    grid_packet *pk;
    grid_packet_count *cn;
    accel_counters *c;
    uint32_t *mail;
    const grid_list_blocks *blocks; /* cells=blocks: the lists as blocks, else NULL */
    double w_max; /* at least every active ray's w_end */
    uint64_t visits, budget; /* cells visited by this packet, and the most it may visit */
    int aborted;             /* the budget ran out: the active rays go to the single-ray walk */
    int naive, spheres, mailbox, any_hit;
} nwalk;

/* Ends the packet walk: its active rays go to the single-ray walk. */
static int give_up(nwalk *w)
{
    w->aborted = 1;
    return 0;
}

/* Counts a cell visit against the packet's budget; 0 once it runs out. */
static inline int spend(nwalk *w)
{
    return ++w->visits <= w->budget || give_up(w);
}

static inline int test_list(nwalk *w, const uint32_t *ids, uint32_t n, const double hull[2][2])
{
    return grid_packet_test_list(w->s, w->pk, w->cn, w->c, w->mail, ids, n, hull, w->naive,
                                 w->spheres, w->mailbox, w->any_hit);
}

static inline void count_grid_cell(nwalk *w)
{
    if (w->c) w->cn->visits++;
}

/* Largest w_end over the active rays. */
static double active_w_max(const grid_packet *pk)
{
    double m = -INFINITY;
    for (uint64_t a = pk->active; a; a &= a - 1) {
        const double e = pk->w_end[__builtin_ctzll(a)];
        m = e > m ? e : m;
    }
    return m;
}

/* Slice i of a sub-grid along the walk: its index, or -1 once the slice
 * starts beyond every active ray's end. */
static inline int sub_slice(const nwalk *w, const grid_frame *f, int i)
{
    const grid_packet *pk = w->pk;
    const int K = pk->axis[0], n = f->res[K];
    const int k = pk->kstep > 0 ? i : n - 1 - i;
    const double w_in = pk->kstep * (double)f->planes[K][pk->kstep > 0 ? k : k + 1];
    return w_in > w->w_max ? -1 : k;
}

/* ---- when the packet gives up ----------------------------------------------------- */

/* A sub-grid whose first reached slice spans more than this many cells on
 * an axis ends the packet walk: the packet's footprint there is far wider
 * than the cells (shadow rays from a finely meshed surface to a light,
 * whose 8x8 tile covers thousands of sub-cells), and it would visit cells
 * no ray passes through. Its active rays are traced again by the
 * single-ray walk (retrace below). Measured in grid/README.md ("Nested
 * grid"). */
#ifndef NGRID_PACKET_WIDE
#define NGRID_PACKET_WIDE 8
#endif
/* Most cells a packet may visit per live ray before it gives up the same
 * way: a bound on the worst case, not a tuning knob (the widest packets
 * that pass the rule above visit about 1,000 per ray on teapot_stadium). */
#ifndef NGRID_PACKET_BUDGET
#define NGRID_PACKET_BUDGET 4096
#endif

/* ---- sub-grids, both layouts ------------------------------------------------------ */

static int walk_sub(nwalk *w, const grid_frame *f, const ngrid_node *node, const uint32_t *leaf);

/* The cells [lo, hi] of slice k of grid f: a word-layout grid (node: cell
 * words, a child word walks its sub-grid) or a compact sub-grid (leaf:
 * leaf cell k holds refs[leaf[k] .. leaf[k+1])). */
static int visit_cells(nwalk *w, const grid_frame *f, const ngrid_node *node, const uint32_t *leaf,
                       int k, const int lo[2], const int hi[2], const double hull[2][2])
{
    const grid_packet *pk = w->pk;
    const uint32_t *words = node ? w->g->cells + node->cell_base : NULL;
    const uint32_t st1 = f->stride[pk->axis[1]], st2 = f->stride[pk->axis[2]];
    for (int j = lo[1]; j <= hi[1]; j++) {
        const uint32_t row = (uint32_t)k * f->stride[pk->axis[0]] + (uint32_t)j * st2;
        for (int i = lo[0]; i <= hi[0]; i++) {
            const uint32_t cell = row + (uint32_t)i * st1;
            if (!spend(w)) return 0;
            if (leaf) {
                if (!test_list(w, w->g->compact->refs + leaf[cell], leaf[cell + 1] - leaf[cell], hull))
                    return 0;
                continue;
            }
            const uint32_t word = words[cell];
            if (word & NGRID_CHILD) {
                count_grid_cell(w);
                const ngrid_node *child = &w->g->nodes[word & ~NGRID_CHILD];
                if (!walk_sub(w, &child->frame, child, NULL)) return 0;
                continue;
            }
            const uint32_t *list = w->g->lists + word;
            if (w->blocks ? !grid_packet_test_blocks(w->pk, w->cn, w->c, w->mail,
                                                     w->blocks->blocks, w->blocks->first[word],
                                                     list[0], w->s->tri_count, hull, w->mailbox,
                                                     w->any_hit)
                          : !test_list(w, list + 1, list[0], hull))
                return 0;
        }
    }
    return 1;
}

/* A sub-grid (cells as in visit_cells), slice by slice in the walk's
 * direction. The packet gives up when the first slice it reaches spans
 * more than NGRID_PACKET_WIDE cells on an axis. */
static int walk_sub(nwalk *w, const grid_frame *f, const ngrid_node *node, const uint32_t *leaf)
{
    const int n = f->res[w->pk->axis[0]];
    int first = 1;
    for (int i = 0; i < n; i++) {
        const int k = sub_slice(w, f, i);
        if (k < 0) break;
        int lo[2], hi[2];
        double hull[2][2];
        if (!grid_packet_span(f, w->pk, k, k, lo, hi, hull)) continue;
        if (first && (hi[0] - lo[0] >= NGRID_PACKET_WIDE || hi[1] - lo[1] >= NGRID_PACKET_WIDE))
            return give_up(w);
        first = 0;
        if (!visit_cells(w, f, node, leaf, k, lo, hi, hull)) return 0;
    }
    return 1;
}

/* ---- the compact layout's top level ---------------------------------------------------- */

/* A top cell's sub-grid: its frame remade from the top planes as the build
 * and the single-ray walk make it (ngrid_compact.c), then walked. */
static int walk_compact_sub(nwalk *w, const int idx[3], ngrid_top_cell tc)
{
    const ngrid_compact *kc = w->g->compact;
    const grid_frame *top = &kc->top;
    float planes[3 * (NGRID_COMPACT_MAX_RES + 1)];
    grid_frame f;
    const int res[3] = {(int)(tc.res & 0xFF) + 1, (int)(tc.res >> 8 & 0xFF) + 1,
                        (int)(tc.res >> 16 & 0xFF) + 1};
    const box3 cb = {{top->planes[0][idx[0]], top->planes[1][idx[1]], top->planes[2][idx[2]]},
                     {top->planes[0][idx[0] + 1], top->planes[1][idx[1] + 1],
                      top->planes[2][idx[2] + 1]}};
    grid_frame_init(&f, cb, res, planes);
    return walk_sub(w, &f, NULL, kc->leaf + tc.first);
}

/* The cells [lo, hi] of top slice k of the compact layout. */
static int visit_compact(nwalk *w, int k, const int lo[2], const int hi[2],
                         const double hull[2][2])
{
    const ngrid_compact *kc = w->g->compact;
    const grid_frame *f = &kc->top;
    const grid_packet *pk = w->pk;
    const int K = pk->axis[0], a1 = pk->axis[1], a2 = pk->axis[2];
    int idx[3];
    idx[K] = k;
    for (int j = lo[1]; j <= hi[1]; j++) {
        idx[a2] = j;
        for (int i = lo[0]; i <= hi[0]; i++) {
            idx[a1] = i;
            const uint32_t cell = (uint32_t)idx[0] + f->stride[1] * (uint32_t)idx[1] +
                                  f->stride[2] * (uint32_t)idx[2];
            const ngrid_top_cell tc = kc->tops[cell];
            if (!spend(w)) return 0;
            if (tc.res == 0) {
                const uint32_t b = kc->leaf[tc.first];
                if (!test_list(w, kc->refs + b, kc->leaf[tc.first + 1] - b, hull)) return 0;
                continue;
            }
            count_grid_cell(w);
            if (!walk_compact_sub(w, idx, tc)) return 0;
        }
    }
    return 1;
}

/* ---- the top walk and the batch ------------------------------------------------------ */

static void packet_walk(nwalk *w, const grid_frame *top)
{
    grid_packet *pk = w->pk;
    const int nk = top->res[pk->axis[0]];
    uint32_t slices = 0;
    for (int k = pk->k_start; k >= 0 && k < nk; k += pk->kstep) {
        slices++;
        if (ACCEL_STEP_BOUND_BROKEN(w->c, slices, nk)) return;
        /* Tighter bounds once a quarter of the rays have stopped. */
        if (4 * __builtin_popcountll(pk->active) <= 3 * __builtin_popcountll(pk->bounded))
            grid_packet_bound(pk);
        int lo[2], hi[2];
        double hull[2][2];
        if (grid_packet_span(top, pk, k, k, lo, hi, hull)) {
            w->w_max = active_w_max(pk);
            if (!(w->g->compact ? visit_compact(w, k, lo, hi, hull)
                                : visit_cells(w, top, &w->g->nodes[0], NULL, k, lo, hi, hull)))
                return;
        }
        if (!grid_packet_leave_slice(top, pk, w->cn, w->c, k)) return;
    }
}

/* A packet whose walk ran over its budget: its still active rays (mask
 * `left`) traced again from the start by the single-ray walk, which
 * overwrites their answers; in counted runs they pay both walks. */
static void retrace(const ngrid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
                    uint64_t left, accel_counters *c, size_t base)
{
    accel_ray r[P];
    accel_hit h[P];
    uint8_t o[P];
    uint32_t steps[P], prims[P];
    int idx[P], n = 0;
    for (uint64_t m = left; m; m &= m - 1) {
        idx[n] = __builtin_ctzll(m);
        r[n] = rays[idx[n]];
        n++;
    }
    accel_counters sub, *cs = NULL;
    if (c) {
        memset(&sub, 0, sizeof sub);
        sub.ray_steps = steps;
        sub.ray_prims = prims;
        cs = &sub;
    }
    if (occ)
        ngrid_single_occluded(g, r, o, (size_t)n, cs);
    else
        ngrid_single_intersect(g, r, h, (size_t)n, cs);
    for (int i = 0; i < n; i++) {
        if (occ)
            occ[idx[i]] = o[i];
        else
            hits[idx[i]] = h[i];
        if (c && c->ray_steps) c->ray_steps[base + idx[i]] += steps[i];
        if (c && c->ray_prims) c->ray_prims[base + idx[i]] += prims[i];
    }
    if (c) {
        sub.rays = 0; /* counted with the packet */
        sub.ray_steps = sub.ray_prims = NULL;
        memset(sub.level_steps, 0, sizeof sub.level_steps); /* not split in packet mode */
        accel_counters_add(c, &sub);
    }
}

static inline __attribute__((always_inline)) void
npacket_batch(const ngrid_accel *g, const accel_ray *rays, accel_hit *hits, uint8_t *occ,
              size_t count, accel_counters *c, int naive, int spheres, int mailbox)
{
    grid_packet pk; /* about 24 KB, aligned by its members */
    grid_packet_count cn;
    uint32_t mail[GRID_PACKET_MAIL];
    const grid_frame *top = g->compact ? &g->compact->top : &g->nodes[0].frame;
    /* cells=blocks (layout=words): built for triangles with the watertight
     * test only. */
    const grid_list_blocks *blocks = !naive && !spheres && g->blocks.first ? &g->blocks : NULL;
    nwalk w = {g, &g->store.prims, &pk, &cn, c, mail, blocks, 0.0, 0, 0, 0, naive, spheres,
               mailbox, occ != NULL};
    for (size_t base = 0; base < count; base += P) {
        const uint32_t n = (uint32_t)(count - base < P ? count - base : P);
        for (size_t i = base + P; i < base + 2 * P && i < count; i += 2)
            __builtin_prefetch(&rays[i]); /* the next packet: 2 rays per cache line */
        const int mode = grid_packet_setup(top, g->ref_count, GRID_PACKET_MAX_CELLS, &pk, rays + base, n);
        if (mode == GRID_PACKET_SINGLE) {
            /* level_steps are not split in packet mode: the single-ray
             * walk's are dropped, so that a batch mixing walked and
             * fallen-back packets (any ray order) keeps levels 0 or all */
            uint64_t levels[NGRID_MAX_LEVELS];
            if (c) memcpy(levels, c->level_steps, sizeof levels);
            grid_packet_trace_single(g, ngrid_single_intersect, ngrid_single_occluded,
                                     rays + base, hits ? hits + base : NULL,
                                     occ ? occ + base : NULL, n, c, base);
            if (c) memcpy(c->level_steps, levels, sizeof levels);
            continue;
        }
        if (c) memset(&cn, 0, sizeof cn);
        w.aborted = 0;
        if (mode == GRID_PACKET_WALK) {
            if (mailbox) memset(mail, 0xFF, sizeof mail); /* ACCEL_MISS: no primitive */
            w.visits = 0;
            w.budget = NGRID_PACKET_BUDGET * (uint64_t)__builtin_popcountll(pk.live);
            packet_walk(&w, top);
        }
        const uint64_t left = w.aborted ? pk.active : 0;
        grid_packet_finish(&g->store, &pk, &cn, hits, occ, c, base, mode == GRID_PACKET_WALK);
        if (left) retrace(g, rays + base, hits ? hits + base : NULL, occ ? occ + base : NULL, left, c, base);
    }
}

/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): the default on triangles (4) and spheres (6), and closest hits
 * with the naive test (5). */
ACCEL_KERNEL_PAIR_SEL(npacket, npacket_batch, (0, 0, 0, 0, 1, 1, 1, 0), (0, 0, 0, 0, 1, 0, 1, 0))

/* Packets in any ray order (core/coherence.h); incoherent packets fall
 * back to the single-ray nested grid in npacket_batch, on the walk's
 * criterion. */
ACCEL_COHERENT_ENTRIES(ngrid_packet_intersect, ngrid_packet_occluded, const ngrid_accel,
                       npacket_hit_table, npacket_occ_table, ngrid_packet_flags,
                       (accel_hit_batch_fn)NULL, (accel_occ_batch_fn)NULL)
