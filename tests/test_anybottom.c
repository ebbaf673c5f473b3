/*
 * test_anybottom.c - every registered kind with a walk (accel.h) as the
 * bottom level of `instanced`, with top=bvh and top=grid, against the
 * oracle on the flattened scene: the built-in multi-mesh scenes (field,
 * animated) and the stiff scenes of test_instanced.c (shared edges, the
 * turned sheet at 1e5, mirrored, scaled and far instances, overlapping
 * ones). Zero holes, false hits, disagreements and occlusion mismatches.
 * The controls show the check can fail: pad=0, and a bottom kind whose
 * walk ignores the pad, both give bad rays on the far scenes; a kind
 * without a walk is refused at build, by name.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "instanced/instanced.h"
#include "lab/check.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"
#include "test_instanced.h"

/* A bvh whose walk forgets the pad: the mistake the pad=0 control makes
 * on purpose, made inside a kind. */
static int nopad_walk(const void *a, const accel_ray *ray, float pad, accel_walk_visit visit,
                      void *ctx, uint32_t *steps)
{
    (void)pad;
    return accel_find_kind("bvh")->walk(a, ray, 0.0f, visit, ctx, steps);
}

typedef struct {
    const char *name;
    char *text; /* scene file text, or NULL for a built-in spec in name */
    int far;    /* the flattening's rounding is visible: the controls must fail */
} case_scene;

static int load(const case_scene *c, accel_scene *s)
{
    if (!c->text) return !test_make_scene(c->name, s);
    accel_error err = {0};
    scene_file_options o = {0, inst_stiff_mesh, NULL};
    int rc = scene_parse_scene(c->name, "", c->text, strlen(c->text), &o, s, &err);
    if (rc) test_fail(__FILE__, __LINE__, "%s: %s", c->name, err.msg);
    return rc;
}

TEST(anybottom_every_kind_exact)
{
    case_scene cases[] = {
        {"field:instances=30,detail=2", NULL, 0},
        {"animated:frame=77,instances=6,detail=2", NULL, 0},
        {"sheet", inst_sheet(8, ""), 0},
        {"sheet_far_turned", inst_sheet(8, "rotate 1 2 3 37 translate 100000 100000 0"), 1},
        {"mirrored_scaled", (char *)inst_scene_mirrored_scaled, 0},
        {"far", (char *)inst_scene_far, 1},
        {"overlap", (char *)inst_scene_overlap, 0},
    };
    /* Every registered kind with a walk at its defaults, and the modes of
     * bvh whose walks differ (binary, 4- and 8-wide). */
    char bottoms[16][64];
    size_t nb = 0;
    for (size_t i = 0; i < accel_kind_count && nb < 12; i++)
        if (accel_kinds[i]->walk) snprintf(bottoms[nb++], 64, "%s:", accel_kinds[i]->name);
    snprintf(bottoms[nb++], 64, "bvh:width=4");
    snprintf(bottoms[nb++], 64, "bvh:width=8;leaf=1");
    snprintf(bottoms[nb++], 64, "bvh:width=8;quant=1"); /* decoded boxes */
    snprintf(bottoms[nb++], 64, "nested_grid:layout=compact"); /* no nodes: the store's walk */
    CHECKF(nb >= 7, "only %zu bottom kinds with a walk", nb);
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        accel_scene s;
        if (load(&cases[c], &s)) continue;
        ray_list l = {0};
        inst_make_rays(&s, &l);
        accel_hit *ref = malloc(l.n * sizeof *ref);
        accel_reference_trace(&s, l.r, ref, l.n, 2);
        for (size_t b = 0; b < nb; b++)
            for (int top = 0; top < 2; top++) {
                char spec[160];
                snprintf(spec, sizeof spec, "instanced:top=%s,bottom=%.63s", top ? "grid" : "bvh",
                         bottoms[b]);
                size_t bad = inst_bad_rays(&s, &l, ref, spec, NULL);
                CHECKF(bad == 0, "%s on %s: %zu bad rays of %zu", spec, cases[c].name, bad, l.n);
            }
        if (cases[c].far) {
            /* The controls: without the pad the far scenes disagree. */
            size_t p0 = inst_bad_rays(&s, &l, ref, "instanced:pad=0,bottom=bvh:", NULL) +
                        inst_bad_rays(&s, &l, ref, "instanced:pad=0,bottom=grid:", NULL);
            const accel_kind *bvh = accel_find_kind("bvh");
            accel_kind broken = *bvh;
            broken.name = "bvh_without_pad";
            broken.walk = nopad_walk;
            void *a = NULL;
            accel_build_stats st;
            accel_error err = {0};
            size_t np = 0;
            if (instanced_build_with_bottom(&s, "", &broken, "", 1, &a, &st, &err) == 0) {
                np = inst_count_bad(&accel_kind_instanced, a, &s, &l, ref, "pad=0 (no pad)",
                                    NULL);
                accel_kind_instanced.destroy(a);
            } else {
                test_fail(__FILE__, __LINE__, "%s", err.msg);
            }
            test_note("%s: %zu rays; pad=0 control %zu bad, walk without the pad %zu bad",
                      cases[c].name, l.n, p0, np);
            CHECKF(p0 > 0, "%s: pad=0 agrees everywhere: the scene tests nothing", cases[c].name);
            CHECKF(np > 0, "%s: a walk without the pad agrees everywhere", cases[c].name);
        }
        free(ref);
        free(l.r);
        scene_free(&s);
    }
    free(cases[2].text);
    free(cases[3].text);
}

