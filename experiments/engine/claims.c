/*
 * claims.c - the claims of the study, in the order the summary lists them.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "claims.h"

const exp_claim exp_claims[] = {
    {"brute-cost", "lecture", "cost without acceleration",
     "Primary rays cost O(N\xc2\xb7M) without acceleration", "exp_scaling"},
    {"accel-sublinear", "lecture", "structures reduce M",
     "Reduce M by stepping through a regular grid / by traversing a binary tree", "exp_scaling"},
    {"cost-model", "lecture", "the cost model",
     "C_step \xc2\xb7 N_steps + C_intersect \xc2\xb7 N_intersect (\"stepping is not free\")",
     "exp_step_cost"},
    {"grid-model-optimum", "lecture", "grid resolution by the model",
     "The optimal resolution minimizes C_step \xc2\xb7 N_steps + C_intersect \xc2\xb7 N_intersect",
     "exp_grid_resolution"},
    {"grid-scene-dependent", "lecture", "grid optimum per scene",
     "it is scene-dependent", "exp_grid_resolution"},
    {"grid-region-dependent", "lecture", "grid optimum per region",
     "even region-dependent", "exp_grid_resolution"},
    {"nested-adapts", "lecture", "nested grid adapts",
     "A grid whose dense cells hold grids of their own: it adapts to local scene complexity",
     "exp_nested_grid"},
    {"nested-tweaking", "lecture", "nested grid tweaking",
     "\"but resolutions still require manual tweaking\"", "exp_nested_grid"},
    {"bvh-layout", "lecture", "BVH node layout and order",
     "the 32-byte node, sibling pairs in one cache line, and \"better: the near child first\"",
     "exp_sah"},
    {"sah-2x", "lecture", "SAH speed-up", "SAH will double performance", "exp_sah"},
    {"sah-build-slower", "lecture", "SAH build cost", "but construction becomes much slower",
     "exp_sah"},
    {"binned-quality", "lecture", "binned SAH quality",
     "Binned SAH: a high quality BVH in little time", "exp_binning"},
    {"binned-30hz", "lecture", "binned SAH at 30 Hz", "up to 100k triangles @ 30 Hz",
     "exp_binning"},
    {"packets-speedup", "lecture", "ray packets",
     "Traverse a node if any ray of the packet hits its box (first active ray, early in, scan)",
     "exp_packets"},
    {"realtime-20fps", "lecture", "real time",
     "BVH + ray packets = real-time performance: 800\xc3\x97" "600 at 20 fps, 9.6M primary plus "
     "9.6M shadow rays per second",
     "exp_threads"},
    {"threads-linear", "lecture", "thread scaling", "near-linear scaling in cores",
     "exp_threads"},
    {"threads-ht", "lecture", "hyper-threading", "about +20% from hyper-threading",
     "exp_threads"},
    {"threads-100m", "lecture", "100M rays/s",
     "multithreading \"easily\" pushes past 100M rays/s", "exp_threads"},
    {"wide-bvh", "study", "wide BVHs",
     "4- and 8-wide BVHs with SIMD traversal trace at least 2.8x the binary BVH's rays per second "
     "on primary rays and 3.7x on shadow and diffuse rays (the study's targets: about 1.1x the "
     "industrial CPU kernels measured when they were set; the section Wide BVHs)",
     "exp_wide"},
    {"spatial-splits", "study", "spatial splits",
     "binned SAH with spatial splits (SBVH, Stich et al. 2009) makes the slivers scene several "
     "times faster to trace and costs nothing measurable in speed on the scanned meshes (the "
     "study's target; the section The Surface Area Heuristic)",
     "exp_sah"},
    {"grids-best", "study", "grids at their best",
     "the best known grid techniques (coherent grid traversal, empty-space skipping, nested and "
     "irregular grids) give packets 5x the single-ray grid on primary rays and bring the best "
     "grid within 1.3x of the BVH on the same triangle kernel (per-id grids against the binary "
     "BVH, block grids against the 8-wide one) on the scanned meshes, 2x on teapot_stadium (the "
     "study's targets; the section Grids at their best)",
     "exp_grids"},
    {"realtime-animated", "lecture", "real time, animated",
     "800\xc3\x97" "600 at 20 fps, primary plus shadow rays, for an animated scene of about 100k "
     "triangles with its structure updated every frame (the study's target for the lecture's "
     "real-time claim and lab; the section Scenes of many meshes)",
     "exp_twolevel"},
    {"two-level", "study", "two-level against flattened",
     "a two-level structure (a top level over the instances, one bottom level per mesh, rays "
     "moved to object space: the lab's step 3) builds faster and needs less memory than one "
     "flattened BVH over the world-space triangles (step 1), and pays for it in trace speed",
     "exp_twolevel"},
    {"refit", "study", "refit against rebuild",
     "refitting a deforming mesh's BVH (boxes updated, the tree kept; Wald, Boulos and Shirley "
     "2007) costs much less per frame than rebuilding it, and the refit tree traces more slowly "
     "as the frames go by",
     "exp_twolevel"},
    {"error-time", "request", "error against run time",
     "error against run time: the lowest image error in a fixed time, and what robust kernels "
     "cost",
     "exp_error_time"},
    {"build-pays-off", "study", "build time against trace time",
     "a structure slower to build but faster to trace pays off after enough rays",
     "exp_time_to_image"},
    {"stability", "request", "stability",
     "stability on stiff and extreme cases: no holes, false hits or leaks", "exp_stability"},
    {"leave-out", "request", "leave out what is not needed",
     "leaving out what a scene does not need: configurations that mean nothing for a scene are "
     "skipped with their reason",
     "(every section)"},
};
const int exp_claim_count = (int)(sizeof exp_claims / sizeof exp_claims[0]);

const exp_claim *exp_claim_find(const char *id)
{
    for (int i = 0; i < exp_claim_count; i++)
        if (!strcmp(exp_claims[i].id, id)) return &exp_claims[i];
    return NULL;
}

int exp_verdict_valid(const char *v)
{
    return !strcmp(v, EXP_CONFIRMED) || !strcmp(v, EXP_PARTLY) || !strcmp(v, EXP_REFUTED) ||
           !strcmp(v, EXP_UNTESTABLE) || !strcmp(v, EXP_ON_LINE) || !strcmp(v, EXP_ANSWERED);
}

const char *exp_judge(const exp_decider *d)
{
    double lo = d->lo * d->sense, hi = d->hi * d->sense, th = d->threshold * d->sense;
    if (d->sense == 0 || lo != lo || hi != hi || th != th) return EXP_ON_LINE;
    if (lo > hi) { double t = lo; lo = hi; hi = t; }
    if (d->n >= 2 && !(hi > lo)) return EXP_ON_LINE; /* not an interval */
    if (lo >= th) return EXP_CONFIRMED;
    if (hi < th) return EXP_REFUTED;
    return EXP_ON_LINE;
}

