/*
 * test_tools_user.c - the tools as a new user meets them (issue 36): a
 * typo is an error before any work, outputs are written where they are
 * asked for and say so, and every tool keeps one exit-code convention.
 * The tools run as subprocesses on tiny sizes.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bench/cli.h"
#include "support.h"

#define DIR "build/test_tools_user"

static int run(const char *cmd, char **out, char **err) { return test_run(DIR, cmd, out, err); }

/* Runs cmd: exit status code, `text` in stderr, nothing on stdout, within
 * max_ms of wall time. */
static void expect_early_error(const char *cmd, int code, const char *text, double max_ms)
{
    char *out = NULL, *err = NULL;
    double t0 = accel_now_ms();
    int rc = run(cmd, &out, &err);
    double ms = accel_now_ms() - t0;
    CHECKF(rc == code && err && strstr(err, text), "%s: exit %d (expected %d), stderr '%s'", cmd,
           rc, code, err ? err : "");
    CHECKF(out && !*out, "%s: printed before failing: '%.300s'", cmd, out ? out : "");
    CHECKF(ms < max_ms, "%s: failed after %.0f ms, not before any work (%.0f ms)", cmd, ms, max_ms);
    free(out), free(err);
}

/* Defect 2: `--kinds gird`, `--accel grid:lamda=4` gave a green, empty report. */
TEST(tools_experiment_choices_checked_before_work)
{
    expect_early_error("bin/exp_grids --quick --kinds gird --out " DIR "/e1", CLI_EXIT_USAGE,
                       "unknown kind 'gird'", 5000);
    expect_early_error("bin/exp_grids --quick --kinds grid, --out " DIR "/e1", CLI_EXIT_USAGE,
                       "unknown kind ''", 5000);
    expect_early_error("bin/exp_grids --quick --accel grid:lamda=4 --out " DIR "/e1",
                       CLI_EXIT_USAGE, "lamda", 5000);
    expect_early_error("bin/exp_sah --quick --accel bvh:widht=4 --out " DIR "/e1", CLI_EXIT_USAGE,
                       "widht", 5000);
    expect_early_error("bin/exp_grids --quick --accel grid:res=0 --out " DIR "/e1",
                       CLI_EXIT_USAGE, "res=0", 5000);
    struct stat st;
    CHECKF(stat(DIR "/e1", &st) != 0, DIR "/e1 was made by a run that failed its options");
    /* make report passes KINDS and ACCEL on: report.sh refuses them before
     * any experiment runs or any earlier section is removed. */
    mkdir("build", 0777), mkdir(DIR, 0777), mkdir(DIR "/rep", 0777);
    FILE *f = fopen(DIR "/rep/exp_old.md", "w");
    if (f) fputs("an earlier section\n", f), fclose(f);
    expect_early_error("KINDS=gird experiments/report.sh --quick --dir " DIR "/rep",
                       CLI_EXIT_USAGE, "unknown kind 'gird'", 10000);
    expect_early_error("ACCEL='grid bvh:widht=4' experiments/report.sh --quick --dir " DIR "/rep",
                       CLI_EXIT_USAGE, "widht", 10000);
    CHECKF(stat(DIR "/rep/exp_old.md", &st) == 0, "a refused report.sh removed earlier sections");
}

/* Defect 3: every --accel is checked in full before the scene loads: a
 * value the kind checks only when it builds, and instanced's bottom=. */
TEST(tools_trace_checks_every_spec_before_the_scene)
{
    const char *big = "bin/trace --size 16x16 --repeat 1 --scene soup:tris=4000000 --accel bvh ";
    char cmd[512];
    snprintf(cmd, sizeof cmd, "%s--accel grid:res=0", big);
    expect_early_error(cmd, CLI_EXIT_USAGE, "--accel grid:res=0: grid: res=0", 3000);
    snprintf(cmd, sizeof cmd, "%s--accel instanced:bottom=bvh:widht=4", big);
    expect_early_error(cmd, CLI_EXIT_USAGE, "bottom=bvh:widht=4: bvh: unknown parameter 'widht'",
                       3000);
    snprintf(cmd, sizeof cmd, "%s--accel instanced:bottom=gird", big);
    expect_early_error(cmd, CLI_EXIT_USAGE, "bottom=gird: unknown accelerator 'gird'", 3000);
    snprintf(cmd, sizeof cmd, "%s--gen-accel grid:res=0", big);
    expect_early_error(cmd, CLI_EXIT_USAGE, "--gen-accel grid:res=0", 3000);
    /* Good sub-specs still run. */
    char *err = NULL;
    int rc = run("bin/trace --size 16x16 --repeat 1 --scene soup:tris=300 --quiet "
                 "--accel instanced:bottom=bvh:width=4 --accel instanced:bottom=grid",
                 NULL, &err);
    CHECKF(rc == 0, "good bottom= specs: exit %d, '%s'", rc, err ? err : "");
    free(err);
}
