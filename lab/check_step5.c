/*
 * check_step5.c - step 5 of the lab (LAB.md): be proud. First every
 * variant of the kind (accel_kind.variants, the ones the conformance suite
 * runs: leaf=1, traverse=packet) on step 2's scenes, each in its own
 * child, so that a crash names the variant and the scene; then frames per
 * second at 800x600 (primary and shadow rays) beside the project's
 * bvh:traverse=packet, frames compared, speed reported, never failed.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check_common.h"
#include "measure/bench.h"
#include "scene/scene.h"


typedef struct {
    double ms_primary, ms_shadow;
    accel_hit *hits;
    uint8_t *occ;
} frame_time;

/* Median of 3 timed frames (primary then shadow rays) after one warm-up. */
static int time_frames(const accel_kind *k, const void *a, const rays_set *prim,
                       const rays_set *shadow, int threads, frame_time *out, accel_error *err)
{
    bench_trace_opts o = {0};
    o.threads = threads;
    o.warmup = 1;
    o.repeats = 3;
    o.hits = out->hits;
    bench_result res;
    int rc = bench_trace(k, a, prim, 0, &o, &res, err);
    if (rc) return rc;
    out->ms_primary = res.ms.median;
    o.hits = NULL;
    o.occluded = out->occ;
    rc = bench_trace(k, a, shadow, 1, &o, &res, err);
    out->ms_shadow = res.ms.median;
    return rc;
}

static void check_real_time(const lab_subject *s, const char *spec, lab_result *r,
                            accel_error *err)
{
    int w = s->quick ? 200 : 800, h = s->quick ? 150 : 600;
    accel_scene sc;
    if (scene_create(spec, &sc, err)) {
        lab_fail(r, "scene %s: %s", spec, err->msg);
        return;
    }
    const accel_kind *refk = accel_find_kind("bvh");
    rays_set prim = {0}, shadow = {0};
    void *mine = NULL, *theirs = NULL;
    accel_build_stats st_mine, st_theirs;
    frame_time fm = {0}, ft = {0};
    int ran = 0;
    int threads = s->threads > 0 ? s->threads : 1;
    if (rays_primary(&sc.camera, w, h, &prim, err)) goto out;
    fm.hits = malloc(prim.count * sizeof *fm.hits);
    ft.hits = malloc(prim.count * sizeof *ft.hits);
    if (!fm.hits || !ft.hits || !refk) {
        lab_fail(r, "step 5 needs the project's bvh kind and memory for %zu rays", prim.count);
        goto out;
    }
    if (accel_build_kind(refk, "traverse=packet", &sc, threads, &theirs, &st_theirs, err)) goto out;
    accel_trace(refk, theirs, prim.rays, ft.hits, prim.count, threads, NULL);
    if (rays_shadow(&sc, &prim, ft.hits, &shadow, err)) goto out;
    fm.occ = malloc(shadow.count + 1);
    ft.occ = malloc(shadow.count + 1);
    if (!fm.occ || !ft.occ) goto out;
    /* The student's fastest mode: packets when the kind has them. */
    const char *mode = "traverse=packet";
    if (lab_build_subject(s, mode, &sc, &mine, &st_mine, err)) {
        mode = "";
        if (lab_build_subject(s, mode, &sc, &mine, &st_mine, err)) {
            lab_fail(r, "%s: your build failed: %s", spec, err->msg);
            goto out;
        }
    }
    if (time_frames(s->kind, mine, &prim, &shadow, threads, &fm, err) ||
        time_frames(refk, theirs, &prim, &shadow, threads, &ft, err))
        goto out;
    hits_diff d = hits_compare(&sc, prim.rays, ft.hits, fm.hits, prim.count);
    size_t occ_bad = 0;
    for (size_t i = 0; i < shadow.count; i++) occ_bad += fm.occ[i] != ft.occ[i];
    if (d.first_bad != SIZE_MAX || occ_bad) {
        lab_fail(r, "%s at %dx%d: %zu primary rays and %zu shadow rays differ from the project's "
                "BVH: fix steps 2 and 4 first",
             spec, w, h, prim.count - d.agree, occ_bad);
        goto out;
    }
    double f_mine = 1000.0 / (fm.ms_primary + fm.ms_shadow);
    double f_theirs = 1000.0 / (ft.ms_primary + ft.ms_shadow);
    lab_say(r, "  ok   %s (%u triangles) at %dx%d, %d thread(s), primary + shadow rays:\n", spec,
        sc.live_count, w, h, threads);
    char kv[256]; /* the spec timed: the subject's parameters and the mode */
    snprintf(kv, sizeof kv, "%s%s%s", s->kv, *s->kv && *mode ? "," : "", mode);
    lab_say(r, "       yours (%s%s%s): build %.1f ms, primary %.1f ms, shadow %.1f ms: %.1f frames/s\n",
        s->kind->name, *kv ? ":" : "", kv, st_mine.ms, fm.ms_primary, fm.ms_shadow, f_mine);
    lab_say(r, "       project's bvh:traverse=packet: build %.1f ms, primary %.1f ms, shadow %.1f ms: "
           "%.1f frames/s\n",
        st_theirs.ms, ft.ms_primary, ft.ms_shadow, f_theirs);
    if (w == 800 && h == 600)
        lab_say(r, "       the lecture's target is 20 frames/s at 800x600: %s\n",
            f_mine >= 20.0 ? "reached. Be proud."
                           : "not yet (LAB.md, step 5, says what helps most)");
    else
        lab_say(r, "       (a reduced size: the lecture's 20 frames/s target is for 800x600)\n");
    ran = 1;
out:
    if (!ran && r->passed) lab_fail(r, "step 5 could not run: %s", err->msg);
    if (mine) s->kind->destroy(mine);
    if (theirs) refk->destroy(theirs);
    rays_free(&prim);
    rays_free(&shadow);
    free(fm.hits);
    free(ft.hits);
    free(fm.occ);
    free(ft.occ);
    scene_free(&sc);
}

