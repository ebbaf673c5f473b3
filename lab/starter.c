/*
 * starter.c - the lab's starting point (see LAB.md): a BVH kind with every
 * piece of plumbing in place and the lab's steps left to write.
 *
 * `make lab` copies this file to lab/student.c (kind name "student") the
 * first time; you edit lab/student.c, never this file: `make test` checks
 * that the lab's checks fail on this untouched starter.
 *
 * What is here already: the node (the lecture's 32 bytes), the primitive
 * store every kind builds over (accel.h: the live primitives, local ids,
 * scene_id[] to map a hit back), the parameters, the batch entries, the
 * counters, memory and destroy. What you write, step by step:
 *
 *   step 1  build_node(): a median-split BVH (the lecture's lab, step 1)
 *   step 2  trace_ray(): single-ray traversal with a ray/box test, counting
 *           nodes visited (the depth view is a heatmap of that count)
 *   step 3  walk_ray(): your step 2 traversal as a conservative walk, boxes
 *           grown by a pad, every primitive of a reached leaf handed to a
 *           callback: your kind becomes the bottom level of the two-level
 *           kind `instanced`, which transforms rays to object space
 *   step 4  trace_packet(): 8x8 packets of rays (traverse=packet)
 *   step 7  (optional) lab_top_starter(): the top level of a scene of
 *           instances yourself: the loop, the inverse transforms, t in world
 *           units (lab/top.h)
 *
 * Step 5 measures your frames per second.
 *
 * Useful, in accel/core/: box3_slab (geom.h: the robust ray/box slab test),
 * accel_prep_ray and accel_prim_hit (prim.h: ray setup and the exact
 * watertight triangle test), accel_prim_bounds / accel_prim_centroid.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/prim.h"
#include "core/variant.h"
#include "top.h"      /* step 7 (optional): the top level */
#include "validate.h" /* the tree check run after your build (nothing to do there) */

/* The lecture's node: a leaf holds `count` primitives starting at
 * order[left_first]; an interior node (count == 0) has its children at
 * nodes[left_first] and nodes[left_first + 1]. */
typedef struct {
    float bmin[3];
    uint32_t left_first;
    float bmax[3];
    uint32_t count;
} lab_node;

_Static_assert(sizeof(lab_node) == 32, "the lecture's 32-byte node");
_Static_assert(sizeof(lab_node) == sizeof(lab_tree_node) &&
                   offsetof(lab_node, count) == offsetof(lab_tree_node, count),
               "validate.h reads the nodes");

/* Deepest tree the traversal stack allows (a median split halves the
 * primitives at every level, so 64 levels hold 2^64 of them). */
#define LAB_MAX_DEPTH 64

typedef struct {
    accel_prim_store store; /* the primitives (local ids) and scene_id[] */
    lab_node *nodes;        /* node_count nodes, root first */
    uint32_t node_count;
    uint32_t *order;        /* local primitive ids in leaf order */
    int max_leaf;           /* leaf=N: largest leaf */
    int packet;             /* traverse=packet */
    int naive;              /* tri=naive */
    int depth;              /* tree depth, root = 1 (for the statistics) */
    uint32_t leaf_count;
} lab_bvh;

/* The parameters as parsed: one field per key of lab_params, where
 * .offset tells the parser where each value goes (a parameter of your own
 * is a field here and a line there). */
typedef struct {
    int leaf;     /* leaf=N: largest leaf */
    int traverse; /* traverse=single (0) or packet (1): the choice's position */
} lab_spec;

static const accel_param_def lab_params[] = {
    {.key = "leaf", .type = ACCEL_PARAM_INT, .def = "4", .min = 1, .max = 64,
     .help = "largest leaf (primitives)", .offset = offsetof(lab_spec, leaf)},
    {.key = "traverse", .type = ACCEL_PARAM_ENUM, .def = "single", .choices = "single|packet",
     .help = "single rays, or packets of 64 consecutive rays (8x8 tiles) (step 4)",
     .offset = offsetof(lab_spec, traverse)},
};

/* ---- step 1: build -------------------------------------------------------- */

/*
 * Builds the subtree of node `idx` over order[first, first + count) and
 * returns 0 (or an accel_fail status). To do (step 1):
 *  - set the node's box to the bounds of its primitives
 *    (accel_prim_bounds(&b->store.prims, prim));
 *  - if count <= b->max_leaf, make it a leaf (left_first = first);
 *  - else split at the object median along the largest axis of the
 *    centroids' bounds (sort or partially sort order[first..] by centroid,
 *    e.g. with qsort_r, whose context argument carries the axis, or an
 *    nth-element of your own), take two new nodes
 *    (b->node_count, b->node_count + 1), and recurse into both halves;
 *  - keep b->depth and b->leaf_count up to date.
 * The node pool holds 2 * prim_count nodes: enough for any binary tree.
 */
