/*
 * coherence_raster.h - the raster order of core/coherence.c (private to
 * core/coherence.c and core/coherence_raster.c; the interface is
 * core/coherence.h): finding a camera's rays in pixel order, and the
 * order that takes such a block's rays in tiles.
 */
#ifndef ACCEL_CORE_COHERENCE_RASTER_H
#define ACCEL_CORE_COHERENCE_RASTER_H

#include <stddef.h>
#include <stdint.h>

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Rasters at most this wide are kept as they come: 64 consecutive rays
 * span at least four rows, as tight as a tile. */
#define ACCEL_RASTER_KEEP_W 16

/* 1 when rays[0..n) are a raster: rows *w wide (0: a row or two) whose
 * first whole row starts at index *first. */
int accel_find_raster(const accel_ray *rays, size_t n, size_t *w, size_t *first);
/* The block's rays in tiles of 64 (see coherence_raster.c) into idx;
 * 0 (order kept) when the block holds fewer than two whole rows. */
int accel_tile_order(size_t n, size_t w, size_t first, uint16_t *idx);

#ifdef __cplusplus
}
#endif

#endif
