/*
 * test.h - a tiny test harness: TEST(name) registers a test (no central
 * list to edit), CHECK records a failure and continues. Output ends with
 * "N passed, N failed"; `bin/run_tests FILTER` runs the tests whose name
 * contains FILTER (make test T=FILTER).
 */
#ifndef TESTS_TEST_H
#define TESTS_TEST_H

#include <stdio.h>

void test_register(const char *name, void (*fn)(void));
/* Records a failed check of the running test (prints file:line: message). */
void test_fail(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Prints a note (e.g. "skipped: ../shared/scenes absent") under the running test. */
void test_note(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

#define TEST(name)                                                                       \
    static void name(void);                                                              \
    __attribute__((constructor)) static void test_reg_##name(void) { test_register(#name, name); } \
    static void name(void)

#define CHECK(cond)                                                                      \
    do {                                                                                 \
        if (!(cond)) test_fail(__FILE__, __LINE__, "check failed: %s", #cond);            \
    } while (0)

#define CHECKF(cond, ...)                                                                \
    do {                                                                                 \
        if (!(cond)) test_fail(__FILE__, __LINE__, __VA_ARGS__);                         \
    } while (0)

/* Whether the suites should run kind `name`: all, unless the environment
 * variable KINDS lists kinds (comma-separated), e.g. make test KINDS=grid. */
int test_kind_selected(const char *name);

/* Path of ../shared/scenes relative to the repository (NULL when absent). */
const char *test_shared_scenes(void);

#endif
