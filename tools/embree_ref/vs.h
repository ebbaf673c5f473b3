/*
 * vs.h - bin/embree_ref --vs: one of the project's accelerators timed in
 * the same process as Embree, pass for pass (vs.c). Apart from
 * embree_ref.c so that it needs no Embree header.
 */
#ifndef EMBREE_REF_VS_H
#define EMBREE_REF_VS_H

#include <stddef.h>

#include "accel.h"

/* The median of v[0..n) (n >= 1), which it sorts: embree_ref's passes and
 * builds too. */
double vs_median(double *v, int n);

/* One timed pass of the other tracer over every ray; its milliseconds. */
typedef double (*vs_pass_fn)(void *ctx);

/* Builds spec on scene (1 thread) and times its passes over rays (closest
 * hits, or any-hit with occluded; `threads` threads) in turn with `other`'s:
 * a warm-up pair, then `passes` pairs, ours first in even pairs and second
 * in odd ones. Prints one line "vs spec=... mrays=... embree_mrays=...
 * ratio=... ratio_min=... ratio_max=... passes=..." where ratio is the
 * median over the pairs of ours' speed over the other's. Returns 0, or a
 * CLI exit code after a message naming spec. */
int vs_time(const char *spec, const accel_scene *scene, const accel_ray *rays, size_t n, int threads,
            int occluded, int passes, vs_pass_fn other, void *ctx);

#endif
