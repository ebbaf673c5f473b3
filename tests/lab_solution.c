/*
 * lab_solution.c - the lab's reference solution (LAB.md): lab/starter.c
 * with its four functions written as the lab asks (median split, single
 * rays near child first with the padded pop cull box3_entry_before, the
 * padded walk, 8x8 packets), and the mutant students of tests/test_lab.c:
 * each MUTANT(LM_...) point is one typical mistake (lab_solution.h),
 * chosen at run time by lab_solution_mutant so that one compile serves all
 * of them. Everything outside the four functions (and their helpers) is the
 * starter's, word for word (test_lab.c checks that), so the checks see the
 * solution exactly as they see a student's kind.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/prim.h"
#include "core/variant.h"
#include "tests/lab_solution.h"
#include "lab/top.h"
#include "lab/validate.h" /* the tree check run after your build (nothing to do there) */

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

int lab_solution_mutant = LM_NONE;
#define MUTANT(m) (lab_solution_mutant == (m))

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

/* The centroid of a primitive on one axis: the median split's sort key. */
static float centroid_on(const lab_bvh *b, uint32_t prim, int axis)
{
    vec3 c = accel_prim_centroid(&b->store.prims, prim);
    return axis == 0 ? c.x : axis == 1 ? c.y : c.z;
}

/* Puts the k-th smallest centroid (on axis) of ids[0, n) at ids[k], the
 * smaller ones before it and the larger after it (Hoare's quickselect,
 * middle pivot): the object median without a full sort. */
