/*
 * wide_embree.h - exp_wide's industrial reference: Embree 3 (bin/embree_ref,
 * built only by `make embree`) beside the best wide single-ray kernel of a
 * scene, on the same triangles and rays, 1 thread. Without bin/embree_ref,
 * or on a scene with spheres, no row.
 */
#ifndef WIDE_EMBREE_H
#define WIDE_EMBREE_H

#include "engine/group.h"

typedef struct {
    int scenes;    /* scenes with Embree's row */
    exp_decider d; /* the first of them: ours / Embree, primary rays */
    char what[600], scene[128], runs[400];
} wide_embree;

/* Embree's row of one scene beside configuration bw of g (its Mrays/s from
 * the judging half of the rounds). On the first scene with a row, Embree
 * and bw timed pass for pass in fresh processes of bin/embree_ref --vs
 * decide e->d; the other scenes get Embree's runs only. */
void wide_embree_row(exp_ctx *x, wide_embree *e, const accel_scene *s, const bench_sets *sets,
                     exp_group *g, int bw);

#endif
