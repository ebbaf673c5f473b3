/*
 * oracle.c - the double-precision reference every test compares against.
 *
 * Its answer is defined by the brute-force loop (accel_reference_trace_brute):
 * every live primitive in live order against every ray, in double precision,
 * with the watertight triangle test (Woop, Benthin, Wald, JCGT 2013) and the
 * cancellation-free sphere test of core/prim.h; a later primitive replaces
 * the current hit when the test accepts it, i.e. when its t is in
 * [t_near, t_current] (so on equal t the LAST in live order wins).
 *
 * accel_oracle_* returns exactly (bitwise t, prim, u, v) that answer, but
 * runs the same tests only on the primitives a culling tree (oracle_build.c)
 * cannot rule out, and replays the tie rule: a hit replaces the current one
 * when its t is smaller, or equal and its live position later.
 *
 * Why the culling never drops a hit the double test would accept. Per ray,
 * let S = max|origin coordinate| + max|coordinate of the tree's root box|,
 * so that every vertex - origin difference is at most S per axis, and let
 * eps = 2^-53. Every box is widened by M = 2^-20 S: about 10^7 times the
 * double rounding errors below (each a few tens of eps S at most), which
 * also makes the slab test's own rounding irrelevant.
 *  1. The line. The triangle test accepts only when its three rounded edge
 *     functions U, V, W share a sign and one of them exceeds 16 eps times
 *     its magnitude bound (the edge-on rule), a bound about 8 times its
 *     rounding error. So the exact edge functions of the rounded, sheared
 *     vertices have that sign up to their rounding error, which puts the
 *     ray within a few eps times the vertices' sheared magnitudes of the
 *     (rounded) triangle; the rounding of vertex - origin and of the shear
 *     moves each vertex by a few eps S more. The ray's line therefore meets
 *     the triangle's box widened by ~30 eps S. The sphere test accepts only
 *     when r^2 >= |l|^2 for the rounded centre-to-line vector l, whose error
 *     is ~20 eps S: the line passes within r + 20 eps S of the centre, i.e.
 *     through the sphere's widened box. A node whose widened box the
 *     infinite line misses holds no acceptable primitive.
 *  2. The distance, triangles only. An accepted t is computed as
 *     (U az + V bz + W cz) sz / det with U, V, W of one sign: a convex
 *     combination of the vertices' offsets along the dominant axis kz,
 *     divided by d[kz], up to ~8 eps S. Where that value's error bound is
 *     not small (huge triangles, whose +-1e30 offsets cancel in the sum),
 *     prim.h takes the plane form n.(v0 - o)/n.d instead, but clamped into
 *     [min, max] of az sz, bz sz, cz sz: the same interval, up to the
 *     rounding of those three products. So t lies in the kz slab interval
 *     of any widened box holding the triangle: a node whose kz interval
 *     starts after the current hit's t (strictly after: an equal t may still
 *     win the tie) or ends before t_near holds no better hit. The usual
 *     slab interval over all three axes would not be safe: for a nearly
 *     edge-on triangle the rounded weights may put t anywhere within the
 *     triangle's depth range, where the ray can be outside the triangle's
 *     box on the other two axes. Spheres get no distance bound (the second
 *     root (|f|^2 - r^2)/q is arbitrary when q is all rounding, as for a
 *     tangent ray from the surface), so a subtree holding a sphere is
 *     culled by the line alone.
 *  3. Primitives with a non-finite coordinate (scene_finish keeps them
 *     live) have no box to test: they are tested against every ray.
 * tests/test_oracle.c checks the result against the brute-force loop,
 * bitwise, on every stiff case, every built-in scene and adversarial rays.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/oracle_bvh.h"
#include "core/prim.h"

/* ---- the definition: brute force in live order ---------------------------- */

typedef struct {
    const accel_scene *scene;
    const accel_ray *rays;
    accel_hit *hits;
} brute_job;

static void brute_chunk(void *p, size_t begin, size_t end, int thread)
{
    (void)thread;
    brute_job *j = p;
    const accel_scene *s = j->scene;
    for (size_t i = begin; i < end; i++) {
        accel_hit h = accel_hit_miss();
        accel_ray_prep fp;
        accel_ray_d r;
        if (accel_prep_ray(&j->rays[i], &fp)) {
            accel_prep_ray_d(&fp, &r);
            double t = fp.t_far, u = 0, v = 0;
            uint32_t best = ACCEL_MISS;
            for (uint32_t k = 0; k < s->live_count; k++) {
                uint32_t prim = s->live[k];
                int hit = prim < s->tri_count
                              ? accel_tri_watertight_d(&r, s->tris + 9 * (size_t)prim, &t, &u, &v)
                              : accel_sphere_hit_d(&r, s->spheres + 4 * (size_t)(prim - s->tri_count), &t);
                if (hit) {
                    best = prim;
                    if (prim >= s->tri_count) u = v = 0;
                }
            }
            if (best != ACCEL_MISS) {
                h.t = (float)t;
                h.prim = best;
                h.u = (float)u;
                h.v = (float)v;
            }
        }
        j->hits[i] = h;
    }
}

