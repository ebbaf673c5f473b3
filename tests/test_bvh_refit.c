/*
 * test_bvh_refit.c - the `bvh` kind's update (bvh/bvh_refit.c): a tree
 * built at frame 0 of the animated scene and refit frame by frame answers
 * exactly what the oracle answers on the new frame, for the binary and
 * wide trees, packets and the spatial-split builder; a refit that leaves
 * the boxes stale is caught; other primitive counts are refused.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bvh/bvh.h"
#include "bvh/wide/node.h"
#include "rays/rays.h"
#include "support.h"
#include "test.h"
#include "test_instanced.h"

#define ANIM "animated:instances=8,detail=2"

static int make_frame(int frame, accel_scene *s)
{
    char spec[128];
    snprintf(spec, sizeof spec, ANIM ",frame=%d", frame);
    accel_error err = {0};
    int rc = scene_create(spec, s, &err);
    CHECKF(rc == 0, "%s: %s", spec, err.msg);
    return rc == 0;
}

/* Camera rays (64-ray tiles, so packets are exercised) and the stiff rays
 * of test_instanced.c (at vertices and edge midpoints, shadow rays). */
static void frame_rays(const accel_scene *s, ray_list *l)
{
    inst_make_rays(s, l);
    rays_set p;
    accel_error err = {0};
    if (rays_primary(&s->camera, 48, 48, &p, &err) != 0) {
        CHECKF(0, "%s", err.msg);
        return;
    }
    accel_ray *r = realloc(l->r, (l->n + p.count) * sizeof *r);
    CHECK(r != NULL);
    if (r) {
        memcpy(r + l->n, p.rays, p.count * sizeof *r);
        l->r = r;
        l->n += p.count;
    }
    rays_free(&p);
}

/* Bad rays (holes, false hits, disagreements, occlusion mismatches) of a
 * built structure on scene s against the reference; *holes gets the holes. */
static size_t bad_rays(const accel_kind *k, const void *a, const accel_scene *s, size_t *holes)
{
    ray_list l = {0};
    frame_rays(s, &l);
    accel_hit *ref = test_oracle_hits(s, l.r, l.n, TEST_ORACLE_REFERENCE);
    size_t bad = l.n ? l.n : 1;
    if (ref) {
        test_diff d = test_trace_diff(s, k, a, l.r, l.n, ref, 1, NULL, NULL);
        bad = test_diff_bad(&d);
        if (holes) *holes = d.holes;
    }
    CHECK(l.n > 1000);
    free(ref);
    free(l.r);
    return bad;
}

static const char *const refit_specs[] = {
    "bvh", "bvh:width=4", "bvh:width=8", "bvh:width=8,traverse=packet", "bvh:build=sbvh",
    "bvh:traverse=packet", "bvh:pairs=split,first=left", "bvh:width=8,quant=1",
    /* issue 50: bfs keeps the refit, mixed rebuilds, any_order's perm bits follow the refit */
    "bvh:width=8,layout=bfs", "bvh:width=8,layout=mixed", "bvh:width=8,any_order=leaf", NULL,
};

TEST(bvh_refit_frames_match_oracle)
{
    for (const char *const *spec = refit_specs; *spec; spec++) {
        accel_scene s;
        if (!make_frame(0, &s)) return;
        const accel_kind *k;
        void *a = NULL;
        accel_build_stats st;
        accel_error err = {0};
        int rc = accel_build_spec(*spec, &s, 1, &k, &a, &st, &err);
        scene_free(&s); /* the tree copies what it traverses */
        CHECKF(rc == 0, "%s: %s", *spec, err.msg);
        if (rc) continue;
        CHECK(k->update != NULL);
        for (int f = 1; f <= 20; f++) {
            if (!make_frame(f, &s)) break;
            accel_update_stats us;
            rc = k->update(a, &s, 1, &us, &err);
            CHECKF(rc == 0, "%s frame %d: %s", *spec, f, err.msg);
            /* quantized nodes keep no float boxes, layout=mixed no refit order: rebuilt instead */
            int quant = strstr(*spec, "quant=1") != NULL || strstr(*spec, "layout=mixed") != NULL;
            CHECKF(us.meshes_refit == (uint32_t)!quant && us.meshes_rebuilt == (uint32_t)quant,
                   "%s frame %d: refit %u rebuilt %u",
                   *spec, f, us.meshes_refit, us.meshes_rebuilt);
            if (f == 1 || f == 7 || f == 20) {
                size_t bad = bad_rays(k, a, &s, NULL);
                CHECKF(bad == 0, "%s refit to frame %d: %zu bad rays", *spec, f, bad);
            }
            scene_free(&s);
        }
        k->destroy(a);
    }
}

