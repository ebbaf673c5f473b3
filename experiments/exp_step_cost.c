/*
 * exp_step_cost - what does one traversal step and one primitive test cost
 * on this machine, per kind, and does the lecture's cost model predict
 * trace time? (Issue 39's first question, issue 38's cost-model test.)
 *
 * Model (lecture, section 2): time per ray = C_step * N_steps +
 * C_intersect * N_intersect, plus C_ray, a fixed cost per ray (ray setup,
 * the root box, writing the hit) fitted too so that it does not bias the
 * two slopes. Every registered kind gets a family of configurations that
 * trades steps against tests (grid resolutions, nested-grid thresholds,
 * irregular-grid top resolutions, BVH leaf sizes and node costs for the
 * binary, 4-wide, 8-wide and packet BVHs, the two-level kind's leaf size),
 * all traced on each scene in interleaved rounds; the three costs are
 * fitted by non-negative least squares per family, scene AND ray type
 * (primary, shadow, diffuse: coherent and incoherent rays use the caches
 * differently, and pooling them fits neither). Each fit is validated by
 * leaving one configuration out: the fit on the others predicts it, and
 * the held-out error is what the model is worth on a configuration it has
 * not seen. A family whose configurations barely move the two counts (no
 * fit can separate them) is named with its spreads, never fitted.
 *
 * Beside the fits, micro-benchmarks hot in L1 (a few triangles, boxes or
 * cells, repeated; ns per operation): the watertight triangle test of
 * core/prim.h, the slab test of a binary node's two child boxes, and one
 * 3D-DDA cell step (Amanatides and Woo, "A Fast Voxel Traversal Algorithm
 * for Ray Tracing", Eurographics 1987) with a cell read. They bound the
 * fitted constants from below: a kernel's step also misses caches,
 * mispredicts and keeps a stack.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/prim.h"
#include "engine/group.h"
#include "step_micro.h"
#include "engine/svg.h"

/* The families: a spec belongs to the family of its kind, width and
 * traversal; --accel specs join theirs (a new one starts a family). */
static const char *const default_specs[] = {
    "grid:lambda=0.25", "grid:lambda=1", "grid:lambda=4", "grid:lambda=16", "grid:lambda=64",
    /* the per-id cells: the kernel's share of the grid's cost */
    "grid:cells=ids,lambda=0.25", "grid:cells=ids,lambda=1", "grid:cells=ids,lambda=4",
    "grid:cells=ids,lambda=16", "grid:cells=ids,lambda=64",
    "nested_grid:lambda=0.25", "nested_grid:lambda=1", "nested_grid", "nested_grid:lambda=16",
    "nested_grid:lambda=64",
    "irregular_grid:top_lambda=0.25", "irregular_grid:top_lambda=1", "irregular_grid:top_lambda=4",
    "irregular_grid:top_lambda=16", "irregular_grid:top_lambda=64",
    /* instanced over walked binary bvh bottoms, all meeting triangles one by one (its
     * default, the 8-wide levels on blocks, cannot vary its leaves: one point) */
    "instanced:bottom=bvh:leaf=1", "instanced:bottom=bvh:leaf=4", "instanced:bottom=bvh:leaf=32;ct=4",
    "instanced:bottom=bvh:leaf=64;ct=16", "instanced:bottom=bvh:leaf=256;ct=64",
    "bvh:leaf=1", "bvh", "bvh:leaf=32,ct=4", "bvh:leaf=64,ct=16", "bvh:leaf=256,ct=64",
    "bvh:width=4,leaf=1", "bvh:width=4,leaf=8,ct=2", "bvh:width=4,leaf=16,ct=2", "bvh:width=4,leaf=32,ct=4",
    "bvh:width=4,leaf=64,ct=16", "bvh:width=4,leaf=128,ct=32",
    "bvh:width=8,leaf=1", "bvh:width=8,leaf=8,ct=2", "bvh:width=8,leaf=16,ct=2", "bvh:width=8,leaf=32,ct=4",
    "bvh:width=8,leaf=64,ct=16", "bvh:width=8,leaf=128,ct=32",
    "bvh:traverse=packet,leaf=1", "bvh:traverse=packet", "bvh:traverse=packet,leaf=32,ct=4",
    "bvh:traverse=packet,leaf=64,ct=16", "bvh:traverse=packet,leaf=256,ct=64",
};

