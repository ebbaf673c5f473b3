/*
 * minimal.c - the library from C in one page: load a scene, build an
 * accelerator from a spec string, trace a few rays, print their hits.
 *
 *     bin/minimal [SCENE [ACCEL]]    (default: ../shared/scenes/bunny.off bvh)
 *
 * Build your own program like this one (README.md, "Using the library
 * from C"): cc -Iaccel -I. my.c build/libgridbvh.a -lm -pthread
 */
#include <math.h>
#include <stdio.h>

#include "accel.h"
#include "scene/scene.h"

int main(int argc, char **argv)
{
    const char *scene_spec = argc > 1 ? argv[1] : "../shared/scenes/bunny.off";
    const char *accel_spec = argc > 2 ? argv[2] : "bvh";
    accel_scene scene;
    accel_error err = {0};
    if (scene_create(scene_spec, &scene, &err)) { /* a mesh file or a built-in spec */
        fprintf(stderr, "minimal: %s\n", err.msg);
        return 1;
    }
    const accel_kind *kind;
    void *accel;
    accel_build_stats stats;
    if (accel_build_spec(accel_spec, &scene, 1, &kind, &accel, &stats, &err)) {
        fprintf(stderr, "minimal: %s\n", err.msg);
        scene_free(&scene);
        return 1;
    }
    printf("%s: %u primitives, %s built\n", scene_spec, scene.prim_count, accel_spec);
    /* Five rays from the camera's eye to points along the bounds' diagonal. */
    enum { N = 5 };
    accel_ray rays[N];
    accel_hit hits[N];
    vec3 e = scene.camera.eye, lo = scene.bounds.min, hi = scene.bounds.max;
    for (int i = 0; i < N; i++) {
        float f = (i + 1.0f) / (N + 1.0f);
        rays[i] = (accel_ray){e.x, e.y, e.z, 0.0f, lo.x + f * (hi.x - lo.x) - e.x,
                              lo.y + f * (hi.y - lo.y) - e.y, lo.z + f * (hi.z - lo.z) - e.z,
                              INFINITY};
    }
    accel_trace(kind, accel, rays, hits, N, 1, NULL); /* closest hits; counters: none */
    for (int i = 0; i < N; i++) {
        printf("ray %.9g %.9g %.9g -> %.9g %.9g %.9g: ", rays[i].ox, rays[i].oy, rays[i].oz,
               rays[i].dx, rays[i].dy, rays[i].dz);
        if (hits[i].prim == ACCEL_MISS)
            printf("miss\n");
        else
            printf("prim %u t %.9g u %.6f v %.6f\n", hits[i].prim, hits[i].t, hits[i].u, hits[i].v);
    }
    kind->destroy(accel);
    scene_free(&scene);
    return 0;
}
