/*
 * build_sbvh.c - the split BVH (build=sbvh): binned SAH with spatial splits.
 *
 * Stich, Friedrich and Dietrich, "Spatial Splits in Bounding Volume
 * Hierarchies", High-Performance Graphics 2009. An object split puts every
 * reference wholly on one side; long thin triangles then give children
 * that overlap, and a ray through the overlap visits both. A spatial split
 * cuts space at a plane instead: a reference that straddles the plane goes
 * to both children, each with the box of its part on that side ("chopped"
 * boxes), so the children do not overlap at all. Per node:
 *
 *  1. the best binned object split (Wald 2007: `bins` centroid bins on each
 *     axis, one sweep from each side);
 *  2. only where that split's children overlap by more than `alpha` times
 *     the root's area (Stich et al., section 4.5; alpha = 1e-5 by default),
 *     the best binned spatial split: `bins` equal slabs of the node's box on
 *     each axis; every reference is chopped into the slabs it spans (entry
 *     count in its first slab, exit count in its last), one sweep gives the
 *     cost of each plane;
 *  3. reference unsplitting (section 4.4): a straddling reference goes to
 *     one side whole when that costs less than putting it in both;
 *  4. the cheaper split is made, or a leaf by the SAH termination rule that
 *     every builder shares (split_common.c).
 *
 * Exactness. Triangles are still tested whole, with the shared exact test,
 * so a triangle in several leaves answers the same everywhere; the one
 * thing that must hold is that every point of a triangle lies in the box of
 * some leaf that holds it. A chopped box is the box of the triangle's part
 * on one side of the plane, computed in double and rounded outward to float
 * (min down, max up), padded by a bound on the double rounding of the
 * edge/plane intersection, and intersected with the reference's previous
 * box (which already contains that part): build_sbvh_chop.c. Spheres are
 * chopped as boxes.
 *
 * Budget. The references live in one array of N(1 + split_budget) slots.
 * A task owns a run of that array (its references, then free slots); a
 * split gives each child its references plus a share of the free slots in
 * proportion to its count. A spatial split whose duplicates exceed the
 * task's free slots is not considered, so the total never exceeds the
 * budget, and nothing is reallocated during the build. Node slots follow
 * the array: a task of capacity C owns 2(C - 1) node slots, so the layout
 * is that of the other builders and the driver's compaction applies.
 *
 * Depth. A split never gives a child more references than its parent, so
 * the shared depth rule (object median once level + log2(count) reaches
 * BVH_MAX_DEPTH) still bounds the depth; the budget bounds the duplicates.
 * Together they end every input, flat, zero-sized or huge.
 *
 * The build runs on one thread (the result does not depend on `threads`).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "split_common.h"

#define SBVH_BINS_MAX 256

typedef struct {
    box3 box;
    uint32_t count;   /* object bins: references; spatial bins: entries */
    uint32_t exits;   /* spatial bins: references whose last slab this is */
} sbvh_bin;

typedef struct {
    bvh_build_ctx *ctx;
    uint32_t cap;        /* slots of ctx->refs */
    bvh_ref *tmp;        /* scratch: the right part of a task while it is placed */
    uint8_t *side;       /* scratch: where each reference of a spatial split goes */
    double root_area;    /* half area of the root box */
    double alpha;
    float delta;         /* bvh_box_delta: the pad of every stored box */
    int bins;
    sbvh_bin bin[3][SBVH_BINS_MAX];
    double right_area[SBVH_BINS_MAX];
} sbvh_ctx;

/* A task: the driver's task plus its capacity (references then free slots
 * at refs[first, first + cap)). */
typedef struct {
    bvh_task t;
    uint32_t cap;
} sbvh_task;

/* A candidate split: object (spatial = 0: bin <= at goes left by centroid)
 * or spatial (slab <= at goes left, plane between slab at and at + 1). */
typedef struct {
    double cost; /* A_L*N_L + A_R*N_R, half areas */
    int axis, at, spatial;
    box3 left, right;
    uint32_t nl, nr;
} sbvh_choice;

/* ---- boxes --------------------------------------------------------------------- */

static inline int box_valid(box3 b)
{
    return b.min.x <= b.max.x && b.min.y <= b.max.y && b.min.z <= b.max.z;
}

static inline box3 box_intersect(box3 a, box3 b)
{
    a.min = v3_max(a.min, b.min);
    a.max = v3_min(a.max, b.max);
    return a;
}

