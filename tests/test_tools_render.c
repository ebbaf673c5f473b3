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
    /* Each message lists what the option accepts, as trace's do ("bad
     * value for --update: refitt" did not). */
    static const char *const bad[][2] = {
        {"--frames 2abc", "--frames 2abc: expected a whole number in 1..100000"},
        {"--size 8x8junk", "--size 8x8junk: expected WxH with 1 <= W, H <= 16384"},
        {"--threads 2xyz", "--threads 2xyz: expected a whole number in 1..256"},
        {"--first 99999999999", "--first 99999999999: expected a whole number in 0..100000000"},
        {"--size x8", "--size x8: expected WxH"},
        {"--step 0", "--step 0: expected a whole number in 1..100000000"},
        {"--update refitt", "--update refitt: expected refit, rebuild or full"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char cmd[256], *err = NULL;
        snprintf(cmd, sizeof cmd, "bin/render --scene animated --out " DIR "/r %s", bad[i][0]);
        int rc = run(cmd, NULL, &err);
        CHECKF(rc == 2 && err && strstr(err, bad[i][1]), "render %s: exit %d, '%s' (expected '%s')",
               bad[i][0], rc, err ? err : "", bad[i][1]);
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

/* The scene_ms column of frame `frame` in render's table (-1 if absent). */
static double scene_ms_of(const char *out, int frame)
{
    char key[32];
    snprintf(key, sizeof key, "\n%6d ", frame);
    const char *p = out ? strstr(out, key) : NULL;
    double ms = -1;
    if (p) sscanf(p + strlen(key), "%lf", &ms);
    return ms;
}

/* A still (a mesh, a .scene file) was remade every frame (26-63 ms each),
 * so its frames per second with the scene making were wrong: it is made
 * once and kept, and frames after the first make nothing. An animated
 * scene is still made per frame. */
TEST(tools_render_keeps_a_still)
{
    mkdir("build", 0777), mkdir(DIR, 0777);
    FILE *f = fopen(DIR "/still.scene", "w");
    if (f) fputs("mesh a soup:tris=20000\ninstance a\n", f), fclose(f);
    char *out = NULL, *err = NULL;
    int rc = run("bin/render --scene " DIR "/still.scene --accel bvh --size 16x12 --frames 3 "
                 "--threads 1 --verify", &out, &err);
    CHECKF(rc == 0, "still: exit %d: %s", rc, err ? err : "");
    CHECKF(out && strstr(out, "a still, made once and kept"), "no word of the still: %.300s",
           out ? out : "");
    CHECKF(scene_ms_of(out, 0) > 0, "frame 0 made no scene: %.400s", out ? out : "");
    for (int fr = 1; fr < 3; fr++)
        CHECKF(scene_ms_of(out, fr) == 0, "still frame %d: scene_ms %.2f, not 0 (remade): %.400s",
               fr, scene_ms_of(out, fr), out ? out : "");
    /* update + trace equals it with the scene making: nothing was made. */
    const char *med = out ? strstr(out, "median over 2 updated frames: ") : NULL;
    double a = -1, b = -2;
    if (med) sscanf(med, "median over 2 updated frames: %lf frames/s (update + trace), %lf", &a, &b);
    CHECKF(a == b, "still: %.2f frames/s, %.2f with the scene making", a, b);
    free(out), free(err);
    rc = run("bin/render --scene animated:instances=2,detail=2 --accel bvh --size 16x12 "
             "--frames 2 --threads 1", &out, &err);
    CHECKF(rc == 0 && scene_ms_of(out, 1) > 0, "animated: exit %d, frame 1 scene_ms %.2f: %s", rc,
           scene_ms_of(out, 1), err ? err : "");
    free(out), free(err);
}
