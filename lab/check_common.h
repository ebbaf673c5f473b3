/*
 * check_common.h - what the lab's step checks share (check_common.c): the
 * subject and the result of a check, the report it writes, and stiff rays.
 * check.c runs the steps; step 3 has its own file, check_step3.c.
 */
#ifndef LAB_CHECK_COMMON_H
#define LAB_CHECK_COMMON_H

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

/* Appends to the report. */
void lab_say(lab_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Fails the step with a message (the first failure is the one to fix). */
void lab_fail(lab_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Rays from the camera through triangle vertices, and axis-parallel rays
 * with +-0 components from the faces of the scene's box. */
int lab_make_stiff_rays(const accel_scene *sc, rays_set *out, accel_error *err);
/* Step 3 (check_step3.c), run by lab_check (check.h). */
void lab_check_step3(const lab_subject *s, lab_result *r, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
