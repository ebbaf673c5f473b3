/*
 * test_lab.c - the lab's checks can pass and can fail. Each step's check
 * passes on the project's own implementation (bvh:build=median, with
 * traverse=packet for step 4) and on the lab's reference solution
 * (tests/lab_solution.c, the starter with its four functions written), and
 * fails on the untouched starter (lab/starter.c) and on every mutant
 * student (lab_solution.h: one typical mistake each), each with the
 * outcome it deserves: wrong, crashed, or correct but slow. A check that
 * cannot fail is caught here, not by a student.
 *
 * LAB_MUTANT_TABLE=1 bin/run_tests lab_mutants prints the table of
 * mutants: step, outcome, the first line of the report's failure.
 */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "lab/check.h"
#include "tests/lab_solution.h"
#include "support.h"
#include "test.h"

extern const accel_kind accel_kind_starter;
extern const accel_kind accel_kind_grid_starter;
void lab_top_starter(const lab_top *top, const accel_ray *ray, accel_hit *hit);
void lab_top_lab_solution(const lab_top *top, const accel_ray *ray, accel_hit *hit);

static void run_step(int step)
{
    const accel_kind *bvh = accel_find_kind("bvh");
    CHECK(bvh != NULL);
    if (!bvh) return;
    accel_error err = {0};
    lab_result r;
    lab_subject own = {bvh, "build=median", 2, NULL, 1, NULL};
    if (step != 7) { /* step 7 checks a function of the student's file, not a kind */
        CHECK(lab_check(step, &own, &r, &err) == 0);
        CHECKF(r.passed, "step %d fails on the project's own implementation:\n%s", step, r.report);
    }
    lab_solution_mutant = LM_NONE;
    lab_subject sol = {&accel_kind_lab_solution, "", 2, NULL, 1, lab_top_lab_solution};
    CHECK(lab_check(step, &sol, &r, &err) == 0);
    CHECKF(r.passed && r.outcome == LAB_PASSED,
           "step %d fails on the reference solution (tests/lab_solution.c):\n%s", step, r.report);
    if (getenv("LAB_MUTANT_TABLE")) fputs(r.report, stdout);
    lab_subject starter = {&accel_kind_starter, "", 2, NULL, 1, lab_top_starter};
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
TEST(lab_step7_top_level) { run_step(7); }

/* The optional grid step: the project's grid in its plain form (bounding
 * box overlap, no mailbox) passes, the untouched lab/grid_starter.c fails. */
TEST(lab_step6_grid)
{
    const accel_kind *grid = accel_find_kind("grid");
    CHECK(grid != NULL);
    if (!grid) return;
    accel_error err = {0};
    lab_result r;
    lab_subject own = {grid, "overlap=bbox,mailbox=0", 2, NULL, 1, NULL};
    CHECK(lab_check(6, &own, &r, &err) == 0);
    CHECKF(r.passed, "step 6 fails on the project's grid:\n%s", r.report);
    lab_subject starter = {&accel_kind_grid_starter, "", 2, NULL, 1, NULL};
    CHECK(lab_check(6, &starter, &r, &err) == 0);
    CHECKF(!r.passed && r.outcome == LAB_WRONG && strstr(r.report, "FAIL"),
           "step 6 passes on the untouched grid starter\n%s", r.report);
}

/* ---- mutant students ------------------------------------------------------ */

typedef struct {
    int id;
    int step;           /* the step whose check must fail */
    lab_outcome expect; /* and how */
    const char *name;
    const char *says;   /* NULL, or words the report's failure must hold (the cause) */
} mutant_case;

/* A traversal stack too small for the tree is undefined behaviour that
 * gives no wrong answer here: only AddressSanitizer sees it (make lab runs
 * the student's code under it; `make sanitize` runs this table under it). */
#if defined(__SANITIZE_ADDRESS__)
#define LAB_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LAB_ASAN 1
#endif
#endif
#ifndef LAB_ASAN
#define LAB_ASAN 0
#endif

static const mutant_case mutants[] = {
    {LM_LEAF_START, 1, LAB_WRONG, "step 1: a leaf's left_first is its node index", NULL},
    {LM_EMPTY_LEAF, 1, LAB_WRONG, "step 1: empty leaves (box-middle split)", NULL},
    {LM_CENTROID_BOX, 1, LAB_WRONG, "step 1: node boxes from centroids", NULL},
    {LM_FIRST_PRIM_BOX, 1, LAB_WRONG, "step 1: node boxes from the first primitive", NULL},
    {LM_LOST_PRIM, 1, LAB_WRONG, "step 1: the right child loses a primitive", NULL},
    {LM_NO_LEAF_COUNT, 1, LAB_WRONG, "step 1: leaves never counted", NULL},
    {LM_LEAF_SWAP, 1, LAB_WRONG, "step 1: a leaf's left_first and count swapped",
     "swapped"},
    {LM_LEAF_RECURSE, 1, LAB_CRASHED, "step 1: leaf when count < leaf: leaf=1 recurses forever",
     "with leaf=1"},
    {LM_CULL_LT, 2, LAB_WRONG, "step 2: pop cull entry < t", NULL},
    {LM_CULL_LE, 2, LAB_WRONG, "step 2: pop cull entry <= t", NULL},
    {LM_NO_FAR_PUSH, 2, LAB_WRONG, "step 2: the far child never pushed", NULL},
    {LM_FIRST_HIT, 2, LAB_WRONG, "step 2: stops at the first leaf that hits", NULL},
    {LM_POP_EMPTY, 2, LAB_CRASHED, "step 2: pops an empty stack", NULL},
    {LM_NO_STEPS, 2, LAB_WRONG, "step 2: counts no node visits", NULL},
    {LM_OWN_ORDER_ID, 2, LAB_WRONG, "step 2: the hit's position in order[], not its id",
     "not its position"},
    {LM_NO_PRIM_COUNT, 2, LAB_WRONG, "step 2: primitive tests never counted", "*prims"},
    {LM_LEAVES_ONLY, 2, LAB_WRONG, "step 2: node visits counted at leaves only", "*steps"},
    {LM_SMALL_STACK, 2, LAB_CRASHED, "step 2: a traversal stack of 8 entries (ASan only)",
     "AddressSanitizer or UBSan stopped"},
    {LM_ANY_HIT_ALL, 2, LAB_SLOW, "step 2: occluded() searches on for the closest hit",
     "occluded()"},
    {LM_FAR_FIRST, 2, LAB_SLOW, "step 2: the far child first", NULL},
    {LM_NO_ORDER, 2, LAB_SLOW, "step 2: no near-first order", NULL},
    {LM_NO_SHRINK, 2, LAB_SLOW, "step 2: t_max never shrunk", NULL},
    {LM_NO_SORT, 2, LAB_SLOW, "step 1's split never sorts (step 2's rule)", NULL},
    {LM_ROOT_BOX, 2, LAB_SLOW, "step 1's node boxes all the root's (step 2's rule)",
     "look at the boxes and the depth view"},
    {LM_WALK_ALL, 3, LAB_SLOW, "step 3: every primitive to the visitor", NULL},
    {LM_WALK_NO_PAD, 3, LAB_WRONG, "step 3: boxes not padded", NULL},
    {LM_WALK_PRIM_HIT, 3, LAB_WRONG, "step 3: filters with its own triangle test", NULL},
    {LM_WALK_T_ONE, 3, LAB_WRONG, "step 3: boxes against [t_near, 1]", NULL},
    {LM_WALK_NO_STEPS, 3, LAB_WRONG, "step 3: the walk counts no node visits", "*steps"},
    {LM_WALK_NO_SHRINK, 3, LAB_SLOW, "step 3: t_max never shrinks the walk", "t_max"},
    {LM_PACKET_FAKE, 4, LAB_WRONG, "step 4: single rays, packet_steps += 1", NULL},
    {LM_PACKET_CULL_LT, 4, LAB_WRONG, "step 4: a lane's cull entry < t", NULL},
    {LM_PACKET_FIRST_ONLY, 4, LAB_WRONG, "step 4: only the first lane's box test", NULL},
    {LM_PACKET_NO_COUNT, 4, LAB_WRONG, "step 4: packet_steps never counted", NULL},
    {LM_PACKET_PER_LANE, 4, LAB_WRONG, "step 4: packet_steps counted once per lane",
     "once per lane"},
    {LM_PACKET_UNINIT, 4, LAB_WRONG, "step 4: lanes that miss keep a stale hit",
     "uninitialized"},
    {LM_TOP_FORWARD, 7, LAB_WRONG, "step 7: object -> world matrix, not its inverse", NULL},
    {LM_TOP_DIR_MOVED, 7, LAB_WRONG, "step 7: the direction translated too", NULL},
    {LM_TOP_NORMALIZE, 7, LAB_WRONG, "step 7: object direction renormalized", NULL},
    {LM_TOP_FIRST_INSTANCE, 7, LAB_WRONG, "step 7: the first instance hit, not the nearest", NULL},
};

static const char *outcome_name(lab_outcome o)
{
    static const char *const names[] = {"PASSED", "wrong", "crashed", "correct but slow"};
    return o <= LAB_SLOW ? names[o] : "?";
}

/* The first failure line of a report, without its tag. */
static void first_failure(const char *report, char *out, size_t size)
{
    const char *tags[] = {"  FAIL ", "  SLOW ", "  CRASH "}, *at = NULL;
    for (int i = 0; i < 3; i++) {
        const char *p = strstr(report, tags[i]);
        if (p && (!at || p < at)) at = p;
    }
    snprintf(out, size, "%s", at ? at + 2 : "(no failure line)");
    char *nl = strchr(out, '\n');
    if (nl) *nl = '\0';
}

/* Every mutant of `step`, and of the steps before it that it must pass. */
static void run_mutants(int step)
{
    int table = getenv("LAB_MUTANT_TABLE") != NULL;
    lab_subject sol = {&accel_kind_lab_solution, "", 2, NULL, 1, lab_top_lab_solution};
    for (size_t i = 0; i < sizeof mutants / sizeof mutants[0]; i++) {
        const mutant_case *m = &mutants[i];
        if (m->step != step) continue;
        if (m->id == LM_SMALL_STACK && !LAB_ASAN) {
            if (table)
                printf("| %d | %s | (only under make sanitize / make lab) | | |\n", m->step,
                       m->name);
            continue;
        }
        accel_error err = {0};
        lab_result r;
        lab_solution_mutant = m->id;
        int rc = lab_check(step, &sol, &r, &err);
        lab_solution_mutant = LM_NONE;
        CHECK(rc == 0);
        char line[200];
        first_failure(r.report, line, sizeof line);
        CHECKF(!r.passed, "mutant %s passes step %d: the check cannot catch it\n%s", m->name,
               step, r.report);
        CHECKF(r.passed || r.outcome == m->expect, "mutant %s fails step %d as %s, not as %s:\n%s",
               m->name, step, outcome_name(r.outcome), outcome_name(m->expect), r.report);
        CHECKF(r.passed || !m->says || strstr(r.report, m->says),
               "mutant %s fails step %d without naming the cause (\"%s\"):\n%s", m->name, step,
               m->says, r.report);
        if (table)
            printf("| %d | %s | %s | %s | %.160s |\n", m->step, m->name,
                   r.passed ? "NO" : "yes", outcome_name(r.outcome), line);
    }
}

TEST(lab_mutants_step1) { run_mutants(1); }
TEST(lab_mutants_step2) { run_mutants(2); }
TEST(lab_mutants_step3) { run_mutants(3); }
TEST(lab_mutants_step4) { run_mutants(4); }
TEST(lab_mutants_step7) { run_mutants(7); }

/* The solution is the starter with its four functions written: the rest
 * (the build's frame and its tree check, lab_walk, the batch entries) is
 * the starter's word for word, so the checks see it as a student's kind. */
TEST(lab_solution_keeps_the_starter)
{
    static const char *const parts[][2] = {
        {"static void lab_destroy", "/* ---- step 2"},
        {"static int lab_walk(", "/* ---- step 4"},
        {"/* ---- batch entries", "const accel_kind accel_kind_"},
    };
    char *st = test_read_file("lab/starter.c", NULL);
    char *sol = test_read_file("tests/lab_solution.c", NULL);
    CHECK(st && sol);
    for (size_t i = 0; st && sol && i < sizeof parts / sizeof parts[0]; i++) {
        const char *a = strstr(st, parts[i][0]), *b = strstr(sol, parts[i][0]);
        const char *ae = a ? strstr(a, parts[i][1]) : NULL, *be = b ? strstr(b, parts[i][1]) : NULL;
        CHECKF(ae && be, "part %s..%s missing", parts[i][0], parts[i][1]);
        if (!ae || !be) continue;
        CHECKF(ae - a == be - b && memcmp(a, b, (size_t)(ae - a)) == 0,
               "tests/lab_solution.c's part from \"%s\" differs from lab/starter.c's", parts[i][0]);
    }
    free(st);
    free(sol);
}

/* Step 5 runs the kind's variants first, each scene in its own child: a
 * leaf rule that recurses forever at leaf=1 (step 1 catches it too) is
 * reported naming the variant and the scene, not as a bare "died". */
TEST(lab_step5_names_the_variant)
{
    lab_subject sol = {&accel_kind_lab_solution, "", 2, NULL, 1, NULL};
    accel_error err = {0};
    lab_result r;
    lab_solution_mutant = LM_LEAF_RECURSE;
    int rc = lab_check(5, &sol, &r, &err);
    lab_solution_mutant = LM_NONE;
    CHECK(rc == 0);
    CHECKF(!r.passed && r.outcome == LAB_CRASHED &&
               strstr(r.report, "on scene soup:tris=3000,seed=7, your build with leaf=1"),
           "step 5 does not name the variant and the scene of a crash:\n%s", r.report);
}

/* ---- the sanitized checks (Makefile: bin-lab/lab-safe) ------------------- */

static void dies_of_a_signal(const lab_subject *s, const char *scene, lab_result *r,
                             accel_error *err)
{
    (void)s, (void)scene, (void)err;
    lab_where(r, "scene %s, ray set primary", scene);
    raise(SIGABRT); /* not SIGSEGV: AddressSanitizer (make sanitize) would catch that */
}

static void stopped_by_a_sanitizer(const lab_subject *s, const char *scene, lab_result *r,
                                   accel_error *err)
{
    (void)s, (void)scene, (void)err;
    lab_where(r, "scene %s, ray set shadow", scene);
    _exit(1); /* what AddressSanitizer and UBSan do after their report */
}

/* A crash in a run without the sanitizers points at the sanitized check;
 * a child stopped by a sanitizer points at its report, which names the
 * line; both name the scene and the ray set. */
TEST(lab_crash_hints_name_the_sanitizers)
{
    lab_subject sol = {&accel_kind_lab_solution, "", 1, NULL, 1, NULL};
    accel_error err = {0};
    lab_result r;
    memset(&r, 0, sizeof r);
    r.passed = 1;
    lab_run_isolated(dies_of_a_signal, &sol, "cube:n=2", &r, &err);
    CHECKF(!r.passed && r.outcome == LAB_CRASHED && strstr(r.report, "ray set primary") &&
               strstr(r.report, "`make lab STEP=n` runs the check under AddressSanitizer"),
           "a crash's report does not point at the sanitized check:\n%s", r.report);
    memset(&r, 0, sizeof r);
    r.passed = 1;
    lab_run_isolated(stopped_by_a_sanitizer, &sol, "cube:n=2", &r, &err);
    CHECKF(!r.passed && r.outcome == LAB_CRASHED && strstr(r.report, "ray set shadow") &&
               strstr(r.report, "AddressSanitizer or UBSan stopped your code") &&
               strstr(r.report, "names the line"),
           "a sanitizer's stop is not reported as one:\n%s", r.report);
}

/* make lab STEP=n runs bin-lab/lab-safe (the student's file compiled with
 * -fsanitize=address,undefined) where the compiler links the sanitizers,
 * except step 5, which times frames and runs the plain bin-lab/lab. */
TEST(lab_make_runs_the_checks_sanitized)
{
    static const char *const cases[][2] = {{"2", "lab-safe"}, {"4", "lab-safe"}, {"5", "lab"}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char cmd[512], *out = NULL, *err = NULL;
        snprintf(cmd, sizeof cmd,
                 "env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make -s --no-print-directory "
                 "--eval 'LAB_HAVE_SAN := 1' --eval 'lab-print-checker: ; @echo "
                 "\"$(LAB_SAN)|$(LAB_SAFE_OBJ)|$(LAB_CHECKER)\"' lab-print-checker STEP=%s",
                 cases[i][0]);
        int st = test_run("build/test-lab", cmd, &out, &err);
        char want[64];
        snprintf(want, sizeof want, "|%s\n", cases[i][1]);
        CHECKF(st == 0 && out && strstr(out, "-fsanitize=address,undefined") &&
                   strstr(out, "lab/student.safe.o") && strstr(out, want),
               "STEP=%s: exit %d, not %s with the sanitizers: %.300s %.300s", cases[i][0], st,
               cases[i][1], out ? out : "", err ? err : "");
        free(out), free(err);
    }
}