/* The refit without its box pass: the primitives moved out of their old
 * boxes, so rays miss them. Shows the test above can fail. */
TEST(bvh_refit_stale_boxes_show_holes)
{
    const char *const specs[] = {"bvh", "bvh:width=8,traverse=packet", "bvh:width=8,layout=mixed"};
    for (int i = 0; i < 3; i++) {
        accel_scene s0, s1;
        if (!make_frame(0, &s0)) return;
        if (!make_frame(20, &s1)) return;
        const accel_kind *k;
        void *a = NULL;
        accel_build_stats st;
        accel_error err = {0};
        CHECKF(accel_build_spec(specs[i], &s0, 1, &k, &a, &st, &err) == 0, "%s", err.msg);
        if (a) {
            bvh_refit_stale(a, &s1);
            size_t holes = 0, bad = bad_rays(k, a, &s1, &holes);
            CHECKF(holes > 100 && bad >= holes, "%s, stale boxes: %zu holes, %zu bad", specs[i],
                   holes, bad);
            /* The real update repairs it. */
            accel_update_stats us;
            CHECK(k->update(a, &s1, 1, &us, &err) == 0);
            CHECK(bad_rays(k, a, &s1, NULL) == 0);
            k->destroy(a);
        }
        scene_free(&s0);
        scene_free(&s1);
    }
}

/* refit = 0 rebuilds; another primitive count is refused, and the tree
 * still answers the scene it was built on. */
TEST(bvh_refit_rebuild_and_refusal)
{
    accel_scene s0, s1, other;
    accel_error err = {0};
    if (!make_frame(0, &s0) || !make_frame(9, &s1)) return;
    CHECK(scene_create("animated:instances=9,detail=2", &other, &err) == 0);
    CHECK(other.tri_count != s0.tri_count);
    const accel_kind *k;
    void *a = NULL;
    accel_build_stats st;
    CHECKF(accel_build_spec("bvh:width=4", &s0, 1, &k, &a, &st, &err) == 0, "%s", err.msg);
    if (a) {
        accel_update_stats us;
        err.msg[0] = 0;
        int rc = k->update(a, &other, 1, &us, &err);
        CHECK(rc == ACCEL_ERR_SPEC && err.code == ACCEL_ERR_SPEC);
        CHECKF(strstr(err.msg, "same primitive counts") != NULL, "message: %s", err.msg);
        CHECK(bad_rays(k, a, &s0, NULL) == 0);
        CHECK(k->update(a, &other, 0, &us, &err) == ACCEL_ERR_SPEC);
        CHECKF(k->update(a, &s1, 0, &us, &err) == 0, "%s", err.msg);
        CHECK(us.meshes_rebuilt == 1 && us.meshes_refit == 0);
        CHECK(bad_rays(k, a, &s1, NULL) == 0);
        k->destroy(a);
    }
    scene_free(&s0);
    scene_free(&s1);
    scene_free(&other);
}

/* A copy of everything a tree holds that a refit rewrites: the binary
 * nodes and slots, or the wide nodes (boxes, children, octant orders) and
 * leaf blocks. */
static unsigned char *tree_bytes(const void *a, size_t *n)
{
    const bvh *b = a;
    size_t parts[2][2];
    const void *src[2];
    if (b->wide) {
        const bvh_wide *w = b->wide;
        src[0] = w->nodes, parts[0][0] = w->node_count, parts[0][1] = w->width == 8 ? 256 : 128;
        src[1] = w->blocks, parts[1][0] = w->block_count, parts[1][1] = w->block == 8 ? 320 : 160;
    } else {
        src[0] = b->nodes, parts[0][0] = b->node_count, parts[0][1] = sizeof(bvh_node);
        src[1] = b->prim_data, parts[1][0] = b->prim_count, parts[1][1] = BVH_SLOT_FLOATS * sizeof(float);
    }
    *n = parts[0][0] * parts[0][1] + parts[1][0] * parts[1][1];
    unsigned char *out = malloc(*n ? *n : 1);
    if (!out) return NULL;
    memcpy(out, src[0], parts[0][0] * parts[0][1]);
    memcpy(out + parts[0][0] * parts[0][1], src[1], parts[1][0] * parts[1][1]);
    return out;
}

