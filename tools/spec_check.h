/*
 * spec_check.h - an accelerator spec checked in full before any work, for
 * bin/trace, bin/render and the experiments (experiments/harness.c): a typo
 * in the last --accel must cost nothing, not a build and a trace of the
 * ones before it.
 *
 * Three steps, each naming the option and the spec in its message:
 *   1. accel_params_parse: the kind, the keys, the values its table checks;
 *   2. a bottom= sub-spec (instanced: <kind>:k=v;k=v, ';' for ','), parsed
 *      the same way, its message prefixed with "bottom=" so the user knows
 *      which half of the spec is wrong;
 *   3. a build on a 12-triangle scene (milliseconds), for the values a kind
 *      checks only when it builds (grid's res=0). Only a spec or range
 *      error of that build counts: any other failure is left to the real
 *      build, on the real scene.
 * Header-only (static functions), since each tool is one source file.
 */
#ifndef TOOLS_SPEC_CHECK_H
#define TOOLS_SPEC_CHECK_H

#include <stdio.h>
#include <string.h>

#include "accel.h"
#include "bench/bench.h"
#include "scene/scene.h"

/* The bottom= value of spec (up to the next ','), copied into out; 0 if none. */
static inline int spec_check_bottom(const char *spec, char *out, size_t n)
{
    const char *colon = strchr(spec, ':');
    for (const char *p = colon; p && *p; p = strchr(p + 1, ','))
        if (!strncmp(p + 1, "bottom=", 7)) {
            const char *v = p + 8;
            snprintf(out, n, "%.*s", (int)strcspn(v, ","), v);
            return 1;
        }
    return 0;
}

/* 0, or ACCEL_ERR_SPEC with "<opt> <spec>: <reason>" in err. */
static inline int spec_check_accel(const char *opt, const char *spec, accel_error *err)
{
    accel_params p;
    accel_error e = {0};
    if (accel_params_parse(spec, &p, &e))
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: %s", opt, spec, e.msg);
    char bottom[256], sub[256];
    if (spec_check_bottom(spec, bottom, sizeof bottom) && strcmp(bottom, "bvh") &&
        strcmp(bottom, "grid")) {
        snprintf(sub, sizeof sub, "%s", bottom);
        for (char *c = sub; *c; c++)
            if (*c == ';') *c = ',';
        accel_params q;
        if (accel_params_parse(sub, &q, &e))
            return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: bottom=%s: %s", opt, spec, bottom,
                              e.msg);
    }
    accel_scene tiny;
    if (scene_create("soup:tris=12", &tiny, &e)) return 0; /* nothing to try it on */
    const accel_kind *kind;
    void *accel = NULL;
    accel_build_stats st;
    accel_timing bt;
    int rc = bench_build(spec, &tiny, 1, 1, 0.0, &kind, &accel, &st, &bt, NULL, &e);
    if (!rc) kind->destroy(accel);
    scene_free(&tiny);
    if (rc && (e.code == ACCEL_ERR_SPEC || e.code == ACCEL_ERR_RANGE))
        return accel_fail(err, ACCEL_ERR_SPEC, "%s %s: %s", opt, spec, e.msg);
    return 0;
}

#endif
