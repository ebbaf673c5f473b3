/*
 * test_headers.c - every header of accel/ and of the backends compiles on
 * its own, as C11 and (when a C++ compiler is present) as C++17, with
 * warnings as errors; and a C++ program including all of them links
 * against this build's library and traces a ray, which it can only do when
 * the headers declare the library's functions extern "C".
 *
 * The Makefile tells this file which compilers, library and link flags the
 * build uses (TEST_CC, TEST_CXX, TEST_LIB, TEST_LDLIBS); the tests run from
 * the repository root. C++17 is the standard asked for: the headers use
 * hexadecimal float literals, standard C99 and C++17.
 */
#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "support.h"

#ifndef TEST_CC
#define TEST_CC "cc"
#endif
#ifndef TEST_CXX
#define TEST_CXX "c++"
#endif
#ifndef TEST_LIB
#define TEST_LIB "build/libgridbvh.a"
#endif
#ifndef TEST_LDLIBS
#define TEST_LDLIBS "-lm -pthread"
#endif

enum { MAX_HEADERS = 128 };

/* A header whose text holds this marker is a kernel body that one .c file
 * includes (SIMD lanes, traversal templates): it must compile on its own
 * as C, but it is not part of the interface a C++ program includes. */
#define C_ONLY_MARKER "kernel body (C only)"

typedef struct {
    char path[MAX_HEADERS][300];
    int c_only[MAX_HEADERS];
    int count;
} header_list;

static void add_headers(header_list *h, const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    while ((e = readdir(d)) && h->count < MAX_HEADERS) {
        size_t n = strlen(e->d_name);
        if (n < 3 || strcmp(e->d_name + n - 2, ".h")) continue;
        snprintf(h->path[h->count++], sizeof h->path[0], "%s/%s", dir, e->d_name);
    }
    closedir(d);
}

static int by_path(const void *a, const void *b)
{
    return strcmp((const char *)a, (const char *)b);
}

/* accel/, its layers and every backend folder and subfolder (sources.mk). */
static int collect_headers(header_list *h)
{
    static const char *const dirs[] = {"accel",         "accel/core",  "accel/scene", "accel/rays",
                                       "accel/measure", "accel/image", "accel/cli"};
    h->count = 0;
    for (size_t i = 0; i < sizeof dirs / sizeof dirs[0]; i++) add_headers(h, dirs[i]);
    char backends[32][256];
    int count = test_backend_folders(backends, 32);
    for (int i = 0; i < count; i++) {
        add_headers(h, backends[i]);
        char subs[8][256];
        int n = test_backend_subfolders(backends[i], subs, 8);
        for (int k = 0; k < n; k++) add_headers(h, subs[k]);
    }
    qsort(h->path, (size_t)h->count, sizeof h->path[0], by_path);
    return count >= 3;
}

/* Is the compiler `cc` (a command name) on PATH? */
static int have_compiler(const char *cc)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "command -v '%s' > /dev/null 2>&1", cc);
    return system(cmd) == 0;
}

/* Runs cmd; on failure records a check failure with the first lines of
 * its output (kept in log). Returns 1 on success. */
static int run(const char *what, const char *cmd, const char *log)
{
    char full[4096];
    snprintf(full, sizeof full, "%s > '%s' 2>&1", cmd, log);
    if (system(full) == 0) return 1;
    char *out = test_read_file(log, NULL);
    if (out && strlen(out) > 1500) strcpy(out + 1500, "...");
    test_fail(__FILE__, __LINE__, "%s failed: %s\n%s", what, cmd, out ? out : "(no output)");
    free(out);
    return 0;
}

static int write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    int ok = fputs(text, f) >= 0;
    return fclose(f) == 0 && ok;
}

