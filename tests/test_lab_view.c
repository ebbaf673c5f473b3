/*
 * test_lab_view.c - the depth view `make lab STEP=2` writes (LAB.md, step 2)
 * shows the scene: each ray's node count lands on its own pixel. Primary
 * rays come in 8x8 tiles (rays.h), so a view filled in ray order is a
 * scramble of stripes; the test rebuilds the expected image from a counted
 * trace placed by rays_set.pixel and compares it with the file, byte for
 * byte.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "image/image.h"
#include "lab/check.h"
#include "png_decode.h"
#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"
#include "test.h"

#define VIEW 256 /* the size check.c renders the depth view at */

/* The expected view: bvh:build=median's node counts per pixel, coloured as
 * the check colours them. */
static int expected_view(const char *spec, image_rgb *img)
{
    accel_scene sc;
    rays_set rays = {0};
    accel_error err = {0};
    if (!test_make_scene(spec, &sc)) return -1;
    const accel_kind *bvh = NULL;
    void *a = NULL;
    accel_build_stats st;
    uint32_t *steps = malloc((size_t)VIEW * VIEW * sizeof *steps);
    float *v = malloc((size_t)VIEW * VIEW * sizeof *v);
    accel_hit *hits = malloc((size_t)VIEW * VIEW * sizeof *hits);
    int rc = -1;
    if (!steps || !v || !hits || rays_primary(&sc.camera, VIEW, VIEW, &rays, &err) ||
        !rays.pixel ||
        accel_build_spec("bvh:build=median", &sc, 1, &bvh, &a, &st, &err))
        goto out;
    accel_counters c = {0};
    c.ray_steps = steps;
    accel_trace(bvh, a, rays.rays, hits, rays.count, 1, &c);
    for (size_t i = 0; i < rays.count; i++) v[rays.pixel[i]] = (float)steps[i];
    char title[128];
    image_heat_title(title, sizeof title, bvh->name, bvh, 0);
    rc = image_heatmap(v, VIEW, VIEW, NULL, title, img, &err);
out:
    if (a) bvh->destroy(a);
    rays_free(&rays);
    free(steps);
    free(v);
    free(hits);
    scene_free(&sc);
    return rc;
}

TEST(lab_depth_view_pixels)
{
    const accel_kind *bvh = accel_find_kind("bvh");
    char dir[] = "/tmp/gridbvh_lab_view_XXXXXX";
    CHECK(bvh != NULL);
    if (!bvh || !mkdtemp(dir)) return;
    lab_subject own = {bvh, "build=median", 1, dir, 1, NULL};
    lab_result r;
    accel_error err = {0};
    CHECK(lab_check(2, &own, &r, &err) == 0);
    CHECKF(r.passed, "step 2 fails on the project's own BVH:\n%s", r.report);
    CHECKF(strstr(r.report, "depth view") != NULL, "no depth view reported:\n%s", r.report);

    char path[256];
    snprintf(path, sizeof path, "%s/step2_depth_cube_n_6.png", dir);
    size_t n = 0;
    char *png = test_read_file(path, &n);
    CHECKF(png != NULL, "%s was not written", path);
    image_rgb want = {0};
    CHECK(expected_view("cube:n=6", &want) == 0);
    int w = 0, h = 0;
    uint8_t *rgb = NULL;
    char msg[256];
    png_stats ps;
    if (png && want.rgb &&
        test_png_decode((const uint8_t *)png, n, &w, &h, &rgb, &ps, msg, sizeof msg) == 0) {
        CHECKF(w == want.width && h == want.height, "view %dx%d, expected %dx%d", w, h,
               want.width, want.height);
        size_t bytes = (size_t)w * h * 3, bad = 0;
        for (size_t i = 0; w == want.width && h == want.height && i < bytes; i++)
            bad += rgb[i] != want.rgb[i];
        CHECKF(bad == 0, "%zu of %zu bytes of the depth view differ from the node counts "
                         "placed at their pixels", bad, bytes);
    } else {
        CHECKF(0, "cannot decode %s", path);
    }
    free(rgb);
    free(png);
    image_free(&want);
    /* the check's four views, then the folder */
    const char *names[] = {"soup_tris_3000_seed_7", "teapot_stadium_n_4", "sphereflake_level_2",
                           "cube_n_6"};
    for (int i = 0; i < 4; i++) {
        /* the reference's view beside it: here the subject is the reference */
        char ref_path[300];
        snprintf(path, sizeof path, "%s/step2_depth_%s.png", dir, names[i]);
        snprintf(ref_path, sizeof ref_path, "%s/step2_depth_%s_reference.png", dir, names[i]);
        size_t na = 0, nb = 0;
        char *a = test_read_file(path, &na), *b = test_read_file(ref_path, &nb);
        CHECKF(a && b && na == nb && memcmp(a, b, na) == 0,
               "%s: the reference's view is missing or differs from the same kind's", ref_path);
        free(a);
        free(b);
        remove(path);
        remove(ref_path);
    }
    rmdir(dir);
}