/* Refit boxes are the build's boxes: a tree refit to frame 20 and back to
 * frame 0 holds, byte for byte, what the build at frame 0 made (binned
 * builds; sbvh's clipped boxes are the exception bvh_refit.c names). */
TEST(bvh_refit_back_to_frame0_is_the_build)
{
    const char *const specs[] = {"bvh", "bvh:width=4", "bvh:width=8,traverse=packet",
                                 "bvh:width=8,block=4", "bvh:build=sah,leaf=1"};
    accel_scene s0, s20;
    if (!make_frame(0, &s0) || !make_frame(20, &s20)) return;
    for (int i = 0; i < 5; i++) {
        const accel_kind *k;
        void *a = NULL;
        accel_build_stats st;
        accel_error err = {0};
        CHECKF(accel_build_spec(specs[i], &s0, 1, &k, &a, &st, &err) == 0, "%s", err.msg);
        if (!a) continue;
        size_t n0, n1, n2;
        unsigned char *built = tree_bytes(a, &n0);
        accel_update_stats us;
        CHECK(k->update(a, &s20, 1, &us, &err) == 0);
        unsigned char *moved = tree_bytes(a, &n1);
        CHECK(k->update(a, &s0, 1, &us, &err) == 0);
        unsigned char *back = tree_bytes(a, &n2);
        CHECK(built && moved && back && n0 == n1 && n0 == n2);
        if (built && moved && back && n0 == n2) {
            CHECKF(memcmp(built, moved, n0) != 0, "%s: frame 20 changed nothing", specs[i]);
            CHECKF(memcmp(built, back, n0) == 0, "%s: refit to frame 0 differs from the build",
                   specs[i]);
        }
        free(built), free(moved), free(back);
        k->destroy(a);
    }
    scene_free(&s0);
    scene_free(&s20);
}

/* Wide nodes whose octant orders (bvh/wide/node.h) do not rank the used
 * children by their box centres along each octant's diagonal. */
static uint32_t misordered_nodes(const void *a)
{
    const bvh_wide *w = ((const bvh *)a)->wide;
    const int wd = w->width;
    const size_t floats = (wd == 8 ? 256 : 128) / sizeof(float);
    uint32_t bad = 0;
    for (uint32_t i = 0; i < w->node_count; i++) {
        const float *rows = (const float *)w->nodes + floats * i;
        const uint32_t *child = (const uint32_t *)(rows + 6 * wd), *perm = child + wd;
        int k = 0;
        while (k < wd && child[k] != WIDE_EMPTY) k++;
        int ok = 1;
        for (int o = 0; o < 8; o++) {
            int base = o < 4 ? o : 7 - o;
            float prev = -INFINITY;
            for (int r = 0; r < k; r++) {
                int c = (int)(perm[r] >> (3 * o) & 7);
                float cx = 0.5f * rows[0 * wd + c] + 0.5f * rows[1 * wd + c];
                float cy = 0.5f * rows[2 * wd + c] + 0.5f * rows[3 * wd + c];
                float cz = 0.5f * rows[4 * wd + c] + 0.5f * rows[5 * wd + c];
                float key = (base & 1 ? -cx : cx) + (base & 2 ? -cy : cy) + cz;
                if (o >= 4) key = -key;
                if (c >= k || key < prev) ok = 0;
                prev = key;
            }
        }
        bad += !ok;
    }
    return bad;
}

/* After a refit the octant orders follow the moved boxes. */
TEST(bvh_refit_wide_octant_orders)
{
    accel_scene s0, s20;
    if (!make_frame(0, &s0) || !make_frame(20, &s20)) return;
    const accel_kind *k;
    void *a = NULL;
    accel_build_stats st;
    accel_error err = {0};
    CHECKF(accel_build_spec("bvh:width=8", &s0, 1, &k, &a, &st, &err) == 0, "%s", err.msg);
    if (a) {
        CHECK(misordered_nodes(a) == 0);
        accel_update_stats us;
        CHECK(k->update(a, &s20, 1, &us, &err) == 0);
        uint32_t bad = misordered_nodes(a);
        CHECKF(bad == 0, "%u of %u nodes misordered after the refit", bad,
               ((const bvh *)a)->wide->node_count);
        k->destroy(a);
    }
    scene_free(&s0);
    scene_free(&s20);
}

