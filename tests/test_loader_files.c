/*
 * test_loader_files.c - the loaders on files: the shared scenes checked
 * against an independent strtof-based reader, and the fuzz regression
 * inputs and seed corpora (each loads, or fails with a message naming the
 * file).
 */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/load_common.h"
#include "test_loader.h"

/* ---- the shared scenes against an independent reader --------------------- */

/* A deliberately different OFF reader: stdio, strtol and strtof. Returns the
 * triangles of a triangle-only file (NULL when a face is not a triangle). */
static float *reference_off(const char *path, size_t *tri_count, long *nv_out, long *nf_out)
{
    char *text = test_read_file(path, NULL);
    float *v = NULL, *tris = NULL;
    if (!text) return NULL;
    char *p = strstr(text, "OFF");
    if (!p) goto done;
    p += 3;
    long nv = strtol(p, &p, 10), nf = strtol(p, &p, 10);
    strtol(p, &p, 10);
    *nv_out = nv;
    *nf_out = nf;
    v = malloc((size_t)nv * 3 * sizeof *v);
    tris = malloc((size_t)nf * 9 * sizeof *tris);
    if (!v || !tris) goto fail;
    for (long i = 0; i < 3 * nv; i++) v[i] = strtof(p, &p);
    for (long i = 0; i < nf; i++) {
        if (strtol(p, &p, 10) != 3) goto fail;
        for (int c = 0; c < 3; c++) {
            long idx = strtol(p, &p, 10);
            if (idx < 0 || idx >= nv) goto fail;
            memcpy(tris + 9 * i + 3 * c, v + 3 * idx, 3 * sizeof *v);
        }
    }
    *tri_count = (size_t)nf;
    goto done;
fail:
    free(tris);
    tris = NULL;
done:
    free(v);
    free(text);
    return tris;
}

TEST(loader_shared_scenes)
{
    char paths[32][512];
    int count = test_shared_files(".off .obj .ply", paths, 32);
    for (int i = 0; i < count; i++) {
        const char *path = paths[i], *name = strrchr(path, '/') + 1, *dot = strrchr(name, '.');
        accel_scene s;
        accel_error err = {0};
        double t0 = accel_now_ms();
        int rc = scene_load_file(path, &s, &err);
        double ms = accel_now_ms() - t0;
        CHECKF(rc == 0, "%s: %s", path, err.msg);
        if (rc) continue;
        test_note("%s: %u triangles, %u degenerate, loaded in %.1f ms", name, s.tri_count,
                  s.degenerate_count, ms);
        if (!strcmp(name, "bunny.off")) CHECK(s.tri_count == 75408);
        if (!strcmp(dot, ".off")) {
            size_t n = 0;
            long nv = 0, nf = 0;
            float *ref = reference_off(path, &n, &nv, &nf);
            if (!ref) {
                test_note("%s: not a triangle-only OFF, header counts not compared", name);
            } else {
                /* every face a triangle: the header's face count is the triangle count */
                CHECKF(s.tri_count == (uint32_t)nf, "%s: %u triangles, header says %ld faces", name,
                       s.tri_count, nf);
                CHECKF(n == s.tri_count && memcmp(ref, s.tris, n * 9 * sizeof(float)) == 0,
                       "%s: triangles differ from the strtof reader", name);
                free(ref);
            }
        }
        scene_free(&s);
    }
    CHECK(count != 0);
}

/* ---- fuzz regressions ---------------------------------------------------- */

/* Runs every file of dir named obj-*, ply-* or off-* (or, with `format`, every
 * file) through its parser: it must load or fail with a message naming the
 * file; files whose name ends in "-ok" (and seed corpus files) must load. */
static int run_inputs(const char *dir, const char *format, int must_load)
{
    DIR *d = opendir(dir);
    if (!d) return -1;
    struct dirent *ent;
    int count = 0;
    while ((ent = readdir(d))) {
        const char *fmt = format;
        if (!fmt) {
            if (strlen(ent->d_name) < 4 || ent->d_name[3] != '-') continue;
            fmt = ent->d_name;
        }
        parse_fn parse = !strncmp(fmt, "obj", 3)   ? scene_parse_obj
                         : !strncmp(fmt, "ply", 3) ? scene_parse_ply
                         : !strncmp(fmt, "off", 3) ? scene_parse_off
                                                   : NULL;
        if (!parse || ent->d_name[0] == '.') continue;
        size_t len = strlen(ent->d_name);
        int load = must_load || (len > 3 && !strcmp(ent->d_name + len - 3, "-ok"));
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, ent->d_name);
        char *data;
        size_t size;
        accel_error err = {0};
        if (load_read_file(path, &data, &size, &err)) {
            CHECKF(0, "%s", err.msg);
            continue;
        }
        char *copy = malloc(size ? size : 1); /* exact size: reads past it are caught */
        if (!copy) {
            free(data);
            continue;
        }
        memcpy(copy, data, size);
        scene_builder b = {0};
        int rc = parse(ent->d_name, copy, size, &b, &err);
        CHECKF(rc == 0 || (!load && strstr(err.msg, ent->d_name) == err.msg), "%s: message '%s'",
               path, err.msg);
        CHECKF(rc == 0 || b.tri_count == 0, "%s: a failed load left triangles", path);
        scene_builder_free(&b);
        free(copy);
        free(data);
        count++;
    }
    closedir(d);
    return count;
}

/* tests/data/fuzz_regress/ keeps every input that made a fuzz target fail
 * (none so far) and, from the fuzzers' corpora, the smallest input reaching
 * each distinct loader outcome; tests/fuzz/corpus/ holds the seeds, all valid.
 * Under `make sanitize` this also checks them for memory errors and leaks. */
TEST(loader_fuzz_regressions)
{
    int n = run_inputs("tests/data/fuzz_regress", NULL, 0);
    if (n < 0) {
        test_skip("tests/data/fuzz_regress absent (run from the repository root)");
        return;
    }
    CHECK(n > 0);
    int seeds = 0;
    static const char *const formats[3] = {"obj", "ply", "off"};
    for (int i = 0; i < 3; i++) {
        char dir[64];
        snprintf(dir, sizeof dir, "tests/fuzz/corpus/%s", formats[i]);
        int k = run_inputs(dir, formats[i], 1);
        CHECKF(k > 0, "%s: no seed inputs", dir);
        seeds += k > 0 ? k : 0;
    }
    test_note("%d fuzz regression inputs, %d seeds", n, seeds);
}
