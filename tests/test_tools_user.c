/*
 * test_tools_user.c - the tools as a new user meets them (issue 36): a
 * typo is an error before any work, outputs are written where they are
 * asked for and say so, and every tool keeps one exit-code convention.
 * The tools run as subprocesses on tiny sizes.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli/cli.h"
#include "rays/rays.h"
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

/* Defect 5: shadow and ao answers can leave the project and come back: a
 * hit file per set, any-hit answers by FORMATS.md's rule, --occluded for
 * rays from a file, and `trace compare --occluded`. */
TEST(tools_trace_dumps_and_compares_any_hit_answers)
{
    char *out = NULL, *err = NULL;
    int rc = run("bin/trace --size 24x24 --repeat 1 --quiet --scene sphereflake --accel bvh "
                 "--rays primary,shadow,ao --dump-rays " DIR "/s --dump-hits " DIR "/h",
                 &out, &err);
    CHECKF(rc == 0, "exit %d: %s", rc, err ? err : "");
    static const char *const sets[] = {"primary", "shadow", "ao"};
    for (int i = 0; i < 3; i++) {
        char path[256], said[300];
        snprintf(path, sizeof path, DIR "/h.%s.hits", sets[i]);
        snprintf(said, sizeof said, "wrote %s: ", path);
        CHECKF(access(path, R_OK) == 0, "%s not written", path);
        CHECKF(out && strstr(out, said), "'%s' not said: %s", said, out ? out : "");
        snprintf(path, sizeof path, DIR "/s.%s.rays", sets[i]);
        snprintf(said, sizeof said, "wrote %s: ", path);
        CHECKF(out && strstr(out, said), "'%s' not said: %s", said, out ? out : "");
    }
    CHECK(out && strstr(out, "any-hit answers of shadow rays"));
    free(out), free(err);
    /* The shadow rays again from their file, as any-hit queries of another kind. */
    rc = run("bin/trace --repeat 1 --quiet --scene sphereflake --accel grid --occluded --rays "
             DIR "/s.shadow.rays --dump-hits " DIR "/g.hits", &out, &err);
    CHECKF(rc == 0 && out && strstr(out, "occluded"), "--occluded: exit %d: %s %s", rc,
           out ? out : "", err ? err : "");
    free(out), free(err);
    rc = run("bin/trace compare --occluded " DIR "/h.shadow.hits " DIR "/g.hits", &out, NULL);
    CHECKF(rc == 0 && out && strstr(out, "leaks 0"), "compare: exit %d: %s", rc, out ? out : "");
    free(out);
    /* The rule: another triangle of an occluded ray agrees, a ray let through leaks. */
    accel_hit *h = NULL;
    size_t n = 0, occluded = SIZE_MAX, clear = SIZE_MAX;
    accel_error e = {0};
    CHECKF(hits_read(DIR "/h.shadow.hits", &h, &n, &e) == 0, "%s", e.msg);
    for (size_t i = 0; i < n; i++) {
        if (h[i].prim != ACCEL_MISS && occluded == SIZE_MAX) occluded = i;
        if (h[i].prim == ACCEL_MISS && clear == SIZE_MAX) clear = i;
    }
    CHECKF(occluded != SIZE_MAX && clear != SIZE_MAX, "no occluded or no clear shadow ray");
    if (occluded == SIZE_MAX || clear == SIZE_MAX) {
        free(h);
        return;
    }
    h[occluded].prim ^= 1, h[occluded].t *= 0.5f;
    hits_write(DIR "/other.hits", h, n, &e);
    rc = run("bin/trace compare --occluded " DIR "/h.shadow.hits " DIR "/other.hits", &out, NULL);
    CHECKF(rc == 0, "another triangle of an occluded ray: exit %d: %s", rc, out ? out : "");
    free(out);
    rc = run("bin/trace compare " DIR "/h.shadow.hits " DIR "/other.hits", NULL, NULL);
    CHECKF(rc == CLI_EXIT_DIFFER, "closest-hit rule on another triangle: exit %d", rc);
    h[occluded].prim = ACCEL_MISS, h[occluded].t = INFINITY;
    hits_write(DIR "/other.hits", h, n, &e);
    rc = run("bin/trace compare --occluded " DIR "/h.shadow.hits " DIR "/other.hits", &out, NULL);
    CHECKF(rc == CLI_EXIT_DIFFER && out && strstr(out, "leaks 1"), "a leak: exit %d: %s", rc,
           out ? out : "");
    free(out), free(h);
    expect_early_error("bin/trace --occluded", CLI_EXIT_USAGE, "--occluded needs a .rays file",
                       3000);
    rc = run("bin/trace compare --help", NULL, NULL);
    CHECKF(rc == 0, "trace compare --help: exit %d", rc);
}

