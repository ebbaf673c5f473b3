/*
 * group_stats.c - what a measured group's rounds say (group.h): times per
 * ray, paired speed-ups, counts per ray, the comparisons table and the
 * best configuration. Split from group.c, which measures.
 */
#include <math.h>
#include <string.h>

#include "group.h"

/* Whether round r is in the group's half (group.h). */
static int in_half(const exp_group *g, int r)
{
    if (!g->half || g->per_proc < 2) return 1;
    return (r % g->per_proc) % 2 == g->half - 1;
}

const int *exp_group_procs(const exp_group *g, int *buf)
{
    if (!g->half || g->per_proc < 2) return g->round_proc;
    int m = 0;
    for (int r = 0; r < g->rounds; r++)
        if (in_half(g, r)) buf[m++] = g->round_proc[r];
    return buf;
}

/* exp_group_round_ms over every round, the half left aside. */
static int all_round_ms(const exp_group *g, int c, int mask, double *out)
{
    const exp_cfg *cf = &g->cfg[c];
    int n = EXP_MAX_SAMPLES;
    for (int bit = 1; bit <= BENCH_AO; bit <<= 1) {
        const exp_trace *t = &cf->set[exp_set_index(bit)];
        if ((mask & bit) && t->have && t->n < n) n = t->n;
    }
    if (n == EXP_MAX_SAMPLES) n = 0;
    for (int r = 0; r < n; r++) {
        out[r] = 0;
        for (int bit = 1; bit <= BENCH_AO; bit <<= 1) {
            const exp_trace *t = &cf->set[exp_set_index(bit)];
            if ((mask & bit) && t->have) out[r] += t->samples[r];
        }
    }
    return n;
}

int exp_group_round_ms(const exp_group *g, int c, int mask, double *out)
{
    int n = all_round_ms(g, c, mask, out), m = 0;
    for (int r = 0; r < n; r++)
        if (in_half(g, r)) out[m++] = out[r];
    return m;
}

size_t exp_group_rays(const exp_group *g, int c, int mask)
{
    size_t n = 0;
    for (int bit = 1; bit <= BENCH_AO; bit <<= 1)
        if ((mask & bit) && g->cfg[c].set[exp_set_index(bit)].have)
            n += g->cfg[c].set[exp_set_index(bit)].rays;
    return n;
}

exp_est exp_group_ns(const exp_group *g, int c, int mask)
{
    double v[EXP_MAX_SAMPLES];
    int n = exp_group_round_ms(g, c, mask, v);
    exp_est e;
    int pb[EXP_MAX_SAMPLES];
    exp_est_of_procs(v, exp_group_procs(g, pb), n, &e);
    size_t rays = exp_group_rays(g, c, mask);
    return exp_est_scale(&e, rays ? 1e6 / (double)rays : 0);
}

exp_est exp_group_mrays(const exp_group *g, int c, int mask)
{
    exp_est ns = exp_group_ns(g, c, mask);
    return exp_est_inv(&ns, 1e3);
}

exp_est exp_group_speedup_level(const exp_group *g, int base, int c, int mask, double level)
{
    double a[EXP_MAX_SAMPLES], b[EXP_MAX_SAMPLES];
    int na = exp_group_round_ms(g, base, mask, a), nb = exp_group_round_ms(g, c, mask, b);
    exp_est e;
    int pb[EXP_MAX_SAMPLES];
    exp_est_ratio_level(a, b, exp_group_procs(g, pb), na < nb ? na : nb, level, &e);
    return e;
}

exp_est exp_group_speedup(const exp_group *g, int base, int c, int mask)
{
    return exp_group_speedup_level(g, base, c, mask, 0.95);
}

exp_est exp_group_ns_level(const exp_group *g, int c, int mask, double level)
{
    double v[EXP_MAX_SAMPLES];
    int n = exp_group_round_ms(g, c, mask, v);
    exp_est e;
    int pb[EXP_MAX_SAMPLES];
    exp_est_of_level(v, exp_group_procs(g, pb), n, level, &e);
    size_t rays = exp_group_rays(g, c, mask);
    return exp_est_scale(&e, rays ? 1e6 / (double)rays : 0);
}

static double per_ray(const exp_group *g, int c, int mask, int what)
{
    uint64_t v = 0;
    size_t rays = exp_group_rays(g, c, mask);
    for (int bit = 1; bit <= BENCH_AO; bit <<= 1) {
        const exp_trace *t = &g->cfg[c].set[exp_set_index(bit)];
        if (!(mask & bit) || !t->have) continue;
        v += what == 0 ? t->counters.steps : what == 1 ? t->counters.prim_tests : t->counters.box_tests;
    }
    return rays ? (double)v / (double)rays : 0;
}

double exp_group_steps(const exp_group *g, int c, int mask) { return per_ray(g, c, mask, 0); }
double exp_group_prims(const exp_group *g, int c, int mask) { return per_ray(g, c, mask, 1); }
double exp_group_boxes(const exp_group *g, int c, int mask) { return per_ray(g, c, mask, 2); }

