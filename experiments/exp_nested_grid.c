/*
 * exp_nested_grid - does nesting fix the regular grid, and can its tweaking
 * be removed?
 *
 * On a uniform scene (soup) and non-uniform ones (teapot in a stadium,
 * sphereflake, scanned meshes), in interleaved rounds: the regular grid
 * swept over lambda = 1..256 (its best, with ties, is the grid's answer),
 * the nested grid at its defaults, at hand-set parameters and in its
 * `auto` mode (cost-model driven), and BVHs for scale. The lecture says
 * nested grids adapt to local complexity "but resolutions still require
 * manual tweaking": the first is tested against the best regular grid on
 * the non-uniform scenes, the second by asking whether the defaults or
 * `auto` tie with the best hand-set configuration.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/group.h"

#define MASK (BENCH_PRIMARY | BENCH_DIFFUSE)

/* The nested grid's hand-set parameters (the default first); then the
 * configurations that set it in context. Specs this build lacks (the
 * irregular grid, empty-space skipping) are left out with their reason. */
static const char *const hand_full[] = {
    "nested_grid",
    "nested_grid:lambda=0.5",
    "nested_grid:lambda=8",
    "nested_grid:sub_lambda=2",
    "nested_grid:sub_lambda=16",
    "nested_grid:threshold=4",
    "nested_grid:threshold=32",
    "nested_grid:depth=2",
    "nested_grid:lambda=0.5,sub_lambda=8,threshold=8",
    "nested_grid:lambda=8,sub_lambda=2,threshold=32,depth=2"};
static const char *const hand_quick[] = {"nested_grid", "nested_grid:depth=2"};
static const char *const others[] = {"nested_grid:auto", "bvh", "bvh:build=sah", "irregular_grid",
                                     "grid:skip=macro", "grid:skip=cloud"};

/* Issue 38's numbers. nested-adapts: the best nested grid's speed-up
 * over the best regular grid >= 1.0 on each non-uniform scene.
 * nested-tweaking: the defaults' time over the best hand-set nested
 * grid's above TWEAK_GAIN (a tweak that gains less than 5% is not
 * "required"). Both bests are chosen on the group's rounds and judged in
 * a decider pass (issue 52; group.h: exp_group_duel). */
#define TWEAK_GAIN 1.05

typedef struct {
    exp_tally ad, tw;
    int collapsed_adapts; /* non-uniform scenes where every regular grid collapsed */
    int d, a, t, adapts, nonuniform;
    int duel_procs, duel_rounds; /* the last decider pass's shape (duel) */
    exp_text tweak_ev, adapt_ev, findings, scenes;
} study;

/* The best configuration among [lo, hi) whose spec starts with prefix. */
static int best_of(const exp_group *g, const char *prefix, int lo, int hi)
{
    return exp_group_best(g, MASK, lo, hi, prefix);
}

/* time(a) / time(b) at level, judged in a decider pass (group.h:
 * exp_group_duel). */
static exp_est duel(const exp_group *g, int a, int b, double level, study *st)
{
    exp_group d;
    exp_group_duel(g, a, b, MASK, 0, &d);
    exp_est e = exp_group_speedup_level(&d, 0, 1, MASK, level);
    st->duel_procs = d.procs, st->duel_rounds = d.per_proc;
    exp_group_duel_free(&d);
    return e;
}

/* c against b: "+12.0% [...]" of time, and whether they tie. */
static int vs(const exp_group *g, int c, int b, char *buf, size_t n)
{
    exp_est r = exp_group_speedup(g, c, b, MASK);
    exp_fmt_pct(buf, n, &r);
    return exp_ratio_cmp(&r, g->floor);
}

/* Long on purpose (122 lines): one scene's nested-grid runs, tables and
 * findings, in the order the report prints them; the steps share the group,
 * its per-configuration arrays and the study's tallies, which separate
 * functions would take as a dozen parameters each. */
