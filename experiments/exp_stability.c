/*
 * exp_stability - holes per million rays on the stiff and extreme cases.
 *
 * Every kind (and the traversals and kinds this build adds: packets, wide
 * BVHs, grid packets and skipping, the irregular grid), with the
 * watertight (default) and the naive (Moller-Trumbore) triangle test, on
 * every case of rays/stiff.c and on the shared meshes: holes (the
 * reference hits, the tracer misses), false hits and disagreements per
 * million rays, and leaks per million of the rays that can leak (those
 * starting inside a closed mesh). A rate of zero is shown with its 95%
 * upper bound (Clopper-Pearson; 1 - 0.05^(1/n), about 3/n): zero in 2,400
 * rays means "below 1,250 per million", not "never". Rows that are all
 * zero are folded; so are rows equal for every kind. Speeds (interleaved
 * rounds) show the performance cliffs. Then self-intersection of secondary
 * rays: a fixed epsilon offset against the robust offset of Waechter and
 * Binder (Ray Tracing Gems, 2019), on a closed mesh moved from the origin.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "group.h"
#include "cli/cli.h"
#include "rays/stiff.h"

#define MAX_CFG 32
#define CLIFF 10.0

static const char *const extras[] = {"bvh:traverse=packet", "bvh:width=4", "bvh:width=8",
                                     "grid:traverse=packet", "grid:skip=macro", "irregular_grid",
                                     "nested_grid:traverse=packet"};

typedef struct {
    double value;
    exp_text what;
} worst;

typedef struct {
    uint64_t robust_rays, robust_bad_cases, cases;
    /* the cases' own rays, each counted once: every configuration traces
     * the same rays, so a rate bound per configuration rests on these */
    uint64_t distinct_rays;
    worst holes, leaks;
    exp_text clean, cliffs, speeds, left;
} study;

typedef struct {
    size_t holes, false_hits, dis, leaks;
} counts;

static void rate(char *buf, size_t n, size_t k, size_t of)
{
    if (!of)
        snprintf(buf, n, "-");
    else
        snprintf(buf, n, "%.0f (< %.0f)", 1e6 * (double)k / (double)of, 1e6 * exp_binom_upper(k, of));
}

/* The worst naive configuration of a case by holes (what 0) or leaks (1)
 * per million; equal counts are a tie, so every configuration that has
 * them is named. */
static void note_worst(worst *w, const exp_group *g, const counts *cnt, int m, size_t of, int what,
                       const char *name)
{
    double v[MAX_CFG], top = 0;
    int naive_n = 0, at_top = 0;
    for (int k = 0; k < m; k++) {
        v[k] = -1;
        if (!g->cfg[k].ok || !strstr(g->cfg[k].spec, "tri=naive") || !of) continue;
        v[k] = 1e6 * (double)(what ? cnt[k].leaks : cnt[k].holes) / (double)of;
        naive_n++;
        if (v[k] > top) top = v[k], at_top = 0;
        at_top += v[k] == top;
    }
    if (!(top > w->value)) return;
    w->value = top;
    exp_text_free(&w->what);
    if (at_top == naive_n && naive_n > 1) {
        exp_text_add(&w->what, "every naive configuration alike on %s: a tie, the triangle test "
                     "is shared", name);
        return;
    }
    for (int k = 0; k < m; k++)
        if (v[k] == top) exp_text_add(&w->what, "%s`%s`", w->what.len ? ", " : "", g->cfg[k].spec);
    exp_text_add(&w->what, " on %s", name);
}

