/*
 * oracle_build.c - the culling tree of the exact oracle: binned SAH over
 * the live primitives (Wald, "On fast Construction of SAH-based Bounding
 * Volume Hierarchies", IEEE RT 2007), top-down with an explicit task stack.
 *
 * Exactness never depends on the tree's quality, only on its boxes holding
 * their primitives (see oracle.c), so the builder is the simplest fast
 * one: one axis (the largest centroid extent) binned per node, areas in
 * double so that boxes near FLT_MAX cannot overflow the cost.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/geom.h"
#include "core/oracle_bvh.h"

enum {
    ORACLE_BINS = 16,    /* bins on the split axis */
    ORACLE_LEAF_MIN = 4, /* primitives: at or below, always a leaf */
    ORACLE_LEAF_MAX = 8  /* primitives: at or below, a leaf when the SAH prefers it */
};

typedef struct {
    float lo[3], hi[3];
    uint32_t prim, pos;
} oracle_ref;

typedef struct {
    uint32_t node, begin, end;
    int depth;
} build_task;

/* Bounds of a primitive; returns 0 when one of them is not finite. */
static int prim_box(const accel_scene *s, uint32_t prim, oracle_ref *r)
{
    if (prim < s->tri_count) {
        const float *t = s->tris + 9 * (size_t)prim;
        for (int a = 0; a < 3; a++) {
            r->lo[a] = minf(minf(t[a], t[3 + a]), t[6 + a]);
            r->hi[a] = maxf(maxf(t[a], t[3 + a]), t[6 + a]);
        }
        for (int i = 0; i < 9; i++)
            if (!isfinite(t[i])) return 0;
    } else {
        /* The test uses r*r, so a negative radius (possible only in a
         * hand-made scene) is the sphere of radius |r|. */
        const float *sp = s->spheres + 4 * (size_t)(prim - s->tri_count);
        double rad = fabs((double)sp[3]);
        for (int a = 0; a < 3; a++) {
            r->lo[a] = accel_float_down((double)sp[a] - rad);
            r->hi[a] = accel_float_up((double)sp[a] + rad);
        }
        if (!isfinite(sp[3])) return 0;
    }
    for (int a = 0; a < 3; a++)
        if (!isfinite(r->lo[a]) || !isfinite(r->hi[a])) return 0;
    return 1;
}

/* Centroid without overflow near FLT_MAX. */
static float centroid(const oracle_ref *r, int axis)
{
    return 0.5f * r->lo[axis] + 0.5f * r->hi[axis];
}

static double half_area(const float *lo, const float *hi)
{
    double x = (double)hi[0] - lo[0], y = (double)hi[1] - lo[1], z = (double)hi[2] - lo[2];
    return x * y + y * z + z * x;
}

static void grow_box(float *lo, float *hi, const float *lo2, const float *hi2)
{
    for (int a = 0; a < 3; a++) {
        lo[a] = minf(lo[a], lo2[a]);
        hi[a] = maxf(hi[a], hi2[a]);
    }
}

static void empty_box(float *lo, float *hi)
{
    for (int a = 0; a < 3; a++) lo[a] = INFINITY, hi[a] = -INFINITY;
}

static int bin_of(const oracle_ref *r, int axis, double cmin, double scale)
{
    double k = ((double)centroid(r, axis) - cmin) * scale;
    int b = (int)k;
    return b < 0 ? 0 : (b >= ORACLE_BINS ? ORACLE_BINS - 1 : b);
}

/*
 * Chooses where [begin, end) splits: returns the first index of the right
 * child after partitioning the refs, or 0 to make a leaf.
 */
static uint32_t split_refs(oracle_ref *refs, uint32_t begin, uint32_t end, const float *lo,
                           const float *hi)
{
    uint32_t n = end - begin;
    float clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = begin; i < end; i++)
        for (int a = 0; a < 3; a++) {
            float c = centroid(&refs[i], a);
            clo[a] = minf(clo[a], c);
            chi[a] = maxf(chi[a], c);
        }
    int axis = 0;
    double ext = -1.0;
    for (int a = 0; a < 3; a++) {
        double e = (double)chi[a] - clo[a];
        if (e > ext) ext = e, axis = a;
    }
    /* Every centroid equal (coincident or same-centroid primitives): any
     * halving is as good as another; it only keeps the leaves small. */
    if (!(ext > 0.0)) return n > ORACLE_LEAF_MIN ? begin + n / 2 : 0;

    double cmin = clo[axis], scale = ORACLE_BINS * (1.0 - 0x1p-20) / ext;
    uint32_t count[ORACLE_BINS] = {0};
    float blo[ORACLE_BINS][3], bhi[ORACLE_BINS][3];
    for (int b = 0; b < ORACLE_BINS; b++) empty_box(blo[b], bhi[b]);
    for (uint32_t i = begin; i < end; i++) {
        int b = bin_of(&refs[i], axis, cmin, scale);
        count[b]++;
        grow_box(blo[b], bhi[b], refs[i].lo, refs[i].hi);
    }
    /* Sweep: right areas from the right, then the cost of each plane. */
    double right_area[ORACLE_BINS];
    float rlo[3], rhi[3];
    empty_box(rlo, rhi);
    uint32_t right_n = 0;
    for (int b = ORACLE_BINS - 1; b > 0; b--) {
        grow_box(rlo, rhi, blo[b], bhi[b]);
        right_n += count[b];
        right_area[b] = right_n ? half_area(rlo, rhi) : 0.0;
    }
    float llo[3], lhi[3];
    empty_box(llo, lhi);
    uint32_t left_n = 0;
    int best = -1;
    double best_cost = INFINITY;
    for (int b = 1; b < ORACLE_BINS; b++) {
        grow_box(llo, lhi, blo[b - 1], bhi[b - 1]);
        left_n += count[b - 1];
        if (left_n == 0 || left_n == n) continue;
        double cost = half_area(llo, lhi) * left_n + right_area[b] * (n - left_n);
        if (cost < best_cost) best_cost = cost, best = b;
    }
    if (best < 0) return begin + n / 2; /* cannot happen: min and max centroids bin apart */
    /* SAH with a node visit costing one primitive test. */
    double area = half_area(lo, hi);
    if (n <= ORACLE_LEAF_MAX && area * n <= area + best_cost) return 0;
    uint32_t i = begin, j = end;
    while (i < j) {
        if (bin_of(&refs[i], axis, cmin, scale) < best) {
            i++;
        } else {
            oracle_ref t = refs[i];
            refs[i] = refs[--j];
            refs[j] = t;
        }
    }
    return i;
}

