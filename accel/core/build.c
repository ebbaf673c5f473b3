/*
 * build.c - accel_build_spec: parse a spec, build the kind it names on a
 * scene, time the build and account its memory.
 */
#include <string.h>

#include "accel.h"

static int build_parsed(const accel_params *p, const accel_scene *scene, int threads,
                        void **accel_out, accel_build_stats *stats, accel_error *err)
{
    memset(stats, 0, sizeof *stats);
    double t0 = accel_now_ms();
    int rc = p->kind->build(scene, p, threads, accel_out, stats, err);
    if (rc) return rc;
    stats->ms = accel_now_ms() - t0;
    stats->bytes = p->kind->memory(*accel_out);
    return 0;
}

int accel_build_spec(const char *spec, const accel_scene *scene, int threads,
                     const accel_kind **kind_out, void **accel_out, accel_build_stats *stats,
                     accel_error *err)
{
    accel_params p;
    int rc = accel_params_parse(spec, &p, err);
    if (rc) return rc;
    rc = build_parsed(&p, scene, threads, accel_out, stats, err);
    if (rc) return rc;
    *kind_out = p.kind;
    return 0;
}

int accel_build_kind(const accel_kind *kind, const char *kv, const accel_scene *scene,
                     int threads, void **accel_out, accel_build_stats *stats, accel_error *err)
{
    accel_params p;
    int rc = accel_params_parse_kind(kind, kv, &p, err);
    return rc ? rc : build_parsed(&p, scene, threads, accel_out, stats, err);
}