double exp_margin(const exp_decider *d)
{
    double lo = d->lo * d->sense, hi = d->hi * d->sense, th = d->threshold * d->sense;
    if (d->sense == 0 || lo != lo || hi != hi || th != th || d->value != d->value) return NAN;
    if (lo > hi) { double t = lo; lo = hi; hi = t; }
    double scale = fabs(d->threshold) > 0 ? fabs(d->threshold) : 1;
    const char *v = exp_judge(d);
    if (!strcmp(v, EXP_CONFIRMED)) return (lo - th) / scale;
    if (!strcmp(v, EXP_REFUTED)) return (hi - th) / scale;
    return 0;
}

const char *exp_combine(const char *const *w, int n, int mode)
{
    int m = 0, conf = 0, ref = 0, part = 0, line = 0, unt = 0, ans = 0;
    for (int i = 0; i < n; i++) {
        if (!w[i]) continue;
        m++;
        conf += !strcmp(w[i], EXP_CONFIRMED), ref += !strcmp(w[i], EXP_REFUTED);
        part += !strcmp(w[i], EXP_PARTLY), line += !strcmp(w[i], EXP_ON_LINE);
        unt += !strcmp(w[i], EXP_UNTESTABLE), ans += !strcmp(w[i], EXP_ANSWERED);
    }
    if (!m) return NULL;
    if (ans == m) return EXP_ANSWERED;
    int judged = conf + ref + part + line;
    if (!judged) return unt ? EXP_UNTESTABLE : EXP_ANSWERED;
    if (mode == EXP_EVERY) {
        if (ref) return EXP_REFUTED;
        if (part) return EXP_PARTLY;
        if (conf == m - ans) return EXP_CONFIRMED;
        return line ? EXP_ON_LINE : EXP_UNTESTABLE; /* confirmed, but a scene not testable */
    }
    if (conf == judged) return EXP_CONFIRMED;
    if (ref == judged) return EXP_REFUTED;
    if (part || (conf && ref)) return EXP_PARTLY;
    return ref ? EXP_REFUTED : EXP_ON_LINE;
}

const char *exp_combine_counts(int confirmed, int refuted, int online, int mode)
{
    const char *w[3] = {confirmed > 0 ? EXP_CONFIRMED : NULL, refuted > 0 ? EXP_REFUTED : NULL,
                        online > 0 ? EXP_ON_LINE : NULL};
    return exp_combine(w, 3, mode);
}