/* Defect 1: trace passes have the builds' time budget, and a structure that
 * collapses (the regular grid around teapot_stadium's teapot: thousands of
 * primitive tests per ray) is named in one line. */
TEST(tools_trace_passes_stop_at_the_budget_and_collapse_warns)
{
    char *out = NULL, *err = NULL;
    int rc = run("bin/trace --quiet --scene teapot_stadium --size 32x24 --accel grid "
                 "--repeat 5 --budget 0.05", &out, &err);
    CHECKF(rc == 0, "exit %d: %s", rc, err ? err : "");
    CHECKF(out && strstr(out, " of 5 timed passes: a pass takes ") && strstr(out, "0.05 s budget"),
           "the row does not say the budget cut the passes: %s", out ? out : "");
    CHECKF(err && strstr(err, "warning: grid collapses on teapot_stadium: "),
           "no collapse warning: %s", err ? err : "");
    free(out), free(err);
    /* A structure that adapts: every pass, no warning. */
    rc = run("bin/trace --quiet --scene teapot_stadium --size 32x24 --accel bvh --repeat 3",
             &out, &err);
    CHECKF(rc == 0 && out && !strstr(out, "timed passes:") && err && !strstr(err, "collapses"),
           "bvh: exit %d, '%s', '%s'", rc, out ? out : "", err ? err : "");
    free(out), free(err);
}

/* --dump-hits F.hits with several sets wrote F.hits.primary.hits: a
 * trailing extension is taken off before the set's name (hits, rays, the
 * heatmap's png), and --help says so and that the heatmap is the last
 * --accel's. One set keeps the name as given. */
TEST(tools_trace_per_set_files_drop_the_extension)
{
    system("rm -rf " DIR "/sets && mkdir -p " DIR "/sets");
    char *out = NULL, *err = NULL;
    int rc = run("bin/trace --quiet --scene sphere --size 16x12 --repeat 1 --rays primary,shadow "
                 "--accel bvh --accel grid --dump-hits " DIR "/sets/eye.hits --dump-rays " DIR
                 "/sets/eye.rays --heatmap steps " DIR "/sets/heat.png", &out, &err);
    CHECKF(rc == 0, "exit %d: %s", rc, err ? err : "");
    static const char *const made[] = {"eye.primary.hits", "eye.shadow.hits", "eye.primary.rays",
                                       "eye.shadow.rays", "heat.primary.png", "heat.shadow.png"};
    for (int i = 0; i < 6; i++) {
        char path[256];
        snprintf(path, sizeof path, DIR "/sets/%s", made[i]);
        CHECKF(access(path, R_OK) == 0, "%s not written", path);
    }
    CHECKF(out && strstr(out, "wrote " DIR "/sets/eye.primary.hits: ") &&
           !strstr(out, "eye.hits.primary"), "the names written: %.400s", out ? out : "");
    CHECKF(access(DIR "/sets/eye.hits.primary.hits", F_OK) != 0, "eye.hits.primary.hits written");
    free(out), free(err);
    rc = run("bin/trace --quiet --scene sphere --size 16x12 --repeat 1 --dump-hits " DIR
             "/sets/one.hits", &out, NULL);
    CHECKF(rc == 0 && access(DIR "/sets/one.hits", R_OK) == 0, "one set: exit %d, no one.hits", rc);
    free(out);
    rc = run("bin/trace --help", &out, NULL);
    CHECKF(rc == 0 && out && strstr(out, "eye.hits gives") && strstr(out, "eye.primary.hits") &&
           strstr(out, "with several --accel it holds the last"),
           "--help says nothing of the names or the heatmap's --accel");
    free(out);
}

/* The README's examples wrote about 36 MB into the checkout's top, neither
 * ignored nor tidied: every output they name (--heatmap, --image,
 * --dump-rays, --dump-hits, --out, --export-obj) is under ex/, which git
 * ignores. */
