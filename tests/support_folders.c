/*
 * support_folders.c - the subfolders of a backend (support.h), which
 * sources.mk builds into the library like the backend's own files.
 */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

static int by_folder(const void *a, const void *b)
{
    return strcmp((const char *)a, (const char *)b);
}

int test_backend_subfolders(const char *backend, char (*names)[256], int max)
{
    DIR *d = opendir(backend);
    if (!d) return 0;
    int count = 0;
    struct dirent *e;
    while ((e = readdir(d)) && count < max) {
        if (e->d_name[0] == '.') continue;
        char path[256];
        if (snprintf(path, sizeof path, "%s/%s", backend, e->d_name) >= (int)sizeof path) continue;
        DIR *sub = opendir(path);
        if (!sub) continue; /* a file */
        closedir(sub);
        snprintf(names[count++], 256, "%s", path);
    }
    closedir(d);
    qsort(names, (size_t)count, sizeof names[0], by_folder);
    return count;
}