TEST(anybottom_refuses_kind_without_walk)
{
    accel_scene s;
    accel_error err = {0};
    if (!test_make_scene("field:instances=3,detail=1", &s)) return;
    const accel_kind *k;
    void *a = NULL;
    accel_build_stats st;
    int rc = accel_build_spec("instanced:bottom=instanced", &s, 1, &k, &a, &st, &err);
    CHECK(rc == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "'instanced' has no walk") != NULL, "message: %s", err.msg);
    rc = accel_build_spec("instanced:bottom=nosuchkind", &s, 1, &k, &a, &st, &err);
    CHECK(rc == ACCEL_ERR_SPEC);
    CHECKF(strstr(err.msg, "nested_grid") != NULL, "the message lists the kinds: %s", err.msg);
    scene_free(&s);
}

TEST(anybottom_update_frames)
{
    /* A walked bottom is rebuilt when its mesh moves: exact on every frame. */
    accel_scene f0, f1;
    accel_error err = {0};
    if (!test_make_scene("animated:frame=0,instances=6,detail=2", &f0)) return;
    if (!test_make_scene("animated:frame=9,instances=6,detail=2", &f1)) {
        scene_free(&f0);
        return;
    }
    const accel_kind *k;
    void *a = NULL;
    accel_build_stats st;
    CHECK(accel_build_spec("instanced:bottom=nested_grid", &f0, 1, &k, &a, &st, &err) == 0);
    accel_update_stats us;
    CHECKF(k->update(a, &f1, 1, &us, &err) == 0, "%s", err.msg);
    CHECK(us.meshes_rebuilt > 0);
    ray_list l = {0};
    inst_make_rays(&f1, &l);
    accel_hit *ref = malloc(l.n * sizeof *ref);
    accel_reference_trace(&f1, l.r, ref, l.n, 2);
    size_t bad = inst_count_bad(k, a, &f1, &l, ref, "update", NULL);
    CHECKF(bad == 0, "after update: %zu bad rays of %zu", bad, l.n);
    k->destroy(a);
    free(ref);
    free(l.r);
    scene_free(&f0);
    scene_free(&f1);
}

TEST(anybottom_lab_step3_catches_a_walk_without_pad)
{
    /* Lab step 3's check on a bvh whose walk forgets the pad: it must fail,
     * naming a ray and a triangle (test_lab.c runs it on the project's bvh,
     * which passes, and on the untouched starter, which fails). */
    accel_kind broken = *accel_find_kind("bvh");
    broken.name = "bvh_without_pad";
    broken.walk = nopad_walk;
    lab_subject sub = {&broken, "build=median", 2, NULL, 1, NULL};
    lab_result r;
    accel_error err = {0};
    CHECK(lab_check(3, &sub, &r, &err) == 0);
    CHECKF(!r.passed, "step 3 passes a walk without the pad:\n%s", r.report);
    CHECKF(strstr(r.report, "the reference hits triangle") != NULL, "report:\n%s", r.report);
}
