/*
 * k8_stream_hit.c - the 8-wide ray stream kernels (traverse=stream)
 * for closest hits: tables.h for one width, row and query, a unit of its own
 * (tables.h says why).
 */
#define WIDE_NW 8
#define WIDE_ROW WIDE_ROW_STREAM
#define WIDE_ANY 0
#include "tables.h"

const accel_kernel_table *WIDE_UNIT(bvh_wide_k8_stream_hit)(int block8)
{
    return wide_query[block8];
}
