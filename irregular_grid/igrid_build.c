/*
 * igrid_build.c - build and bookkeeping of the `irregular_grid` kind
 * (Perard-Gayot, Kalojanov & Slusallek, EG 2017; igrid.h; its parameters:
 * igrid_params.c).
 *
 * Build, step by step:
 *   0. coincident copies of a primitive are grouped; steps 1-3 run on one
 *      representative per group, and a leaf holds every copy of its
 *      representatives (igrid_top.c);
 *   1. the top grid: the resolution rule at top_lambda (no cell longer
 *      than twice its middle side: igrid_top.c), a count pass, and
 *      per top cell an octree depth: log2 of the largest axis the rule gives
 *      for sub_lambda on the cell's own count (the paper's second-level
 *      density), capped by max_depth. The deepest cell sets the virtual
 *      lattice: top_res << shift voxels per axis, with its boundary planes
 *      stored once (grid_frame_init), so that every cell box, at any level,
 *      and every crossing distance of the walk come from the same floats;
 *   2. the top cells' lists (count / prefix-sum / fill passes of the grid
 *      API, exact overlap, padded by 1/1024 voxel);
 *   3. subdivision: every non-empty top cell is split into octants down to
 *      its depth, each split a 2x2x2 grid over the node's box built by the
 *      same passes on the node's list (a child's padded box lies inside its
 *      parent's, so the parent's list is complete for it). The leaves are
 *      the cells; the octree is the voxel map;
 *   4. merge and expansion (igrid_opt.c), then the flat arrays the walk
 *      reads: 32-byte cells, one reference array, the map.
 *
 * Threads: step 2 on all threads; step 3 over chunks of top cells, each
 * chunk's output gathered in chunk order, so any thread count gives the
 * same arrays; merge and expansion are sequential.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/isa.h"
#include "igrid_impl.h"

/* split=adaptive, above the paper's depth too, for nodes of at least this
 * many primitives: its depth assumes primitives small against the cell, and
 * 1,000 near-coincident triangles (vertices moved by up to 1e-6) counted
 * whole in every top cell built in 158 s and 898 MB (now 41 ms, 155 KB).
 * The report's scenes get the same cells and bytes with it and without. */
#ifndef IGRID_MUST_GUARD_MIN
#define IGRID_MUST_GUARD_MIN 64
#endif
/* Top cells per work item of the subdivision. */
#define IGRID_CHUNK 64

/* ---- frames on the virtual lattice ------------------------------------------------ */

/* The frame of n[a] cells of `step` voxels each from voxel v0 on: its planes
 * are the lattice's own (copied into `planes`), its padding the lattice's. */
static void sub_frame(const grid_frame *v, const int v0[3], int step, const int n[3],
                      grid_frame *out, float *planes)
{
    float *p = planes;
    for (int a = 0; a < 3; a++) {
        for (int k = 0; k <= n[a]; k++) p[k] = v->planes[a][v0[a] + k * step];
        out->planes[a] = p;
        out->lo[a] = p[0];
        out->hi[a] = p[n[a]];
        out->res[a] = n[a];
        double ext = (double)p[n[a]] - p[0];
        out->inv_cell[a] = ext > 0.0 ? (float)(n[a] / ext) : 0.0f;
        out->pad[a] = v->pad[a];
        p += n[a] + 1;
    }
    out->stride[0] = 1;
    out->stride[1] = (uint32_t)n[0];
    out->stride[2] = (uint32_t)n[0] * (uint32_t)n[1];
}

static int ceil_log2(int x)
{
    int k = 0;
    while ((1 << k) < x) k++;
    return k;
}

/* ---- subdivision --------------------------------------------------------------------- */