/* The two parts of a reference's box at a plane: the triangle's parts, or
 * for a sphere the box's own halves (the sphere's part of either side lies
 * in it). Empty parts come back with min > max. */
static void chop_ref(const sbvh_ctx *x, const bvh_ref *ref, int axis, double plane, box3 *left,
                     box3 *right)
{
    const accel_scene *s = x->ctx->scene;
    box3 box = bvh_ref_box(ref);
    if (ref->prim < s->tri_count) {
        bvh_sbvh_chop(s->tris + 9 * (size_t)ref->prim, box, axis, plane, 1, left, right);
        /* A part's box is grown like every stored box (split_common.h),
         * inside the reference's own (grown) box. */
        if (box_valid(*left)) *left = box_intersect(box3_hit_pad(*left, x->delta), box);
        if (box_valid(*right)) *right = box_intersect(box3_hit_pad(*right, x->delta), box);
        return;
    }
    bvh_sbvh_chop_box(box, axis, plane, left, right);
}

/* ---- binning ------------------------------------------------------------------ */

static inline int bin_of(double v, double lo, double scale, int bins)
{
    double f = (v - lo) * scale;
    if (!(f > 0.0)) return 0; /* also NaN */
    return f >= bins - 1 ? bins - 1 : (int)f;
}

/* The object split: centroids binned on each axis of positive extent. */
static void object_split(sbvh_ctx *x, const bvh_task *t, box3 cb, sbvh_choice *best)
{
    const bvh_ref *refs = x->ctx->refs + t->first;
    const int K = x->bins;
    for (int a = 0; a < 3; a++) {
        double lo = v3_get(cb.min, a), ext = (double)v3_get(cb.max, a) - lo;
        double scale = K / ext;
        if (!(ext > 0.0) || !isfinite(scale)) continue;
        sbvh_bin *bin = x->bin[a];
        for (int i = 0; i < K; i++) bin[i].box = box3_empty(), bin[i].count = 0;
        for (uint32_t i = 0; i < t->count; i++) {
            int k = bin_of(bvh_ref_centroid(&refs[i], a), lo, scale, K);
            bin[k].box = box3_union(bin[k].box, bvh_ref_box(&refs[i]));
            bin[k].count++;
        }
        box3 acc = box3_empty();
        for (int i = K - 1; i >= 1; i--) {
            acc = box3_union(acc, bin[i].box);
            x->right_area[i] = bvh_half_area(acc);
        }
        acc = box3_empty();
        uint32_t nl = 0;
        for (int i = 0; i < K - 1; i++) {
            acc = box3_union(acc, bin[i].box);
            nl += bin[i].count;
            if (nl == 0 || nl == t->count) continue;
            double cost = bvh_half_area(acc) * nl + x->right_area[i + 1] * (t->count - nl);
            if (cost < best->cost) {
                best->cost = cost, best->axis = a, best->at = i, best->spatial = 0;
                best->nl = nl, best->nr = t->count - nl;
            }
        }
    }
    if (best->at < 0) return;
    best->left = best->right = box3_empty();
    for (int i = 0; i < K; i++) {
        box3 *side = i <= best->at ? &best->left : &best->right;
        *side = box3_union(*side, x->bin[best->axis][i].box);
    }
}

/* The slab geometry of a spatial split on one axis of the node's box. */
typedef struct {
    double lo, width, scale;
} slabs;

static inline double slab_plane(const slabs *s, int i) { return s->lo + s->width * i; }

/* Grows box b by the point where the edge a-b crosses the plane x[axis] = p
 * (a[axis] < p < b[axis]). */
static inline void grow_cross(float *lo, float *hi, const float *a, const float *b, int axis, float p)
{
    float s = (p - a[axis]) / (b[axis] - a[axis]);
    for (int k = 0; k < 3; k++) {
        float q = k == axis ? p : a[k] + s * (b[k] - a[k]);
        lo[k] = minf(lo[k], q);
        hi[k] = maxf(hi[k], q);
    }
}

/* Grows bins b0..b1 by the boxes of a reference's parts in each slab. This
 * only estimates the split's cost, so it runs in float and rounds to
 * nearest; the split itself chops with bvh_sbvh_chop. With the vertices
 * sorted along the axis, a plane strictly between the first and the last
 * vertex crosses the long edge (first-last) and one of the two others, so
 * a part's box is the crossings on its two planes and the vertices between
 * them, clipped to the reference's box. Spheres: the box's own slices. */
