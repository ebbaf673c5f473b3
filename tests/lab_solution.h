/*
 * lab_solution.h - the lab's reference solution (tests/lab_solution.c: the
 * starter with its four functions written) and its mutant students: each
 * mutant is one typical mistake, switched on at run time by
 * lab_solution_mutant, so that one compile serves them all. tests/test_lab.c
 * asserts the reference passes every step and each mutant fails its own.
 */
#ifndef TESTS_LAB_SOLUTION_H
#define TESTS_LAB_SOLUTION_H

#include "accel.h"

typedef enum {
    LM_NONE, /* the reference solution */
    /* step 1: the build */
    LM_LEAF_START,     /* a leaf's left_first is its node index, not `first` */
    LM_EMPTY_LEAF,     /* a box-middle split that leaves an empty child as a leaf */
    LM_CENTROID_BOX,   /* node boxes from the primitives' centroids */
    LM_FIRST_PRIM_BOX, /* node boxes from each node's first primitive */
    LM_LOST_PRIM,      /* the right child gets count/2 primitives: odd counts lose one */
    LM_NO_LEAF_COUNT,  /* leaves never counted (the statistics say: no tree) */
    LM_LEAF_SWAP,      /* a leaf's left_first and count swapped */
    LM_ROOT_BOX,       /* every node's box is the root's: valid, and useless (step 2's rule) */
    LM_LEAF_RECURSE,   /* a leaf when count < leaf, no depth guard: leaf=1 recurses forever */
    /* step 2: single rays */
    LM_CULL_LT,     /* a popped node culled with entry < t */
    LM_CULL_LE,     /* ... with entry <= t */
    LM_NO_FAR_PUSH, /* the far child is never pushed */
    LM_FIRST_HIT,   /* closest hit: stops at the first leaf that hits */
    LM_POP_EMPTY,   /* pops without asking whether the stack is empty */
    LM_NO_STEPS,    /* counts no node visits */
    LM_OWN_ORDER_ID, /* reports the hit's position in order[], not the triangle's id */
    LM_NO_PRIM_COUNT, /* primitive tests never counted */
    LM_LEAVES_ONLY,   /* node visits counted at leaves only */
    LM_SMALL_STACK,   /* a traversal stack of 8 entries (caught under AddressSanitizer) */
    /* step 2's quality rule: correct but slow */
    LM_FAR_FIRST, /* the farther child first */
    LM_NO_ORDER,  /* always the left child first */
    LM_NO_SHRINK, /* boxes tested against the ray's t_far, no pop cull */
    LM_NO_SORT,   /* the median split never sorts: halves in arbitrary order */
    LM_SPLIT_DEPTH, /* the split axis by depth (x, y, z, ...): not in test_lab.c's table, it
                    * measures 0.85-1.07x as the solution does (0.88-1.06x) */
    LM_ANY_HIT_ALL, /* occluded() keeps searching for the closest hit */
    /* step 3: the walk */
    LM_WALK_ALL,      /* every primitive handed over, the tree ignored */
    LM_WALK_NO_PAD,   /* boxes not grown by pad */
    LM_WALK_PRIM_HIT, /* only primitives its own triangle test hits */
    LM_WALK_T_ONE,    /* boxes tested against [t_near, 1] */
    LM_WALK_NO_STEPS, /* the walk counts no node visits */
    LM_WALK_NO_SHRINK, /* boxes against the ray's t_far: t_max never shrinks the walk */
    /* step 4: packets */
    LM_PACKET_FAKE,       /* single rays, packet_steps += 1 per packet */
    LM_PACKET_CULL_LT,    /* a lane enters a box when its entry < t */
    LM_PACKET_FIRST_ONLY, /* only the first active lane's box test decides */
    LM_PACKET_NO_COUNT,   /* packet_steps never counted */
    LM_PACKET_PER_LANE,   /* packet_steps counted once per active lane, not per packet */
    LM_PACKET_UNINIT,     /* lanes that miss keep an uninitialized (stale) hit */
    /* step 7 (optional): the top level */
    LM_TOP_FORWARD,        /* the object -> world matrix instead of its inverse */
    LM_TOP_DIR_MOVED,      /* the direction moved by the translation too */
    LM_TOP_NORMALIZE,      /* the object direction renormalized: t not in world units */
    LM_TOP_FIRST_INSTANCE, /* stops at the first instance hit, not the nearest */
    LM_COUNT
} lab_mutant_id;

/* The mutant the reference kind behaves as (LM_NONE: the reference). */
extern int lab_solution_mutant;
extern const accel_kind accel_kind_lab_solution;

#endif
