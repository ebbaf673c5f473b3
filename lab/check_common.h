/*
 * check_common.h - what the lab's step checks share (check_common.c): the
 * subject and the result of a check, the report it writes, and stiff rays.
 * check.c runs the steps; step 3 has its own file, check_step3.c.
 */
#ifndef LAB_CHECK_COMMON_H
#define LAB_CHECK_COMMON_H

#include "accel.h"
#include "rays/rays.h"
#include "top.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Steps 1-5 are the lecture's lab; 6 (a grid) and 7 (the top level) are optional. */
#define LAB_STEPS 7

typedef struct {
    const accel_kind *kind; /* the kind under test (registered or not) */
    const char *kv;         /* its parameters, the part of a spec after "name:" */
    int threads;            /* step 5 */
    const char *out_dir;    /* NULL: no images; else an existing folder for step 2's depth views */
    int quick;              /* smaller sizes (the self-test in `make test`) */
    lab_top_fn top;         /* step 7: the subject's top level (NULL: none) */
} lab_subject;

/* How a step ended: PASSED, or not yet in one of three ways. */
typedef enum {
    LAB_PASSED,
    LAB_WRONG,   /* a wrong answer, a broken tree, a counter that is not the walk's */
    LAB_CRASHED, /* the check's child process died (or ran out of time) */
    LAB_SLOW     /* correct, but more work than the reference (the quality rule) */
} lab_outcome;

typedef struct {
    int passed;
    lab_outcome outcome;
    char where[160];   /* what the check is doing: "scene X, ray set Y" (for a crash) */
    char report[8192]; /* what was checked; on failure what is wrong, with a hint */
} lab_result;

/* The quality rule: a correct kind doing more than this many times the
 * reference's work (nodes visited per ray; the walk's nodes and triangles)
 * is "correct but slow". Correct solutions measure 0.86-0.99x, the usual
 * mistakes of order (far child first, no near-first order, no t_max shrink,
 * a split that never sorts) 1.27-1.96x (issue 37). */
#define LAB_SLOW_RATIO 1.25
/* The counters' lower band: a correct walk visits every node on the way to
 * every leaf it tests, so it counts at least this share of the reference's
 * nodes and primitive tests (a count of leaves only: 0.13x). */
#define LAB_COUNT_LOW 0.5
/* Above this many times the reference's work, the order is not the cause:
 * the hint points at the boxes and the depth view. */
#define LAB_BOX_RATIO 3.0

/* Seconds a scene's check may take before it counts as an endless loop. */
#define LAB_SCENE_TIMEOUT 120

/* Appends to the report. */
void lab_say(lab_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Fails the step with a message (the first failure is the one to fix). */
void lab_fail(lab_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Fails the step as correct but slow (the quality rule). */
void lab_slow(lab_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Notes what the check does now: a crash report names it. */
void lab_where(lab_result *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Runs fn(s, scene, r, err) in a child process, so that a crash (or an
 * endless loop) of the kind becomes a report naming the scene and the
 * ray set, and the next steps still run. */
typedef void (*lab_scene_check)(const lab_subject *s, const char *scene, lab_result *r,
                                accel_error *err);
void lab_run_isolated(lab_scene_check fn, const lab_subject *s, const char *scene, lab_result *r,
                      accel_error *err);
/* Rays from the camera through triangle vertices, and axis-parallel rays
 * with +-0 components from the faces of the scene's box. */
int lab_make_stiff_rays(const accel_scene *sc, rays_set *out, accel_error *err);
/* Builds the subject with extra parameters (e.g. "leaf=1") after its own. */
int lab_build_subject(const lab_subject *s, const char *extra, const accel_scene *scene, void **a,
                      accel_build_stats *st, accel_error *err);
/* Step 5 (check_step5.c): the kind's variants on scenes[0, n), then frames. */
void lab_check_step5(const lab_subject *s, const char *const *scenes, size_t n, lab_result *r,
                     accel_error *err);
/* Step 3 (check_step3.c), run by lab_check (check.h). */
void lab_check_step3(const lab_subject *s, lab_result *r, accel_error *err);
/* Step 7, the optional top level (check_top.c). */
void lab_check_top(const lab_subject *s, lab_result *r, accel_error *err);
/* Mirrored, scaled, rotated and far instances (a .scene text). */
extern const char *const lab_far_scene;

#ifdef __cplusplus
}
#endif

#endif