void exp_group_compare_head(exp_group *g)
{
    exp_md(g->x, "\nComparisons (paired rounds; a tie is inside the interval or under the noise "
                 "floor of %.1f%%):\n", 100 * g->floor);
    exp_md_table(g->x, "comparison|rays|time change [95% CI]|speed-up [95% CI]|outcome");
}

int exp_group_compare(exp_group *g, int c, int base, int mask, char *buf, size_t n)
{
    exp_est r = exp_group_speedup(g, c, base, mask), sp = exp_est_inv(&r, 1.0);
    exp_fmt_pct(buf, n, &r);
    int cmp = exp_ratio_cmp(&r, g->floor);
    char s[96], sets[64] = "";
    for (int bit = 1; bit <= BENCH_AO; bit <<= 1)
        if ((mask & g->mask) & bit)
            snprintf(sets + strlen(sets), sizeof sets - strlen(sets), "%s%s", sets[0] ? "+" : "",
                     bench_set_name(bit));
    exp_md(g->x, "| `%s` against `%s` | %s | %s | %s | %s |\n", g->cfg[c].spec, g->cfg[base].spec,
           sets, buf, exp_fmt_x(s, sizeof s, &sp), cmp == 0 ? "a tie" : cmp < 0 ? "faster" : "slower");
    if (cmp == 0) snprintf(buf + strlen(buf), n - strlen(buf), " (a tie)");
    return cmp;
}

exp_est exp_group_build_ratio_level(const exp_group *g, int a, int b, double level)
{
    const exp_cfg *ca = &g->cfg[a], *cb = &g->cfg[b];
    exp_est r;
    if (ca->build_procs && cb->build_procs) { /* one build per process: paired by process */
        int ids[16];
        for (int p = 0; p < 16; p++) ids[p] = p;
        int m = ca->build_ms.n < cb->build_ms.n ? ca->build_ms.n : cb->build_ms.n;
        exp_est_ratio_level(ca->build_samples, cb->build_samples, ids, m, level, &r);
        return r;
    }
    int m = ca->build_ms.n < cb->build_ms.n ? ca->build_ms.n : cb->build_ms.n;
    exp_est_ratio_level(ca->build_samples, cb->build_samples, NULL, m, level, &r);
    return r;
}

int exp_group_compare_build(exp_group *g, int c, int base, char *buf, size_t n)
{
    const exp_cfg *a = &g->cfg[c], *b = &g->cfg[base];
    exp_est r = exp_group_build_ratio_level(g, c, base, 0.95), sp;
    sp = exp_est_inv(&r, 1.0);
    exp_fmt_pct(buf, n, &r);
    int cmp = exp_ratio_cmp(&r, g->floor);
    char s[96];
    exp_md(g->x, "| `%s` against `%s` | build | %s | %s | %s |\n", a->spec, b->spec, buf,
           exp_fmt_x(s, sizeof s, &sp), cmp == 0 ? "a tie" : cmp < 0 ? "faster" : "slower");
    if (cmp == 0) snprintf(buf + strlen(buf), n - strlen(buf), " (a tie)");
    return cmp;
}

int exp_group_best(const exp_group *g, int mask, int lo, int hi, const char *prefix)
{
    int best = -1;
    size_t pl = strlen(prefix);
    for (int c = lo; c < hi && c < g->count; c++)
        if (g->cfg[c].ok && !strncmp(g->cfg[c].spec, prefix, pl) &&
            (best < 0 || exp_group_ns(g, c, mask).median < exp_group_ns(g, best, mask).median))
            best = c;
    if (best < 0) return -1;
    int refined = best;
    double low = 1.0;
    for (int c = lo; c < hi && c < g->count; c++) {
        if (!g->cfg[c].ok || c == best || strncmp(g->cfg[c].spec, prefix, pl)) continue;
        exp_est r = exp_group_speedup(g, c, best, mask);
        if (r.n && r.median < low) low = r.median, refined = c;
    }
    return refined;
}

int exp_group_find(const exp_group *g, const char *spec)
{
    for (int c = 0; c < g->count; c++)
        if (!strcmp(g->cfg[c].spec, spec)) return c;
    return -1;
}

const char *exp_group_absolute(const exp_group *g, exp_decider *d, int rate, char *why, size_t n)
{
    if (g->ref.n < 2 || !(g->ref.median > 0) || !(g->ref_lo > 0)) {
        snprintf(why, n, "the reference kernel was not measured in these rounds: an absolute "
                 "threshold cannot be judged here");
        return EXP_UNTESTABLE;
    }
    return exp_ref_normalize(d, rate, g->ref.median, g->ref_lo, g->ref_hi, "process means",
                             g->ref_hi / g->ref_lo - 1, why, n);
}
