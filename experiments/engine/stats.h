/*
 * stats.h - the statistics every verdict of the study rests on.
 *
 * - A measurement is an estimate: the median of its samples with a
 *   distribution-free confidence interval of at least 95% from two order
 *   statistics (exp_median_rank; issue 38: the percentile bootstrap it
 *   replaces covered the true median 49% of the time at n = 2 and 93% at
 *   n = 5), plus min and max. Below 6 samples no pair of order statistics
 *   reaches 95%: the interval is min-max and `level` says what it covers.
 * - Samples from several processes (group.h runs every group's rounds in
 *   8 interleaved processes): the process is the unit of replication
 *   (issue 52). The estimate is the mean over processes of each process's
 *   mean (of logs, for times and ratios), the interval the t-interval on
 *   those means (df = processes - 1); n counts the processes. An interval
 *   on fewer than 6 units, below 95% or of zero width is never printed as
 *   a 95% interval (exp_est_is_95).
 * - Two estimates tie when their intervals overlap or they differ by less
 *   than the noise floor; a tie is never a win (exp_cmp).
 * - Configurations measured in interleaved rounds (A B A B ...) give paired
 *   samples: the ratio of round i's A to round i's B cancels the drift of a
 *   shared machine, and its bootstrap interval is the speed-up's.
 * - Rates of rare events carry an exact binomial upper bound
 *   (Clopper and Pearson 1934; for zero events 1 - 0.05^(1/n), about 3/n,
 *   the "rule of three").
 * - The cost model is fitted by non-negative least squares; a coefficient
 *   pinned at zero is reported, never dropped silently.
 * - Growth exponents are least-squares slopes on log-log points with the
 *   t-interval of the slope.
 */
#ifndef EXP_STATS_H
#define EXP_STATS_H

#include <stddef.h>
#include <stdint.h>

/* A median (or, from processes, the mean of the process means) with its
 * interval [lo, hi] (at least 95% from n >= 6), min,
 * max and the sample count (n == 0: nothing measured; n == 1: lo == hi ==
 * median). The rest is 0 when an estimate is written by hand: level, the
 * interval's coverage (exact for continuous data, exp_median_rank); procs,
 * the processes the samples came from; within and between, the relative
 * half-widths (log space for ratios) of the pooled interval and of the
 * t-interval on the processes' means (0 with fewer than 2 processes). With
 * 2 or more processes n counts the processes, not the samples. */
typedef struct {
    double median, lo, hi, min, max;
    int n;
    double level;
    int procs;
    double within, between;
} exp_est;
/* 1 when e's interval may be printed as a 95% interval: its level reaches
 * 95%, it rests on 6 or more units (processes, or samples from one
 * process; a t-interval with df >= 5) and it has a width (issue 52: a
 * zero-width self-ratio is not an interval). */
int exp_est_is_95(const exp_est *e);

/* The most samples one estimate holds. */
#define EXP_MAX_SAMPLES 64

void exp_est_of(const double *samples, int n, exp_est *out);
/* The rank k (1-based) of the order statistics x(k), x(n + 1 - k) that
 * bound the median at confidence 1 - 2 P(B <= k - 1), B ~ Binomial(n, 1/2):
 * the largest k whose level is still >= 95% (1 below n = 6). The level goes
 * to *level. Conover, Practical Nonparametric Statistics, 3rd ed. (1999),
 * section 3.2 (the confidence interval for a quantile). */
int exp_median_rank(int n, double *level);
/* exp_est_of for samples taken in several processes: proc[i] names the
 * process of sample i (NULL: one process). */
void exp_est_of_procs(const double *samples, const int *proc, int n, exp_est *out);
/* The percentile bootstrap (Efron 1979) the study used before issue 38,
 * kept for the coverage test that shows why it was replaced. */
void exp_est_boot(const double *samples, int n, exp_est *out);
/* Paired ratio a[i] / b[i] of the first n rounds (pairs with b[i] <= 0 are skipped),
 * estimated in log space (an even count's median is a geometric mean). */
void exp_est_ratio(const double *a, const double *b, int n, exp_est *out);
/* The same with the process of each round (exp_est_of_procs). */
void exp_est_ratio_procs(const double *a, const double *b, const int *proc, int n, exp_est *out);
/* k * e (k > 0) and k / e (e > 0): intervals follow (k / e swaps the ends). */
exp_est exp_est_scale(const exp_est *e, double k);
exp_est exp_est_inv(const exp_est *e, double k);
/* a / b for estimates that are not paired: the interval from the ends
 * (a.lo / b.hi, a.hi / b.lo), conservative. */
exp_est exp_est_div(const exp_est *a, const exp_est *b);

/* 1 when a and b cannot be told apart: their intervals, each widened by
 * the factor sqrt(1 + floor), overlap (two points tie when they differ by
 * less than the floor). The floor widens intervals, never overrules them. */
