/*
 * grid_impl.h - the built grid, shared by the builder (grid_build.c), the
 * empty-space tables (grid_skip.c) and the traversals (grid_trace.c,
 * grid_packet_trace.c). Private to grid/.
 */
#ifndef GRID_GRID_IMPL_H
#define GRID_GRID_IMPL_H

#include "core/variant.h"
#include "grid.h"
#include "grid_skip.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    /* The primitive store (accel.h): the live primitives copied in Morton
     * order (reorder=1) or scene order; cells hold local ids, and
     * store.scene_id maps a hit back. */
    accel_prim_store store;
    grid_frame frame;
    grid_cells cells;
    /* cells=blocks (single rays on triangles): the cells as primitive
     * blocks for the shared block test; offsets NULL when not built. */
    grid_cell_blocks blocks;
    float *planes;      /* storage behind frame.planes */
    int naive;          /* tri=naive */
    int mailbox;        /* the single-ray kernels' mailbox (off with blocks) */
    int packet_mailbox; /* traverse=packet: the packets' mailbox (mailbox=1) */
    int has_spheres;
    int isa;            /* ACCEL_ISA_AVX2 or _AVX512 (core/isa.h): whose block kernels run */
    int traverse;       /* GRID_TRAVERSE_SINGLE / GRID_TRAVERSE_PACKET */
    uint8_t *macro;     /* traverse=packet: occupancy of GRID_MACRO^3 blocks of cells */
    /* Empty-space skipping (grid_skip.h): skip=cloud keeps one distance
     * byte per cell, skip=macro one empty flag per block of 2^macro_shift
     * cells per axis (macro_res blocks per axis). */
    grid_skip_mode skip;
    uint8_t *skip_dist;  /* cloud: cell_count bytes */
    uint8_t *macro_empty;/* macro: macro_res[0]*[1]*[2] bytes */
    int skip_min;        /* cloud: smallest radius jumped (cells) */
    int macro_shift;
    int macro_res[3];
} grid_accel;

/* Cells per macro cell and axis (traverse=packet skips empty layers). */
#ifndef GRID_MACRO
#define GRID_MACRO 4
#endif

/* Traversal modes (parameter traverse=). */
enum { GRID_TRAVERSE_SINGLE = 0, GRID_TRAVERSE_PACKET = 1 };

/* Macro cells: GRID_MACRO^3 cells each, 1 when any of them holds a
 * primitive (grid_accel.macro, built for traverse=packet; grid_skip.c). */
int grid_macro_build(grid_accel *g, accel_error *err);
/* 1 when a macro cell of layer `layer` (on K) covering cells [lo, hi] on
 * a1, a2 holds a primitive. */
int grid_macro_any(const grid_accel *g, int K, int a1, int a2, int layer, const int lo[2],
                   const int hi[2]);

/* The kernel-variant flags of a built grid (core/variant.h). */
static inline unsigned grid_variant_flags(const grid_accel *g)
{
    return accel_variant_flags(g->naive, g->has_spheres, g->mailbox);
}

/* The packet kernels' flags: their own mailbox switch (a packet's
 * mailbox pays with blocks too; the single-ray fallback's does not). */
static inline unsigned grid_packet_variant_flags(const grid_accel *g)
{
    return accel_variant_flags(g->naive, g->has_spheres, g->packet_mailbox);
}

/* Single-ray traversal (grid_trace.c). */
void grid_intersect(const void *accel, const accel_ray *rays, accel_hit *hits, size_t count,
                    accel_counters *counters);
void grid_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded, size_t count,
                   accel_counters *counters);

/* Coherent grid traversal, 64-ray packets (grid_packet_trace.c); packets that
 * do not qualify go to the single-ray kernels above. */
void grid_packet_intersect(const void *accel, const accel_ray *rays, accel_hit *hits,
                           size_t count, accel_counters *counters);
void grid_packet_occluded(const void *accel, const accel_ray *rays, uint8_t *occluded,
                          size_t count, accel_counters *counters);

/* accel.h's conservative walk (grid_walk.c): a DDA over cells grown by the pad. */
int grid_walk(const void *accel, const accel_ray *ray, float pad, accel_walk_visit visit,
              void *ctx, uint32_t *steps);

#ifdef __cplusplus
}
#endif

#endif
