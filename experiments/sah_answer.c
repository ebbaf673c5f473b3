/*
 * sah_answer.c - exp_sah's answer at the top of REPORT.md (sah_answer.h).
 */
#include <math.h>
#include <string.h>

#include "sah_answer.h"
#include "engine/svg.h"

void sah_answer_add(sah_answer *a, const exp_group *g, const accel_scene *s, const char *pure,
                    const char *sah, const char *binned)
{
    int p = exp_group_find(g, pure), q = exp_group_find(g, sah), b = exp_group_find(g, binned);
    if (a->n >= SAH_ANSWER_MAX || p < 0 || q < 0 || !g->cfg[p].ok || !g->cfg[q].ok) return;
    sah_answer_row *r = &a->r[a->n++];
    memset(r, 0, sizeof *r);
    snprintf(r->name, sizeof r->name, "%s", s->name);
    r->tris = s->live_count;
    r->cost_pure = g->cfg[p].build.sah_cost;
    r->cost_sah = g->cfg[q].build.sah_cost;
    r->sah = exp_group_speedup(g, p, q, g->mask);
    r->sah_build = exp_group_build_ratio_level(g, q, p, 0.95);
    r->have_bin = b >= 0 && g->cfg[b].ok;
    if (r->have_bin) {
        exp_est sp = exp_group_speedup(g, q, b, g->mask); /* time(sah) / time(binned) */
        r->bin = exp_est_inv(&sp, 1.0);
        r->bin_build = exp_group_build_ratio_level(g, b, q, 0.95);
        r->bin_sp = exp_group_speedup(g, p, b, g->mask);
    }
}

void sah_answer_write(exp_ctx *x, const sah_answer *a, int stride)
{
    if (!a->n) return;
    exp_md(x, "\n<!-- answer -->\n\n### What SAH and binning buy, on every scene\n\nPaired "
              "ratios [95%% interval], primary+shadow+diffuse rays (%dx%d, 1 in %d tiles). SAH: "
              "`build=sah` over the pure median split (the lecture: \"SAH will double "
              "performance\"); binned: `build=binned` (16 bins, 3 axes) over `build=sah`, below 1 "
              "faster. SAH cost: the tree's expected cost, pure median -> SAH.\n",
           x->rt_size[0], x->rt_size[1], stride);
    exp_md_table(x, "scene|tris|SAH cost|SAH speed-up over pure median|SAH build time / pure "
                    "median's|binned / full-sweep trace time|binned / full-sweep build time");
    svg_plot p;
    svg_plot_init(&p, "SAH and binned SAH: speed-up against build time, both over the pure "
                      "median split", "build time / the pure median split's",
                  "speed-up over the pure median split (all rays)");
    p.log_x = 1;
    double sx[SAH_ANSWER_MAX], sy[SAH_ANSWER_MAX], slo[SAH_ANSWER_MAX], shi[SAH_ANSWER_MAX],
        bx[SAH_ANSWER_MAX], by[SAH_ANSWER_MAX], blo[SAH_ANSWER_MAX], bhi[SAH_ANSWER_MAX];
    int ns = 0, nb = 0;
    double lo = INFINITY, hi = 0;
    for (int i = 0; i < a->n; i++) {
        char c1[96], c2[96], c3[96], c4[96];
        const sah_answer_row *r = &a->r[i];
        exp_md(x, "| %s | %u | %.2f -> %.2f | %s | %s | %s | %s |\n", r->name, r->tris,
               r->cost_pure, r->cost_sah, exp_fmt_x(c1, sizeof c1, &r->sah),
               exp_fmt_x(c2, sizeof c2, &r->sah_build),
               r->have_bin ? exp_fmt_x(c3, sizeof c3, &r->bin) : "-",
               r->have_bin ? exp_fmt_x(c4, sizeof c4, &r->bin_build) : "-");
        if (r->sah_build.median > 0) {
            sx[ns] = r->sah_build.median, sy[ns] = r->sah.median, slo[ns] = r->sah.lo,
            shi[ns++] = r->sah.hi;
            lo = fmin(lo, r->sah_build.median), hi = fmax(hi, r->sah_build.median);
            svg_mark(&p, r->sah_build.median, r->sah.median, r->name);
        }
        if (r->have_bin && r->bin_build.median > 0 && r->sah_build.median > 0) {
            /* binned over pure median: (binned / sah) x (sah / pure) */
            double x0 = r->bin_build.median * r->sah_build.median;
            bx[nb] = x0, by[nb] = r->bin_sp.median, blo[nb] = r->bin_sp.lo, bhi[nb++] = r->bin_sp.hi;
            lo = fmin(lo, x0), hi = fmax(hi, x0);
        }
    }
    svg_add(&p, "full-sweep SAH (ringed)", sx, sy, slo, shi, ns, SVG_POINTS);
    svg_add(&p, "binned SAH, 16 bins", bx, by, blo, bhi, nb, SVG_POINTS);
    double lx[2] = {lo, hi}, ly[2] = {2, 2};
    if (hi > 0) svg_add(&p, "the lecture's 2x", lx, ly, NULL, NULL, 2, SVG_DASHED);
    exp_svg(x, &p, "sah_answer", "Every scene: what SAH and binned SAH buy (speed-up over the pure "
            "median split, 95% intervals) for their build time (over the split's); dashed: the "
            "lecture's 2x");
    exp_md(x, "\n<!-- /answer -->\n");
}

/* A point of the answer's plot, under the builder's series. */
void sah_plot_point(sah_plot *st, const char *spec, double x, const exp_est *y)
{
    int k = 0;
    while (k < st->np && strcmp(st->pname[k], spec)) k++;
    if (k == st->np) {
        if (st->np == SVG_MAX_SERIES - 1) return; /* room for the 2x line */
        snprintf(st->pname[st->np++], sizeof st->pname[0], "%s", spec);
    }
    if (st->pn[k] >= 12 || !(x > 0) || !(y->median > 0)) return;
    int i = st->pn[k]++;
    st->px[k][i] = x, st->py[k][i] = y->median, st->plo[k][i] = y->lo, st->phi[k][i] = y->hi;
}

/* The answer's plot: what every builder buys (speed-up) for what it costs
 * (build time), both over the pure median split, with the lecture's 2x. */
void sah_plot_write(exp_ctx *x, const sah_plot *st)
{
    if (!st->np) return;
    svg_plot p;
    svg_plot_init(&p, "Builders: primary speed-up against build time, "
                      "both over the pure median split", "build time / the pure median split's",
                  "primary speed-up over the pure median split");
    p.log_x = 1;
    double lo = INFINITY, hi = 0;
    for (int k = 0; k < st->np; k++) {
        svg_add(&p, st->pname[k], st->px[k], st->py[k], st->plo[k], st->phi[k], st->pn[k],
                SVG_POINTS);
        for (int i = 0; i < st->pn[k]; i++) lo = fmin(lo, st->px[k][i]), hi = fmax(hi, st->px[k][i]);
    }
    double lx[2] = {lo, hi}, ly[2] = {2, 2};
    if (hi > 0) svg_add(&p, "the lecture's 2x", lx, ly, NULL, NULL, 2, SVG_DASHED);
    exp_svg(x, &p, "sah_speedup", "Every builder on every scene (one point per scene, 95% "
            "intervals): primary speed-up over the pure median split against its build time "
            "over the split's; dashed: the lecture's 2x");
}