#define MASK (BENCH_PRIMARY | BENCH_SHADOW | BENCH_DIFFUSE)
/* Spreads below these cannot separate C_step from C_intersect. */
#define MIN_CV 0.10
#define MAX_CORR 0.99 /* leave-one-out shows what an ill-conditioned fit is worth */
/* The claim's threshold: the model predicts a configuration it has not
 * seen within this (the median held-out error over the fits). */
#define GOOD_FIT 0.15
#define MAX_FITS 96
#define MAXP 16

static const char *const set_names[3] = {"primary", "shadow", "diffuse"};

/* The family of a spec: kind[:width=N][,traverse=packet][,cells=ids|blocks]
 * (cells only where the spec names it). */
static void family_of(const char *spec, char *out, size_t n)
{
    size_t k = strcspn(spec, ":");
    const char *w = strstr(spec, "width="), *p = strstr(spec, "traverse=packet");
    const char *c = strstr(spec, "cells=");
    char parts[48] = "";
    if (w) snprintf(parts + strlen(parts), sizeof parts - strlen(parts), ",width=%d", atoi(w + 6));
    if (p) snprintf(parts + strlen(parts), sizeof parts - strlen(parts), ",traverse=packet");
    if (c)
        snprintf(parts + strlen(parts), sizeof parts - strlen(parts), ",cells=%.*s",
                 (int)strcspn(c + 6, ",;"), c + 6);
    snprintf(out, n, "%.*s%s%s", (int)k, spec, parts[0] ? ":" : "", parts[0] ? parts + 1 : "");
}

typedef struct {
    char family[64], scene[128];
    int set, n, fitted;
    double c[3], held_med, held_max;
    double meas[MAXP], pred[MAXP]; /* held-out predictions */
    /* The fit on equal terms: C_intersect fixed at the micro-benchmark's
     * cost per primitive of the family's own test (lanes: 0 one at a time,
     * 4 or 8 a block lane), C_step and C_ray fitted (non-negative). */
    int lanes, fixed_ok;
    double fixed_ci, fixed_c[2], fixed_med, fixed_max;
} fit_row;

typedef struct {
    fit_row f[MAX_FITS];
    int count, unfit;
    exp_text scenes, findings;
    const step_micro *m;
} study;

/* ns per primitive test of a kind that tests `lanes` at once (0: one by
 * one): the scalar test, or a full block's time over its lanes, hot in L1.
 * The memory micro (the same tests on a scene-sized array in a shuffled
 * order) was tried as the diffuse rays' value for scalar tests
 * (67d717c-a18df72): on this VM it read 18.7, 25.5, 29.9, 53.5 and 70.2 ns
 * in five runs of one afternoon, while the traces' own free fits put a
 * diffuse scalar test at 23-49 ns; fixed at those readings, bvh's diffuse
 * fit swung from a 24 ns step to 0 with 85% held-out error. It is printed
 * beside the hot micro, not held fixed. */
static double micro_per_prim(const step_micro *m, int lanes)
{
    return lanes == 8 ? m->block8.median / 8 : lanes == 4 ? m->block4.median / 4 : m->tri.median;
}

/* Why a family has no fit on equal terms, or NULL. instanced's family is
 * walked binary bottoms (its default tests 8-wide blocks, but leaf= does
 * not change that structure): each test is a call of the walk's visitor
 * into the world-space decision, a test no shared micro-benchmark times,
 * so holding C_intersect at the scalar test's would pin C_step at 0. */
static const char *fixed_skip_reason(const char *family)
{
    if (!strncmp(family, "instanced", 9))
        return "not on equal terms: its family's test is the walk's visitor calling the "
               "world-space decision, which no shared micro-benchmark times (free fit below)";
    return NULL;
}

/* C_step and C_ray by non-negative least squares on y - ci * prims, with
 * the held-out errors (each point predicted by the fit on the others). */
static int fit_fixed(const double *st, const double *pr, const double *ns, int n, const double *ci,
                     double *coef, double *pred)
{
    double r[MAXP], one[MAXP];
    for (int i = 0; i < n; i++) r[i] = ns[i] - ci[i] * pr[i], one[i] = 1;
    const double *cols[2] = {st, one};
    exp_fit f;
    if (exp_nnls(cols, 2, r, n, &f)) return -1;
    coef[0] = f.coef[0], coef[1] = f.coef[1];
    for (int k = 0; k < n; k++) {
        double s[MAXP], y[MAXP], o[MAXP];
        int m = 0;
        for (int i = 0; i < n; i++)
            if (i != k) s[m] = st[i], y[m] = r[i], o[m++] = 1;
        const double *c2[2] = {s, o};
        exp_fit g;
        if (exp_nnls(c2, 2, y, m, &g)) return -1;
        pred[k] = g.coef[0] * st[k] + ci[k] * pr[k] + g.coef[1];
    }
    return 0;
}

