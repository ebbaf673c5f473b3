/*
 * test_isa.c - the kernel units' two instruction sets (core/isa.h): the
 * detection agrees with the kernel's own list of CPU flags, the switches
 * (isa=, GRIDBVH_ISA) choose what they say and refuse what cannot run, and
 * the AVX-512 tables answer bit for bit what the AVX2 tables answer (t, u,
 * v, prim, the any-hit answers and every counter) for every row: single
 * rays in both orders, branchy, quantized, packets, streams, widths 4 and 8, blocks
 * of 4 and 8, on built-in scenes with primary, shadow and diffuse rays and
 * on the stability study's stiff cases; the same for the grid family's
 * block kernels (grid, nested_grid and irregular_grid with cells=blocks,
 * single rays and packets, every skipping mode). Where the CPU or the build has no
 * AVX-512 the comparison is skipped (a note says why) and the AVX2 tables
 * are still checked against the reference.
 */
#include <stdlib.h>
#include <string.h>

#include "core/isa.h"
#include "rays/rays.h"
#include "rays/stiff.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

/* Every row of the tables (bvh/wide/trace.c): width, block, order, packets, quant, streams. */
static const char *const isa_specs[] = {
    "width=8",          "width=4",           "width=8,block=4",
    "width=4,block=8",  "width=8,order=dist", "width=4,block=4,order=dist",
    "width=8,order=branchy", "width=4,order=branchy", "width=8,quant=1",
    "width=8,quant=1,block=4", "width=8,traverse=packet", "width=4,traverse=packet",
    "width=8,block=4,traverse=packet", "width=4,block=4,traverse=packet,hybrid=0",
    "width=8,traverse=stream", "width=4,block=4,traverse=stream,stream=64,hybrid=0",
};
#define ISA_SPEC_COUNT (sizeof isa_specs / sizeof *isa_specs)

/* The grid family's kernel units on blocks (grid/k8_*.c, nested_grid/k8_*.c,
 * irregular_grid/k8_cells.c): single rays in every skipping mode, packets
 * with and without their mailbox, nested levels of both walks. */
static const char *const isa_grid_specs[] = {
    "grid:skip=none",
    "grid:skip=cloud",
    "grid:skip=macro",
    "grid:traverse=packet",
    "grid:traverse=packet,mailbox=0",
    "nested_grid:cells=blocks",
    "nested_grid:cells=blocks,depth=3,threshold=4",
    "nested_grid:cells=blocks,traverse=packet",
    "nested_grid:cells=blocks,traverse=packet,mailbox=0,threshold=4",
    "irregular_grid:cells=blocks",
};
#define ISA_GRID_SPEC_COUNT (sizeof isa_grid_specs / sizeof *isa_grid_specs)

static int avx512_usable(void) { return accel_isa_built_avx512() && accel_isa_cpu_avx512(); }

/* Whether /proc/cpuinfo's flags (which Linux clears when the OS does not
 * save the state) list every AVX-512 subset the units need; -1 unreadable. */
static int cpuinfo_avx512(void)
{
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (!f) return -1;
    static char line[8192];
    int all = -1;
    while (all < 0 && fgets(line, sizeof line, f)) {
        if (strncmp(line, "flags", 5)) continue;
        line[strcspn(line, "\n")] = 0;
        static const char *const need[] = {" avx512f", " avx512cd", " avx512bw", " avx512dq", " avx512vl"};
        all = 1;
        for (size_t i = 0; i < 5; i++) {
            const char *at = strstr(line, need[i]);
            all &= at != NULL && (at[strlen(need[i])] == ' ' || at[strlen(need[i])] == 0);
        }
    }
    fclose(f);
    return all;
}

