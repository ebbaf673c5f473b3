/*
 * check.h - the pass/fail check of each lab step (LAB.md), run by
 * `make lab STEP=n` on the student's kind and by `make test` on the
 * project's own implementation (must pass) and on the untouched starter
 * (must fail), so that a check that cannot fail is caught.
 */
#ifndef LAB_CHECK_H
#define LAB_CHECK_H

#include "accel.h"
#include "rays/rays.h"

#ifdef __cplusplus
extern "C" {
#endif

#define LAB_STEPS 5

typedef struct {
    const accel_kind *kind; /* the kind under test (registered or not) */
    const char *kv;         /* its parameters, the part of a spec after "name:" */
    int threads;            /* step 5 */
    const char *out_dir;    /* NULL: no images; else an existing folder for step 2's depth views */
    int quick;              /* smaller sizes (the self-test in `make test`) */
} lab_subject;

typedef struct {
    int passed;
    char report[8192]; /* what was checked; on failure what is wrong, with a hint */
} lab_result;

const char *lab_step_title(int step);
/* Runs step `step` (1..LAB_STEPS) on the subject. Returns 0 when the check
 * could run (passed or not: see out->passed), else an error status. */
int lab_check(int step, const lab_subject *s, lab_result *out, accel_error *err);

/* Shared by the checks (check.c, check_step3.c). */
void lab_say(lab_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Fails the step with a message (the first failure is the one to fix). */
void lab_fail(lab_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Rays from the camera through triangle vertices, and axis-parallel rays
 * with +-0 components from the faces of the scene's box. */
int lab_make_stiff_rays(const accel_scene *sc, rays_set *out, accel_error *err);
/* Step 3 (check_step3.c). */
void lab_check_step3(const lab_subject *s, lab_result *r, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
