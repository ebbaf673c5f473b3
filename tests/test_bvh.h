/*
 * test_bvh.h - what the BVH test files share, defined in test_bvh.c.
 */
#ifndef TESTS_TEST_BVH_H
#define TESTS_TEST_BVH_H

#include "bvh/bvh.h"
#include "support.h"

/* The four builders, as specs: binned SAH, full-sweep SAH, middle, median. */
enum { TEST_BVH_BUILDERS = 4 };
extern const char *const test_bvh_builders[TEST_BVH_BUILDERS];

/*
 * The structural invariants of a built pool: 64-byte alignment; node 1
 * unused; children pairs at even indices after their parent, each node
 * reached exactly once; boxes nest; leaves tile the slot array in order
 * and hold at most max_leaf primitives; the slots are a permutation of the
 * live primitives; depth within BVH_MAX_DEPTH and as reported.
 */
void test_bvh_check_pool(const accel_scene *s, const void *a, int max_leaf, const char *spec);

#endif