typedef struct {
    uint32_t *nodes;         /* octree entries, groups of 8 (local numbering) */
    size_t node_len, node_cap;
    uint32_t *roots;         /* entry per top cell of the chunk */
    int32_t (*box)[6];       /* leaf boxes */
    uint32_t *leaf_off;      /* leaf lists' starts in refs (leaf_len + 1) */
    size_t leaf_len, box_cap, off_cap;
    uint32_t *refs;
    size_t ref_len, ref_cap;
    int failed;              /* ACCEL_ERR_NOMEM or ACCEL_ERR_RANGE */
} chunk_out;

typedef struct {
    const grid_frame *v;     /* virtual lattice */
    const accel_scene *s;
    const grid_cells *top;
    const int *top_res;
    const uint8_t *depth;    /* per top cell */
    int shift;               /* lattice depth the job builds on */
    int adaptive;            /* split=adaptive: the per-node rule below the paper's depth */
    double split_min;        /* split=adaptive: smallest count worth a split below that depth */
    double split_ratio;      /* split=adaptive: most references per primitive after a split */
    const uint32_t *copy_off; /* coincident copies (group_copies), or NULL: */
    const uint32_t *copies;   /* representative r stands for copies[copy_off[r]..copy_off[r+1]) */
    chunk_out *out;          /* per chunk */
    double max_bytes;
    uint64_t used;           /* bytes of lists and entries so far (atomic) */
} split_job;

static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return 1;
    size_t c = *cap ? *cap : 64;
    while (c < need) c *= 2;
    void *q = realloc(*p, c * elem);
    if (!q) return 0;
    *p = q;
    *cap = c;
    return 1;
}