static void measure_scene(exp_ctx *x, study *st, const char *spec, const exp_list *ctx_specs)
{
    static const double lambdas_full[] = {1, 2, 4, 8, 16, 32, 64, 128, 256};
    static const double lambdas_quick[] = {1, 8, 64};
    const double *ls = x->quick ? lambdas_quick : lambdas_full;
    int nl = x->quick ? 3 : 9;
    const char *const *hands = x->quick ? hand_quick : hand_full;
    int nh = x->quick ? 2 : 10;
    accel_scene s;
    bench_sets sets;
    exp_scene_section(x, spec, &s, MASK, exp_tiles_stride(x), &sets);
    exp_group g;
    exp_group_init(&g, x, &s, &sets, MASK);
    g.collapse_ms = x->quick ? 500 : 1500;
    /* nested-adapts and nested-tweaking are decided here, each best chosen
     * on the group's rounds and judged in a decider pass (exp_group_duel:
     * the two timed back to back in fresh processes). Judged on half the
     * group's rounds instead, with 6 rounds per process, bunny's interval
     * read [0.95, 1.28] in one of three runs of one commit: a dozen
     * configurations lay between the two in every round. */
    g.time_builds = 0; /* the table shows one build time; no verdict rests on it */
    int hand_lo = 0;
    if (exp_kind_wanted(x, "nested_grid"))
        for (int i = 0; i < nh; i++) exp_group_add(&g, hands[i], 0);
    int hand_hi = g.count;
    if (exp_kind_wanted(x, "grid"))
        for (int i = 0; i < nl; i++) {
            char sp[64];
            /* the nested grid's own kernel (its default cells=ids): the
             * comparison is of structures, not of triangle tests */
            snprintf(sp, sizeof sp, "grid:cells=ids,lambda=%g", ls[i]);
            exp_group_add(&g, sp, 0);
        }
    int grid_hi = g.count;
    for (int i = 0; i < ctx_specs->count; i++) exp_group_add(&g, ctx_specs->spec[i], 0);
    exp_group_run(&g);
    int all = best_of(&g, "", 0, g.count);
    exp_md_table(x, "configuration|ns/ray [95% CI]|vs the scene's best|cells or nodes/ray|"
                    "prims/ray|build ms|MB|B/prim");
    for (int c = 0; c < g.count && all >= 0; c++) {
        const exp_cfg *cf = &g.cfg[c];
        if (!cf->ok) continue;
        exp_est e = exp_group_ns(&g, c, MASK);
        char m[96], v[128];
        exp_fmt_est(m, sizeof m, &e, 0);
        if (c == all)
            snprintf(v, sizeof v, "best");
        else if (vs(&g, c, all, v, sizeof v) == 0)
            strcat(v, " (tie)");
        /* Bytes per primitive: the whole structure, duplicated references
         * (and a block grid's blocks) included. */
        const double bpp = (double)cf->build.bytes / (s.live_count ? (double)s.live_count : 1.0);
        exp_md(x, "| `%s` | %s | %s | %.1f | %.1f | %.1f | %.1f | %.0f |\n", cf->spec, m, v,
               exp_group_steps(&g, c, MASK), exp_group_prims(&g, c, MASK), cf->build_ms.median,
               cf->build.bytes / 1048576.0, bpp);
        exp_csv(x, "%s,%s,%.3f,%.3f,%.3f,%.3f,%.3f,%.4f,%.4f,%.1f\n", s.name, cf->spec, e.median,
                e.lo, e.hi, exp_group_steps(&g, c, MASK), exp_group_prims(&g, c, MASK),
                cf->build_ms.median, cf->build.bytes / 1048576.0, bpp);
    }
    exp_group_note(&g);
    exp_text_add(&st->scenes, "%s%s", st->scenes.len ? ", " : "", s.name);
    /* issue 52: every best chosen on the group's rounds, every decider
     * judged in its own decider pass (duel) */
    int bg = best_of(&g, "grid:cells=ids,lambda=", hand_hi, grid_hi), bh = best_of(&g, "", hand_lo, hand_hi);
    int au = exp_group_find(&g, "nested_grid:auto"), df = hand_hi > hand_lo ? hand_lo : -1;
    if (au >= 0 && !g.cfg[au].ok) au = -1;
    if (df >= 0 && !g.cfg[df].ok) df = -1;
    int nonuniform = strncmp(s.name, "soup", 4) != 0;
    char a[128], b[128];
    int bv = best_of(&g, "bvh", grid_hi, g.count);
    exp_group_compare_head(&g);
    /* Adapts: the best nested grid (hand-set or auto) against the best regular grid. */
    int bn = bh;
    if (au >= 0 && (bn < 0 || exp_group_ns(&g, au, MASK).median < exp_group_ns(&g, bn, MASK).median))
        bn = au;
    if (bn >= 0) {
        if (bg >= 0) {
            int cmp = exp_group_compare(&g, bn, bg, MASK, a, sizeof a);
            exp_text_add(&st->findings, "- %s: the best nested grid `%s` against the best regular "
                         "grid `%s`: time %s.\n", s.name, g.cfg[bn].spec, g.cfg[bg].spec, a);
            if (nonuniform) {
                st->nonuniform++;
                st->adapts += cmp < 0;
                char what[400];
                snprintf(what, sizeof what, "best nested / best regular grid speed-up, %s %u tris, "
                         "primary+diffuse %dx%d (1 in %d tiles)", s.name, s.live_count, x->rt_size[0],
                         x->rt_size[1], exp_tiles_stride(x));
                exp_est e = duel(&g, bg, bn, exp_tally_level(&st->ad), st);
                exp_decider d = exp_decider_of(what, &e, 1.0, +1);
                exp_tally_add(&st->ad, &d);
                char j[96];
                exp_text_add(&st->adapt_ev, "%s%s %s, judged back to back %s", st->adapt_ev.len
                             ? "; " : "", s.name, a, exp_fmt_x(j, sizeof j, &e));
            }
        } else if (nonuniform) {
            /* Every regular grid collapsed: a nested grid that ran adapts. */
            st->nonuniform++, st->adapts++, st->collapsed_adapts++;
            exp_text_add(&st->findings, "- %s: every regular grid collapsed (left out above); "
                         "the nested grid `%s` traces normally.\n", s.name, g.cfg[bn].spec);
            exp_text_add(&st->adapt_ev, "%s%s: every regular grid collapsed", st->adapt_ev.len ? "; " : "",
                         s.name);
        }
    }
    /* Tweaking: the defaults and auto against the best nested grid of all
     * (hand-set or auto), ties included. */
    if (bn >= 0 && df >= 0) {
        int dcmp = df == bn ? 0 : exp_group_compare(&g, df, bn, MASK, a, sizeof a);
        int acmp = au >= 0 ? (au == bn ? 0 : exp_group_compare(&g, au, bn, MASK, b, sizeof b)) : 1;
        const char *cls;
        if (dcmp == 0)
            st->d++, cls = "the defaults tie with the best: no tweaking needed";
        else if (acmp == 0)
            st->a++, cls = "the defaults lose; `auto` finds the best without a hand";
        else
            st->t++, cls = "only a hand-set configuration reaches the best";
        exp_text_add(&st->findings, "- %s: the best nested grid is `%s`; time of the defaults %s, "
                     "of `auto` %s: %s.\n", s.name, g.cfg[bn].spec, df == bn ? "(the same)" : a,
                     au < 0 ? "(not measured)" : au == bn ? "(the same)" : b, cls);
        char judged[96] = "";
        if (bh >= 0) {
            char what[400];
            snprintf(what, sizeof what, "defaults / best hand-set nested grid time, %s %u tris, "
                     "primary+diffuse %dx%d (1 in %d tiles)", s.name, s.live_count, x->rt_size[0],
                     x->rt_size[1], exp_tiles_stride(x));
            exp_est e = df == bh ? (exp_est){0} : duel(&g, df, bh, exp_tally_level(&st->tw), st);
            exp_decider d = exp_decider_of(what, &e, TWEAK_GAIN, +1);
            /* The defaults are the best hand-set configuration: the ratio
             * is 1 exactly (no interval to take), and tweaking gains
             * nothing over them. */
            if (df == bh) {
                snprintf(what + strlen(what), sizeof what - strlen(what), " (the defaults are the "
                         "best hand-set configuration: exactly 1)");
                d = (exp_decider){what, 1.0, 1.0, 1.0, TWEAK_GAIN, +1, 1};
            }
            exp_tally_add(&st->tw, &d);
            if (df != bh)
                exp_fmt_x(judged, sizeof judged, &e);
        }
        exp_text_add(&st->tweak_ev, "%s%s: defaults %s, auto %s%s%s", st->tweak_ev.len ? "; " : "",
                     s.name, df == bn ? "best" : a, au < 0 ? "n/a" : au == bn ? "best" : b,
                     judged[0] ? ", the defaults over the best hand-set judged back to back " : "",
                     judged);
    }
    if (bv >= 0 && bn >= 0) {
        exp_group_compare(&g, bv, bn, MASK, a, sizeof a);
        exp_text_add(&st->findings, "- %s: `%s` against the best nested grid: time %s.\n",
                     s.name, g.cfg[bv].spec, a);
    }
    exp_group_free(&g);
    bench_sets_free(&sets);
    scene_free(&s);
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_nested_grid",
             "Does a nested grid beat the best regular grid on non-uniform scenes, and does it "
             "still need hand-set parameters?",
             NULL);
    exp_limits(&x, 8, 2);
    exp_header(&x, "Nested grids",
               "a nested grid \"adapts to local scene complexity, but resolutions still require "
               "manual tweaking\"",
               "on uniform and non-uniform scenes, how does the nested grid compare with the "
               "regular grid at its best lambda (swept to 256), do its defaults or its `auto` mode "
               "(resolutions chosen by the cost model) tie with the best hand-set parameters, and "
               "where do BVHs stand? ns per ray over the primary rays of one in %d of the 8x8 "
               "tiles of a %dx%d image (its density and coherence at the work of %dx%d) plus one "
               "diffuse bounce, every configuration of a scene in interleaved rounds; \"vs the "
               "scene's best\" is the paired ratio of times.", exp_tiles_stride(&x), x.rt_size[0],
               x.rt_size[1], x.size, x.size);
    if (!accel_find_kind("nested_grid") || !exp_kind_wanted(&x, "nested_grid")) {
        exp_md(&x, "\nLeft out: no `nested_grid` kind in this run.\n");
        exp_verdict(&x, "nested-tweaking", EXP_UNTESTABLE, "-", "no nested_grid kind in this run");
        return exp_finish(&x);
    }
    const char *scenes[8];
    int scene_count = 0;
    if (x.quick) {
        scenes[scene_count++] = "teapot_stadium:n=4,stadium=32,tiers=4";
    } else {
        scenes[scene_count++] = "soup:tris=200000";
        scenes[scene_count++] = "teapot_stadium:n=16";
        scenes[scene_count++] = "sphereflake";
        for (int i = 0; i < x.mesh_count && scene_count < 5; i++) scenes[scene_count++] = x.meshes[i];
    }
    scene_count = exp_scene_list(&x, scenes, scene_count, 8);
    exp_csv(&x, "scene,spec,ns_per_ray,ns_lo,ns_hi,steps_per_ray,prims_per_ray,build_ms,mb,"
                "bytes_per_prim\n");
    exp_list ctx;
    exp_list_make(&x, others, (int)(sizeof others / sizeof others[0]), NULL, &ctx);
    study st = {0};
    exp_tally_init(&st.ad, scene_count), exp_tally_init(&st.tw, scene_count);
    for (int si = 0; si < scene_count; si++) measure_scene(&x, &st, scenes[si], &ctx);
    exp_md(&x, "\n**Findings:**\n\n%s", exp_text_str(&st.findings));
    if (st.tw.added)
        exp_verdict_num(&x, "nested-tweaking", exp_tally_verdict(&st.tw), &st.tw.worst,
                        exp_text_str(&st.scenes),
                        "\"requires manual tweaking\" read as the defaults' time more than %.2fx "
                        "the best hand-set nested grid's, on each of %d scenes (intervals at "
                        "%.2f%%, Bonferroni, each judged in a decider pass: the two timed back to "
                        "back in fresh processes): %d confirm, %d miss, %d on the line; `auto` ties "
                        "with the best on %d (time against the best: %s)", TWEAK_GAIN, st.tw.added,
                        100 * exp_tally_level(&st.tw), st.tw.confirmed, st.tw.refuted,
                        st.tw.online, st.a, exp_text_str(&st.tweak_ev));
    else
        exp_verdict(&x, "nested-tweaking", EXP_UNTESTABLE, "-", "no hand-set configuration ran");
    if (st.ad.added) {
        const char *v = exp_tally_verdict(&st.ad);
        exp_verdict_num(&x, "nested-adapts", v, &st.ad.worst, exp_text_str(&st.scenes),
                        "the best nested grid faster than the best regular grid (speed-up >= "
                        "1.0) on each of %d non-uniform scenes (intervals at %.2f%%, Bonferroni): "
                        "%d confirm, %d miss, %d on the line; every regular grid collapsed on %d "
                        "more (time against the grid, then the speed-up judged in a decider pass: "
                        "the two timed back to back, A B then B A, in %d fresh processes of %d "
                        "rounds: %s)", st.ad.added,
                        100 * exp_tally_level(&st.ad), st.ad.confirmed, st.ad.refuted,
                        st.ad.online, st.collapsed_adapts, st.duel_procs, st.duel_rounds,
                        exp_text_str(&st.adapt_ev));
    } else if (st.collapsed_adapts)
        exp_verdict(&x, "nested-adapts", EXP_CONFIRMED, exp_text_str(&st.scenes),
                    "every regular grid collapsed on the %d non-uniform scenes, the nested grid "
                    "traced (%s)", st.collapsed_adapts, exp_text_str(&st.adapt_ev));
    else
        exp_verdict(&x, "nested-adapts", EXP_UNTESTABLE, "-",
                    "no non-uniform scene with both a nested and a regular grid in this run");
    exp_text_free(&st.findings);
    exp_text_free(&st.tweak_ev);
    exp_text_free(&st.adapt_ev);
    exp_text_free(&st.scenes);
    exp_list_free(&ctx);
    return exp_finish(&x);
}
