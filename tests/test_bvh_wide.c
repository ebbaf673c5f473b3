/*
 * test_bvh_wide.c - the wide BVHs (bvh:width=4|8): the SSE ray preparation
 * against accel_prep_ray, the SIMD leaf test lane by lane against the
 * scalar watertight test (bit-identical t, same decisions on rays aimed at
 * edges and vertices, where the exact fallback decides), the collapsed
 * tree's invariants, memory accounting and spec errors. Traces against the
 * reference are in test_bvh_wide_trace.c.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh/split_common.h"
#include "bvh/bvh.h"
#include "bvh/wide/node.h"
#include "core/simd.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

#define WIDE_LB 4
#include "core/block_test.h"
#undef WIDE_LB
#define WIDE_LB 8
#include "core/block_test.h"
#undef WIDE_LB

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static float frand(void) { return test_rand_of(&rng); }
static float frange(float lo, float hi) { return lo + (hi - lo) * frand(); }

/* ---- ray preparation ------------------------------------------------------------ */

static int prep_equal(const accel_ray_prep *a, const accel_ray_prep *b)
{
    return !memcmp(&a->org, &b->org, sizeof a->org) && !memcmp(&a->dir, &b->dir, sizeof a->dir) &&
           !memcmp(&a->inv_dir, &b->inv_dir, sizeof a->inv_dir) &&
           !memcmp(a->neg, b->neg, sizeof a->neg) && a->kx == b->kx && a->ky == b->ky &&
           a->kz == b->kz && !memcmp(&a->sx, &b->sx, 4) && !memcmp(&a->sy, &b->sy, 4) &&
           !memcmp(&a->sz, &b->sz, 4) && !memcmp(&a->t_near, &b->t_near, 4) &&
           !memcmp(&a->t_far, &b->t_far, 4);
}

TEST(bvh_wide_prep_matches_scalar)
{
    const float special[] = {0.0f, -0.0f, 1.0f, -1.0f, 1e-38f, -3e38f, INFINITY, -INFINITY, NAN, 0.5f};
    size_t bad = 0, valid = 0, n = 0;
    for (int i = 0; i < 20000; i++) {
        accel_ray r;
        float *f = &r.ox;
        for (int k = 0; k < 8; k++)
            f[k] = (i % 3 == 0 && frand() < 0.3f) ? special[(int)(frand() * 10) % 10] : frange(-5, 5);
        if (i % 2) r.t_near = fabsf(r.t_near) * 0.1f, r.t_far = fabsf(r.t_far) + 1.0f;
        accel_ray_prep a, b;
        memset(&a, 0, sizeof a);
        memset(&b, 0, sizeof b);
        int ra = accel_prep_ray(&r, &a), rb = wide_prep_ray(&r, &b);
        n++;
        valid += ra;
        if (ra != rb || (ra && !prep_equal(&a, &b))) {
            if (!bad)
                test_fail(__FILE__, __LINE__, "ray %d (%g %g %g / %g %g %g): scalar %d, wide %d", i,
                          r.ox, r.oy, r.oz, r.dx, r.dy, r.dz, ra, rb);
            bad++;
        }
    }
    CHECKF(bad == 0, "%zu of %zu rays prepared differently", bad, n);
    CHECKF(valid > n / 3 && valid < n, "%zu valid of %zu: the special values did not mix in", valid, n);
}

/* ---- the SIMD leaf test, lane by lane --------------------------------------------- */

/* Block of B lanes (v[vertex][axis][lane]): lane `k` holds tri, every
 * other lane a small triangle far away (a sure miss for these rays). */
static void fill_block(float *v, uint32_t *id, int block, int k, const float *tri)
{
    static const float far_tri[9] = {1e4f, 1e4f, -1e4f, 1e4f + 1, 1e4f, -1e4f, 1e4f, 1e4f + 1, -1e4f};
    for (int lane = 0; lane < block; lane++)
        for (int i = 0; i < 9; i++) v[i * block + lane] = lane == k ? tri[i] : far_tri[i];
    for (int lane = 0; lane < block; lane++) id[lane] = lane == k ? 7u : 100u + (uint32_t)lane;
}

