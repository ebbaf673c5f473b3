/*
 * test_runner.c - the test runner itself, run as a child process: --list
 * names every test (one per registered kind for the per-kind families), a
 * selection picks a family, an exact name or a pattern, an item selecting
 * no test and a KINDS naming an unknown kind are refused with a message and
 * exit status 2 before any test runs, KINDS limits the per-kind tests to
 * the kinds it names, a skip is counted and says why, a crash fails its
 * unit only; and every test's name starts with its file's family.
 */
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "support.h"

/* Runs this very binary with `args` (and env assignments before it);
 * returns its exit status (-1 when it did not exit) and its output. */
static int run_self(const char *env, const char *args, char **out)
{
    char exe[1024], log[] = "/tmp/gridbvh_runner_XXXXXX";
    *out = NULL;
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    int fd = mkstemp(log);
    if (n <= 0 || fd < 0) {
        test_fail(__FILE__, __LINE__, "cannot find the test binary or make a temporary file");
        if (fd >= 0) close(fd);
        return -1;
    }
    close(fd);
    exe[n] = 0;
    char cmd[3000];
    snprintf(cmd, sizeof cmd, "%s '%s' %s > '%s' 2>&1", env, exe, args, log);
    int status = system(cmd);
    *out = test_read_file(log, NULL);
    remove(log);
    return status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(runner_list_kinds_and_filters)
{
    char *out;
    /* --list: every test once, the per-kind ones for every kind. */
    int rc = run_self("KINDS=", "--list", &out);
    CHECKF(rc == 0 && out, "--list: exit %d", rc);
    if (out) {
        CHECKF(strstr(out, "runner_list_kinds_and_filters\n") != NULL, "--list lacks this test");
        for (size_t k = 0; k < accel_kind_count; k++) {
            char line[256];
            snprintf(line, sizeof line, "\nconformance_%s\n", accel_kinds[k]->name);
            CHECKF(strstr(out, line) != NULL, "--list lacks conformance_%s", accel_kinds[k]->name);
        }
        CHECKF(!strstr(out, " ok ") && !strstr(out, "passed,"), "--list ran tests: %s", out);
    }
    free(out);

    /* KINDS limits the per-kind tests; a pattern selects among them. */
    rc = run_self("KINDS=grid", "--list 'conformance_*grid'", &out);
    CHECKF(rc == 0 && out && !strcmp(out, "conformance_grid\n"),
           "KINDS=grid --list: exit %d, '%s'", rc, out ? out : "");
    free(out);

    /* A family is its files' tests, not every name containing the word:
     * grid is grid_*, neither conformance_grid nor the ngrid_ tests. */
    rc = run_self("KINDS=", "--list grid", &out);
    CHECKF(rc == 0 && out && !strncmp(out, "grid_", 5) && !strstr(out, "\nconformance_grid\n") &&
               !strstr(out, "ngrid_") && !strstr(out, "igrid_"),
           "--list grid: exit %d, '%s'", rc, out ? out : "");
    for (const char *p = out; p && *p; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : "")
        CHECKF(!strncmp(p, "grid_", 5), "--list grid names '%.40s'", p);
    free(out);
    rc = run_self("KINDS=", "--list '*grid*'", &out);
    CHECKF(rc == 0 && out && !strncmp(out, "conformance_grid\n", 17) && strstr(out, "ngrid_") &&
               strstr(out, "grid_build_threads_identical\n"),
           "--list '*grid*': exit %d", rc);
    free(out);
    rc = run_self("KINDS=grid", "--list conformance_grid,image_crc_adler_known_values", &out);
    CHECKF(rc == 0 && out && !strcmp(out, "conformance_grid\nimage_crc_adler_known_values\n"),
           "exact names: exit %d, '%s'", rc, out ? out : "");
    free(out);
    /* The run says what it selected before anything else. */
    rc = run_self("KINDS=", "-j 1 runner_skip_probe", &out);
    CHECKF(rc == 0 && out && !strncmp(out, "selected: test runner_skip_probe\n", 33),
           "the first line names the selection: '%.60s'", out ? out : "");
    free(out);

    /* Refusals, before any test runs. */
    rc = run_self("KINDS=grid,no_such_kind", "core", &out);
    CHECKF(rc == 2 && out && strstr(out, "unknown kind 'no_such_kind'") && strstr(out, "grid") &&
               !strstr(out, "passed,"),
           "KINDS=grid,no_such_kind: exit %d, '%s'", rc, out ? out : "");
    free(out);
    rc = run_self("KINDS=", "no_test_has_this_name", &out);
    CHECKF(rc == 2 && out && strstr(out, "no family or test is named 'no_test_has_this_name'"),
           "unmatched selection: exit %d, '%s'", rc, out ? out : "");
    free(out);
    rc = run_self("KINDS=", "grid,conformance_", &out); /* a prefix is neither */
    CHECKF(rc == 2 && out && strstr(out, "no family or test is named 'conformance_'") &&
               !strstr(out, "passed,"),
           "a prefix as a name: exit %d, '%s'", rc, out ? out : "");
    free(out);
    rc = run_self("KINDS=", "--frobnicate", &out);
    CHECKF(rc == 2 && out && strstr(out, "unknown option"), "unknown option: exit %d, '%s'", rc,
           out ? out : "");
    free(out);
}

/* A crash fails its unit and the run goes on to its summary. Run as such,
 * the probe runs itself in a child runner with GRIDBVH_TEST_CRASH set,
 * where it crashes its process, and checks what that runner reported. */
TEST(runner_crash_probe)
{
    if (getenv("GRIDBVH_TEST_CRASH")) raise(SIGABRT);
    char *out;
    int rc = run_self("KINDS= GRIDBVH_TEST_CRASH=1", "-j 2 runner_crash_probe", &out);
    CHECKF(rc == 1 && out && strstr(out, "died (signal 6)") &&
               strstr(out, "0 passed, 1 failed, 0 skipped\n"),
           "crash: exit %d, '%s'", rc, out ? out : "");
    free(out);
}

/* Skips when told to (GRIDBVH_TEST_SKIP, set by runner_skip_counted), else
 * passes. */
TEST(runner_skip_probe)
{
    const char *why = getenv("GRIDBVH_TEST_SKIP");
    if (why) {
        test_skip("%s", why);
        return;
    }
    CHECK(1 + 1 == 2);
}

/* A skipped test is counted as skipped, not passed, and says why. */
TEST(runner_skip_counted)
{
    char *out;
    int rc = run_self("KINDS= GRIDBVH_TEST_SKIP='no such input'", "-j 1 runner_skip_probe", &out);
    CHECKF(rc == 0 && out && strstr(out, "  skip runner_skip_probe (no such input)\n") &&
               strstr(out, "\n0 passed, 0 failed, 1 skipped\n"),
           "skip: exit %d, '%s'", rc, out ? out : "");
    free(out);
    rc = run_self("KINDS=", "-j 1 runner_skip_probe", &out);
    CHECKF(rc == 0 && out && strstr(out, "\n1 passed, 0 failed, 0 skipped\n"),
           "no skip: exit %d, '%s'", rc, out ? out : "");
    free(out);
}

typedef struct {
    int checked, wrong;
} family_census;

static void check_family(const char *name, const char *family, void *ctx)
{
    family_census *c = ctx;
    size_t n = strlen(family);
    c->checked++;
    if (!n || strncmp(name, family, n) != 0 || name[n] != '_') {
        c->wrong++;
        test_fail(__FILE__, __LINE__,
                  "test %s is in test_%s*.c: its name must start with its family, '%s_' "
                  "(tests/README.md): rename it or move it",
                  name, family, family);
    }
}

/* make test T=grid runs exactly test_grid*.c: every test's name starts with
 * the family of its file (the first word after test_), so a name says where
 * the test is and which T selects it. */
TEST(runner_names_start_with_their_family)
{
    family_census c = {0, 0};
    int n = test_each(check_family, &c);
    CHECKF(n > 200 && c.checked == n, "%d tests registered, %d checked", n, c.checked);
}

TEST(runner_processes_isolate_and_agree)
{
    /* One process or two: the same tests pass, with the same summary. */
    char *one, *two;
    int rc1 = run_self("KINDS=", "-j 1 image", &one);
    int rc2 = run_self("KINDS=", "-j 2 image", &two);
    CHECKF(rc1 == 0 && rc2 == 0 && one && two, "exit %d and %d", rc1, rc2);
    if (one && two) {
        const char *s1 = strrchr(one, '\n'), *s2 = strrchr(two, '\n');
        CHECK(strstr(one, "10 passed, 0 failed, 0 skipped\n") &&
              strstr(two, "10 passed, 0 failed, 0 skipped\n"));
        CHECK(s1 && s2 && strlen(s1) == 1 && strlen(s2) == 1); /* the summary is the last line */
        for (const char *p = one; (p = strstr(p, "  ok   ")) != NULL; p++) {
            char name[128];
            if (sscanf(p, "  ok   %127s", name) == 1) {
                char line[160];
                snprintf(line, sizeof line, "  ok   %s (", name);
                CHECKF(strstr(two, line) != NULL, "-j 2 lacks '%s'", line);
            }
        }
    }
    free(one);
    free(two);
}
