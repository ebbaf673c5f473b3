/*
 * test_make.c - the Makefile's command-line variables: a variable it does
 * not know (QUIK=1, SCENE=x) is an error before any work, naming the ones
 * it knows, and a boolean (QUICK, LAB) takes 1 and 0 with their meaning
 * (QUICK=0 is the full run, not the quick one). Each make runs without the
 * running make's MAKEFLAGS (make test T=... passes T down).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

#define DIR "build/test-make"
#define MAKE "env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make --no-print-directory "

TEST(make_unknown_variables_refused)
{
    static const char *const cmds[] = {"report QUIK=1", "report SCENE=x", "test TT=foo",
                                       "report QUICK=1 KIND=grid"};
    for (size_t i = 0; i < sizeof cmds / sizeof cmds[0]; i++) {
        char cmd[256], *out = NULL, *err = NULL;
        snprintf(cmd, sizeof cmd, MAKE "%s", cmds[i]);
        int st = test_run(DIR, cmd, &out, &err);
        const char *bad = strchr(cmds[i], ' ') + 1;
        if (strrchr(bad, ' ')) bad = strrchr(bad, ' ') + 1;
        char name[32];
        snprintf(name, sizeof name, "unknown variable %.*s ", (int)strcspn(bad, "="), bad);
        CHECKF(st == 2, "make %s: exit %d, not 2", cmds[i], st);
        CHECKF(err && strstr(err, name) && strstr(err, "known: CC ") && strstr(err, " QUICK ") &&
                   strstr(err, " SCENES "),
               "make %s: no '%s' with the known list: %.300s", cmds[i], name, err ? err : "");
        /* Before any work: no compile line, no experiment, no test. */
        CHECKF(out && out[0] == 0, "make %s did work before refusing: %.300s", cmds[i],
               out ? out : "");
        free(out), free(err);
    }
}

TEST(make_booleans_zero_and_one)
{
    char *out = NULL, *err = NULL;
    /* QUICK=0: the full run (no --quick); QUICK=1: the quick one. */
    int st = test_run(DIR, MAKE "-n report QUICK=0", &out, &err);
    CHECKF(st == 0 && out && strstr(out, "experiments/report.sh") && !strstr(out, "--quick"),
           "make -n report QUICK=0 (exit %d) is not the full run: %.300s", st, err ? err : "");
    free(out), free(err);
    st = test_run(DIR, MAKE "-n report QUICK=1", &out, &err);
    CHECKF(st == 0 && out && strstr(out, "experiments/report.sh --quick"),
           "make -n report QUICK=1 (exit %d) is not the quick run", st);
    free(out), free(err);
    /* LAB=0 is the project's build, LAB=1 the lab's. */
    st = test_run(DIR, MAKE "-n build/.flags LAB=0", &out, &err);
    CHECKF(st == 0 && out && strstr(out, "-std=c11") && !strstr(out, "GRIDBVH_LAB"),
           "make LAB=0 (exit %d) builds the lab: %.300s", st, out ? out : "");
    free(out), free(err);
    st = test_run(DIR, MAKE "-n build/.flags LAB=1", &out, &err);
    CHECKF(st == 0 && out && strstr(out, "-DGRIDBVH_LAB"), "make LAB=1 (exit %d) is not the lab", st);
    free(out), free(err);
    /* Anything else is an error before any work. */
    static const char *const bad[] = {"report QUICK=yes", "report QUICK=2", "all LAB=true"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char cmd[256];
        snprintf(cmd, sizeof cmd, MAKE "%s", bad[i]);
        st = test_run(DIR, cmd, &out, &err);
        CHECKF(st == 2 && err && strstr(err, "takes 1 (on) or 0 (off)") && out && !out[0],
               "make %s: exit %d: %.300s", bad[i], st, err ? err : "");
        free(out), free(err);
    }
}