static int leaf_hit(int block, const void *blk, const accel_ray_prep *p, float *t, float *u,
                    float *v, uint32_t *id, int any_hit)
{
    if (block == 8) {
        wide_leaf_ray_8 lr;
        leaf_setup_8(&lr, p);
        return leaf_block_8(blk, &lr, p, t, u, v, id, 1000, 0, 0, any_hit);
    }
    wide_leaf_ray_4 lr;
    leaf_setup_4(&lr, p);
    return leaf_block_4(blk, &lr, p, t, u, v, id, 1000, 0, 0, any_hit);
}

/*
 * How far a float test's t, u and v may lie from the double-precision
 * answer (t, u, v): the float edge functions err by at most the cheap
 * bounds eu, ev, ew of ACCEL_EDGE_FILTER (core/prim.h) and T by
 * et = 16u sum |E| |z| + sum e_E |z|; u = V/det, v = W/det and t = T/det
 * then err by about (e_num + |value| e_det) / |det|, e_det = eu + ev + ew.
 * Computed in double from the exact coordinates, doubled for the
 * bounds' own looseness. Both float tests stay within it; a fused
 * multiply-add (core/block_test.h) lands elsewhere in it than the scalar test.
 */
typedef struct { double t, u, v; } value_bounds;

static value_bounds float_bounds(const accel_ray_prep *p, const float *tri, double t, double u, double v)
{
    double x[3], y[3], z[3], mx[3], my[3], e[3], E[3];
    for (int k = 0; k < 3; k++) {
        double a[3];
        for (int i = 0; i < 3; i++) a[i] = (double)tri[3 * k + i] - (double)v3_idx(p->org, i);
        double ax = a[p->kx], ay = a[p->ky], az = a[p->kz];
        x[k] = ax - p->sx * az, y[k] = ay - p->sy * az, z[k] = p->sz * az;
        mx[k] = fabs(ax) + fabs(p->sx) * fabs(az), my[k] = fabs(ay) + fabs(p->sy) * fabs(az);
    }
    for (int k = 0; k < 3; k++) { /* U from vertices 1, 2; V from 2, 0; W from 0, 1 */
        int i = (k + 1) % 3, j = (k + 2) % 3;
        E[k] = x[j] * y[i] - y[j] * x[i];
        e[k] = ACCEL_EDGE_FILTER * (mx[j] * my[i] + my[j] * mx[i]);
    }
    double det = fabs(E[0] + E[1] + E[2]), ed = e[0] + e[1] + e[2], et = 0;
    for (int k = 0; k < 3; k++) et += ACCEL_EDGE_FILTER * fabs(E[k]) * fabs(z[k]) + e[k] * fabs(z[k]);
    value_bounds b = {2 * (et + fabs(t) * ed) / det, 2 * (e[1] + fabs(u) * ed) / det,
                      2 * (e[2] + fabs(v) * ed) / det};
    return b;
}

/* w within its bound of the double answer r, give or take two ulps. */
static int close_to(float w, double r, double bound)
{
    return fabs(w - r) <= bound + 2.0 * FLT_EPSILON * fabs(r);
}

/* Rays aimed exactly at vertices and at (rounded) points of edges: most
 * of these are decided by the double-precision fallback, so a SIMD lane
 * test without it (or with other arithmetic) disagrees somewhere. */