static void measure_case(exp_ctx *x, study *st, stiff_case *c, const exp_list *list)
{
    size_t n = c->rays.count, leakable = n - c->leak_begin;
    accel_hit *ref = malloc((n ? n : 1) * sizeof *ref), *h = malloc((n ? n : 1) * sizeof *h);
    if (!ref || !h) exit(CLI_EXIT_INTERNAL);
    exp_reference(x, &c->scene, c->rays.rays, ref, n);
    bench_sets one = {0};
    one.primary = c->rays;
    one.made = BENCH_PRIMARY;
    exp_group g;
    exp_group_init(&g, x, &c->scene, &one, BENCH_PRIMARY);
    g.collapse_ms = x->quick ? 500 : 3000;
    g.time_builds = 0; /* no build time is reported here */
    for (int i = 0; i < list->count; i++) {
        if (!strncmp(list->spec[i], "brute", 5) && (!list->spec[i][5] || list->spec[i][5] == ':') &&
            c->scene.live_count > 20000) {
            if (!strcmp(list->spec[i], "brute"))
                exp_text_add(&st->left, "- %s: `brute` (%u primitives against every ray: minutes "
                             "per pass; both tests).\n", c->name, c->scene.live_count);
            exp_note_left(x, EXP_LEFT_POINTLESS);
            continue;
        }
        exp_group_add(&g, list->spec[i], 0);
    }
    exp_group_run(&g);
    counts cnt[MAX_CFG] = {{0}};
    int m = g.count < MAX_CFG ? g.count : MAX_CFG, all_zero = 1, wt_zero = 1, any_wt = 0;
    for (int k = 0; k < m; k++) {
        if (!g.cfg[k].ok) continue;
        accel_trace(g.cfg[k].kind, g.cfg[k].accel, c->rays.rays, h, n, x->threads, NULL);
        hits_diff d = hits_compare(ref, h, n);
        cnt[k].holes = d.holes, cnt[k].false_hits = d.false_hits, cnt[k].dis = d.disagreements;
        for (size_t i = c->leak_begin; i < n; i++) cnt[k].leaks += h[i].prim == ACCEL_MISS;
        int zero = !cnt[k].holes && !cnt[k].false_hits && !cnt[k].dis && !cnt[k].leaks;
        int naive = strstr(g.cfg[k].spec, "tri=naive") != NULL;
        all_zero &= zero;
        if (!naive) {
            wt_zero &= zero;
            any_wt = 1;
            st->robust_rays += n;
        }
        exp_csv(x, "stiff,%s,%s,%zu,%zu,%zu,%zu,%zu,%zu,%.4f,,,\n", c->name, g.cfg[k].spec, n,
                leakable, cnt[k].holes, cnt[k].false_hits, cnt[k].dis, cnt[k].leaks,
                exp_group_mrays(&g, k, BENCH_PRIMARY).median);
    }
    note_worst(&st->holes, &g, cnt, m, n, 0, c->name);
    note_worst(&st->leaks, &g, cnt, m, leakable, 1, c->name);
    st->cases++;
    st->robust_bad_cases += !wt_zero;
    if (any_wt) st->distinct_rays += n;
    char hb[64], fb[64], db[64], lb[64];
    rate(hb, sizeof hb, 0, n), rate(lb, sizeof lb, 0, leakable);
    if (all_zero) {
        exp_text_add(&st->clean, "- %s (%zu rays%s): every configuration, both tests: no holes, "
                     "false hits, disagreements or leaks; per million rays %s%s%s.\n", c->name, n,
                     leakable ? ", some starting inside" : "", hb, leakable ? ", per million leak "
                     "rays " : "", leakable ? lb : "");
    } else {
        exp_md(x, "| **%s** | | %zu (%zu) | | | | |\n", c->name, n, leakable);
        for (int naive = 0; naive < 2; naive++) {
            /* One row when every configuration of this test counts the same. */
            int first = -1, same = 1;
            for (int k = 0; k < m; k++) {
                if (!g.cfg[k].ok || (strstr(g.cfg[k].spec, "tri=naive") != NULL) != naive) continue;
                if (first < 0) first = k;
                else same &= !memcmp(&cnt[k], &cnt[first], sizeof cnt[k]);
            }
            for (int k = 0; k < m && first >= 0; k++) {
                if (!g.cfg[k].ok || (strstr(g.cfg[k].spec, "tri=naive") != NULL) != naive) continue;
                if (same && k != first) continue;
                rate(hb, sizeof hb, cnt[k].holes, n), rate(fb, sizeof fb, cnt[k].false_hits, n);
                rate(db, sizeof db, cnt[k].dis, n), rate(lb, sizeof lb, cnt[k].leaks, leakable);
                exp_md(x, "| %s | %s | %s | %s | %s | %s | %s |\n",
                       same ? "every configuration" : g.cfg[k].spec, naive ? "naive" : "watertight",
                       "", hb, fb, db, lb);
            }
        }
    }
    /* Speeds of the watertight configurations: the cliffs. */
    int fast = -1, slow = -1;
    exp_text_add(&st->speeds, "| %s |", c->name);
    for (int k = 0; k < m; k++) {
        if (!g.cfg[k].ok || strstr(g.cfg[k].spec, "tri=naive")) continue;
        exp_est r = exp_group_mrays(&g, k, BENCH_PRIMARY);
        exp_text_add(&st->speeds, "%s `%s` %.2f", st->speeds.s[st->speeds.len - 1] == '|' ? "" : ",",
                     g.cfg[k].spec, r.median);
        if (!strcmp(g.cfg[k].spec, "brute")) continue;
        if (fast < 0 || r.median > exp_group_mrays(&g, fast, BENCH_PRIMARY).median) fast = k;
        if (slow < 0 || r.median < exp_group_mrays(&g, slow, BENCH_PRIMARY).median) slow = k;
    }
    double ratio = 0;
    if (fast >= 0 && slow >= 0) {
        ratio = exp_group_mrays(&g, fast, BENCH_PRIMARY).median / exp_group_mrays(&g, slow, BENCH_PRIMARY).median;
        if (ratio >= CLIFF)
            exp_text_add(&st->cliffs, "- A performance cliff on %s: `%s` traces %.1fx slower than "
                         "`%s`.\n", c->name, g.cfg[slow].spec, ratio, g.cfg[fast].spec);
    }
    exp_text_add(&st->speeds, " | %.1f |\n", ratio);
    for (int k = 0; k < g.count; k++)
        if (g.cfg[k].left && (g.cfg[k].left != EXP_LEFT_UNPARSED ||
                              (st->cases == 1 && !strstr(g.cfg[k].spec, "tri=naive"))))
            exp_text_add(&st->left, "- %s%s`%s` (%s).\n", g.cfg[k].left == EXP_LEFT_UNPARSED ? ""
                         : c->name, g.cfg[k].left == EXP_LEFT_UNPARSED ? "" : ": ", g.cfg[k].spec,
                         g.cfg[k].why);
    exp_group_free(&g);
    free(ref);
    free(h);
}