TEST(tools_readme_example_outputs_ignored)
{
    char *readme = test_read_file("README.md", NULL);
    CHECKF(readme != NULL, "README.md not read");
    if (!readme) return;
    static const char *const opts[] = {"--heatmap prims ", "--heatmap steps ", "--image ",
                                       "--dump-rays ", "--dump-hits ", "--out ", "--export-obj "};
    int seen = 0;
    for (const char *line = readme; line && *line; line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL) {
        size_t len = strcspn(line, "\n");
        /* Example lines: commands of bin/ tools and their continuations. */
        int cmd = !strncmp(line, "bin/", 4) || !strncmp(line, "          --", 12);
        for (size_t k = 0; cmd && k < sizeof opts / sizeof opts[0]; k++) {
            for (const char *p = line; (p = strstr(p, opts[k])) && p < line + len; p++) {
                const char *v = p + strlen(opts[k]);
                if (*v == '`' || *v == 'F' || *v == 'D' || *v == 'P') continue; /* prose */
                seen++;
                CHECKF(!strncmp(v, "ex/", 3), "a README example writes outside ex/: %.*s",
                       (int)len, line);
            }
        }
    }
    free(readme);
    CHECKF(seen >= 6, "only %d example outputs found in README.md", seen);
    int rc = system("git check-ignore ex/grid.png ex/frames/f_0000.png ex/eye.primary.rays > /dev/null");
    CHECKF(rc == 0, "git does not ignore ex/ (git check-ignore: %d)", rc);
}

/* Brute force on a real mesh started without a word, its estimate of over
 * an hour per pass shown only after 20 s: a pass predicted over a minute
 * is a warning with the estimate before the work starts. trace is stopped
 * as soon as the warning is out (its pass takes minutes). */
TEST(tools_trace_warns_of_a_slow_pass_first)
{
    char *out = NULL, *err = NULL;
    int rc = run("(bin/trace --quiet --scene soup:tris=200000 --accel brute --rays primary "
                 "--size 512x512 2> " DIR "/slow.err & p=$!; for i in $(seq 300); do "
                 "grep -q 'warning: brute' " DIR "/slow.err && break; sleep 0.1; done; "
                 "kill $p; wait $p; cat " DIR "/slow.err >&2)", &out, &err);
    (void)rc;
    const char *w = err ? strstr(err, "trace: warning: brute on soup:tris=200000: about ") : NULL;
    CHECKF(w != NULL, "no warning before the pass: %.400s", err ? err : "");
    if (w) {
        double v = 0;
        char unit[8] = "";
        sscanf(w + strlen("trace: warning: brute on soup:tris=200000: about "), "%lf %7s", &v, unit);
        double s = v * (!strcmp(unit, "h") ? 3600 : !strcmp(unit, "min") ? 60 : 1);
        CHECKF(s > 60, "the estimate %.1f %s is not over a minute", v, unit);
        CHECKF(strstr(w, " per primary pass of 262144 rays (a probe of "),
               "the warning names no pass: %.300s", w);
    }
    CHECKF(out && !strstr(out, "Mrays/s"), "the warning came after the pass: %.300s", out ? out : "");
    free(out), free(err);
    /* A fast structure on the same scene: no warning. */
    rc = run("bin/trace --quiet --scene soup:tris=200000 --accel bvh --rays primary --size 64x64 "
             "--repeat 1", &out, &err);
    CHECKF(rc == 0 && err && !strstr(err, "warning"), "bvh: exit %d: %.300s", rc, err ? err : "");
    free(out), free(err);
}

/* Defect 6: a user's own scene in the experiments: --scene measures exactly
 * the scenes given (.scene files too), and a scene given is never dropped
 * without an error that says so. */