TEST(bvh_wide_leaf_lanes_match_scalar)
{
    wide_block8 b8 __attribute__((aligned(64)));
    wide_block4 b4 __attribute__((aligned(64)));
    size_t trials = 0, hits = 0, bad = 0, exact = 0, fused = 0, scalar_in = 0;
    double worst_t = 0, worst_uv = 0, worst_st = 0, worst_suv = 0;
    for (int i = 0; i < 30000; i++) {
        float tri[9];
        float scale = (i % 5 == 0) ? 1e-3f : (i % 5 == 1 ? 1e3f : 1.0f);
        for (int k = 0; k < 9; k++) tri[k] = frange(-1, 1) * scale;
        vec3 a = v3_load(tri), b = v3_load(tri + 3), c = v3_load(tri + 6);
        vec3 target;
        float s = frand();
        switch (i % 4) {
        case 0: target = (i & 4) ? a : b; break;                              /* a vertex */
        case 1: target = v3_add(a, v3_scale(v3_sub(b, a), s)); break;       /* an edge */
        case 2: target = v3_add(c, v3_scale(v3_sub(a, c), s)); break;
        default: target = v3_add(v3_scale(v3_add(a, b), 0.5f * s), v3_scale(c, 1 - s)); break;
        }
        vec3 o = v3(frange(-3, 3) * scale, frange(-3, 3) * scale, frange(2, 4) * scale);
        if (i % 7 == 0) o = v3_add(o, v3(1e3f, -2e3f, 5e2f)); /* far from the origin */
        vec3 d = v3_sub(target, o);
        accel_ray r = {o.x, o.y, o.z, 0.0f, d.x, d.y, d.z, (i % 3 == 0) ? 1.0f : INFINITY};
        if (i % 11 == 0) r.t_near = 1.0f, r.t_far = 2.0f; /* hit exactly at t_near */
        accel_ray_prep p;
        if (!accel_prep_ray(&r, &p)) continue;
        float ts = p.t_far, us = 0, vs = 0;
        int hs = accel_tri_watertight(&p, tri, &ts, &us, &vs);
        accel_ray_d rd;
        accel_prep_ray_d(&p, &rd);
        double tr = p.t_far, ur = 0, vr = 0;
        if (hs) accel_tri_watertight_d(&rd, tri, &tr, &ur, &vr);
        value_bounds vb = float_bounds(&p, tri, tr, ur, vr);
        int block = (i & 1) ? 8 : 4, lane = i % block;
        if (block == 8)
            fill_block(b8.v[0][0], b8.id, 8, lane, tri);
        else
            fill_block(b4.v[0][0], b4.id, 4, lane, tri);
        const void *blk = block == 8 ? (const void *)&b8 : (const void *)&b4;
        for (int any = 0; any < 2; any++) {
            float tw = p.t_far, uw = 0, vw = 0;
            uint32_t id = ACCEL_MISS;
            int hw = leaf_hit(block, blk, &p, &tw, &uw, &vw, &id, any);
            trials++;
            /* The same decision always; t, u, v the scalar test's, or as
             * close to the double-precision answer (a fused multiply-add
             * rounds differently: core/block_test.h). */
            int same = hw == hs;
            if (same && hs && !any) {
                same = id == 7u && close_to(tw, tr, vb.t) && close_to(uw, ur, vb.u) && close_to(vw, vr, vb.v);
                scalar_in += close_to(ts, tr, vb.t) && close_to(us, ur, vb.u) && close_to(vs, vr, vb.v);
                worst_t = fmax(worst_t, fabs(tw - tr) / fmax(1.0, fabs(tr)));
                worst_uv = fmax(worst_uv, fmax(fabs(uw - ur), fabs(vw - vr)));
                worst_st = fmax(worst_st, fabs(ts - tr) / fmax(1.0, fabs(tr)));
                worst_suv = fmax(worst_suv, fmax(fabs(us - ur), fabs(vs - vr)));
                exact += !memcmp(&tw, &ts, 4) && !memcmp(&uw, &us, 4) && !memcmp(&vw, &vs, 4);
                fused += 1;
            }
            if (!same) {
                if (!bad)
                    test_fail(__FILE__, __LINE__,
                              "trial %d (block %d lane %d, any %d): scalar %d t %.9g u %.9g v %.9g, "
                              "wide %d t %.9g u %.9g v %.9g id %u; double t %.9g u %.9g v %.9g",
                              i, block, lane, any, hs, ts, us, vs, hw, tw, uw, vw, id, tr, ur, vr);
                bad++;
            }
        }
        hits += hs;
    }
    CHECKF(bad == 0, "%zu of %zu lane tests differ from the scalar test", bad, trials);
    CHECKF(hits > trials / 8, "only %zu hits in %zu trials", hits, trials);
    CHECKF(exact > fused / 2, "only %zu of %zu hits bit-identical to the scalar test", exact, fused);
    CHECKF(scalar_in == fused, "the scalar test's t, u, v outside their bounds on %zu of %zu hits",
           fused - scalar_in, fused);
    fprintf(stderr, "    %zu of %zu hits bit-identical to the scalar test; from the double answer: wide t %.2g, "
                    "u/v %.2g; scalar t %.2g, u/v %.2g\n", exact, fused, worst_t, worst_uv, worst_st, worst_suv);
}

