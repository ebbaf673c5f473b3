/*
 * k8_trace.c - the single-ray traversal of the `instanced` kind (see
 * README.md). A kernel unit (sources.mk's SLOW_SRC): compiled once for
 * AVX2 and, where the build has ARCH512, once more for AVX-512 with
 * WIDE_AVX512_UNIT (its entries then end in _avx512, bvh/wide/node.h's
 * WIDE_UNIT), so that the wide node test and child order it shares with
 * bvh/wide/ run in the ISA the structure was built for (inst_packet.c
 * dispatches on inst_accel.isa).
 *
 * Per ray: the top level (BVH or grid over the instances' world bounds) is
 * walked in world space, nearest first. For each instance it reaches, the
 * ray goes to object space in double (the inverse matrix; t is unchanged,
 * since the map is affine and the direction is not renormalized), then
 * walks the mesh's shared bottom level with every box grown by a pad. The
 * pad covers (a) how far the flattened world triangles, rounded to float,
 * can lie from the exact image of the mesh's triangles, and (b) the
 * rounding of the object-space ray. So the bottom level is conservative:
 * it reaches every triangle whose world copy the ray may hit. Each
 * triangle it reaches is then decided in world space, on the world ray and
 * the flattened triangle's very floats: at an 8-wide leaf, the leaf's
 * world blocks (copies made at build with world=blocks, or the object
 * block taken to world space by the flattener's expression with
 * world=compute) with the shared block test (core/block_test.h, bvh/wide's
 * leaf test); in the walks that meet triangles one by one, the shared
 * scalar test (core/prim.h). The same tests, on the same floats, as any
 * kind on the flattened scene, hence the same answers as the oracle.
 *
 * An identity instance (and a plain scene, one identity instance of
 * itself) needs no pad and no transform: its walk is a plain BVH or grid.
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include "core/prim.h"
#include "core/variant.h"
#include "inst_impl.h"
#include "inst_ray.h"

/* The wide BVH's node test and child order (bvh/wide/kernel.h, 8 wide)
 * and its leaf test (core/block_test.h), run on world blocks. */
#define WIDE_NW 8
#define WIDE_LB 8
#include "core/block_test.h"
#include "bvh/wide/kernel.h"

#define INST_STACK BVH_MAX_DEPTH /* bvh_build_boxes builds no deeper tree (bvh.h) */

typedef struct {
    accel_ray_prep p;   /* world ray for the float kernels */
    wide_leaf_ray_8 lr; /* its constants for the block test (once per ray) */
    double o[3], d[3];  /* world ray in double */
    float t, u, v;      /* closest hit so far (t = t_far before any) */
    uint32_t prim;
    int any, done;      /* occlusion query; a hit ends it */
    /* Counted runs only (core/variant.h: the timed copies count nothing):
     * the hot walks (walk_wide, test_blocks) take it as a literal, so
     * their timed copies hold no counting code; the rest test it. */
    int counted;
    uint32_t top_steps, bottom_steps, boxes, prims, empties, skips;
} ray_state;

#define INLINE static inline __attribute__((always_inline))

/* ---- the world-space decision ------------------------------------------------ */

/* Mesh triangle q of instance it, met alone (width=2, grids, a walked
 * kind): its world triangle (the flattened scene's, or computed by the
 * flattener's expression with world=compute) decided by the shared scalar
 * test (inst_decide). */
INLINE void test_prim(const inst_accel *a, const inst_item *it, const accel_scene *mesh,
                      uint32_t q, ray_state *r, int naive, int spheres)
{
    const accel_scene *s = a->scene;
    uint32_t id = it->base + q;
    float w[9];
    const float *tri = NULL, *sphere = NULL;
    if (r->counted) r->prims++;
    if (spheres && id >= s->tri_count) {
        /* Only plain scenes hold spheres (meshes of instances cannot). */
        sphere = s->spheres + 4 * (size_t)(id - s->tri_count);
    } else if (it->identity || a->world == INST_WORLD_BLOCKS) {
        tri = s->tris + 9 * (size_t)id;
    } else {
        const float *m = mesh->tris + 9 * (size_t)q;
        for (int k = 0; k < 3; k++) accel_xform_vertex(it->xform, m + 3 * k, w + 3 * k);
        tri = w;
    }
    if (inst_decide(&r->p, tri, sphere, id, naive, it->has_dead, &r->t, &r->u, &r->v, &r->prim) &&
        r->any)
        r->done = 1;
}

