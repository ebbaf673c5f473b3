/*
 * test_layout.c - the layering rule of the source tree, checked on the
 * files themselves (the tests run from the repository root):
 *
 *  - accel/ is layered core < scene < rays < {measure, image} < cli: a file
 *    includes only accel.h, its own layer and the layers below it (measure,
 *    the timed traces, and image, the pictures, sit side by side: neither
 *    includes the other; cli, the tools' option table, is on top of both);
 *  - a backend (every top-level folder the build treats as one, read from
 *    sources.mk) includes only accel.h, accel/core/ headers, its own
 *    folder's headers, and the documented cross-backend APIs,
 *    grid/grid_core.h (the grid walk and cell visit of the grid family:
 *    nested, irregular and instanced grids reuse it),
 *    grid/grid_packet_walk.h (the coherent packet walk its levels reuse),
 *    grid/grid_blocks.h (the cell visit on primitive blocks)
 *    and, for instanced/ only, bvh/bvh.h (bvh_build_boxes builds its BVH
 *    levels over boxes);
 *  - sources.mk's ACCEL_LAYERS names these layers, and accel/ has no other
 *    folder;
 *  - a backend's subfolder (bvh/wide/, built by sources.mk too) is a room
 *    of its own: its files include only accel.h, accel/core/ headers, their
 *    own subfolder and the parent's headers listed in sub_parent_headers
 *    below; the parent's files include of the subfolder only its entry
 *    header, named after it (bvh/wide/wide.h), never its internals;
 *  - no library, backend, tool, experiment, lab or test source file is over
 *    650 lines (split past about 600).
 */
#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "support.h"

static const char *const layers[] = {"core", "scene", "rays", "measure", "image", "cli"};
enum { LAYER_COUNT = 6, MAX_LINES = 650 };
/* The layers each layer may include, comma-separated (itself last). */
static const char *const allowed[LAYER_COUNT] = {
    "core",
    "core,scene",
    "core,scene,rays",
    "core,scene,rays,measure",
    "core,scene,rays,image",
    "core,scene,rays,measure,image,cli",
};

/* Is layer l in the list of layers `own` may include? */
static int layer_allowed(int own, int l)
{
    const char *p = allowed[own];
    size_t n = strlen(layers[l]);
    while (*p) {
        size_t len = strcspn(p, ",");
        if (len == n && !strncmp(p, layers[l], n)) return 1;
        p += len + (p[len] == ',');
    }
    return 0;
}

static int layer_of(const char *name)
{
    for (int i = 0; i < LAYER_COUNT; i++)
        if (!strcmp(layers[i], name)) return i;
    return -1;
}

static int source_file(const char *name)
{
    size_t n = strlen(name);
    return n > 2 && name[n - 2] == '.' && (name[n - 1] == 'c' || name[n - 1] == 'h');
}

/* Calls fn(path, ctx) for every .c/.h file directly in dir. */
static int each_source(const char *dir, void (*fn)(const char *path, const char *dir, void *ctx),
                       void *ctx)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (!source_file(e->d_name)) continue;
        char path[512];
        if (snprintf(path, sizeof path, "%s/%s", dir, e->d_name) >= (int)sizeof path) continue;
        fn(path, dir, ctx);
        n++;
    }
    closedir(d);
    return n;
}

/* Calls fn(file, line, target) for every #include "target" of a file. */
static void each_include(const char *path, void (*fn)(const char *, int, const char *, void *),
                         void *ctx)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        test_fail(__FILE__, __LINE__, "cannot read %s", path);
        return;
    }
    char line[1024];
    int no = 0;
    while (fgets(line, sizeof line, f)) {
        no++;
        const char *p = line;
        while (*p == ' ' || *p == '\t') p++;
        if (strncmp(p, "#include", 8)) continue;
        const char *q = strchr(p, '"');
        if (!q) continue; /* <system> header */
        const char *end = strchr(q + 1, '"');
        if (!end) continue;
        char target[256];
        size_t len = (size_t)(end - q - 1) < sizeof target - 1 ? (size_t)(end - q - 1) : sizeof target - 1;
        memcpy(target, q + 1, len);
        target[len] = 0;
        fn(path, no, target, ctx);
    }
    fclose(f);
}

