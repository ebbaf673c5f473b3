/*
 * test_report_keep.c - make report never loses the previous report: every
 * experiment's limits are checked before the first one runs, the run
 * writes into a fresh folder, and REPORT.md and report/ are replaced only
 * when every experiment has finished. A failed or interrupted run leaves
 * them byte for byte as they were and names the folder of its partial
 * output.
 *
 * experiments/report.sh runs from a copy of the repository's layout in
 * build/test-report-keep/repo (the script works from its own folder's
 * parent), with stand-in experiments (shell scripts named as the real
 * ones) that write a minimal section, fail, interrupt the run or refuse
 * their choices on purpose, and the real bin/mkreport: seconds, not the
 * quick report's minute, and the committed report is never touched.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "experiments/engine/svg.h"
#include "support.h"

#define T "build/test-report-keep"
#define REPO T "/repo"

/* A stand-in experiment, bin/<name> of the copy: with --check it exits 0
 * (or 2 for "refuse"); else it writes a section into --out and marks that
 * it ran, then succeeds ("ok"), fails ("fail") or sends its parent, the
 * report script, SIGTERM as an interrupted run gets ("term"). */
static int stand_in(const char *name, const char *mode)
{
    char path[512], text[2048];
    snprintf(path, sizeof path, REPO "/bin/%s", name);
    snprintf(text, sizeof text,
             "#!/bin/sh\n"
             "mode=%s\n"
             "for a in \"$@\"; do\n"
             "  if [ \"$a\" = --check ]; then\n"
             "    [ $mode = refuse ] && { echo \"%s: refused on purpose\" >&2; exit 2; }\n"
             "    exit 0\n"
             "  fi\n"
             "done\n"
             "out=experiments/out\n"
             "while [ $# -gt 0 ]; do [ \"$1\" = --out ] && out=\"$2\"; shift; done\n"
             "mkdir -p \"$out\" && touch ran.%s\n"
             "printf '## Stand-in (%s)\\n\\n**Question:** q\\n\\n<!-- verdicts -->\\n\\n"
             "| a |\\n|---|\\n| %s |\\n\\n**Findings:**\\n\\n- none\\n' > \"$out/%s.md\"\n"
             "printf 'a\\n1\\n' > \"$out/%s.csv\"\n"
             "case $mode in\n"
             "  fail) echo '%s: failing on purpose' >&2; exit 1 ;;\n"
             "  term) kill -TERM $PPID; exit 0 ;;\n"
             "esac\n"
             "exit 0\n",
             mode, name, name, name, mode, name, name, name);
    if (!test_write_file(path, text)) return 0;
    CHECKF(chmod(path, 0755) == 0, "cannot make %s executable", path);
    return 1;
}

/* Runs the copy's report script; its status, stderr in *err. */
static int run_report(const char *args, char **err)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "(cd " REPO " && experiments/report.sh %s)", args);
    return test_run(T "/log", cmd, NULL, err);
}

/* Whether the two folders hold the same files with the same bytes. */
static int same_tree(const char *a, const char *b)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "diff -r %s %s > " T "/diff.txt 2>&1", a, b);
    return system(cmd) == 0;
}

