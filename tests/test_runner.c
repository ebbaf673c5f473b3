/*
 * test_runner.c - the test runner itself, run as a child process: --list
 * names every test (one per registered kind for the per-kind families),
 * a filter matching no test and a KINDS naming an unknown kind are refused
 * with a message and exit status 2 before any test runs, and KINDS limits
 * the per-kind tests to the kinds it names.
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

    /* KINDS limits the per-kind tests; a filter selects among them. */
    rc = run_self("KINDS=grid", "--list conformance_", &out);
    CHECKF(rc == 0 && out && (!strncmp(out, "conformance_grid\n", 17) || strstr(out, "\nconformance_grid\n")),
           "KINDS=grid --list: exit %d, '%s'", rc, out ? out : "");
    for (size_t k = 0; out && k < accel_kind_count; k++) {
        char line[256];
        snprintf(line, sizeof line, "conformance_%s\n", accel_kinds[k]->name);
        const char *at = strstr(out, line);
        CHECKF(!strcmp(accel_kinds[k]->name, "grid") || !at || (at != out && at[-1] != '\n'),
               "KINDS=grid --list lists %s", line);
    }
    free(out);

    /* Refusals, before any test runs. */
    rc = run_self("KINDS=grid,no_such_kind", "core_", &out);
    CHECKF(rc == 2 && out && strstr(out, "unknown kind 'no_such_kind'") && strstr(out, "grid") &&
               !strstr(out, "passed,"),
           "KINDS=grid,no_such_kind: exit %d, '%s'", rc, out ? out : "");
    free(out);
    rc = run_self("KINDS=", "no_test_has_this_name", &out);
    CHECKF(rc == 2 && out && strstr(out, "no test name contains 'no_test_has_this_name'"),
           "unmatched filter: exit %d, '%s'", rc, out ? out : "");
    free(out);
    rc = run_self("KINDS=", "--frobnicate", &out);
    CHECKF(rc == 2 && out && strstr(out, "unknown option"), "unknown option: exit %d, '%s'", rc,
           out ? out : "");
    free(out);
}

/* Run only by runner_processes_isolate_and_agree (below), which sets the
 * variable: a test that crashes its process. */
TEST(runner_crash_probe)
{
    if (getenv("GRIDBVH_TEST_CRASH")) raise(SIGABRT);
}

TEST(runner_processes_isolate_and_agree)
{
    /* One process or two: the same tests pass, with the same summary. */
    char *one, *two;
    int rc1 = run_self("KINDS=", "-j 1 image_", &one);
    int rc2 = run_self("KINDS=", "-j 2 image_", &two);
    CHECKF(rc1 == 0 && rc2 == 0 && one && two, "exit %d and %d", rc1, rc2);
    if (one && two) {
        const char *s1 = strrchr(one, '\n'), *s2 = strrchr(two, '\n');
        CHECK(strstr(one, "10 passed, 0 failed\n") && strstr(two, "10 passed, 0 failed\n"));
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
    /* A crash fails its unit and the run goes on to its summary. */
    char *out;
    int rc = run_self("KINDS= GRIDBVH_TEST_CRASH=1", "-j 2 runner_crash_probe", &out);
    CHECKF(rc == 1 && out && strstr(out, "died (signal 6)") && strstr(out, "0 passed, 1 failed\n"),
           "crash: exit %d, '%s'", rc, out ? out : "");
    free(out);
}
