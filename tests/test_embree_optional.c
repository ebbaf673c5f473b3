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

/* tools/vs_embree.sh without Embree: a stand-in bin/embree_ref (it prints
 * the reference's result line) beside the real bin/trace. The script names
 * the ISA bin/trace picked (not the compiler target of build/.flags, which
 * named AVX-512 on a CPU without it), and its cache of OBJ and rays follows
 * the scene's content: an edited mesh of the same name and size is made
 * anew, the same content is not. */
TEST(embree_vs_script_isa_and_cache)
{
    if (system("mkdir -p " DIR "/bin " DIR "/m && ln -sf \"$PWD/bin/trace\" " DIR "/bin/trace && "
               "printf '#!/bin/sh\\necho \"embree mode=single rays=1 hits=1 mrays=1.500 min=1 "
               "max=2 passes=1 isa=standin builds=1\"\\n' > " DIR "/bin/embree_ref && "
               "chmod +x " DIR "/bin/embree_ref && rm -rf build/vs_embree/tri.off-*") != 0) {
        test_fail(__FILE__, __LINE__, "cannot set up " DIR "/bin");
        return;
    }
    const char *run = "BIN=" DIR "/bin ROUNDS=1 SIZE=16x12 CHECK=0 PASSES=1 SETS=primary "
                      "tools/vs_embree.sh " DIR "/m/tri.off 2>&1";
    static const char *const meshes[3] = {
        "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", /* made */
        "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", /* the same: from the cache */
        "OFF\n3 1 0\n0 0 0\n2 0 0\n0 1 0\n3 0 1 2\n", /* edited, same name and size: made */
    };
    for (int i = 0; i < 3; i++) {
        if (!test_write_file(DIR "/m/tri.off", meshes[i])) return;
        char *out = NULL;
        int rc = test_run(DIR, run, &out, NULL);
        CHECKF(rc == 0, "vs_embree.sh (mesh %d): exit %d: %.400s", i, rc, out ? out : "");
        int made = out && strstr(out, "vs_embree: making ") != NULL;
        CHECKF(made == (i != 1), "mesh %d: the OBJ and rays were %s: %.400s", i,
               made ? "made anew for the same content" : "taken from the cache of other content",
               out ? out : "");
        char want[128];
        snprintf(want, sizeof want, "ISA: ours bvh:width=8 %s (what bin/trace picked)", accel_isa_name());
        CHECKF(out && strstr(out, want), "no '%s': %.400s", want, out ? out : "");
        free(out);
    }
    /* GRIDBVH_ISA=avx2 forces the baseline: the script says so. */
    char cmd[512], *out = NULL;
    snprintf(cmd, sizeof cmd, "GRIDBVH_ISA=avx2 %s", run);
    int rc = test_run(DIR, cmd, &out, NULL);
    CHECKF(rc == 0 && out && strstr(out, "ISA: ours bvh:width=8 avx2 (what bin/trace picked)"),
           "GRIDBVH_ISA=avx2: exit %d: %.400s", rc, out ? out : "");
    free(out);
}
