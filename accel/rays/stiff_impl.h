/*
 * stiff_impl.h - internal to stiff.c and stiff_post.c.
 */
#ifndef ACCEL_STIFF_IMPL_H
#define ACCEL_STIFF_IMPL_H

#include "rays/stiff.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Drops repeated rays of c (see stiff_post.c). */
int stiff_dedupe(stiff_case *c, accel_error *err);
/* c->shadow from the leak rays (t_far = 1.25: each aims at t = 1 at a point
 * of the convex mesh it starts in). */
int stiff_make_shadow(stiff_case *c, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