/* Counts bytes against the limit; 0 when it is passed. */
static int charge(split_job *j, size_t bytes)
{
    uint64_t used = __atomic_add_fetch(&j->used, (uint64_t)bytes, __ATOMIC_RELAXED);
    return (double)used <= j->max_bytes;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static uint32_t emit_leaf(split_job *j, chunk_out *o, const int v0[3], int size,
                          const uint32_t *ids, uint32_t n)
{
    if (o->failed) return 0;
    uint32_t reps = n;
    if (j->copies) {
        uint64_t total = 0;
        for (uint32_t k = 0; k < reps; k++) total += j->copy_off[ids[k] + 1] - j->copy_off[ids[k]];
        if (total >= 0xFFFFFFFFu) {
            o->failed = ACCEL_ERR_RANGE;
            return 0;
        }
        n = (uint32_t)total;
    }
    if (!grow((void **)&o->box, &o->box_cap, o->leaf_len + 1, sizeof *o->box) ||
        !grow((void **)&o->leaf_off, &o->off_cap, o->leaf_len + 2, sizeof *o->leaf_off) ||
        !grow((void **)&o->refs, &o->ref_cap, o->ref_len + n, sizeof *o->refs)) {
        o->failed = ACCEL_ERR_NOMEM;
        return 0;
    }
    if (!charge(j, (size_t)n * 4 + sizeof(igrid_cell) + 4)) o->failed = ACCEL_ERR_RANGE;
    for (int a = 0; a < 3; a++) {
        o->box[o->leaf_len][a] = v0[a];
        o->box[o->leaf_len][3 + a] = v0[a] + size;
    }
    o->leaf_off[o->leaf_len] = (uint32_t)o->ref_len;
    if (!j->copies) {
        if (n) memcpy(o->refs + o->ref_len, ids, (size_t)n * sizeof *ids);
    } else if (n) {
        uint32_t *at = o->refs + o->ref_len;
        for (uint32_t k = 0; k < reps; k++)
            for (uint32_t c = j->copy_off[ids[k]]; c < j->copy_off[ids[k] + 1]; c++) *at++ = j->copies[c];
        qsort(o->refs + o->ref_len, n, sizeof *o->refs, cmp_u32); /* lists stay sorted */
    }
    o->ref_len += n;
    o->leaf_off[o->leaf_len + 1] = (uint32_t)o->ref_len;
    return (uint32_t)(o->leaf_len++) << 1;
}

/* The entry of the node of `size` voxels per axis at v0 holding ids[0..n):
 * a leaf, or an inner node whose octants are split in turn. `must` levels
 * remain down to the paper's depth, `depth_left` down to the lattice. */
static uint32_t split_node(split_job *j, chunk_out *o, const int v0[3], int size,
                           const uint32_t *ids, uint32_t n, int must, int depth_left)
{
    const int optional = must <= 0;
    if (depth_left == 0 || n == 0 || o->failed ||
        (optional && (!j->adaptive || n < j->split_min)))
        return emit_leaf(j, o, v0, size, ids, n);
    grid_frame f;
    float planes[9];
    const int two[3] = {2, 2, 2};
    const int half = size / 2;
    sub_frame(j->v, v0, half, two, &f, planes);
    grid_cells kids;
    accel_error err;
    int rc = grid_cells_build(&f, j->s, ids, n, GRID_OVERLAP_EXACT, 1, j->max_bytes, &kids, &err);
    if (rc) {
        o->failed = rc == ACCEL_ERR_NOMEM ? ACCEL_ERR_NOMEM : ACCEL_ERR_RANGE;
        return 0;
    }
    if ((optional || (j->adaptive && n >= IGRID_MUST_GUARD_MIN)) &&
        (double)kids.ref_count > j->split_ratio * n) {
        /* The octants share most primitives: splitting separates nothing. */
        grid_cells_free(&kids);
        return emit_leaf(j, o, v0, size, ids, n);
    }
    size_t group = o->node_len;
    if (!grow((void **)&o->nodes, &o->node_cap, group + 8, sizeof *o->nodes)) {
        grid_cells_free(&kids);
        o->failed = ACCEL_ERR_NOMEM;
        return 0;
    }
    o->node_len += 8;
    if (!charge(j, 8 * sizeof(uint32_t))) o->failed = ACCEL_ERR_RANGE;
    for (int k = 0; k < 8; k++) {
        int c0[3] = {v0[0] + (k & 1) * half, v0[1] + ((k >> 1) & 1) * half,
                     v0[2] + ((k >> 2) & 1) * half};
        uint32_t begin = kids.offsets[k], end = kids.offsets[k + 1];
        uint32_t e =
            split_node(j, o, c0, half, kids.refs + begin, end - begin, must - 1, depth_left - 1);
        o->nodes[group + (size_t)k] = e; /* o->nodes may have moved: index, no pointer */
    }
    grid_cells_free(&kids);
    return (uint32_t)(group << 1) | 1u;
}

static void split_chunk(void *ctx, size_t begin, size_t end, int thread)
{
    (void)thread;
    split_job *j = ctx;
    chunk_out *o = &j->out[begin / IGRID_CHUNK];
    o->roots = malloc((end - begin) * sizeof *o->roots);
    if (!o->roots) {
        o->failed = ACCEL_ERR_NOMEM;
        return;
    }
    const int tx = j->top_res[0], ty = j->top_res[1];
    for (size_t c = begin; c < end && !o->failed; c++) {
        int v0[3] = {(int)(c % (size_t)tx) << j->shift, (int)(c / (size_t)tx % (size_t)ty) << j->shift,
                     (int)(c / ((size_t)tx * ty)) << j->shift};
        uint32_t b = j->top->offsets[c], e = j->top->offsets[c + 1];
        o->roots[c - begin] = split_node(j, o, v0, 1 << j->shift, j->top->refs + b, e - b,
                                         j->depth[c], j->shift);
    }
}

static void chunk_free(chunk_out *o)
{
    free(o->nodes);
    free(o->roots);
    free(o->box);
    free(o->leaf_off);
    free(o->refs);
}

/* Gathers the chunks into b: map = top entries then every chunk's nodes,
 * cells = every chunk's leaves, in chunk order. */
static int gather(chunk_out *out, size_t chunks, uint64_t top_cells, igrid_bcells *b,
                  accel_error *err)
{
    uint64_t nodes = 0, leaves = 0, refs = 0;
    for (size_t k = 0; k < chunks; k++) {
        nodes += out[k].node_len;
        leaves += out[k].leaf_len;
        refs += out[k].ref_len;
    }
    if (top_cells + nodes >= 0x7FFFFFFFu || leaves >= 0x7FFFFFFFu || refs >= 0xFFFFFFFFu)
        return accel_fail(err, ACCEL_ERR_RANGE,
                          "irregular_grid: %llu cells, %llu map entries or %llu references exceed "
                          "the 32-bit index limit (lower sub_lambda or max_depth)",
                          (unsigned long long)leaves, (unsigned long long)(top_cells + nodes),
                          (unsigned long long)refs);
    b->map_len = top_cells + nodes;
    b->count = (uint32_t)leaves;
    b->map = malloc(b->map_len * sizeof *b->map);
    b->box = malloc((leaves ? leaves : 1) * sizeof *b->box);
    b->exit = malloc((leaves ? leaves : 1) * sizeof *b->exit);
    b->list = malloc((leaves ? leaves : 1) * sizeof *b->list);
    b->len = malloc((leaves ? leaves : 1) * sizeof *b->len);
    b->owned = calloc(leaves ? leaves : 1, 1);
    b->pool = accel_alloc_large(refs ? refs : 1, sizeof *b->pool, sizeof(void *));
    if (!b->map || !b->box || !b->exit || !b->list || !b->len || !b->owned || !b->pool)
        return accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory for the cells");
    uint64_t node_base = top_cells, leaf_base = 0, ref_base = 0, top = 0;
    for (size_t k = 0; k < chunks; k++) {
        chunk_out *o = &out[k];
        /* Local entries to global: nodes after the top entries, leaves after
         * the previous chunks' leaves. */
#define RELOC(e) (((e) & 1u) ? (uint32_t)((node_base + ((e) >> 1)) << 1) | 1u \
                             : (uint32_t)((leaf_base + ((e) >> 1)) << 1))
        size_t roots = top + IGRID_CHUNK <= top_cells ? IGRID_CHUNK : (size_t)(top_cells - top);
        for (size_t r = 0; r < roots; r++) b->map[top + r] = RELOC(o->roots[r]);
        for (size_t i = 0; i < o->node_len; i++) b->map[node_base + i] = RELOC(o->nodes[i]);
#undef RELOC
        for (size_t l = 0; l < o->leaf_len; l++) {
            memcpy(b->box[leaf_base + l], o->box[l], sizeof b->box[0]);
            b->list[leaf_base + l] = b->pool + ref_base + o->leaf_off[l];
            b->len[leaf_base + l] = o->leaf_off[l + 1] - o->leaf_off[l];
        }
        if (o->ref_len) memcpy(b->pool + ref_base, o->refs, o->ref_len * sizeof *o->refs);
        top += roots;
        node_base += o->node_len;
        leaf_base += o->leaf_len;
        ref_base += o->ref_len;
    }
    return ACCEL_OK;
}