static void bin_pieces(const sbvh_ctx *x, const bvh_ref *r, int a, const slabs *sl, int b0, int b1,
                       sbvh_bin *bin)
{
    const accel_scene *s = x->ctx->scene;
    box3 box = bvh_ref_box(r);
    if (r->prim >= s->tri_count) {
        for (int k = b0; k <= b1; k++) {
            box3 piece = box;
            float lo = k > b0 ? (float)slab_plane(sl, k) : v3_get(box.min, a);
            float hi = k < b1 ? (float)slab_plane(sl, k + 1) : v3_get(box.max, a);
            if (a == 0) piece.min.x = lo, piece.max.x = hi;
            else if (a == 1) piece.min.y = lo, piece.max.y = hi;
            else piece.min.z = lo, piece.max.z = hi;
            if (box_valid(piece)) bin[k].box = box3_union(bin[k].box, piece);
        }
        return;
    }
    const float *t = s->tris + 9 * (size_t)r->prim;
    /* vertices in axis order */
    int i0 = 0, i1 = 1, i2 = 2, tmp;
    if (t[3 * i1 + a] < t[3 * i0 + a]) tmp = i0, i0 = i1, i1 = tmp;
    if (t[3 * i2 + a] < t[3 * i1 + a]) tmp = i1, i1 = i2, i2 = tmp;
    if (t[3 * i1 + a] < t[3 * i0 + a]) tmp = i0, i0 = i1, i1 = tmp;
    const float *v0 = t + 3 * i0, *v1 = t + 3 * i1, *v2 = t + 3 * i2;
    const float *vs[3] = {v0, v1, v2};
    int vb[3];
    for (int i = 0; i < 3; i++) {
        int b = bin_of(vs[i][a], sl->lo, sl->scale, x->bins);
        vb[i] = b < b0 ? b0 : b > b1 ? b1 : b;
    }
    float llo[3] = {INFINITY, INFINITY, INFINITY}, lhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int k = b0; k <= b1; k++) {
        /* the crossings on the slab's lower plane (llo, lhi), then its upper one */
        float lo[3] = {llo[0], llo[1], llo[2]}, hi[3] = {lhi[0], lhi[1], lhi[2]};
        float ulo[3] = {INFINITY, INFINITY, INFINITY}, uhi[3] = {-INFINITY, -INFINITY, -INFINITY};
        if (k < b1) {
            float p = (float)slab_plane(sl, k + 1);
            if (v0[a] < p && p < v2[a]) {
                grow_cross(ulo, uhi, v0, v2, a, p);
                if (p < v1[a])
                    grow_cross(ulo, uhi, v0, v1, a, p);
                else
                    grow_cross(ulo, uhi, v1, v2, a, p);
            }
        }
        for (int c = 0; c < 3; c++) {
            lo[c] = minf(lo[c], ulo[c]), hi[c] = maxf(hi[c], uhi[c]);
            for (int i = 0; i < 3; i++)
                if (vb[i] == k) lo[c] = minf(lo[c], vs[i][c]), hi[c] = maxf(hi[c], vs[i][c]);
            llo[c] = ulo[c], lhi[c] = uhi[c];
        }
        box3 piece = box_intersect((box3){{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}}, box);
        if (box_valid(piece)) bin[k].box = box3_union(bin[k].box, piece);
    }
}

/* The spatial split: each reference chopped into the slabs it spans. Only
 * planes whose duplicates fit the task's free slots are considered. */
