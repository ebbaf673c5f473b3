/*
 * exp_time_to_image - build plus trace time against the number of rays.
 *
 * A structure that is slower to build but faster to trace wins once enough
 * rays are traced. With build time B and trace rate R (rays per ms on a
 * primary+diffuse mix, every structure of a scene in interleaved rounds),
 * the time to trace n rays is B + n/R. The fastest way to n rays is the
 * lower envelope of these lines: from n = 0 the structure that builds
 * fastest, then, at each crossing n* = (B2 - B1) / (1/R1 - 1/R2), one that
 * traces faster. A crossing counts only when the two rates differ outside
 * the noise; its interval comes from the ends of the build and rate
 * intervals. Contenders: the regular grid, the nested grid, binned,
 * full-sweep and middle-split BVHs, and (when this build has them) grids
 * with empty-space skipping, the irregular grid and wide BVHs.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/group.h"
#include "engine/svg.h"

#define MASK (BENCH_PRIMARY | BENCH_DIFFUSE)
#define FRAME_1080P 2073600.0

static const char *const wanted[] = {"grid", "nested_grid", "bvh:build=binned", "bvh:build=sah",
                                     "bvh:build=mid", "grid:skip=macro", "irregular_grid",
                                     "bvh:width=4", "bvh:width=8"};

/* build-pays-off, issue 38 (no longer "some crossing exists", which holds
 * by construction): the full-sweep SAH tree, the slowest BVH build, pays
 * off when it joins the lower envelope at a crossing n* of at most
 * PAYOFF_MAX rays (100 frames of 1080p primary rays), on each scene; a
 * scene where it never joins the envelope counts against it. */
#define SWEEP "bvh:build=sah"
#define PAYOFF_MAX (100 * FRAME_1080P)
/* An interval end that never crosses, for the CSV (finite numbers only). */
#define NEVER 1e18

typedef struct {
    exp_tally pay;    /* the sweep's n* on the scenes where it joins the envelope */
    int sweep_scenes, sweep_on; /* scenes with the sweep measured; where it joins */
    exp_text sweep_ev;
    int scenes, with_cross;
    /* scenes where some structure traces faster than the fastest-building
     * one (outside the noise): only there can a slower build pay off */
    int contested;
    exp_text ev, findings, names;
} study;

/* The crossing of a (faster builder) and b (faster tracer) from the ends
 * of their intervals: lo, hi (INFINITY when an end never crosses). */
static double crossing(const exp_est *ba, const exp_est *ra, const exp_est *bb, const exp_est *rb,
                       double *lo, double *hi)
{
    double n = (bb->median - ba->median) / (1 / ra->median - 1 / rb->median);
    *lo = INFINITY, *hi = 0;
    for (int k = 0; k < 16; k++) {
        double b1 = k & 1 ? ba->hi : ba->lo, b2 = k & 2 ? bb->hi : bb->lo;
        double r1 = k & 4 ? ra->hi : ra->lo, r2 = k & 8 ? rb->hi : rb->lo;
        double d = 1 / r1 - 1 / r2, v = d > 0 ? (b2 - b1) / d : INFINITY;
        if (v < 0) v = 0;
        *lo = fmin(*lo, v), *hi = fmax(*hi, v);
    }
    return n < 0 ? 0 : n;
}

/* Long on purpose (134 lines): one scene's build and trace times, break-even
 * table and findings, in the order the report prints them; the steps share
 * the group, its per-configuration arrays and the study's tallies, which
 * separate functions would take as a dozen parameters each. */