int exp_decisive(const char *word, const char *const *w, const double *margins, int n)
{
    if (!word) return -1;
    int pick = -1;
    int partly = !strcmp(word, EXP_PARTLY);
    const char *want = partly ? EXP_REFUTED : word;
    for (int i = 0; i < n; i++) {
        if (!w[i] || strcmp(w[i], want)) continue;
        double m = margins ? margins[i] : NAN;
        if (pick < 0) { pick = i; continue; }
        double mp = margins[pick];
        if (!strcmp(want, EXP_REFUTED) && (mp != mp || m < mp)) pick = i;
        else if (!strcmp(want, EXP_CONFIRMED) && (mp != mp || m < mp)) pick = i;
    }
    if (pick < 0 && partly) /* a part itself partly */
        for (int i = 0; i < n && pick < 0; i++)
            if (w[i] && !strcmp(w[i], EXP_PARTLY)) pick = i;
    for (int i = 0; i < n && pick < 0; i++)
        if (w[i] && !strcmp(w[i], word)) pick = i;
    return pick;
}

void exp_tally_init(exp_tally *t, int m)
{
    memset(t, 0, sizeof *t);
    t->m = m > 0 ? m : 1;
}

double exp_tally_level(const exp_tally *t) { return t->m > 1 ? 1 - 0.05 / t->m : 0.95; }

void exp_tally_add(exp_tally *t, const exp_decider *d)
{
    double lo = fmin(d->lo, d->hi), hi = fmax(d->lo, d->hi);
    if (d->n >= 2 && lo == hi) { /* a self-ratio: no interval, no comparison */
        t->degenerate++;
        return;
    }
    if (t->added >= EXP_TALLY_MAX) return;
    const char *v = exp_judge(d);
    int i = t->added++;
    t->confirmed += !strcmp(v, EXP_CONFIRMED);
    t->refuted += !strcmp(v, EXP_REFUTED);
    t->online += !strcmp(v, EXP_ON_LINE);
    t->all[i] = *d;
    snprintf(t->whats[i], sizeof t->whats[i], "%s", d->what ? d->what : "");
    t->all[i].what = t->whats[i];
    const char *words[EXP_TALLY_MAX];
    double margins[EXP_TALLY_MAX];
    for (int k = 0; k < t->added; k++) words[k] = exp_judge(&t->all[k]), margins[k] = exp_margin(&t->all[k]);
    int pick = exp_decisive(exp_tally_verdict(t), words, margins, t->added);
    if (pick < 0) pick = i;
    t->worst = t->all[pick];
    snprintf(t->what, sizeof t->what, "%s", t->all[pick].what);
    t->worst.what = t->what;
}

void exp_tally_untestable(exp_tally *t) { t->untestable++; }

const char *exp_tally_verdict(const exp_tally *t)
{
    if (!t->added && !t->untestable) return NULL;
    const char *words[EXP_TALLY_MAX + 1];
    for (int k = 0; k < t->added; k++) words[k] = exp_judge(&t->all[k]);
    words[t->added] = t->untestable ? EXP_UNTESTABLE : NULL;
    return exp_combine(words, t->added + 1, EXP_EVERY);
}

const char *exp_compound(exp_tally *const *parts, int n, const exp_decider **dec)
{
    const char *words[16];
    double margins[16];
    if (n > 16) n = 16;
    for (int i = 0; i < n; i++) {
        words[i] = exp_tally_verdict(parts[i]);
        margins[i] = words[i] ? exp_margin(&parts[i]->worst) : NAN;
    }
    const char *word = exp_combine(words, n, EXP_PARTS);
    *dec = NULL;
    int pick = exp_decisive(word, words, margins, n);
    if (pick >= 0) *dec = &parts[pick]->worst;
    return word;
}

const char *exp_ref_normalize(exp_decider *d, int rate, double med, double fast, double slow,
                              const char *spread, double stray, char *why, size_t why_n)
{
    double f = med / EXP_REF_NS_PER_RAY, ff = fast / EXP_REF_NS_PER_RAY,
           fs = slow / EXP_REF_NS_PER_RAY;
    if (rate) /* a rate times the factor: the low end by the fast reference's */
        d->value *= f, d->lo *= ff, d->hi *= fs;
    else      /* a time over the factor: the low end over the slow reference's */
        d->value /= f, d->lo /= fs, d->hi /= ff;
    const char *v = exp_judge(d);
    int off = !(stray <= EXP_REF_STRAY) && !strcmp(v, EXP_ON_LINE);
    snprintf(why, why_n, "normalized to the stated reference rate (%.0f ns per ray of the "
             "reference kernel; %.0f ns beside these rounds, so the number is x %.2f; the "
             "interval's ends normalized by the fast and slow ends of the %s, %.0f and %.0f ns, so "
             "that it holds whichever normalization), the reference %s %.1f%%%s",
             EXP_REF_NS_PER_RAY, med, rate ? f : 1 / f, spread, fast, slow,
             stray <= EXP_REF_STRAY ? "stayed within" : "strayed by", 100 * stray,
             off ? " and the word depends on which end normalizes: not testable here"
             : stray <= EXP_REF_STRAY ? "" : ", but the word is the same at both ends");
    return off ? EXP_UNTESTABLE : v;
}
