/*
 * igrid_opt.c - the two optimisation steps of the irregular grid
 * (Perard-Gayot, Kalojanov & Slusallek, EG 2017, sections 4.2 and 4.3):
 * merging cells by a surface-area cost, and expanding each cell's exit box
 * over neighbours whose primitives it already holds.
 *
 * Both work on the cells as built (igrid_bcells): original boxes on the
 * virtual lattice, sorted reference lists, and the voxel map to find the
 * cell of a voxel. Both are sequential and visit cells in index order, so
 * the result depends on the input alone.
 */
#include <stdlib.h>
#include <string.h>

#include "igrid_impl.h"

/* ---- merge ------------------------------------------------------------------------- */

/* Half the surface area of box bx (voxels) in world units. */
static double half_area(const grid_frame *f, const int32_t bx[6])
{
    double e[3];
    for (int a = 0; a < 3; a++) e[a] = (double)f->planes[a][bx[3 + a]] - f->planes[a][bx[a]];
    return e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
}

/* Size of the union of two sorted lists. */
static uint32_t union_count(const uint32_t *p, uint32_t n, const uint32_t *q, uint32_t m)
{
    uint32_t i = 0, j = 0, c = 0;
    while (i < n && j < m) {
        uint32_t a = p[i], b = q[j];
        i += a <= b;
        j += b <= a;
        c++;
    }
    return c + (n - i) + (m - j);
}

static void union_write(const uint32_t *p, uint32_t n, const uint32_t *q, uint32_t m, uint32_t *out)
{
    uint32_t i = 0, j = 0;
    while (i < n && j < m) {
        uint32_t a = p[i], b = q[j];
        *out++ = a <= b ? a : b;
        i += a <= b;
        j += b <= a;
    }
    while (i < n) *out++ = p[i++];
    while (j < m) *out++ = q[j++];
}

/*
 * One pass along `axis`: every live cell not yet merged in this pass is
 * merged with its neighbour across its high face when that neighbour has
 * the same cross-section, was not merged in this pass either, and the cost
 * test passes. fwd[n] records where a merged-away cell went (the map is
 * renumbered once per round, by compact()). Returns the number of merges,
 * or -1 when out of memory.
 */
static long merge_pass(igrid_bcells *b, int axis, double ct, uint8_t *alive, uint8_t *busy,
                       uint32_t *fwd)
{
    const grid_frame *f = b->frame;
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    long merges = 0;
    memset(busy, 0, b->count);
    for (uint32_t c = 0; c < b->count; c++) {
        if (!alive[c] || busy[c]) continue;
        int32_t *bc = b->box[c];
        if (bc[3 + axis] >= f->res[axis]) continue;
        int v[3];
        v[axis] = bc[3 + axis];
        v[a1] = bc[a1];
        v[a2] = bc[a2];
        uint32_t n = igrid_bcell_at(b, v[0], v[1], v[2]);
        while (!alive[n]) n = fwd[n]; /* merged earlier in this round */
        if (busy[n]) continue;
        const int32_t *bn = b->box[n];
        if (bn[axis] != bc[3 + axis] || bn[a1] != bc[a1] || bn[3 + a1] != bc[3 + a1] ||
            bn[a2] != bc[a2] || bn[3 + a2] != bc[3 + a2])
            continue;
        int32_t u[6];
        memcpy(u, bc, sizeof u);
        u[3 + axis] = bn[3 + axis];
        uint32_t n1 = b->len[c], n2 = b->len[n];
        double a_c = half_area(f, bc), a_n = half_area(f, bn), a_u = half_area(f, u);
        double split = a_c * (n1 + ct) + a_n * (n2 + ct);
        /* The union holds at least the larger list: a cheap early out. */
        if (a_u * ((n1 > n2 ? n1 : n2) + ct) > split) continue;
        uint32_t nu = union_count(b->list[c], n1, b->list[n], n2);
        if (a_u * (nu + ct) > split) continue;
        uint32_t *list = NULL;
        if (nu > n1) {
            list = malloc((size_t)nu * sizeof *list);
            if (!list) return -1;
            union_write(b->list[c], n1, b->list[n], n2, list);
            if (b->owned[c]) free(b->list[c]);
            b->list[c] = list;
            b->owned[c] = 1;
        }
        /* nu == n1: n's list is a subset of c's, which stays as it is. */
        if (b->owned[n]) free(b->list[n]);
        b->list[n] = NULL;
        b->owned[n] = 0;
        b->len[n] = 0;
        b->len[c] = nu;
        bc[3 + axis] = bn[3 + axis];
        alive[n] = 0;
        busy[c] = busy[n] = 1;
        fwd[n] = c;
        merges++;
    }
    return merges;
}

/* Drops the merged-away cells: renumbers the live ones in order and points
 * the map's leaves at the new numbers. */