/* Step 5, first: every variant of the kind (accel_kind.variants, which
 * the conformance suite runs too: leaf=1, traverse=packet) on each scene,
 * in its own child, so that a crash or a wrong answer names the variant
 * and the scene, not only "died" in the suite's output. */
static const char *variant_now = ""; /* set before each child starts */

static void check_variant(const lab_subject *s, const char *spec, lab_result *r, accel_error *err)
{
    accel_scene sc;
    if (scene_create(spec, &sc, err)) {
        lab_fail(r, "scene %s: %s", spec, err->msg);
        return;
    }
    rays_set rays = {0};
    void *a = NULL;
    accel_build_stats st;
    accel_hit *ref = NULL, *hits = NULL;
    lab_where(r, "scene %s, your build with %s", spec, variant_now);
    if (lab_build_subject(s, variant_now, &sc, &a, &st, err)) {
        lab_fail(r, "%s: your build with %s failed: %s", spec, variant_now, err->msg);
        goto out;
    }
    if (rays_primary(&sc.camera, 32, 32, &rays, err) ||
        !(ref = malloc(rays.count * sizeof *ref)) || !(hits = malloc(rays.count * sizeof *hits))) {
        lab_fail(r, "%s: could not make the rays", spec);
        goto out;
    }
    lab_where(r, "scene %s, variant %s, primary rays", spec, variant_now);
    accel_reference_trace(&sc, rays.rays, ref, rays.count, 1);
    accel_trace(s->kind, a, rays.rays, hits, rays.count, 1, NULL);
    hits_diff d = hits_compare(&sc, rays.rays, ref, hits, rays.count);
    if (d.first_bad != SIZE_MAX)
        lab_fail(r, "%s with %s: %zu holes, %zu false hits, %zu other disagreements of %zu "
                    "primary rays (first: ray %zu): the variant the conformance suite runs "
                    "(bin-lab/lab --step 2 --accel student:%s shows the ray)",
                 spec, variant_now, d.holes, d.false_hits, d.disagreements, rays.count,
                 d.first_bad, variant_now);
out:
    if (a) s->kind->destroy(a);
    rays_free(&rays);
    free(ref);
    free(hits);
    scene_free(&sc);
}

/* Does kv set a key that variant sets too (bvh:build=median and
 * build=mid)? Then the variant is not this subject's. */
static int sets_a_key_of(const char *kv, const char *variant)
{
    for (const char *p = variant; *p;) {
        const char *eq = strchr(p, '='), *comma = strchr(p, ',');
        if (!eq || (comma && comma < eq)) break;
        char key[64];
        size_t len = (size_t)(eq - p) + 1; /* with the '=' */
        if (len >= sizeof key) break;
        memcpy(key, p, len);
        key[len] = '\0';
        for (const char *q = kv; (q = strstr(q, key)) != NULL; q++)
            if (q == kv || q[-1] == ',') return 1;
        if (!comma) break;
        p = comma + 1;
    }
    return 0;
}

static void check_variants(const lab_subject *s, const char *const *scenes, size_t n,
                           lab_result *r, accel_error *err)
{
    size_t ran = 0;
    for (const char *const *v = s->kind->variants; v && *v && r->passed; v++) {
        if (!**v || sets_a_key_of(s->kv, *v)) continue; /* the default: steps 1-4 */
        variant_now = *v;
        for (size_t i = 0; i < n && r->passed; i++, ran++)
            lab_run_isolated(check_variant, s, scenes[i], r, err);
    }
    variant_now = "";
    if (r->passed && ran)
        lab_say(r, "  ok   your kind's variants (%zu builds) agree with the reference\n", ran);
}

void lab_check_step5(const lab_subject *s, const char *const *scenes, size_t n, lab_result *r,
                     accel_error *err)
{
    check_variants(s, scenes, s->quick && n > 2 ? 2 : n, r, err); /* quick: make test */
    if (r->passed) lab_run_isolated(check_real_time, s, "teapot_stadium:n=16", r, err);
}
