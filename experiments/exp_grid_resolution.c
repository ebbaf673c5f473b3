/*
 * exp_grid_resolution - how fine should a regular grid be?
 *
 * Sweeps lambda (cells per primitive in n_i = d_i * cbrt(lambda*N/V)) from
 * 1/16 to 256 (and a few explicit resolutions on the first scene) on
 * several scenes, all configurations of a scene in interleaved rounds:
 * trace time with its 95% interval, cells stepped and primitive tests per
 * ray, build time, memory. The cost model C_step*N_steps +
 * C_intersect*N_intersect + C_ray is calibrated once, on the first
 * (uniform) scene, by non-negative least squares with the per-ray term
 * (without it the slopes absorb the per-ray cost and the model looks worse
 * than it is), and then asked, from each other scene's counts alone, where
 * its optimum lies. Three of the lecture's claims are tested:
 * - the model's optimum against the measured one (ties counted as hits);
 * - "scene-dependent": is there one lambda within 5% of every scene's best?
 * - "even region-dependent": with the calibrated model on the per-ray
 *   counts of the primary rays, grouped by 4x4 screen regions, how much
 *   would choosing lambda per region save over the best single lambda?
 *   (A statement about the model: per-ray times cannot be measured.)
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "group.h"
#include "svg.h"

#define MASK (BENCH_PRIMARY | BENCH_DIFFUSE)
#define MAX_SCENES 12
#define MAX_LAMBDAS 16
#define REGIONS 4 /* per image axis */
#define WITHIN 0.05

typedef struct {
    char name[128];
    int count;                       /* configurations */
    double lambda[64];               /* 0 for explicit resolutions and --accel rows */
    double excess[64];               /* time / best time - 1 (median of paired rounds) */
    int tie_best[64];                /* tied with the best */
    double region_gain;              /* model: per-region choice against the best single */
    int region_lambdas;              /* distinct lambdas the regions choose */
} scene_result;

typedef struct {
    int calibrated;
    exp_fit fit;                     /* C_step, C_intersect, C_ray */
    double default_lambda;
    scene_result sc[MAX_SCENES];
    int scenes;
    int model_hits, model_scenes;
    exp_text model_ev, findings;
} study;

static double lambda_of(const char *spec)
{
    const char *l = strstr(spec, "lambda=");
    if (!l || strchr(spec, ',')) return 0; /* only the plain sweep counts as a lambda */
    return atof(l + 7);
}

static double model_ns(const study *st, double steps, double prims)
{
    return st->fit.coef[0] * steps + st->fit.coef[1] * prims + st->fit.coef[2];
}

static void calibrate(exp_ctx *x, study *st, const exp_group *g)
{
    double s[64], p[64], y[64], one[64];
    int n = 0;
    for (int c = 0; c < g->count && n < 64; c++) {
        if (!g->cfg[c].ok) continue;
        s[n] = exp_group_steps(g, c, MASK);
        p[n] = exp_group_prims(g, c, MASK);
        y[n] = exp_group_ns(g, c, MASK).median;
        one[n++] = 1;
    }
    const double *cols[3] = {s, p, one};
    st->calibrated = n >= 4 && exp_nnls(cols, 3, y, n, &st->fit) == 0;
    if (st->calibrated)
        exp_md(x, "\nCalibration on this scene (non-negative least squares over its %d "
                  "configurations): C_step = %.2f ns, C_intersect = %.2f ns, C_ray = %.1f ns%s.\n",
               n, st->fit.coef[0], st->fit.coef[1], st->fit.coef[2],
               st->fit.pinned[0] || st->fit.pinned[1] || st->fit.pinned[2]
                   ? " (a cost at 0.00 is held there by the non-negativity constraint)" : "");
    else
        exp_md(x, "\nNo calibration: fewer than 4 configurations or no non-negative fit.\n");
}

/* The per-region test: model cost of every primary ray per configuration,
 * summed per screen region; the best lambda per region against the best
 * single one. */