TEST(headers_compile_alone_as_c_and_cxx)
{
    header_list *h = malloc(sizeof *h);
    char dir[] = "/tmp/gridbvh_headers_XXXXXX";
    if (!h || !mkdtemp(dir)) {
        test_fail(__FILE__, __LINE__, "no memory or no temporary folder");
        free(h);
        return;
    }
    CHECKF(collect_headers(h) && h->count >= 15, "only %d headers found", h->count);
    int cxx = have_compiler(TEST_CXX);
    if (!cxx) test_note("skipped the C++ checks: no C++ compiler '%s' on PATH", TEST_CXX);
    char src[600], log[600], cmd[2048];
    snprintf(src, sizeof src, "%s/one.c", dir);
    snprintf(log, sizeof log, "%s/log", dir);
    int compiled = 0;
    for (int i = 0; i < h->count; i++) {
        /* The guard itself, so that a header whose functions the program
         * below does not call cannot lose it unseen. */
        char *body = test_read_file(h->path[i], NULL);
        h->c_only[i] = body && strstr(body, C_ONLY_MARKER) != NULL;
        CHECKF(h->c_only[i] || (body && strstr(body, "#ifdef __cplusplus\nextern \"C\" {\n#endif")),
               "%s: no extern \"C\" guard (#ifdef __cplusplus / extern \"C\" { / #endif)",
               h->path[i]);
        free(body);
        char text[400];
        snprintf(text, sizeof text, "#include \"%s\"\n", h->path[i]);
        if (!write_text(src, text)) break;
        snprintf(cmd, sizeof cmd,
                 "%s -fsyntax-only -std=c11 -D_GNU_SOURCE -Wall -Wextra -pedantic -Werror -Iaccel "
                 "-I. -x c '%s'",
                 TEST_CC, src);
        compiled += run(h->path[i], cmd, log);
        if (!cxx || h->c_only[i]) continue;
        snprintf(cmd, sizeof cmd,
                 "%s -fsyntax-only -std=c++17 -D_GNU_SOURCE -Wall -Wextra -pedantic -Werror "
                 "-Iaccel -I. -x c++ '%s'",
                 TEST_CXX, src);
        run(h->path[i], cmd, log);
    }
    CHECKF(compiled == h->count, "%d of %d headers compile as C", compiled, h->count);
    if (cxx) {
        /* Every header in one C++ program that builds a grid and traces a
         * ray straight down onto a cube: links only with extern "C". */
        char *prog = malloc((size_t)h->count * 320 + 1024);
        if (prog) {
            size_t n = 0;
            for (int i = 0; i < h->count; i++)
                if (!h->c_only[i]) n += (size_t)sprintf(prog + n, "#include \"%s\"\n", h->path[i]);
            sprintf(prog + n,
                    "#include <cstdio>\n"
                    "int main()\n{\n"
                    "    accel_scene s;\n    accel_error err = {};\n"
                    "    if (scene_create(\"cube:n=2\", &s, &err)) return 1;\n"
                    "    const accel_kind *kind;\n    void *a;\n    accel_build_stats st;\n"
                    "    if (accel_build_spec(\"grid\", &s, 1, &kind, &a, &st, &err)) return 2;\n"
                    "    accel_ray r = {0.5f, 0.5f, -5.0f, 0.0f, 0.0f, 0.0f, 1.0f, INFINITY};\n"
                    "    accel_hit hit;\n"
                    "    accel_trace(kind, a, &r, &hit, 1, 1, nullptr);\n"
                    "    std::printf(\"%%s %%g\\n\", hit.prim == ACCEL_MISS ? \"miss\" : \"hit\", "
                    "(double)hit.t);\n"
                    "    kind->destroy(a);\n    scene_free(&s);\n    return 0;\n}\n");
            char cpp[600], exe[600];
            snprintf(cpp, sizeof cpp, "%s/smoke.cpp", dir);
            snprintf(exe, sizeof exe, "%s/smoke", dir);
            if (write_text(cpp, prog)) {
                snprintf(cmd, sizeof cmd,
                         "%s -std=c++17 -D_GNU_SOURCE -Wall -Wextra -Werror -Iaccel -I. '%s' %s %s "
                         "-o '%s'",
                         TEST_CXX, cpp, TEST_LIB, TEST_LDLIBS, exe);
                if (run("a C++ program linking the library", cmd, log)) {
                    snprintf(cmd, sizeof cmd, "'%s'", exe);
                    if (run("the C++ program", cmd, log)) {
                        char *out = test_read_file(log, NULL);
                        /* The cube of cube:n=2 spans [-1,1]^3: hit at z = -1. */
                        CHECKF(out && !strcmp(out, "hit 4\n"), "the C++ program printed '%s'",
                               out ? out : "");
                        free(out);
                    }
                }
                remove(exe);
            }
            remove(cpp);
            free(prog);
        }
    }
    remove(src);
    remove(log);
    rmdir(dir);
    free(h);
}
