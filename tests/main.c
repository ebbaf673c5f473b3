/*
 * main.c - runs the registered tests.
 *
 * Usage: run_tests [--list] [-j N] [SELECTION]
 *   SELECTION  what to run (all without one): a comma-separated list whose
 *            items are each a family (the first word of a test file's name
 *            after "test_": `grid` is test_grid*.c, tests named grid_*), a
 *            test's exact name, or a pattern with * or ? (fnmatch: '*word*'
 *            is every test whose name contains word). The first line of the
 *            output says what was selected;
 *   --list   print the names (those selected) and run nothing;
 *   -j N     run them in N processes (default: one per online CPU, at most
 *            8). A unit of work is one family of test files (test_report*.c
 *            is one: its tests share build/quick-report) or one per-kind
 *            test; each unit runs in a forked child whose output is printed
 *            whole when it ends, so a crash fails its unit, not the run.
 * The environment variable KINDS (comma-separated kind names) limits the
 * suites that iterate over kinds, and the per-kind tests, to those kinds.
 * An item selecting no test and a KINDS naming an unknown kind are errors
 * (exit status 2) before anything runs; failed checks give exit status 1.
 * The last line is "N passed, N failed, N skipped": a test that calls
 * test_skip() (its subject absent, e.g. ../shared/scenes) counts as skipped
 * and its line says why, unless a check of it failed first.
 */
#include <fcntl.h>
#include <fnmatch.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "support.h"

typedef struct {
    const char *name;
    const char *file; /* source file (for per-kind tests, the registering one) */
    void (*fn)(void);
    void (*kind_fn)(const accel_kind *kind); /* per-kind tests: fn is NULL */
    const accel_kind *kind;
} test_case;

enum { MAX_TESTS = 512, MAX_FAMILIES = 16 };

static test_case tests[MAX_TESTS];
static int test_count;
static int current_failures;
static char current_skip[256]; /* why the running test skipped ("" if it did not) */

/* Per-kind test families, expanded by expand_families() once main runs
 * (the registry is not safe to read from a constructor). */
