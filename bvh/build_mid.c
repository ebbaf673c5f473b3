/*
 * build_mid.c - the lab's starting builders (build=mid, build=median).
 *
 * mid: split the node's centroid bounds in the middle of their longest axis
 *      (pbrt-v3's SplitMethod::Middle); fast, blind to where the geometry is.
 * median: put half of the primitives on each side along that axis (pbrt's
 *      EqualCounts): a balanced tree of depth log2(N), however the
 *      primitives are spread.
 *
 * Both still stop with the SAH termination rule (a leaf when the split's
 * SAH cost is no better, up to the leaf size bound), so that ct, ci and leaf
 * mean the same for every builder.
 */
#include "split_common.h"

static void median_split(bvh_build_ctx *ctx, const bvh_task *t, int threads, bvh_split *out)
{
    (void)threads;
    bvh_split_median(ctx, t, out);
    if (!bvh_split_pays(ctx, t, bvh_split_sum(out, t->count))) out->left_count = 0;
}

static void mid_split(bvh_build_ctx *ctx, const bvh_task *t, int threads, bvh_split *out)
{
    (void)threads;
    out->left_count = 0;
    int axis = v3_max_axis(box3_extent(t->cbounds));
    float lo = v3_get(t->cbounds.min, axis), hi = v3_get(t->cbounds.max, axis);
    if (bvh_task_forced(t) || !(hi > lo)) {
        median_split(ctx, t, threads, out);
        return;
    }
    float mid = 0.5f * lo + 0.5f * hi;
    bvh_ref *r = ctx->refs;
    uint32_t i = t->first, j = t->first + t->count; /* [i, j) unclassified */
    box3 lb = box3_empty(), rb = box3_empty(), lc = box3_empty(), rc = box3_empty();
    while (i < j) {
        if (bvh_ref_centroid(&r[i], axis) < mid) {
            lb = box3_union(lb, bvh_ref_box(&r[i]));
            lc = box3_grow(lc, bvh_ref_center(&r[i]));
            i++;
        } else {
            j--;
            bvh_ref tmp = r[i];
            r[i] = r[j];
            r[j] = tmp;
            rb = box3_union(rb, bvh_ref_box(&r[j]));
            rc = box3_grow(rc, bvh_ref_center(&r[j]));
        }
    }
    uint32_t nl = i - t->first;
    if (nl == 0 || nl == t->count) { /* the middle rounded onto an end */
        median_split(ctx, t, threads, out);
        return;
    }
    out->left_count = nl;
    out->left = lb, out->right = rb, out->left_c = lc, out->right_c = rc;
    if (!bvh_split_pays(ctx, t, bvh_split_sum(out, t->count))) out->left_count = 0;
}

int bvh_build_mid(bvh_build_ctx *ctx, accel_error *err)
{
    (void)err;
    ctx->split = mid_split;
    bvh_build_tree(ctx);
    return 0;
}

int bvh_build_median(bvh_build_ctx *ctx, accel_error *err)
{
    (void)err;
    ctx->split = median_split;
    bvh_build_tree(ctx);
    return 0;
}