/* split=cell, the paper's rule: the octree depth of top cell c (index in
 * frame f) holding n primitives is log2 of the largest axis of the grid the
 * resolution rule gives for sub_lambda on the cell's box and count. */
static int cell_depth(const grid_frame *f, uint32_t n, uint64_t c, double sub_lambda)
{
    if (n == 0) return 0;
    const uint64_t tx = (uint64_t)f->res[0], ty = (uint64_t)f->res[1];
    const int idx[3] = {(int)(c % tx), (int)(c / tx % ty), (int)(c / (tx * ty))};
    box3 cell = {{f->planes[0][idx[0]], f->planes[1][idx[1]], f->planes[2][idx[2]]},
                 {f->planes[0][idx[0] + 1], f->planes[1][idx[1] + 1], f->planes[2][idx[2] + 1]}};
    int r[3];
    grid_resolution(cell, n, sub_lambda, r);
    int m = r[0] > r[1] ? r[0] : r[1];
    return ceil_log2(m > r[2] ? m : r[2]);
}

/* Depth actually reached: the lattice shrinks to it (every box coordinate
 * is then a multiple of 2^(shift - used)), with the same planes. */
static void shrink_lattice(igrid_accel *g, igrid_bcells *b, int shift)
{
    int smallest = 1 << shift;
    for (uint32_t c = 0; c < b->count; c++) {
        int size = b->box[c][3] - b->box[c][0];
        smallest = size < smallest ? size : smallest;
    }
    int drop = 0;
    while ((1 << (drop + 1)) <= smallest) drop++;
    if (drop == 0) return;
    for (uint32_t c = 0; c < b->count; c++)
        for (int k = 0; k < 6; k++) b->box[c][k] >>= drop;
    /* The octree keeps its shape: only shift changes. */
    float pad[3] = {g->frame.pad[0], g->frame.pad[1], g->frame.pad[2]};
    box3 box = {{g->frame.lo[0], g->frame.lo[1], g->frame.lo[2]},
                {g->frame.hi[0], g->frame.hi[1], g->frame.hi[2]}};
    int v[3];
    for (int a = 0; a < 3; a++) v[a] = g->top_res[a] << (shift - drop);
    grid_frame_init(&g->frame, box, v, g->planes);
    for (int a = 0; a < 3; a++) g->frame.pad[a] = pad[a]; /* the padding the lists were built with */
    b->shift = g->shift = shift - drop;
}

