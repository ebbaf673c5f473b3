/*
 * check.h - the pass/fail check of each lab step (LAB.md), run by
 * `make lab STEP=n` on the student's kind and by `make test` on the
 * project's own implementation (must pass) and on the untouched starter
 * (must fail), so that a check that cannot fail is caught.
 */
#ifndef LAB_CHECK_H
#define LAB_CHECK_H

#include "accel.h"
#include "check_common.h"

#ifdef __cplusplus
extern "C" {
#endif

const char *lab_step_title(int step);
/* Runs step `step` (1..LAB_STEPS) on the subject. Returns 0 when the check
 * could run (passed or not: see out->passed), else an error status. */
int lab_check(int step, const lab_subject *s, lab_result *out, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
