/*
 * test_report_checks.c - the report a referee would accept, checked on the
 * quick run (build/quick-report, made by report_quick_smoke or here):
 * no nan or inf in any table or CSV, every CSV strict RFC 4180 with one
 * column count, no finding cut short, every number a finding quotes
 * present in its section's tables, no interval that holds zero presented
 * as a difference, and the summary table with a verdict for every claim.
 * Also the statistics the verdicts rest on (ties, bootstrap intervals,
 * binomial bounds, non-negative fits) and the SVG axes.
 */
#include <ctype.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "support.h"
#include "test.h"
#include "experiments/engine/claims.h"
#include "experiments/engine/stats.h"
#include "experiments/engine/svg.h"

#ifndef DIR_OUT
#define DIR_OUT "build/quick-report"
#endif

/* Calls fn(path, text) for every file of the quick report ending in ext
 * (and starting with "exp_" when sections_only). */
static int sections_only;
static int each_file(const char *ext, void (*fn)(const char *path, char *text))
{
    DIR *d = opendir(DIR_OUT);
    struct dirent *e;
    int n = 0;
    size_t el = strlen(ext);
    while (d && (e = readdir(d))) {
        size_t l = strlen(e->d_name);
        if (l < el || strcmp(e->d_name + l - el, ext)) continue;
        if (sections_only && strncmp(e->d_name, "exp_", 4)) continue;
        char path[512];
        snprintf(path, sizeof path, DIR_OUT "/%s", e->d_name);
        char *text = test_read_file(path, NULL);
        if (text) fn(path, text), n++;
        free(text);
    }
    if (d) closedir(d);
    return n;
}

/* A word nan or inf (any case, any sign) in s. */
static int has_nonfinite(const char *s)
{
    for (const char *p = s; *p; p++) {
        if (p > s && isalnum((unsigned char)p[-1])) continue;
        if ((!strncasecmp(p, "nan", 3) || !strncasecmp(p, "inf", 3)) && !isalnum((unsigned char)p[3]))
            return 1;
    }
    return 0;
}

static void check_tables_finite(const char *path, char *text)
{
    for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n"))
        if (line[0] == '|') CHECKF(!has_nonfinite(line), "%s: a table row holds nan or inf: %.200s", path, line);
}

TEST(report_quick_tables_finite)
{
    if (!test_quick_report()) return;
    CHECKF(each_file(".md", check_tables_finite) >= 12, "too few Markdown files in " DIR_OUT);
}

/* Strict RFC 4180: fields separated by commas, records by LF or CRLF,
 * quoted fields with doubled quotes, no quote inside an unquoted field,
 * one field count for every record. Returns records, -1 when malformed. */
static int strict_csv(const char *s, int *columns, char *why, size_t wn)
{
    int records = 0;
    *columns = -1;
    while (*s) {
        int fields = 0;
        for (;;) {
            if (*s == '"') {
                for (s++;; s++) {
                    if (!*s) return snprintf(why, wn, "record %d: unterminated quote", records + 1), -1;
                    if (*s == '"' && s[1] == '"') s++;
                    else if (*s == '"') { s++; break; }
                }
            } else {
                for (; *s && *s != ',' && *s != '\n' && *s != '\r'; s++)
                    if (*s == '"') return snprintf(why, wn, "record %d: a quote inside an unquoted field", records + 1), -1;
            }
            fields++;
            if (*s == ',') { s++; continue; }
            if (*s == '\r' && s[1] == '\n') s += 2;
            else if (*s == '\n') s++;
            else if (*s) return snprintf(why, wn, "record %d: text after a closing quote", records + 1), -1;
            break;
        }
        if (*columns < 0) *columns = fields;
        if (fields != *columns)
            return snprintf(why, wn, "record %d has %d fields, the header %d", records + 1, fields, *columns), -1;
        records++;
    }
    return records;
}

static void check_csv(const char *path, char *text)
{
    char why[160] = "";
    int cols, n = strict_csv(text, &cols, why, sizeof why);
    CHECKF(n >= 1, "%s: not strict RFC 4180 CSV: %s", path, why);
    CHECKF(!has_nonfinite(text), "%s: a field holds nan or inf", path);
}

