/*
 * stats.c - medians with order-statistic intervals, ties, paired ratios, binomial
 * bounds and the fits of the study (see stats.h).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "stats.h"

/* Resamples per bootstrap interval: the 2.5% and 97.5% points are the
 * 50th and 1950th of 2000 sorted medians. */
#define BOOT_RESAMPLES 2000

/* splitmix64 (Steele, Lea and Flood 2014): a fixed seed makes every
 * interval a function of its samples alone. */
static uint64_t next_rand(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median_sorted(const double *v, int n)
{
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* The percentile bootstrap (stats.h: kept for the coverage test). */
void exp_est_boot(const double *samples, int n, exp_est *out)
{
    memset(out, 0, sizeof *out);
    if (n <= 0) return;
    if (n > EXP_MAX_SAMPLES) n = EXP_MAX_SAMPLES;
    double v[EXP_MAX_SAMPLES], r[EXP_MAX_SAMPLES];
    memcpy(v, samples, (size_t)n * sizeof *v);
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    out->n = n, out->procs = 1, out->level = 0.95;
    out->min = v[0];
    out->max = v[n - 1];
    out->median = median_sorted(v, n);
    out->lo = out->hi = out->median;
    if (n < 2) return;
    static double meds[BOOT_RESAMPLES];
    uint64_t seed = 0x5EEDull ^ (uint64_t)n;
    for (int b = 0; b < BOOT_RESAMPLES; b++) {
        for (int i = 0; i < n; i++) r[i] = v[next_rand(&seed) % (uint64_t)n];
        qsort(r, (size_t)n, sizeof *r, cmp_double);
        meds[b] = median_sorted(r, n);
    }
    qsort(meds, BOOT_RESAMPLES, sizeof *meds, cmp_double);
    out->lo = meds[BOOT_RESAMPLES / 40];
    out->hi = meds[BOOT_RESAMPLES - 1 - BOOT_RESAMPLES / 40];
}

/* P(B <= k) for B ~ Binomial(n, 1/2), n <= 64: exact in doubles. */
static double binom_half_cdf(int k, int n)
{
    double c = 1, sum = 0; /* c = C(n, i) */
    for (int i = 0; i <= k && i <= n; i++) {
        sum += c;
        c = c * (n - i) / (i + 1);
    }
    return sum * pow(0.5, n);
}

/* exp_median_rank at any level: the largest k with 1 - 2 P(B <= k - 1) >=
 * level (k = 1 when none reaches it). */
static int median_rank_at(int n, double want, double *level)
{
    int k = 1;
    while (k + 1 <= (n + 1) / 2 && 1 - 2 * binom_half_cdf(k, n) >= want) k++;
    if (level) *level = n >= 1 ? 1 - 2 * binom_half_cdf(k - 1, n) : 0;
    return k;
}

int exp_median_rank(int n, double *level) { return median_rank_at(n, 0.95, level); }

double exp_bonferroni_level(int m) { return m > 1 ? 1 - 0.05 / m : 0.95; }

/* Student's t density with df degrees of freedom. */
static double t_density(double t, int df)
{
    double v = df;
    return exp(lgamma((v + 1) / 2) - lgamma(v / 2)) / sqrt(v * M_PI) * pow(1 + t * t / v, -(v + 1) / 2);
}

/* P(0 <= T <= t) by Simpson's rule (t >= 0). */
static double t_mass(double t, int df)
{
    const int steps = 2000;
    double h = t / steps, sum = t_density(0, df) + t_density(t, df);
    for (int i = 1; i < steps; i++) sum += (i % 2 ? 4 : 2) * t_density(i * h, df);
    return sum * h / 3;
}

/* The few (level, df) pairs a run asks for, remembered: each costs about
 * 10^5 density evaluations. The experiments compute estimates on one thread. */
#define T_CACHE 16
static struct { double level, t; int df; } t_cache[T_CACHE];
static int t_cached;

double exp_t_quantile(double level, int df)
{
    if (df < 1) return INFINITY;
    for (int i = 0; i < t_cached; i++)
        if (t_cache[i].df == df && t_cache[i].level == level) return t_cache[i].t;
    double lo = 0, hi = 1;
    while (t_mass(hi, df) < level / 2 && hi < 1e6) hi *= 2;
    for (int it = 0; it < 50; it++) {
        double mid = 0.5 * (lo + hi);
        if (t_mass(mid, df) < level / 2)
            lo = mid;
        else
            hi = mid;
    }
    double t = 0.5 * (lo + hi);
    int slot = t_cached < T_CACHE ? t_cached++ : df % T_CACHE;
    t_cache[slot].level = level, t_cache[slot].df = df, t_cache[slot].t = t;
    return t;
}

/* The order-statistic interval at `level` of n pooled samples (one
 * process, or fewer than 2 processes). With samples from 2 or more
 * processes the process is the unit of replication (issue 52): each
 * process's samples are averaged, the estimate is the mean of those
 * process means and the interval the t-interval on them (df = processes -
 * 1); n is then the number of processes. The
 * order-statistic half-width stays in `within` for the footers. */
static void est_core(const double *samples, const int *proc, int n, double level, exp_est *out)
{
    memset(out, 0, sizeof *out);
    if (n <= 0) return;
    if (n > EXP_MAX_SAMPLES) n = EXP_MAX_SAMPLES;
    double v[EXP_MAX_SAMPLES];
    memcpy(v, samples, (size_t)n * sizeof *v);
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    out->n = n, out->procs = 1;
    out->min = v[0];
    out->max = v[n - 1];
    out->median = median_sorted(v, n);
    out->lo = out->hi = out->median;
    if (n < 2) return;
    int k = median_rank_at(n, level, &out->level);
    out->lo = v[k - 1], out->hi = v[n - k];
    out->within = (out->hi - out->lo) / 2; /* absolute here; callers scale */
    if (!proc) return;
    /* Each process's value: the mean of its samples, or their median from
     * 3 samples on (4 rounds: the mean of the middle two). A slow spell of
     * the host covers one configuration of a round and not the other
     * (engine/harness.h), so a process's rounds hold an outlier now and
     * then; its median leaves it out where its mean carried a quarter of
     * it (the coverage test simulates both). */
    double means[EXP_MAX_SAMPLES];
    int p = 0;
    for (int id = 0; id < EXP_MAX_SAMPLES; id++) {
        int m = 0;
        double own[EXP_MAX_SAMPLES], sum = 0;
        for (int i = 0; i < n; i++)
            if (proc[i] == id) sum += samples[i], own[m++] = samples[i];
        if (!m) continue;
        if (m < 3) {
            means[p++] = sum / m;
            continue;
        }
        qsort(own, (size_t)m, sizeof *own, cmp_double);
        means[p++] = median_sorted(own, m);
    }
    out->procs = p;
    if (p < 2) return;
    double mean = 0, ss = 0;
    for (int i = 0; i < p; i++) mean += means[i];
    mean /= p;
    for (int i = 0; i < p; i++) ss += (means[i] - mean) * (means[i] - mean);
    double half = exp_t_quantile(level, p - 1) * sqrt(ss / (p - 1) / p);
    out->between = half;
    out->n = p;
    out->level = level;
    out->median = mean;
    out->lo = mean - half;
    out->hi = mean + half;
}

/* Positive samples (times) from several processes: the process means are
 * taken on the logs (a geometric mean per process), so that the interval
 * stays positive and treats a process 1.3x slower and one 1.3x faster
 * alike; min and max stay the samples'. */
void exp_est_of_level(const double *samples, const int *proc, int n, double level, exp_est *out)
{
    int positive = n > 0;
    for (int i = 0; i < n && i < EXP_MAX_SAMPLES; i++) positive &= samples[i] > 0;
    if (!proc || !positive) {
        est_core(samples, proc, n, level, out);
        double scale = fabs(out->median) > 0 ? fabs(out->median) : 1;
        out->within /= scale, out->between /= scale;
        return;
    }
    double lg[EXP_MAX_SAMPLES];
    int m = n < EXP_MAX_SAMPLES ? n : EXP_MAX_SAMPLES;
    for (int i = 0; i < m; i++) lg[i] = log(samples[i]);
    est_core(lg, proc, m, level, out);
    out->median = exp(out->median), out->lo = exp(out->lo), out->hi = exp(out->hi);
    out->min = exp(out->min), out->max = exp(out->max);
    /* Half-widths in log space are relative spreads already. */
}

void exp_est_of_procs(const double *samples, const int *proc, int n, exp_est *out)
{
    exp_est_of_level(samples, proc, n, 0.95, out);
}

void exp_est_of(const double *samples, int n, exp_est *out)
{
    exp_est_of_level(samples, NULL, n, 0.95, out);
}

/* Ratios are estimated in log space, so that a median of an even count is
 * the geometric mean of the middle two: the estimate of b/a is then the
 * inverse of that of a/b (exp_est_inv), median and interval alike. With the
 * arithmetic mean a report's finding quoted 2.35x for a speed-up its table,
 * which prints the inverse of the time ratio, showed as 1.98x [1.42, 3.29]
 * (four rounds of a quick report). Odd counts give the same order
 * statistics either way. */
void exp_est_ratio_level(const double *a, const double *b, const int *proc, int n, double level,
                         exp_est *out)
{
    double r[EXP_MAX_SAMPLES];
    int m = 0, pr[EXP_MAX_SAMPLES];
    for (int i = 0; i < n && m < EXP_MAX_SAMPLES; i++)
        if (b[i] > 0) pr[m] = proc ? proc[i] : 0, r[m++] = log(a[i] / b[i]);
    est_core(r, proc ? pr : NULL, m, level, out);
    if (out->n == 0) return;
    /* Half-widths in log space are relative spreads already. */
    out->median = exp(out->median), out->lo = exp(out->lo), out->hi = exp(out->hi);
    out->min = exp(out->min), out->max = exp(out->max);
}

void exp_est_ratio(const double *a, const double *b, int n, exp_est *out)
{
    exp_est_ratio_level(a, b, NULL, n, 0.95, out);
}

void exp_est_ratio_procs(const double *a, const double *b, const int *proc, int n, exp_est *out)
{
    exp_est_ratio_level(a, b, proc, n, 0.95, out);
}

exp_est exp_est_scale(const exp_est *e, double k)
{
    exp_est o = *e;
    o.median *= k, o.lo *= k, o.hi *= k, o.min *= k, o.max *= k;
    return o;
}

exp_est exp_est_inv(const exp_est *e, double k)
{
    exp_est o = *e;
    o.median = e->median > 0 ? k / e->median : 0;
    o.lo = e->hi > 0 ? k / e->hi : 0;
    o.hi = e->lo > 0 ? k / e->lo : 0;
    o.min = e->max > 0 ? k / e->max : 0;
    o.max = e->min > 0 ? k / e->min : 0;
    return o;
}

exp_est exp_est_div(const exp_est *a, const exp_est *b)
{
    exp_est o = {0};
    if (!(b->median > 0) || !(b->lo > 0)) return o;
    o.n = a->n < b->n ? a->n : b->n;
    o.median = a->median / b->median;
    o.lo = a->lo / b->hi;
    o.hi = a->hi / b->lo;
    o.min = a->min / b->max;
    o.max = a->max / b->min;
    return o;
}

/* The floor widens each interval by the factor sqrt(1 + floor), so that
 * two points tie when they differ by less than the floor (issue 52: a
 * floor may widen an interval, never overrule one). */
int exp_tie(const exp_est *a, const exp_est *b, double floor)
{
    double w = sqrt(1 + (floor > 0 ? floor : 0));
    double alo = a->lo / w, ahi = a->hi * w, blo = b->lo / w, bhi = b->hi * w;
    if (!(a->median > 0) || !(b->median > 0)) { /* not positive: widen by the floor additively */
        double s = floor * fmin(fabs(a->median), fabs(b->median));
        alo = a->lo - s, ahi = a->hi + s, blo = b->lo, bhi = b->hi;
    }
    return alo <= bhi && blo <= ahi;
}

int exp_cmp(const exp_est *a, const exp_est *b, double floor)
{
    if (exp_tie(a, b, floor)) return 0;
    return a->median < b->median ? -1 : 1;
}

int exp_ratio_cmp(const exp_est *r, double floor)
{
    /* The interval widened by the factor 1 + floor at both ends (symmetric
     * in the ratio: 1.25 and 0.8 are the same distance from 1); a tie when
     * it holds 1. The floor widens, it never overrules: a floor of any size
     * moves each end by the same factor. */
    double w = 1 + (floor > 0 ? floor : 0);
    if (r->lo / w <= 1.0 && r->hi * w >= 1.0) return 0;
    return r->median < 1.0 ? -1 : 1;
}

int exp_est_is_95(const exp_est *e)
{
    return e->n >= 6 && e->level >= 0.95 - 1e-9 && e->hi > e->lo;
}

/* " n=8", or " n=4, not a 95% interval" (exp_est_is_95). */
static const char *n_tail(char *b, size_t n, const exp_est *e)
{
    if (exp_est_is_95(e) || !(e->level > 0))
        snprintf(b, n, " n=%d", e->n);
    else if (e->procs >= 2)
        snprintf(b, n, " n=%d, t with df %d: not a 95%% interval", e->n, e->n - 1);
    else
        snprintf(b, n, " n=%d, covers %.0f%%: not a 95%% interval", e->n, 100 * e->level);
    return b;
}

/* Issue 52: no printed interval spans more than EXP_MAX_SPAN (hi / lo of
 * a positive interval; of 1 + the change for a percent): one that does is
 * printed as its median and "not resolved", never as an interval. */
static const char *wide_tail(char *b, size_t n, const exp_est *e)
{
    snprintf(b, n, " (n=%d; its interval spans more than %.0fx: not resolved)", e->n, EXP_MAX_SPAN);
    return b;
}

const char *exp_fmt_est(char *buf, size_t n, const exp_est *e, int decimals)
{
    char t[96];
    /* two significant digits of a positive lower end at least: 0.1 [0.0,
     * 0.1] said nothing of a 0.06 ms build */
    while (decimals < 6 && e->lo > 0 && e->lo < pow(10, 1 - decimals)) decimals++;
    if (e->n < 2 || !(e->hi > e->lo))
        snprintf(buf, n, "%.*f", decimals, e->median);
    else if (exp_span_unresolved(e->lo, e->hi))
        snprintf(buf, n, "%.*f%s", decimals, e->median, wide_tail(t, sizeof t, e));
    else
        snprintf(buf, n, "%.*f [%.*f, %.*f]%s", decimals, e->median, decimals, e->lo, decimals,
                 e->hi, n_tail(t, sizeof t, e));
    return buf;
}

const char *exp_fmt_spreads(char *buf, size_t n, const exp_est *e)
{
    if (e->procs < 2)
        snprintf(buf, n, "%s", "");
    else
        snprintf(buf, n, "within +-%.1f%%, between processes +-%.1f%% (%d processes)",
                 100 * e->within, 100 * e->between, e->procs);
    return buf;
}

const char *exp_fmt_pct(char *buf, size_t n, const exp_est *r)
{
    char t[96];
    if (r->n < 2 || !(r->hi > r->lo))
        snprintf(buf, n, "%+.1f%%", 100 * (r->median - 1));
    else if (exp_span_unresolved(r->lo, r->hi))
        snprintf(buf, n, "%+.1f%%%s", 100 * (r->median - 1), wide_tail(t, sizeof t, r));
    else
        snprintf(buf, n, "%+.1f%% [%+.1f%%, %+.1f%%]%s", 100 * (r->median - 1),
                 100 * (r->lo - 1), 100 * (r->hi - 1), n_tail(t, sizeof t, r));
    return buf;
}

const char *exp_fmt_x(char *buf, size_t n, const exp_est *e)
{
    char t[96];
    if (e->n < 2 || !(e->hi > e->lo))
        snprintf(buf, n, "%.2fx", e->median);
    else if (exp_span_unresolved(e->lo, e->hi))
        snprintf(buf, n, "%.2fx%s", e->median, wide_tail(t, sizeof t, e));
    else
        snprintf(buf, n, "%.2fx [%.2f, %.2f]%s", e->median, e->lo, e->hi, n_tail(t, sizeof t, e));
    return buf;
}

double exp_est_spread(const exp_est *e)
{
    return e->median > 0 ? (e->hi - e->lo) / 2 / e->median : 0;
}

/* log P(X <= k) for X ~ Binomial(n, p), summed in log space. */
static double log_binom_cdf(uint64_t k, uint64_t n, double p)
{
    if (p <= 0) return 0;
    if (p >= 1) return k >= n ? 0 : -INFINITY;
    double lp = log(p), lq = log1p(-p), lnf = lgamma((double)n + 1), acc = -INFINITY;
    for (uint64_t i = 0; i <= k && i <= n; i++) {
        double t = lnf - lgamma((double)i + 1) - lgamma((double)(n - i) + 1) + (double)i * lp +
                   (double)(n - i) * lq;
        double hi = fmax(acc, t);
        acc = hi == -INFINITY ? hi : hi + log(exp(acc - hi) + exp(t - hi));
    }
    return acc;
}

double exp_binom_upper(uint64_t k, uint64_t n)
{
    if (n == 0 || k >= n) return 1.0;
    if (k == 0) return 1.0 - pow(0.05, 1.0 / (double)n);
    /* The p at which P(X <= k) falls to 2.5%: the CDF decreases in p. */
    double lo = (double)k / (double)n, hi = 1.0, target = log(0.025);
    for (int it = 0; it < 60; it++) {
        double mid = 0.5 * (lo + hi);
        if (log_binom_cdf(k, n, mid) > target)
            lo = mid;
        else
            hi = mid;
    }
    return hi;
}

/* Solves the m x m system A c = r by Gaussian elimination with partial
 * pivoting; -1 when singular (relative to the matrix's scale). */
static int solve(double A[3][3], double r[3], int m, double c[3])
{
    double scale = 0;
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++) scale = fmax(scale, fabs(A[i][j]));
    if (!(scale > 0)) return -1;
    for (int col = 0; col < m; col++) {
        int piv = col;
        for (int i = col + 1; i < m; i++)
            if (fabs(A[i][col]) > fabs(A[piv][col])) piv = i;
        if (fabs(A[piv][col]) < 1e-12 * scale) return -1;
        for (int j = 0; j < m; j++) {
            double t = A[col][j];
            A[col][j] = A[piv][j];
            A[piv][j] = t;
        }
        double t = r[col];
        r[col] = r[piv];
        r[piv] = t;
        for (int i = 0; i < m; i++) {
            if (i == col) continue;
            double f = A[i][col] / A[col][col];
            for (int j = 0; j < m; j++) A[i][j] -= f * A[col][j];
            r[i] -= f * r[col];
        }
    }
    for (int i = 0; i < m; i++) c[i] = r[i] / A[i][i];
    return 0;
}

/* Least squares over the columns whose bit is set in `use`; coefficients
 * of the others are 0. Returns the squared residual, or -1 if singular. */
static double lsq_subset(const double *const *x, int m, const double *y, int n, unsigned use,
                         double coef[3])
{
    int idx[3], k = 0;
    for (int j = 0; j < m; j++) {
        coef[j] = 0;
        if (use & (1u << j)) idx[k++] = j;
    }
    if (k > 0) {
        if (n < k) return -1;
        double A[3][3] = {{0}}, r[3] = {0}, c[3];
        for (int i = 0; i < n; i++)
            for (int a = 0; a < k; a++) {
                r[a] += x[idx[a]][i] * y[i];
                for (int b = 0; b < k; b++) A[a][b] += x[idx[a]][i] * x[idx[b]][i];
            }
        if (solve(A, r, k, c)) return -1;
        for (int a = 0; a < k; a++) coef[idx[a]] = c[a];
    }
    double sse = 0;
    for (int i = 0; i < n; i++) {
        double p = 0;
        for (int j = 0; j < m; j++) p += coef[j] * x[j][i];
        sse += (y[i] - p) * (y[i] - p);
    }
    return sse;
}

int exp_lsq(const double *const *x, int m, const double *y, int n, double coef[3])
{
    return lsq_subset(x, m, y, n, (1u << m) - 1, coef) < 0 ? -1 : 0;
}

int exp_nnls(const double *const *x, int m, const double *y, int n, exp_fit *out)
{
    memset(out, 0, sizeof *out);
    /* Every coefficient pinned at 0 is feasible too: the answer when every
     * other subset wants a negative coefficient (a fixed term that alone
     * over-predicts every point). */
    out->sse = 0;
    for (int i = 0; i < n; i++) out->sse += y[i] * y[i];
    for (int j = 0; j < m; j++) out->pinned[j] = 1;
    for (unsigned use = 1; use < (1u << m); use++) {
        double c[3];
        double sse = lsq_subset(x, m, y, n, use, c);
        if (sse < 0) continue;
        int feasible = 1;
        for (int j = 0; j < m; j++) feasible &= c[j] >= 0;
        if (!feasible || sse >= out->sse) continue;
        out->sse = sse;
        for (int j = 0; j < m; j++) {
            out->coef[j] = c[j];
            out->pinned[j] = !(use & (1u << j));
        }
    }
    return 0;
}

/* 97.5% points of Student's t for 1..30 degrees of freedom. */
static const double t975[30] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306,
                                2.262,  2.228, 2.201, 2.179, 2.160, 2.145, 2.131, 2.120,
                                2.110,  2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064,
                                2.060,  2.056, 2.052, 2.048, 2.045, 2.042};

