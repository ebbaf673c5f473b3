/*
 * exp_scaling - how does each accelerator's cost grow with the triangle count?
 *
 * For every registered kind (default parameters; --accel specs join) on
 * `soup` (uniform) and `teapot_stadium` (non-uniform), from a few hundred
 * triangles up to a million or what the budget allows, all kinds of one
 * size in interleaved rounds: build time, memory per triangle, ns per ray
 * on primary plus diffuse rays, steps and primitive tests per ray. The
 * growth exponent k of cost ~ N^k is fitted on the log-log points with
 * its 95% t-interval. The lecture: primary rays cost O(N*M) without
 * acceleration; a structure reduces M.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/group.h"
#include "engine/svg.h"

#define MASK (BENCH_PRIMARY | BENCH_DIFFUSE)
#define MAX_SPECS 24
#define MAX_SIZES 8

typedef struct {
    const char *spec;
    int pts;
    double work[MAX_SIZES]; /* steps plus primitive tests per ray (the counts) */
    double n[MAX_SIZES], build[MAX_SIZES], ns[MAX_SIZES], lo[MAX_SIZES], hi[MAX_SIZES], last_pass_ms;
    int stopped; /* left out at a size: larger sizes are not tried */
    char stop_why[800];
} series;

/* Both claims are decided on the counts, which are exact (issue 52: no
 * time fit decides what the counts prove). accel-sublinear: the work per
 * ray, steps plus primitive tests, grows as N^k with k < SUBLINEAR_MAX on
 * each structure and scene family, k from the smallest to the largest
 * size (an exact number: a least-squares slope over 4-7 deterministic
 * points would carry a t-interval of the curve's bends, not of noise); a
 * series needs MIN_FIT_POINTS sizes. brute-cost: brute force's primitive
 * tests per ray grow as N^k with k >= BRUTE_MIN, k from its counts the
 * same way; its time exponent is quoted beside it. */
#define SUBLINEAR_MAX 1.0
#define BRUTE_MIN 0.85
#define MIN_FIT_POINTS 4

typedef struct {
    exp_tally sub;
    int sub_series; /* series announced for the tally */
    int sub_yes, sub_no, sub_n;
    exp_text sub_ev, findings, cliffs;
    int brute_done;
    exp_est brute_slope;  /* of the time per ray (the co-evidence) */
    double brute_k;       /* of the tests per ray: decides */
    double brute_n0, brute_n1;
} study;

/* The exponent k of y ~ x^k from the first to the last point with x, y > 0
 * (NaN without two): exact when the ys are counts. */
static double end_slope(const double *xs, const double *ys, int n)
{
    int a = -1, b = -1;
    for (int i = 0; i < n; i++)
        if (xs[i] > 0 && ys[i] > 0) {
            if (a < 0) a = i;
            b = i;
        }
    if (a < 0 || b == a || xs[b] == xs[a]) return NAN;
    return log(ys[b] / ys[a]) / log(xs[b] / xs[a]);
}

/* An exponent as "0.12 +- 0.08 (7 sizes, 95%)": on the log scale already,
 * its interval is a difference, not a ratio (a [lo, hi] around a value
 * near 0 would read as a factor). A fit's t-interval has n - 2 degrees of
 * freedom: under 5 (7 sizes) it is not printed (issue 52). */
static const char *fmt_exponent(char *buf, size_t n, const exp_est *k)
{
    if (k->n >= 7 && k->hi > k->lo)
        snprintf(buf, n, "%.2f +- %.2f (%d sizes, 95%%)", k->median, (k->hi - k->lo) / 2, k->n);
    else
        snprintf(buf, n, "%.2f (%d sizes: too few for an interval)", k->median, k->n);
    return buf;
}

/* An exact number as a decider (n 1: judged as a point, exp_judge). */
static exp_decider exact_decider(const char *what, double k, double threshold, int sense)
{
    exp_decider d = {what, k, k, k, threshold, sense, 1};
    return d;
}

/* Long on purpose (130 lines): one scene family's sizes: runs, fits, table
 * and findings, in the order the report prints them; the steps share the
 * group, its per-configuration arrays and the study's tallies, which
 * separate functions would take as a dozen parameters each. */
