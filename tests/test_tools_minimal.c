/*
 * test_tools_minimal.c - bin/minimal, the README's program of the library
 * from C, as a subprocess: it prints its scene's size and, for each of its
 * five rays, the ray and its hit, which must agree with the reference
 * traced here on the same rays (parsed from its output: %.9g gives every
 * float back exactly).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rays/rays.h"
#include "scene/scene.h"
#include "support.h"

#define DIR "build/test_tools_minimal"

/* Runs bin/minimal on scene with accel; checks every printed hit. */
static void check_minimal(const char *scene, const char *accel)
{
    char cmd[1024], *out = NULL, *err = NULL;
    snprintf(cmd, sizeof cmd, "bin/minimal '%s' '%s'", scene, accel);
    int rc = test_run(DIR, cmd, &out, &err);
    CHECKF(rc == 0 && out, "%s: exit %d, stderr '%s'", cmd, rc, err ? err : "");
    accel_scene s;
    if (rc != 0 || !out || !test_make_scene(scene, &s)) {
        free(out), free(err);
        return;
    }
    char head[256];
    snprintf(head, sizeof head, ": %u primitives, %s built\n", s.prim_count, accel);
    CHECKF(strstr(out, head) != NULL, "%s: no line '%s' in '%s'", cmd, head, out);
    int rays = 0, hits = 0;
    for (const char *p = strstr(out, "\nray "); p; p = strstr(p + 1, "\nray ")) {
        accel_ray r = {0};
        accel_hit got = accel_hit_miss(), ref;
        char what[16] = "";
        int n = sscanf(p, "\nray %f %f %f -> %f %f %f: %15s", &r.ox, &r.oy, &r.oz, &r.dx, &r.dy,
                       &r.dz, what);
        CHECKF(n == 7, "%s: cannot read '%.120s'", cmd, p + 1);
        if (n != 7) break;
        r.t_far = INFINITY;
        if (!strcmp(what, "prim")) {
            const char *h = strstr(p, ": prim ");
            CHECK(h && sscanf(h, ": prim %u t %f u %f v %f", &got.prim, &got.t, &got.u, &got.v) == 4);
            hits++;
        } else {
            CHECKF(!strcmp(what, "miss"), "%s: '%s' is neither prim nor miss", cmd, what);
        }
        accel_reference_trace(&s, &r, &ref, 1, 1);
        CHECKF(ref.prim == got.prim && hits_agree(&s, &r, &ref, &got),
               "%s, ray %d: prim %u t %.9g, the reference prim %u t %.9g", cmd, rays, got.prim,
               (double)got.t, ref.prim, (double)ref.t);
        rays++;
    }
    CHECKF(rays == 5, "%s: %d rays printed (expected 5)", cmd, rays);
    CHECKF(hits >= 3, "%s: %d of its rays hit (at least 3 expected)", cmd, hits);
    scene_free(&s);
    free(out), free(err);
}

TEST(tools_minimal_hits_match_the_reference)
{
    check_minimal("sphere:segments=16", "grid");
    check_minimal("sphereflake:level=2", "bvh:width=8");
    const char *dir = test_shared_scenes();
    if (!dir) {
        test_note("bunny.off not run: ../shared/scenes not found");
        return;
    }
    check_minimal("../shared/scenes/bunny.off", "bvh");
}
