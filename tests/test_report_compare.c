/*
 * test_report_compare.c - experiments/compare_reports.sh counts every
 * change of verdict word between runs, "on the line" included (issue 52),
 * names apart the rows whose interval ends within 2% of the threshold and
 * those that become "not testable here", and exits 1 only on a change.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

#define T "build/test-report-compare"

/* One run's verdicts.csv with three rows: the words and intervals given. */
static int write_run(const char *dir, const char *w1, const char *w2, double lo2, const char *w3)
{
    char path[256], text[2048];
    snprintf(path, sizeof path, "%s/exp_x.verdicts.csv", dir);
    snprintf(text, sizeof text,
             "claim,verdict,evidence,scenes,section,deciding,value,lo,hi,threshold,sense,margin,n\n"
             "c-one,%s,\"e, with a comma\",s1,exp_x,d,1.5,1.4,1.6,1.2,1,0.1,8\n"
             "c-two,%s,e,s2,exp_x,d,1.1,%g,1.3,1,1,0,8\n"
             "c-abs,%s,e,s3,exp_x,d,30,25,35,20,1,0.2,8\n",
             w1, w2, lo2, w3);
    return test_write_file(path, text);
}

TEST(report_compare_counts_every_change)
{
    if (system("rm -rf " T " && mkdir -p " T "/a " T "/b " T "/c " T "/d " T "/e") != 0) {
        test_fail(__FILE__, __LINE__, "cannot set up " T);
        return;
    }
    /* b: c-one moves from confirmed to on the line (a change); c-two's
     * interval starts 1% from its threshold in a (near); c-abs becomes not
     * testable (apart). c: the same words as a. e against d: only c-two's
     * word moves, both intervals ending 10% or more away (a change). */
    if (!write_run(T "/a", "confirmed", "confirmed", 1.01, "confirmed") ||
        !write_run(T "/b", "on the line", "on the line", 0.99, "not testable here") ||
        !write_run(T "/c", "confirmed", "confirmed", 1.01, "confirmed") ||
        !write_run(T "/d", "confirmed", "refuted", 0.8, "confirmed") ||
        !write_run(T "/e", "confirmed", "confirmed", 1.1, "confirmed"))
        return;
    char *out = NULL;
    int st = test_run(T "/log", "experiments/compare_reports.sh " T "/a " T "/b " T "/c", &out, NULL);
    CHECKF(st == 1, "a change of word through \"on the line\" must fail the comparison (exit %d)", st);
    CHECKF(out && strstr(out, "CHANGE: exp_x | c-one"), "c-one's change not named: %s", out ? out : "");
    CHECKF(out && strstr(out, "near the threshold") && strstr(out, "c-two"),
           "c-two's interval end within 2%% not named apart: %s", out ? out : "");
    CHECKF(out && strstr(out, "not testable in one run: exp_x | c-abs"),
           "c-abs not named as not testable in one run: %s", out ? out : "");
    CHECKF(out && strstr(out, T "/b against " T "/a: 0 rows the same, 1 change, 1 near the "
                              "threshold, 1 not testable in one run"),
           "wrong counts for b: %s", out ? out : "");
    CHECKF(out && strstr(out, T "/c against " T "/a: 3 rows the same, 0 change"),
           "wrong counts for c: %s", out ? out : "");
    free(out);
    st = test_run(T "/log", "experiments/compare_reports.sh " T "/a " T "/c", &out, NULL);
    CHECKF(st == 0, "identical runs must compare equal (exit %d): %s", st, out ? out : "");
    free(out);
    st = test_run(T "/log", "experiments/compare_reports.sh " T "/e " T "/d", &out, NULL);
    CHECKF(st == 1 && out && strstr(out, "CHANGE: exp_x | c-two"),
           "a word that moves far from its threshold is a change (exit %d): %s", st, out ? out : "");
    free(out);
}
