/*
 * sah_answer.h - exp_sah's answer at the top of REPORT.md (issue 52): per
 * scene, the full-sweep SAH against the lecture's pure median split and
 * binned SAH against the full sweep, as one table and one plot between
 * the <!-- answer --> markers bin/mkreport lifts under the summary.
 */
#ifndef EXPERIMENTS_SAH_ANSWER_H
#define EXPERIMENTS_SAH_ANSWER_H

#include "engine/group.h"
#include "engine/svg.h"

#define SAH_ANSWER_MAX 12

typedef struct {
    char name[128];
    unsigned tris;
    double cost_pure, cost_sah; /* SAH cost of the two trees */
    /* 95%, paired: SAH over pure median (speed-up over every ray set of the
     * group, build time ratio); binned over SAH (trace and build time
     * ratios) and binned over pure median (speed-up, for the plot) */
    exp_est sah, sah_build, bin, bin_build, bin_sp;
    int have_bin;
} sah_answer_row;

typedef struct {
    sah_answer_row r[SAH_ANSWER_MAX];
    int n;
} sah_answer;

/* One scene's row from a group that measured pure, sah and (if present)
 * binned; nothing when pure or sah did not run. */
void sah_answer_add(sah_answer *a, const exp_group *g, const accel_scene *s, const char *pure,
                    const char *sah, const char *binned);
/* The table and the plot sah_answer.svg, between the answer markers
 * (stride: the rays were one in stride of x->rt_size's 8x8 tiles). */
void sah_answer_write(exp_ctx *x, const sah_answer *a, int stride);

/* The section's plot (issue 39): per builder, one point per scene: build
 * time over the pure median split's (x) against the primary speed-up over
 * it (y, with its interval). */
typedef struct {
    char pname[SVG_MAX_SERIES][64];
    double px[SVG_MAX_SERIES][12], py[SVG_MAX_SERIES][12], plo[SVG_MAX_SERIES][12],
        phi[SVG_MAX_SERIES][12];
    int pn[SVG_MAX_SERIES], np;
} sah_plot;
/* A point under the builder's series (at most 12 per series). */
void sah_plot_point(sah_plot *p, const char *spec, double x, const exp_est *y);
/* The plot sah_speedup.svg, with the lecture's 2x (nothing without points). */
void sah_plot_write(exp_ctx *x, const sah_plot *p);

#endif