/* Steps 1-3: top grid, depths, lattice, top lists, octrees. Fills g's frame
 * and b. */
static int subdivide(igrid_accel *g, const accel_params *params, int threads, double max_bytes,
                     igrid_bcells *b, accel_error *err)
{
    const igrid_spec *spec = ACCEL_SPEC(params, igrid_spec);
    const accel_scene *s = &g->store.prims;
    box3 box = grid_frame_box(s->bounds);
    uint32_t *reps, rep_count, *copy_off, *copies;
    if (igrid_group_copies(s, &reps, &rep_count, &copy_off, &copies))
        return accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory for the copies");
    int t[3];
    igrid_top_resolution(s->bounds, box, rep_count, spec->top_lambda, t);
    uint64_t top_cells;
    int rc = grid_cell_count("irregular_grid: top grid", t, max_bytes, &top_cells, err);
    if (rc) {
        free(reps), free(copy_off), free(copies);
        return rc;
    }
    int max_depth = spec->subdivide != 0 ? spec->max_depth : 0;
    for (int a = 0; a < 3; a++)
        while (max_depth > 0 && ((int64_t)t[a] << max_depth) > GRID_MAX_AXIS_RES) max_depth--;
    uint8_t *depth = calloc(top_cells, 1);
    float *top_planes = malloc(grid_plane_count(t) * sizeof *top_planes);
    if (!depth || !top_planes) {
        free(depth), free(top_planes), free(reps), free(copy_off), free(copies);
        return accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory for the top grid");
    }
    /* The top grid's lists, padded by 1/1024 of a top cell: a superset of
     * what the lattice's finer padding would give (membership only has to
     * be conservative), on planes that are the lattice's own: ext*k/n in
     * double does not change when k and n are scaled by 2^shift. */
    grid_frame f;
    grid_frame_init(&f, box, t, top_planes);
    grid_cells top;
    rc = grid_cells_build(&f, s, reps, rep_count, GRID_OVERLAP_EXACT, threads, max_bytes, &top, err);
    free(reps);
    if (rc) {
        free(depth), free(top_planes), free(copy_off), free(copies);
        return rc;
    }
    /* The paper's depth of every top cell; the lattice is as deep as the
     * deepest (split=cell) or as max_depth allows (split=adaptive). */
    int shift = 0, any = 0;
    const int adaptive = spec->split == 0;
    const double sub_lambda = spec->sub_lambda;
    for (uint64_t c = 0; c < top_cells && max_depth > 0; c++) {
        uint32_t n = top.offsets[c + 1] - top.offsets[c];
        int d = cell_depth(&f, n, c, sub_lambda);
        depth[c] = (uint8_t)(d < max_depth ? d : max_depth);
        shift = depth[c] > shift ? depth[c] : shift;
        any |= n > 0;
    }
    if (adaptive && any) shift = max_depth;
    int v[3] = {t[0] << shift, t[1] << shift, t[2] << shift};
    g->planes = malloc(grid_plane_count(v) * sizeof *g->planes);
    if (!g->planes) {
        grid_cells_free(&top), free(depth), free(top_planes), free(copy_off), free(copies);
        return accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory for the lattice");
    }
    grid_frame_init(&g->frame, box, v, g->planes);
    size_t chunks = (size_t)((top_cells + IGRID_CHUNK - 1) / IGRID_CHUNK);
    chunk_out *out = calloc(chunks ? chunks : 1, sizeof *out);
    if (!out) {
        grid_cells_free(&top), free(depth), free(top_planes), free(copy_off), free(copies);
        return accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory");
    }
    split_job j = {&g->frame, s, &top, t, depth, shift, adaptive, spec->split_min, spec->split_ratio,
                   copy_off, copies, out, max_bytes,
                   (uint64_t)(top.cell_count + 1) * 4};
    accel_parallel_for(top_cells, IGRID_CHUNK, threads, split_chunk, &j);
    int failed = 0;
    for (size_t k = 0; k < chunks; k++) failed = failed ? failed : out[k].failed;
    if (failed == ACCEL_ERR_RANGE)
        rc = accel_fail(err, ACCEL_ERR_RANGE,
                        "irregular_grid: the octrees need more than max_mb = %.1f MiB (lower "
                        "sub_lambda or max_depth, or raise max_mb)",
                        max_bytes / 1048576.0);
    else if (failed)
        rc = accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory for the octrees");
    else {
        for (int a = 0; a < 3; a++) b->top_res[a] = g->top_res[a] = t[a];
        b->shift = g->shift = shift;
        b->frame = &g->frame;
        rc = gather(out, chunks, top_cells, b, err);
        if (!rc) shrink_lattice(g, b, shift);
    }
    for (size_t k = 0; k < chunks; k++) chunk_free(&out[k]);
    free(out);
    grid_cells_free(&top);
    free(depth);
    free(top_planes);
    free(copy_off);
    free(copies);
    return rc;
}

