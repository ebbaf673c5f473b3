/*
 * tables.h - one row of one width's kernel tables (core/variant.h).
 * A kernel body (C only), included once per translation unit with WIDE_NW
 * (4 or 8) and WIDE_ROW (the row: WIDE_ROW_SINGLE, _PACKET, _BRANCHY,
 * _QUANT, _STREAM) defined: by the k<width>_<row>.c files, one unit per row so
 * that a 2-core build spreads the forced inlining over seven units of
 * similar size instead of two large ones (trace.c dispatches).
 *
 * It instantiates the templates core/block_test.h (blocks of 4 and 8), kernel.h and,
 * for the packet row, packet.h (for the stream row, stream.h; width
 * WIDE_NW, blocks of 4 and 8) and defines wide_row[any hit][block 8] for
 * its row; the packet and stream rows, the largest, are split once more
 * by query (WIDE_ANY 0 or 1: one unit each) and define wide_query[block 8].
 * Each table compiles its counted copy and the timed copies of the flag
 * combinations the experiments time (WT_K*, below); the others run the
 * counted copy with counters off.
 */
#include "node.h"

#define WIDE_LB 4
#include "core/block_test.h"
#undef WIDE_LB
#define WIDE_LB 8
#include "core/block_test.h"
#undef WIDE_LB

#define WIDE_LB 4
#include "kernel.h"
#if WIDE_ROW == WIDE_ROW_PACKET
#include "packet.h"
#elif WIDE_ROW == WIDE_ROW_STREAM
#include "stream.h"
#endif
#undef WIDE_LB
#define WIDE_LB 8
#include "kernel.h"
#if WIDE_ROW == WIDE_ROW_PACKET
#include "packet.h"
#elif WIDE_ROW == WIDE_ROW_STREAM
#include "stream.h"
#endif
#undef WIDE_LB

#define WT_CAT_(a, n, b) a##_##n##_##b
#define WT_CAT(a, n, b) WT_CAT_(a, n, b)
/* The copies compiled per table (core/variant.h, ACCEL_KERNEL_TABLE_SEL):
 * the flag combinations the experiments time, index = flags (1 naive,
 * 2 spheres, 4 ACCEL_V_OPT); every other one runs the counted copy with
 * counters off, the same hits bit for bit. block=auto gives triangle
 * scenes blocks of 8 and sphere scenes blocks of 4, so a table of blocks
 * of 8 is timed with index 4 (the octant order, which every row but single
 * rays with order=dist uses) and its naive twin 5 (exp_error_time,
 * exp_stability), a table of blocks of 4 with 6 (spheres); exp_wide times
 * block=4 on triangle scenes too (index 4: single rays and order=branchy).
 * Never timed, so no copy (issue 53's GRIDBVH_KLOG runs of make test, the
 * quick report and every experiment on its full scenes): order=dist
 * (indices 0-3), block 8 with spheres, the naive test with spheres (3, 7),
 * the any-hit queries' naive test, the naive test on blocks of 4. */
#define WT_K8_HIT (0, 0, 0, 0, 1, 1, 0, 0)
#define WT_K8_ANY (0, 0, 0, 0, 1, 0, 0, 0)
#define WT_K4_OCT (0, 0, 0, 0, 1, 0, 1, 0)
#define WT_K4_SPH (0, 0, 0, 0, 0, 0, 1, 0)
#define WT_TABLE(NAME, KERNEL, KEEP) ACCEL_KERNEL_TABLE_SEL(NAME, KERNEL, KEEP)
/* One query's tables for blocks of 4 and of 8. */
#define WT_BOTH(name, kernel, keep4, keep8)                                                         \
    WT_TABLE(WT_CAT(name, WIDE_NW, 4), WT_CAT(kernel, WIDE_NW, 4), keep4)                          \
    WT_TABLE(WT_CAT(name, WIDE_NW, 8), WT_CAT(kernel, WIDE_NW, 8), keep8)
