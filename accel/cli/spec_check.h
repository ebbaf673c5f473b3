/*
 * spec_check.h - an accelerator spec checked in full before any work, for
 * bin/trace, bin/render and the experiments (experiments/engine/harness.c): a typo
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
 */
#ifndef ACCEL_CLI_SPEC_CHECK_H
#define ACCEL_CLI_SPEC_CHECK_H

#include <stddef.h>

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The bottom= value of spec (up to the next ','), copied into out; 0 if none. */
int spec_check_bottom(const char *spec, char *out, size_t n);

/* 0, or ACCEL_ERR_SPEC with "<opt> <spec>: <reason>" in err. */
int spec_check_accel(const char *opt, const char *spec, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