/* ---- the collapsed tree ----------------------------------------------------------- */

static int box_has(const float *rows, int w, int lane, box3 b)
{
    return rows[0 * w + lane] <= b.min.x && rows[1 * w + lane] >= b.max.x &&
           rows[2 * w + lane] <= b.min.y && rows[3 * w + lane] >= b.max.y &&
           rows[4 * w + lane] <= b.min.z && rows[5 * w + lane] >= b.max.z;
}

typedef struct {
    const accel_scene *s;
    const bvh_wide *w;
    const char *spec;
    uint8_t *node_seen, *block_seen, *prim_seen;
    int depth, bad;
} walk_ctx;

/* Checks a leaf: its blocks, padding, and that box (row `lane` of rows)
 * holds every primitive. */
static void walk_leaf(walk_ctx *x, uint32_t ref, const float *rows, int lane)
{
    const bvh_wide *w = x->w;
    uint32_t first = wide_leaf_first(ref), nb = wide_leaf_blocks(ref);
    if ((uint64_t)first + nb > w->block_count) {
        test_fail(__FILE__, __LINE__, "%s: leaf blocks %u+%u beyond %u", x->spec, first, nb, w->block_count);
        x->bad = 1;
        return;
    }
    for (uint32_t k = 0; k < nb; k++) {
        if (x->block_seen[first + k]++) {
            test_fail(__FILE__, __LINE__, "%s: block %u in two leaves", x->spec, first + k);
            x->bad = 1;
        }
        const uint32_t *id = w->block == 8 ? ((const wide_block8 *)w->blocks)[first + k].id
                                           : ((const wide_block4 *)w->blocks)[first + k].id;
        for (int l = 0; l < w->block; l++) {
            /* padding repeats the leaf's last primitive, only in its last block */
            if (l > 0 && id[l] == id[l - 1]) {
                CHECKF(k == nb - 1, "%s: repeated id inside a leaf", x->spec);
                continue;
            }
            if (id[l] >= x->s->prim_count) {
                test_fail(__FILE__, __LINE__, "%s: id %u out of range", x->spec, id[l]);
                x->bad = 1;
                continue;
            }
            x->prim_seen[id[l]]++;
            if (rows) CHECKF(box_has(rows, w->width, lane, accel_prim_bounds(x->s, id[l])),
                             "%s: primitive %u outside its leaf's box", x->spec, id[l]);
        }
    }
}

