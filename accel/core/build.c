/*
 * build.c - accel_build_spec: parse a spec, build the kind it names on a
 * scene, time the build and account its memory.
 */
#include <string.h>

#include "accel.h"

int accel_build_spec(const char *spec, const accel_scene *scene, int threads,
                     const accel_kind **kind_out, void **accel_out, accel_build_stats *stats,
                     accel_error *err)
{
    accel_params p;
    int rc = accel_params_parse(spec, &p, err);
    if (rc) return rc;
    memset(stats, 0, sizeof *stats);
    double t0 = accel_now_ms();
    rc = p.kind->build(scene, &p, threads, accel_out, stats, err);
    if (rc) return rc;
    stats->ms = accel_now_ms() - t0;
    stats->bytes = p.kind->memory(*accel_out);
    *kind_out = p.kind;
    return 0;
}
