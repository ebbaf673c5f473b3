/*
 * test_tools_render.c - bin/render as a subprocess: its numbers are parsed
 * strictly, and a frame range is checked whole before the first frame.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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
 * last frame (a scene parameter out of range: a usage error, 2, as in trace); one past int (first + (frames - 1) x step) is a usage error. */
TEST(tools_render_checks_the_last_frame_first)
{
    char *out = NULL, *err = NULL;
    int rc = run("bin/render --scene animated --size 8x8 --first 9999999 --frames 3", &out, &err);
    CHECKF(rc == 2 && err && strstr(err, "frame 10000001, the last one") && out && !*out,
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

/* Issue 36, defect 4: the README's --out makes its folder, a .scene file
 * renders as a still, and render keeps trace's exit statuses. */
TEST(tools_render_takes_scene_files_and_trace_exit_codes)
{
    mkdir("build", 0777), mkdir(DIR, 0777);
    FILE *f = fopen(DIR "/two.scene", "w");
    if (f) fputs("mesh a soup:tris=200\ninstance a\ninstance a translate 2 0 0\n", f), fclose(f);
    f = fopen(DIR "/afile", "w");
    if (f) fclose(f);
    system("rm -rf " DIR "/frames");
    char *out = NULL, *err = NULL;
    int rc = run("bin/render --scene " DIR "/two.scene --size 16x12 --frames 2 --out " DIR
                 "/frames/f", &out, &err);
    CHECKF(rc == 0 && out && strstr(out, "a still"), "a .scene file: exit %d, '%s' '%s'", rc,
           out ? out : "", err ? err : "");
    CHECK(access(DIR "/frames/f_0001.png", R_OK) == 0);
    free(out), free(err);
    static const struct { const char *args, *text; int code; } bad[] = {
        {"--accel gird", "unknown accelerator 'gird'", 2},
        {"--accel instanced:bottom=bvh:widht=2", "bottom=", 2},
        {"--frames 2 --bogus", "unknown option --bogus", 2},
        {"--scene " DIR "/absent.scene", "absent.scene", 3},
        {"--out " DIR "/afile/f", "afile", 3},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char cmd[256];
        snprintf(cmd, sizeof cmd, "bin/render --size 8x8 --frames 1 %s", bad[i].args);
        rc = run(cmd, &out, &err);
        CHECKF(rc == bad[i].code && err && strstr(err, bad[i].text) && out && !*out,
               "render %s: exit %d (expected %d), out '%s', err '%s'", bad[i].args, rc,
               bad[i].code, out ? out : "", err ? err : "");
        free(out), free(err);
    }
    rc = run("bin/render --help", &out, NULL);
    CHECKF(rc == 0 && out && strstr(out, "Exit status:") && strstr(out, "3  input error"),
           "render --help: exit %d, no exit statuses", rc);
    free(out);
}
