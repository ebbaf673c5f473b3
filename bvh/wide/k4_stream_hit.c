/*
 * k4_stream_hit.c - the 4-wide ray stream kernels (traverse=stream)
 * for closest hits: tables.h for one width, row and query, a unit of its own
 * (tables.h says why).
 */
#define WIDE_NW 4
#define WIDE_ROW WIDE_ROW_STREAM
#define WIDE_ANY 0
#include "tables.h"

const accel_kernel_table *WIDE_UNIT(bvh_wide_k4_stream_hit)(int block8)
{
    return wide_query[block8];
}