static void family(exp_ctx *x, study *st, int f, const exp_list *list)
{
    static const char *const names[2] = {"soup", "teapot_stadium"};
    static const int soup_full[] = {250, 1000, 4000, 16000, 64000, 256000, 1000000};
    static const int teapot_full[] = {4, 8, 16, 32, 64, 128};
    static const int soup_quick[] = {250, 1000, 4000}, teapot_quick[] = {2, 8};
    const int *sizes = f == 0 ? (x->quick ? soup_quick : soup_full) : (x->quick ? teapot_quick : teapot_full);
    int nsz = f == 0 ? (x->quick ? 3 : 7) : (x->quick ? 2 : 6);
    double limit_ms = x->quick ? 300 : 4000; /* the longest pass worth a size */
    series se[MAX_SPECS] = {{0}};
    int ns = list->count < MAX_SPECS ? list->count : MAX_SPECS;
    for (int k = 0; k < ns; k++) se[k].spec = list->spec[k];
    exp_md(x, "\n### %s\n", names[f]);
    exp_md_table(x, "configuration|triangles|build ms [95% CI]|MB|B/tri|ns/ray [95% CI]|"
                    "steps/ray|prims/ray");
    for (int z = 0; z < nsz; z++) {
        char spec[64];
        snprintf(spec, sizeof spec, f == 0 ? "soup:tris=%d"
                                  : x->quick ? "teapot_stadium:n=%d,stadium=32,tiers=4"
                                             : "teapot_stadium:n=%d", sizes[z]);
        accel_scene s;
        exp_scene(x, spec, &s);
        bench_sets sets;
        exp_sets(x, &s, MASK, &sets);
        exp_group g;
        exp_group_init(&g, x, &s, &sets, MASK);
        g.collapse_ms = limit_ms;
        int idx[MAX_SPECS];
        for (int k = 0; k < ns; k++) {
            idx[k] = -1;
            if (se[k].stopped) continue;
            /* O(N) per ray: the next size's pass from the last one's. */
            double ratio = z ? (double)s.live_count / se[k].n[se[k].pts ? se[k].pts - 1 : 0] : 1;
            if (se[k].pts && se[k].last_pass_ms * ratio > limit_ms && !strcmp(se[k].spec, "brute")) {
                snprintf(se[k].stop_why, sizeof se[k].stop_why, "from %u triangles on: a pass "
                         "would take about %.0f s (O(N) per ray)", s.live_count,
                         se[k].last_pass_ms * ratio / 1e3);
                se[k].stopped = 1;
                exp_note_left(x, EXP_LEFT_POINTLESS);
                continue;
            }
            idx[k] = exp_group_add(&g, se[k].spec, 0);
        }
        exp_group_run(&g);
        for (int k = 0; k < ns; k++) {
            if (idx[k] < 0) continue;
            const exp_cfg *cf = &g.cfg[idx[k]];
            if (!cf->ok) {
                snprintf(se[k].stop_why, sizeof se[k].stop_why, "from %u triangles on: %s",
                         s.live_count, cf->why);
                se[k].stopped = 1;
                continue;
            }
            exp_est e = exp_group_ns(&g, idx[k], MASK);
            char b[96], t[96];
            exp_md(x, "| `%s` | %u | %s | %.1f | %.0f | %s | %.1f | %.1f |\n", cf->spec,
                   s.live_count, exp_fmt_est(b, sizeof b, &cf->build_ms, 1),
                   cf->build.bytes / 1048576.0, (double)cf->build.bytes / s.live_count,
                   exp_fmt_est(t, sizeof t, &e, 0), exp_group_steps(&g, idx[k], MASK),
                   exp_group_prims(&g, idx[k], MASK));
            exp_csv(x, "%s,%s,%u,%.4f,%.4f,%.4f,%zu,%.2f,%.3f,%.3f,%.3f,%.3f,%.3f\n", names[f],
                    cf->spec, s.live_count, cf->build_ms.median, cf->build_ms.lo, cf->build_ms.hi,
                    cf->build.bytes, (double)cf->build.bytes / s.live_count, e.median, e.lo, e.hi,
                    exp_group_steps(&g, idx[k], MASK), exp_group_prims(&g, idx[k], MASK));
            series *q = &se[k];
            q->n[q->pts] = s.live_count, q->build[q->pts] = cf->build_ms.median, q->ns[q->pts] = e.median;
            q->lo[q->pts] = e.lo, q->hi[q->pts] = e.hi;
            q->work[q->pts] = exp_group_steps(&g, idx[k], MASK) + exp_group_prims(&g, idx[k], MASK);
            q->last_pass_ms = cf->counted_ms;
            if (q->pts && q->ns[q->pts] > 3 * q->ns[q->pts - 1] * pow(q->n[q->pts] / q->n[q->pts - 1], 0.5))
                exp_text_add(&st->cliffs, "- `%s` on %s: %.0f ns per ray at %.0f triangles, %.0f at "
                             "%.0f: a cliff, not a growth law.\n", q->spec, names[f],
                             q->ns[q->pts - 1], q->n[q->pts - 1], q->ns[q->pts], q->n[q->pts]);
            q->pts++;
        }
        exp_group_free(&g);
        bench_sets_free(&sets);
        scene_free(&s);
    }
    svg_plot pl;
    char title[128], name[64];
    snprintf(title, sizeof title, "Scaling on %s: ns per ray against triangles", names[f]);
    svg_plot_init(&pl, title, "triangles", "ns per ray (primary + diffuse)");
    pl.log_x = pl.log_y = 1;
    for (int k = 0; k < ns; k++) {
        series *q = &se[k];
        if (q->pts < 2) continue;
        exp_est kt;
        double a, fx[2] = {q->n[0], q->n[q->pts - 1]}, fy[2];
        exp_loglog_slope(q->n, q->ns, q->pts, &kt, &a);
        fy[0] = exp(a) * pow(fx[0], kt.median), fy[1] = exp(a) * pow(fx[1], kt.median);
        char fit[200];
        snprintf(fit, sizeof fit, "%s fit N^%.2f", q->spec, kt.median);
        svg_add(&pl, q->spec, q->n, q->ns, q->lo, q->hi, q->pts, SVG_POINTS);
        svg_add(&pl, fit, fx, fy, NULL, NULL, 2, SVG_DASHED);
    }
    snprintf(name, sizeof name, "scaling_%s", names[f]);
    exp_svg(x, &pl, name, "Time per ray against the triangle count (medians with 95% intervals; "
            "dashed: the least-squares power law)");
    exp_md(x, "\nGrowth exponents (least squares on the log-log points, +- the half-width of "
              "the 95%% t-interval):\n");
    exp_md_table(x, "configuration|triangles|build time ~ N^k|trace time per ray ~ N^k");
    for (int k = 0; k < ns; k++) {
        series *q = &se[k];
        if (q->pts < 2) continue;
        exp_est kb, kt;
        exp_loglog_slope(q->n, q->build, q->pts, &kb, NULL);
        exp_loglog_slope(q->n, q->ns, q->pts, &kt, NULL);
        char a[96], b[96];
        exp_md(x, "| `%s` | %.0f to %.0f | %s | %s |\n", q->spec, q->n[0], q->n[q->pts - 1],
               fmt_exponent(a, sizeof a, &kb), fmt_exponent(b, sizeof b, &kt));
        exp_text_add(&st->findings, "- `%s` on %s: build time grows as N^%s, trace time per ray as "
                     "N^%s.\n", q->spec, names[f], a, b);
        if (!strcmp(q->spec, "brute")) {
            if (f == 0) {
                st->brute_done = 1, st->brute_slope = kt;
                st->brute_k = end_slope(q->n, q->work, q->pts);
                st->brute_n0 = q->n[0], st->brute_n1 = q->n[q->pts - 1];
            }
        } else if (q->pts >= (x->quick ? 3 : MIN_FIT_POINTS)) {
            double kw = end_slope(q->n, q->work, q->pts);
            char what[300];
            snprintf(what, sizeof what, "exponent k of steps+tests per ray ~ N^k (exact, from the "
                     "counts), `%s` on %s, %.0f to %.0f tris, %d sizes", q->spec, names[f], q->n[0],
                     q->n[q->pts - 1], q->pts);
            exp_decider d = exact_decider(what, kw, SUBLINEAR_MAX, -1);
            exp_tally_add(&st->sub, &d);
            st->sub_n++;
            exp_text_add(&st->sub_ev, "%s%s on %s: counts N^%.2f (%s), time N^%s",
                         st->sub_ev.len ? "; " : "", q->spec, names[f], kw, exp_judge(&d), b);
        }
    }
    for (int k = 0; k < ns; k++)
        if (se[k].stopped) exp_md(x, "\nLeft out: `%s` %s.\n", se[k].spec, se[k].stop_why);
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_scaling",
             "How do build time, memory and trace time grow with the triangle count, per "
             "accelerator?",
             NULL);
    exp_limits(&x, 0, EXP_MAX_MESHES);
    exp_scenes_unused(&x, "its question needs scenes of growing size (soup, teapot_stadium)");
    /* Builds of the 256k and 1M sizes take 0.1-1 s: 0.6 s of interleaved
     * builds per configuration gives them 1-6 samples (the growth fit
     * rests on seven sizes, not on one size's interval; no verdict rests
     * on build time here, nor on one size's trace time: accel-sublinear is
     * decided by the counts, brute-cost by the fit over the sizes). */
    if (!x.quick) x.build_budget_ms = 600, x.set_budget_ms = 400;
    exp_header(&x, "Scaling with scene size", "\"Primary rays cost O(N\xc2\xb7M) without "
               "acceleration\"; structures \"reduce M\"",
               "how do build time, memory and trace time per ray grow with the number of "
               "triangles M, for each accelerator? Scenes: `soup` (uniform random triangles) and "
               "`teapot_stadium` (a teapot in a stadium: non-uniform), default parameters of every "
               "kind, %dx%d primary rays and one diffuse bounce, all kinds of one size in "
               "interleaved rounds.", x.size, x.size);
    exp_csv(&x, "scene,spec,tris,build_ms,build_lo,build_hi,bytes,bytes_per_tri,ns_per_ray,ns_lo,"
                "ns_hi,steps_per_ray,prims_per_ray\n");
    const char *kinds[MAX_SPECS];
    int nk = 0;
    for (size_t k = 0; k < accel_kind_count && nk < MAX_SPECS; k++) kinds[nk++] = accel_kinds[k]->name;
    /* beside the defaults: the fastest kind, and the grid on its old per-id
     * cells (the kernel's share of the grid's speed, issue 49) */
    kinds[nk++] = "bvh:width=8";
    kinds[nk++] = "grid:cells=ids";
    exp_list list;
    exp_list_make(&x, kinds, nk, NULL, &list);
    study st = {0};
    /* Every structure on both families (brute excluded): the tally's m. */
    int structures = 0;
    for (int k = 0; k < list.count && k < MAX_SPECS; k++) structures += strcmp(list.spec[k], "brute") != 0;
    exp_tally_init(&st.sub, 2 * structures);
    for (int f = 0; f < 2; f++) family(&x, &st, f, &list);
    exp_md(&x, "\n**Findings:**\n\n%s%s", exp_text_str(&st.findings), exp_text_str(&st.cliffs));
    exp_md(&x, "\nA structure whose trace cost grows as N^0.1-0.3 is doing its job (ideal: log N); "
               "brute force grows as N^1.\n");
    char b[96];
    if (st.brute_done && st.brute_k == st.brute_k) {
        char what[200];
        snprintf(what, sizeof what, "exponent k of brute force's primitive tests per ray ~ N^k "
                 "(exact, from the counts), soup %.0f to %.0f tris", st.brute_n0, st.brute_n1);
        exp_decider d = exact_decider(what, st.brute_k, BRUTE_MIN, +1);
        exp_verdict_num(&x, "brute-cost", exp_judge(&d), &d, "soup",
                        "brute force tests N^%.3f triangles per ray (threshold: k >= %.2f); its "
                        "time per ray grows as N^%s over the same sizes (the co-evidence: the "
                        "fixed per-ray cost weighs at small N)", st.brute_k, BRUTE_MIN,
                        fmt_exponent(b, sizeof b, &st.brute_slope));
    } else
        exp_verdict(&x, "brute-cost", EXP_UNTESTABLE, "-", "brute force was not measured at two sizes");
    if (st.sub.added)
        exp_verdict_num(&x, "accel-sublinear", exp_tally_verdict(&st.sub), &st.sub.worst,
                        "soup, teapot_stadium",
                        "steps plus primitive tests per ray (the counts, not times) grow as N^k "
                        "with k < %.1f on each of %d structure and scene series of %d+ sizes (k "
                        "from the smallest to the largest size: exact): %d confirm, %d miss, %d "
                        "on the line (%s)%s", SUBLINEAR_MAX, st.sub.added, MIN_FIT_POINTS,
                        st.sub.confirmed, st.sub.refuted,
                        st.sub.online, exp_text_str(&st.sub_ev),
                        st.cliffs.len ? "; cliffs: see the findings" : "");
    else
        exp_verdict(&x, "accel-sublinear", EXP_UNTESTABLE, "-", "no structure was measured at %d "
                    "sizes", MIN_FIT_POINTS);
    exp_text_free(&st.findings);
    exp_text_free(&st.cliffs);
    exp_text_free(&st.sub_ev);
    exp_list_free(&list);
    return exp_finish(&x);
}