static void walk(walk_ctx *x, uint32_t ref, int level, const float *parent_rows, int lane)
{
    if (x->bad) return;
    if (level > x->depth) x->depth = level;
    if (ref & WIDE_LEAF) {
        walk_leaf(x, ref, parent_rows, lane);
        return;
    }
    const bvh_wide *w = x->w;
    if (ref >= w->node_count || x->node_seen[ref]++) {
        test_fail(__FILE__, __LINE__, "%s: node %u out of range or reached twice", x->spec, ref);
        x->bad = 1;
        return;
    }
    const float *rows = w->width == 8 ? ((const wide_node8 *)w->nodes)[ref].box[0]
                                      : ((const wide_node4 *)w->nodes)[ref].box[0];
    const uint32_t *child = (const uint32_t *)(rows + 6 * w->width);
    int used = 0;
    for (int i = 0; i < w->width; i++) {
        int empty = rows[0 * w->width + i] == INFINITY && rows[1 * w->width + i] == -INFINITY;
        if (empty) {
            CHECKF(child[i] == WIDE_EMPTY, "%s: empty slot with a child", x->spec);
            continue;
        }
        used++;
        if (parent_rows) {
            box3 b = {{rows[0 * w->width + i], rows[2 * w->width + i], rows[4 * w->width + i]},
                      {rows[1 * w->width + i], rows[3 * w->width + i], rows[5 * w->width + i]}};
            CHECKF(box_has(parent_rows, w->width, lane, b), "%s: child box outside its parent's", x->spec);
        }
        /* depth-first numbering: children after their parent */
        if (!(child[i] & WIDE_LEAF)) CHECKF(child[i] > ref, "%s: child %u before parent %u", x->spec, child[i], ref);
        walk(x, child[i], level + 1, rows, i);
    }
    CHECKF(used >= 2, "%s: node %u has %d children", x->spec, ref, used);
    /* order=octant: per octant, the ranks are a permutation of the slots,
     * used slots first, each octant's nearest-first order along its diagonal */
    const uint32_t *perm = child + w->width;
    for (int o = 0; o < 8; o++) {
        unsigned seen = 0;
        float prev = -INFINITY;
        for (int r = 0; r < w->width; r++) {
            unsigned l = (perm[r] >> (3 * o)) & 7u;
            CHECKF(l < (unsigned)w->width && !(seen >> l & 1u), "%s: octant %d: bad permutation", x->spec, o);
            seen |= 1u << l;
            int is_used = child[l] != WIDE_EMPTY;
            CHECKF(is_used == (r < used), "%s: octant %d: unused slot ranked before a used one", x->spec, o);
            if (!is_used || l >= (unsigned)w->width) continue;
            float c3[3]; /* the builder's float arithmetic, in its order */
            for (int axis = 0; axis < 3; axis++) {
                c3[axis] = 0.5f * rows[(2 * axis) * w->width + l] + 0.5f * rows[(2 * axis + 1) * w->width + l];
                if (o >> axis & 1) c3[axis] = -c3[axis];
            }
            float key = c3[0] + c3[1] + c3[2];
            CHECKF(key >= prev, "%s: octant %d: children not sorted along the diagonal", x->spec, o);
            prev = key;
        }
    }
}

static void check_wide(const accel_scene *s, const char *spec)
{
    const accel_kind *k;
    accel_build_stats st;
    void *a = test_build_kind(spec, s, 1, &k, &st);
    if (!a) return;
    const bvh *b = a;
    const bvh_wide *w = b->wide;
    CHECKF(w != NULL, "%s: no wide tree", spec);
    if (!w) return;
    walk_ctx x = {s, w, spec, calloc(w->node_count + 1, 1), calloc(w->block_count + 1, 1),
                  calloc(s->prim_count + 1, 1), 0, 0};
    CHECKF(((uintptr_t)w->nodes & 63) == 0 && ((uintptr_t)w->blocks & 63) == 0, "%s: alignment", spec);
    if (w->root != WIDE_EMPTY) walk(&x, w->root, 1, NULL, 0);
    if (!x.bad) {
        for (uint32_t i = 0; i < w->node_count; i++) CHECKF(x.node_seen[i] == 1, "%s: node %u unused", spec, i);
        for (uint32_t i = 0; i < w->block_count; i++) CHECKF(x.block_seen[i] == 1, "%s: block %u unused", spec, i);
        for (uint32_t i = 0; i < s->live_count; i++)
            CHECKF(x.prim_seen[s->live[i]] == 1, "%s: live primitive %u stored %d times", spec,
                   s->live[i], x.prim_seen[s->live[i]]);
        CHECKF(x.depth == w->depth && st.depth == w->depth, "%s: depth %d, stats %d, tree %d", spec,
               x.depth, st.depth, w->depth);
    }
    /* Memory: the struct, the nodes and the blocks, nothing else kept. */
    size_t expect = sizeof(bvh) + sizeof(bvh_wide) +
                    (size_t)w->node_count * (w->width == 8 ? sizeof(wide_node8) : sizeof(wide_node4)) +
                    (size_t)w->block_count * (w->block == 8 ? sizeof(wide_block8) : sizeof(wide_block4));
    CHECKF(st.bytes == expect && k->memory(a) == expect, "%s: %zu bytes reported, %zu expected", spec,
           st.bytes, expect);
    CHECK(st.nodes == w->node_count && st.leaves == w->leaf_count);
    CHECK(b->nodes == NULL && b->prim_data == NULL); /* binary pools freed */
    free(x.node_seen);
    free(x.block_seen);
    free(x.prim_seen);
    k->destroy(a);
}