int exp_loglog_slope(const double *x, const double *y, int n, exp_est *slope, double *intercept)
{
    double lx[256], ly[256];
    int m = 0;
    for (int i = 0; i < n && m < 256; i++)
        if (x[i] > 0 && y[i] > 0) lx[m] = log(x[i]), ly[m] = log(y[i]), m++;
    memset(slope, 0, sizeof *slope);
    if (intercept) *intercept = 0;
    if (m < 2) return m;
    double mx = 0, my = 0;
    for (int i = 0; i < m; i++) mx += lx[i], my += ly[i];
    mx /= m, my /= m;
    double sxx = 0, sxy = 0;
    for (int i = 0; i < m; i++) sxx += (lx[i] - mx) * (lx[i] - mx), sxy += (lx[i] - mx) * (ly[i] - my);
    if (!(sxx > 0)) return 0;
    double b = sxy / sxx, a = my - b * mx, sse = 0;
    for (int i = 0; i < m; i++) sse += (ly[i] - a - b * lx[i]) * (ly[i] - a - b * lx[i]);
    slope->n = m;
    slope->median = slope->min = slope->max = b;
    double half = 0;
    if (m > 2) half = (m - 2 <= 30 ? t975[m - 3] : 1.96) * sqrt(sse / (m - 2) / sxx);
    slope->lo = b - half;
    slope->hi = b + half;
    if (intercept) *intercept = a;
    return m;
}