static void spatial_split(sbvh_ctx *x, const sbvh_task *st, sbvh_choice *best)
{
    const bvh_task *t = &st->t;
    const bvh_ref *refs = x->ctx->refs + t->first;
    const int K = x->bins;
    const uint32_t free_slots = st->cap - t->count;
    for (int a = 0; a < 3; a++) {
        slabs sl;
        sl.lo = v3_get(t->bounds.min, a);
        double ext = (double)v3_get(t->bounds.max, a) - sl.lo;
        sl.width = ext / K, sl.scale = K / ext;
        if (!(ext > 0.0) || !isfinite(sl.scale) || !isfinite(ext)) continue;
        sbvh_bin *bin = x->bin[a];
        for (int i = 0; i < K; i++) bin[i].box = box3_empty(), bin[i].count = bin[i].exits = 0;
        for (uint32_t i = 0; i < t->count; i++) {
            const bvh_ref *r = &refs[i];
            int b0 = bin_of(r->lo[a], sl.lo, sl.scale, K), b1 = bin_of(r->hi[a], sl.lo, sl.scale, K);
            bin[b0].count++;
            bin[b1].exits++;
            if (b0 == b1)
                bin[b0].box = box3_union(bin[b0].box, bvh_ref_box(r));
            else
                bin_pieces(x, r, a, &sl, b0, b1, bin);
        }
        box3 acc = box3_empty();
        uint32_t nr = 0;
        uint32_t right_count[SBVH_BINS_MAX];
        for (int i = K - 1; i >= 1; i--) {
            acc = box3_union(acc, bin[i].box);
            nr += bin[i].exits;
            x->right_area[i] = bvh_half_area(acc);
            right_count[i] = nr;
        }
        acc = box3_empty();
        uint32_t nl = 0;
        for (int i = 0; i < K - 1; i++) {
            acc = box3_union(acc, bin[i].box);
            nl += bin[i].count;
            uint32_t r = right_count[i + 1];
            if (nl == 0 || r == 0 || nl + r - t->count > free_slots) continue;
            double cost = bvh_half_area(acc) * nl + x->right_area[i + 1] * r;
            if (cost < best->cost) {
                best->cost = cost, best->axis = a, best->at = i, best->spatial = 1;
                best->nl = nl, best->nr = r;
            }
        }
    }
    if (!best->spatial) return;
    best->left = best->right = box3_empty();
    for (int i = 0; i < K; i++) {
        box3 *side = i <= best->at ? &best->left : &best->right;
        *side = box3_union(*side, x->bin[best->axis][i].box);
    }
}

/* ---- placing a split's references ------------------------------------------- */

static inline void set_ref_box(bvh_ref *r, box3 b)
{
    r->lo[0] = b.min.x, r->lo[1] = b.min.y, r->lo[2] = b.min.z;
    r->hi[0] = b.max.x, r->hi[1] = b.max.y, r->hi[2] = b.max.z;
}

/* Makes the two children of task st from its references, of which the
 * left ones are now at refs[first, first + nl) and the right ones in
 * x->tmp[0, nr): the right ones move behind the left child's share of the
 * free slots. Fills the children tasks (bounds included). */
static void place_children(sbvh_ctx *x, const sbvh_task *st, uint32_t nl, uint32_t nr,
                           sbvh_task *l, sbvh_task *r)
{
    const bvh_task *t = &st->t;
    uint32_t free_slots = st->cap - nl - nr;
    uint32_t share = (uint32_t)((uint64_t)free_slots * nl / (nl + nr));
    uint32_t cl = nl + share, cr = st->cap - cl;
    bvh_ref *refs = x->ctx->refs;
    memcpy(refs + t->first + cl, x->tmp, (size_t)nr * sizeof(bvh_ref));
    uint32_t pair = t->region;
    l->cap = cl, r->cap = cr;
    l->t = (bvh_task){pair, t->first, nl, pair + 2, t->level + 1, box3_empty(), box3_empty()};
    r->t = (bvh_task){pair + 1, t->first + cl, nr, pair + 2 + 2 * (cl - 1), t->level + 1,
                      box3_empty(), box3_empty()};
    bvh_refs_bounds(refs, l->t.first, nl, &l->t.bounds, &l->t.cbounds);
    bvh_refs_bounds(refs, r->t.first, nr, &r->t.bounds, &r->t.cbounds);
}

/* Object split (or median, already partitioned: left_count given). */
static void apply_object(sbvh_ctx *x, const sbvh_task *st, const sbvh_choice *c, uint32_t nl,
                         sbvh_task *l, sbvh_task *r)
{
    const bvh_task *t = &st->t;
    bvh_ref *refs = x->ctx->refs + t->first;
    if (c) { /* partition by centroid bin, stable on each side */
        double lo = v3_get(t->cbounds.min, c->axis);
        double scale = x->bins / ((double)v3_get(t->cbounds.max, c->axis) - lo);
        nl = 0;
        uint32_t nr = 0;
        for (uint32_t i = 0; i < t->count; i++) {
            if (bin_of(bvh_ref_centroid(&refs[i], c->axis), lo, scale, x->bins) <= c->at)
                refs[nl++] = refs[i];
            else
                x->tmp[nr++] = refs[i];
        }
    } else {
        memcpy(x->tmp, refs + nl, (size_t)(t->count - nl) * sizeof(bvh_ref));
    }
    place_children(x, st, nl, t->count - nl, l, r);
}

/* Spatial split with reference unsplitting (Stich et al., section 4.4):
 * for a straddling reference, compare the split's cost with the cost of
 * leaving it whole on either side, with the children's boxes and counts
 * updated as references are decided. Returns 0 (and changes nothing) when
 * a side would end up empty. */
