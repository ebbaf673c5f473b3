/*
 * oracle_bvh.h - the culling tree of the exact oracle (private to
 * core/oracle.c and core/oracle_build.c; the interface is in accel.h).
 *
 * A binary BVH over the live primitives whose coordinates are all finite,
 * built with binned SAH (Wald, "On fast Construction of SAH-based Bounding
 * Volume Hierarchies", 2007). It only decides which primitives the
 * double-precision tests of core/prim.h are run on; why that never loses a
 * hit the brute-force oracle reports is argued in core/oracle.c.
 */
#ifndef ACCEL_ORACLE_BVH_H
#define ACCEL_ORACLE_BVH_H

#include <assert.h>
#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

/* 32 bytes. Boxes are the exact float bounds of the vertices (min and max
 * of floats round nothing); sphere boxes are rounded outward. */
typedef struct {
    float lo[3], hi[3];
    uint32_t index; /* interior: first child, the second is index + 1; leaf: first item */
    uint32_t count; /* low 31 bits: leaf items (> 0), 0 for interior; top bit: ORACLE_SPHERES */
} oracle_node;
static_assert(sizeof(oracle_node) == 32, "oracle_node is 32 bytes");

/* Set on a node whose subtree holds a sphere: such a node is culled by the
 * line test alone, never by distance (see oracle.c). */
#define ORACLE_SPHERES 0x80000000u

/* A primitive to test: its id, and its position in scene->live, which
 * decides ties exactly as the brute-force loop's visiting order does. */
typedef struct {
    uint32_t prim, pos;
} oracle_item;

struct accel_oracle {
    const accel_scene *scene; /* borrowed: must outlive the oracle */
    oracle_node *nodes;       /* nodes[0] is the root; NULL when no finite primitive */
    uint32_t node_count;
    int depth;                /* levels below the root: bounds the traversal stack */
    oracle_item *items;       /* in leaf order */
    uint32_t item_count;
    oracle_item *always;      /* live primitives with a non-finite coordinate: */
    uint32_t always_count;    /* tested against every ray, as brute force does */
    double scale;             /* largest |coordinate| of the root box */
};

/* Builds o->nodes, o->items, o->always, o->scale from o->scene. */
int oracle_bvh_build(accel_oracle *o, accel_error *err);

#ifdef __cplusplus
}
#endif

#endif