/* The blocks [first, first + nb) of instance it's bottom level, in world
 * space, against the world ray with the shared block test: a plain
 * scene's own blocks, the instance's copies (world=blocks), or each
 * object block taken to world space here (world=compute). Counts the
 * triangles (lanes) tested, as bvh/wide does. */
INLINE void test_blocks(const inst_accel *a, const inst_item *it, const inst_wide *w,
                        uint32_t first, uint32_t nb, ray_state *r, int naive, int spheres, int cnt)
{
    const accel_block8 *blk = a->plain ? w->blocks + first : it->world ? it->world + first : NULL;
    for (uint32_t k = 0; k < nb; k++) {
        accel_block8 tmp __attribute__((aligned(64)));
        const accel_block8 *b = blk ? blk + k : &tmp;
        if (!blk) inst_world_block(it, w->blocks + first + k, &tmp);
        if (cnt) {
            r->prims++;
            for (int lane = 1; lane < 8; lane++) r->prims += b->id[lane] != b->id[lane - 1];
        }
        if (leaf_block_8(b, &r->lr, &r->p, &r->t, &r->u, &r->v, &r->prim, a->scene->tri_count, naive,
                         spheres, r->any) &&
            r->any) {
            r->prim = b->id[0]; /* occluded: which primitive does not matter */
            r->done = 1;
            return;
        }
    }
}

/* ---- bottom level: BVH ------------------------------------------------------ */

/* Slab test of a node's box grown by pad (Ize 2013's robust float test). */
INLINE int node_slab(const bvh_node *n, float pad, vec3 org, vec3 inv, const int *neg, float lo_t,
                     float hi_t, float *entry)
{
    if (pad == 0.0f) return box3_slab(n->bmin, n->bmax, org, inv, neg, lo_t, hi_t, entry);
    float lo[3] = {n->bmin[0] - pad, n->bmin[1] - pad, n->bmin[2] - pad};
    float hi[3] = {n->bmax[0] + pad, n->bmax[1] + pad, n->bmax[2] + pad};
    return box3_slab(lo, hi, org, inv, neg, lo_t, hi_t, entry);
}

/* The ray (org, dir) is the instance's ray shifted by `shift` (object
 * parameter tau = t - shift); slack widens the t range by a relative
 * 2^-20 for non-identity instances (the world test decides anyway). */
