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
 * by query (WIDE_ANY 0 or 1: one unit each) and define wide_query[block 8]. The single-ray row
 * compiles all eight flag copies (ACCEL_V_OPT: order=octant or dist); the
 * octant rows (packets, streams, branchy, quantized) only the copies with
 * ACCEL_V_OPT set (WT_TABLE_OCT), and tri=naive once, with the spheres
 * flag read at run time: no experiment times these rows with the naive
 * test (its timed rows are every kind's default and the 8-wide single
 * rays), so the fourth full body per table was compile time for nothing.
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
/* A layer of its own, so that the pasted names are expanded before
 * ACCEL_KERNEL_TABLE pastes again. */
#define WT_TABLE(name, kernel) ACCEL_KERNEL_TABLE(name, kernel)
/* The rows other than single rays (packets, order=branchy, quant=1) always
 * trace in the octant order: their kernels never read ACCEL_V_OPT, so the
 * copies with it clear would be the copies with it set, compiled again.
 * Only the copies with OPT set are compiled; the OPT-clear entries name the
 * same functions (a packet tree built with order=dist selects them). The
 * naive test gets one copy (_vn) for both values of ACCEL_V_SPHERES. */
#define WT_TABLE_OCT(name, kernel) WT_TABLE_OCT_(name, kernel) /* expands the names first */
#define WT_TABLE_OCT_(NAME, KERNEL)                                                                 \
    ACCEL_KERNEL_COUNTED_(NAME, KERNEL)                                                             \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 4)                                                             \
    ACCEL_KERNEL_COPY_(NAME, KERNEL, 6)                                                             \
    static void NAME##_vn(const void *a, const accel_ray *r, void *o, size_t n, accel_counters *c,   \
                          unsigned f)                                                               \
    {                                                                                               \
        (void)c;                                                                                    \
        KERNEL(a, r, o, n, (accel_counters *)NULL,                                                  \
               (f & ACCEL_V_SPHERES) | ACCEL_V_OPT | ACCEL_V_NAIVE);                                 \
    }                                                                                               \
    static const accel_kernel_table NAME = {                                                        \
        NAME##_counted,                                                                             \
        {NAME##_v4, NAME##_vn, NAME##_v6, NAME##_vn, NAME##_v4, NAME##_vn, NAME##_v6, NAME##_vn}};
#define WT_BOTH_(table, name, kernel)                                                               \
    table(WT_CAT(name, WIDE_NW, 4), WT_CAT(kernel, WIDE_NW, 4))                                    \
    table(WT_CAT(name, WIDE_NW, 8), WT_CAT(kernel, WIDE_NW, 8))
#define WT_BOTH(name, kernel) WT_BOTH_(WT_TABLE, name, kernel)
#define WT_BOTH_OCT(name, kernel) WT_BOTH_(WT_TABLE_OCT, name, kernel)
#define WT_ROW(closest, any)                                                                        \
    {{&WT_CAT(closest, WIDE_NW, 4), &WT_CAT(closest, WIDE_NW, 8)},                                 \
     {&WT_CAT(any, WIDE_NW, 4), &WT_CAT(any, WIDE_NW, 8)}}

#if WIDE_ROW == WIDE_ROW_SINGLE
WT_BOTH(closest, wide_closest)
WT_BOTH(any, wide_any)
static const accel_kernel_table *const wide_row[2][2] = WT_ROW(closest, any);
#elif WIDE_ROW == WIDE_ROW_PACKET && !WIDE_ANY
WT_BOTH_OCT(pclosest, wide_pclosest)
static const accel_kernel_table *const wide_query[2] = {&WT_CAT(pclosest, WIDE_NW, 4),
                                                        &WT_CAT(pclosest, WIDE_NW, 8)};
#elif WIDE_ROW == WIDE_ROW_PACKET
WT_BOTH_OCT(pany, wide_pany)
static const accel_kernel_table *const wide_query[2] = {&WT_CAT(pany, WIDE_NW, 4),
                                                        &WT_CAT(pany, WIDE_NW, 8)};
#elif WIDE_ROW == WIDE_ROW_STREAM && !WIDE_ANY
WT_BOTH_OCT(sclosest, wide_sclosest)
static const accel_kernel_table *const wide_query[2] = {&WT_CAT(sclosest, WIDE_NW, 4),
                                                        &WT_CAT(sclosest, WIDE_NW, 8)};
#elif WIDE_ROW == WIDE_ROW_STREAM
WT_BOTH_OCT(sany, wide_sany)
static const accel_kernel_table *const wide_query[2] = {&WT_CAT(sany, WIDE_NW, 4),
                                                        &WT_CAT(sany, WIDE_NW, 8)};
#elif WIDE_ROW == WIDE_ROW_BRANCHY
WT_BOTH_OCT(bclosest, wide_closest_br)
WT_BOTH_OCT(bany, wide_any_br)
static const accel_kernel_table *const wide_row[2][2] = WT_ROW(bclosest, bany);
#elif WIDE_ROW == WIDE_ROW_QUANT && WIDE_NW == 8
WT_BOTH_OCT(qclosest, wide_closest_q)
WT_BOTH_OCT(qany, wide_any_q)
static const accel_kernel_table *const wide_row[2][2] = WT_ROW(qclosest, qany);
#else
#error "tables.h: WIDE_ROW names no row of this width"
#endif

#undef WT_ROW
#undef WT_BOTH_OCT
#undef WT_BOTH
#undef WT_BOTH_
#undef WT_TABLE_OCT
#undef WT_TABLE_OCT_
#undef WT_TABLE
#undef WT_CAT
#undef WT_CAT_