/* GRIDBVH_ISA set to value (NULL: unset) for one call of resolve. */
static int resolve_with_env(const char *value, int requested, int *isa, accel_error *err)
{
    const char *old = getenv("GRIDBVH_ISA");
    char *saved = old ? strdup(old) : NULL;
    if (value)
        setenv("GRIDBVH_ISA", value, 1);
    else
        unsetenv("GRIDBVH_ISA");
    int rc = accel_isa_resolve(requested, isa, err);
    if (saved)
        setenv("GRIDBVH_ISA", saved, 1);
    else
        unsetenv("GRIDBVH_ISA");
    free(saved);
    return rc;
}

TEST(isa_detection_and_switches)
{
    int proc = cpuinfo_avx512();
    if (proc >= 0)
        CHECKF(proc == accel_isa_cpu_avx512(), "cpuid/xgetbv say AVX-512 %s, /proc/cpuinfo %s",
               accel_isa_cpu_avx512() ? "usable" : "not usable", proc ? "lists it" : "does not");
    int have = avx512_usable(), isa = -1;
    accel_error err = {0};
    CHECK(resolve_with_env(NULL, ACCEL_ISA_AVX2, &isa, &err) == 0 && isa == ACCEL_ISA_AVX2);
    CHECK(resolve_with_env(NULL, ACCEL_ISA_AUTO, &isa, &err) == 0 &&
          isa == (have ? ACCEL_ISA_AVX512 : ACCEL_ISA_AVX2));
    CHECK(resolve_with_env("avx2", ACCEL_ISA_AUTO, &isa, &err) == 0 && isa == ACCEL_ISA_AVX2);
    CHECK(resolve_with_env("auto", ACCEL_ISA_AUTO, &isa, &err) == 0 &&
          isa == (have ? ACCEL_ISA_AVX512 : ACCEL_ISA_AVX2));
    /* a parameter wins over the environment */
    CHECK(resolve_with_env("avx512", ACCEL_ISA_AVX2, &isa, &err) == 0 && isa == ACCEL_ISA_AVX2);
    CHECKF(resolve_with_env("sse9", ACCEL_ISA_AUTO, &isa, &err) == ACCEL_ERR_SPEC &&
               strstr(err.msg, "GRIDBVH_ISA=sse9"),
           "GRIDBVH_ISA=sse9: %s", err.msg);
    int rc = resolve_with_env(NULL, ACCEL_ISA_AVX512, &isa, &err);
    CHECKF(have ? rc == 0 && isa == ACCEL_ISA_AVX512 : rc == ACCEL_ERR_SPEC && strstr(err.msg, "isa=avx512"),
           "isa=avx512 with AVX-512 %s: rc %d, %s", have ? "usable" : "absent", rc, err.msg);
    CHECK(!strcmp(accel_isa_label(ACCEL_ISA_AVX2), "avx2") && !strcmp(accel_isa_label(ACCEL_ISA_AVX512), "avx512"));

    /* The kind: the tree records the ISA in its statistics; isa= on the
     * binary tree and avx512 where it cannot run are spec errors. */
    accel_scene s;
    if (scene_create("soup:tris=500", &s, &err)) {
        test_fail(__FILE__, __LINE__, "soup: %s", err.msg);
        return;
    }
    const accel_kind *kind;
    void *a;
    accel_build_stats st;
    CHECK(accel_build_spec("bvh:width=8,isa=avx2", &s, 1, &kind, &a, &st, &err) == 0);
    if (st.isa) CHECKF(!strcmp(st.isa, "avx2"), "isa=avx2 built with %s", st.isa);
    CHECK(st.isa != NULL);
    kind->destroy(a);
    CHECK(accel_build_spec("bvh:isa=avx2", &s, 1, &kind, &a, &st, &err) == ACCEL_ERR_SPEC);
    rc = accel_build_spec("bvh:width=4,isa=avx512", &s, 1, &kind, &a, &st, &err);
    CHECKF(have ? rc == 0 : rc == ACCEL_ERR_SPEC, "bvh:width=4,isa=avx512: rc %d (%s)", rc, rc ? err.msg : "");
    if (rc == 0) {
        CHECK(st.isa && !strcmp(st.isa, "avx512"));
        kind->destroy(a);
    }

    /* The grid family: isa= where the cells hold blocks, recorded in the
     * statistics; the per-id cells (one kernel) record none; avx512 where
     * it cannot run is the wide BVH's spec error. */
    static const char *const grids[][2] = {{"grid", ""},
                                           {"nested_grid", "cells=blocks,"},
                                           {"irregular_grid", "cells=blocks,"}};
    for (int k = 0; k < 3; k++) {
        char spec[128];
        snprintf(spec, sizeof spec, "%s:%sisa=avx2", grids[k][0], grids[k][1]);
        rc = accel_build_spec(spec, &s, 1, &kind, &a, &st, &err);
        CHECKF(rc == 0, "%s: rc %d (%s)", spec, rc, rc ? err.msg : "");
        if (rc == 0) {
            CHECKF(st.isa && !strcmp(st.isa, "avx2"), "%s built with %s", spec, st.isa ? st.isa : "(none)");
            kind->destroy(a);
        }
        snprintf(spec, sizeof spec, "%s:%sisa=auto", grids[k][0], grids[k][1]);
        rc = accel_build_spec(spec, &s, 1, &kind, &a, &st, &err);
        CHECKF(rc == 0, "%s: rc %d (%s)", spec, rc, rc ? err.msg : "");
        if (rc == 0) {
            const char *want = getenv("GRIDBVH_ISA") ? NULL : have ? "avx512" : "avx2";
            CHECKF(st.isa && (!want || !strcmp(st.isa, want)), "%s built with %s", spec,
                   st.isa ? st.isa : "(none)");
            kind->destroy(a);
        }
        snprintf(spec, sizeof spec, "%s:cells=ids", grids[k][0]);
        rc = accel_build_spec(spec, &s, 1, &kind, &a, &st, &err);
        CHECKF(rc == 0, "%s: rc %d (%s)", spec, rc, rc ? err.msg : "");
        if (rc == 0) {
            CHECKF(st.isa == NULL, "%s records isa %s", spec, st.isa);
            kind->destroy(a);
        }
        snprintf(spec, sizeof spec, "%s:%sisa=avx512", grids[k][0], grids[k][1]);
        rc = accel_build_spec(spec, &s, 1, &kind, &a, &st, &err);
        CHECKF(have ? rc == 0 : rc == ACCEL_ERR_SPEC && strstr(err.msg, "isa=avx512"), "%s: rc %d (%s)", spec,
               rc, rc ? err.msg : "");
        if (rc == 0) {
            CHECKF(st.isa && !strcmp(st.isa, "avx512"), "%s built with %s", spec, st.isa ? st.isa : "(none)");
            kind->destroy(a);
        }
    }
    scene_free(&s);
}