TEST(report_quick_csv_strict)
{
    if (!test_quick_report()) return;
    char why[160];
    int cols;
    /* The reader itself must refuse what RFC 4180 refuses. */
    CHECK(strict_csv("a,b\n1,2\n", &cols, why, sizeof why) == 2 && cols == 2);
    CHECK(strict_csv("a,b\n\"x,\"\"y\"\"\",2\r\n", &cols, why, sizeof why) == 2);
    CHECK(strict_csv("a,b\n1,2,3\n", &cols, why, sizeof why) < 0);
    CHECK(strict_csv("a,b\nx\"y,2\n", &cols, why, sizeof why) < 0);
    CHECK(strict_csv("a,b\n\"x\"y,2\n", &cols, why, sizeof why) < 0);
    CHECKF(each_file(".csv", check_csv) >= 22, "too few CSV files in " DIR_OUT);
}

/* The findings of a section: the "- " lines after its **Findings line. */
static void check_findings(const char *path, char *text)
{
    char *f = strstr(text, "\n**Findings");
    CHECKF(f != NULL, "%s: no findings", path);
    if (!f) return;
    CHECKF(strstr(text, " ran in ") != NULL, "%s: the section has no footer (cut short?)", path);
    *f = 0; /* text: the section above its findings */
    char *body = text;
    int lines = 0;
    for (char *line = strtok(f + 1, "\n"); line; line = strtok(NULL, "\n")) {
        if (strncmp(line, "- ", 2)) continue;
        lines++;
        size_t l = strlen(line);
        char last = l ? line[l - 1] : 0;
        CHECKF(last == '.' || last == ')' || last == ':', "%s: a finding ends mid-sentence: %.300s",
               path, line);
        /* Every measured-looking number (decimals, percentages, factors)
         * must stand in the section above, where its table is. */
        for (const char *p = line; *p; p++) {
            if (!isdigit((unsigned char)*p) || (p > line && (isalnum((unsigned char)p[-1]) ||
                                                             p[-1] == '.' || p[-1] == '=' || p[-1] == '_')))
                continue;
            const char *q = p;
            while (isdigit((unsigned char)*q) || *q == '.') q++;
            if (q[-1] == '.') q--;
            int decimal = memchr(p, '.', (size_t)(q - p)) != NULL;
            int unit = *q == '%' || (*q == 'x' && !isalnum((unsigned char)q[1]));
            if (decimal || unit) {
                char tok[64];
                snprintf(tok, sizeof tok, "%.*s%s", (int)(q - p), p, *q == '%' ? "%" : "");
                CHECKF(strstr(body, tok) != NULL, "%s: the finding quotes %s, which its tables "
                       "do not show: %.200s", path, tok, line);
            }
            p = q - 1;
        }
    }
    (void)lines;
}

TEST(report_quick_findings_complete)
{
    if (!test_quick_report()) return;
    sections_only = 1;
    CHECKF(each_file(".md", check_findings) >= 11, "too few sections");
    sections_only = 0;
}

/* A row showing a change with an interval that holds zero must say tie. */
static void check_ties(const char *path, char *text)
{
    for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
        if (line[0] != '|') continue;
        const char *p = line;
        while ((p = strstr(p, "% ["))) {
            double lo, hi;
            if (sscanf(p + 3, "%lf%%, %lf%%]", &lo, &hi) == 2 && lo <= 0 && hi >= 0)
                CHECKF(strstr(line, "tie") != NULL, "%s: an interval holding zero is not called "
                       "a tie: %.300s", path, line);
            p += 3;
        }
    }
}

TEST(report_quick_ties_not_wins)
{
    if (!test_quick_report()) return;
    each_file(".md", check_ties);
}

