/*
 * exp_step_cost - what does one traversal step and one primitive test cost
 * on this machine, and does the lecture's cost model predict trace time?
 *
 * Model (lecture, section 2): time per ray = C_step * N_steps +
 * C_intersect * N_intersect, plus C_ray, a fixed cost per ray (ray setup,
 * the root box, writing the hit) fitted too so that it does not bias the
 * two slopes. For each kind a family of configurations that trades steps
 * against tests (grid resolutions, BVH leaf sizes and node costs,
 * nested-grid thresholds) is traced on each scene in interleaved rounds;
 * the three costs are fitted by non-negative least squares per kind and
 * scene. A cost held at zero by the constraint is said so, with the free
 * fit's value; a family whose configurations barely move the two counts
 * (so no fit can separate them) is named with its spreads, never fitted.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "group.h"

/* The families: each spec belongs to the family of its kind. --accel
 * specs join the family of theirs (a new kind starts a new family). */
static const char *const default_specs[] = {
    "grid:lambda=0.25", "grid:lambda=1", "grid:lambda=4", "grid:lambda=16", "grid:lambda=64",
    "grid:lambda=4,mailbox=0",
    "nested_grid:threshold=4", "nested_grid:threshold=16", "nested_grid:threshold=64",
    "nested_grid:depth=1", "nested_grid:auto",
    "bvh:leaf=1", "bvh", "bvh:leaf=32,ct=4", "bvh:leaf=64,ct=16", "bvh:leaf=256,ct=64",
    "bvh:build=median,term=none,leaf=32",
};

/* Spreads below these cannot separate C_step from C_intersect. */
#define MIN_CV 0.10
#define MAX_CORR 0.95
/* A fit is good when it predicts every point within this. */
#define GOOD_FIT 0.15

typedef struct {
    int fits, good, unfit;
    exp_text evidence, scenes;
} tally;