/* The held-out error of each point: the fit on the others predicts it.
 * 0, or -1 when a fit on n-1 points fails. */
static int leave_one_out(const double *st, const double *pr, const double *ns, int n, double *pred)
{
    for (int k = 0; k < n; k++) {
        double s[MAXP], p[MAXP], y[MAXP], one[MAXP];
        int m = 0;
        for (int i = 0; i < n; i++)
            if (i != k) s[m] = st[i], p[m] = pr[i], y[m] = ns[i], one[m++] = 1;
        const double *cols[3] = {s, p, one};
        exp_fit f;
        if (exp_nnls(cols, 3, y, m, &f)) return -1;
        pred[k] = f.coef[0] * st[k] + f.coef[1] * pr[k] + f.coef[2];
    }
    return 0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* One family on one scene and ray set: the fit, its held-out errors, the
 * detail table (in the appendix). */
static void fit_family(exp_ctx *x, const exp_group *g, const char *family, int set, study *sd,
                       const char *scene)
{
    double st[MAXP], pr[MAXP], ns[MAXP], one[MAXP], ci[MAXP];
    int cfg_of[MAXP], n = 0, lanes = -1;
    for (int c = 0; c < g->count && n < MAXP; c++) {
        const exp_cfg *cf = &g->cfg[c];
        char fam[64];
        family_of(cf->spec, fam, sizeof fam);
        const exp_trace *tr = &cf->set[set];
        if (!cf->ok || strcmp(fam, family) || !tr->have || !tr->rays) continue;
        st[n] = (double)tr->counters.steps / (double)tr->rays;
        pr[n] = (double)tr->counters.prim_tests / (double)tr->rays;
        ns[n] = exp_est_scale(&tr->ms, 1e6 / (double)tr->rays).median;
        /* each configuration's own test (a family may mix blocks of 4 and 8) */
        ci[n] = micro_per_prim(sd->m, cf->build.test_lanes);
        lanes = lanes == -1 || lanes == cf->build.test_lanes ? cf->build.test_lanes : -2;
        one[n] = 1, cfg_of[n++] = c;
    }
    if (!n || sd->count >= MAX_FITS) return;
    double cvs = exp_cv(st, n), cvp = exp_cv(pr, n), r = exp_corr(st, pr, n);
    const double *cols[3] = {st, pr, one};
    exp_fit fit;
    fit_row *fr = &sd->f[sd->count];
    memset(fr, 0, sizeof *fr);
    int can = n >= 5 && cvs >= MIN_CV && cvp >= MIN_CV && fabs(r) <= MAX_CORR;
    if (!can || exp_nnls(cols, 3, ns, n, &fit) || leave_one_out(st, pr, ns, n, fr->pred)) {
        sd->unfit++;
        exp_md(x, "\n**%s**, %s rays: no fit: %d points, steps per ray vary by %.0f%% and primitive "
                  "tests by %.0f%% (at least 5 points and %.0f%% each are needed), correlation "
                  "%.2f.\n", family, set_names[set], n, 100 * cvs, 100 * cvp, 100 * MIN_CV, r);
        return;
    }
    snprintf(fr->family, sizeof fr->family, "%s", family);
    snprintf(fr->scene, sizeof fr->scene, "%s", scene);
    fr->set = set, fr->n = n, fr->fitted = 1;
    memcpy(fr->c, fit.coef, sizeof fr->c);
    double err[MAXP];
    for (int i = 0; i < n; i++) fr->meas[i] = ns[i], err[i] = fabs(fr->pred[i] - ns[i]) / ns[i];
    qsort(err, (size_t)n, sizeof err[0], cmp_double);
    fr->held_med = n % 2 ? err[n / 2] : 0.5 * (err[n / 2 - 1] + err[n / 2]);
    fr->held_max = err[n - 1];
    double fpred[MAXP];
    fr->lanes = lanes;
    {
        double lo = ci[0], hi = ci[0];
        for (int i = 1; i < n; i++) lo = fmin(lo, ci[i]), hi = fmax(hi, ci[i]);
        fr->fixed_ci = lanes >= 0 ? ci[0] : 0.5 * (lo + hi); /* mixed: the table says so */
        if (!fixed_skip_reason(family) && !fit_fixed(st, pr, ns, n, ci, fr->fixed_c, fpred)) {
            fr->fixed_ok = 1;
            for (int i = 0; i < n; i++) err[i] = fabs(fpred[i] - ns[i]) / ns[i];
            qsort(err, (size_t)n, sizeof err[0], cmp_double);
            fr->fixed_med = n % 2 ? err[n / 2] : 0.5 * (err[n / 2 - 1] + err[n / 2]);
            fr->fixed_max = err[n - 1];
        }
    }
    sd->count++;
    exp_md(x, "\n**%s**, %s rays: C_step = %.2f ns, C_intersect = %.2f ns, C_ray = %.1f ns "
              "(non-negative least squares, %d points%s); held-out error %.0f%% median, %.0f%% "
              "worst.\n", family, set_names[set], fit.coef[0], fit.coef[1], fit.coef[2], n,
           fit.pinned[0] || fit.pinned[1] || fit.pinned[2] ? "; a 0.00 is held there by the "
                                                             "constraint" : "",
           100 * fr->held_med, 100 * fr->held_max);
    exp_md_table(x, "configuration|steps/ray|prims/ray|measured ns/ray|fitted|held out|held-out error");
    for (int i = 0; i < n; i++) {
        const exp_cfg *cf = &g->cfg[cfg_of[i]];
        double in = fit.coef[0] * st[i] + fit.coef[1] * pr[i] + fit.coef[2];
        exp_md(x, "| `%s` | %.1f | %.1f | %.0f | %.0f | %.0f | %+.0f%% |\n", cf->spec, st[i], pr[i],
               ns[i], in, fr->pred[i], 100 * (fr->pred[i] - ns[i]) / ns[i]);
        exp_csv(x, "%s,%s,%s,%s,%.3f,%.3f,%.3f,%.3f,%.3f,%.4f,%.4f,%.4f,%d,%.4f,%.4f,%.4f\n", scene,
                family, cf->spec, set_names[set], ns[i], st[i], pr[i], in, fr->pred[i],
                fit.coef[0], fit.coef[1], fit.coef[2], cf->build.test_lanes, ci[i],
                fr->fixed_ok ? fr->fixed_c[0] : -1, fr->fixed_ok ? fr->fixed_c[1] : -1);
    }
}

static void measure_scene(exp_ctx *x, const char *spec, const exp_list *specs, study *sd)
{
    accel_scene s;
    bench_sets sets;
    exp_scene_section(x, spec, &s, MASK, exp_tiles_stride(x), &sets);
    exp_text_add(&sd->scenes, "%s%s", sd->scenes.len ? ", " : "", s.name);
    exp_group g;
    exp_group_init(&g, x, &s, &sets, MASK);
    g.time_builds = 0;
    g.collapse_ms = x->quick ? 500 : 4000;
    for (int i = 0; i < specs->count; i++) exp_group_add(&g, specs->spec[i], 0);
    exp_group_run(&g);
    /* One family per kind, width and traversal, in the order they first appear. */
    for (int c = 0; c < g.count; c++) {
        char fam[64], other[64];
        if (!g.cfg[c].ok) continue;
        family_of(g.cfg[c].spec, fam, sizeof fam);
        int first = 1;
        for (int d = 0; d < c && first; d++)
            if (g.cfg[d].ok) family_of(g.cfg[d].spec, other, sizeof other), first = strcmp(fam, other) != 0;
        if (!first) continue;
        for (int set = 0; set < 3; set++) fit_family(x, &g, fam, set, sd, s.name);
    }
    exp_group_note(&g);
    exp_group_free(&g);
    bench_sets_free(&sets);
    scene_free(&s);
}

/* The lecture's "visualize traversal depth": steps per pixel of every
 * kind's default on one scene, on one colour scale (in the appendix). */
static void heatmaps(exp_ctx *x)
{
    const char *specs[16];
    int n = 0;
    for (size_t k = 0; k < accel_kind_count && n < 16; k++)
        if (strcmp(accel_kinds[k]->name, "brute") && exp_kind_wanted(x, accel_kinds[k]->name))
            specs[n++] = accel_kinds[k]->name;
    accel_scene s;
    exp_scene(x, x->quick ? "sphereflake:level=1" : "teapot_stadium:n=12", &s);
    bench_sets sets;
    exp_sets(x, &s, BENCH_PRIMARY, &sets);
    exp_md(x, "\n### Heatmaps: steps per pixel on %s\n\nEach kind with its defaults on the same "
              "primary rays, one colour scale; brighter = more cells stepped / nodes visited.\n",
           s.name);
    exp_heatmaps_shared(x, specs, n, &s, &sets, 's', "heat");
    bench_sets_free(&sets);
    scene_free(&s);
}

/* ---- the answer: one table, one plot, the verdict -------------------------------- */

/* The 95% distribution-free interval of the median of n sorted values:
 * order statistics j and n+1-j with P(Binomial(n, 1/2) < j) <= 2.5%. */
static void median_interval(const double *v, int n, double *lo, double *hi)
{
    double p = pow(0.5, n), cum = p;
    int j = 0; /* 0-based: v[j] */
    for (int k = 1; k <= n / 2; k++) {
        p = p * (n - k + 1) / k; /* P(B = k) */
        if (cum + p > 0.025) break;
        cum += p, j = k;
    }
    *lo = v[j], *hi = v[n - 1 - j];
}

/* What one counted step and one counted test are for a family. */
static const char *step_of(const char *family)
{
    if (!strncmp(family, "grid", 4)) return "a cell";
    if (!strncmp(family, "nested_grid", 11)) return "a cell of any level";
    if (!strncmp(family, "irregular_grid", 14)) return "a cell (top or leaf)";
    if (!strncmp(family, "instanced", 9)) return "a node or cell of either level";
    if (strstr(family, "width=8")) return "a node of 8 children";
    if (strstr(family, "width=4")) return "a node of 4 children";
    if (strstr(family, "traverse=packet")) return "a node of 2, per packet";
    if (!strncmp(family, "bvh", 3)) return "a node of 2 children";
    return "-";
}

static const char *test_of(int lanes)
{
    return lanes == 8 ? "a lane of a block of 8" : lanes == 4 ? "a lane of a block of 4"
           : lanes == 0 ? "one triangle (scalar)" : "a block lane of 4 or 8 (mixed; C_intersect: their mean)";
}

/* The table on equal terms: every family's C_intersect fixed at the
 * micro-benchmark of its own test, C_step fitted beside it. */
static void answer_fixed(exp_ctx *x, const study *sd)
{
    exp_md(x, "\n### Step cost on equal terms: C_intersect fixed by the micro-benchmark\n\nThe "
              "free fit above may trade one count for the other. Here every family's C_intersect "
              "is the micro-benchmark's cost per primitive of the test it runs (a block test's "
              "time over its lanes, or the scalar test), the same number for every kind with the "
              "same test, hot in L1 (the memory micro above is too unsteady on a shared machine "
              "to hold a fit: see exp_step_cost.c). C_step and C_ray are fitted beside it "
              "(non-negative least squares, held-out error as above). A partly filled block "
              "costs a whole block: that shows in C_step. Primary and diffuse rays on %s.\n",
           sd->count ? sd->f[0].scene : "-");
    exp_md_table(x, "family|rays|a step is|a test is|C_intersect ns (fixed)|C_step ns|C_ray ns|"
                    "held-out median (worst)|free fit: C_step, C_intersect ns");
    for (int i = 0; i < sd->count; i++) {
        const fit_row *f = &sd->f[i];
        if (strcmp(f->scene, sd->f[0].scene) || f->set == 1) continue;
        if (!f->fixed_ok) {
            const char *why = fixed_skip_reason(f->family);
            exp_md(x, "| `%s` | %s | %s | %s | - | - | - | %s | %.2f, %.2f |\n", f->family,
                   set_names[f->set], step_of(f->family), test_of(f->lanes), why ? why : "no fit",
                   f->c[0], f->c[1]);
            continue;
        }
        exp_md(x, "| `%s` | %s | %s | %s | %.2f | %.2f | %.0f | %.0f%% (%.0f%%) | %.2f, %.2f |\n",
               f->family, set_names[f->set], step_of(f->family), test_of(f->lanes), f->fixed_ci,
               f->fixed_c[0], f->fixed_c[1], 100 * f->fixed_med, 100 * f->fixed_max, f->c[0],
               f->c[1]);
    }
}

/* The first answer at the top of the report (issue 52): one row per kind on
 * equal terms (C_intersect fixed by its test's micro-benchmark, C_step
 * fitted; primary and diffuse rays of the first scene), and one plot of
 * C_step against C_intersect, between the markers mkreport lifts. */
static void answer_top(exp_ctx *x, const study *sd)
{
    if (!sd->count) return;
    exp_md(x, "\n<!-- answer -->\n\n### What a step and a test cost, per kind\n\nOn equal terms: "
              "C_intersect is the micro-benchmark's cost per primitive of the kind's own test (hot "
              "in L1; a block test over its lanes; the same test on %d triangles read in a "
              "shuffled order is timed too, see the section: where that costs more, a diffuse "
              "C_step of 0 can be the fit putting those misses in C_ray). C_step and C_ray are "
              "fitted beside it on %s "
              "(ns per ray = C_step N_steps + C_intersect N_intersect + C_ray; held-out error: "
              "each configuration predicted by the fit without it). A step in tests: C_step / "
              "C_intersect.\n",
           sd->m->mem_tris, sd->f[0].scene);
    exp_md_table(x, "kind|a step is|a test is|C_intersect ns (fixed)|C_step ns: primary, diffuse|"
                    "a step in tests: primary, diffuse|held-out error median: primary, diffuse");
    svg_plot p;
    svg_plot_init(&p, "What a step costs against what a test costs, per kind (equal terms)",
                  "C_intersect, ns per primitive test (fixed by the micro-benchmark)",
                  "C_step, ns per step (fitted)");
    p.log_x = p.log_y = 1;
    double lo = INFINITY, hi = 0;
    for (int i = 0; i < sd->count; i++) {
        const fit_row *a = &sd->f[i], *d = NULL;
        if (strcmp(a->scene, sd->f[0].scene) || a->set != 0) continue;
        if (!a->fixed_ok) {
            const char *why = fixed_skip_reason(a->family);
            exp_md(x, "| `%s` | %s | %s | - | - | - | %s |\n", a->family, step_of(a->family),
                   test_of(a->lanes), why ? why : "no fit on equal terms (free fit below)");
            continue;
        }
        for (int j = 0; j < sd->count; j++)
            if (sd->f[j].set == 2 && sd->f[j].fixed_ok && !strcmp(sd->f[j].scene, a->scene) &&
                !strcmp(sd->f[j].family, a->family))
                d = &sd->f[j];
        char cs[64] = "-", ct[64] = "-", he[64] = "-";
        double ci = a->fixed_ci;
        if (d) {
            snprintf(cs, sizeof cs, "%.2f, %.2f", a->fixed_c[0], d->fixed_c[0]);
            snprintf(ct, sizeof ct, "%.2f, %.2f", a->fixed_c[0] / ci, d->fixed_c[0] / ci);
            snprintf(he, sizeof he, "%.0f%%, %.0f%%", 100 * a->fixed_med, 100 * d->fixed_med);
        } else {
            snprintf(cs, sizeof cs, "%.2f, -", a->fixed_c[0]);
            snprintf(ct, sizeof ct, "%.2f, -", a->fixed_c[0] / ci);
            snprintf(he, sizeof he, "%.0f%%, -", 100 * a->fixed_med);
        }
        exp_md(x, "| `%s` | %s | %s | %.2f | %s | %s | %s |\n", a->family, step_of(a->family),
               test_of(a->lanes), ci, cs, ct, he);
        double px[2] = {ci, ci}, py[2] = {a->fixed_c[0], d ? d->fixed_c[0] : 0};
        /* a C_step pinned at 0 cannot show on a log axis: svg_add leaves it out */
        if (p.count < SVG_MAX_SERIES - 1) svg_add(&p, a->family, px, py, NULL, NULL, d ? 2 : 1,
                                                  SVG_LINE | SVG_POINTS);
        lo = fmin(lo, ci), hi = fmax(hi, ci);
    }
    if (hi > 0) {
        double ex[2] = {lo / 2, hi * 2};
        svg_add(&p, "a step costs one test", ex, ex, NULL, NULL, 2, SVG_DASHED);
    }
    exp_svg(x, &p, "step_cost_answer", "C_step against C_intersect per kind, on equal terms: "
            "each kind's two points (one x: its test) are its primary and its diffuse rays; above "
            "the dashed line a step costs more than a test");
    exp_md(x, "\n<!-- /answer -->\n");
}

static void answer(exp_ctx *x, study *sd, const step_micro *m)
{
    answer_top(x, sd);
    char a[64], b[64], c[64], d[64], e[64];
    exp_md(x, "\n### The free fit: cost per step and per test, per kind and ray type\n\nFitted on %s "
              "(the first scene; the others in the appendix). Held-out error: each configuration "
              "predicted by the fit on the others (median and worst over the family).\n",
           sd->count ? sd->f[0].scene : "-");
    exp_md_table(x, "family|rays|C_step ns|C_intersect ns|C_ray ns|held-out error median (worst)|points");
    for (int i = 0; i < sd->count; i++) {
        const fit_row *f = &sd->f[i];
        if (strcmp(f->scene, sd->f[0].scene)) continue;
        exp_md(x, "| `%s` | %s | %.2f | %.2f | %.0f | %.0f%% (%.0f%%) | %d |\n", f->family,
               set_names[f->set], f->c[0], f->c[1], f->c[2], 100 * f->held_med, 100 * f->held_max, f->n);
    }
    char f[64], g[64], h[64];
    exp_md(x, "\nOn this machine, hot in L1 (median of 15 samples [95%% interval], ns per "
              "operation): one watertight triangle test %s, one block test of 8 triangles %s "
              "and of 4 %s (the shared block test of the wide BVH and the block grids, %s "
              "path), one binary node visit (two slab tests) %s, one 3D-DDA cell step with its "
              "cell read %s. The same tests on %d triangles read in a shuffled order (the "
              "triangle through an id array, or the blocks), what a scattered ray's test pays: "
              "triangle %s, block of 8 %s, block of 4 %s. A fitted constant below the hot ones "
              "is the fit trading one count for the other, not the machine.\n",
           exp_fmt_est(a, sizeof a, &m->tri, 2), exp_fmt_est(d, sizeof d, &m->block8, 2),
           exp_fmt_est(e, sizeof e, &m->block4, 2), "AVX2", exp_fmt_est(b, sizeof b, &m->node, 2),
           exp_fmt_est(c, sizeof c, &m->step, 2), m->mem_tris, exp_fmt_est(f, sizeof f, &m->tri_mem, 2),
           exp_fmt_est(g, sizeof g, &m->block8_mem, 2), exp_fmt_est(h, sizeof h, &m->block4_mem, 2));
    answer_fixed(x, sd);
    svg_plot p;
    svg_plot_init(&p, "Held-out prediction against measurement", "measured ns per ray",
                  "predicted ns per ray (fit without that configuration)");
    p.log_x = 1, p.log_y = 1;
    double lo = INFINITY, hi = 0;
    for (int s = 0; s < 3; s++) {
        double mx[MAX_FITS * MAXP], py[MAX_FITS * MAXP];
        int n = 0;
        for (int i = 0; i < sd->count; i++)
            if (sd->f[i].set == s)
                for (int k = 0; k < sd->f[i].n; k++) {
                    mx[n] = sd->f[i].meas[k], py[n++] = sd->f[i].pred[k];
                    lo = fmin(lo, sd->f[i].meas[k]), hi = fmax(hi, sd->f[i].meas[k]);
                }
        if (n) svg_add(&p, set_names[s], mx, py, NULL, NULL, n, SVG_POINTS);
    }
    if (hi > 0) {
        double ex[2] = {lo, hi}, ey[2] = {lo, hi}, e15[2] = {lo * (1 + GOOD_FIT), hi * (1 + GOOD_FIT)};
        svg_add(&p, "equal", ex, ey, NULL, NULL, 2, SVG_LINE);
        svg_add(&p, "+15% (the claim's line)", ex, e15, NULL, NULL, 2, SVG_DASHED);
    }
    exp_svg(x, &p, "step_cost_heldout", "Every configuration, ray type and scene: measured time "
            "against the prediction of the fit that did not see it");
}

static void verdict(exp_ctx *x, study *sd, const step_micro *m)
{
    double med[MAX_FITS];
    for (int i = 0; i < sd->count; i++) med[i] = sd->f[i].held_med;
    if (!sd->count) {
        exp_verdict(x, "cost-model", EXP_UNTESTABLE, exp_text_str(&sd->scenes),
                    "no family could be fitted (%d without enough spread)", sd->unfit);
        return;
    }
    qsort(med, (size_t)sd->count, sizeof med[0], cmp_double);
    int n = sd->count;
    char what[160];
    snprintf(what, sizeof what, "median held-out error over %d kind x ray-type fits", n);
    exp_decider d = {what, n % 2 ? med[n / 2] : 0.5 * (med[n / 2 - 1] + med[n / 2]), 0, 0,
                     GOOD_FIT, -1, n};
    median_interval(med, n, &d.lo, &d.hi);
    int good = 0;
    for (int i = 0; i < n; i++) good += sd->f[i].held_med <= GOOD_FIT;
    exp_text_add(&sd->findings, "- The model predicts a configuration it has not seen within "
                 "%.0f%% (median held-out error) in %d of %d fits per kind, scene and ray type; "
                 "the median over the fits is %.3f [%.3f, %.3f].\n", 100 * GOOD_FIT, good, n,
                 d.value, d.lo, d.hi);
    exp_md(x, "\nMedian held-out error over the %d fits: %.3f [%.3f, %.3f] (95%% order-statistic "
              "interval); %d fits within %.0f%%.\n", n, d.value, d.lo, d.hi, good, 100 * GOOD_FIT);
    exp_verdict_num(x, "cost-model", exp_judge(&d), &d, exp_text_str(&sd->scenes),
                    "fitted per kind, scene and ray type and validated by leaving one "
                    "configuration out: %d of %d fits predict the held-out configurations within "
                    "%.0f%% (median); %d famil%s not fittable; micro-benchmarks: triangle test "
                    "%.2f ns, node visit %.2f ns, cell step %.2f ns", good, n, 100 * GOOD_FIT,
                    sd->unfit, sd->unfit == 1 ? "y" : "ies", m->tri.median, m->node.median,
                    m->step.median);
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_step_cost",
             "What do a traversal step and a primitive test cost here, per kind and ray type, "
             "and does C_step*N_steps + C_intersect*N_intersect predict trace time?",
             NULL);
    exp_limits(&x, 8, 1);
    const char *scenes[8];
    int scene_count = 0;
    scenes[scene_count++] = x.quick ? "soup:tris=4000" : "soup:tris=100000";
    if (!x.quick) scenes[scene_count++] = "teapot_stadium:n=8"; /* 16k triangles, non-uniform */
    scene_count = exp_scene_list(&x, scenes, scene_count, 8);
    exp_header(&x, "Cost of a step and of an intersection",
               "C_step \xc2\xb7 N_steps + C_intersect \xc2\xb7 N_intersect; \"stepping is not free\"",
               "what do one traversal step (grid cell / BVH node) and one primitive test cost on "
               "this machine for every kind, and does the lecture's model predict a configuration "
               "it was not fitted on? Each kind's configurations trade steps for tests (primary, "
               "shadow and diffuse rays of one in %d of the 8x8 tiles of a %dx%d image: its "
               "density and coherence at the work of %dx%d; interleaved rounds); C_step, "
               "C_intersect and a per-ray C_ray are fitted per kind, scene and ray type (ns per "
               "ray, %d thread%s). The heatmaps are %dx%d pictures, not timings.",
               exp_tiles_stride(&x), x.rt_size[0], x.rt_size[1], x.size, x.size, x.threads,
               x.threads > 1 ? "s" : "", x.size, x.size);
    exp_csv(&x, "scene,family,spec,rayset,ns_per_ray,steps_per_ray,prims_per_ray,fitted_ns,"
                "heldout_ns,c_step_ns,c_intersect_ns,c_ray_ns,test_lanes,fixed_c_intersect_ns,"
                "fixed_c_step_ns,fixed_c_ray_ns\n"); /* fixed_*: -1 where that fit failed */
    exp_list specs;
    exp_list_make(&x, default_specs, (int)(sizeof default_specs / sizeof default_specs[0]), NULL,
                  &specs);
    study *sd = calloc(1, sizeof *sd);
    if (!sd) return 4;
    step_micro m;
    step_micro_run(&x, &m);
    sd->m = &m;
    exp_md(&x, "\n<!-- appendix -->\n");
    for (int si = 0; si < scene_count; si++) measure_scene(&x, scenes[si], &specs, sd);
    heatmaps(&x);
    exp_md(&x, "\n<!-- /appendix -->\n");
    answer(&x, sd, &m);
    verdict(&x, sd, &m);
    exp_md(&x, "\n**Findings:**\n\n%s", exp_text_str(&sd->findings));
    exp_text_free(&sd->findings);
    exp_text_free(&sd->scenes);
    exp_list_free(&specs);
    free(sd);
    return exp_finish(&x);
}
