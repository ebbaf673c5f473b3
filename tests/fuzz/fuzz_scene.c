/*
 * fuzz_scene.c - libFuzzer target for the `.scene` reader (load_scene.c and
 * the flattener, compose.c). Meshes come from a callback, never from files
 * or generators: a SOURCE starting with 'x' fails to load, any other gives
 * (length % 4) triangles, so the fuzzer explores the parser, not the mesh
 * loaders. Beyond ASan and UBSan's checks it aborts when the reader breaks
 * its contract: a failure names the file and leaves the scene empty; a
 * success gives finite coordinates, consecutive base ids and instances whose
 * matrix times inverse is the identity.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int fuzz_mesh(void *ctx, const char *source, const char *dir, accel_scene *mesh,
                     accel_error *err)
{
    (void)ctx;
    (void)dir;
    if (source[0] == 'x') return accel_fail(err, ACCEL_ERR_IO, "%s: cannot open", source);
    scene_builder b = {0};
    int rc = 0;
    size_t n = strlen(source) % 4;
    for (size_t i = 0; i < n && rc == 0; i++)
        rc = scene_builder_add_tri(&b, v3((float)i, 0, 0), v3(0, 1, 0), v3(0, 0, 1), err);
    if (rc == 0) rc = scene_finish(&b, source, mesh, err);
    scene_builder_free(&b);
    return rc;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    accel_scene s;
    accel_error err = {0};
    scene_file_options o = {1u << 16, fuzz_mesh, NULL};
    int rc = scene_parse_scene("fuzz.scene", "", (const char *)data, size, &o, &s, &err);
    if (rc != 0) {
        if (strncmp(err.msg, "fuzz.scene:", 11) != 0) abort();
        if (s.tris || s.instances || s.prim_count) abort();
        return 0;
    }
    for (size_t i = 0; i < 9 * (size_t)s.tri_count; i++)
        if (!isfinite(s.tris[i])) abort();
    const accel_instances *set = s.instances;
    if (!set) abort();
    uint64_t next = 0;
    for (uint32_t k = 0; k < set->instance_count; k++) {
        const accel_instance *in = &set->instances[k];
        if (in->mesh >= set->mesh_count || in->base != next) abort();
        next += set->meshes[in->mesh].prim_count;
        /* M * inverse = identity on the linear part, to a loose tolerance
         * scaled by the entries' size (the reader refuses singular ones). */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double e = 0, mag = 0;
                for (int q = 0; q < 3; q++) {
                    e += in->xform[4 * i + q] * in->inverse[4 * q + j];
                    mag += fabs(in->xform[4 * i + q] * in->inverse[4 * q + j]);
                }
                if (fabs(e - (i == j)) > 1e-6 * (1 + mag)) abort();
            }
    }
    if (next != s.prim_count) abort();
    scene_free(&s);
    return 0;
}