static void region_test(const study *st, const exp_group *g, scene_result *r)
{
    const rays_set *pr = &g->sets->primary;
    int w = pr->width > 0 ? pr->width : 1, h = pr->height > 0 ? pr->height : 1;
    double cost[64][REGIONS * REGIONS];
    int cfgs[64], n = 0;
    for (int c = 0; c < g->count && n < 64; c++) {
        const exp_trace *t = &g->cfg[c].set[0];
        if (!g->cfg[c].ok || !t->ray_steps || lambda_of(g->cfg[c].spec) <= 0) continue;
        memset(cost[n], 0, sizeof cost[n]);
        for (size_t i = 0; i < pr->count; i++) {
            uint32_t px = pr->pixel ? pr->pixel[i] : (uint32_t)i;
            int reg = (int)((px % (uint32_t)w) * REGIONS / (uint32_t)w) +
                      REGIONS * (int)((px / (uint32_t)w) * REGIONS / (uint32_t)h);
            if (reg >= REGIONS * REGIONS) reg = REGIONS * REGIONS - 1;
            cost[n][reg] += model_ns(st, t->ray_steps[i], t->ray_prims[i]);
        }
        cfgs[n++] = c;
    }
    r->region_gain = 0, r->region_lambdas = 0;
    if (n < 2) return;
    double single = INFINITY, per_region = 0;
    for (int k = 0; k < n; k++) {
        double tot = 0;
        for (int q = 0; q < REGIONS * REGIONS; q++) tot += cost[k][q];
        single = fmin(single, tot);
    }
    int chosen[64] = {0};
    for (int q = 0; q < REGIONS * REGIONS; q++) {
        int best = 0;
        for (int k = 1; k < n; k++)
            if (cost[k][q] < cost[best][q]) best = k;
        per_region += cost[best][q];
        chosen[best] = 1;
    }
    for (int k = 0; k < n; k++) r->region_lambdas += chosen[k];
    r->region_gain = single > 0 ? 1 - per_region / single : 0;
    (void)cfgs;
}

static void sweep_plot(exp_ctx *x, const study *st, const exp_group *g, int si, const char *scene)
{
    double lx[64], ly[64], lo[64], hi[64], mx[64], my[64];
    int n = 0;
    for (int c = 0; c < g->count && n < 64; c++) {
        double l = lambda_of(g->cfg[c].spec);
        if (!g->cfg[c].ok || l <= 0) continue;
        exp_est e = exp_group_ns(g, c, MASK);
        lx[n] = mx[n] = l, ly[n] = e.median, lo[n] = e.lo, hi[n] = e.hi;
        my[n] = st->calibrated ? model_ns(st, exp_group_steps(g, c, MASK), exp_group_prims(g, c, MASK))
                               : 0;
        n++;
    }
    if (n < 2) return;
    for (int i = 1; i < n; i++) /* by lambda: the default joins the sweep at its place */
        for (int j = i; j > 0 && lx[j - 1] > lx[j]; j--) {
            double *arr[6] = {lx, ly, lo, hi, mx, my};
            for (int a = 0; a < 6; a++) {
                double t = arr[a][j];
                arr[a][j] = arr[a][j - 1], arr[a][j - 1] = t;
            }
        }
    char title[256], name[64];
    snprintf(title, sizeof title, "Grid resolution on %s: ns per ray against lambda", scene);
    snprintf(name, sizeof name, "grid_res_%d", si);
    svg_plot p;
    svg_plot_init(&p, title, "lambda (cells per primitive)", "ns per ray (primary + diffuse)");
    p.log_x = 1, p.log_y = 1;
    svg_add(&p, "measured", lx, ly, lo, hi, n, SVG_LINE | SVG_POINTS);
    if (st->calibrated) svg_add(&p, "cost model", mx, my, NULL, NULL, n, SVG_DASHED);
    exp_svg(x, &p, name, "Measured time (medians with 95% intervals) and the cost model "
            "calibrated on the first scene (dashed), against lambda");
}