/* ---- the flat structure ------------------------------------------------------------- */

void igrid_bcells_free(igrid_bcells *b)
{
    if (b->list && b->owned)
        for (uint32_t c = 0; c < b->count; c++)
            if (b->owned[c]) free(b->list[c]);
    free(b->map);
    free(b->box);
    free(b->exit);
    free(b->list);
    free(b->len);
    free(b->owned);
    free(b->pool);
    memset(b, 0, sizeof *b);
}

/* Cells (exit boxes) and one reference array from b; the map moves to g. */
static int flatten(igrid_accel *g, igrid_bcells *b, accel_error *err)
{
    uint64_t refs = 0;
    for (uint32_t c = 0; c < b->count; c++) refs += b->len[c];
    g->cells = accel_alloc_large(b->count ? b->count : 1, sizeof *g->cells, sizeof(void *));
    g->refs = accel_alloc_large(refs ? refs : 1, sizeof *g->refs, sizeof(void *));
    if (!g->cells || !g->refs)
        return accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory for the cells");
    uint64_t at = 0;
    for (uint32_t c = 0; c < b->count; c++) {
        igrid_cell *cell = &g->cells[c];
        for (int a = 0; a < 3; a++) {
            cell->lo[a] = b->exit[c][a];
            cell->hi[a] = b->exit[c][3 + a];
        }
        cell->begin = (uint32_t)at;
        if (b->len[c]) memcpy(g->refs + at, b->list[c], (size_t)b->len[c] * sizeof *g->refs);
        at += b->len[c];
        cell->end = (uint32_t)at;
    }
    g->cell_count = b->count;
    g->ref_count = refs;
    g->map = b->map;
    g->map_len = b->map_len;
    b->map = NULL;
    return ACCEL_OK;
}

