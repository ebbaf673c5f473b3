/*
 * trace.c - the wide BVH's batch entries: the kernel table (core/variant.h)
 * of the tree's width, row (single rays, packets, order=branchy, quant=1,
 * streams, layout=mixed, any_order=),
 * block size and query, each compiled from the templates core/block_test.h (the SIMD
 * watertight leaf test), kernel.h, packet.h and stream.h (the traversals) by its own
 * unit k<width>_<row>.c (tables.h), once for AVX2 and once for AVX-512
 * (the tree's isa, chosen by the kind at build time: core/isa.h).
 */
#include "core/isa.h"
#include "node.h"

#define WIDE_PACKET_ROWS(sfx)                                                                       \
    static const accel_kernel_table *bvh_wide_k4_packet##sfx(int any_hit, int block8)                \
    {                                                                                              \
        return any_hit ? bvh_wide_k4_packet_any##sfx(block8) : bvh_wide_k4_packet_hit##sfx(block8); \
    }                                                                                              \
    static const accel_kernel_table *bvh_wide_k8_packet##sfx(int any_hit, int block8)                \
    {                                                                                              \
        return any_hit ? bvh_wide_k8_packet_any##sfx(block8) : bvh_wide_k8_packet_hit##sfx(block8); \
    }                                                                                              \
    static const accel_kernel_table *bvh_wide_k4_stream##sfx(int any_hit, int block8)                \
    {                                                                                              \
        return any_hit ? bvh_wide_k4_stream_any##sfx(block8) : bvh_wide_k4_stream_hit##sfx(block8); \
    }                                                                                              \
    static const accel_kernel_table *bvh_wide_k8_stream##sfx(int any_hit, int block8)                \
    {                                                                                              \
        return any_hit ? bvh_wide_k8_stream_any##sfx(block8) : bvh_wide_k8_stream_hit##sfx(block8); \
    }
/* [width 8][row]: width 4 has no quantized, layout=mixed or any_order=
 * row (width 8 only; the build refuses them), so those slots repeat the
 * branchy one. */
#define WIDE_ROWS(sfx)                                                                              \
    {{bvh_wide_k4_single##sfx, bvh_wide_k4_packet##sfx, bvh_wide_k4_branchy##sfx,                 \
      bvh_wide_k4_branchy##sfx, bvh_wide_k4_stream##sfx, bvh_wide_k4_branchy##sfx,               \
      bvh_wide_k4_branchy##sfx},                                                                   \
     {bvh_wide_k8_single##sfx, bvh_wide_k8_packet##sfx, bvh_wide_k8_branchy##sfx,                 \
      bvh_wide_k8_quant##sfx, bvh_wide_k8_stream##sfx, bvh_wide_k8_mixed##sfx,                   \
      bvh_wide_k8_anyord##sfx}}

WIDE_PACKET_ROWS()
#ifdef GRIDBVH_AVX512
WIDE_PACKET_ROWS(_avx512)
#endif

/* [AVX-512][width 8][row]: the units compiled for each ISA (Makefile,
 * node.h); a build without the AVX-512 units repeats the AVX2 ones, which
 * accel_isa_resolve never lets a tree choose then. */
static const wide_row_fn wide_rows[2][2][7] = {
    WIDE_ROWS(),
#ifdef GRIDBVH_AVX512
    WIDE_ROWS(_avx512),
#else
    WIDE_ROWS(),
#endif
};

static const accel_kernel_table *table_of(const bvh_wide *w, int row, int any_hit)
{
    return wide_rows[w->isa == ACCEL_ISA_AVX512][w->width == 8][row](any_hit, w->block == 8);
}

/* The single-ray row of w for a query: quant=1 (quantized nodes, branchy
 * push), layout=mixed (the one pool), any_order= (any-hit queries only),
 * order=branchy, else the default (order=octant or dist). The build
 * allows at most one of them. */
static int single_row(const bvh_wide *w, int any_hit)
{
    return w->quant                                ? WIDE_ROW_QUANT
           : w->layout == WIDE_LAYOUT_MIXED        ? WIDE_ROW_MIXED
           : any_hit && w->any_order != WIDE_ANY_NEAR ? WIDE_ROW_ANY
           : w->order == WIDE_ORDER_BRANCHY        ? WIDE_ROW_BRANCHY
                                                   : WIDE_ROW_SINGLE;
}

/* Packets and streams keep their own order (octant). */
static int table_row(const bvh_wide *w, int any_hit)
{
    return w->packets ? WIDE_ROW_PACKET : w->stream ? WIDE_ROW_STREAM : single_row(w, any_hit);
}

static unsigned kernel_flags(const bvh_wide *w, int naive, int has_spheres)
{
    return accel_variant_flags(naive, has_spheres, w->order != WIDE_ORDER_DIST);
}

void bvh_wide_intersect(const bvh_wide *w, const accel_ray *rays, accel_hit *hits, size_t count,
                        accel_counters *c, int naive, int has_spheres)
{
    accel_run_kernel(table_of(w, table_row(w, 0), 0), w, rays, hits, count, c,
                     kernel_flags(w, naive, has_spheres));
}

void bvh_wide_occluded(const bvh_wide *w, const accel_ray *rays, uint8_t *occ, size_t count,
                       accel_counters *c, int naive, int has_spheres)
{
    accel_run_kernel(table_of(w, table_row(w, 1), 1), w, rays, occ, count, c,
                     kernel_flags(w, naive, has_spheres));
}

/* The single-ray row of w (w->packets ignored): the packet layer's
 * fallback for incoherent groups (core/coherence.h). */

void bvh_wide_single_intersect(const bvh_wide *w, const accel_ray *rays, accel_hit *hits,
                               size_t count, accel_counters *c, int naive, int has_spheres)
{
    accel_run_kernel(table_of(w, single_row(w, 0), 0), w, rays, hits, count, c,
                     kernel_flags(w, naive, has_spheres));
}

void bvh_wide_single_occluded(const bvh_wide *w, const accel_ray *rays, uint8_t *occ, size_t count,
                              accel_counters *c, int naive, int has_spheres)
{
    accel_run_kernel(table_of(w, single_row(w, 1), 1), w, rays, occ, count, c,
                     kernel_flags(w, naive, has_spheres));
}