/* Rays plus the reference's answers, and the counters of one trace. */
typedef struct {
    const char *name;
    const accel_ray *rays;
    size_t n;
    const accel_hit *ref;
} isa_set;

typedef struct {
    accel_hit *hits;
    uint8_t *occ;
    accel_counters c;
} isa_run;

/* Timed (uncounted) closest and any hit, and a counted closest-hit trace. */
static void isa_trace(const accel_kind *kind, const void *a, const isa_set *set, isa_run *r)
{
    size_t n = set->n ? set->n : 1;
    r->hits = malloc(n * sizeof *r->hits);
    r->occ = malloc(n);
    accel_hit *counted = malloc(n * sizeof *counted);
    memset(&r->c, 0, sizeof r->c);
    accel_trace(kind, a, set->rays, r->hits, set->n, 1, NULL);
    accel_trace_occluded(kind, a, set->rays, r->occ, set->n, 1, NULL);
    accel_trace(kind, a, set->rays, counted, set->n, 1, &r->c);
    CHECKF(!memcmp(counted, r->hits, set->n * sizeof *counted), "%s: counted trace differs", set->name);
    free(counted);
}

/* One spec built for both ISAs (or AVX2 alone), compared ray by ray;
 * spec is bvh's parameters, or a whole kind:parameters when it names its
 * kind. Returns the rays that differ. */