static void igrid_destroy(void *a)
{
    igrid_accel *g = a;
    if (!g) return;
    free(g->map);
    free(g->cells);
    free(g->refs);
    free(g->planes);
    grid_cell_blocks_free(&g->blocks);
    accel_prim_store_free(&g->store);
    free(g);
}

static size_t igrid_memory(const void *a)
{
    const igrid_accel *g = a;
    return sizeof *g + (size_t)g->map_len * sizeof *g->map +
           (size_t)g->cell_count * sizeof *g->cells + (size_t)g->ref_count * sizeof *g->refs +
           grid_plane_count(g->frame.res) * sizeof(float) + accel_prim_store_bytes(&g->store) +
           grid_cell_blocks_bytes(&g->blocks);
}

/* cells=blocks: the cells' reference lists (contiguous, in cell order:
 * flatten) as blocks of 8 triangles, through the regular grid's builder. */
static int build_blocks(igrid_accel *g, double max_bytes, accel_error *err)
{
    grid_cells view = {0};
    view.offsets = malloc(((size_t)g->cell_count + 1) * sizeof *view.offsets);
    if (!view.offsets)
        return accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory for the blocks");
    for (uint32_t c = 0; c < g->cell_count; c++) view.offsets[c] = g->cells[c].begin;
    view.offsets[g->cell_count] = (uint32_t)g->ref_count;
    view.refs = g->refs;
    view.cell_count = g->cell_count;
    view.ref_count = g->ref_count;
    int rc = grid_cell_blocks_build(&view, &g->store.prims, max_bytes, &g->blocks, err);
    free(view.offsets);
    if (rc && err && !strncmp(err->msg, "grid: ", 6)) {
        char inner[sizeof err->msg];
        snprintf(inner, sizeof inner, "%s", err->msg + 6);
        accel_fail(err, rc, "irregular_grid: %s", inner);
    }
    return rc;
}