/* The layer a quoted include names ("core/prim.h" -> core), -1 for accel.h,
 * -2 for anything else. */
static int include_layer(const char *target)
{
    if (!strcmp(target, "accel.h")) return -1;
    const char *slash = strchr(target, '/');
    if (!slash) return -2;
    char first[64];
    size_t n = (size_t)(slash - target) < sizeof first - 1 ? (size_t)(slash - target) : sizeof first - 1;
    memcpy(first, target, n);
    first[n] = 0;
    int l = layer_of(first);
    return l >= 0 ? l : -2;
}

static void check_accel_include(const char *path, int line, const char *target, void *ctx)
{
    int own = *(const int *)ctx;
    int l = include_layer(target);
    CHECKF(l == -1 || (l >= 0 && layer_allowed(own, l)),
           "%s:%d: includes \"%s\": accel/%s may include only accel.h and accel/{%s} headers",
           path, line, target, layers[own], allowed[own]);
}

static void check_accel_file(const char *path, const char *dir, void *ctx)
{
    (void)dir;
    each_include(path, check_accel_include, ctx);
}

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

typedef struct {
    const char *folder; /* "bvh" or "bvh/wide" */
    const char *parent; /* "bvh" for a subfolder, else NULL */
} backend_ctx;

/* The parent headers a subfolder's files may include: what the wide tree
 * documents needing (wide/node.h: the binary node and the kernels' shared
 * pieces; collapse.c and refit.c: the builders' primitive boxes and
 * allocation helpers). */
static const char *const sub_parent_headers[] = {"bvh/bvh_node.h", "bvh/split_common.h", NULL};

/* Is target "sub/sub.h" or "<folder>/sub/sub.h" for a subfolder sub of
 * folder: the one header a parent's file may include from a subfolder? */
static int subfolder_entry(const char *folder, const char *target)
{
    size_t fl = strlen(folder);
    if (!strncmp(target, folder, fl) && target[fl] == '/') target += fl + 1;
    const char *slash = strchr(target, '/');
    if (!slash || strchr(slash + 1, '/')) return 0;
    size_t sl = (size_t)(slash - target);
    char path[512];
    snprintf(path, sizeof path, "%s/%s", folder, target);
    return strlen(slash + 1) == sl + 2 && !strncmp(slash + 1, target, sl) &&
           !strcmp(slash + 1 + sl, ".h") && file_exists(path);
}

static void check_backend_include(const char *path, int line, const char *target, void *ctx)
{
    const backend_ctx *b = ctx;
    int l = include_layer(target);
    if (l == -1 || l == 0) return;
    char own[512];
    size_t fl = strlen(b->folder);
    if (!strchr(target, '/')) {
        snprintf(own, sizeof own, "%s/%s", b->folder, target);
        if (file_exists(own)) return;
    } else if (!strncmp(target, b->folder, fl) && target[fl] == '/' && !strchr(target + fl + 1, '/')) {
        return;
    } else if (!b->parent && subfolder_entry(b->folder, target)) {
        return;
    } else if (b->parent) {
        for (int i = 0; sub_parent_headers[i]; i++)
            if (!strcmp(target, sub_parent_headers[i])) return;
    }
    if (!strcmp(target, "grid/grid_core.h") || !strcmp(target, "grid/grid_packet_walk.h") ||
        !strcmp(target, "grid/grid_blocks.h"))
        return;
    /* instanced/ walks its BVH levels on the wide BVH's nodes, collapse
     * and node tests (its README): the layouts and the two templates. */
    if (!strcmp(b->folder, "instanced") &&
        (!strcmp(target, "bvh/bvh.h") || !strcmp(target, "bvh/wide/node.h") ||
         !strcmp(target, "bvh/wide/kernel.h") || !strcmp(target, "bvh/wide/packet.h")))
        return;
    test_fail(__FILE__, __LINE__,
              "%s:%d: includes \"%s\": a backend may include only accel.h, core/ headers, its "
              "own folder, a subfolder's entry header (sub/sub.h), grid/grid_core.h, grid/grid_blocks.h, "
              "grid/grid_packet_walk.h (instanced/ also bvh/bvh.h and bvh/wide/'s node.h, kernel.h, packet.h); a subfolder only its own files and the parent headers "
              "of sub_parent_headers",
              path, line, target);
}

