/*
 * test.h - a tiny test harness: TEST(name) registers a test (no central
 * list to edit), TEST_PER_KIND(prefix) one test per registered accelerator
 * kind, CHECK records a failure and continues, test_skip() says why a test
 * could not run. Output ends with "N passed, N failed, N skipped".
 * `bin/run_tests grid` (make test T=grid) runs a family: the tests of
 * test_grid*.c, whose names all start with "grid_" (a test's name starts
 * with its file's family, the first word after "test_"); `bin/run_tests
 * conformance_grid` one test by its exact name; `bin/run_tests '*word*'`
 * (make test T='*word*') the tests whose name contains word; a comma-
 * separated list any of these. `bin/run_tests --list` lists them, and
 * `bin/run_tests -j N` runs them in N processes (default: one per CPU).
 * tests/README.md has the rules.
 */
#ifndef TESTS_TEST_H
#define TESTS_TEST_H

#include <stdio.h>

#include "accel.h"

/* file: the source file of the test; the tests of one file family
 * (test_report*.c, test_loader*.c, ...) share temporary paths, so the
 * runner's workers take such a family as one unit. */
void test_register(const char *name, void (*fn)(void), const char *file);
/* Registers fn as one test per kind of accel_kinds[] (main.c expands it
 * when it starts), named prefix_<kind>: a new kind gets its own tests.
 * file: the source file (prefix is its family). */
void test_register_per_kind(const char *prefix, void (*fn)(const accel_kind *kind),
                            const char *file);
/* Records a failed check of the running test (prints file:line: message). */
void test_fail(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
/* Prints a note under the running test (e.g. a part of it not run, and why). */
void test_note(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* Marks the running test skipped, with the reason (e.g. "../shared/scenes
 * not found"): it counts as skipped, not passed, unless a check failed. The
 * test returns after it. */
void test_skip(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* Calls fn for every registered test (per-kind ones expanded) with its name
 * and its file's family; returns their count. */
int test_each(void (*fn)(const char *name, const char *family, void *ctx), void *ctx);

#define TEST(name)                                                                       \
    static void name(void);                                                              \
    __attribute__((constructor)) static void test_reg_##name(void)                       \
    {                                                                                    \
        test_register(#name, name, __FILE__);                                            \
    }                                                                                    \
    static void name(void)

/* TEST_PER_KIND(conformance) { ... kind ... } defines conformance_brute,
 * conformance_bvh, ...: `make test T=conformance_grid` runs grid's only. */
#define TEST_PER_KIND(prefix)                                                            \
    static void prefix(const accel_kind *kind);                                          \
    __attribute__((constructor)) static void test_reg_##prefix(void)                     \
    {                                                                                    \
        test_register_per_kind(#prefix, prefix, __FILE__);                                         \
    }                                                                                    \
    static void prefix(const accel_kind *kind)

#define CHECK(cond)                                                                      \
    do {                                                                                 \
        if (!(cond)) test_fail(__FILE__, __LINE__, "check failed: %s", #cond);            \
    } while (0)

#define CHECKF(cond, ...)                                                                \
    do {                                                                                 \
        if (!(cond)) test_fail(__FILE__, __LINE__, __VA_ARGS__);                         \
    } while (0)

/* Whether the suites should run kind `name`: all, unless the environment
 * variable KINDS lists kinds (comma-separated), e.g. make test KINDS=grid.
 * run_tests refuses a KINDS naming no registered kind before any test runs. */
int test_kind_selected(const char *name);

/* Path of ../shared/scenes relative to the repository (NULL when absent). */
const char *test_shared_scenes(void);

#endif