TEST(report_keep_previous_on_failure)
{
    if (system("rm -rf " T " && mkdir -p " REPO "/bin " REPO "/experiments " T "/log && "
               "cp experiments/report.sh " REPO "/experiments/ && "
               "ln -s \"$PWD/bin/mkreport\" " REPO "/bin/mkreport") != 0) {
        test_fail(__FILE__, __LINE__, "cannot set up " REPO);
        return;
    }
    /* A complete run: the previous report (full layout: REPORT.md + report/,
     * and the quick one in build/quick-report/). */
    if (!stand_in("exp_step_cost", "ok") || !stand_in("exp_sah", "ok")) return;
    char *err = NULL;
    int st = run_report("", &err);
    CHECKF(st == 0, "the complete run failed (%d): %s", st, err ? err : "");
    free(err);
    st = run_report("--quick", &err);
    CHECKF(st == 0, "the complete quick run failed (%d): %s", st, err ? err : "");
    free(err);
    if (system("cp -pR " REPO "/report " REPO "/REPORT.md " REPO "/build/quick-report " T "/") != 0) {
        test_fail(__FILE__, __LINE__, "no previous report to keep");
        return;
    }

    /* exp_sah, the later experiment, fails after exp_step_cost wrote its
     * section: nothing of the previous report changes. */
    if (!stand_in("exp_sah", "fail")) return;
    const char *layouts[2][3] = {{"", REPO "/report", T "/report"},
                                 {"--quick", REPO "/build/quick-report", T "/quick-report"}};
    for (int l = 0; l < 2; l++) {
        unlink(REPO "/ran.exp_step_cost");
        st = run_report(layouts[l][0], &err);
        CHECKF(st != 0, "report.sh %s: exit 0 although exp_sah failed", layouts[l][0]);
        CHECKF(access(REPO "/ran.exp_step_cost", F_OK) == 0,
               "exp_step_cost did not run before the failure: the test shows nothing");
        CHECKF(same_tree(layouts[l][1], layouts[l][2]),
               "report.sh %s: a failed run changed the previous report (%s/diff.txt)",
               layouts[l][0], T);
        CHECKF(l || same_tree(REPO "/REPORT.md", T "/REPORT.md"),
               "a failed run changed REPORT.md");
        /* It says where its partial output is, and it is there. */
        char partial[200];
        snprintf(partial, sizeof partial, "%s/exp_step_cost.md",
                 l ? REPO "/build/quick-report.partial" : REPO "/build/report.partial/report");
        CHECKF(err && strstr(err, "the previous report") && strstr(err, "is as it was") &&
               strstr(err, l ? "build/quick-report.partial/" : "build/report.partial/report/"),
               "report.sh %s: no word of the kept report and the partial output: %s",
               layouts[l][0], err ? err : "");
        char *sec = test_read_file(partial, NULL);
        CHECKF(sec && strstr(sec, "(exp_step_cost)"), "%s: the partial output is not there", partial);
        free(sec);
        free(err);
    }

    /* An interrupted run (SIGTERM during exp_sah) keeps it as well. */
    if (!stand_in("exp_sah", "term")) return;
    st = run_report("", &err);
    CHECKF(st != 0, "report.sh: exit 0 although interrupted");
    CHECKF(same_tree(REPO "/report", T "/report") && same_tree(REPO "/REPORT.md", T "/REPORT.md"),
           "an interrupted run changed the previous report (%s/diff.txt)", T);
    CHECKF(err && strstr(err, "build/report.partial/report/"),
           "the interrupted run does not name its partial output: %s", err ? err : "");
    free(err);

    /* A later experiment that refuses the choices stops the run before the
     * first experiment starts: no work, no partial output. */
    if (!stand_in("exp_sah", "refuse") || system("rm -rf " REPO "/build/report.partial") != 0) return;
    unlink(REPO "/ran.exp_step_cost");
    st = run_report("", &err);
    CHECKF(st == 2, "report.sh: exit %d (not 2) when exp_sah refuses its choices", st);
    CHECKF(access(REPO "/ran.exp_step_cost", F_OK) != 0,
           "exp_step_cost ran although exp_sah refused the choices up front");
    CHECKF(access(REPO "/build/report.partial", F_OK) != 0, "a refused run made a partial folder");
    CHECKF(err && strstr(err, "exp_sah refuses these choices"), "no word of the refusal: %s",
           err ? err : "");
    CHECKF(same_tree(REPO "/report", T "/report"), "a refused run changed the previous report");
    free(err);

    /* A complete run replaces the report whole: a file of the previous one
     * that this run did not write is gone. */
    if (!stand_in("exp_sah", "ok") || !test_write_file(REPO "/report/stale_plot.svg", "<svg/>\n"))
        return;
    st = run_report("", &err);
    CHECKF(st == 0, "the second complete run failed (%d): %s", st, err ? err : "");
    free(err);
    CHECKF(access(REPO "/report/stale_plot.svg", F_OK) != 0, "a stale file survived a complete run");
    CHECKF(access(REPO "/report/exp_sah.md", F_OK) == 0 && access(REPO "/REPORT.md", F_OK) == 0,
           "the complete run did not publish its report");
    CHECKF(access(REPO "/build/report.partial", F_OK) != 0, "a complete run left its staging folder");
}

/* The real experiments: --check answers from the options and the declared
 * limits alone (exit 0 at once, no output), and refuses what the
 * experiment would refuse after minutes of work. */