/* quant=1: the same collapse as the float tree (same node numbering), and
 * every decoded child box holds the float one, at most about two steps
 * looser per axis; memory of 128-byte nodes (its refusals: bvh_wide_spec_errors). */
static void check_quant(const accel_scene *s)
{
    accel_error err = {0};
    const accel_kind *k;
    void *fa, *qa;
    accel_build_stats fs, qs;
    if (accel_build_spec("bvh:width=8", s, 1, &k, &fa, &fs, &err)) {
        test_fail(__FILE__, __LINE__, "%s: %s", s->name, err.msg);
        return;
    }
    if (accel_build_spec("bvh:width=8,quant=1", s, 1, &k, &qa, &qs, &err)) {
        test_fail(__FILE__, __LINE__, "%s, quant=1: %s", s->name, err.msg);
        k->destroy(fa);
        return;
    }
    const bvh_wide *fw = ((const bvh *)fa)->wide, *qw = ((const bvh *)qa)->wide;
    CHECK(qw->quant == 1 && fw->node_count == qw->node_count && fw->root == qw->root);
    int bad = 0, loose = 0;
    for (uint32_t n = 0; n < fw->node_count && n < qw->node_count; n++) {
        const wide_node8 *f = (const wide_node8 *)fw->nodes + n;
        const wide_qnode8 *q = (const wide_qnode8 *)qw->nodes + n;
        int used = 0;
        while (used < 8 && f->child[used] != WIDE_EMPTY) used++;
        bad += q->count != used || memcmp(q->child, f->child, sizeof q->child) != 0;
        for (int c = 0; c < used; c++) {
            float lo[3], hi[3];
            bvh_wide_qbox(q, c, lo, hi);
            for (int a = 0; a < 3; a++) {
                float flo = f->box[2 * a][c], fhi = f->box[2 * a + 1][c];
                bad += !(lo[a] <= flo && hi[a] >= fhi);
                double step = ldexp(1.0, q->ex[a]);
                loose += (double)(hi[a] - lo[a]) - (double)(fhi - flo) >
                         2.01 * step + 1e-6 * fabs((double)q->org[a]) + 1e-30;
            }
        }
    }
    CHECKF(bad == 0, "%s: %d decoded boxes or child lists differ from the float tree", s->name, bad);
    CHECKF(loose == 0, "%s: %d decoded planes looser than two steps", s->name, loose);
    size_t expect = sizeof(bvh) + sizeof(bvh_wide) + (size_t)qw->node_count * sizeof(wide_qnode8) +
                    (size_t)qw->block_count * (qw->block == 8 ? sizeof(wide_block8) : sizeof(wide_block4));
    CHECKF(qs.bytes == expect && qs.bytes < fs.bytes, "%s: %zu bytes, %zu expected (float tree %zu)",
           s->name, qs.bytes, expect, fs.bytes);
    k->destroy(fa);
    k->destroy(qa);
}