/* One kind's configurations on one scene: fit and table. */
static void fit_family(exp_ctx *x, const exp_group *g, const char *kind, const char *scene,
                       exp_text *findings, tally *t)
{
    enum { MAXP = 128 };
    double st[MAXP], pr[MAXP], ns[MAXP], one[MAXP];
    exp_est est[MAXP];
    int cfg_of[MAXP], set_of[MAXP], n = 0;
    for (int c = 0; c < g->count && n < MAXP - 1; c++) {
        const exp_cfg *cf = &g->cfg[c];
        if (!cf->ok || strcmp(cf->kind->name, kind)) continue;
        for (int i = 0; i < 4; i += 2) {
            const exp_trace *tr = &cf->set[i];
            if (!tr->have || !tr->rays) continue;
            st[n] = (double)tr->counters.steps / (double)tr->rays;
            pr[n] = (double)tr->counters.prim_tests / (double)tr->rays;
            est[n] = exp_est_scale(&tr->ms, 1e6 / (double)tr->rays);
            ns[n] = est[n].median;
            one[n] = 1;
            cfg_of[n] = c, set_of[n] = i;
            n++;
        }
    }
    if (!n) return;
    double cvs = exp_cv(st, n), cvp = exp_cv(pr, n), r = exp_corr(st, pr, n);
    const double *cols[3] = {st, pr, one};
    exp_fit fit;
    int can = n >= 4 && cvs >= MIN_CV && cvp >= MIN_CV && fabs(r) <= MAX_CORR;
    int fitted = can && exp_nnls(cols, 3, ns, n, &fit) == 0;
    exp_md(x, "\n**%s**: ", kind);
    if (!fitted) {
        t->unfit++;
        exp_md(x, "no fit: across these %d points steps per ray vary by %.0f%% and primitive "
                  "tests by %.0f%% (coefficient of variation; at least %.0f%% each is needed), "
                  "correlation %.2f: too little independent variation to separate C_step from "
                  "C_intersect.\n", n, 100 * cvs, 100 * cvp, 100 * MIN_CV, r);
        exp_text_add(findings, "- %s on %s: not fitted (steps vary by %.0f%%, tests by %.0f%%).\n",
                     kind, scene, 100 * cvs, 100 * cvp);
    } else {
        double freec[3];
        int have_free = exp_lsq(cols, 3, ns, n, freec) == 0;
        static const char *const names[3] = {"C_step", "C_intersect", "C_ray"};
        exp_md(x, "C_step = %.2f ns, C_intersect = %.2f ns, C_ray = %.1f ns (non-negative least "
                  "squares over %d points)", fit.coef[0], fit.coef[1], fit.coef[2], n);
        for (int j = 0; j < 3; j++)
            if (fit.pinned[j])
                exp_md(x, "; %s is held at 0 by the constraint%s%.2f ns)", names[j],
                       have_free ? " (the unconstrained fit gives " : " (", have_free ? freec[j] : 0.0);
        exp_md(x, ".\n");
    }
    exp_md_table(x, fitted ? "configuration|rays|steps/ray|prims/ray|measured ns/ray [95% CI]|"
                             "predicted ns/ray|error"
                           : "configuration|rays|steps/ray|prims/ray|measured ns/ray [95% CI]");
    double worst = 0;
    for (int i = 0; i < n; i++) {
        const exp_cfg *cf = &g->cfg[cfg_of[i]];
        char m[96];
        exp_fmt_est(m, sizeof m, &est[i], 0);
        const char *set = set_of[i] == 0 ? "primary" : "diffuse";
        if (fitted) {
            double pred = fit.coef[0] * st[i] + fit.coef[1] * pr[i] + fit.coef[2];
            double e = (pred - ns[i]) / ns[i];
            worst = fmax(worst, fabs(e));
            exp_md(x, "| `%s` | %s | %.1f | %.1f | %s | %.0f | %+.0f%% |\n", cf->spec, set, st[i],
                   pr[i], m, pred, 100 * e);
            exp_csv(x, "%s,%s,%s,%s,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.4f,%.4f,%.4f\n", scene, kind,
                    cf->spec, set, ns[i], est[i].lo, est[i].hi, st[i], pr[i], pred, fit.coef[0],
                    fit.coef[1], fit.coef[2]);
        } else {
            exp_md(x, "| `%s` | %s | %.1f | %.1f | %s |\n", cf->spec, set, st[i], pr[i], m);
            exp_csv(x, "%s,%s,%s,%s,%.3f,%.3f,%.3f,%.3f,%.3f,,,,\n", scene, kind, cf->spec, set,
                    ns[i], est[i].lo, est[i].hi, st[i], pr[i]);
        }
    }
    if (fitted) {
        t->fits++;
        t->good += worst <= GOOD_FIT;
        exp_md(x, "\nWorst prediction error: %.0f%%.\n", 100 * worst);
        exp_text_add(findings, "- %s on %s: C_step = %.2f ns, C_intersect = %.2f ns, C_ray = "
                     "%.1f ns; worst prediction error %.0f%%.\n", kind, scene, fit.coef[0],
                     fit.coef[1], fit.coef[2], 100 * worst);
        exp_text_add(&t->evidence, "%s%s on %s: worst error %.0f%%", t->evidence.len ? "; " : "",
                     kind, scene, 100 * worst);
    }
}

static void measure_scene(exp_ctx *x, const char *spec, const exp_list *specs, exp_text *findings,
                          tally *t)
{
    accel_scene s;
    bench_sets sets;
    exp_scene_section(x, spec, &s, BENCH_PRIMARY | BENCH_DIFFUSE, 0, &sets);
    exp_text_add(&t->scenes, "%s%s", t->scenes.len ? ", " : "", s.name);
    exp_group g;
    exp_group_init(&g, x, &s, &sets, BENCH_PRIMARY | BENCH_DIFFUSE);
    g.time_builds = 0;
    g.collapse_ms = x->quick ? 500 : 4000;
    for (int i = 0; i < specs->count; i++) exp_group_add(&g, specs->spec[i], 0);
    exp_group_run(&g);
    /* One family per kind, in the order the kinds first appear. */
    for (int c = 0; c < g.count; c++) {
        if (!g.cfg[c].ok) continue;
        int first = 1;
        for (int d = 0; d < c; d++) first &= !(g.cfg[d].ok && g.cfg[d].kind == g.cfg[c].kind);
        if (first) fit_family(x, &g, g.cfg[c].kind->name, s.name, findings, t);
    }
    exp_group_note(&g);
    exp_group_free(&g);
    bench_sets_free(&sets);
    scene_free(&s);
}