static void check_backend_file(const char *path, const char *dir, void *ctx)
{
    backend_ctx b = {dir, ctx};
    each_include(path, check_backend_include, &b);
}

/* sources.mk builds accel/'s layers from its ACCEL_LAYERS line: the same
 * layers, in the same order, and no folder of accel/ outside them. */
static void check_layer_list(void)
{
    char *mk = test_read_file("sources.mk", NULL);
    const char *line = mk ? strstr(mk, "\nACCEL_LAYERS := ") : NULL;
    char want[128] = "";
    for (int l = 0; l < LAYER_COUNT; l++)
        snprintf(want + strlen(want), sizeof want - strlen(want), "%s%s", l ? " " : "", layers[l]);
    CHECKF(line && !strncmp(line + 17, want, strlen(want)) && line[17 + strlen(want)] == '\n',
           "sources.mk: ACCEL_LAYERS is not \"%s\"", want);
    free(mk);
    DIR *d = opendir("accel");
    CHECKF(d != NULL, "cannot read accel/");
    struct dirent *e;
    while (d && (e = readdir(d))) {
        char path[512];
        struct stat st;
        if (e->d_name[0] == '.') continue;
        snprintf(path, sizeof path, "accel/%s", e->d_name);
        if (stat(path, &st) || !S_ISDIR(st.st_mode)) continue;
        CHECKF(layer_of(e->d_name) >= 0, "%s: a folder of accel/ that is no layer", path);
    }
    if (d) closedir(d);
}

TEST(layout_layers_and_backends)
{
    check_layer_list();
    for (int l = 0; l < LAYER_COUNT; l++) {
        char dir[64];
        snprintf(dir, sizeof dir, "accel/%s", layers[l]);
        CHECKF(each_source(dir, check_accel_file, &l) > 0, "%s: no sources", dir);
    }
    char backends[32][256];
    int count = test_backend_folders(backends, 32);
    int subs_seen = 0;
    for (int i = 0; i < count; i++) {
        each_source(backends[i], check_backend_file, NULL);
        char subs[8][256];
        int n = test_backend_subfolders(backends[i], subs, 8);
        for (int k = 0; k < n; k++) subs_seen += each_source(subs[k], check_backend_file, backends[i]) > 0;
    }
    CHECKF(subs_seen >= 1, "no backend subfolder with sources (bvh/wide expected)");
    CHECKF(count >= 3, "only %d backends found (grid, nested_grid, bvh expected)", count);
}

static void check_length(const char *path, const char *dir, void *ctx)
{
    (void)dir;
    (void)ctx;
    FILE *f = fopen(path, "r");
    if (!f) return;
    int lines = 0, ch;
    while ((ch = fgetc(f)) != EOF) lines += ch == '\n';
    fclose(f);
    CHECKF(lines <= MAX_LINES, "%s: %d lines (split files past about 600 lines)", path, lines);
}

TEST(layout_file_length)
{
    static const char *const dirs[] = {"accel",       "accel/core",  "accel/scene", "accel/rays",
                                       "accel/measure", "accel/image", "accel/cli", "tools",
                                       "experiments", "tests", "tests/fuzz", "lab"};
    int files = 0;
    for (size_t i = 0; i < sizeof dirs / sizeof dirs[0]; i++)
        files += each_source(dirs[i], check_length, NULL);
    char backends[32][256];
    int count = test_backend_folders(backends, 32);
    for (int i = 0; i < count; i++) {
        files += each_source(backends[i], check_length, NULL);
        char subs[8][256];
        int n = test_backend_subfolders(backends[i], subs, 8);
        for (int k = 0; k < n; k++) files += each_source(subs[k], check_length, NULL);
    }
    CHECKF(files > 50 && count >= 3, "only %d source files in %d backends measured", files, count);
}