TEST(bvh_wide_tree_invariants)
{
    static const char *const scenes[] = {"soup:tris=4000", "sphereflake:level=2", "slivers:tris=2000,slivers=100",
                                         "cube:n=4", "teapot_stadium:n=2"};
    static const char *const specs[] = {"bvh:width=4", "bvh:width=8", "bvh:width=4,block=4",
                                        "bvh:width=8,block=4", "bvh:width=8,leaf=1",
                                        "bvh:width=4,ct=0,leaf=256", "bvh:width=8,build=median",
                                        "bvh:width=8,order=dist", "bvh:width=8,collapse=greedy",
                                        "bvh:width=4,collapse=dp,leaf_below=2,leaf_blocks=4",
                                        "bvh:width=8,collapse=dp,leaf_cost=0.05,leaf_blocks=1",
                                        "bvh:width=8,collapse=dp,leaf_cost=50", "bvh:width=8,leaf_below=4"};
    for (size_t i = 0; i < sizeof scenes / sizeof *scenes; i++) {
        accel_scene s;
        accel_error err = {0};
        if (scene_create(scenes[i], &s, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", scenes[i], err.msg);
            continue;
        }
        for (size_t k = 0; k < sizeof specs / sizeof *specs; k++) check_wide(&s, specs[k]);
        check_quant(&s);
        scene_free(&s);
    }
}

/* Fewer levels than the binary tree, and node counts near N / (W - 1) /
 * leaf size: the collapse really merges levels. */
TEST(bvh_wide_collapse_merges_levels)
{
    accel_scene s;
    accel_error err = {0};
    if (scene_create("soup:tris=20000", &s, &err)) {
        test_fail(__FILE__, __LINE__, "%s", err.msg);
        return;
    }
    const char *specs[] = {"bvh", "bvh:width=4", "bvh:width=8"};
    accel_build_stats st[3];
    for (int i = 0; i < 3; i++) {
        const accel_kind *k;
        void *a;
        if (accel_build_spec(specs[i], &s, 1, &k, &a, &st[i], &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", specs[i], err.msg);
            scene_free(&s);
            return;
        }
        k->destroy(a);
    }
    /* binary depth d: a 4-wide tree needs about d/2 levels, an 8-wide d/3 */
    CHECKF(st[1].depth * 10 <= st[0].depth * 7, "width 4 depth %d vs binary %d", st[1].depth, st[0].depth);
    CHECKF(st[2].depth * 10 <= st[0].depth * 5, "width 8 depth %d vs binary %d", st[2].depth, st[0].depth);
    CHECKF(st[2].nodes < st[1].nodes && st[1].nodes * 2 < st[0].nodes, "nodes %llu %llu %llu",
           (unsigned long long)st[0].nodes, (unsigned long long)st[1].nodes, (unsigned long long)st[2].nodes);
    scene_free(&s);
}

TEST(bvh_wide_spec_errors)
{
    static const char *const bad[] = {"bvh:block=8", "bvh:width=4,traverse=packet,frustum=1", "bvh:width=3",
                                      "bvh:width=8,block=2", "bvh:width=4,quant=1",
                                      "bvh:width=8,quant=1,traverse=packet", "bvh:width=8,quant=1,order=dist",
                                      "bvh:quant=1", "bvh:width=8,order=branchy,traverse=packet",
                                      "bvh:width=8,first=left", "bvh:width=4,pairs=split",
                                      "bvh:collapse=dp", "bvh:leaf_below=4",
                                      "bvh:width=8,collapse=greedy,leaf_cost=2",
                                      "bvh:width=4,collapse=greedy,leaf_blocks=1",
                                      /* issue 50: layout and any_order */
                                      "bvh:layout=bfs", "bvh:any_order=area", "bvh:width=4,layout=mixed",
                                      "bvh:width=8,layout=mixed,traverse=packet",
                                      "bvh:width=8,layout=mixed,traverse=stream", "bvh:width=8,layout=mixed,quant=1",
                                      "bvh:width=8,layout=mixed,order=branchy", "bvh:width=4,any_order=area",
                                      "bvh:width=8,any_order=area,order=dist",
                                      "bvh:width=8,any_order=leaf,order=branchy",
                                      "bvh:width=8,any_order=octant,traverse=packet",
                                      "bvh:width=8,any_order=area,quant=1",
                                      "bvh:width=8,any_order=area,layout=mixed", "bvh:width=8,layout=dfz"};
    accel_scene s;
    accel_error err = {0};
    if (scene_create("soup:tris=100", &s, &err)) return;
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        int rc = test_build_rc(bad[i], &s, &err);
        CHECKF(rc == ACCEL_ERR_SPEC && err.msg[0], "%s: rc %d (%s)", bad[i], rc, err.msg);
    }
    /* A wide tree cannot be saved (the file format is the binary pool). */
    const accel_kind *k;
    void *a;
    accel_build_stats st;
    if (accel_build_spec("bvh:width=4", &s, 1, &k, &a, &st, &err) == 0) {
        CHECK(bvh_save(a, "/tmp/gridbvh_wide_test.bvh", &err) == ACCEL_ERR_SPEC);
        k->destroy(a);
    }
    scene_free(&s);
}