#define WT_ROW(closest, any)                                                                        \
    {{&WT_CAT(closest, WIDE_NW, 4), &WT_CAT(closest, WIDE_NW, 8)},                                 \
     {&WT_CAT(any, WIDE_NW, 4), &WT_CAT(any, WIDE_NW, 8)}}

#if WIDE_ROW == WIDE_ROW_SINGLE
WT_BOTH(closest, wide_closest, WT_K4_OCT, WT_K8_HIT)
WT_BOTH(any, wide_any, WT_K4_OCT, WT_K8_ANY)
static const accel_kernel_table *const wide_row[2][2] = WT_ROW(closest, any);
#elif WIDE_ROW == WIDE_ROW_PACKET && !WIDE_ANY
WT_BOTH(pclosest, wide_pclosest, WT_K4_SPH, WT_K8_HIT)
static const accel_kernel_table *const wide_query[2] = {&WT_CAT(pclosest, WIDE_NW, 4),
                                                        &WT_CAT(pclosest, WIDE_NW, 8)};
#elif WIDE_ROW == WIDE_ROW_PACKET
WT_BOTH(pany, wide_pany, WT_K4_SPH, WT_K8_ANY)
static const accel_kernel_table *const wide_query[2] = {&WT_CAT(pany, WIDE_NW, 4),
                                                        &WT_CAT(pany, WIDE_NW, 8)};
#elif WIDE_ROW == WIDE_ROW_STREAM && !WIDE_ANY
WT_BOTH(sclosest, wide_sclosest, WT_K4_SPH, WT_K8_HIT)
static const accel_kernel_table *const wide_query[2] = {&WT_CAT(sclosest, WIDE_NW, 4),
                                                        &WT_CAT(sclosest, WIDE_NW, 8)};
#elif WIDE_ROW == WIDE_ROW_STREAM
WT_BOTH(sany, wide_sany, WT_K4_SPH, WT_K8_ANY)
static const accel_kernel_table *const wide_query[2] = {&WT_CAT(sany, WIDE_NW, 4),
                                                        &WT_CAT(sany, WIDE_NW, 8)};
#elif WIDE_ROW == WIDE_ROW_BRANCHY
WT_BOTH(bclosest, wide_closest_br, WT_K4_OCT, WT_K8_ANY)
WT_BOTH(bany, wide_any_br, WT_K4_OCT, WT_K8_ANY)
static const accel_kernel_table *const wide_row[2][2] = WT_ROW(bclosest, bany);
#elif WIDE_ROW == WIDE_ROW_MIXED && WIDE_NW == 8
/* layout=mixed: the single-ray kernels on the one pool (WIDE_MIXED set by
 * the unit, k8_mixed.c) */
WT_BOTH(mclosest, wide_closest, WT_K4_OCT, WT_K8_HIT)
WT_BOTH(many, wide_any, WT_K4_OCT, WT_K8_ANY)
static const accel_kernel_table *const wide_row[2][2] = WT_ROW(mclosest, many);
#elif WIDE_ROW == WIDE_ROW_ANY && WIDE_NW == 8
/* any_order=octant|area|leaf: the any-hit kernel alone (trace.c asks this
 * row for any-hit queries only; its closest slot repeats the any table) */
WT_BOTH(fany, wide_any_fix, WT_K4_OCT, WT_K8_ANY)
static const accel_kernel_table *const wide_row[2][2] = WT_ROW(fany, fany);
#elif WIDE_ROW == WIDE_ROW_QUANT && WIDE_NW == 8
WT_BOTH(qclosest, wide_closest_q, WT_K4_SPH, WT_K8_ANY)
WT_BOTH(qany, wide_any_q, WT_K4_SPH, WT_K8_ANY)
static const accel_kernel_table *const wide_row[2][2] = WT_ROW(qclosest, qany);
#else
#error "tables.h: WIDE_ROW names no row of this width"
#endif

#undef WT_ROW
#undef WT_BOTH
#undef WT_TABLE
#undef WT_K8_HIT
#undef WT_K8_ANY
#undef WT_K4_OCT
#undef WT_K4_SPH
#undef WT_CAT
#undef WT_CAT_