int oracle_bvh_build(accel_oracle *o, accel_error *err)
{
    const accel_scene *s = o->scene;
    uint32_t n = s->live_count, finite = 0, odd = 0;
    oracle_ref *refs = malloc((n ? n : 1) * sizeof *refs);
    if (!refs) return accel_fail(err, ACCEL_ERR_NOMEM, "oracle: out of memory for %u refs", n);
    /* Finite primitives go to the tree; the others are tested against every
     * ray (their boxes hold nothing a slab test can use). */
    for (uint32_t k = 0; k < n; k++) {
        oracle_ref r;
        r.prim = s->live[k];
        r.pos = k;
        if (prim_box(s, r.prim, &r)) refs[finite++] = r;
        else refs[n - 1 - odd++] = r;
    }
    if (finite > 0x7FFFFFFFu) {
        free(refs); /* node ids would overflow: the caller falls back to brute force */
        return accel_fail(err, ACCEL_ERR_RANGE, "oracle: %u primitives exceed the tree's limit",
                          finite);
    }
    o->always_count = odd;
    o->always = malloc((odd ? odd : 1) * sizeof *o->always);
    o->items = malloc((finite ? finite : 1) * sizeof *o->items);
    build_task *stack = malloc(((size_t)finite + 1) * sizeof *stack);
    size_t cap = finite ? 2 * (size_t)finite - 1 : 1;
    o->nodes = malloc(cap * sizeof *o->nodes);
    if (!o->always || !o->items || !stack || !o->nodes) {
        free(refs);
        free(stack);
        return accel_fail(err, ACCEL_ERR_NOMEM, "oracle: out of memory for a tree over %u prims",
                          finite);
    }
    for (uint32_t k = 0; k < odd; k++)
        o->always[k] = (oracle_item){refs[n - 1 - k].prim, refs[n - 1 - k].pos};
    o->item_count = finite;
    if (finite == 0) {
        free(refs);
        free(stack);
        free(o->nodes);
        o->nodes = NULL;
        return 0;
    }

    o->node_count = 1;
    o->depth = 0;
    size_t top = 0;
    stack[top++] = (build_task){0, 0, finite, 0};
    while (top) {
        build_task t = stack[--top];
        oracle_node *node = &o->nodes[t.node];
        empty_box(node->lo, node->hi);
        uint32_t spheres = 0;
        for (uint32_t i = t.begin; i < t.end; i++) {
            grow_box(node->lo, node->hi, refs[i].lo, refs[i].hi);
            if (refs[i].prim >= s->tri_count) spheres = ORACLE_SPHERES;
        }
        if (t.depth > o->depth) o->depth = t.depth;
        uint32_t mid = t.end - t.begin > ORACLE_LEAF_MIN
                           ? split_refs(refs, t.begin, t.end, node->lo, node->hi)
                           : 0;
        if (mid == 0) {
            node->index = t.begin;
            node->count = (t.end - t.begin) | spheres;
            continue;
        }
        node->index = o->node_count;
        node->count = spheres;
        o->node_count += 2;
        stack[top++] = (build_task){node->index + 1, mid, t.end, t.depth + 1};
        stack[top++] = (build_task){node->index, t.begin, mid, t.depth + 1};
    }
    o->scale = 0.0;
    for (int a = 0; a < 3; a++) {
        o->scale = fmax(o->scale, fabs((double)o->nodes[0].lo[a]));
        o->scale = fmax(o->scale, fabs((double)o->nodes[0].hi[a]));
    }
    for (uint32_t i = 0; i < finite; i++) o->items[i] = (oracle_item){refs[i].prim, refs[i].pos};
    oracle_node *shrunk = realloc(o->nodes, (size_t)o->node_count * sizeof *o->nodes);
    if (shrunk) o->nodes = shrunk;
    free(refs);
    free(stack);
    return 0;
}
