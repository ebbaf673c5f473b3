/*
 * fuzz_loader.c - libFuzzer target for one mesh loader, chosen at compile
 * time (-DFUZZ_FORMAT_OBJ, _PLY or _OFF). Beyond "no crash, no leak, no
 * out-of-bounds read" (ASan, UBSan), it checks the loaders' contract:
 * a failure names the file and adds no triangle, a success adds only
 * finite coordinates.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene.h"

#if defined(FUZZ_FORMAT_OBJ)
#define FUZZ_PARSE scene_parse_obj
#define FUZZ_NAME "fuzz.obj"
#elif defined(FUZZ_FORMAT_PLY)
#define FUZZ_PARSE scene_parse_ply
#define FUZZ_NAME "fuzz.ply"
#elif defined(FUZZ_FORMAT_OFF)
#define FUZZ_PARSE scene_parse_off
#define FUZZ_NAME "fuzz.off"
#else
#error "define FUZZ_FORMAT_OBJ, FUZZ_FORMAT_PLY or FUZZ_FORMAT_OFF"
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    scene_builder b = {0};
    accel_error err = {0};
    int rc = FUZZ_PARSE(FUZZ_NAME, (const char *)data, size, &b, &err);
    if (rc != 0) {
        if (strncmp(err.msg, FUZZ_NAME ":", strlen(FUZZ_NAME) + 1) != 0) abort();
        if (b.tri_count != 0) abort();
    } else {
        for (size_t i = 0; i < 9 * b.tri_count; i++)
            if (!isfinite(b.tris[i])) abort();
    }
    scene_builder_free(&b);
    return 0;
}
