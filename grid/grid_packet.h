/*
 * grid_packet.h - the packet of the coherent grid traversal (grid_packet_trace.c),
 * its setup and its slice ranges (grid_packet_setup.c).
 * A kernel body (C only): included by the .c files of its folder, not part
 * of the interface a C++ program includes.
 * Private to grid/, but for nested_grid/ngrid_packet.c, which walks its
 * levels with it through grid_packet_walk.h.
 *
 * A packet holds up to GRID_PACKET_SIZE consecutive rays as arrays of
 * doubles (one per attribute, AVX2 loads 4 rays at once), relative to a
 * reference point `ref` (the first live origin): the filters' magnitudes
 * are then those of the packet, not of the world coordinates.
 */
#ifndef GRID_GRID_PACKET_H
#define GRID_GRID_PACKET_H

#include "grid_impl.h"

/* The AVX2 + FMA paths (x86-64-v3); build with -DGRID_NO_SIMD to compare
 * against their scalar twins, which compute the same bounds. */
#if defined(__AVX2__) && defined(__FMA__) && !defined(GRID_NO_SIMD)
#define GRID_PACKET_AVX 1
#include <immintrin.h>

#ifdef __cplusplus
extern "C" {
#endif
#else
#define GRID_PACKET_AVX 0
#endif

/* Rays per packet: the 8x8 screen tiles the primary ray sets emit. */
#define GRID_PACKET_SIZE 64
/* Margin of every conservative bound, relative to the magnitudes it is
 * computed from: 2^-40 = 8192 units of double rounding (u = 2^-53), far
 * above the few dozen u any of the bounds accumulates. */
#define GRID_PACKET_REL 0x1p-40
/* Margin of the quantities derived from float reciprocals (the slab entry
 * and exit of a ray: relative error below 2^-22). */
#define GRID_PACKET_REL_F 0x1p-20

/* Widest range of cells (per axis) a packet may sweep in a slice: wider
 * packets are traced ray by ray (a performance choice, not a correctness
 * one; measured in grid/README.md). */
#ifndef GRID_PACKET_MAX_CELLS
#define GRID_PACKET_MAX_CELLS 16.0
#endif

typedef struct {
    /* Filter data; dead lanes hold harmless values and are masked by
     * `active` wherever they are read. */
    _Alignas(32) double dx[GRID_PACKET_SIZE];
    _Alignas(32) double dy[GRID_PACKET_SIZE];
    _Alignas(32) double dz[GRID_PACKET_SIZE];
    _Alignas(32) double mx[GRID_PACKET_SIZE]; /* moment M = (O - ref) x D */
    _Alignas(32) double my[GRID_PACKET_SIZE];
    _Alignas(32) double mz[GRID_PACKET_SIZE];
    _Alignas(32) double emag[GRID_PACKET_SIZE]; /* GRID_PACKET_REL * |D|_1 */
    _Alignas(32) double omag[GRID_PACKET_SIZE]; /* |O - ref|_1 */
    _Alignas(32) double d2[GRID_PACKET_SIZE];   /* |D|_2^2 */
    /* The slice walk along axis K (axis[0]); u = coordinates on axis[1],
     * axis[2] as u = u0 + s (z - z0). */
    _Alignas(32) double ok[GRID_PACKET_SIZE];     /* origin on K */
    /* w = kstep * z, the coordinate that grows along the walk. w_end: the
     * ray needs no slice beyond it: the nearest of its box exit (or t_far)
     * and its nearest hit so far, widened by their rounding. */
    _Alignas(32) double w_end[GRID_PACKET_SIZE];
    _Alignas(32) double zr[GRID_PACKET_SIZE];     /* where the ray starts on K, - z0, widened back */
    _Alignas(32) double u0[2][GRID_PACKET_SIZE];
    _Alignas(32) double s[2][GRID_PACKET_SIZE];
    _Alignas(32) double umag[2][GRID_PACKET_SIZE]; /* |o_u| + |s (z0 - o_K)|: rounding scale of u0 */
    float t[GRID_PACKET_SIZE]; /* nearest hit so far (t_far at first) */
    float u[GRID_PACKET_SIZE], v[GRID_PACKET_SIZE];
    uint32_t prim[GRID_PACKET_SIZE];
    accel_ray_prep prep[GRID_PACKET_SIZE]; /* made on a ray's first exact test */
    const accel_ray *rays;
    uint64_t live;    /* rays the single-ray kernel would trace */
    uint64_t active;  /* rays still walking */
    uint64_t prepped; /* prep[i] is made */
    uint64_t bounded; /* the bounds below hold over these rays (>= active) */
    uint32_t n, boxes; /* rays; grid-box tests (counters) */
    double ref[3];
    int axis[3];      /* K, a1, a2 */
    int kstep;        /* +1 / -1: direction of the walk along K */
    int k_start;      /* first slice */
    double z0;        /* ref[K]: the coordinate u0 is taken at */
    double w_next;    /* min of w_end over the active rays */
    const double *dk; /* dx, dy or dz: the rays' K components */
    /* Bounds over `bounded`. */
    double u0_lo[2], u0_hi[2], s_lo[2], s_hi[2], umag_max[2];
    /* Rounding margins of the slice ranges and of the envelope cull (their
     * magnitudes bounded over the grid box: |z - z0| <= zext on K, |u| <=
     * umax[j] on axis[1 + j]). */
    double pad_span[2], pad_env[2], zext, umax[2], pad_cell[2];
    double d_lo[3], d_hi[3], m_lo[3], m_hi[3], emag_max, omag_max;
    int common;       /* all of them start at ref (M = 0) */
} grid_packet;

#if GRID_PACKET_AVX
/* All-ones lanes for the low 4 bits of `bits`. */
static inline __m256d grid_packet_lanes(uint64_t bits)
{
    const __m256i sel = _mm256_setr_epi64x(1, 2, 4, 8);
    const __m256i b = _mm256_and_si256(_mm256_set1_epi64x((long long)bits), sel);
    return _mm256_castsi256_pd(_mm256_cmpeq_epi64(b, sel));
}
#endif

enum { GRID_PACKET_EMPTY, GRID_PACKET_WALK, GRID_PACKET_SINGLE };

/* Prepares packet pk from rays[0..n-1] (n <= GRID_PACKET_SIZE) for a walk
 * of frame f (a regular grid, or a nested grid's top level) holding
 * ref_count references: the live rays (those the single-ray kernel traces:
 * valid, accepted by box3_slab against the grid box; none when ref_count is
 * 0), the axis K from their mean direction, the start slice, the arrays and
 * bounds. Returns GRID_PACKET_EMPTY when no ray is live, GRID_PACKET_SINGLE
 * when the live rays do not all move the same way along K or would sweep
 * more than max_cells cells of f per axis (GRID_PACKET_MAX_CELLS for the
 * regular grid) (the single-ray
 * kernel then traces the packet). The bounds' margins hold for every frame
 * inside f whose cells are no larger than f's (a nested grid's levels). */
int grid_packet_setup(const grid_frame *f, uint64_t ref_count, double max_cells, grid_packet *pk,
                      const accel_ray *rays, uint32_t n);

/* Recomputes the bounds over the active rays. */
void grid_packet_bound(grid_packet *pk);

/* Cells [lo[j], hi[j]] on axis[1 + j] that slice k can touch: every point
 * of every active ray within the slice has its coordinate on axis[1 + j] in
 * [hull[j][0], hull[j][1]] (rounding included, plus 1/1024 of a cell), and
 * lies in those cells. Returns 0 when the range misses the grid. */
int grid_packet_span(const grid_frame *f, const grid_packet *pk, int k, int k_end, int lo[2],
                     int hi[2], double hull[2][2]);

#ifdef __cplusplus
}
#endif

#endif
