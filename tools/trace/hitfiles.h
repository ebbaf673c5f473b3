/*
 * hitfiles.h - bin/trace's hit files (FORMATS.md): `trace compare`, by the
 * closest-hit rule or, with --occluded, by the any-hit rule; and the
 * any-hit answers of an occlusion query, which --dump-hits writes for
 * shadow, ao and `--occluded` file rays.
 */
#ifndef TOOLS_TRACE_HITFILES_H
#define TOOLS_TRACE_HITFILES_H

#include <stddef.h>
#include <stdint.h>

#include "accel.h"

/* `trace compare [--occluded] REFERENCE.hits OTHER.hits` (argv[1] is
 * "compare"); returns the exit status (bench/cli.h). */
int trace_compare(int argc, char **argv);

/* FORMATS.md "Any-hit answers" for rays whose occlusion answers are occ:
 * a miss where occ[i] is 0, otherwise one triangle the ray hits with its t,
 * u, v. The occlusion kernels answer yes or no only, so the triangle is the
 * closest hit of the same structure (an untimed pass); where that finds
 * none, the double-precision reference's. Returns how many occluded rays
 * neither found a triangle for (written as misses; the caller says so). */
size_t trace_anyhit_answers(const accel_kind *kind, const void *accel, const accel_scene *scene,
                            const accel_ray *rays, const uint8_t *occ, size_t n, int threads,
                            accel_hit *out);

#endif