int exp_tie(const exp_est *a, const exp_est *b, double floor);
/* -1 when a is below b, 1 above, 0 a tie (exp_tie). */
int exp_cmp(const exp_est *a, const exp_est *b, double floor);
/* A ratio against 1: 0 when its interval widened by the factor 1 + floor
 * ([lo / (1 + floor), hi (1 + floor)]) holds 1, else -1 (below) or 1
 * (above). */
int exp_ratio_cmp(const exp_est *r, double floor);

/* "12.3 [12.1, 12.6] n=10": the median, its interval and the sample
 * count ("12.3" when n < 2); the formats below print n the same way. An
 * interval whose ends are more than EXP_MAX_SPAN apart (hi / lo) is not
 * printed: "12.3 (n=10; its interval spans more than 3x: not resolved)". */
#define EXP_MAX_SPAN 3.0
/* 1 when [lo, hi] (lo > 0) spans more than EXP_MAX_SPAN: not printed. */
static inline int exp_span_unresolved(double lo, double hi)
{
    return lo > 0 && hi > EXP_MAX_SPAN * lo;
}
const char *exp_fmt_est(char *buf, size_t n, const exp_est *e, int decimals);
/* A ratio as a change: "+20.2% [-3.1%, +41.0%] n=10" ("+20.2%" when n < 2). */
const char *exp_fmt_pct(char *buf, size_t n, const exp_est *ratio);
/* A factor: "1.84x [1.80, 1.90] n=10" ("1.84x" when n < 2). */
/* Both spreads of an estimate from several processes, e.g. "within
 * +-2.1%, between processes +-6.3% (3 processes)"; "" for one process. */
const char *exp_fmt_spreads(char *buf, size_t n, const exp_est *e);
/* The coverage each of m intervals needs so that all m hold together with
 * probability at least 95% (Bonferroni: 1 - 0.05 / m), for verdicts that
 * count "k of m scenes". */
double exp_bonferroni_level(int m);
/* The 1 - (1 - level) / 2 point of Student's t with df degrees of freedom
 * (the density integrated by Simpson's rule, then bisection). */
double exp_t_quantile(double level, int df);
/* exp_est_of_procs at coverage `level` (e.g. exp_bonferroni_level(m))
 * instead of 95%. */
void exp_est_of_level(const double *samples, const int *proc, int n, double level, exp_est *out);
void exp_est_ratio_level(const double *a, const double *b, const int *proc, int n, double level,
                         exp_est *out);
const char *exp_fmt_x(char *buf, size_t n, const exp_est *e);
/* The relative half-width of the interval, (hi - lo) / 2 / median. */
double exp_est_spread(const exp_est *e);

/* Upper end of the 95% interval of a binomial rate with k events in n
 * trials: one-sided 1 - 0.05^(1/n) for k == 0, else the two-sided
 * Clopper-Pearson bound. 1 when n == 0. */
double exp_binom_upper(uint64_t k, uint64_t n);

/* Non-negative least squares of y = sum_j coef[j] * x[j][i] over m <= 3
 * columns: every subset of free columns is solved and the feasible one with
 * the least squared residual kept, the empty subset (every coef 0)
 * included, so that there is always an answer. pinned[j] = 1 when coef[j]
 * was held at 0. Returns 0. */
typedef struct {
    double coef[3];
    int pinned[3];
    double sse;
} exp_fit;
int exp_nnls(const double *const *x, int m, const double *y, int n, exp_fit *out);
/* The unconstrained least squares of the same (0, or -1 when singular). */
int exp_lsq(const double *const *x, int m, const double *y, int n, double coef[3]);

/* Slope of log(y) against log(x) over the points with x, y > 0, with its
 * 95% t-interval (lo == hi == slope with 2 points). Returns the points used. */
int exp_loglog_slope(const double *x, const double *y, int n, exp_est *slope, double *intercept);

/* Coefficient of variation (standard deviation / mean) of n values. */
double exp_cv(const double *v, int n);
/* Pearson correlation of two columns (0 when either is constant). */
double exp_corr(const double *a, const double *b, int n);

/* A paired ratio estimate against an issue's target: "met" when its whole
 * 95% interval lies on the target's side, "not met" when it lies wholly on
 * the other, else "a tie with the target (inside the interval)". at_least:
 * the ratio must reach t (speed-ups, lo >= t); otherwise stay at or under t
 * (time ratios, hi <= t). */
const char *exp_target_outcome(const exp_est *r, double t, int at_least);
/* The same as a number: 1 met, 0 a tie, -1 not met. */
int exp_target_cmp(const exp_est *r, double t, int at_least);
/* A 2-thread over 1-thread ratio against target t: exp_target_outcome,
 * except that a miss is "not testable here" on a busy machine (busy: no
 * free core) or when the thread probe of the same rounds (probe, NULL or
 * n == 0 when there is none: work that touches no memory, group.h) has its
 * median under t too: then the machine held the ratio down. A probe at t or
 * more whose interval reaches below t excuses nothing: the row stays "not
 * met" and says so. Verdicts that miss start with "not met". */
const char *exp_threads_outcome(const exp_est *row, const exp_est *probe, int busy, double t);

#endif
