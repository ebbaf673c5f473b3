/*
 * test_stats_coverage.c - the intervals the verdicts rest on
 * (experiments/stats.c) cover the true median as often as they say
 * (issue 38). Each test simulates the estimator: many synthetic
 * experiments of paired ratios with a known median, counting how often the
 * interval holds it. The simulation's own error is binomial: with E
 * experiments and true coverage p its standard error is sqrt(p (1 - p) / E);
 * the checks allow 3 of them (about 1% at E = 2000, p = 0.95).
 */
#include <math.h>
#include <string.h>

#include "experiments/stats.h"
#include "test.h"

/* splitmix64, then Box-Muller for normals: the test's own fixed stream. */
static uint64_t cov_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double cov_uniform(uint64_t *s) { return ((double)(cov_next(s) >> 11) + 0.5) / 9007199254740992.0; }

static double cov_normal(uint64_t *s)
{
    double u = cov_uniform(s), v = cov_uniform(s);
    return sqrt(-2 * log(u)) * cos(2 * M_PI * v);
}

/* One synthetic ratio with median `med`: lognormal (shape 0) or skewed
 * (shape 1: med + 0.3 (E - ln 2) for E exponential, whose median is ln 2;
 * a long right tail like a shared machine's interruptions). */
static double cov_ratio(uint64_t *s, int shape, double med)
{
    if (shape == 0) return med * exp(0.15 * cov_normal(s));
    return med + 0.3 * (-log(cov_uniform(s)) - log(2.0));
}

#define COV_RUNS 2000

/* Coverage of one estimator over COV_RUNS experiments of n ratios whose
 * true median is 1.3, drawn as paired times a = ratio * b. */
static double coverage(int n, int shape, int boot, uint64_t seed)
{
    int hold = 0, runs = boot ? COV_RUNS / 2 : COV_RUNS;
    for (int e = 0; e < runs; e++) {
        double a[EXP_MAX_SAMPLES], b[EXP_MAX_SAMPLES], r[EXP_MAX_SAMPLES];
        for (int i = 0; i < n; i++) {
            b[i] = 10 + cov_uniform(&seed);
            r[i] = cov_ratio(&seed, shape, 1.3);
            a[i] = r[i] * b[i];
        }
        exp_est est;
        if (boot)
            exp_est_boot(r, n, &est);
        else
            exp_est_ratio(a, b, n, &est);
        hold += est.lo <= 1.3 && est.hi >= 1.3;
    }
    return (double)hold / runs;
}

TEST(stats_coverage_order_statistic)
{
    double level;
    int k = exp_median_rank(10, &level);
    /* n = 10: x(2) and x(9), 1 - 2 * 11 / 1024 = 97.85% (Conover 1999, table A3). */
    CHECKF(k == 2 && fabs(level - (1 - 22.0 / 1024)) < 1e-12, "rank %d, level %.5f", k, level);
    k = exp_median_rank(9, &level);
    CHECKF(k == 2 && fabs(level - (1 - 20.0 / 512)) < 1e-12, "rank %d at n=9, level %.5f", k, level);
    exp_median_rank(5, &level);
    CHECKF(fabs(level - (1 - 2.0 / 32)) < 1e-12, "n=5 reaches only %.4f", level);
    exp_median_rank(10, &level);
    double se = sqrt(level * (1 - level) / COV_RUNS);
    for (int shape = 0; shape < 2; shape++) {
        double c = coverage(10, shape, 0, 0xC0FFEEull + (uint64_t)shape);
        CHECKF(fabs(c - level) <= 3 * se + 1e-9 && c >= 0.95 - 3 * sqrt(0.95 * 0.05 / COV_RUNS),
               "%s ratios, n=10: coverage %.4f, stated %.4f (3 SE = %.4f)",
               shape ? "skewed" : "lognormal", c, level, 3 * se);
    }
    /* The bootstrap it replaced under-covers at the n the old report used. */
    double boot = coverage(3, 0, 1, 0xB007ull);
    CHECKF(boot < 0.90, "bootstrap at n=3 covers %.3f, expected well under 95%%", boot);
}

/* Rounds replicated in 3 processes that differ by a process effect (log
 * sd 0.08) larger than the rounds' noise (log sd 0.02), 4 rounds each: the
 * pooled order-statistic interval alone under-covers the processes' common
 * median; the interval with the between-process t-interval does not. */
TEST(stats_coverage_between_processes)
{
    uint64_t seed = 0x9A0Cull;
    int hold = 0, hold_pooled = 0, wider = 0;
    for (int e = 0; e < COV_RUNS; e++) {
        double a[12], b[12];
        int proc[12];
        for (int p = 0; p < 3; p++) {
            double eff = 0.08 * cov_normal(&seed);
            for (int i = 0; i < 4; i++) {
                int j = 4 * p + i;
                proc[j] = p;
                b[j] = 5 + cov_uniform(&seed);
                a[j] = b[j] * 1.3 * exp(eff + 0.02 * cov_normal(&seed));
            }
        }
        exp_est with, pooled;
        exp_est_ratio_procs(a, b, proc, 12, &with);
        exp_est_ratio(a, b, 12, &pooled);
        hold += with.lo <= 1.3 && with.hi >= 1.3;
        hold_pooled += pooled.lo <= 1.3 && pooled.hi >= 1.3;
        wider += with.procs == 3 && with.between > with.within;
    }
    double c = (double)hold / COV_RUNS, cp = (double)hold_pooled / COV_RUNS;
    double se = sqrt(0.95 * 0.05 / COV_RUNS);
    CHECKF(c >= 0.95 - 3 * se, "with the between-process interval: coverage %.4f", c);
    CHECKF(cp < 0.80, "pooled rounds alone: coverage %.4f, expected far under 95%%", cp);
    CHECKF(wider > COV_RUNS / 2, "the between-process spread was the larger in %d of %d", wider,
           COV_RUNS);
    /* Student's t: the 97.5% point at 2 and 9 degrees of freedom. */
    CHECKF(fabs(exp_t_quantile(0.95, 2) - 4.303) < 2e-3 && fabs(exp_t_quantile(0.95, 9) - 2.262) < 2e-3,
           "t quantiles %.4f %.4f", exp_t_quantile(0.95, 2), exp_t_quantile(0.95, 9));
    CHECK(fabs(exp_bonferroni_level(5) - 0.99) < 1e-12);
}