TEST(report_quick_summary_verdicts)
{
    if (!test_quick_report()) return;
    char *r = test_read_file(DIR_OUT "/REPORT.md", NULL);
    CHECKF(r != NULL, DIR_OUT "/REPORT.md missing");
    if (!r) return;
    char *sum = strstr(r, "## Summary"), *contents = strstr(r, "## Contents");
    CHECKF(sum && contents && sum < contents, "no summary before the contents");
    if (!sum || !contents) { free(r); return; }
    *contents = 0;
    for (int c = 0; c < exp_claim_count; c++) {
        char tag[96];
        snprintf(tag, sizeof tag, " `%s` | ", exp_claims[c].id);
        char *row = strstr(sum, tag);
        CHECKF(row != NULL, "the summary has no row for claim %s", exp_claims[c].id);
        if (!row) continue;
        char *end = strchr(row, '\n');
        if (end) *end = 0;
        /* the verdict cell: one of the six labels, "(N rows)" after it when several */
        static const char *const labels[] = {EXP_CONFIRMED, EXP_PARTLY, EXP_REFUTED, EXP_UNTESTABLE,
                                             EXP_ON_LINE, EXP_ANSWERED};
        const char *cell = row + strlen(tag);
        int ok = 0;
        for (int k = 0; k < 6; k++) {
            size_t n = strlen(labels[k]);
            ok |= !strncmp(cell, labels[k], n) && (!strncmp(cell + n, " |", 2) || !strncmp(cell + n, " (", 2));
        }
        CHECKF(ok, "claim %s has no verdict: %.300s", exp_claims[c].id, row);
        if (end) *end = '\n';
    }
    *contents = '#';
    CHECK(strstr(r, "## Machine and method") && strstr(r, "| machine |") && strstr(r, "| commit |"));
    CHECK(strstr(r, "> **Verdict on ") != NULL);
    free(r);
}

/* Every section's footer states how many interleaved rounds it timed: at
 * least one (exp_grid_packet and exp_wide once said "0 to 0", timing
 * outside the rounds they claimed). */
static void check_rounds(const char *path, char *text)
{
    const char *f = strstr(text, " interleaved timed rounds per configuration");
    CHECKF(f != NULL, "%s: the footer does not state its rounds", path);
    if (!f) return;
    const char *p = f;
    while (p > text && p[-1] != ';') p--;
    int lo = -1, hi = -1;
    CHECKF(sscanf(p, " %d to %d", &lo, &hi) == 2 && lo >= 1 && hi >= lo,
           "%s: footer rounds %d to %d: %.80s", path, lo, hi, p);
}

TEST(report_quick_footer_rounds)
{
    if (!test_quick_report()) return;
    sections_only = 1;
    CHECKF(each_file(".md", check_rounds) >= 11, "too few sections");
    sections_only = 0;
}

/* The run record names every section's own wall time and their sum. */
static char *run_row;
static void check_run_time(const char *path, char *text)
{
    (void)text;
    const char *name = strrchr(path, '/') + 1;
    char tag[128];
    snprintf(tag, sizeof tag, "%.*s ", (int)(strlen(name) - 3), name);
    const char *at = run_row ? strstr(run_row, tag) : NULL;
    int sec = -1;
    CHECKF(at && sscanf(at + strlen(tag), "%d s", &sec) == 1 && sec >= 0,
           "the run record has no wall time for %s", name);
}

TEST(report_quick_run_times)
{
    if (!test_quick_report()) return;
    char *r = test_read_file(DIR_OUT "/REPORT.md", NULL);
    CHECKF(r != NULL, DIR_OUT "/REPORT.md missing");
    if (!r) return;
    run_row = strstr(r, "| run | ");
    char *end = run_row ? strchr(run_row, '\n') : NULL;
    if (end) *end = 0;
    CHECKF(run_row && strstr(run_row, "per experiment: ") && strstr(run_row, "(sum "),
           "the run record has no per-experiment times: %.300s", run_row ? run_row : "(none)");
    sections_only = 1;
    each_file(".md", check_run_time);
    sections_only = 0;
    run_row = NULL;
    free(r);
}

/* Issue 11's and issue 13's closing tables: every kernel they compare has
 * its row or is left out with a reason; the targets are stated. */