TEST(tools_experiments_measure_the_scenes_given)
{
    mkdir("build", 0777), mkdir(DIR, 0777);
    FILE *f = fopen(DIR "/my.scene", "w");
    if (f) fputs("mesh a soup:tris=300\ninstance a\ninstance a translate 2 0 0\n", f), fclose(f);
    char *out = NULL, *err = NULL;
    int rc = run("bin/exp_sah --quick --quiet --out " DIR "/sah --scene " DIR "/my.scene", &out,
                 &err);
    CHECKF(rc == 0, "exp_sah --scene: exit %d: %s", rc, err ? err : "");
    free(out), free(err);
    char *csv = test_read_file(DIR "/sah/exp_sah.csv", NULL);
    CHECKF(csv && strstr(csv, "\nmy.scene,"), "my.scene not measured: %.300s", csv ? csv : "");
    CHECKF(csv && !strstr(csv, "\nsoup"), "the experiment's own scenes measured too");
    free(csv);
    rc = run("bin/exp_grids --quick --quiet --out " DIR "/grids --only-accels --accel grid "
             "--accel bvh --scene soup:tris=400", NULL, &err);
    CHECKF(rc == 0, "exp_grids --scene: exit %d: %s", rc, err ? err : "");
    free(err);
    csv = test_read_file(DIR "/grids/exp_grids.csv", NULL);
    CHECKF(csv && strstr(csv, "\nsoup:tris=400,") && !strstr(csv, "sphereflake"),
           "exp_grids did not measure exactly soup:tris=400: %.300s", csv ? csv : "");
    free(csv);
    expect_early_error("bin/exp_sah --quick --out " DIR "/sah --mesh " DIR "/my.scene",
                       CLI_EXIT_USAGE, "--scene", 5000);
    expect_early_error("bin/exp_sah --out " DIR "/sah --mesh " DIR "/my.scene --mesh " DIR
                       "/my.scene --mesh " DIR "/my.scene", CLI_EXIT_USAGE,
                       "measures the first 2", 5000);
    expect_early_error("bin/exp_step_cost --quick --out " DIR "/bin --scene sphere --scene tetra "
                       "--scene sphere --scene tetra --scene sphere --scene tetra --scene sphere "
                       "--scene tetra --scene sphere", CLI_EXIT_USAGE, "measures at most 8", 5000);
}

/* Defect 8: the smaller ones. A closing summary table, the light printed,
 * --help naming .scene files and the light, CSV columns for the primitive
 * count, image size and grid resolution with empty fields (never nan)
 * where a value does not apply, and --help of every tool exits 0. */
TEST(tools_trace_summary_light_and_csv_columns)
{
    char *out = NULL, *err = NULL;
    int rc = run("bin/trace --quiet --size 24x16 --repeat 1 --scene soup:tris=300 --accel bvh "
                 "--accel grid --rays primary,shadow", &out, &err);
    CHECKF(rc == 0, "exit %d: %s", rc, err ? err : "");
    const char *sum = out ? strstr(out, "\nsummary: Mrays/s") : NULL;
    CHECKF(sum != NULL, "no summary table: %s", out ? out : "");
    if (sum) {
        CHECK(strstr(sum, "primary") && strstr(sum, "shadow") && strstr(sum, "build ms") &&
              strstr(sum, "MiB"));
        CHECK(strstr(sum, "\n  bvh ") && strstr(sum, "\n  grid "));
    }
    CHECKF(out && strstr(out, "  light ("), "the light is not printed");
    free(out), free(err);
    rc = run("bin/trace --help", &out, NULL);
    CHECKF(rc == 0 && out && strstr(out, ".scene") && strstr(out, "light"),
           "trace --help names neither .scene files nor the light");
    free(out);
    rc = run("bin/trace --quiet --csv --size 24x16 --repeat 1 --scene soup:tris=300 --accel bvh "
             "--accel grid:res=4", &out, NULL);
    CHECKF(rc == 0 && out, "--csv: exit %d", rc);
    CHECKF(out && strstr(out, "csv,kind,spec,scene,prims,rayset,width,height,") &&
           strstr(out, ",grid_res,"), "CSV header without prims, width, height, grid_res: %s",
           out ? out : "");
    CHECKF(out && strstr(out, ",soup:tris=300,300,primary,24,16,") && strstr(out, ",4x4x4,"),
           "CSV values: %s", out ? out : "");
    CHECKF(out && !strstr(out, "nan"), "a nan in the CSV: %s", out ? out : "");
    free(out);
    rc = run("bin/mkreport --help", &out, NULL);
    CHECKF(rc == 0 && out && strstr(out, "usage: mkreport"), "mkreport --help: exit %d", rc);
    free(out);
}
