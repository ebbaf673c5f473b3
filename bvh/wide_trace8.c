/*
 * wide_trace8.c - the 8-wide BVH's kernel tables (core/variant.h), one per
 * block size and query, compiled from the templates wide_leaf.h and
 * wide_kernel.h / wide_packet.h. A translation unit apart from the 4-wide
 * kernels (wide_trace.c) so that the two compile in parallel: each takes
 * about half a minute of forced inlining.
 */
#include "wide_node.h"

#define WIDE_LB 4
#include "wide_leaf.h"
#undef WIDE_LB
#define WIDE_LB 8
#include "wide_leaf.h"
#undef WIDE_LB

#define WIDE_NW 8
#define WIDE_LB 4
#include "wide_kernel.h"
#include "wide_packet.h"
#undef WIDE_LB
#define WIDE_LB 8
#include "wide_kernel.h"
#include "wide_packet.h"
#undef WIDE_LB
#undef WIDE_NW

ACCEL_KERNEL_TABLE(closest_8_4, wide_closest_8_4)
ACCEL_KERNEL_TABLE(closest_8_8, wide_closest_8_8)
ACCEL_KERNEL_TABLE(any_8_4, wide_any_8_4)
ACCEL_KERNEL_TABLE(any_8_8, wide_any_8_8)
ACCEL_KERNEL_TABLE(bclosest_8_4, wide_closest_br_8_4)
ACCEL_KERNEL_TABLE(bclosest_8_8, wide_closest_br_8_8)
ACCEL_KERNEL_TABLE(bany_8_4, wide_any_br_8_4)
ACCEL_KERNEL_TABLE(bany_8_8, wide_any_br_8_8)
ACCEL_KERNEL_TABLE(qclosest_8_4, wide_closest_q_8_4)
ACCEL_KERNEL_TABLE(qclosest_8_8, wide_closest_q_8_8)
ACCEL_KERNEL_TABLE(qany_8_4, wide_any_q_8_4)
ACCEL_KERNEL_TABLE(qany_8_8, wide_any_q_8_8)
ACCEL_KERNEL_TABLE(pclosest_8_4, wide_pclosest_8_4)
ACCEL_KERNEL_TABLE(pclosest_8_8, wide_pclosest_8_8)
ACCEL_KERNEL_TABLE(pany_8_4, wide_pany_8_4)
ACCEL_KERNEL_TABLE(pany_8_8, wide_pany_8_8)

/* [single | packets | single with order=branchy | quantized][any hit][block 8] */
static const accel_kernel_table *const tables8[4][2][2] = {
    {{&closest_8_4, &closest_8_8}, {&any_8_4, &any_8_8}},
    {{&pclosest_8_4, &pclosest_8_8}, {&pany_8_4, &pany_8_8}},
    {{&bclosest_8_4, &bclosest_8_8}, {&bany_8_4, &bany_8_8}},
    {{&qclosest_8_4, &qclosest_8_8}, {&qany_8_4, &qany_8_8}},
};

const accel_kernel_table *bvh_wide_kernels8(int row, int any_hit, int block8)
{
    return tables8[row][any_hit][block8];
}