static void measure_scene(exp_ctx *x, study *st, int si, const char *spec, const exp_list *extra)
{
    static const double full_l[] = {0.0625, 0.25, 0.5, 1, 2, 4, 8, 16, 32, 64, 128, 256};
    static const double quick_l[] = {0.5, 4, 32};
    const double *ls = x->quick ? quick_l : full_l;
    int nl = x->quick ? 3 : 12;
    accel_scene s;
    bench_sets sets;
    exp_scene_section(x, spec, &s, MASK, 0, &sets);
    exp_group g;
    exp_group_init(&g, x, &s, &sets, MASK);
    g.per_ray = 1;
    g.collapse_ms = x->quick ? 1000 : 4000;
    char specs[MAX_LAMBDAS + 8][64];
    int ns = 0, have_default = 0;
    for (int i = 0; i < nl; i++) {
        snprintf(specs[ns++], sizeof specs[0], "grid:lambda=%g", ls[i]);
        have_default |= ls[i] == st->default_lambda;
    }
    if (!have_default) snprintf(specs[ns++], sizeof specs[0], "grid:lambda=%g", st->default_lambda);
    if (si == 0 && !x->quick)
        for (int r = 32; r <= 256; r *= 2) snprintf(specs[ns++], sizeof specs[0], "grid:res=%d", r);
    for (int i = 0; i < ns; i++) exp_group_add(&g, specs[i], 0);
    for (int i = 0; i < extra->count; i++) exp_group_add(&g, extra->spec[i], 0);
    exp_group_run(&g);
    if (si == 0) calibrate(x, st, &g);
    scene_result *r = &st->sc[si];
    snprintf(r->name, sizeof r->name, "%s", s.name);
    int best = exp_group_best(&g, MASK, 0, g.count, "");
    int pick = -1;
    double pick_v = INFINITY;
    exp_md_table(x, "spec|resolution|ns/ray [95% CI]|vs best|cells/ray|prims/ray|model ns/ray|"
                    "build ms|MB");
    for (int c = 0; c < g.count && best >= 0; c++) {
        const exp_cfg *cf = &g.cfg[c];
        if (!cf->ok) continue;
        exp_est e = exp_group_ns(&g, c, MASK), ex = exp_group_speedup(&g, c, best, MASK);
        double steps = exp_group_steps(&g, c, MASK), prims = exp_group_prims(&g, c, MASK);
        double model = st->calibrated ? model_ns(st, steps, prims) : 0;
        if (st->calibrated && model < pick_v) pick_v = model, pick = c;
        r->lambda[r->count] = lambda_of(cf->spec);
        r->excess[r->count] = c == best ? 0 : ex.median - 1;
        r->tie_best[r->count] = c == best || exp_ratio_cmp(&ex, g.floor) == 0;
        r->count++;
        char m[96], v[128], mo[32], pc[96];
        exp_fmt_est(m, sizeof m, &e, 0);
        if (c == best)
            snprintf(v, sizeof v, "best");
        else
            snprintf(v, sizeof v, "%s%s", exp_fmt_pct(pc, sizeof pc, &ex),
                     r->tie_best[r->count - 1] ? " (tie)" : "");
        snprintf(mo, sizeof mo, st->calibrated ? "%.0f" : "n/a", model);
        exp_md(x, "| `%s` | %d x %d x %d | %s | %s | %.1f | %.1f | %s | %.1f | %.1f |\n", cf->spec,
               cf->build.res[0], cf->build.res[1], cf->build.res[2], m, v, steps, prims, mo,
               cf->build_ms.median, cf->build.bytes / 1048576.0);
        exp_csv(x, "%s,%s,%g,%d,%d,%d,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.4f,%.4f\n", s.name,
                cf->spec, lambda_of(cf->spec), cf->build.res[0], cf->build.res[1],
                cf->build.res[2], e.median, e.lo, e.hi, steps, prims, st->calibrated ? model : 0.0,
                cf->build_ms.median, cf->build.bytes / 1048576.0);
    }
    exp_group_note(&g);
    if (best >= 0 && pick >= 0) {
        exp_est ex = exp_group_speedup(&g, pick, best, MASK);
        int hit = pick == best || exp_ratio_cmp(&ex, g.floor) == 0 || ex.median - 1 <= WITHIN;
        st->model_hits += hit;
        st->model_scenes++;
        char e[128];
        exp_fmt_pct(e, sizeof e, &ex);
        if (exp_ratio_cmp(&ex, g.floor) == 0) strcat(e, " (a tie)");
        exp_md(x, "\nMeasured best: `%s`. The model picks `%s`%s%s%s.\n", g.cfg[best].spec,
               g.cfg[pick].spec, pick == best ? " (the same)" : ": ", pick == best ? "" : e,
               pick == best ? "" : hit ? " against the best (a hit: tied or within 5%)"
                                       : " against the best (a miss)");
        exp_text_add(&st->findings, "- %s: best `%s`; the model picks `%s`%s%s.\n", s.name,
                     g.cfg[best].spec, g.cfg[pick].spec, pick == best ? " (the same)" : ", ",
                     pick == best ? "" : e);
        if (pick != best)
            exp_text_add(&st->model_ev, "%s%s %+.1f%% (%s)", st->model_ev.len ? ", " : "", s.name,
                         100 * (ex.median - 1), hit ? "a hit: tied or within 5%" : "a miss");
    }
    if (st->calibrated) {
        region_test(st, &g, r);
        if (r->region_lambdas)
            exp_md(x, "\nBy region (model, primary rays, %dx%d screen regions): choosing lambda "
                      "per region would cost %.1f%% less than the best single lambda; the regions "
                      "choose %d different lambda%s.\n", REGIONS, REGIONS, 100 * r->region_gain,
                   r->region_lambdas, r->region_lambdas == 1 ? "" : "s");
    }
    sweep_plot(x, st, &g, si, s.name);
    if (si == 1 || (x->quick && si == 0)) {
        char why[600], name[64], cap[256];
        const char *const heat[] = {"grid:lambda=0.5", "grid:lambda=32"};
        for (int h = 0; h < 2; h++) {
            snprintf(name, sizeof name, "grid_res_heat_%d", h);
            snprintf(cap, sizeof cap, "`%s` on %s: cells stepped per pixel", heat[h], s.name);
            if (exp_heatmap(x, heat[h], &s, &sets, 's', name, cap, why, sizeof why))
                exp_md(x, "\n(heatmap skipped: %s)\n", why);
        }
    }
    exp_group_free(&g);
    bench_sets_free(&sets);
    scene_free(&s);
    st->scenes = si + 1;
}