static int build_node(lab_bvh *b, uint32_t idx, uint32_t first, uint32_t count, int level,
                      accel_error *err)
{
    (void)b;
    (void)idx;
    (void)first;
    (void)count;
    (void)level;
    (void)err;
    return ACCEL_OK; /* TODO step 1 */
}

static void lab_destroy(void *a)
{
    lab_bvh *b = a;
    if (!b) return;
    accel_prim_store_free(&b->store);
    free(b->nodes);
    free(b->order);
    free(b);
}

static size_t lab_memory(const void *a)
{
    const lab_bvh *b = a;
    return sizeof *b + accel_prim_store_bytes(&b->store) +
           (size_t)b->node_count * sizeof(lab_node) +
           (size_t)b->store.prims.prim_count * sizeof(uint32_t);
}

static int lab_build(const accel_scene *scene, const accel_params *params, int threads,
                     void **out, accel_build_stats *stats, accel_error *err)
{
    (void)threads;
    *out = NULL;
    lab_bvh *b = calloc(1, sizeof *b);
    if (!b) return accel_fail(err, ACCEL_ERR_NOMEM, "lab: out of memory");
    int rc = accel_prim_store_build(scene, params->reorder, &b->store, err);
    if (rc) {
        free(b);
        return rc;
    }
    const lab_spec *spec = ACCEL_SPEC(params, lab_spec);
    b->max_leaf = spec->leaf;
    b->packet = spec->traverse == 1;
    b->naive = params->naive;
    uint32_t n = b->store.prims.prim_count;
    b->nodes = calloc((size_t)2 * n + 1, sizeof *b->nodes);
    b->order = malloc(((size_t)n + 1) * sizeof *b->order);
    if (!b->nodes || !b->order) {
        lab_destroy(b);
        return accel_fail(err, ACCEL_ERR_NOMEM, "lab: out of memory for %u primitives", n);
    }
    for (uint32_t i = 0; i < n; i++) b->order[i] = i;
    if (n > 0) {
        b->node_count = 1; /* the root; build_node takes its children from here on */
        rc = build_node(b, 0, 0, n, 1, err);
        /* Your tree, checked (validate.h): a wrong box or a lost primitive
         * fails here with "node 17: ...", not later as a hole or a crash. */
        if (!rc)
            rc = lab_validate_tree((const lab_tree_node *)b->nodes, b->node_count, b->order,
                                   &b->store.prims, err);
        if (rc) {
            lab_destroy(b);
            return rc;
        }
    }
    memset(stats, 0, sizeof *stats);
    stats->nodes = b->leaf_count ? b->node_count : 0;
    stats->leaves = b->leaf_count;
    stats->depth = b->depth;
    stats->refs = 0;
    for (uint32_t i = 0; i < b->node_count && b->leaf_count; i++) stats->refs += b->nodes[i].count;
    stats->sah_cost = NAN;
    stats->bytes = lab_memory(b);
    *out = b;
    return ACCEL_OK;
}

/* ---- step 2: single rays -------------------------------------------------- */

/*
 * Closest hit (any_hit == 0) or any hit of one ray. To do (step 2): from
 * the root, test a node's box with box3_slab (geom.h) using p->org,
 * p->inv_dir, p->neg, p->t_near and the closest hit so far; in a leaf test
 * its primitives with accel_prim_hit(&b->store.prims, prim, p, &t, &u, &v,
 * naive, spheres), which keeps the nearest hit in t; at an interior node
 * visit the nearer child first and push the other on a stack of
 * LAB_MAX_DEPTH entries, with its entry distance. Drop a popped node whose
 * entry lies beyond the closest hit t with !box3_entry_before(entry, t)
 * (geom.h): `entry < t` or `entry <= t` loses hits on rays that end exactly
 * at the hit (t_far == the hit's t), where the entry's rounding can land
 * just past t. Count every node visited in *steps, every box
 * test in *boxes, every primitive test in *prims (the depth view and the
 * checks read them). Return the local id hit (or ACCEL_MISS) and fill
 * *t_out, *u_out, *v_out.
 */