static void compact(igrid_bcells *b, const uint8_t *alive, const uint32_t *fwd, uint32_t *new_id)
{
    uint32_t k = 0;
    for (uint32_t c = 0; c < b->count; c++) {
        if (!alive[c]) continue;
        new_id[c] = k;
        memcpy(b->box[k], b->box[c], sizeof b->box[0]);
        b->list[k] = b->list[c];
        b->len[k] = b->len[c];
        b->owned[k] = b->owned[c];
        k++;
    }
    for (uint64_t i = 0; i < b->map_len; i++) {
        uint32_t e = b->map[i];
        if (e & 1u) continue;
        uint32_t c = e >> 1;
        while (!alive[c]) c = fwd[c]; /* a cell merges once per pass: at most 3 links */
        b->map[i] = new_id[c] << 1;
    }
    b->count = k;
}

int igrid_merge(igrid_bcells *b, double alpha, double ct, accel_error *err)
{
    if (b->count == 0) return ACCEL_OK;
    uint8_t *alive = malloc(b->count), *busy = malloc(b->count);
    uint32_t *fwd = malloc((size_t)b->count * sizeof *fwd);
    uint32_t *new_id = malloc((size_t)b->count * sizeof *new_id);
    int rc = ACCEL_OK;
    if (!alive || !busy || !fwd || !new_id) {
        rc = accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory for the merge");
        goto done;
    }
    for (;;) {
        uint32_t before = b->count;
        long merges = 0;
        memset(alive, 1, b->count);
        for (int axis = 0; axis < 3; axis++) {
            long m = merge_pass(b, axis, ct, alive, busy, fwd);
            if (m < 0) {
                rc = accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory for the merge");
                goto done;
            }
            merges += m;
        }
        if (merges > 0) compact(b, alive, fwd, new_id);
        /* Another round while this one removed at least 1-alpha of the cells. */
        if (!((double)b->count < alpha * before)) break;
    }
done:
    free(alive);
    free(busy);
    free(fwd);
    free(new_id);
    return rc;
}

/* ---- expansion ----------------------------------------------------------------------- */

/* Whether sorted list p (n ids) is a subset of sorted list q (m ids). */
static int is_subset(const uint32_t *p, uint32_t n, const uint32_t *q, uint32_t m)
{
    if (n > m) return 0;
    uint32_t j = 0;
    for (uint32_t i = 0; i < n; i++) {
        while (j < m && q[j] < p[i]) j++;
        if (j == m || q[j] != p[i]) return 0;
        j++;
    }
    return 1;
}

/*
 * How many voxel layers the exit box of cell c can grow across its face on
 * `axis` (high side if hi, else low side): the face is tiled by the exit
 * boxes of the cells beyond it (each found through the map at one voxel of
 * the layer next to the face, and skipped over by its own extent); each
 * must hold a subset of c's primitives, and the growth stays within every
 * one of them.
 */
static int face_growth(const igrid_bcells *b, uint32_t c, int axis, int hi)
{
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    const int32_t *e = b->exit[c];
    int layer = hi ? e[3 + axis] : e[axis] - 1;
    if (layer < 0 || layer >= b->frame->res[axis]) return 0;
    int d = b->frame->res[axis];
    int v[3];
    v[axis] = layer;
    for (int j = e[a2]; j < e[3 + a2];) {
        int k2 = b->frame->res[a2];
        for (int i = e[a1]; i < e[3 + a1];) {
            v[a1] = i;
            v[a2] = j;
            uint32_t n = igrid_bcell_at(b, v[0], v[1], v[2]);
            if (!is_subset(b->list[n], b->len[n], b->list[c], b->len[c])) return 0;
            const int32_t *en = b->exit[n];
            int depth = hi ? en[3 + axis] - layer : layer + 1 - en[axis];
            d = depth < d ? depth : d;
            k2 = en[3 + a2] - j < k2 ? en[3 + a2] - j : k2;
            i = en[3 + a1];
        }
        j += k2;
    }
    return d;
}

/* A face that could not grow once is not tried again (bit 2*axis + hi of
 * blocked[c]): its neighbours could only let it grow if their own exit
 * boxes grew over the one that blocked it, a gain too rare for a whole
 * face walk per pass. */
int igrid_expand(igrid_bcells *b, int passes, accel_error *err)
{
    if (passes == 0 || b->count == 0) return ACCEL_OK;
    uint8_t *blocked = calloc(b->count, 1);
    if (!blocked) return accel_fail(err, ACCEL_ERR_NOMEM, "irregular_grid: out of memory");
    for (int p = 0; p < passes; p++) {
        int grown = 0;
        for (int axis = 0; axis < 3; axis++)
            for (uint32_t c = 0; c < b->count; c++)
                for (int hi = 0; hi < 2; hi++) {
                    uint8_t bit = (uint8_t)(1u << (2 * axis + hi));
                    if (blocked[c] & bit) continue;
                    int d = face_growth(b, c, axis, hi);
                    if (!d) blocked[c] |= bit;
                    if (hi)
                        b->exit[c][3 + axis] += d;
                    else
                        b->exit[c][axis] -= d;
                    grown |= d;
                }
        if (!grown) break;
    }
    free(blocked);
    return ACCEL_OK;
}