double exp_cv(const double *v, int n)
{
    if (n < 2) return 0;
    double m = 0, s = 0;
    for (int i = 0; i < n; i++) m += v[i];
    m /= n;
    for (int i = 0; i < n; i++) s += (v[i] - m) * (v[i] - m);
    return m != 0 ? sqrt(s / (n - 1)) / fabs(m) : 0;
}

double exp_corr(const double *a, const double *b, int n)
{
    double ma = 0, mb = 0;
    for (int i = 0; i < n; i++) ma += a[i], mb += b[i];
    if (n < 2) return 0;
    ma /= n, mb /= n;
    double sab = 0, saa = 0, sbb = 0;
    for (int i = 0; i < n; i++) {
        sab += (a[i] - ma) * (b[i] - mb);
        saa += (a[i] - ma) * (a[i] - ma);
        sbb += (b[i] - mb) * (b[i] - mb);
    }
    return saa > 0 && sbb > 0 ? sab / sqrt(saa * sbb) : 0;
}

int exp_target_cmp(const exp_est *r, double t, int at_least)
{
    int met = at_least ? r->lo >= t : r->hi <= t, missed = at_least ? r->hi < t : r->lo > t;
    return met ? 1 : missed ? -1 : 0;
}

const char *exp_target_outcome(const exp_est *r, double t, int at_least)
{
    int o = exp_target_cmp(r, t, at_least);
    return o > 0 ? "met" : o < 0 ? "not met" : "a tie with the target (inside the interval)";
}

const char *exp_threads_outcome(const exp_est *row, const exp_est *probe, int busy, double t)
{
    const char *v = exp_target_outcome(row, t, 1);
    int has_probe = probe && probe->n;
    if (!strcmp(v, "met")) return v;
    if (busy) return "not testable here (no free core)";
    if (has_probe && probe->median < t) return "not testable here (the probe's median stayed below the target too)";
    if (!strcmp(v, "not met") && has_probe && probe->lo < t)
        return "not met (the probe's interval reaches below the target too, its median does not)";
    return v;
}
