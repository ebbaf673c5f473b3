/*
 * main.c - runs the registered tests. Usage: run_tests [FILTER]
 */
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "accel.h"
#include "test.h"

typedef struct {
    const char *name;
    void (*fn)(void);
} test_case;

static test_case tests[512];
static int test_count;
static int current_failures;

void test_register(const char *name, void (*fn)(void))
{
    if (test_count < (int)(sizeof tests / sizeof tests[0])) tests[test_count++] = (test_case){name, fn};
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

int test_kind_selected(const char *name)
{
    const char *list = getenv("KINDS");
    if (!list || !*list) return 1;
    size_t n = strlen(name);
    for (const char *p = list; *p;) {
        const char *comma = strchr(p, ',');
        size_t len = comma ? (size_t)(comma - p) : strlen(p);
        if (len == n && !strncmp(p, name, n)) return 1;
        if (!comma) break;
        p = comma + 1;
    }
    return 0;
}

static int by_name(const void *a, const void *b)
{
    return strcmp(((const test_case *)a)->name, ((const test_case *)b)->name);
}

int main(int argc, char **argv)
{
    const char *filter = argc > 1 ? argv[1] : "";
    setvbuf(stdout, NULL, _IOLBF, 0);
    qsort(tests, (size_t)test_count, sizeof tests[0], by_name);
    int passed = 0, failed = 0;
    for (int i = 0; i < test_count; i++) {
        if (!strstr(tests[i].name, filter)) continue;
        current_failures = 0;
        double t0 = accel_now_ms();
        printf("%s\n", tests[i].name);
        tests[i].fn();
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
