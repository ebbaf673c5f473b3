/*
 * test_report_probe.c - the experiments' collapse probe (experiments/engine/group.c):
 * a configuration whose counted pass would take seconds (the regular grid
 * on teapot_stadium, one cell holding the teapot) is left out on a
 * 2048-ray probe, with the probe's prediction as its reason, instead of
 * after a full counted pass (143 s for the per-id `grid` at 800x600 in a
 * full report); the fast configurations of the same scene are still
 * measured.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

TEST(report_probe_leaves_out_collapsed)
{
    /* 320x240: about 77k primary rays at some 30k rays/s for `grid`, a
     * predicted pass of seconds, far past the quick budget's 0.5 s. */
    /* The per-id grid (cells=ids): the block grid's 8-wide test makes the
     * same collapse some 8 times cheaper, measured within the budget. */
    if (system("bin/exp_grids --quick --kinds grid --accel grid:cells=ids --scene teapot_stadium:n=8 "
               "--rt-size 320x240 --out build/test-probe --quiet > build/test-probe.log 2>&1") != 0) {
        test_fail(__FILE__, __LINE__, "bin/exp_grids failed: see build/test-probe.log");
        return;
    }
    char *md = test_read_file("build/test-probe/exp_grids.md", NULL);
    CHECKF(md != NULL, "build/test-probe/exp_grids.md not written");
    if (!md) return;
    const char *left = strstr(md, "`grid:cells=ids` (collapsed: ");
    CHECKF(left != NULL, "`grid:cells=ids` was not left out as collapsed");
    if (left) {
        const char *end = strstr(left, ")");
        const char *probe = strstr(left, "in a probe of 2048 rays, which predicts ");
        CHECKF(probe && (!end || probe < end + 200),
               "`grid:cells=ids` was left out without the probe: %.200s", left);
        double s = 0;
        if (probe) sscanf(probe + strlen("in a probe of 2048 rays, which predicts "), "%lf", &s);
        CHECKF(s > 0.625, "the probe predicted %.2f s, under 1.25 times the 0.5 s budget", s);
    }
    /* The packet traversal and the block grid of the same scene are fast:
     * measured, with their rows. */
    CHECK(strstr(md, "| `grid:traverse=packet` |") != NULL);
    CHECK(strstr(md, "| `grid` |") != NULL);
    free(md);
}