static inline __attribute__((always_inline)) uint32_t
trace_ray(const lab_bvh *b, const accel_ray_prep *p, int any_hit, int naive, int spheres,
          float *t_out, float *u_out, float *v_out, uint32_t *steps, uint32_t *boxes,
          uint32_t *prims)
{
    (void)b;
    (void)p;
    (void)any_hit;
    (void)naive;
    (void)spheres;
    (void)t_out;
    (void)u_out;
    (void)v_out;
    (void)steps;
    (void)boxes;
    (void)prims;
    return ACCEL_MISS; /* TODO step 2 */
}

/* ---- step 3: the walk (many meshes) -------------------------------------- */

/*
 * accel.h's conservative walk: the two-level kind `instanced` builds your
 * kind once per mesh, in the mesh's object space, and for each instance a
 * ray reaches it calls this with the ray in object space. It decides every
 * triangle itself, on the world-space copy the flattened scene holds, so
 * all it needs from you is every primitive the ray passes NEAR: within
 * `pad` of the ray (the flattening rounds each world triangle to float,
 * and the object-space ray is rounded too; the pad covers both).
 *
 * To do (step 3): your trace_ray() from step 2, with two changes:
 *  - grow every box by pad on every side before box3_slab (bmin - pad,
 *    bmax + pad), with the current t_max as the far end of the ray;
 *  - in a leaf, do not test the primitives (no accel_prim_hit: hand over
 *    every one, hit or not): for each prim = b->order[left_first + i], call
 *    t_max = visit(ctx, b->store.scene_id[prim], t_max);
 *    the answer is the closest hit instanced has found so far (in your
 *    ray's t): use it to cull boxes and popped nodes as in step 2. If it
 *    drops below p->t_near the walk is over (an occlusion ray hit): return.
 * t_near need not be 0 (instanced may move the origin along the ray): use
 * p->t_near and the t_max visit() returns, nothing else. Count every node
 * visited in *steps. Visiting a primitive twice, or one
 * that is not hit, is allowed; missing one is a hole.
 */
static int walk_ray(const lab_bvh *b, const accel_ray_prep *p, float pad, accel_walk_visit visit,
                    void *ctx, uint32_t *steps)
{
    (void)b;
    (void)p;
    (void)pad;
    (void)visit;
    (void)ctx;
    (void)steps;
    return ACCEL_OK; /* TODO step 3: visits nothing yet */
}

/*
 * Optional step 7 (LAB.md): the top level yourself, as the lecture's step 3
 * means it. `top` holds your kind built once per mesh in the mesh's object
 * space (top->mesh_accel[mesh]) and the instances (top->instances[k]: its
 * mesh, the id `base` of its first primitive in the flattened scene, and
 * `inverse`, the world -> object 3x4 matrix, rows: x' = m[0]x + m[1]y +
 * m[2]z + m[3], ...). To do: for every instance, transform the ray's origin
 * (a point: with the translation column) and direction (a vector: without
 * it) by `inverse`, in double, and do NOT renormalize the direction: then
 * t along the object ray is t along the world ray, so t_near, t_far and
 * the hit's t stay in world units. Trace it with
 * top->kind->intersect(top->mesh_accel[mesh], &object_ray, &h, 1, NULL),
 * with t_far the nearest hit so far; keep the nearest hit over all
 * instances, its id base + h.prim. *hit = accel_hit_miss() when none.
 */
void lab_top_starter(const lab_top *top, const accel_ray *ray, accel_hit *hit)
{
    (void)top;
    (void)ray;
    *hit = accel_hit_miss(); /* TODO step 7 (optional) */
}

static int lab_walk(const void *a, const accel_ray *ray, float pad, accel_walk_visit visit,
                    void *ctx, uint32_t *steps)
{
    const lab_bvh *b = a;
    accel_ray_prep p;
    if (!visit) return ACCEL_OK; /* "can you walk?": yes */
    if (b->node_count == 0 || !accel_prep_ray(ray, &p)) return ACCEL_OK;
    return walk_ray(b, &p, pad, visit, ctx, steps);
}

/* ---- step 4: packets ------------------------------------------------------ */

/*
 * Traces rays[0, n) (n <= 64, consecutive rays: an 8x8 tile of primary
 * rays) together: one walk of the tree for the whole packet, a node
 * entered when any active ray hits its box (the lecture's "first active
 * ray" and early-out), the closest hit kept per ray. To do (step 4); until
 * then each ray is traced alone, which is correct but not a packet.
 * Fill hit_local[i] (local id or ACCEL_MISS), t[i], u[i], v[i], and the
 * per-ray counters as in step 2; count each node the packet enters (once
 * for the whole packet) in *packet_steps: the check's sharing figure. The
 * check holds it against the per-ray work (a packet fetches at least every
 * node its busiest ray needs): a count that is not the walk's is caught.
 */
