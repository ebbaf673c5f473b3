/*
 * main.c - runs the registered tests.
 *
 * Usage: run_tests [--list] [FILTER]
 *   FILTER   run the tests whose name contains it (all without one);
 *   --list   print the names (those matching FILTER) and run nothing.
 * The environment variable KINDS (comma-separated kind names) limits the
 * suites that iterate over kinds, and the per-kind tests, to those kinds.
 * A FILTER matching no test and a KINDS naming an unknown kind are errors
 * (exit status 2) before anything runs; failed checks give exit status 1.
 */
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "support.h"

typedef struct {
    const char *name;
    void (*fn)(void);
    void (*kind_fn)(const accel_kind *kind); /* per-kind tests: fn is NULL */
    const accel_kind *kind;
} test_case;

enum { MAX_TESTS = 512, MAX_FAMILIES = 16 };

static test_case tests[MAX_TESTS];
static int test_count;
static int current_failures;

/* Per-kind test families, expanded by expand_families() once main runs
 * (the registry is not safe to read from a constructor). */
static struct {
    const char *prefix;
    void (*fn)(const accel_kind *kind);
} families[MAX_FAMILIES];
static int family_count;
static int dropped; /* registrations beyond the tables' capacity */

static void add_test(test_case t)
{
    if (test_count < MAX_TESTS)
        tests[test_count++] = t;
    else
        dropped++;
}

void test_register(const char *name, void (*fn)(void))
{
    add_test((test_case){name, fn, NULL, NULL});
}

void test_register_per_kind(const char *prefix, void (*fn)(const accel_kind *kind))
{
    if (family_count < MAX_FAMILIES) {
        families[family_count].prefix = prefix;
        families[family_count++].fn = fn;
    } else {
        dropped++;
    }
}

void test_fail(const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stdout, "    %s:%d: ", file, line);
    vfprintf(stdout, fmt, ap);
    fputc('\n', stdout);
    va_end(ap);
    current_failures++;
}

void test_note(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("    note: ", stdout);
    vfprintf(stdout, fmt, ap);
    fputc('\n', stdout);
    va_end(ap);
}

const char *test_shared_scenes(void)
{
    static const char *const candidates[] = {"../shared/scenes", "../../shared/scenes"};
    const char *env = getenv("GRIDBVH_SCENES");
    struct stat st;
    if (env && stat(env, &st) == 0) return env;
    for (size_t i = 0; i < sizeof candidates / sizeof candidates[0]; i++)
        if (stat(candidates[i], &st) == 0 && S_ISDIR(st.st_mode)) return candidates[i];
    return NULL;
}

/* Calls fn(name, len, ctx) for every name of the comma-separated list. */
static int each_listed(const char *list, int (*fn)(const char *, size_t, void *), void *ctx)
{
    for (const char *p = list; *p;) {
        const char *comma = strchr(p, ',');
        size_t len = comma ? (size_t)(comma - p) : strlen(p);
        if (fn(p, len, ctx)) return 1;
        if (!comma) break;
        p = comma + 1;
    }
    return 0;
}

static int same_name(const char *p, size_t len, void *name)
{
    return len == strlen(name) && !strncmp(p, name, len);
}

int test_kind_selected(const char *name)
{
    const char *list = getenv("KINDS");
    if (!list || !*list) return 1;
    return each_listed(list, same_name, (void *)name);
}

/* each_listed callback: reports a name that is no registered kind. */
static int unknown_kind(const char *p, size_t len, void *ctx)
{
    for (size_t k = 0; k < accel_kind_count; k++)
        if (len == strlen(accel_kinds[k]->name) && !strncmp(p, accel_kinds[k]->name, len)) return 0;
    *(const char **)ctx = p;
    return 1;
}

/* Refuses a KINDS that names an unknown kind (an empty name included). */
static int check_kinds(void)
{
    const char *list = getenv("KINDS"), *bad = NULL;
    if (!list || !*list || !each_listed(list, unknown_kind, &bad)) return 1;
    size_t len = strcspn(bad, ",");
    fprintf(stderr, "run_tests: KINDS=%s: unknown kind '%.*s'; registered kinds:", list, (int)len,
            bad);
    for (size_t k = 0; k < accel_kind_count; k++) fprintf(stderr, " %s", accel_kinds[k]->name);
    fputc('\n', stderr);
    return 0;
}

/* One test per family and selected kind, named prefix_kind. */
static void expand_families(void)
{
    for (int f = 0; f < family_count; f++)
        for (size_t k = 0; k < accel_kind_count; k++) {
            const accel_kind *kind = accel_kinds[k];
            if (!test_kind_selected(kind->name)) continue;
            size_t len = strlen(families[f].prefix) + strlen(kind->name) + 2;
            char *name = malloc(len);
            if (!name) {
                dropped++;
                continue;
            }
            snprintf(name, len, "%s_%s", families[f].prefix, kind->name);
            add_test((test_case){name, NULL, families[f].fn, kind});
        }
}

static int by_name(const void *a, const void *b)
{
    return strcmp(((const test_case *)a)->name, ((const test_case *)b)->name);
}

int main(int argc, char **argv)
{
    int list = 0;
    const char *filter = "";
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--list")) {
            list = 1;
        } else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            printf("usage: run_tests [--list] [FILTER]\n"
                   "  runs (or with --list, names) the tests whose name contains FILTER;\n"
                   "  KINDS=a,b in the environment limits the kind suites to those kinds.\n"
                   "exit status: 0 all passed, 1 a check failed, 2 usage error (unknown\n"
                   "option or kind, or no test matching FILTER)\n");
            return 0;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            fprintf(stderr, "run_tests: unknown option '%s' (try --help)\n", argv[i]);
            return 2;
        } else {
            filter = argv[i];
        }
    }
    setvbuf(stdout, NULL, _IOLBF, 0);
    if (!check_kinds()) return 2;
    expand_families();
    if (dropped) {
        fprintf(stderr, "run_tests: %d tests not registered: raise MAX_TESTS or MAX_FAMILIES\n",
                dropped);
        return 2;
    }
    qsort(tests, (size_t)test_count, sizeof tests[0], by_name);
    int matched = 0;
    for (int i = 0; i < test_count; i++) matched += strstr(tests[i].name, filter) != NULL;
    if (!matched) {
        fprintf(stderr, "run_tests: no test name contains '%s' (run_tests --list names them)\n",
                filter);
        return 2;
    }
    if (list) {
        for (int i = 0; i < test_count; i++)
            if (strstr(tests[i].name, filter)) printf("%s\n", tests[i].name);
        return 0;
    }
    int passed = 0, failed = 0;
    for (int i = 0; i < test_count; i++) {
        if (!strstr(tests[i].name, filter)) continue;
        current_failures = 0;
        test_seed(TEST_SEED);
        double t0 = accel_now_ms();
        printf("%s\n", tests[i].name);
        if (tests[i].fn)
            tests[i].fn();
        else
            tests[i].kind_fn(tests[i].kind);
        double ms = accel_now_ms() - t0;
        if (current_failures) {
            printf("  FAIL %s (%d failed checks, %.0f ms)\n", tests[i].name, current_failures, ms);
            failed++;
        } else {
            printf("  ok   %s (%.0f ms)\n", tests[i].name, ms);
            passed++;
        }
    }
    printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}
