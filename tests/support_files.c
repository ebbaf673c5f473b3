/*
 * support_files.c - the helpers of support.h that deal with files, folders
 * and commands: the shared scene files, the backend folders of sources.mk,
 * whole-file reads and writes, temporary folders, captured commands.
 */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>
#include <sys/wait.h>

#include "support.h"

/* qsort order of fixed-size name buffers. */
static int by_name(const void *a, const void *b)
{
    return strcmp((const char *)a, (const char *)b);
}

int test_shared_files(const char *exts, char (*paths)[512], int max)
{
    const char *dir = test_shared_scenes();
    if (!dir) {
        test_note("skipped: ../shared/scenes not found");
        return -1;
    }
    DIR *d = opendir(dir);
    if (!d) {
        test_note("skipped: cannot list %s", dir);
        return -1;
    }
    struct dirent *e;
    int count = 0;
    while ((e = readdir(d)) && count < max) {
        const char *dot = strrchr(e->d_name, '.');
        if (!dot || e->d_name[0] == '.') continue;
        /* The extension, as a whole word of exts. */
        size_t len = strlen(dot);
        const char *hit = exts;
        while ((hit = strstr(hit, dot)) && hit[len] != ' ' && hit[len] != 0) hit += len;
        if (!hit) continue;
        snprintf(paths[count++], 512, "%s/%s", dir, e->d_name);
    }
    closedir(d);
    qsort(paths, (size_t)count, sizeof paths[0], by_name);
    return count;
}

/* The NOT_BACKENDS list of sources.mk as " a b c " (0 when absent). */
static int read_not_backends(char *out, size_t size)
{
    FILE *f = fopen("sources.mk", "r");
    if (!f) return 0;
    char line[1024];
    int found = 0;
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, "NOT_BACKENDS", 12)) continue;
        const char *eq = strstr(line, ":=");
        if (!eq) continue;
        snprintf(out, size, " %s ", eq + 2);
        for (char *p = out; *p; p++)
            if (*p == '\n' || *p == '\t') *p = ' ';
        found = 1;
    }
    fclose(f);
    return found;
}

static int has_c_file(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    struct dirent *e;
    int found = 0;
    while (!found && (e = readdir(d))) {
        size_t n = strlen(e->d_name);
        found = n > 2 && !strcmp(e->d_name + n - 2, ".c");
    }
    closedir(d);
    return found;
}

int test_backend_folders(char (*names)[256], int max)
{
    char not_backends[1024];
    if (!read_not_backends(not_backends, sizeof not_backends)) {
        test_fail(__FILE__, __LINE__,
                  "sources.mk: no NOT_BACKENDS line (run from the repository root)");
        return -1;
    }
    DIR *d = opendir(".");
    if (!d) return 0;
    int count = 0;
    struct dirent *e;
    while ((e = readdir(d)) && count < max) {
        if (e->d_name[0] == '.') continue;
        char key[300];
        snprintf(key, sizeof key, " %s ", e->d_name);
        if (strstr(not_backends, key) || !has_c_file(e->d_name)) continue;
        snprintf(names[count++], 256, "%s", e->d_name);
    }
    closedir(d);
    qsort(names, (size_t)count, sizeof names[0], by_name);
    return count;
}

char *test_read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    long n = -1;
    if (fseek(f, 0, SEEK_END) == 0) n = ftell(f);
    if (n >= 0 && fseek(f, 0, SEEK_SET) == 0) buf = malloc((size_t)n + 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    if (!buf) return NULL;
    buf[n] = 0;
    if (size) *size = (size_t)n;
    return buf;
}

int test_write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    int ok = f && fputs(text, f) >= 0;
    if (f && fclose(f) != 0) ok = 0;
    CHECKF(ok, "cannot write %s", path);
    return ok;
}

int test_temp_dir(const char *stem, char *dir, size_t size)
{
    int n = snprintf(dir, size, "/tmp/gridbvh_%s_XXXXXX", stem);
    int ok = n > 0 && (size_t)n < size && mkdtemp(dir) != NULL;
    CHECKF(ok, "no temporary folder for %s", stem);
    return ok;
}

void test_remove_dir(const char *dir)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) test_note("could not remove %s", dir);
}

int test_run(const char *dir, const char *cmd, char **out, char **err)
{
    mkdir("build", 0777);
    mkdir(dir, 0777);
    char full[4096];
    snprintf(full, sizeof full, "%s >%s/out.txt 2>%s/err.txt", cmd, dir, dir);
    int st = system(full);
    char path[1024];
    snprintf(path, sizeof path, "%s/out.txt", dir);
    if (out) *out = test_read_file(path, NULL);
    snprintf(path, sizeof path, "%s/err.txt", dir);
    if (err) *err = test_read_file(path, NULL);
    return st != -1 && WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}