/* A 10 x 10 sheet of triangles in z = 0 and 5 spheres above it, moved by
 * `shift` along x (spheres by 2 * shift: they move relative to the
 * sheet); triangle `flat` (if < 100) collapsed onto a line. */
static int sheet_scene(float shift, uint32_t flat, accel_scene *s)
{
    scene_builder b = {0};
    accel_error err = {0};
    for (uint32_t i = 0; i < 100; i++) {
        vec3 p = v3(shift + (float)(i % 10), (float)(i / 10), 0.0f);
        vec3 q = v3_add(p, v3(0.9f, 0, 0)), r = v3_add(p, v3(0, 0.9f, 0));
        if (i == flat) r = v3_add(p, v3(0.45f, 0, 0));
        test_add_tri(&b, p, q, r);
    }
    for (int i = 0; i < 5; i++)
        CHECK(scene_builder_add_sphere(&b, v3(2 * shift + 2.0f * (float)i, 5.0f, 2.0f), 0.7f, &err) == 0);
    return test_finish(&b, "sheet", s);
}

/* Rays straight down at every triangle's centroid and every sphere's centre. */
static size_t sheet_bad(const accel_kind *k, const void *a, const accel_scene *s)
{
    accel_ray r[105];
    size_t n = 0;
    for (uint32_t i = 0; i < s->tri_count + s->sphere_count; i++) {
        vec3 c = accel_prim_centroid(s, i);
        memset(&r[n], 0, sizeof r[n]);
        r[n].ox = c.x, r[n].oy = c.y, r[n].oz = 10.0f;
        r[n].dx = 0.0f, r[n].dy = 0.0f, r[n].dz = -1.0f;
        r[n].t_near = 0.0f;
        r[n].t_far = INFINITY;
        n++;
    }
    accel_hit *ref = test_oracle_hits(s, r, n, TEST_ORACLE_REFERENCE);
    size_t bad = n;
    if (ref) {
        test_diff d = test_trace_diff(s, k, a, r, n, ref, 1, NULL, NULL);
        bad = test_diff_bad(&d);
    }
    free(ref);
    return bad;
}

/* Moved spheres are refit too; a triangle that stops (or starts) being
 * degenerate changes the set of traced primitives, so update rebuilds. */
TEST(bvh_refit_spheres_and_degenerate_changes)
{
    const char *const specs[] = {"bvh", "bvh:width=4", "bvh:width=8,traverse=packet"};
    for (int i = 0; i < 3; i++) {
        accel_scene a0, a1, b1, c1;
        if (!sheet_scene(0.0f, 37, &a0) || !sheet_scene(0.3f, 37, &a1) ||
            !sheet_scene(0.3f, 100, &b1) || !sheet_scene(2.0f, 37, &c1))
            return;
        CHECK(a0.live_count == 104 && b1.live_count == 105);
        const accel_kind *k;
        void *a = NULL;
        accel_build_stats st;
        accel_error err = {0};
        CHECKF(accel_build_spec(specs[i], &a0, 1, &k, &a, &st, &err) == 0, "%s", err.msg);
        if (!a) continue;
        accel_update_stats us;
        CHECK(k->update(a, &a1, 1, &us, &err) == 0 && us.meshes_refit == 1);
        CHECKF(sheet_bad(k, a, &a1) == 0, "%s: moved spheres", specs[i]);
        bvh_refit_stale(a, &c1); /* stale boxes: the spheres are missed */
        CHECKF(sheet_bad(k, a, &c1) > 0, "%s: stale boxes not caught", specs[i]);
        CHECK(k->update(a, &b1, 1, &us, &err) == 0);
        CHECKF(us.meshes_rebuilt == 1 && us.meshes_refit == 0, "%s: refit %u rebuilt %u", specs[i],
               us.meshes_refit, us.meshes_rebuilt);
        CHECKF(sheet_bad(k, a, &b1) == 0, "%s: triangle 37 no longer degenerate", specs[i]);
        CHECK(k->update(a, &c1, 1, &us, &err) == 0 && us.meshes_rebuilt == 1);
        CHECKF(sheet_bad(k, a, &c1) == 0, "%s: triangle 37 degenerate again", specs[i]);
        k->destroy(a);
        scene_free(&a0), scene_free(&a1), scene_free(&b1), scene_free(&c1);
    }
}