/* Fraction of secondary rays whose first hit is their own triangle. */
static void self_intersection(exp_ctx *x, exp_text *findings)
{
    static const float offsets[] = {0, 1e2f, 1e4f, 1e5f, 1e6f};
    const int no = x->quick ? 2 : 5;
    exp_md(x, "\n### Self-intersection of secondary rays\n\n"
              "Diffuse rays leave the primary hits of a closed sphere moved to (d, d, d); a ray "
              "whose first hit is its own triangle is a self-intersection. Fixed: origin = hit "
              "point + 1e-4 * normal, t_near = 0. Robust: the integer-ULP offset of Waechter and "
              "Binder (2019), t_near = 0. Per million rays (95%% upper bound), default "
              "accelerator.\n");
    exp_md_table(x, "distance d|rays|fixed epsilon 1e-4|robust offset");
    double worst_fixed = 0;
    size_t robust_bad = 0, total = 0;
    for (int i = 0; i < no; i++) {
        accel_scene base, s;
        accel_error err = {0};
        exp_scene(x, "sphere:segments=24", &base);
        if (scene_transform(&base, 1.0f, v3(offsets[i], offsets[i], offsets[i]), &s, &err)) {
            fprintf(stderr, "exp_stability: %s\n", err.msg);
            exit(cli_exit_of(err.code));
        }
        scene_free(&base);
        bench_sets sets;
        exp_sets(x, &s, BENCH_PRIMARY, &sets);
        const char *gen = accel_find_kind("bvh") ? "bvh" : "brute";
        const accel_kind *k;
        void *a;
        accel_build_stats bs;
        if (accel_build_spec(gen, &s, x->threads, &k, &a, &bs, &err)) {
            fprintf(stderr, "exp_stability: %s\n", err.msg);
            exit(cli_exit_of(err.code));
        }
        accel_hit *ph = malloc(sets.primary.count * sizeof *ph);
        if (!ph) exit(CLI_EXIT_INTERNAL);
        accel_trace(k, a, sets.primary.rays, ph, sets.primary.count, x->threads, NULL);
        size_t n = 0, self_fixed = 0, self_robust = 0;
        for (size_t r = 0; r < sets.primary.count; r++) {
            vec3 p, nn;
            if (!rays_hit_frame(&s, &sets.primary.rays[r], &ph[r], &p, &nn)) continue;
            /* Leave towards the outside (the mesh is closed and convex: the
             * true first hit of an outgoing ray is nothing at all). */
            vec3 d = v3_norm(v3_add(nn, v3(rays_rand(3, r, 0) - 0.5f, rays_rand(3, r, 1) - 0.5f,
                                           rays_rand(3, r, 2) - 0.5f)));
            if (v3_dot(d, nn) <= 0.05f) continue;
            vec3 of = v3_add(p, v3_scale(nn, 1e-4f)), ro = rays_offset_origin(p, nn);
            accel_ray rr[2] = {{of.x, of.y, of.z, 0, d.x, d.y, d.z, INFINITY},
                               {ro.x, ro.y, ro.z, 0, d.x, d.y, d.z, INFINITY}};
            accel_hit hh[2];
            k->intersect(a, rr, hh, 2, NULL);
            self_fixed += hh[0].prim != ACCEL_MISS;
            self_robust += hh[1].prim != ACCEL_MISS;
            n++;
        }
        char f[64], r[64];
        rate(f, sizeof f, self_fixed, n), rate(r, sizeof r, self_robust, n);
        exp_md(x, "| %g | %zu | %s | %s |\n", offsets[i], n, f, r);
        exp_csv(x, "selfhit,sphere:segments=24,%s,%zu,,,,%zu,%zu,,%g,,\n", gen, n, self_fixed,
                self_robust, offsets[i]);
        worst_fixed = fmax(worst_fixed, n ? 1e6 * (double)self_fixed / (double)n : 0);
        robust_bad += self_robust, total += n;
        free(ph);
        k->destroy(a);
        bench_sets_free(&sets);
        scene_free(&s);
    }
    exp_text_add(findings, "- Self-intersection: a fixed 1e-4 offset self-intersects up to %.0f "
                 "rays per million as the scene moves away from the origin; the robust offset "
                 "%s in %zu rays.\n", worst_fixed, robust_bad ? "also fails" : "never does", total);
}