/* The lecture's "visualize traversal depth": steps per pixel per kind. */
static void heatmaps(exp_ctx *x)
{
    const char *heat_scenes[2] = {x->quick ? "sphereflake:level=1" : "teapot_stadium:n=12",
                                  x->quick ? NULL : (x->mesh_count ? x->meshes[0] : "sphereflake")};
    exp_md(x, "\n### Heatmaps: steps per pixel\n\nEach kind with its default parameters on the "
              "same primary rays; brighter = more cells stepped / nodes visited.\n");
    for (int h = 0; h < 2; h++) {
        if (!heat_scenes[h]) continue;
        accel_scene s;
        exp_scene(x, heat_scenes[h], &s);
        bench_sets sets;
        exp_sets(x, &s, BENCH_PRIMARY, &sets);
        for (size_t k = 0; k < accel_kind_count; k++) {
            const accel_kind *kind = accel_kinds[k];
            if (!strcmp(kind->name, "brute") || !exp_kind_wanted(x, kind->name)) continue;
            char name[128], caption[256], why[600];
            snprintf(name, sizeof name, "heat_%s_%d", kind->name, h);
            snprintf(caption, sizeof caption, "`%s` on %s", kind->name, s.name);
            if (exp_heatmap(x, kind->name, &s, &sets, 's', name, caption, why, sizeof why))
                exp_md(x, "\n`%s` on %s: skipped (%s)\n", kind->name, s.name, why);
        }
        bench_sets_free(&sets);
        scene_free(&s);
    }
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_step_cost",
             "What do a traversal step and a primitive test cost here, and does "
             "C_step*N_steps + C_intersect*N_intersect predict trace time?",
             NULL);
    exp_mesh_room(&x, 1);
    const char *scenes[8];
    int scene_count = 0;
    if (x.quick) {
        scenes[scene_count++] = "soup:tris=4000";
    } else {
        scenes[scene_count++] = "soup:tris=100000";
        scenes[scene_count++] = "teapot_stadium:n=8"; /* 4k teapot triangles: the grid's passes stay short */
        if (x.mesh_count) scenes[scene_count++] = x.meshes[0];
    }
    scene_count = exp_scene_list(&x, scenes, scene_count, 8);
    exp_header(&x, "Cost of a step and of an intersection",
               "C_step \xc2\xb7 N_steps + C_intersect \xc2\xb7 N_intersect; \"stepping is not free\"",
               "what do one traversal step (grid cell / BVH node) and one primitive test cost on "
               "this machine, and does the lecture's model predict the measured trace time? For "
               "each kind, configurations that trade steps for tests are traced (primary and "
               "diffuse rays, %dx%d, interleaved rounds); C_step, C_intersect and a per-ray "
               "constant C_ray are fitted by non-negative least squares on all of them (ns per "
               "ray, %d thread%s).",
               x.size, x.size, x.threads, x.threads > 1 ? "s" : "");
    exp_csv(&x, "scene,kind,spec,rayset,ns_per_ray,ns_lo,ns_hi,steps_per_ray,prims_per_ray,"
                "predicted_ns,c_step_ns,c_intersect_ns,c_ray_ns\n");
    exp_list specs;
    exp_list_make(&x, default_specs, (int)(sizeof default_specs / sizeof default_specs[0]), NULL,
                  &specs);
    exp_text findings = {0};
    tally t = {0};
    for (int si = 0; si < scene_count; si++) measure_scene(&x, scenes[si], &specs, &findings, &t);
    heatmaps(&x);
    exp_md(&x, "\n**Findings:**\n\n%s", exp_text_str(&findings));
    exp_md(&x, "\nThe fitted constants absorb cache behaviour (coherent primary rays against "
               "incoherent diffuse ones), so one set of constants per kind and scene is the "
               "model's best case; the worst error above is what it costs to use it.\n");
    const char *v = !t.fits ? EXP_UNTESTABLE : t.good == t.fits ? EXP_CONFIRMED
                    : t.good == 0 ? exp_no_difference(exp_section_floor(&x)) : EXP_PARTLY;
    exp_verdict(&x, "cost-model", v, exp_text_str(&t.scenes),
                "%d of %d fits predict every configuration within %.0f%% (%s); %d famil%s not "
                "fittable", t.good, t.fits, 100 * GOOD_FIT, exp_text_str(&t.evidence), t.unfit,
                t.unfit == 1 ? "y" : "ies");
    exp_text_free(&findings);
    exp_text_free(&t.evidence);
    exp_text_free(&t.scenes);
    exp_list_free(&specs);
    return exp_finish(&x);
}
