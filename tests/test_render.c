/*
 * test_render.c - bin/render as a subprocess: its numbers are parsed
 * strictly, and a frame range is checked whole before the first frame.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support.h"

#define DIR "build/test_render"

static int run(const char *cmd, char **out, char **err) { return test_run(DIR, cmd, out, err); }

TEST(tools_render_parses_numbers_strictly)
{
    /* atoi took "2abc" as 2 and 99999999999 as 1215752191. */
    static const char *const bad[] = {"--frames 2abc", "--size 8x8junk", "--threads 2xyz",
                                      "--first 99999999999", "--size x8", "--step 0"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char cmd[256], *err = NULL;
        snprintf(cmd, sizeof cmd, "bin/render --scene animated --out " DIR "/r %s", bad[i]);
        int rc = run(cmd, NULL, &err);
        CHECKF(rc == 2 && err && strstr(err, "bad value for"), "render %s: exit %d, '%s'", bad[i],
               rc, err ? err : "");
        free(err);
    }
}

/* A frame range the scene refuses fails before the first frame, naming the
 * last frame; one past int (first + (frames - 1) x step) is a usage error. */
TEST(tools_render_checks_the_last_frame_first)
{
    char *out = NULL, *err = NULL;
    int rc = run("bin/render --scene animated --size 8x8 --first 9999999 --frames 3", &out, &err);
    CHECKF(rc == 1 && err && strstr(err, "frame 10000001, the last one") && out && !*out,
           "exit %d, out '%s', err '%s'", rc, out ? out : "", err ? err : "");
    free(out), free(err);
    rc = run("bin/render --scene animated --size 8x8 --first 100000000 --frames 100000 "
             "--step 100000000", NULL, &err);
    CHECKF(rc == 2 && err && strstr(err, "is past 100000000"), "exit %d, '%s'", rc,
           err ? err : "");
    free(err);
    /* The range's last frame itself is fine. */
    rc = run("bin/render --scene animated --size 8x8 --first 9999998 --frames 3", NULL, &err);
    CHECKF(rc == 0, "exit %d, '%s'", rc, err ? err : "");
    free(err);
}