void accel_reference_trace_brute(const accel_scene *scene, const accel_ray *rays, accel_hit *hits,
                                 size_t count, int threads)
{
    brute_job j = {scene, rays, hits};
    accel_parallel_for(count, 256, threads, brute_chunk, &j);
}

/* ---- the culled oracle ------------------------------------------------------ */

/* Relative widening of every box (see the argument above). */
#define ORACLE_MARGIN 0x1p-20
/* Below these, building the tree costs more than it saves. */
enum { ORACLE_MIN_RAYS = 32, ORACLE_MIN_PRIMS = 64 };

int accel_oracle_build(const accel_scene *scene, accel_oracle **out, accel_error *err)
{
    *out = NULL;
    accel_oracle *o = calloc(1, sizeof *o);
    if (!o) return accel_fail(err, ACCEL_ERR_NOMEM, "oracle: out of memory");
    o->scene = scene;
    int rc = oracle_bvh_build(o, err);
    if (rc) {
        accel_oracle_free(o);
        return rc;
    }
    *out = o;
    return 0;
}

void accel_oracle_free(accel_oracle *o)
{
    if (!o) return;
    free(o->nodes);
    free(o->items);
    free(o->always);
    free(o);
}

size_t accel_oracle_memory(const accel_oracle *o)
{
    return sizeof *o + (size_t)o->node_count * sizeof *o->nodes +
           ((size_t)o->item_count + o->always_count) * sizeof *o->items;
}

typedef struct {
    double t, u, v;
    uint32_t prim;
    int64_t pos; /* live position of prim; -1 before the first hit */
} oracle_best;

/* The brute-force loop's step for one primitive, with its tie rule made
 * explicit: the test accepts t <= best t only, and an equal t wins only
 * from a later live position. */
static inline void test_item(const accel_scene *s, const accel_ray_d *r, oracle_item it,
                             oracle_best *b)
{
    double t = b->t, u = 0, v = 0;
    int hit = it.prim < s->tri_count
                  ? accel_tri_watertight_d(r, s->tris + 9 * (size_t)it.prim, &t, &u, &v)
                  : accel_sphere_hit_d(r, s->spheres + 4 * (size_t)(it.prim - s->tri_count), &t);
    if (hit && (t < b->t || (int64_t)it.pos > b->pos)) {
        b->t = t;
        b->u = u;
        b->v = v;
        b->prim = it.prim;
        b->pos = it.pos;
    }
}

/* Per-ray constants of the widened slab test, in double. */
typedef struct {
    double inv[3];      /* 1/d (+-inf for a +-0 component) */
    double off_near[3]; /* origin shifted so that near - off_near = widened near plane - origin */
    double off_far[3];
    int neg[3];         /* sign bit of d: the near plane is hi */
    int kz;             /* dominant axis: the one whose interval bounds t (point 2) */
    double t_near;
} slab_ray;

static void slab_setup(const accel_oracle *o, const accel_ray_prep *p, slab_ray *q)
{
    const double org[3] = {p->org.x, p->org.y, p->org.z}, dir[3] = {p->dir.x, p->dir.y, p->dir.z};
    double big = 0.0;
    for (int a = 0; a < 3; a++) big = fmax(big, fabs(org[a]));
    double m = ORACLE_MARGIN * (big + o->scale) + 0x1p-1000;
    for (int a = 0; a < 3; a++) {
        q->inv[a] = 1.0 / dir[a];
        q->neg[a] = signbit(dir[a]) != 0;
        q->off_near[a] = q->neg[a] ? org[a] - m : org[a] + m;
        q->off_far[a] = q->neg[a] ? org[a] + m : org[a] - m;
    }
    q->kz = p->kz;
    q->t_near = p->t_near;
}

/*
 * Whether node n may hold a hit at t <= t_best. *order gets the kz entry
 * distance (for front-to-back order), *cull the distance beyond which the
 * node can be skipped once popped (-inf when it holds a sphere). A 0 * inf
 * (a zero direction component, origin on a widened plane) is a NaN that
 * the compare-and-select below ignores: the slab then counts as crossed.
 */
static inline int node_hit(const oracle_node *n, const slab_ray *q, double t_best, double *order,
                           double *cull)
{
    double t0[3], t1[3];
    for (int a = 0; a < 3; a++) {
        double near = q->neg[a] ? n->hi[a] : n->lo[a];
        double far = q->neg[a] ? n->lo[a] : n->hi[a];
        t0[a] = (near - q->off_near[a]) * q->inv[a];
        t1[a] = (far - q->off_far[a]) * q->inv[a];
    }
    double lo = -INFINITY, hi = INFINITY;
    for (int a = 0; a < 3; a++) {
        lo = t0[a] > lo ? t0[a] : lo;
        hi = t1[a] < hi ? t1[a] : hi;
    }
    if (lo > hi) return 0; /* the line misses the widened box */
    *order = t0[q->kz];
    *cull = -INFINITY;
    if (n->count & ORACLE_SPHERES) return 1;
    if (t0[q->kz] > t_best || t1[q->kz] < q->t_near) return 0;
    *cull = t0[q->kz];
    return 1;
}

