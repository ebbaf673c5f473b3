/*
 * shade.h - a shaded picture of closest hits, for bin/trace --image.
 */
#ifndef ACCEL_SHADE_H
#define ACCEL_SHADE_H

#include "image/image.h"
#include "rays/rays.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Colours the pixel of every ray of r (r->pixel, or ray i = pixel i) in img
 * from its hit; pixels without a ray keep their colour. */
void image_shade(const accel_scene *s, const rays_set *r, const accel_hit *hits, image_rgb *img);

#ifdef __cplusplus
}
#endif

#endif
