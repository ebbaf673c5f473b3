/*
 * igrid_top.c - what the irregular grid's subdivision starts from
 * (igrid_build.c): the top grid's resolution, and the groups of coincident
 * primitives the subdivision treats as one (Perard-Gayot, Kalojanov &
 * Slusallek, EG 2017, section 4.1: the top grid by the resolution rule;
 * the octrees below it are driven by primitive counts, which copies of
 * one primitive inflate without adding anything a split could separate).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "igrid_impl.h"

/*
 * The top grid: the resolution rule at top_lambda over `count` primitives,
 * with no cell longer than twice its middle side. The octree refines a top
 * cell's three axes together (2x2x2 per level) to a depth set by its
 * longest one, so a needle-shaped cell gets its short axes refined as finely
 * as its long one: (2^depth)^2 times the cells its cross-section needs. The
 * rule's cells are near-cubic, except where it retires thin axes (a
 * flat slab keeps square cells; a needle, two thin axes, gets cells as long
 * as the whole scene's length over lambda*N: a sphere stretched 1e4 times,
 * 2 x 217 x 2, cut into 64 voxels along each axis: 1.75 GB for 768
 * triangles).
 * Such a long axis gets cells as long as the middle side instead. `box` is
 * the frame's (flat axes widened), `bounds` the scene's.
 */
void igrid_top_resolution(box3 bounds, box3 box, uint32_t count, double lambda, int t[3])
{
    grid_resolution(bounds, (double)count, lambda, t);
    const double ext[3] = {(double)box.max.x - box.min.x, (double)box.max.y - box.min.y,
                           (double)box.max.z - box.min.z};
    double side[3];
    int a_long = 0;
    for (int a = 0; a < 3; a++) {
        side[a] = ext[a] / t[a];
        if (side[a] > side[a_long]) a_long = a;
    }
    double mid = 0.0;
    for (int a = 0; a < 3; a++)
        if (a != a_long && side[a] > mid) mid = side[a];
    if (mid > 0.0 && side[a_long] > 2.0 * mid) {
        double n = ceil(ext[a_long] / mid);
        t[a_long] = n > GRID_MAX_AXIS_RES ? GRID_MAX_AXIS_RES : (int)n;
    }
}

/* A primitive's geometry as a sort key: a triangle's vertices in a
 * canonical order (any rotation or reflection of the same three points is
 * the same triangle), or a sphere's centre and radius. */
typedef struct {
    float key[9];
    uint32_t kind, id;
} prim_key;

static int cmp_key(const void *a, const void *b)
{
    const prim_key *x = a, *y = b;
    if (x->kind != y->kind) return x->kind < y->kind ? -1 : 1;
    int c = memcmp(x->key, y->key, sizeof x->key);
    if (c) return c;
    return (x->id > y->id) - (x->id < y->id);
}

static int cmp_vertex(const void *a, const void *b) { return memcmp(a, b, 3 * sizeof(float)); }

static int same_geometry(const prim_key *a, const prim_key *b)
{
    return a->kind == b->kind && !memcmp(a->key, b->key, sizeof a->key);
}

/*
 * Coincident copies: primitives with the same geometry, bit for bit (a
 * mesh's duplicate faces, an instance placed many times over itself). No
 * split can separate them, and a count-driven subdivision takes them for a
 * dense cluster: it splits every node they touch down to the depth their
 * number asks for, each leaf holding all of them (1000 copies of one
 * triangle: minutes and gigabytes). The subdivision therefore runs on one
 * representative per group (the smallest id) and a leaf's list is expanded
 * to every copy of its representatives: the same membership (the copies'
 * geometry is the representative's), the octree of the distinct geometry.
 * Returns 0 with *reps = NULL when all primitives are distinct (nothing
 * changes), else the representatives (ascending) in *reps and, per local
 * id r, its group in copies[copy_off[r] .. copy_off[r+1]) (empty for a
 * non-representative). ACCEL_ERR_NOMEM on allocation failure.
 */
int igrid_group_copies(const accel_scene *s, uint32_t **reps, uint32_t *rep_count,
                        uint32_t **copy_off, uint32_t **copies)
{
    const uint32_t n = s->prim_count;
    *reps = *copy_off = *copies = NULL;
    *rep_count = n;
    if (n < 2) return ACCEL_OK;
    prim_key *k = malloc((size_t)n * sizeof *k);
    if (!k) return ACCEL_ERR_NOMEM;
    for (uint32_t i = 0; i < n; i++) {
        memset(&k[i], 0, sizeof k[i]);
        k[i].id = i;
        if (i < s->tri_count) {
            memcpy(k[i].key, s->tris + 9 * (size_t)i, 9 * sizeof(float));
            qsort(k[i].key, 3, 3 * sizeof(float), cmp_vertex);
        } else {
            k[i].kind = 1;
            memcpy(k[i].key, s->spheres + 4 * (size_t)(i - s->tri_count), 4 * sizeof(float));
        }
    }
    qsort(k, n, sizeof *k, cmp_key);
    uint32_t groups = 1;
    for (uint32_t i = 1; i < n; i++) groups += !same_geometry(&k[i - 1], &k[i]);
    if (groups == n) {
        free(k);
        return ACCEL_OK;
    }
    uint32_t *off = calloc((size_t)n + 1, sizeof *off), *list = malloc((size_t)n * sizeof *list),
             *r = malloc((size_t)groups * sizeof *r);
    if (!off || !list || !r) {
        free(k), free(off), free(list), free(r);
        return ACCEL_ERR_NOMEM;
    }
    /* Group sizes at their representatives, prefix sum, then the members
     * (in id order within a group: the sort's tie-break). */
    for (uint32_t i = 0, rep = 0; i < n; i++) {
        if (i == 0 || !same_geometry(&k[i - 1], &k[i])) rep = k[i].id;
        off[rep + 1]++;
    }
    uint32_t g = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (off[i + 1]) r[g++] = i;
        off[i + 1] += off[i];
    }
    for (uint32_t i = 0, rep = 0, at = 0; i < n; i++) {
        if (i == 0 || !same_geometry(&k[i - 1], &k[i])) {
            rep = k[i].id;
            at = off[rep];
        }
        list[at++] = k[i].id;
    }
    free(k);
    *reps = r;
    *rep_count = groups;
    *copy_off = off;
    *copies = list;
    return ACCEL_OK;
}