INLINE void walk_bvh(const inst_accel *a, const inst_item *it, const inst_bottom *b,
                     ray_state *r, vec3 org, vec3 dir, float pad, double shift, int naive,
                     int spheres)
{
    const bvh_box_tree *h = &b->bvh;
    if (!h->node_count) return;
    vec3 inv = v3(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
    int neg[3] = {signbit(dir.x) != 0, signbit(dir.y) != 0, signbit(dir.z) != 0};
    float slack = it->identity ? 0.0f : 0x1p-20f;
    float lo_t = inst_walk_lo(r->p.t_near, shift, slack);
    struct { uint32_t node; float entry; } stack[INST_STACK];
    int sp = 0;
    uint32_t node = 0;
    for (;;) {
        const bvh_node *n = &h->nodes[node];
        if (r->counted) r->bottom_steps++;
        if (n->count) {
            for (uint32_t i = 0; i < n->count; i++) {
                test_prim(a, it, b->mesh, h->order[n->left_first + i], r, naive, spheres);
                if (r->done) return;
            }
        } else {
            float hi_t = inst_walk_hi(r->t, shift, slack);
            uint32_t c0 = n->left_first, c1 = c0 + 1;
            float e0, e1;
            int h0 = node_slab(&h->nodes[c0], pad, org, inv, neg, lo_t, hi_t, &e0);
            int h1 = node_slab(&h->nodes[c1], pad, org, inv, neg, lo_t, hi_t, &e1);
            if (r->counted) r->boxes += 2;
            if (h0 && h1) {
                int near0 = e0 <= e1;
                stack[sp].node = near0 ? c1 : c0;
                stack[sp++].entry = near0 ? e1 : e0;
                node = near0 ? c0 : c1;
                continue;
            }
            if (h0 || h1) {
                node = h0 ? c0 : c1;
                continue;
            }
        }
        /* Pop, skipping nodes that start beyond the closest hit found since. */
        for (;;) {
            if (sp == 0) return;
            --sp;
            float hi_t = inst_walk_hi(r->t, shift, slack);
            if (box3_entry_before(stack[sp].entry, hi_t)) break;
        }
        node = stack[sp].node;
    }
}

/* ---- both BVH levels, 8-wide (inst_wide.c) --------------------------------------- */

static void visit_instance_flat(const inst_accel *a, uint32_t k, ray_state *r, int naive,
                                int spheres);

/* The walk of an inst_wide: the bottom level of instance `it` (as walk_bvh:
 * the ray shifted by `shift`, t range widened by the slack, boxes grown by
 * pad), or the top level (it == NULL: the world ray, no pad, no slack;
 * leaves are instances). A node is the wide BVH's (bvh/wide/kernel.h: the
 * slab test of its 8 boxes, grown by the pad where there is one, and the
 * hit children pushed in the node's octant order, the nearest first); a
 * pushed child is skipped when it starts beyond the closest hit found since. */
INLINE void walk_wide(const inst_accel *a, const inst_item *it, const inst_wide *w, ray_state *r,
                      vec3 org, vec3 dir, float pad, double shift, int naive, int spheres, int cnt)
{
    if (w->root == WIDE_EMPTY) return;
    const int top = it == NULL;
    float slack = top || it->identity ? 0.0f : 0x1p-20f;
    /* The node test reads the prep's origin, reciprocals, signs and t_near. */
    accel_ray_prep p;
    p.org = org;
    p.inv_dir = top ? r->p.inv_dir : v3(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
    p.neg[0] = signbit(dir.x) != 0, p.neg[1] = signbit(dir.y) != 0, p.neg[2] = signbit(dir.z) != 0;
    p.t_near = inst_walk_lo(r->p.t_near, shift, slack); /* top: shift 0, slack 0 */
    node_ray_8_8 nr;
    node_setup_8_8(&nr, &p);
    const int padded = pad != 0.0f;
    node_pad_8_8 np;
    pad_setup_8_8(&np, &p, pad);
    const int oct = 3 * (p.neg[0] | p.neg[1] << 1 | p.neg[2] << 2);
    uint32_t sref[WIDE_STACK(INST_WIDE) + INST_WIDE]; /* a node stores 8 lanes at the top */
    float st[WIDE_STACK(INST_WIDE) + INST_WIDE];
    int sp = 0;
    uint32_t ref = w->root;
    const wide_node8 *nodes = w->nodes;
    /* The end of the range in the walk's parameter: changes only at leaves. */
    float hi_t = inst_walk_hi(r->t, shift, slack);
    for (;;) {
        if (ref & WIDE_LEAF) {
            uint32_t first = wide_leaf_first(ref), nb = wide_leaf_blocks(ref);
            if (top) {
                for (uint32_t i = 0; i < nb; i++) {
                    visit_instance_flat(a, w->ids[first + i], r, naive, spheres);
                    if (r->done) return;
                }
            } else {
                test_blocks(a, it, w, first, nb, r, naive, spheres, cnt);
                if (r->done) return;
            }
            hi_t = inst_walk_hi(r->t, shift, slack);
        } else {
            if (cnt) {
                if (top)
                    r->top_steps++;
                else
                    r->bottom_steps++;
                r->boxes += INST_WIDE;
            }
            if (padded ? visit_node_oct_pad_8_8(&nodes[ref], &nr, &np, hi_t, &ref, sref, st, &sp, oct)
                       : visit_node_oct_8_8(&nodes[ref], &nr, hi_t, &ref, sref, st, &sp, oct, 0))
                continue;
        }
        for (;;) {
            if (sp == 0) return;
            --sp;
            if (box3_entry_before(st[sp], hi_t)) break;
        }
        ref = sref[sp];
    }
}

/* ---- grids: grid_core.h's DDA, the ray in double ----------------------------------- */

/* Clips [t0, t1] of the ray (o, d), in double, to the grid's box and sets
 * up the walk from there; 0 if the ray misses the box. */
INLINE int grid_start(const inst_grid *g, const double *o, const double *d, double t0, double t1,
                      grid_dda *w)
{
    const grid_frame *f = &g->frame;
    for (int k = 0; k < 3; k++) {
        double lo = f->lo[k], hi = f->hi[k];
        if (d[k] == 0.0) {
            if (o[k] < lo || o[k] > hi) return 0;
            continue;
        }
        double a = (lo - o[k]) / d[k], b = (hi - o[k]) / d[k];
        if (a > b) { double x = a; a = b; b = x; }
        t0 = a > t0 ? a : t0;
        t1 = b < t1 ? b : t1;
    }
    if (!(t0 <= t1)) return 0;
    grid_dda_init_d(w, f, o, d, t0);
    return 1;
}

/* A bottom grid cell's triangle, decided in world space (grid_cell_visit's
 * visitor): 0 once the ray is done. */
typedef struct {
    const inst_accel *a;
    const inst_item *it;
    const inst_bottom *b;
    ray_state *r;
    int naive, spheres;
} bottom_cell;

INLINE int bottom_prim(void *ctx, uint32_t q)
{
    const bottom_cell *v = ctx;
    test_prim(v->a, v->it, v->b->mesh, q, v->r, v->naive, v->spheres);
    return !v->r->done;
}

INLINE void walk_grid(const inst_accel *a, const inst_item *it, const inst_bottom *b, ray_state *r,
                      const double *o, const double *d, double t0, int naive, int spheres)
{
    const inst_grid *g = &b->grid;
    grid_dda w;
    if (!grid_start(g, o, d, t0, r->t, &w)) return;
    bottom_cell v = {a, it, b, r, naive, spheres};
    uint32_t mb[GRID_MAILBOX];
    grid_mailbox_clear(mb);
    do {
        uint32_t begin = g->cells.offsets[w.cell], end = g->cells.offsets[w.cell + 1];
        if (r->counted) r->bottom_steps++, r->empties += begin == end;
        if (!grid_cell_visit(g->cells.refs + begin, end - begin, mb, &r->skips, bottom_prim, &v))
            return;
        if (r->t <= grid_dda_exit(&w)) return;
    } while (grid_dda_step(&w));
}

/* The walks as real functions, flattened: everything they call (the
 * slab test, the triangle test, the vertex transform) is inlined into
 * them, which GCC's size limits would otherwise refuse in this kernel. One
 * call per instance visited; the flags become run-time arguments there. */
static __attribute__((flatten, noinline)) void
walk_bvh_flat(const inst_accel *a, const inst_item *it, const inst_bottom *b, ray_state *r,
              vec3 org, vec3 dir, float pad, double shift, int naive, int spheres)
{
    if (naive)
        walk_bvh(a, it, b, r, org, dir, pad, shift, 1, spheres);
    else if (spheres)
        walk_bvh(a, it, b, r, org, dir, pad, shift, 0, 1);
    else
        walk_bvh(a, it, b, r, org, dir, pad, shift, 0, 0);
}

static __attribute__((flatten, noinline)) void
walk_wide_flat(const inst_accel *a, const inst_item *it, const inst_bottom *b, ray_state *r,
               vec3 org, vec3 dir, float pad, double shift, int naive, int spheres)
{
    const inst_wide *w = &b->wide;
    if (r->counted) {
        if (naive)
            walk_wide(a, it, w, r, org, dir, pad, shift, 1, spheres, 1);
        else if (spheres)
            walk_wide(a, it, w, r, org, dir, pad, shift, 0, 1, 1);
        else
            walk_wide(a, it, w, r, org, dir, pad, shift, 0, 0, 1);
    } else if (naive)
        walk_wide(a, it, w, r, org, dir, pad, shift, 1, spheres, 0);
    else if (spheres)
        walk_wide(a, it, w, r, org, dir, pad, shift, 0, 1, 0);
    else
        walk_wide(a, it, w, r, org, dir, pad, shift, 0, 0, 0);
}

static __attribute__((flatten, noinline)) void
walk_grid_flat(const inst_accel *a, const inst_item *it, const inst_bottom *b, ray_state *r,
               const double *o, const double *d, double t0, int naive, int spheres)
{
    if (naive)
        walk_grid(a, it, b, r, o, d, t0, 1, spheres);
    else if (spheres)
        walk_grid(a, it, b, r, o, d, t0, 0, 1);
    else
        walk_grid(a, it, b, r, o, d, t0, 0, 0);
}

/* ---- bottom level: any kind with a walk (accel.h) ------------------------------ */

typedef struct {
    const inst_accel *a;
    const inst_item *it;
    const inst_bottom *b;
    ray_state *r;
    double shift;
    float slack;
    int naive, spheres;
} walk_ctx;

/* The walk's visitor: decides the candidate in world space and hands back
 * the closest hit so far in the walk's parameter (object space, from the
 * box entry), widened by the slack; -inf ends an occlusion walk. */
static float walk_visit(void *ctx, uint32_t q, float t_max)
{
    walk_ctx *w = ctx;
    if (w->naive)
        test_prim(w->a, w->it, w->b->mesh, q, w->r, 1, w->spheres);
    else if (w->spheres)
        test_prim(w->a, w->it, w->b->mesh, q, w->r, 0, 1);
    else
        test_prim(w->a, w->it, w->b->mesh, q, w->r, 0, 0);
    if (w->r->done) return -INFINITY;
    float hi_t = inst_walk_hi(w->r->t, w->shift, w->slack);
    return hi_t < t_max ? hi_t : t_max;
}

static __attribute__((noinline)) void walk_kind(const inst_accel *a, const inst_item *it,
                                                const inst_bottom *b, ray_state *r, vec3 org,
                                                vec3 dir, float pad, double shift, int naive,
                                                int spheres)
{
    walk_ctx w = {a, it, b, r, shift, it->identity ? 0.0f : 0x1p-20f, naive, spheres};
    float lo_t = inst_walk_lo(r->p.t_near, shift, w.slack);
    float hi_t = inst_walk_hi(r->t, shift, w.slack);
    accel_ray ray = {org.x, org.y, org.z, lo_t, dir.x, dir.y, dir.z, hi_t};
    uint32_t steps = 0;
    if (b->walk) a->walk_kind->walk(b->walk, &ray, pad, walk_visit, &w, &steps);
    r->bottom_steps += steps;
    /* Triangles the kind left out (no area in object space). */
    for (uint32_t i = 0; i < b->dead_count && !r->done; i++) walk_visit(&w, b->dead[i], hi_t);
}

/* ---- one instance ------------------------------------------------------------- */

INLINE void visit_instance(const inst_accel *a, uint32_t k, ray_state *r, int naive, int spheres)
{
    const inst_item *it = &a->items[k];
    const inst_bottom *b = &a->bottoms[it->bottom];
    if (it->identity) {
        /* No transform: the walk sees the world ray itself, no pad (its
         * box and cell tests are the kind's own robust ones, on the very
         * floats the world test uses). */
        if (a->bottom_kind == INST_WALK)
            walk_kind(a, it, b, r, r->p.org, r->p.dir, 0.0f, 0.0, naive, spheres);
        else if (a->bottom_kind == INST_BVH && a->width == INST_WIDE)
            walk_wide_flat(a, it, b, r, r->p.org, r->p.dir, 0.0f, 0.0, naive, spheres);
        else if (a->bottom_kind == INST_BVH)
            walk_bvh_flat(a, it, b, r, r->p.org, r->p.dir, 0.0f, 0.0, naive, spheres);
        else
            walk_grid_flat(a, it, b, r, r->o, r->d, r->p.t_near, naive, spheres);
        return;
    }
    /* The ray in object space, in double, with a bound on its rounding,
     * clipped to the mesh's padded box (inst_ray.h). */
    inst_oray q;
    int clip = inst_object_ray(a, it, b, r->o, r->d, r->p.t_near, r->t, &q);
    if (clip < 0) return;
    if (r->counted) r->boxes++;
    if (!clip) return;
    const double *o = q.o, *d = q.d, s0 = q.s0, e_ray = q.e_ray;
    if (a->bottom_kind == INST_GRID) {
        /* The grid holds boxes grown by the largest pad of the mesh's
         * instances plus 2^-24 of its size; a ray known more loosely than
         * that (an origin some 2^20 mesh sizes away) tests every triangle. */
        if (e_ray > 0x1p-26 * b->abs_max) {
            for (uint32_t k = 0; k < b->mesh->tri_count && !r->done; k++)
                test_prim(a, it, b->mesh, k, r, naive, 0);
            return;
        }
        walk_grid_flat(a, it, b, r, o, d, s0, naive, spheres);
        return;
    }
    vec3 of, df;
    float padf;
    inst_object_float(a, b, &q, &of, &df, &padf);
    if (a->bottom_kind == INST_WALK)
        walk_kind(a, it, b, r, of, df, padf, s0, naive, spheres);
    else if (a->width == INST_WIDE)
        walk_wide_flat(a, it, b, r, of, df, padf, s0, naive, spheres);
    else
        walk_bvh_flat(a, it, b, r, of, df, padf, s0, naive, spheres);
}

static void visit_instance_flat(const inst_accel *a, uint32_t k, ray_state *r, int naive,
                                int spheres)
{
    visit_instance(a, k, r, naive, spheres);
}

/* ---- top level ------------------------------------------------------------------ */

INLINE void top_bvh(const inst_accel *a, ray_state *r, int naive, int spheres)
{
    const bvh_box_tree *h = &a->top_bvh;
    if (!h->node_count) return;
    struct { uint32_t node; float entry; } stack[INST_STACK];
    int sp = 0;
    uint32_t node = 0;
    float e;
    if (r->counted) r->boxes++;
    if (!box3_slab(h->nodes[0].bmin, h->nodes[0].bmax, r->p.org, r->p.inv_dir, r->p.neg, r->p.t_near,
                   r->t, &e))
        return;
    for (;;) {
        const bvh_node *n = &h->nodes[node];
        if (r->counted) r->top_steps++;
        if (n->count) {
            for (uint32_t i = 0; i < n->count; i++) {
                visit_instance(a, h->order[n->left_first + i], r, naive, spheres);
                if (r->done) return;
            }
        } else {
            uint32_t c0 = n->left_first, c1 = c0 + 1;
            float e0, e1;
            int h0 = box3_slab(h->nodes[c0].bmin, h->nodes[c0].bmax, r->p.org, r->p.inv_dir, r->p.neg,
                               r->p.t_near, r->t, &e0);
            int h1 = box3_slab(h->nodes[c1].bmin, h->nodes[c1].bmax, r->p.org, r->p.inv_dir, r->p.neg,
                               r->p.t_near, r->t, &e1);
            if (r->counted) r->boxes += 2;
            if (h0 && h1) {
                int near0 = e0 <= e1;
                stack[sp].node = near0 ? c1 : c0;
                stack[sp++].entry = near0 ? e1 : e0;
                node = near0 ? c0 : c1;
                continue;
            }
            if (h0 || h1) {
                node = h0 ? c0 : c1;
                continue;
            }
        }
        do {
            if (sp == 0) return;
            --sp;
        } while (!box3_entry_before(stack[sp].entry, r->t));
        node = stack[sp].node;
    }
}

/* A top grid cell's instance (grid_cell_visit's visitor): walked when the
 * ray reaches its world bounds; 0 once the ray is done. */
typedef struct {
    const inst_accel *a;
    ray_state *r;
    int naive, spheres;
} top_cell;

INLINE int top_item(void *ctx, uint32_t k)
{
    const top_cell *v = ctx;
    ray_state *r = v->r;
    float e;
    if (r->counted) r->boxes++;
    const box3 *bb = &v->a->item_boxes[k];
    if (!box3_slab(&bb->min.x, &bb->max.x, r->p.org, r->p.inv_dir, r->p.neg, r->p.t_near, r->t,
                   &e))
        return 1;
    visit_instance(v->a, k, r, v->naive, v->spheres);
    return !r->done;
}

INLINE void top_grid(const inst_accel *a, ray_state *r, int naive, int spheres)
{
    const inst_grid *g = &a->top_grid;
    grid_dda w;
    if (!grid_start(g, r->o, r->d, r->p.t_near, r->t, &w)) return;
    top_cell v = {a, r, naive, spheres};
    uint32_t mb[GRID_MAILBOX];
    grid_mailbox_clear(mb);
    do {
        uint32_t begin = g->cells.offsets[w.cell], end = g->cells.offsets[w.cell + 1];
        if (r->counted) r->top_steps++, r->empties += begin == end;
        if (!grid_cell_visit(g->cells.refs + begin, end - begin, mb, &r->skips, top_item, &v))
            return;
        if (r->t <= grid_dda_exit(&w)) return;
    } while (grid_dda_step(&w));
}

/* ---- batch kernels ------------------------------------------------------------- */

INLINE void kernel(const void *acc, const accel_ray *rays, void *out, size_t count,
                   accel_counters *c, unsigned flags, int any)
{
    const inst_accel *a = acc;
    int naive = (flags & ACCEL_V_NAIVE) != 0, spheres = (flags & ACCEL_V_SPHERES) != 0;
    for (size_t i = 0; i < count; i++) {
        ray_state r;
        r.prim = ACCEL_MISS;
        r.any = any, r.done = 0, r.counted = c != NULL;
        r.top_steps = r.bottom_steps = r.boxes = r.prims = r.empties = r.skips = 0;
        r.u = r.v = 0.0f;
        if (accel_prep_ray(&rays[i], &r.p)) {
            leaf_setup_8(&r.lr, &r.p);
            r.t = r.p.t_far;
            r.o[0] = r.p.org.x, r.o[1] = r.p.org.y, r.o[2] = r.p.org.z;
            r.d[0] = r.p.dir.x, r.d[1] = r.p.dir.y, r.d[2] = r.p.dir.z;
            if (a->top == INST_BVH && a->width == INST_WIDE)
                walk_wide(a, NULL, &a->top_wide, &r, r.p.org, r.p.dir, 0.0f, 0.0, naive, spheres,
                          c != NULL);
            else if (a->top == INST_BVH)
                top_bvh(a, &r, naive, spheres);
            else
                top_grid(a, &r, naive, spheres);
        }
        if (any) {
            ((uint8_t *)out)[i] = r.prim != ACCEL_MISS;
        } else {
            accel_hit h = accel_hit_miss();
            if (r.prim != ACCEL_MISS) h.t = r.t, h.prim = r.prim, h.u = r.u, h.v = r.v;
            ((accel_hit *)out)[i] = h;
        }
        if (c) {
            accel_count_ray(c, i, r.top_steps + r.bottom_steps, r.empties, r.boxes, r.prims,
                            r.skips);
            c->level_steps[0] += r.top_steps;
            c->level_steps[1] += r.bottom_steps;
        }
    }
}

#define CLOSEST_KERNEL(a, r, o, n, c, f) kernel(a, r, o, n, c, f, 0)
#define ANY_KERNEL(a, r, o, n, c, f) kernel(a, r, o, n, c, f, 1)
/* The copies the experiments time (core/variant.h; issue 53's GRIDBVH_KLOG
 * runs): triangles (0), spheres (2), closest hits with the naive test (1);
 * the kind never sets ACCEL_V_OPT. */
ACCEL_KERNEL_TABLE_SEL(inst_closest_table, CLOSEST_KERNEL, (1, 1, 1, 0, 0, 0, 0, 0))
ACCEL_KERNEL_TABLE_SEL(inst_any_table, ANY_KERNEL, (1, 0, 1, 0, 0, 0, 0, 0))

static unsigned flags_of(const inst_accel *a)
{
    return accel_variant_flags(a->naive, a->spheres, 0);
}

#define INST_TRACE_HIT WIDE_UNIT(inst_trace_intersect)
#define INST_TRACE_OCC WIDE_UNIT(inst_trace_occluded)
ACCEL_KERNEL_ENTRIES(INST_TRACE_HIT, INST_TRACE_OCC, const void, inst_closest_table, inst_any_table, flags_of)
