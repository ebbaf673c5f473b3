/*
 * ngrid_packet_kernel.h - the `nested_grid` kind's coherent packet walk
 * through every level (described in ngrid_packet.c).
 * A kernel body (C only), private to nested_grid/: the including unit
 * defines NGRID_PACKET_BLOCKS, 0 (the default) for the walk on id lists
 * (ngrid_packet.c) or 1 for the walk on blocks (cells=blocks: the kernel unit k8_packet.c, compiled
 * once per ISA, core/isa.h, since it inlines the shared block test). The
 * sub-grid walk is recursive, so the choice is the preprocessor's, not a
 * constant argument.
 */
#ifndef NESTED_GRID_NGRID_PACKET_KERNEL_H
#define NESTED_GRID_NGRID_PACKET_KERNEL_H

#include <math.h>
#include <string.h>

#include "core/variant.h"
#include "grid/grid_packet_walk.h"
#include "ngrid_impl.h"

#ifndef NGRID_PACKET_BLOCKS
#define NGRID_PACKET_BLOCKS 0 /* the walk on ids */
#endif

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
            if (NGRID_PACKET_BLOCKS ? !grid_packet_test_blocks(w->pk, w->cn, w->c, w->mail,
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
        if (!visit_cells(w, f, node, leaf, k, lo, hi, (const double(*)[2])hull)) return 0;
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
            const double(*ch)[2] = (const double(*)[2])hull; /* C11: no implicit const */
            if (!(w->g->compact ? visit_compact(w, k, lo, hi, ch)
                                : visit_cells(w, top, &w->g->nodes[0], NULL, k, lo, hi, ch)))
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
     * test only; the copies on blocks are the kernel unit k8_packet.c's. */
    const grid_list_blocks *blocks = NGRID_PACKET_BLOCKS ? &g->blocks : NULL;
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

/* The blocks' tables (k8_packet.c): query 0 closest hit, 1 any hit; the
 * AVX2 copy and, where the build has it, the AVX-512 one. */
const accel_kernel_table *ngrid_k8_packet(int query);
const accel_kernel_table *ngrid_k8_packet_avx512(int query);

#undef P

#endif