static int apply_spatial(sbvh_ctx *x, const sbvh_task *st, const sbvh_choice *c, sbvh_task *l,
                         sbvh_task *r)
{
    const bvh_task *t = &st->t;
    bvh_ref *refs = x->ctx->refs + t->first;
    const int a = c->axis, K = x->bins;
    slabs sl;
    sl.lo = v3_get(t->bounds.min, a);
    double ext = (double)v3_get(t->bounds.max, a) - sl.lo;
    sl.width = ext / K, sl.scale = K / ext;
    double plane = slab_plane(&sl, c->at + 1);
    box3 bl = c->left, br = c->right;
    double nl_est = c->nl, nr_est = c->nr;
    /* A dry run decides every reference, so that a split that would empty
     * a side is refused before anything moves. Sides: 1 left, 2 right, 3 both. */
    uint8_t *side = x->side;
    uint32_t nl = 0, nr = 0;
    for (uint32_t i = 0; i < t->count; i++) {
        const bvh_ref *ref = &refs[i];
        int b0 = bin_of(ref->lo[a], sl.lo, sl.scale, K), b1 = bin_of(ref->hi[a], sl.lo, sl.scale, K);
        int s = b1 <= c->at ? 1 : b0 > c->at ? 2 : 3;
        if (s == 3) {
            box3 pl, pr, box = bvh_ref_box(ref);
            chop_ref(x, ref, a, plane, &pl, &pr);
            if (!box_valid(pl)) {
                s = 2;
            } else if (!box_valid(pr)) {
                s = 1;
            } else {
                double split = bvh_half_area(bl) * nl_est + bvh_half_area(br) * nr_est;
                double to_left = bvh_half_area(box3_union(bl, box)) * nl_est +
                                 bvh_half_area(br) * (nr_est - 1);
                double to_right = bvh_half_area(bl) * (nl_est - 1) +
                                  bvh_half_area(box3_union(br, box)) * nr_est;
                if (to_left < split && to_left <= to_right) {
                    s = 1, bl = box3_union(bl, box), nr_est -= 1;
                } else if (to_right < split) {
                    s = 2, br = box3_union(br, box), nl_est -= 1;
                }
            }
        }
        side[i] = (uint8_t)s;
        nl += s & 1;
        nr += s >> 1;
    }
    if (nl == 0 || nr == 0 || nl + nr > st->cap) return 0;
    uint32_t wl = 0, wr = 0;
    for (uint32_t i = 0; i < t->count; i++) {
        bvh_ref ref = refs[i];
        if (side[i] == 3) {
            box3 pl, pr;
            chop_ref(x, &ref, a, plane, &pl, &pr);
            bvh_ref rr = ref;
            set_ref_box(&ref, pl);
            set_ref_box(&rr, pr);
            x->tmp[wr++] = rr;
            refs[wl++] = ref;
        } else if (side[i] == 1) {
            refs[wl++] = ref;
        } else {
            x->tmp[wr++] = ref;
        }
    }
    place_children(x, st, nl, nr, l, r);
    return 1;
}

/* ---- the recursion ---------------------------------------------------------------- */

static void make_leaf(bvh_node *n, const bvh_task *t)
{
    n->left_first = t->first;
    n->count = t->count;
}

/* Splits one task or makes it a leaf; returns 1 with the children filled. */
static int split_task(sbvh_ctx *x, const sbvh_task *st, sbvh_task *l, sbvh_task *r)
{
    bvh_build_ctx *ctx = x->ctx;
    const bvh_task *t = &st->t;
    bvh_node *node = &ctx->nodes[t->node];
    if (t->count <= 1 || (!bvh_task_forced(t) && bvh_leaf_certain(ctx, t))) {
        make_leaf(node, t);
        return 0;
    }
    int done = 0;
    if (bvh_task_forced(t)) {
        bvh_split s;
        bvh_split_median(ctx, t, &s);
        if (!bvh_split_pays(ctx, t, bvh_split_sum(&s, t->count))) {
            make_leaf(node, t);
            return 0;
        }
        apply_object(x, st, NULL, s.left_count, l, r);
        done = 1;
    }
    if (!done) {
        sbvh_choice obj, c;
        memset(&obj, 0, sizeof obj);
        obj.cost = INFINITY, obj.at = -1;
        object_split(x, t, t->cbounds, &obj);
        c = obj;
        /* Spatial splits only where the object split's children overlap by
         * more than alpha of the root's area (or no object split exists). */
        box3 both = box_intersect(obj.left, obj.right);
        double overlap = obj.at < 0 ? INFINITY : box_valid(both) ? bvh_half_area(both) : 0.0;
        if (st->cap > t->count && overlap > x->alpha * x->root_area) spatial_split(x, st, &c);
        if (c.spatial && bvh_split_pays(ctx, t, c.cost)) done = apply_spatial(x, st, &c, l, r);
        if (!done && obj.at >= 0 && bvh_split_pays(ctx, t, obj.cost)) {
            apply_object(x, st, &obj, 0, l, r);
            done = 1;
        }
        if (!done && t->count > (uint32_t)ctx->opts.max_leaf) {
            /* An oversized task must split; the median always can. */
            bvh_split s;
            bvh_split_median(ctx, t, &s);
            apply_object(x, st, NULL, s.left_count, l, r);
            done = 1;
        }
        if (!done) {
            make_leaf(node, t);
            return 0;
        }
    }
    node->left_first = t->region;
    node->count = 0;
    bvh_node_set_box(&ctx->nodes[t->region], l->t.bounds);
    bvh_node_set_box(&ctx->nodes[t->region + 1], r->t.bounds);
    return 1;
}