/* Every stiff case (three in the quick budget), then the meshes. */
static void stiff_cases(exp_ctx *x, study *st, const exp_list *list)
{
    exp_md_table(x, "configuration|triangle test|rays (leak rays)|holes per million (95% bound)|"
                    "false hits per million|disagreements per million|leaks per million leak rays");
    int count = x->quick ? 3 : stiff_case_count();
    for (int i = 0; i < count; i++) {
        stiff_case c;
        accel_error err = {0};
        if (stiff_case_make(i, &c, &err)) {
            exp_text_add(&st->left, "- case %d: %s.\n", i, err.msg);
            continue;
        }
        measure_case(x, st, &c, list);
        stiff_case_free(&c);
    }
    for (int m = 0; m < x->mesh_count; m++) {
        stiff_case c;
        accel_error err = {0};
        if (stiff_case_from_scene(x->meshes[m], 0, &c, &err)) continue;
        measure_case(x, st, &c, list);
        stiff_case_free(&c);
    }
    for (int m = 0; m < x->scene_count; m++) { /* a scene given explicitly: measured, or an error */
        stiff_case c;
        accel_error err = {0};
        if (stiff_case_from_scene(x->scenes[m], 0, &c, &err)) {
            fprintf(stderr, "%s: --scene %s: %s\n", x->name, x->scenes[m], err.msg);
            exit(CLI_EXIT_INPUT);
        }
        measure_case(x, st, &c, list);
        stiff_case_free(&c);
    }
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_stability",
             "How many rays do naive and watertight kernels lose on stiff and extreme cases?",
             NULL);
    /* The timings here only show performance cliffs (ratios of 10x and
     * more): 3 rounds give their interval; the counts are exact. */
    if (x.repeats > 3) x.repeats = 3;
    exp_header(&x, "Stability on stiff and extreme cases", "the user's request: \"stability on "
               "stiff and extreme cases\"",
               "on rays aimed exactly at shared vertices and edges of closed meshes, along axes "
               "and cell diagonals from cell boundaries and split planes, grazing faces, and on "
               "far, tiny, huge, flat, degenerate, coincident and same-centroid scenes: how many "
               "holes (reference hits, tracer misses), false hits, disagreements and leaks (rays "
               "from inside a closed mesh that escape) does each configuration make with the "
               "watertight test (Woop et al. 2013, default) and with the naive Moller-Trumbore "
               "test, and at what speed? The reference is exact (double precision). Rates of zero "
               "carry their 95%% upper bound; rows equal for every configuration are folded.");
    exp_csv(&x, "part,case,spec,rays,leak_rays,holes,false_hits,disagreements,leaks,mrays,"
                "distance,fixed_selfhits,robust_selfhits\n");
    const char *names[MAX_CFG / 2];
    int nk = 0;
    for (size_t k = 0; k < accel_kind_count && nk < MAX_CFG / 2 - 8; k++) names[nk++] = accel_kinds[k]->name;
    for (size_t e = 0; e < sizeof extras / sizeof extras[0]; e++) names[nk++] = extras[e];
    exp_list base;
    exp_list_make(&x, names, nk, NULL, &base);
    const char *both[MAX_CFG];
    static char naive[MAX_CFG][300];
    int nb = 0;
    for (int i = 0; i < base.count && nb < MAX_CFG - 1; i++) {
        both[nb++] = base.spec[i];
        snprintf(naive[nb], sizeof naive[0], "%s%stri=naive", base.spec[i], strchr(base.spec[i], ':') ? "," : ":");
        both[nb] = naive[nb];
        nb++;
    }
    exp_list list = {both, nb};
    study st = {0};
    stiff_cases(&x, &st, &list);
    if (st.clean.len) exp_md(&x, "\nCases with nothing to report (folded):\n\n%s", exp_text_str(&st.clean));
    if (st.left.len) exp_md(&x, "\nLeft out:\n\n%s", exp_text_str(&st.left));
    /* Every configuration traces the same rays: the bound of one
     * configuration's rate rests on the distinct rays, not on the sum. */
    double bound = 1e6 * exp_binom_upper(0, st.distinct_rays);
    exp_md(&x, "\nThe watertight kernels over all cases: %llu ray traces (%llu distinct rays, each "
               "traced by every configuration), %llu case%s with any hole, false hit, "
               "disagreement or leak; for each configuration, a rate of zero is below %.1f per "
               "million (95%%, over its %llu rays).\n", (unsigned long long)st.robust_rays,
           (unsigned long long)st.distinct_rays, (unsigned long long)st.robust_bad_cases,
           st.robust_bad_cases == 1 ? "" : "s", bound, (unsigned long long)st.distinct_rays);
    exp_md(&x, "\n### Speed on the stiff cases (watertight, Mrays/s, interleaved rounds)\n");
    exp_md_table(&x, "case|Mrays/s per configuration|fastest / slowest (brute aside)");
    exp_md(&x, "%s", exp_text_str(&st.speeds));
    exp_text findings = {0};
    exp_text_add(&findings, "- The watertight kernels: %s over %llu distinct rays in %llu cases "
                 "(%llu ray traces in all; each configuration: fewer than %.1f per million at "
                 "95%%).\n", st.robust_bad_cases ? "SOME CASES FAILED (see the rows above)"
                 : "no hole, false hit, disagreement or leak", (unsigned long long)st.distinct_rays,
                 (unsigned long long)st.cases, (unsigned long long)st.robust_rays, bound);
    exp_text_add(&findings, "- The naive kernels: up to %.0f holes per million rays (%s) and %.0f "
                 "leaks per million leak rays (%s).\n", st.holes.value,
                 st.holes.what.len ? exp_text_str(&st.holes.what) : "none", st.leaks.value,
                 st.leaks.what.len ? exp_text_str(&st.leaks.what) : "none");
    exp_text_add(&findings, "%s", exp_text_str(&st.cliffs));
    self_intersection(&x, &findings);
    exp_md(&x, "\n**Findings:**\n\n%s", exp_text_str(&findings));
    exp_verdict(&x, "stability", !st.robust_bad_cases ? EXP_CONFIRMED
                : st.robust_bad_cases * 2 < st.cases ? EXP_PARTLY : EXP_REFUTED, "every stiff case",
                "watertight kernels: %llu of %llu cases with any hole, false hit, disagreement or "
                "leak (%llu distinct rays, each traced by every configuration; a configuration's "
                "rate below %.1f per million at 95%% if none); naive kernels "
                "up to %.0f holes per million rays and %.0f leaks per million leak rays%s",
                (unsigned long long)st.robust_bad_cases, (unsigned long long)st.cases,
                (unsigned long long)st.distinct_rays, bound, st.holes.value, st.leaks.value,
                st.cliffs.len ? "; performance cliffs: see the findings" : "");
    exp_text_free(&findings);
    exp_text_free(&st.clean);
    exp_text_free(&st.cliffs);
    exp_text_free(&st.speeds);
    exp_text_free(&st.left);
    exp_text_free(&st.holes.what);
    exp_text_free(&st.leaks.what);
    exp_list_free(&base);
    return exp_finish(&x);
}