static inline __attribute__((always_inline)) void
trace_packet(const lab_bvh *b, const accel_ray_prep *p, const int *valid, uint32_t n,
             int any_hit, int naive, int spheres, uint32_t *hit_local, float *t, float *u,
             float *v, uint32_t *steps, uint32_t *boxes, uint32_t *prims, uint32_t *packet_steps)
{
    (void)packet_steps;
    for (uint32_t i = 0; i < n; i++) /* TODO step 4: one walk for all n rays */
        hit_local[i] = valid[i] ? trace_ray(b, &p[i], any_hit, naive, spheres, &t[i], &u[i],
                                            &v[i], &steps[i], &boxes[i], &prims[i])
                                : ACCEL_MISS;
}

/* ---- batch entries (nothing to do here) ----------------------------------- */

static inline __attribute__((always_inline)) void
lab_kernel(const lab_bvh *b, const accel_ray *rays, accel_hit *hits, uint8_t *occ, size_t count,
           accel_counters *c, int naive, int spheres, int opt)
{
    (void)opt; /* the lab's kind has no switch of its own */
    const int any_hit = occ != NULL;
    for (size_t base = 0; base < count; base += 64) {
        uint32_t n = (uint32_t)(count - base < 64 ? count - base : 64);
        accel_ray_prep p[64];
        int valid[64];
        uint32_t local[64], steps[64] = {0}, boxes[64] = {0}, prims[64] = {0};
        float t[64], u[64], v[64];
        for (uint32_t i = 0; i < n; i++) {
            valid[i] = b->node_count > 0 && accel_prep_ray(&rays[base + i], &p[i]);
            t[i] = valid[i] ? p[i].t_far : INFINITY;
            u[i] = v[i] = 0.0f;
        }
        if (b->packet) {
            uint32_t packet_steps = 0;
            trace_packet(b, p, valid, n, any_hit, naive, spheres, local, t, u, v, steps, boxes,
                         prims, &packet_steps);
            if (c) c->packet_steps += packet_steps;
        } else {
            for (uint32_t i = 0; i < n; i++)
                local[i] = valid[i] ? trace_ray(b, &p[i], any_hit, naive, spheres, &t[i], &u[i],
                                                &v[i], &steps[i], &boxes[i], &prims[i])
                                    : ACCEL_MISS;
        }
        for (uint32_t i = 0; i < n; i++) {
            size_t r = base + i;
            if (occ) {
                occ[r] = local[i] != ACCEL_MISS;
            } else if (local[i] != ACCEL_MISS) {
                accel_hit h = {t[i], b->store.scene_id[local[i]], u[i], v[i]};
                hits[r] = h;
            } else {
                hits[r] = accel_hit_miss();
            }
            if (c) accel_count_ray(c, r, steps[i], 0, boxes[i], prims[i], 0);
        }
    }
}

ACCEL_KERNEL_PAIR_NO_OPT(lab, lab_kernel)

static unsigned lab_flags(const lab_bvh *b)
{
    return accel_variant_flags(b->naive, b->store.prims.sphere_count > 0, 0);
}

static void lab_intersect(const void *a, const accel_ray *rays, accel_hit *hits, size_t n,
                          accel_counters *c)
{
    accel_run_kernel(&lab_hit_table, a, rays, hits, n, c, lab_flags(a));
}

static void lab_occluded(const void *a, const accel_ray *rays, uint8_t *occ, size_t n,
                         accel_counters *c)
{
    accel_run_kernel(&lab_occ_table, a, rays, occ, n, c, lab_flags(a));
}

static const char *const lab_variants[] = {"", "leaf=1", "traverse=packet", NULL};

const accel_kind accel_kind_starter = {
    .name = "starter",
    .summary = "the lab's BVH (LAB.md): median split, single rays, packets",
    .step_name = "nodes",
    .params = lab_params,
    .param_count = sizeof lab_params / sizeof lab_params[0],
    .spec_size = sizeof(lab_spec),
    .variants = lab_variants,
    .build = lab_build,
    .intersect = lab_intersect,
    .occluded = lab_occluded,
    .memory = lab_memory,
    .destroy = lab_destroy,
    .walk = lab_walk,
};