TEST(report_keep_check_limits)
{
    char *err = NULL;
    /* Two scenes: exp_binning measures each in turn now (it took one). */
    int st = test_run(T "-check", "bin/exp_binning --quick --check --out " T "-check/out "
                      "--scene sphere --scene soup:tris=100", NULL, &err);
    CHECKF(st == 0, "exp_binning --check with two scenes: exit %d: %s", st, err ? err : "");
    free(err);
    CHECKF(access(T "-check/out", F_OK) != 0, "--check wrote its output folder");
    char cmd[1024] = "bin/exp_step_cost --quick --check";
    for (int i = 0; i < 9; i++) strcat(cmd, " --scene sphere");
    st = test_run(T "-check", cmd, NULL, &err);
    CHECKF(st == 2 && err && strstr(err, "measures at most 8"),
           "exp_step_cost --check with 9 scenes: exit %d: %s", st, err ? err : "");
    free(err);
    /* Every experiment declares its limits (exp_limits): --check of each
     * returns at once instead of running the experiment. */
    st = test_run(T "-check", "for e in bin/exp_*; do timeout 20 $e --quick --check --scene sphere "
                  "|| { echo \"$e: exit $?\" >&2; exit 1; }; done", NULL, &err);
    CHECKF(st == 0, "an experiment's --check did not answer: %s", err ? err : "");
    free(err);
}

/* Plot colours repeated beyond 10 series (a plot holds up to
 * SVG_MAX_SERIES): each round of 10 takes another dash pattern and marker,
 * and past 40 other hues, so no two series of a plot look alike. */
TEST(report_svg_series_look_distinct)
{
    char look[80][64];
    for (int dashed = 0; dashed < 2; dashed++) {
        for (int i = 0; i < 80; i++) {
            char c[8];
            const char *dash;
            int marker;
            svg_series_look(i, dashed, c, &dash, &marker);
            CHECKF(c[0] == '#' && strlen(c) == 7, "series %d: colour '%s'", i, c);
            CHECKF(!dashed || dash, "dashed series %d drawn solid", i);
            snprintf(look[i], sizeof look[i], "%s|%s|%d", c, dash ? dash : "-", marker);
            for (int j = 0; j < i; j++)
                CHECKF(strcmp(look[i], look[j]), "series %d and %d look alike (%s)", j, i, look[i]);
        }
    }
    /* A plot of SVG_MAX_SERIES lines: as many distinct strokes. */
    svg_plot pl;
    svg_plot_init(&pl, "many", "x", "y");
    double x[2] = {1, 2}, y[2] = {1, 2};
    for (int i = 0; i < SVG_MAX_SERIES; i++) {
        char name[16];
        snprintf(name, sizeof name, "s%d", i);
        svg_add(&pl, name, x, y, NULL, NULL, 2, SVG_LINE | SVG_POINTS);
    }
    CHECK(svg_write(&pl, "build/test_plot_many.svg") == 0);
    svg_free(&pl);
    char *s = test_read_file("build/test_plot_many.svg", NULL);
    char seen[SVG_MAX_SERIES][96];
    int n = 0;
    for (const char *p = s; p && (p = strstr(p, "<polyline ")); p++) {
        const char *end = strstr(p, " points=");
        if (!end || n == SVG_MAX_SERIES) break;
        snprintf(seen[n], sizeof seen[n], "%.*s", (int)(end - p), p);
        for (int j = 0; j < n; j++)
            CHECKF(strcmp(seen[n], seen[j]), "two lines drawn alike: %s", seen[n]);
        n++;
    }
    CHECKF(n == SVG_MAX_SERIES, "%d lines drawn of %d", n, SVG_MAX_SERIES);
    free(s);
}

/* REPORT.md spoke of "issue 11/13", which a reader of the report cannot
 * follow: the report and its sections refer to their own sections. */
TEST(report_quick_no_issue_numbers)
{
    if (!test_quick_report()) return;
    char *err = NULL;
    int st = test_run(T "-issues", "grep -n -i -E 'issue[s]? *[0-9]|the issue' "
                      "build/quick-report/*.md", NULL, &err);
    char *out = test_read_file(T "-issues/out.txt", NULL);
    CHECKF(st == 1, "the quick report names issues (grep: %d): %.600s", st, out ? out : "");
    free(out), free(err);
}