static int igrid_build(const accel_scene *scene, const accel_params *params, int threads,
                       void **out, accel_build_stats *stats, accel_error *err)
{
    *out = NULL;
    const igrid_spec *spec = ACCEL_SPEC(params, igrid_spec);
    double max_bytes = spec->max_mb * 1048576.0;
    int isa;
    if (accel_isa_resolve(spec->isa, &isa, err)) return ACCEL_ERR_SPEC;
    igrid_accel *g = calloc(1, sizeof *g);
    if (!g) return accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory");
    g->naive = params->naive;
    g->isa = isa;
    g->has_spheres = scene->sphere_count > 0;
    /* Blocks where the block test applies (triangles, the watertight
     * test); a block is tested whole, so they have no mailbox and are
     * traced by the mailbox=0 kernel copies only (igrid_trace.c). */
    const int use_blocks = spec->cells == 1 && !g->naive && !g->has_spheres;
    g->mailbox = spec->mailbox != 0 && !use_blocks;
    igrid_bcells b;
    memset(&b, 0, sizeof b);
    int rc = accel_prim_store_build(scene, params->reorder, &g->store, err);
    if (!rc) rc = subdivide(g, params, threads, max_bytes, &b, err);
    if (!rc && spec->merge != 0) rc = igrid_merge(&b, spec->alpha, spec->ct, err);
    if (!rc) {
        memcpy(b.exit, b.box, (size_t)b.count * sizeof *b.box);
        rc = igrid_expand(&b, spec->expand, err);
        if (!rc) rc = flatten(g, &b, err);
    }
    igrid_bcells_free(&b);
    if (!rc && use_blocks) rc = build_blocks(g, max_bytes, err);
    if (!rc && (double)igrid_memory(g) - accel_prim_store_bytes(&g->store) > max_bytes)
        rc = accel_fail(err, ACCEL_ERR_RANGE,
                        "irregular_grid: %.1f MiB of cells, references%s and map, above the "
                        "limit of %.1f MiB (lower sub_lambda or max_depth, or raise max_mb%s)",
                        ((double)igrid_memory(g) - accel_prim_store_bytes(&g->store)) / 1048576.0,
                        use_blocks ? ", blocks" : "", max_bytes / 1048576.0,
                        use_blocks ? ", or cells=ids" : "");
    if (rc) {
        igrid_destroy(g);
        return rc;
    }
    g->step_bound = (uint64_t)g->frame.res[0] + g->frame.res[1] + g->frame.res[2] + 3;
    memset(stats, 0, sizeof *stats);
    stats->bytes = igrid_memory(g);
    stats->nodes = g->cell_count;
    for (uint32_t c = 0; c < g->cell_count; c++) stats->leaves += g->cells[c].end > g->cells[c].begin;
    stats->refs = g->ref_count;
    stats->sah_cost = NAN;
    stats->depth = g->shift + 1;
    stats->test_lanes = g->blocks.blocks ? 8 : 0;
    stats->isa = g->blocks.blocks ? accel_isa_label(g->isa) : NULL; /* the per-id walk has one */
    for (int a = 0; a < 3; a++) stats->res[a] = g->top_res[a];
    *out = g;
    return ACCEL_OK;
}

void igrid_get_view(const void *accel, igrid_view *v)
{
    const igrid_accel *g = accel;
    v->frame = &g->frame;
    for (int a = 0; a < 3; a++) v->top_res[a] = g->top_res[a];
    v->shift = g->shift;
    v->map = g->map;
    v->map_len = g->map_len;
    v->cells = g->cells;
    v->cell_count = g->cell_count;
    v->refs = g->refs;
    v->ref_count = g->ref_count;
    v->prim_id = g->store.scene_id;
    v->prim_count = g->store.prims.prim_count;
}

/* The suites run each: defaults, each step alone and each left out, a
 * single top cell, a fine top grid, deep octrees, no mailbox; and the
 * cells as blocks on the default, the octree's own cells (unmerged,
 * unexpanded) and a fine top grid. */
static const char *const igrid_variants[] = {
    "",
    "subdivide=0,merge=0,expand=0",
    "merge=0,expand=0",
    "subdivide=0,expand=0",
    "subdivide=0,merge=0",
    "merge=0",
    "expand=0",
    "top_lambda=0.0001",
    "top_lambda=2,max_depth=2",
    "sub_lambda=20,max_depth=8,expand=1",
    "mailbox=0",
    "cells=blocks",
    "cells=blocks,merge=0,expand=0",
    "cells=blocks,top_lambda=2,max_depth=2",
    "cells=blocks,isa=avx2", /* the baseline unit where auto picks AVX-512 (test_isa.c) */
    NULL,
};

const accel_kind accel_kind_irregular_grid = {
    .name = "irregular_grid",
    .summary = "irregular grid (Perard-Gayot et al. 2017): top grid + octrees, merged cells, "
               "expanded exits",
    .step_name = "cells",
    .params = igrid_params,
    .param_count = IGRID_PARAM_COUNT,
    .spec_size = sizeof(igrid_spec),
    .variants = igrid_variants,
    .build = igrid_build,
    .intersect = igrid_intersect,
    .occluded = igrid_occluded,
    .memory = igrid_memory,
    .destroy = igrid_destroy,
    .walk = igrid_walk,
};