static size_t isa_compare(const accel_scene *s, const char *spec, const isa_set *sets, int set_count,
                          int both)
{
    char specs[2][256];
    const char *kind_prefix = strchr(spec, ':') ? "" : "bvh:";
    snprintf(specs[0], sizeof specs[0], "%s%s,isa=avx2", kind_prefix, spec);
    snprintf(specs[1], sizeof specs[1], "%s%s,isa=avx512", kind_prefix, spec);
    const accel_kind *kind;
    void *a[2] = {NULL, NULL};
    accel_build_stats st;
    accel_error err = {0};
    for (int i = 0; i < 1 + both; i++)
        if (accel_build_spec(specs[i], s, 1, &kind, &a[i], &st, &err)) {
            test_fail(__FILE__, __LINE__, "%s on %s: %s", specs[i], s->name, err.msg);
            if (a[0]) kind->destroy(a[0]);
            return 1;
        }
    size_t bad = 0;
    for (int k = 0; k < set_count; k++) {
        const isa_set *set = &sets[k];
        isa_run r[2];
        isa_trace(kind, a[0], set, &r[0]);
        /* the AVX2 tables against the reference (FORMATS.md's rule) */
        test_diff d = test_trace_diff(s, kind, a[0], set->rays, set->n, set->ref, 1, NULL, NULL);
        if (test_diff_bad(&d))
            test_fail_diff(__FILE__, __LINE__, specs[0], &d, set->rays, set->ref, r[0].hits, r[0].occ);
        bad += test_diff_bad(&d);
        if (both) {
            isa_trace(kind, a[1], set, &r[1]);
            size_t diff = 0, first = SIZE_MAX;
            for (size_t i = 0; i < set->n; i++)
                if (memcmp(&r[0].hits[i], &r[1].hits[i], sizeof r[0].hits[i]) || r[0].occ[i] != r[1].occ[i]) {
                    diff++;
                    if (first == SIZE_MAX) first = i;
                }
            if (diff) {
                const accel_hit *h0 = &r[0].hits[first], *h1 = &r[1].hits[first];
                test_fail(__FILE__, __LINE__,
                          "%s on %s/%s: %zu of %zu rays differ between avx2 and avx512 (first %zu: prim %u "
                          "t %a u %a v %a occ %d, avx512 prim %u t %a u %a v %a occ %d)",
                          spec, s->name, set->name, diff, set->n, first, h0->prim, h0->t, h0->u, h0->v,
                          r[0].occ[first], h1->prim, h1->t, h1->u, h1->v, r[1].occ[first]);
            }
            CHECKF(r[0].c.steps == r[1].c.steps && r[0].c.box_tests == r[1].c.box_tests &&
                       r[0].c.prim_tests == r[1].c.prim_tests && r[0].c.rays == r[1].c.rays,
                   "%s on %s/%s: counters differ (steps %llu/%llu, boxes %llu/%llu, prims %llu/%llu)", spec,
                   s->name, set->name, (unsigned long long)r[0].c.steps, (unsigned long long)r[1].c.steps,
                   (unsigned long long)r[0].c.box_tests, (unsigned long long)r[1].c.box_tests,
                   (unsigned long long)r[0].c.prim_tests, (unsigned long long)r[1].c.prim_tests);
            bad += diff;
            free(r[1].hits);
            free(r[1].occ);
        }
        free(r[0].hits);
        free(r[0].occ);
    }
    kind->destroy(a[0]);
    if (a[1]) kind->destroy(a[1]);
    return bad;
}

static int isa_both(void)
{
    if (avx512_usable()) return 1;
    test_note("avx512 comparison skipped: %s; the AVX2 tables are checked against the reference",
              !accel_isa_built_avx512() ? "this build has no AVX-512 units (ARCH512 empty or refused)"
                                        : "this CPU lacks AVX-512 F/CD/BW/DQ/VL or the OS does not save "
                                          "its registers");
    return 0;
}

