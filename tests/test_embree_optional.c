/*
 * test_embree_optional.c - the Embree reference (tools/embree_ref.c) stays
 * optional: `make`, `make test` and `make report` never build or run it,
 * and `make embree` without libembree-dev's header says so and fails.
 * Needs nothing optional: make and the compiler only.
 */
#include <stdlib.h>
#include <string.h>

#include "support.h"
#include "test.h"

#define DIR "build/test_embree_optional"

/* Every command of all, test and report, as if nothing were built (-B). */
TEST(embree_not_in_default_targets)
{
    char *out = NULL, *err = NULL;
    int rc = test_run(DIR, "make -nB --no-print-directory all test report", &out, &err);
    CHECKF(rc == 0, "make -nB all test report: exit %d: %.300s", rc, err ? err : "");
    CHECKF(out && strstr(out, "tools/trace.o") && strstr(out, "run_tests"),
           "make -nB printed no build of bin/trace and bin/run_tests: %.300s", out ? out : "");
    static const char *const never[] = {"embree_ref", "embree3", "rtcore"};
    for (int i = 0; i < 3; i++)
        CHECKF(out && !strstr(out, never[i]), "make -nB all test report mentions %s: %.300s",
               never[i], out && strstr(out, never[i]) ? strstr(out, never[i]) : "");
    free(out), free(err);
}

/* The header hidden (-nostdinc): a clear message and a failure, before
 * anything is compiled. */
TEST(embree_target_without_header)
{
    char *out = NULL, *err = NULL;
    int rc = test_run(DIR, "make --no-print-directory embree EMBREE_CFLAGS=-nostdinc", &out, &err);
    CHECKF(rc != 0, "make embree without the header succeeded");
    CHECKF(out && strstr(out, "make embree: libembree-dev not installed"),
           "no 'libembree-dev not installed' message: %.300s / %.300s", out ? out : "",
           err ? err : "");
    CHECKF(out && !strstr(out, "embree_ref.c"), "make embree compiled without the header: %.300s",
           out ? out : "");
    free(out), free(err);
}
