/*
 * test_runner.c - the test runner itself, run as a child process: --list
 * names every test (one per registered kind for the per-kind families),
 * a filter matching no test and a KINDS naming an unknown kind are refused
 * with a message and exit status 2 before any test runs, and KINDS limits
 * the per-kind tests to the kinds it names.
 */
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
    CHECKF(rc == 0 && out && !strcmp(out, "conformance_grid\n"), "KINDS=grid --list: exit %d, '%s'",
           rc, out ? out : "");
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
