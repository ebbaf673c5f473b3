/*
 * test_lab.c - the lab's checks can pass and can fail: each step's check
 * passes on the project's own implementation (bvh:build=median, with
 * traverse=packet for step 4) and fails on the untouched starter
 * (lab/starter.c), which is compiled into the test binary for this.
 */
#include <string.h>

#include "lab/check.h"
#include "test.h"

extern const accel_kind accel_kind_starter;

static void run_step(int step)
{
    const accel_kind *bvh = accel_find_kind("bvh");
    CHECK(bvh != NULL);
    if (!bvh) return;
    accel_error err = {0};
    lab_result r;
    lab_subject own = {bvh, "build=median", 2, NULL, 1};
    CHECK(lab_check(step, &own, &r, &err) == 0);
    CHECKF(r.passed, "step %d fails on the project's own implementation:\n%s", step, r.report);
    lab_subject starter = {&accel_kind_starter, "", 2, NULL, 1};
    CHECK(lab_check(step, &starter, &r, &err) == 0);
    CHECKF(!r.passed, "step %d passes on the untouched starter: the check cannot fail\n%s", step,
           r.report);
    CHECKF(strstr(r.report, "FAIL") != NULL, "step %d: the starter's report names no failure",
           step);
}

TEST(lab_step1_build) { run_step(1); }
TEST(lab_step2_traversal) { run_step(2); }
TEST(lab_step4_packets) { run_step(4); }
TEST(lab_step5_real_time) { run_step(5); }
TEST(lab_step3_many_meshes) { run_step(3); }