/* Built-in scenes (spheres included) and the bunny if ../shared is there,
 * with primary, shadow and diffuse rays, for every spec of the list. */
static void isa_scenes(const char *const *specs, size_t spec_count)
{
    int both = isa_both();
    char bunny[512] = "";
    const char *dir = test_shared_scenes();
    if (dir) snprintf(bunny, sizeof bunny, "%s/bunny.off", dir);
    const char *const scenes[] = {"teapot_stadium:n=4,stadium=16,tiers=3", "sphereflake:level=2",
                                  "soup:tris=4000", "slivers:tris=3000,slivers=100", bunny};
    for (size_t si = 0; si < sizeof scenes / sizeof *scenes; si++) {
        if (!scenes[si][0]) continue;
        accel_scene s;
        accel_error err = {0};
        if (scene_create(scenes[si], &s, &err)) {
            test_fail(__FILE__, __LINE__, "%s: %s", scenes[si], err.msg);
            continue;
        }
        rays_set rs[3];
        memset(rs, 0, sizeof rs);
        accel_hit *ref[3] = {NULL, NULL, NULL};
        int ok = rays_primary(&s.camera, 32, 32, &rs[0], &err) == 0;
        if (ok) {
            ref[0] = test_oracle_hits(&s, rs[0].rays, rs[0].count, TEST_ORACLE_REFERENCE);
            ok = ref[0] && !rays_shadow(&s, &rs[0], ref[0], &rs[1], &err) &&
                 !rays_diffuse(&s, &rs[0], ref[0], 3, &rs[2], &err);
        }
        for (int k = 1; ok && k < 3; k++) ok = (ref[k] = test_oracle_hits(&s, rs[k].rays, rs[k].count,
                                                                       TEST_ORACLE_REFERENCE)) != NULL;
        if (ok) {
            static const char *const names[] = {"primary", "shadow", "diffuse"};
            isa_set sets[3];
            for (int k = 0; k < 3; k++) sets[k] = (isa_set){names[k], rs[k].rays, rs[k].count, ref[k]};
            for (size_t i = 0; i < spec_count; i++) isa_compare(&s, specs[i], sets, 3, both);
        } else {
            test_fail(__FILE__, __LINE__, "%s: rays: %s", scenes[si], err.msg);
        }
        for (int k = 0; k < 3; k++) {
            rays_free(&rs[k]);
            free(ref[k]);
        }
        scene_free(&s);
    }
}

TEST(isa_same_hits_scenes) { isa_scenes(isa_specs, ISA_SPEC_COUNT); }
TEST(isa_grid_same_hits_scenes) { isa_scenes(isa_grid_specs, ISA_GRID_SPEC_COUNT); }

/* The stability study's stiff cases (vertex and edge rays, axis rays on
 * split planes, far and tiny scenes...), every spec of the list. */
static void isa_stiff(const char *const *specs, size_t spec_count)
{
    int both = isa_both();
    for (int ci = 0; ci < stiff_case_count(); ci++) {
        stiff_case c;
        if (!test_stiff_case(ci, &c)) continue;
        accel_hit *ref = test_oracle_hits(&c.scene, c.rays.rays, c.rays.count, TEST_ORACLE_REFERENCE);
        if (ref) {
            isa_set set = {c.name, c.rays.rays, c.rays.count, ref};
            for (size_t i = 0; i < spec_count; i++) isa_compare(&c.scene, specs[i], &set, 1, both);
        }
        free(ref);
        stiff_case_free(&c);
    }
}

TEST(isa_same_hits_stiff) { isa_stiff(isa_specs, ISA_SPEC_COUNT); }
TEST(isa_grid_same_hits_stiff) { isa_stiff(isa_grid_specs, ISA_GRID_SPEC_COUNT); }