static void measure_scene(exp_ctx *x, study *st, const char *spec, const exp_list *list)
{
    accel_scene s;
    char why[600];
    if (exp_scene_try(x, spec, &s, why, sizeof why)) { /* a scene generator not merged yet */
        exp_md(x, "\nLeft out: scene `%s` (not in this build: %s).\n", spec, why);
        exp_note_left(x, EXP_LEFT_UNPARSED);
        return;
    }
    bench_sets sets;
    exp_sets(x, &s, MASK, &sets);
    exp_md(x, "\n### %s (%u primitives)\n", s.name, s.live_count);
    exp_text_add(&st->names, "%s%s", st->names.len ? ", " : "", s.name);
    exp_group g;
    exp_group_init(&g, x, &s, &sets, MASK);
    g.collapse_ms = x->quick ? 500 : 3000;
    for (int i = 0; i < list->count; i++) exp_group_add(&g, list->spec[i], 0);
    exp_group_run(&g);
    double image = (double)(sets.primary.count + sets.diffuse.count);
    exp_md_table(x, "structure|build ms [95% CI]|Mrays/s [95% CI]|ms for one image|"
                    "for 100 images|for one 1080p frame");
    exp_est B[64], R[64];
    int ok[64] = {0}, n = g.count < 64 ? g.count : 64;
    for (int c = 0; c < n; c++) {
        const exp_cfg *cf = &g.cfg[c];
        if (!cf->ok) continue;
        ok[c] = 1;
        B[c] = cf->build_ms;
        R[c] = exp_group_mrays(&g, c, MASK); /* Mrays/s = rays per microsecond = 1e3 rays/ms */
        R[c] = exp_est_scale(&R[c], 1e3);    /* rays per ms */
        char b[96], r[96];
        exp_est mr = exp_est_scale(&R[c], 1e-3);
        exp_md(x, "| `%s` | %s | %s | %.1f | %.0f | %.1f |\n", cf->spec,
               exp_fmt_est(b, sizeof b, &B[c], 1), exp_fmt_est(r, sizeof r, &mr, 2),
               B[c].median + image / R[c].median, B[c].median + 100 * image / R[c].median,
               B[c].median + FRAME_1080P / R[c].median);
        exp_csv(x, "%s,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f,%.3f,%.3f\n", s.name, cf->spec,
                B[c].median, B[c].lo, B[c].hi, mr.median, mr.lo, mr.hi,
                B[c].median + image / R[c].median, B[c].median + 100 * image / R[c].median,
                B[c].median + FRAME_1080P / R[c].median);
    }
    exp_group_note(&g);
    svg_plot pl;
    char title[256], pname[64];
    snprintf(title, sizeof title, "Time to n rays on %s (build + n / rate)", s.name);
    svg_plot_init(&pl, title, "rays traced", "ms");
    pl.log_x = pl.log_y = 1;
    for (int c = 0; c < n; c++) {
        if (!ok[c]) continue;
        double rx[13], ry[13];
        for (int k = 0; k < 13; k++) rx[k] = pow(10, 3 + 0.5 * k), ry[k] = B[c].median + rx[k] / R[c].median;
        svg_add(&pl, g.cfg[c].spec, rx, ry, NULL, NULL, 13, SVG_LINE);
    }
    snprintf(pname, sizeof pname, "time_to_image_%d", st->scenes);
    exp_svg(x, &pl, pname, "Build plus trace time against the number of rays");
    /* The lower envelope, crossing only where the rates differ outside the noise. */
    int cur = -1;
    for (int c = 0; c < n; c++)
        if (ok[c] && (cur < 0 || exp_cmp(&B[c], &B[cur], g.floor) < 0 ||
                      (exp_cmp(&B[c], &B[cur], g.floor) == 0 && R[c].median > R[cur].median)))
            cur = c;
    if (cur < 0) goto done;
    exp_md(x, "\nThe fastest way to n rays (lower envelope of build + n / rate; a crossing "
              "counts when the rates differ outside the noise floor of %.1f%%):\n\n", 100 * g.floor);
    exp_text line = {0};
    exp_text_add(&line, "from 0 rays `%s`", g.cfg[cur].spec);
    int tied = 0;
    for (int c = 0; c < n; c++) tied += ok[c] && c != cur && exp_cmp(&B[c], &B[cur], g.floor) == 0;
    if (tied)
        exp_md(x, "- from 0 rays: `%s` (its build ties with %d other%s within the noise; it traces "
                  "fastest of them)\n", g.cfg[cur].spec, tied, tied > 1 ? "s" : "");
    else
        exp_md(x, "- from 0 rays: `%s` (builds fastest)\n", g.cfg[cur].spec);
    double at = 0;
    int crosses = 0, contender = 0, sweep = exp_group_find(&g, SWEEP), sweep_on = cur == sweep;
    if (cur == sweep && sweep >= 0) { /* it builds fastest too: n* = 0 */
        exp_text_add(&st->sweep_ev, "%s%s: on the envelope from 0 rays", st->sweep_ev.len ? "; " : "",
                     s.name);
        exp_est e = {0, 0, 0, 0, 0, g.cfg[sweep].set[0].n, 0.95, 1, 0, 0};
        exp_decider d = exp_decider_of("rays n* at which the full sweep joins the envelope (0: it "
                                       "builds fastest)", &e, PAYOFF_MAX, -1);
        exp_tally_add(&st->pay, &d);
    }
    for (int c = 0; c < n; c++) contender |= ok[c] && c != cur && exp_cmp(&R[c], &R[cur], g.floor) > 0;
    for (;;) {
        int next = -1;
        double best_n = INFINITY, blo = 0, bhi = 0;
        for (int c = 0; c < n; c++) {
            if (!ok[c] || c == cur || exp_cmp(&R[c], &R[cur], g.floor) <= 0) continue;
            double lo, hi, v = crossing(&B[cur], &R[cur], &B[c], &R[c], &lo, &hi);
            if (v >= at && v < best_n) best_n = v, next = c, blo = lo, bhi = hi;
        }
        if (next < 0) break;
        char range[96];
        if (isinf(bhi)) /* issue 52: an interval over 3x wide is not printed */
            snprintf(range, sizeof range, "(not resolved: from %.3g rays on, or never within "
                     "the intervals)", blo);
        else if (exp_span_unresolved(blo, bhi))
            snprintf(range, sizeof range, "(not resolved: its interval spans more than %.0fx)",
                     EXP_MAX_SPAN);
        else
            snprintf(range, sizeof range, "[%.3g, %.3g]", blo, bhi);
        exp_md(x, "- from %.3g rays %s (%.2f images of %dx%d primary+diffuse rays, %.3f 1080p "
                  "frames): `%s`\n", best_n, range, best_n / image, x->size, x->size,
               best_n / FRAME_1080P, g.cfg[next].spec);
        exp_text_add(&line, ", from %.3g rays %s `%s`", best_n, range, g.cfg[next].spec);
        if (next == sweep) {
            char what[300];
            snprintf(what, sizeof what, "rays n* at which `%s` joins the envelope, %s %u tris, "
                     "primary+diffuse %dx%d", SWEEP, s.name, s.live_count, x->size, x->size);
            exp_est e = {best_n, blo, isinf(bhi) ? NEVER : bhi, blo, bhi, 0, 0.95, 1, 0, 0};
            e.n = g.cfg[next].set[0].n;
            exp_decider d = exp_decider_of(what, &e, PAYOFF_MAX, -1);
            exp_tally_add(&st->pay, &d);
            sweep_on = 1;
            exp_text_add(&st->sweep_ev, "%s%s: joins at %.3g rays %s (%s)", st->sweep_ev.len ? "; " : "",
                         s.name, best_n, range, exp_judge(&d));
        }
        at = best_n, cur = next, crosses++;
    }
    if (sweep >= 0 && sweep < n && ok[sweep]) {
        st->sweep_scenes++, st->sweep_on += sweep_on;
        if (!sweep_on)
            exp_text_add(&st->sweep_ev, "%s%s: never on the envelope", st->sweep_ev.len ? "; " : "",
                         s.name);
    }
    st->scenes++;
    st->with_cross += crosses > 0;
    st->contested += contender;
    if (!contender)
        exp_text_add(&line, " (it also traces fastest: no slower build to pay off)");
    exp_text_add(&st->findings, "- %s: %s.\n", s.name, exp_text_str(&line));
    exp_text_add(&st->ev, "%s%s: %s", st->ev.len ? "; " : "", s.name, exp_text_str(&line));
    exp_text_free(&line);
done:
    exp_group_free(&g);
    bench_sets_free(&sets);
    scene_free(&s);
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_time_to_image",
             "At how many rays does a slower-to-build, faster-to-trace structure overtake a "
             "faster-to-build one?",
             NULL);
    exp_limits(&x, 8, 4);
    exp_header(&x, "Time to image", "\"SAH will double performance, but construction becomes "
               "much slower\": when does a slower build pay?",
               "counting build time, how many rays must be traced before a structure that is "
               "slower to build but faster to trace pays off? Build time B and trace rate R "
               "(primary plus diffuse rays, %dx%d image) with their intervals, every structure of a "
               "scene in interleaved rounds; time(n) = B + n/R. One 1080p frame is 2.07M primary "
               "rays.", x.size, x.size);
    const char *scenes[8];
    int scene_count = 0;
    if (x.quick) {
        scenes[scene_count++] = "soup:tris=5000";
    } else {
        scenes[scene_count++] = "soup:tris=300000";
        scenes[scene_count++] = "teapot_stadium";
        scenes[scene_count++] = "sphereflake";
        for (int i = 0; i < x.mesh_count && scene_count < 7; i++) scenes[scene_count++] = x.meshes[i];
        scenes[scene_count++] = "field"; /* many meshes at many scales, when this build has it */
    }
    scene_count = exp_scene_list(&x, scenes, scene_count, 8);
    exp_csv(&x, "scene,spec,build_ms,build_lo,build_hi,mrays,mrays_lo,mrays_hi,ms_one_image,"
                "ms_100_images,ms_1080p_frame\n");
    exp_list list;
    exp_list_make(&x, wanted, (int)(sizeof wanted / sizeof wanted[0]), NULL, &list);
    study st = {0};
    exp_tally_init(&st.pay, scene_count);
    for (int si = 0; si < scene_count; si++) measure_scene(&x, &st, scenes[si], &list);
    exp_md(&x, "\n**Findings** (the fastest structure for each range of ray counts):\n\n%s",
           exp_text_str(&st.findings));
    if (!st.sweep_scenes) {
        exp_verdict(&x, "build-pays-off", EXP_UNTESTABLE, "-", "`%s` was not measured", SWEEP);
    } else {
        /* Scenes where the sweep never joins the envelope miss; where it
         * joins, its n* against PAYOFF_MAX decides (exp_tally). */
        int off = st.sweep_scenes - st.sweep_on;
        /* claims.h's one rule: a scene where it never joins is a miss */
        const char *words[2] = {st.pay.added ? exp_tally_verdict(&st.pay) : NULL,
                                off ? EXP_REFUTED : NULL};
        const char *v = exp_combine(words, 2, EXP_EVERY);
        const char *fmt = "the full sweep (`%s`), the slowest BVH build, joins the lower envelope "
                          "of build + n / rate on %d of %d scenes, at n* <= %.3g rays (100 1080p "
                          "frames) on %d (%s; every envelope: %s)";
        if (st.pay.added)
            exp_verdict_num(&x, "build-pays-off", v, &st.pay.worst, exp_text_str(&st.names), fmt,
                            SWEEP, st.sweep_on, st.sweep_scenes, PAYOFF_MAX, st.pay.confirmed,
                            exp_text_str(&st.sweep_ev), exp_text_str(&st.ev));
        else
            exp_verdict(&x, "build-pays-off", v, exp_text_str(&st.names), fmt, SWEEP, st.sweep_on,
                        st.sweep_scenes, PAYOFF_MAX, 0, exp_text_str(&st.sweep_ev),
                        exp_text_str(&st.ev));
    }
    exp_text_free(&st.sweep_ev);
    exp_text_free(&st.findings);
    exp_text_free(&st.ev);
    exp_text_free(&st.names);
    exp_list_free(&list);
    return exp_finish(&x);
}