/* Moves every leaf's references down to the next free slot, in depth-first
 * order (the order of the runs in the array, so nothing is overwritten
 * before it moves). Returns the references kept. */
static uint32_t compact_refs(bvh_build_ctx *ctx)
{
    uint32_t stack[BVH_MAX_DEPTH + 1];
    int sp = 0;
    uint32_t next = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        bvh_node *n = &ctx->nodes[stack[--sp]];
        if (n->count) {
            assert(n->left_first >= next);
            memmove(ctx->refs + next, ctx->refs + n->left_first, (size_t)n->count * sizeof(bvh_ref));
            n->left_first = next;
            next += n->count;
            continue;
        }
        assert(sp + 2 <= BVH_MAX_DEPTH + 1);
        stack[sp++] = n->left_first + 1;
        stack[sp++] = n->left_first;
    }
    return next;
}

int bvh_build_sbvh(bvh_build_ctx *ctx, accel_error *err)
{
    const uint32_t n = ctx->ref_count;
    double extra = floor(ctx->opts.split_budget * n);
    double capd = n + extra;
    uint32_t cap = capd > 0x7FFFFFFF ? 0x7FFFFFFFu : (uint32_t)capd;
    sbvh_ctx *x = calloc(1, sizeof *x);
    bvh_ref *refs = x ? realloc(ctx->refs, (size_t)cap * sizeof(bvh_ref)) : NULL;
    if (refs) ctx->refs = refs;
    bvh_node *nodes = bvh_alloc_nodes(2 * (size_t)cap);
    if (x) {
        x->tmp = bvh_alloc_array(cap, sizeof(bvh_ref));
        x->side = bvh_alloc_array(cap, 1);
    }
    if (!x || !refs || !nodes || !x->tmp || !x->side) {
        if (x) free(x->tmp), free(x->side);
        free(x);
        free(nodes);
        return accel_fail(err, ACCEL_ERR_NOMEM, "bvh: build=sbvh: out of memory for %u references",
                          cap);
    }
    free(ctx->nodes);
    ctx->nodes = nodes;
    x->ctx = ctx;
    x->cap = cap;
    x->bins = ctx->opts.bins;
    x->alpha = ctx->opts.alpha;
    x->delta = bvh_box_delta(ctx->scene);
    sbvh_task root;
    root.t.node = 0, root.t.first = 0, root.t.count = n, root.t.region = 2, root.t.level = 1;
    root.cap = cap;
    bvh_refs_bounds(ctx->refs, 0, n, &root.t.bounds, &root.t.cbounds);
    bvh_node_set_box(&ctx->nodes[0], root.t.bounds);
    x->root_area = bvh_half_area(root.t.bounds);
    /* Depth-first: at most one pending right sibling per level. */
    sbvh_task stack[BVH_MAX_DEPTH + 1];
    int sp = 0;
    stack[sp++] = root;
    while (sp > 0) {
        sbvh_task t = stack[--sp], l, r;
        if (!split_task(x, &t, &l, &r)) continue;
        assert(t.t.level < BVH_MAX_DEPTH && sp + 2 <= BVH_MAX_DEPTH + 1);
        stack[sp++] = r;
        stack[sp++] = l;
    }
    ctx->ref_count = compact_refs(ctx);
    free(x->tmp);
    free(x->side);
    free(x);
    return 0;
}