static void check_rows(const char *path, const char *const *specs, int n, const char *must)
{
    char *t = test_read_file(path, NULL);
    CHECKF(t != NULL, "%s missing", path);
    if (!t) return;
    for (int i = 0; i < n; i++) {
        char row[128], left[128];
        snprintf(row, sizeof row, "| `%s` |", specs[i]);
        snprintf(left, sizeof left, "`%s` (", specs[i]);
        CHECKF(strstr(t, row) || strstr(t, left), "%s: no row for %s", path, specs[i]);
    }
    CHECKF(strstr(t, must) != NULL, "%s: no %s", path, must);
    free(t);
}

TEST(report_quick_issue_tables)
{
    if (!test_quick_report()) return;
    static const char *const wide[] = {"bvh", "bvh:width=4", "bvh:width=8", "bvh:traverse=packet",
                                       "bvh:width=4,traverse=packet", "bvh:width=8,traverse=packet"};
    /* The 2-thread rows, each with the thread probe of its rounds. */
    check_rows(DIR_OUT "/exp_wide.md", wide, 6, "on 2 threads over 1 (thread probe: ");
    /* The probe is a ratio of 2 threads to 1 with its interval: above 1
     * and at most 2 give or take the noise on a machine with 2 free cores,
     * and a machine with one would have said "no free core" instead. */
    char *t = test_read_file(DIR_OUT "/exp_wide.md", NULL);
    const char *p = t ? strstr(t, "(thread probe: ") : NULL;
    double x = 0, lo = 0, hi = 0;
    /* An interval wider than 3x (a loaded machine) prints as its median
     * with "not resolved" (stats.h, EXP_MAX_SPAN): a ratio all the same. */
    int got = p ? sscanf(p, "(thread probe: %lfx [%lf, %lf])", &x, &lo, &hi) : 0;
    if (p && got == 1) {
        const char *nr = strstr(p, "not resolved"), *nl = strchr(p, '\n');
        if (nr && (!nl || nr < nl)) got = 3, lo = hi = x;
    }
    CHECKF(got == 3, "exp_wide.md: no thread probe ratio");
    CHECKF(x > 0.5 && x < 2.3 && lo <= x && x <= hi, "thread probe %.2fx [%.2f, %.2f]", x, lo, hi);
    free(t);
    static const char *const grids[] = {"bvh", "grid", "grid:skip=cloud", "grid:skip=macro",
                                        "grid:traverse=packet", "nested_grid", "irregular_grid",
                                        "irregular_grid:subdivide=0", "irregular_grid:merge=0",
                                        "irregular_grid:expand=0"};
    check_rows(DIR_OUT "/exp_grids.md", grids, 10, "| at least 5x |");
}

/* 2 threads over 1 against 1.9x: a miss is the machine's only when the
 * thread probe of the same rounds missed too (its median), or when no core
 * was free; a probe that reached 1.9x at its median excuses nothing. */
TEST(report_threads_outcome_probe_rule)
{
    exp_est row_low = {1.78, 1.71, 1.84, 1.70, 1.85, 5, 0, 0, 0, 0}, row_tie = {1.88, 1.80, 1.95, 1.8, 1.95, 5, 0, 0, 0, 0};
    exp_est row_met = {1.97, 1.92, 2.01, 1.9, 2.02, 5, 0, 0, 0, 0};
    exp_est probe_ok = {1.99, 1.95, 2.01, 1.95, 2.01, 5, 0, 0, 0, 0}, probe_wide = {1.98, 1.78, 2.00, 1.78, 2.0, 5, 0, 0, 0, 0};
    exp_est probe_low = {1.85, 1.70, 1.95, 1.7, 1.95, 5, 0, 0, 0, 0}, none = {0};
    CHECK(!strcmp(exp_threads_outcome(&row_met, &probe_low, 1, 1.9), "met"));
    CHECK(!strcmp(exp_threads_outcome(&row_low, &probe_ok, 0, 1.9), "not met"));
    CHECK(!strcmp(exp_threads_outcome(&row_low, &none, 0, 1.9), "not met"));
    CHECK(!strcmp(exp_threads_outcome(&row_low, NULL, 0, 1.9), "not met"));
    /* The last report's soup row: the probe 1.98x [1.78, 2.00] was called
     * "did not reach 1.9x either"; it did, at its median. */
    const char *w = exp_threads_outcome(&row_low, &probe_wide, 0, 1.9);
    CHECKF(!strncmp(w, "not met (", 9), "a probe at 1.98x excused a miss: %s", w);
    CHECK(!strncmp(exp_threads_outcome(&row_low, &probe_low, 0, 1.9), "not testable here", 17));
    CHECK(!strncmp(exp_threads_outcome(&row_low, &probe_ok, 1, 1.9), "not testable here (no free", 26));
    CHECK(!strncmp(exp_threads_outcome(&row_tie, &probe_ok, 0, 1.9), "a tie", 5));
    CHECK(!strncmp(exp_threads_outcome(&row_tie, &probe_low, 0, 1.9), "not testable here", 17));
}