typedef struct {
    uint64_t steps, box_tests, prim_tests;
} oracle_tally;

static accel_hit trace_one(const accel_oracle *o, const accel_ray *ray, uint32_t *stack,
                           double *stack_t, oracle_tally *tally)
{
    accel_hit h = accel_hit_miss();
    accel_ray_prep fp;
    accel_ray_d r;
    if (!accel_prep_ray(ray, &fp)) return h;
    accel_prep_ray_d(&fp, &r);
    const accel_scene *s = o->scene;
    oracle_best b = {fp.t_far, 0.0, 0.0, ACCEL_MISS, -1};
    for (uint32_t k = 0; k < o->always_count; k++) test_item(s, &r, o->always[k], &b);
    tally->prim_tests += o->always_count;

    slab_ray q;
    double order, cull;
    if (o->nodes) slab_setup(o, &fp, &q);
    tally->box_tests += o->nodes != NULL;
    if (o->nodes && node_hit(&o->nodes[0], &q, b.t, &order, &cull)) {
        /* Front-to-back descent; the far child waits on the stack with the
         * distance that lets it be skipped once a closer hit is known. */
        size_t sp = 0;
        uint32_t node = 0;
        for (;;) {
            const oracle_node *n = &o->nodes[node];
            uint32_t count = n->count & ~ORACLE_SPHERES;
            tally->steps++;
            if (count) {
                for (uint32_t i = n->index; i < n->index + count; i++)
                    test_item(s, &r, o->items[i], &b);
                tally->prim_tests += count;
            } else {
                double o0, o1, c0, c1;
                int h0 = node_hit(&o->nodes[n->index], &q, b.t, &o0, &c0);
                int h1 = node_hit(&o->nodes[n->index + 1], &q, b.t, &o1, &c1);
                tally->box_tests += 2;
                if (h0 && h1) {
                    int first = o1 < o0;
                    stack[sp] = n->index + !first;
                    stack_t[sp++] = first ? c0 : c1;
                    node = n->index + first;
                    continue;
                }
                if (h0 || h1) {
                    node = n->index + !h0;
                    continue;
                }
            }
            while (sp > 0 && stack_t[sp - 1] > b.t) sp--;
            if (sp == 0) break;
            node = stack[--sp];
        }
    }
    if (b.prim != ACCEL_MISS) {
        h.t = (float)b.t;
        h.prim = b.prim;
        h.u = (float)b.u;
        h.v = (float)b.v;
    }
    return h;
}

typedef struct {
    const accel_oracle *oracle;
    const accel_ray *rays;
    accel_hit *hits;
    oracle_tally *tally; /* one per thread */
} oracle_job;

static void oracle_chunk(void *p, size_t begin, size_t end, int thread)
{
    oracle_job *j = p;
    /* One entry per tree level; binned SAH on badly spread primitives can
     * build deep trees, so the stack is sized from the build, per chunk. */
    size_t need = (size_t)j->oracle->depth + 1;
    uint32_t *stack = malloc(need * sizeof *stack);
    double *stack_t = malloc(need * sizeof *stack_t);
    if (!stack || !stack_t) {
        free(stack);
        free(stack_t);
        accel_reference_trace_brute(j->oracle->scene, j->rays + begin, j->hits + begin,
                                    end - begin, 1);
        return;
    }
    oracle_tally t = {0, 0, 0};
    for (size_t i = begin; i < end; i++)
        j->hits[i] = trace_one(j->oracle, &j->rays[i], stack, stack_t, &t);
    free(stack);
    free(stack_t);
    j->tally[thread].steps += t.steps;
    j->tally[thread].box_tests += t.box_tests;
    j->tally[thread].prim_tests += t.prim_tests;
}

void accel_oracle_trace(const accel_oracle *o, const accel_ray *rays, accel_hit *hits,
                        size_t count, int threads, accel_counters *counters)
{
    if (threads < 1) threads = 1;
    if (threads > 256) threads = 256;
    oracle_tally tally[256];
    memset(tally, 0, (size_t)threads * sizeof *tally);
    oracle_job j = {o, rays, hits, tally};
    accel_parallel_for(count, 256, threads, oracle_chunk, &j);
    if (counters) {
        counters->rays += count;
        for (int i = 0; i < threads; i++) {
            counters->steps += tally[i].steps;
            counters->box_tests += tally[i].box_tests;
            counters->prim_tests += tally[i].prim_tests;
        }
    }
}

void accel_reference_trace(const accel_scene *scene, const accel_ray *rays, accel_hit *hits,
                           size_t count, int threads)
{
    accel_oracle *o = NULL;
    if (count >= ORACLE_MIN_RAYS && scene->live_count >= ORACLE_MIN_PRIMS &&
        accel_oracle_build(scene, &o, NULL) == 0) {
        accel_oracle_trace(o, rays, hits, count, threads, NULL);
        accel_oracle_free(o);
        return;
    }
    /* Few rays or primitives, or no memory for the tree: same answer. */
    accel_reference_trace_brute(scene, rays, hits, count, threads);
}