static struct {
    const char *prefix;
    const char *file;
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

void test_register(const char *name, void (*fn)(void), const char *file)
{
    add_test((test_case){name, file, fn, NULL, NULL});
}

void test_register_per_kind(const char *prefix, void (*fn)(const accel_kind *kind),
                            const char *file)
{
    if (family_count < MAX_FAMILIES) {
        families[family_count].prefix = prefix;
        families[family_count].file = file;
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

void test_skip(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(current_skip, sizeof current_skip, fmt, ap);
    va_end(ap);
    if (!current_skip[0]) snprintf(current_skip, sizeof current_skip, "no reason given");
    printf("    skip: %s\n", current_skip);
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
            add_test((test_case){name, families[f].file, NULL, families[f].fn, kind});
        }
}

static int by_name(const void *a, const void *b)
{
    return strcmp(((const test_case *)a)->name, ((const test_case *)b)->name);
}

/* Counts of a run: passed, failed, skipped. */
enum { PASSED, FAILED, SKIPPED, COUNTS };

/* Runs test i in this process; counts it in counts[PASSED], [FAILED] or [SKIPPED]. */
static void run_one(int i, int *counts)
{
    current_failures = 0;
    current_skip[0] = 0;
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
        counts[FAILED]++;
    } else if (current_skip[0]) {
        printf("  skip %s (%s)\n", tests[i].name, current_skip);
        counts[SKIPPED]++;
    } else {
        printf("  ok   %s (%.0f ms)\n", tests[i].name, ms);
        counts[PASSED]++;
    }
}

/* The family of a test file: its name's first word after "test_", up to
 * the next '_' or '.' (test_report_checks.c and test_report.c are both
 * "report"); *len gets its length. Every test's name starts with its
 * file's family and '_' (runner_names_start_with_their_family). */
static const char *file_family(const char *file, size_t *len)
{
    const char *base = strrchr(file, '/');
    base = base ? base + 1 : file;
    if (!strncmp(base, "test_", 5)) base += 5;
    *len = strcspn(base, "_.");
    return base;
}

int test_each(void (*fn)(const char *name, const char *family, void *ctx), void *ctx)
{
    for (int i = 0; i < test_count; i++) {
        size_t len;
        const char *f = file_family(tests[i].file, &len);
        char family[64];
        snprintf(family, sizeof family, "%.*s", (int)len, f);
        fn(tests[i].name, family, ctx);
    }
    return test_count;
}

/* Whether test i belongs to family (len characters of it). */
static int in_family(int i, const char *family, size_t len)
{
    size_t n;
    const char *f = file_family(tests[i].file, &n);
    return n == len && !strncmp(f, family, len);
}

/* The unit test i belongs to: a per-kind test is its own; a file's tests
 * belong to its family (they may share temporary paths). */
static void unit_key(int i, char *key, size_t size)
{
    if (tests[i].kind) {
        snprintf(key, size, "%s", tests[i].name);
        return;
    }
    size_t n;
    const char *f = file_family(tests[i].file, &n);
    snprintf(key, size, "file %.*s", (int)n, f);
}

typedef struct {
    int first, count; /* its tests: order[first .. first+count-1] */
    pid_t pid;
    int result_fd;    /* the child's counts arrive here */
    char out[64];     /* the child's output file */
} unit;

/* Copies a finished unit's output file to stdout and removes it. */
static void print_output(const char *path)
{
    FILE *f = fopen(path, "r");
    if (f) {
        char buf[8192];
        size_t n;
        while ((n = fread(buf, 1, sizeof buf, f)) > 0) fwrite(buf, 1, n, stdout);
        fclose(f);
    }
    remove(path);
    fflush(stdout);
}

/* The parent's blocks of run_parallel, freed by each child before its
 * exit: LeakSanitizer (make sanitize) checks a child at exit and found the
 * unit table, no longer referenced there, leaked. */
static void *parallel_blocks[3];

static void free_parallel_blocks(void)
{
    for (int k = 0; k < 3; k++) free(parallel_blocks[k]), parallel_blocks[k] = NULL;
}

/* Starts unit u in a forked child writing its output to u->out. */
static int start_unit(unit *u, const int *order)
{
    int fds[2];
    if (pipe(fds) != 0) return -1;
    fflush(stdout);
    pid_t pid = fork();
    if (pid < 0) {
        close(fds[0]);
        close(fds[1]);
        return -1;
    }
    if (pid == 0) {
        close(fds[0]);
        int fd = open(u->out, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd < 0 || dup2(fd, STDOUT_FILENO) < 0) _exit(3);
        close(fd);
        int counts[COUNTS] = {0};
        for (int k = 0; k < u->count; k++) run_one(order[u->first + k], counts);
        fflush(stdout);
        free_parallel_blocks(); /* u and order point into them */
        /* exit, not _exit: a sanitizer build checks for leaks at exit. */
        exit(write(fds[1], counts, sizeof counts) == (ssize_t)sizeof counts ? 0 : 3);
    }
    close(fds[1]);
    u->pid = pid;
    u->result_fd = fds[0];
    return 0;
}

/* Runs the selected tests (order[0..n-1], by name) in `jobs` processes,
 * unit by unit in the order of their first test; returns the counts. */
static void run_parallel(const int *order, int n, int jobs, int *totals)
{
    unit *units = calloc((size_t)n, sizeof *units);
    int *sorted = malloc((size_t)n * sizeof *sorted);
    char (*keys)[128] = malloc((size_t)n * sizeof *keys);
    if (!units || !sorted || !keys) {
        fprintf(stderr, "run_tests: out of memory; running the tests in one process\n");
        for (int k = 0; k < n; k++) run_one(order[k], totals);
        free(units), free(sorted), free(keys);
        return;
    }
    parallel_blocks[0] = units, parallel_blocks[1] = sorted, parallel_blocks[2] = keys;
    /* Units: tests grouped by key, each unit's tests in name order. */
    int unit_count = 0, placed = 0;
    for (int k = 0; k < n; k++) unit_key(order[k], keys[k], sizeof keys[k]);
    for (int k = 0; k < n; k++) {
        int seen = 0;
        for (int j = 0; j < k && !seen; j++) seen = !strcmp(keys[j], keys[k]);
        if (seen) continue;
        unit *u = &units[unit_count++];
        u->first = placed;
        for (int j = k; j < n; j++)
            if (!strcmp(keys[j], keys[k])) sorted[placed++] = order[j];
        u->count = placed - u->first;
        snprintf(u->out, sizeof u->out, "build/run_tests.%ld.%d.out", (long)getpid(), unit_count);
    }
    mkdir("build", 0777);
    int next = 0, running = 0;
    while (next < unit_count || running > 0) {
        while (running < jobs && next < unit_count) {
            if (start_unit(&units[next], sorted) != 0) {
                if (running > 0) break; /* wait for a child to end, then try again */
                fprintf(stderr, "run_tests: cannot fork: running unit %d here\n", next + 1);
                for (int k = 0; k < units[next].count; k++)
                    run_one(sorted[units[next].first + k], totals);
            } else {
                running++;
            }
            next++;
        }
        if (running == 0) continue;
        int status;
        pid_t pid = wait(&status);
        if (pid < 0) break;
        unit *u = NULL;
        for (int k = 0; k < next && !u; k++)
            if (units[k].pid == pid) u = &units[k];
        if (!u) continue;
        running--;
        u->pid = 0;
        int counts[COUNTS];
        ssize_t got = read(u->result_fd, counts, sizeof counts);
        close(u->result_fd);
        print_output(u->out);
        if (got == (ssize_t)sizeof counts && WIFEXITED(status) && WEXITSTATUS(status) == 0) {
            for (int c = 0; c < COUNTS; c++) totals[c] += counts[c];
        } else {
            /* Its last test, the one printed without an "ok" line, crashed. */
            printf("  FAIL the process running %s..%s died (%s %d): the whole unit counts as "
                   "failed\n",
                   tests[sorted[u->first]].name, tests[sorted[u->first + u->count - 1]].name,
                   WIFSIGNALED(status) ? "signal" : "exit status",
                   WIFSIGNALED(status) ? WTERMSIG(status) : WEXITSTATUS(status));
            totals[FAILED] += u->count;
        }
    }
    free_parallel_blocks(); /* units, sorted, keys */
}

static int default_jobs(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > 8 ? 8 : (int)n;
}

/* Whether test i is selected by item (len characters): its exact name, its
 * family, or a pattern with * or ? matching its name. */
static int selects(int i, const char *item, size_t len)
{
    char pat[256];
    snprintf(pat, sizeof pat, "%.*s", (int)len, item);
    if (strpbrk(pat, "*?[")) return fnmatch(pat, tests[i].name, 0) == 0;
    return !strcmp(tests[i].name, pat) || in_family(i, item, len);
}

/* Fills order[] with the tests the comma-separated selection picks (all
 * when it is empty), in name order; prints what it picked to `say`.
 * Returns their count, or -1 when an item picks no test. */
static int select_tests(const char *selection, int *order, FILE *say)
{
    int matched = 0;
    if (!*selection) {
        for (int i = 0; i < test_count; i++) order[matched++] = i;
        if (say) fprintf(say, "selected: all %d tests\n", matched);
        return matched;
    }
    static char taken[MAX_TESTS];
    memset(taken, 0, sizeof taken);
    for (const char *p = selection; *p;) {
        size_t len = strcspn(p, ",");
        int here = 0, exact = -1;
        for (int i = 0; i < test_count; i++)
            if (selects(i, p, len)) {
                here++;
                taken[i] = 1;
                if (strlen(tests[i].name) == len && !strncmp(tests[i].name, p, len)) exact = i;
            }
        if (!here) {
            fprintf(stderr,
                    "run_tests: no family or test is named '%.*s' (T='*%.*s*' selects the names "
                    "containing it; run_tests --list names them)\n",
                    (int)len, p, (int)len, p);
            return -1;
        }
        char pat[256];
        snprintf(pat, sizeof pat, "%.*s", (int)len, p);
        if (!say)
            ;
        else if (strpbrk(pat, "*?["))
            fprintf(say, "selected: pattern '%s': %d tests\n", pat, here);
        else if (exact >= 0 && here == 1)
            fprintf(say, "selected: test %s\n", pat);
        else
            fprintf(say, "selected: family %s: %d tests (test_%s*.c)\n", pat, here, pat);
        p += len;
        if (*p == ',') p++;
    }
    for (int i = 0; i < test_count; i++)
        if (taken[i]) order[matched++] = i;
    return matched;
}

int main(int argc, char **argv)
{
    int list = 0, jobs = default_jobs();
    const char *selection = "";
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--list")) {
            list = 1;
        } else if (!strncmp(argv[i], "-j", 2)) {
            const char *v = argv[i][2] ? argv[i] + 2 : i + 1 < argc ? argv[++i] : "";
            char *end;
            long j = strtol(v, &end, 10);
            if (!*v || *end || j < 1 || j > 64) {
                fprintf(stderr, "run_tests: -j wants a process count from 1 to 64, not '%s'\n", v);
                return 2;
            }
            jobs = (int)j;
        } else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            printf("usage: run_tests [--list] [-j N] [SELECTION]\n"
                   "  runs (or with --list, names) the selected tests: SELECTION is a\n"
                   "  comma-separated list of families (grid: the tests of test_grid*.c,\n"
                   "  named grid_*), exact test names, or patterns with * or ? ('*word*':\n"
                   "  the names containing word); all tests without one;\n"
                   "  -j N runs them in N processes (default: one per CPU, at most 8);\n"
                   "  KINDS=a,b in the environment limits the kind suites to those kinds.\n"
                   "exit status: 0 all passed, 1 a check failed, 2 usage error (unknown\n"
                   "option or kind, or an item of SELECTION selecting no test)\n");
            return 0;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            fprintf(stderr, "run_tests: unknown option '%s' (try --help)\n", argv[i]);
            return 2;
        } else {
            selection = argv[i];
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
    static int order[MAX_TESTS];
    /* --list prints the names only (scripts read them); a run says first what it runs. */
    int matched = select_tests(selection, order, list ? NULL : stdout);
    if (matched < 0) return 2;
    if (list) {
        for (int k = 0; k < matched; k++) printf("%s\n", tests[order[k]].name);
        return 0;
    }
    int counts[COUNTS] = {0};
    if (jobs > 1)
        run_parallel(order, matched, jobs, counts);
    else
        for (int k = 0; k < matched; k++) run_one(order[k], counts);
    printf("%d passed, %d failed, %d skipped\n", counts[PASSED], counts[FAILED], counts[SKIPPED]);
    return counts[FAILED] ? 1 : 0;
}