TEST(report_stats_ties_and_intervals)
{
    /* 10 paired rounds: order statistics 2 and 9 bound the median (97.9%). */
    double a[10] = {10, 11, 10.5, 12, 9.8, 10.2, 30, 10.1, 10.4, 10.6},
           b[10] = {20, 21, 20.5, 22, 19.8, 20.2, 25, 20.1, 20.4, 20.6};
    exp_est ea, eb, ea2;
    exp_est_of(a, 10, &ea);
    exp_est_of(a, 10, &ea2);
    exp_est_of(b, 10, &eb);
    CHECK(ea.median == 10.45 && ea.lo <= ea.median && ea.hi >= ea.median && ea.n == 10);
    CHECK(ea.lo == ea2.lo && ea.hi == ea2.hi); /* deterministic */
    CHECKF(ea.hi < 30 && ea.lo > 9.8 && ea.level > 0.95, "[%g, %g] at %g", ea.lo, ea.hi, ea.level);
    CHECK(exp_cmp(&ea, &eb, 0.01) == -1 && exp_cmp(&eb, &ea, 0.01) == 1);
    exp_est c = ea;
    c.median *= 1.02, c.lo = c.hi = c.median; /* 2% apart, no overlap: a tie only under a 5% floor */
    exp_est d = ea;
    d.lo = d.hi = d.median;
    CHECK(exp_tie(&c, &d, 0.05) && !exp_tie(&c, &d, 0.01));
    exp_est r = {1.3, 0.9, 1.5, 0.9, 1.5, 5, 0, 0, 0, 0};
    CHECK(exp_ratio_cmp(&r, 0.01) == 0); /* the interval holds 1 */
    r.lo = 1.2;
    CHECK(exp_ratio_cmp(&r, 0.01) == 1 && exp_ratio_cmp(&r, 0.4) == 0);
    exp_est q;
    exp_est_ratio(a, b, 10, &q);
    CHECK(q.median > 0.45 && q.median < 0.55 && exp_ratio_cmp(&q, 0.05) == -1);
    /* An even count of paired ratios: the estimate of b/a is the inverse of
     * that of a/b (a finding quoting one and a table the other must agree;
     * arithmetic middle means gave 2.35 against 1 / 0.51 = 1.98). */
    {
        double ta[4] = {10, 20, 30, 12}, tb[4] = {4, 5, 13, 7};
        exp_est ab, ba;
        exp_est_ratio(ta, tb, 4, &ab);
        exp_est_ratio(tb, ta, 4, &ba);
        exp_est inv = exp_est_inv(&ba, 1.0);
        CHECKF(fabs(ab.median - inv.median) < 1e-12 * ab.median &&
                   fabs(ab.lo - inv.lo) < 1e-12 * ab.lo && fabs(ab.hi - inv.hi) < 1e-12 * ab.hi,
               "ratio %.6f [%.6f, %.6f], inverse of the inverse %.6f [%.6f, %.6f]", ab.median, ab.lo,
               ab.hi, inv.median, inv.lo, inv.hi);
        /* middle ratios 30/13 and 10/4: their geometric mean */
        CHECK(fabs(ab.median - sqrt((30.0 / 13) * (10.0 / 4))) < 1e-12);
    }
    /* Clopper-Pearson: 0 in n is about 3/n; 5 in 1000 is 1.16%. */
    CHECK(fabs(exp_binom_upper(0, 3000) - 3.0 / 3000) < 0.05 * 3.0 / 3000);
    CHECK(fabs(exp_binom_upper(5, 1000) - 0.01164) < 2e-4);
    /* NNLS pins a negative constant at zero and says so. */
    double s[5] = {1, 2, 3, 4, 5}, p[5] = {2, 1, 4, 3, 6}, one[5] = {1, 1, 1, 1, 1}, y[5];
    for (int i = 0; i < 5; i++) y[i] = 2 * s[i] + 3 * p[i] - 4;
    const double *cols[3] = {s, p, one};
    exp_fit fit;
    CHECK(exp_nnls(cols, 3, y, 5, &fit) == 0 && fit.pinned[2] && fit.coef[2] == 0 &&
          !fit.pinned[0] && !fit.pinned[1]);
    for (int i = 0; i < 5; i++) y[i] = 2 * s[i] + 3 * p[i] + 1;
    CHECK(exp_nnls(cols, 3, y, 5, &fit) == 0 && fabs(fit.coef[2] - 1) < 1e-9 && !fit.pinned[2]);
    double xs[4] = {1000, 4000, 16000, 64000}, ys[4] = {1, 4.1, 15.9, 64.5};
    exp_est sl;
    CHECK(exp_loglog_slope(xs, ys, 4, &sl, NULL) == 4 && sl.lo < 1 && sl.hi > 1);
    char buf[64];
    exp_est w = {1.0, 1.0, 1.0, 1.0, 1.0, 1, 0, 0, 0, 0};
    CHECK(!strcmp(exp_fmt_est(buf, sizeof buf, &w, 1), "1.0")); /* no interval from one sample */
}