static void select_kth(const lab_bvh *b, uint32_t *ids, uint32_t n, uint32_t k, int axis)
{
    uint32_t lo = 0, hi = n - 1;
    while (lo < hi) {
        float pivot = centroid_on(b, ids[lo + (hi - lo) / 2], axis);
        uint32_t i = lo, j = hi;
        while (i <= j) {
            while (centroid_on(b, ids[i], axis) < pivot) i++;
            while (centroid_on(b, ids[j], axis) > pivot) j--;
            if (i <= j) {
                uint32_t tmp = ids[i];
                ids[i] = ids[j], ids[j] = tmp;
                i++;
                if (j == 0) break;
                j--;
            }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else break;
    }
}

/* Mutant LM_EMPTY_LEAF: a split at the middle of the node's box, with
 * every primitive in one child when the centroids all lie on one side
 * (the other child an empty leaf). Returns the left child's count. */
static uint32_t middle_split(lab_bvh *b, uint32_t first, uint32_t count, const lab_node *nd)
{
    float e[3] = {nd->bmax[0] - nd->bmin[0], nd->bmax[1] - nd->bmin[1], nd->bmax[2] - nd->bmin[2]};
    int axis = e[0] >= e[1] && e[0] >= e[2] ? 0 : e[1] >= e[2] ? 1 : 2;
    float mid = 0.5f * (nd->bmin[axis] + nd->bmax[axis]);
    uint32_t left = 0;
    for (uint32_t i = 0; i < count; i++)
        if (centroid_on(b, b->order[first + i], axis) < mid) {
            uint32_t tmp = b->order[first + left];
            b->order[first + left++] = b->order[first + i], b->order[first + i] = tmp;
        }
    return left == 0 ? count : left;
}

static void node_box(lab_bvh *b, lab_node *nd, uint32_t first, uint32_t count)
{
    if (MUTANT(LM_ROOT_BOX) && nd != b->nodes) { /* the root's box, made first */
        *nd = b->nodes[0];
        return;
    }
    box3 box = box3_empty();
    for (uint32_t i = 0; i < count; i++) {
        uint32_t prim = b->order[first + i];
        box3 pb = accel_prim_bounds(&b->store.prims, prim);
        if (MUTANT(LM_CENTROID_BOX)) pb.min = pb.max = accel_prim_centroid(&b->store.prims, prim);
        if (MUTANT(LM_FIRST_PRIM_BOX) && i > 0) break;
        box = box3_union(box, pb);
    }
    nd->bmin[0] = box.min.x, nd->bmin[1] = box.min.y, nd->bmin[2] = box.min.z;
    nd->bmax[0] = box.max.x, nd->bmax[1] = box.max.y, nd->bmax[2] = box.max.z;
}

static int build_node(lab_bvh *b, uint32_t idx, uint32_t first, uint32_t count, int level,
                      accel_error *err)
{
    lab_node *nd = &b->nodes[idx];
    node_box(b, nd, first, count);
    if (level > b->depth) b->depth = level;
    if (MUTANT(LM_LEAF_RECURSE) ? count < (uint32_t)b->max_leaf : count <= (uint32_t)b->max_leaf) {
        nd->left_first = MUTANT(LM_LEAF_START) ? idx : MUTANT(LM_LEAF_SWAP) ? count : first;
        nd->count = MUTANT(LM_LEAF_SWAP) ? first : count;
        if (!MUTANT(LM_NO_LEAF_COUNT)) b->leaf_count++;
        return ACCEL_OK;
    }
    if (level >= LAB_MAX_DEPTH && !MUTANT(LM_LEAF_RECURSE))
        return accel_fail(err, ACCEL_ERR_INTERNAL, "lab: deeper than %d levels", LAB_MAX_DEPTH);
    uint32_t half = count / 2;
    if (MUTANT(LM_EMPTY_LEAF)) {
        half = middle_split(b, first, count, nd);
        if (half == count) { /* the mutant's guard: all in one leaf, beside an empty one */
            uint32_t c = b->node_count;
            b->node_count += 2;
            nd->left_first = c;
            nd->count = 0;
            lab_node *l = &b->nodes[c], *r = &b->nodes[c + 1];
            node_box(b, l, first, count);
            node_box(b, r, first + count, 0);
            l->left_first = first, l->count = count;
            r->left_first = first + count, r->count = 0;
            b->leaf_count += 2;
            if (level + 1 > b->depth) b->depth = level + 1;
            return ACCEL_OK;
        }
    } else if (!MUTANT(LM_NO_SORT)) {
        box3 cb = box3_empty();
        for (uint32_t i = 0; i < count; i++)
            cb = box3_grow(cb, accel_prim_centroid(&b->store.prims, b->order[first + i]));
        int axis = MUTANT(LM_SPLIT_DEPTH) ? (level - 1) % 3 : v3_max_axis(box3_extent(cb));
        select_kth(b, b->order + first, count, half, axis);
    }
    uint32_t c = b->node_count;
    b->node_count += 2;
    nd->left_first = c;
    nd->count = 0;
    int rc = build_node(b, c, first, half, level + 1, err);
    if (rc) return rc;
    uint32_t right = MUTANT(LM_LOST_PRIM) ? half : count - half;
    return build_node(b, c + 1, first + half, right, level + 1, err);
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

/* The children of node nd that the ray enters before t, nearer first:
 * returns how many (0, 1 or 2), their indices in c[] and entries in e[]. */
static inline __attribute__((always_inline)) int
enter_children(const lab_bvh *b, const lab_node *nd, const accel_ray_prep *p, float t,
               uint32_t *c, float *e, uint32_t *boxes)
{
    float t_far = MUTANT(LM_NO_SHRINK) ? p->t_far : t;
    uint32_t l = nd->left_first, r = l + 1;
    float el, er;
    int hl = box3_slab(b->nodes[l].bmin, b->nodes[l].bmax, p->org, p->inv_dir, p->neg, p->t_near,
                       t_far, &el);
    int hr = box3_slab(b->nodes[r].bmin, b->nodes[r].bmax, p->org, p->inv_dir, p->neg, p->t_near,
                       t_far, &er);
    *boxes += 2;
    int swap = er < el; /* the nearer child first */
    if (MUTANT(LM_FAR_FIRST)) swap = !swap;
    if (MUTANT(LM_NO_ORDER)) swap = 0;
    if (hl && hr) {
        c[0] = swap ? r : l, e[0] = swap ? er : el;
        c[1] = swap ? l : r, e[1] = swap ? el : er;
        return 2;
    }
    c[0] = hl ? l : r, e[0] = hl ? el : er;
    return hl || hr;
}

/* A popped node is still worth entering: its entry lies before the
 * closest hit t, by the slab test's own padding (geom.h). */
static inline __attribute__((always_inline)) int still_before(float entry, float t)
{
    if (MUTANT(LM_NO_SHRINK)) return 1;
    if (MUTANT(LM_CULL_LT)) return entry < t;
    if (MUTANT(LM_CULL_LE)) return entry <= t;
    return box3_entry_before(entry, t);
}

static inline __attribute__((always_inline)) uint32_t
trace_ray(const lab_bvh *b, const accel_ray_prep *p, int any_hit, int naive, int spheres,
          float *t_out, float *u_out, float *v_out, uint32_t *steps, uint32_t *boxes,
          uint32_t *prims)
{
    uint32_t big_stack[LAB_MAX_DEPTH], small_stack[8], hit = ACCEL_MISS, sp = 0, node = 0;
    float big_entry[LAB_MAX_DEPTH], small_entry[8], t = p->t_far, u = 0.0f, v = 0.0f, e0;
    uint32_t *stack = MUTANT(LM_SMALL_STACK) ? small_stack : big_stack;
    float *entry = MUTANT(LM_SMALL_STACK) ? small_entry : big_entry;
    (*boxes)++;
    if (!box3_slab(b->nodes[0].bmin, b->nodes[0].bmax, p->org, p->inv_dir, p->neg, p->t_near, t,
                   &e0))
        return ACCEL_MISS;
    for (;;) {
        const lab_node *nd = &b->nodes[node];
        if (!MUTANT(LM_NO_STEPS) && !(MUTANT(LM_LEAVES_ONLY) && nd->count == 0)) (*steps)++;
        uint32_t c[2];
        float e[2];
        int enter = 0;
        if (nd->count > 0) {
            for (uint32_t i = 0; i < nd->count; i++) {
                uint32_t prim = b->order[nd->left_first + i];
                if (!MUTANT(LM_NO_PRIM_COUNT)) (*prims)++;
                if (accel_prim_hit(&b->store.prims, prim, p, &t, &u, &v, naive, spheres)) {
                    hit = MUTANT(LM_OWN_ORDER_ID) ? nd->left_first + i : prim;
                    if (any_hit && !MUTANT(LM_ANY_HIT_ALL)) goto done;
                }
            }
            if (MUTANT(LM_FIRST_HIT) && hit != ACCEL_MISS) goto done;
        } else {
            enter = enter_children(b, nd, p, t, c, e, boxes);
        }
        if (enter == 2 && !MUTANT(LM_NO_FAR_PUSH)) stack[sp] = c[1], entry[sp++] = e[1];
        if (enter) {
            node = c[0];
            continue;
        }
        if (MUTANT(LM_POP_EMPTY)) { /* pops without asking whether the stack is empty */
            do node = stack[--sp], e0 = entry[sp];
            while (!still_before(e0, t));
            continue;
        }
        while (sp > 0 && !still_before(entry[sp - 1], t)) sp--;
        if (sp == 0) break;
        node = stack[--sp];
    }
done:
    *t_out = t, *u_out = u, *v_out = v;
    return hit;
}

/* ---- step 3: the walk (many meshes) -------------------------------------- */

/* box3_slab on node nd's box grown by pad on every side. */
static inline int slab_padded(const lab_node *nd, const accel_ray_prep *p, float pad, float t_max,
                              float *entry)
{
    if (MUTANT(LM_WALK_NO_PAD)) pad = 0.0f;
    float lo[3] = {nd->bmin[0] - pad, nd->bmin[1] - pad, nd->bmin[2] - pad};
    float hi[3] = {nd->bmax[0] + pad, nd->bmax[1] + pad, nd->bmax[2] + pad};
    if (MUTANT(LM_WALK_T_ONE)) t_max = 1.0f;
    return box3_slab(lo, hi, p->org, p->inv_dir, p->neg, p->t_near, t_max, entry);
}

static int walk_ray(const lab_bvh *b, const accel_ray_prep *p, float pad, accel_walk_visit visit,
                    void *ctx, uint32_t *steps)
{
    float t_max = p->t_far, entry[LAB_MAX_DEPTH], e0, e1;
    uint32_t stack[LAB_MAX_DEPTH], sp = 0, node = 0;
    if (MUTANT(LM_WALK_ALL)) { /* ignores the tree: every primitive, every ray */
        (*steps)++;
        for (uint32_t i = 0; i < b->store.prims.prim_count && t_max >= p->t_near; i++)
            t_max = visit(ctx, b->store.scene_id[i], t_max);
        return ACCEL_OK;
    }
    if (!slab_padded(&b->nodes[0], p, pad, t_max, &e0)) return ACCEL_OK;
    for (;;) {
        const lab_node *nd = &b->nodes[node];
        if (!MUTANT(LM_WALK_NO_STEPS)) (*steps)++;
        if (nd->count > 0) {
            for (uint32_t i = 0; i < nd->count; i++) {
                uint32_t prim = b->order[nd->left_first + i];
                if (MUTANT(LM_WALK_PRIM_HIT)) { /* filters with its own triangle test */
                    float t = t_max, u, v;
                    if (!accel_prim_hit(&b->store.prims, prim, p, &t, &u, &v, 0,
                                        b->store.prims.sphere_count > 0)) continue;
                }
                t_max = visit(ctx, b->store.scene_id[prim], t_max);
                if (t_max < p->t_near) return ACCEL_OK; /* an occlusion ray hit */
            }
        } else {
            uint32_t l = nd->left_first, r = l + 1;
            float t_box = MUTANT(LM_WALK_NO_SHRINK) ? p->t_far : t_max;
            int hl = slab_padded(&b->nodes[l], p, pad, t_box, &e0);
            int hr = slab_padded(&b->nodes[r], p, pad, t_box, &e1);
            if (hl && hr) {
                int swap = e1 < e0;
                stack[sp] = swap ? l : r, entry[sp++] = swap ? e0 : e1;
                node = swap ? r : l;
                continue;
            }
            if (hl || hr) {
                node = hl ? l : r;
                continue;
            }
        }
        while (sp > 0 && !MUTANT(LM_WALK_NO_SHRINK) && !box3_entry_before(entry[sp - 1], t_max))
            sp--;
        if (sp == 0) return ACCEL_OK;
        node = stack[--sp];
    }
}

/* Optional step 7: the top level (lab/top.h). Every instance's object ray
 * from the world ray by the inverse transform, in double, not
 * renormalized, so that t is the world ray's t. */
void lab_top_lab_solution(const lab_top *top, const accel_ray *ray, accel_hit *hit)
{
    *hit = accel_hit_miss();
    const double o[3] = {ray->ox, ray->oy, ray->oz}, d[3] = {ray->dx, ray->dy, ray->dz};
    for (uint32_t k = 0; k < top->instance_count; k++) {
        const accel_instance *in = &top->instances[k];
        const double *m = MUTANT(LM_TOP_FORWARD) ? in->xform : in->inverse;
        double oo[3], od[3];
        for (int r = 0; r < 3; r++) {
            oo[r] = m[4 * r] * o[0] + m[4 * r + 1] * o[1] + m[4 * r + 2] * o[2] + m[4 * r + 3];
            od[r] = m[4 * r] * d[0] + m[4 * r + 1] * d[1] + m[4 * r + 2] * d[2];
            if (MUTANT(LM_TOP_DIR_MOVED)) od[r] += m[4 * r + 3];
        }
        if (MUTANT(LM_TOP_NORMALIZE)) {
            double len = sqrt(od[0] * od[0] + od[1] * od[1] + od[2] * od[2]);
            for (int r = 0; r < 3; r++) od[r] /= len;
        }
        accel_ray obj = {(float)oo[0], (float)oo[1], (float)oo[2], ray->t_near,
                         (float)od[0], (float)od[1], (float)od[2],
                         hit->prim != ACCEL_MISS ? hit->t : ray->t_far};
        accel_hit h;
        top->kind->intersect(top->mesh_accel[in->mesh], &obj, &h, 1, NULL);
        if (h.prim != ACCEL_MISS && (hit->prim == ACCEL_MISS || h.t < hit->t)) {
            *hit = h;
            hit->prim = in->base + h.prim;
            if (MUTANT(LM_TOP_FIRST_INSTANCE)) return;
        }
    }
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

/* Does ray i of the packet enter node nd before its closest hit? */
static inline __attribute__((always_inline)) int
lane_enters(const lab_node *nd, const accel_ray_prep *p, float t)
{
    float entry;
    if (MUTANT(LM_PACKET_CULL_LT)) /* its own cull, unpadded */
        return box3_slab(nd->bmin, nd->bmax, p->org, p->inv_dir, p->neg, p->t_near, INFINITY,
                         &entry) && entry < t;
    return box3_slab(nd->bmin, nd->bmax, p->org, p->inv_dir, p->neg, p->t_near, t, &entry);
}

/* The walk for the whole packet: a stack of (node, first active lane);
 * a node is entered when some lane from `first` on hits its box (the first
 * such lane is the new `first`: the lanes before it miss the node, so they
 * miss its children too); a leaf is tested with every active lane from
 * `first` on. Children are ordered by the first lane's direction. */
static inline __attribute__((always_inline)) void
trace_packet(const lab_bvh *b, const accel_ray_prep *p, const int *valid, uint32_t n,
             int any_hit, int naive, int spheres, uint32_t *hit_local, float *t, float *u,
             float *v, uint32_t *steps, uint32_t *boxes, uint32_t *prims, uint32_t *packet_steps)
{
    if (MUTANT(LM_PACKET_FAKE)) { /* single rays, and a packet count of its own */
        for (uint32_t i = 0; i < n; i++)
            hit_local[i] = valid[i] ? trace_ray(b, &p[i], any_hit, naive, spheres, &t[i], &u[i],
                                                &v[i], &steps[i], &boxes[i], &prims[i])
                                    : ACCEL_MISS;
        *packet_steps += 1;
        return;
    }
    int active[64];
    uint32_t live = 0;
    /* Mutant LM_PACKET_UNINIT: the lanes' hits never set to a miss; what an
     * uninitialized array holds is, typically, the previous packet's (here
     * kept on purpose, so that the mistake is deterministic). */
    static _Thread_local uint32_t stale[64];
    for (uint32_t i = 0; i < n; i++) {
        hit_local[i] = MUTANT(LM_PACKET_UNINIT) ? stale[i] : ACCEL_MISS;
        live += active[i] = valid[i];
    }
    uint32_t stack[LAB_MAX_DEPTH], first_stack[LAB_MAX_DEPTH], sp = 0, node = 0, first = 0;
    for (;;) {
        const lab_node *nd = &b->nodes[node];
        uint32_t f = first;
        while (f < n && !(active[f] && (boxes[f]++, lane_enters(nd, &p[f], t[f])))) {
            if (MUTANT(LM_PACKET_FIRST_ONLY) && active[f]) f = n;
            else f++;
        }
        if (f < n) {
            if (MUTANT(LM_PACKET_PER_LANE)) {
                for (uint32_t i = f; i < n; i++) *packet_steps += (uint32_t)active[i];
            } else if (!MUTANT(LM_PACKET_NO_COUNT)) {
                (*packet_steps)++;
            }
            steps[f]++;
            if (nd->count == 0) {
                const lab_node *l = &b->nodes[nd->left_first], *r = l + 1;
                float d = (r->bmin[0] + r->bmax[0] - l->bmin[0] - l->bmax[0]) * p[f].dir.x +
                          (r->bmin[1] + r->bmax[1] - l->bmin[1] - l->bmax[1]) * p[f].dir.y +
                          (r->bmin[2] + r->bmax[2] - l->bmin[2] - l->bmax[2]) * p[f].dir.z;
                uint32_t near = d >= 0.0f ? nd->left_first : nd->left_first + 1;
                stack[sp] = near == nd->left_first ? near + 1 : nd->left_first;
                first_stack[sp++] = f;
                node = near, first = f;
                continue;
            }
            for (uint32_t i = f; i < n; i++) {
                if (!active[i]) continue;
                for (uint32_t k = 0; k < nd->count; k++) {
                    uint32_t prim = b->order[nd->left_first + k];
                    prims[i]++;
                    if (accel_prim_hit(&b->store.prims, prim, &p[i], &t[i], &u[i], &v[i], naive,
                                       spheres)) {
                        hit_local[i] = prim;
                        if (any_hit) break;
                    }
                }
                if (any_hit && hit_local[i] != ACCEL_MISS) active[i] = 0, live--;
            }
            if (live == 0) break; /* every shadow ray found its occluder */
        }
        if (sp == 0) break;
        node = stack[--sp], first = first_stack[sp];
    }
    if (MUTANT(LM_PACKET_UNINIT)) memcpy(stale, hit_local, n * sizeof *hit_local);
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

const accel_kind accel_kind_lab_solution = {
    .name = "lab_solution",
    .summary = "the lab's reference solution (tests/lab_solution.c)",
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