/* One lambda for every scene? The lambdas of the sweep against each
 * scene's best; then the verdicts. */
static void verdicts(exp_ctx *x, study *st)
{
    double ls[64];
    int nl = 0;
    for (int i = 0; i < st->sc[0].count; i++)
        if (st->sc[0].lambda[i] > 0 && nl < 64) ls[nl++] = st->sc[0].lambda[i];
    int best_l = -1, best_within = -1;
    double best_worst = INFINITY, best_worst_in = 0;
    exp_md(x, "\n### One lambda for every scene?\n\nExcess of each lambda over each scene's "
              "measured best (a tie: inside the intervals or under the noise floor).\n");
    exp_text head = {0};
    exp_text_add(&head, "lambda|scenes tied with the best or within %.0f%%|worst excess", 100 * WITHIN);
    exp_md_table(x, exp_text_str(&head));
    exp_text_free(&head);
    for (int k = 0; k < nl; k++) {
        int within = 0, n = 0;
        double worst = 0, worst_in = 0;
        for (int si = 0; si < st->scenes; si++)
            for (int i = 0; i < st->sc[si].count; i++)
                if (st->sc[si].lambda[i] == ls[k]) {
                    int in = st->sc[si].tie_best[i] || st->sc[si].excess[i] <= WITHIN;
                    n++;
                    within += in;
                    worst = fmax(worst, st->sc[si].excess[i]);
                    if (in) worst_in = fmax(worst_in, st->sc[si].excess[i]);
                }
        exp_md(x, "| %g | %d of %d | %+.1f%% |\n", ls[k], within, n, 100 * worst);
        if (within > best_within || (within == best_within && worst < best_worst))
            best_within = within, best_worst = worst, best_worst_in = worst_in, best_l = k;
    }
    int n = st->scenes;
    if (best_l >= 0) {
        const char *v = best_within == n ? exp_no_difference(exp_section_floor(x))
                        : best_within * 2 > n ? EXP_PARTLY : EXP_CONFIRMED;
        exp_text miss = {0};
        for (int si = 0; si < n; si++)
            for (int i = 0; i < st->sc[si].count; i++)
                if (st->sc[si].lambda[i] == ls[best_l] && !st->sc[si].tie_best[i] &&
                    st->sc[si].excess[i] > WITHIN)
                    exp_text_add(&miss, "%s%s %+.1f%%", miss.len ? ", " : "", st->sc[si].name,
                                 100 * st->sc[si].excess[i]);
        char worst_txt[96] = "at the measured best on each of them"; /* no "+0.0%": no table shows it */
        if (100 * best_worst_in >= 0.05)
            snprintf(worst_txt, sizeof worst_txt, "the largest excess among them %+.1f%%",
                     100 * best_worst_in);
        exp_text_add(&st->findings, "- lambda=%g is tied with the best or within %.0f%% of it on "
                     "%d of %d scenes (%s)%s%s.\n", ls[best_l], 100 * WITHIN, best_within, n,
                     worst_txt, miss.len ? "; it misses on " : "", exp_text_str(&miss));
        exp_verdict(x, "grid-scene-dependent", v, "every scene of the sweep",
                    "one lambda (%g) is tied with the measured best or within %.0f%% of it on %d "
                    "of %d scenes%s%s", ls[best_l], 100 * WITHIN, best_within, n,
                    miss.len ? "; it misses on " : "", exp_text_str(&miss));
        exp_text_free(&miss);
    }
    if (st->model_scenes) {
        const char *v = st->model_hits == st->model_scenes ? EXP_CONFIRMED
                        : st->model_hits * 2 >= st->model_scenes ? EXP_PARTLY : EXP_REFUTED;
        exp_verdict(x, "grid-model-optimum", v, "every scene of the sweep",
                    "the calibrated model's pick is tied with or within %.0f%% of the measured "
                    "best on %d of %d scenes%s%s%s", 100 * WITHIN, st->model_hits,
                    st->model_scenes, st->model_ev.len ? " (where the pick is not the best: " : "",
                    exp_text_str(&st->model_ev), st->model_ev.len ? ")" : "");
    } else {
        exp_verdict(x, "grid-model-optimum", EXP_UNTESTABLE, "-",
                    "the model could not be calibrated (see the first scene)");
    }
    double top = 0;
    const char *where = "";
    int tested = 0;
    for (int si = 0; si < n; si++)
        if (st->sc[si].region_lambdas) {
            tested++;
            if (st->sc[si].region_gain > top) top = st->sc[si].region_gain, where = st->sc[si].name;
        }
    if (!tested) {
        exp_verdict(x, "grid-region-dependent", EXP_UNTESTABLE, "-",
                    "no calibrated model or no per-ray counts");
    } else {
        const char *v = top >= 0.10 ? EXP_CONFIRMED : top >= WITHIN ? EXP_PARTLY : EXP_REFUTED;
        exp_text_add(&st->findings, "- By region (the model on per-ray counts): choosing lambda "
                     "per %dx%d screen region saves at most %.1f%% (%s).\n", REGIONS, REGIONS,
                     100 * top, where);
        exp_verdict(x, "grid-region-dependent", v, where,
                    "by the calibrated model on the counts of every primary ray, a lambda per "
                    "%dx%d screen region would save at most %.1f%% of the best single lambda's "
                    "cost (%s); tested by the model, not by time", REGIONS, REGIONS, 100 * top, where);
    }
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_grid_resolution",
             "What grid resolution is best, does the cost model find it, and is it the same "
             "for every scene and every region?",
             NULL);
    exp_header(&x, "Grid resolution",
               "\"The optimal resolution minimizes C_step \xc2\xb7 N_steps + C_intersect \xc2\xb7 "
               "N_intersect\" and \"is scene-dependent, even region-dependent\"",
               "how does a regular grid's trace time depend on its resolution (lambda = cells per "
               "primitive, or an explicit resolution), where is the optimum, does the cost model "
               "find it, and is it the same for every scene and region? ns per ray over %dx%d "
               "primary rays plus one diffuse bounce, every configuration of a scene in "
               "interleaved rounds; counts per ray.", x.size, x.size);
    const accel_kind *grid = accel_find_kind("grid");
    if (!grid || !exp_kind_wanted(&x, "grid")) {
        exp_md(&x, "\nLeft out: no `grid` kind in this run.\n");
        exp_verdict(&x, "grid-model-optimum", EXP_UNTESTABLE, "-", "no grid kind in this run");
        return exp_finish(&x);
    }
    study *st = calloc(1, sizeof *st);
    if (!st) return 4;
    for (size_t i = 0; i < grid->param_count; i++)
        if (!strcmp(grid->params[i].key, "lambda")) st->default_lambda = atof(grid->params[i].def);
    exp_md(&x, "\nThe grid's default is lambda=%g (its parameter table).\n", st->default_lambda);
    const char *scenes[MAX_SCENES];
    int scene_count = 0;
    scenes[scene_count++] = x.quick ? "soup:tris=4000" : "soup:tris=200000";
    if (!x.quick) {
        scenes[scene_count++] = "teapot_stadium:n=8"; /* 4k teapot triangles: collapsed grids stay at seconds per pass */
        scenes[scene_count++] = "sphereflake";
        scenes[scene_count++] = "slivers";
        scenes[scene_count++] = "mount";
        for (int i = 0; i < x.mesh_count && scene_count < MAX_SCENES; i++) scenes[scene_count++] = x.meshes[i];
    } else {
        scenes[scene_count++] = "teapot_stadium:n=4,stadium=32,tiers=4";
    }
    scene_count = exp_scene_list(&x, scenes, scene_count, MAX_SCENES);
    exp_csv(&x, "scene,spec,lambda,nx,ny,nz,ns_per_ray,ns_lo,ns_hi,steps_per_ray,prims_per_ray,"
                "model_ns,build_ms,mb\n");
    exp_list extra;
    exp_list_make(&x, NULL, 0, "grid", &extra);
    /* The lambda sweep is the question itself: --accel grid specs join it. */
    for (int si = 0; si < scene_count; si++) measure_scene(&x, st, si, scenes[si], &extra);
    verdicts(&x, st);
    exp_md(&x, "\n**Findings:**\n\n%s", exp_text_str(&st->findings));
    exp_text_free(&st->findings);
    exp_text_free(&st->model_ev);
    exp_list_free(&extra);
    free(st);
    return exp_finish(&x);
}