TEST(report_svg_ticks)
{
    double t[64];
    int n = svg_ticks(0, 10, 0, t, 64);
    CHECK(n >= 4 && n <= 12 && t[0] == 0 && t[n - 1] <= 10);
    n = svg_ticks(1, 1000, 1, t, 64);
    CHECK(n == 4 && t[0] == 1 && t[3] == 1000);
    n = svg_ticks(1, 50, 1, t, 64); /* short range: 1 2 5 10 20 50 */
    CHECK(n == 6 && t[1] == 2 && t[5] == 50);
    svg_plot pl;
    svg_plot_init(&pl, "a <title> & more", "x", "y");
    double x[3] = {1, 10, 100}, y[3] = {3, 2, 1};
    CHECK(svg_add(&pl, "s", x, y, NULL, NULL, 3, SVG_LINE | SVG_POINTS) == 0);
    CHECK(svg_write(&pl, "build/test_plot.svg") == 0);
    svg_free(&pl);
    char *s = test_read_file("build/test_plot.svg", NULL);
    CHECK(s && strstr(s, "&lt;title&gt; &amp; more") && strstr(s, "<polyline") && strstr(s, "</svg>"));
    free(s);
    /* Marks that show the answer (issue 39), and one tick format per axis:
     * 1e3 .. 1e6 on a log axis are all powers of ten, never "1000" beside "1e+06". */
    svg_plot_init(&pl, "marks", "x", "y");
    double bx[2] = {1000, 1e6}, by[2] = {1, 2};
    CHECK(svg_add(&pl, "s", bx, by, NULL, NULL, 2, SVG_LINE) == 0);
    pl.log_x = 1;
    CHECK(svg_vline(&pl, 5e4, "time budget") == 0 && svg_mark(&pl, 1e4, 1.5, "model's pick") == 0);
    CHECK(svg_write(&pl, "build/test_plot.svg") == 0);
    svg_free(&pl);
    s = test_read_file("build/test_plot.svg", NULL);
    CHECK(s && strstr(s, ">time budget</text>") && strstr(s, ">model&apos;s pick</text>") == NULL &&
          strstr(s, ">model's pick</text>") && strstr(s, "stroke-dasharray=\"3 3\""));
    CHECKF(s && strstr(s, ">1e3</text>") && strstr(s, ">1e6</text>") && !strstr(s, ">1000</text>"),
           "mixed tick formats on one axis");
    free(s);
    CHECK(!svg_fit_drawable(3, 0) && !svg_fit_drawable(8, 1) && svg_fit_drawable(4, 0));
}
