/*
 * inst_kind.c - the `instanced` kind's table, parameters and build: one
 * bottom level per mesh (object space, shared by all the mesh's
 * instances), one top level over the instances' world bounds, and the
 * per-instance data (inverse matrix, the pad that covers the flattening's
 * rounding). See README.md for why the pads make the result exact.
 *
 * A plain scene (no instance description) is one identity instance of
 * itself: the kind is then a plain BVH or grid over the scene.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/isa.h"
#include "core/prim.h"
#include "inst_impl.h"
#include "instanced.h"

/* The kind's parameters as parsed, one field per key; choices hold their
 * position in the table's list (top: bvh 0, grid 1; world: blocks 0, compute 1). */
typedef struct {
    int top, leaf, world, pad, width, traverse, isa;
    double lambda, top_lambda;
    char bottom[ACCEL_PARAM_TEXT];
} inst_spec;

static const accel_param_def inst_params[] = {
    {.key = "top", .type = ACCEL_PARAM_ENUM, .def = "bvh", .choices = "bvh|grid",
     .help = "top level over the instances' world bounds: binned-SAH BVH or uniform grid",
     .offset = offsetof(inst_spec, top)},
    {.key = "bottom", .type = ACCEL_PARAM_STR, .def = "bvh",
     .help = "bottom level per mesh, object space, shared by its instances: bvh or grid (the "
             "kind's own), or any kind with a walk: <kind> or <kind>:key=value;key=value (';' "
             "for ','), e.g. nested_grid, bvh:width=4",
     .offset = offsetof(inst_spec, bottom)},
    {.key = "leaf", .type = ACCEL_PARAM_INT, .def = "4", .min = 1, .max = 64,
     .help = "bottom=bvh: largest leaf (primitives)",
     .offset = offsetof(inst_spec, leaf)},
    {.key = "width", .type = ACCEL_PARAM_ENUM, .def = "8", .choices = "2|8",
     .help = "BVH levels (top=bvh, bottom=bvh): walked as the binary tree (2) or collapsed to "
             "8-wide nodes whose 8 boxes a ray tests at once (8); the same boxes and leaves",
     .offset = offsetof(inst_spec, width)},
    {.key = "traverse", .type = ACCEL_PARAM_ENUM, .def = "single", .choices = "single|packet",
     .help = "single: ray by ray; packet: 64 rays walk both 8-wide BVH levels together, each "
             "ray testing each world block of a leaf with the shared block test (needs top=bvh, "
             "bottom=bvh, width=8; any ray order: core/coherence.h)",
     .offset = offsetof(inst_spec, traverse)},
    {.key = "lambda", .type = ACCEL_PARAM_FLOAT, .def = "2", .min = 0.01, .max = 64,
     .help = "bottom=grid: cells per primitive",
     .offset = offsetof(inst_spec, lambda)},
    {.key = "top_lambda", .type = ACCEL_PARAM_FLOAT, .def = "2", .min = 0.01, .max = 64,
     .help = "top=grid: cells per instance",
     .offset = offsetof(inst_spec, top_lambda)},
    {.key = "world", .type = ACCEL_PARAM_ENUM, .def = "blocks", .choices = "blocks|compute",
     .help = "world-space leaf blocks the shared block test decides: per-instance copies of the "
             "flattened triangles in the bottom level's leaf order, made at build and update "
             "(blocks: the memory of the flattened scene), or each leaf's object block taken to "
             "world space when a ray reaches it (compute: the flattener's expression, the same "
             "bits; a true two-level structure)",
     .offset = offsetof(inst_spec, world)},
    {.key = "pad", .type = ACCEL_PARAM_BOOL, .def = "1", .min = 0, .max = 1,
     .help = "grow bottom-level boxes by the flattening's rounding (0: exact object-space boxes, "
             "which miss world hits near edges: kept to show why the pad is needed)",
     .offset = offsetof(inst_spec, pad)},
    {.key = "isa", .type = ACCEL_PARAM_ENUM, .def = "auto", .choices = ACCEL_ISA_CHOICES,
     .help = "instruction set of the single-ray traversal (its wide node test is bvh/wide's): "
             "auto (AVX-512 where the CPU and the build have it, or GRIDBVH_ISA), avx2, avx512",
     .offset = offsetof(inst_spec, isa)},
};
#define INST_PARAM_COUNT (sizeof inst_params / sizeof inst_params[0])

static int is_identity(const double *m)
{
    static const double id[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    for (int i = 0; i < 12; i++)
        if (m[i] != id[i]) return 0;
    return 1;
}

/* Max row sum of the linear part: |A x|_inf <= norm * |x|_inf. */
static double row_norm(const double *m)
{
    double n = 0.0;
    for (int r = 0; r < 3; r++)
        n = fmax(n, fabs(m[4 * r]) + fabs(m[4 * r + 1]) + fabs(m[4 * r + 2]));
    return n;
}

static double box_abs_max(box3 b)
{
    if (box3_is_empty(b)) return 0.0;
    double m = 0.0;
    const float *lo = &b.min.x, *hi = &b.max.x;
    for (int a = 0; a < 3; a++) m = fmax(m, fmax(fabs(lo[a]), fabs(hi[a])));
    return m;
}

void inst_destroy(void *p)
{
    inst_accel *a = p;
    if (!a) return;
    for (uint32_t i = 0; i < a->bottom_count; i++) {
        bvh_box_tree_free(&a->bottoms[i].bvh);
        inst_wide_free(&a->bottoms[i].wide);
        inst_grid_free(&a->bottoms[i].grid);
        if (a->bottoms[i].walk) a->walk_kind->destroy(a->bottoms[i].walk);
        free(a->bottoms[i].dead);
    }
    for (uint32_t k = 0; a->items && k < a->item_count; k++) free(a->items[k].world);
    bvh_box_tree_free(&a->top_bvh);
    inst_wide_free(&a->top_wide);
    inst_grid_free(&a->top_grid);
    free(a->bottoms);
    free(a->items);
    free(a->item_boxes);
    free(a);
}

static size_t bvh_bytes(const bvh_box_tree *b)
{
    return (size_t)b->node_count * sizeof(bvh_node) + (size_t)b->count * sizeof(uint32_t);
}

static size_t grid_bytes(const inst_grid *g)
{
    return g->cells.offsets ? ((size_t)g->cells.cell_count + 1 + (size_t)g->cells.ref_count) *
                                      sizeof(uint32_t) +
                                  grid_plane_count(g->frame.res) * sizeof(float)
                            : 0;
}

size_t inst_memory(const void *p)
{
    const inst_accel *a = p;
    size_t bytes = sizeof *a + a->item_count * (sizeof(inst_item) + sizeof(box3)) +
                   a->bottom_count * sizeof(inst_bottom) + bvh_bytes(&a->top_bvh) +
                   inst_wide_memory(&a->top_wide) + grid_bytes(&a->top_grid);
    for (uint32_t i = 0; i < a->bottom_count; i++) {
        const inst_bottom *b = &a->bottoms[i];
        bytes += bvh_bytes(&b->bvh) + inst_wide_memory(&b->wide) + grid_bytes(&b->grid) + b->dead_count * sizeof(uint32_t);
        if (b->walk) bytes += a->walk_kind->memory(b->walk);
    }
    for (uint32_t k = 0; k < a->item_count; k++)
        if (a->items[k].world)
            bytes += (size_t)a->bottoms[a->items[k].bottom].wide.block_count * sizeof(accel_block8);
    return bytes;
}

/* bottom=<kind spec>: the kind over the mesh (object space), and the list
 * of the mesh's triangles it leaves out (no area in object space: their
 * world copies may have some, and are then tested for every instance). */
static int build_walk_bottom(inst_accel *a, inst_bottom *b, accel_error *err)
{
    const accel_scene *m = b->mesh;
    accel_build_stats st;
    int rc = accel_build_kind(a->walk_kind, a->walk_kv, m, a->threads, &b->walk, &st, err);
    if (rc) return rc;
    b->walk_stats = st;
    if (a->walk_kind->walk(b->walk, NULL, 0.0f, NULL, NULL, NULL))
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "instanced: bottom=%s%s%s built a structure that cannot walk (accel.h: "
                          "walk probe refused); choose another mode of the kind",
                          a->walk_kind->name, *a->walk_kv ? ":" : "", a->walk_kv);
    if (!a->scene->instances || m->degenerate_count == 0) return 0;
    uint8_t *alive = calloc(m->tri_count ? m->tri_count : 1, 1);
    b->dead = malloc((m->degenerate_count ? m->degenerate_count : 1) * sizeof *b->dead);
    if (!alive || !b->dead) {
        free(alive);
        return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory");
    }
    for (uint32_t k = 0; k < m->live_count; k++)
        if (m->live[k] < m->tri_count) alive[m->live[k]] = 1;
    for (uint32_t q = 0; q < m->tri_count && b->dead_count < m->degenerate_count; q++)
        if (!alive[q]) b->dead[b->dead_count++] = q;
    free(alive);
    return 0;
}

/* The bottom level of mesh i over its primitives (a plain scene: the live
 * ones), boxes grown by grid_pad in a grid. */
int inst_build_bottom(inst_accel *a, uint32_t i, double grid_pad, accel_error *err)
{
    inst_bottom *b = &a->bottoms[i];
    bvh_box_tree_free(&b->bvh);
    inst_wide_free(&b->wide);
    inst_grid_free(&b->grid);
    if (b->walk) a->walk_kind->destroy(b->walk);
    b->walk = NULL;
    free(b->dead);
    b->dead = NULL;
    b->dead_count = 0;
    const accel_scene *m = b->mesh;
    const uint32_t *ids = a->scene->instances ? NULL : m->live;
    uint32_t n = ids ? m->live_count : m->tri_count;
    box3 *boxes = malloc((n ? n : 1) * sizeof *boxes);
    if (!boxes) return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory");
    b->box = box3_empty();
    for (uint32_t k = 0; k < n; k++) {
        uint32_t id = ids ? ids[k] : k;
        if (id < m->tri_count) {
            const float *t = m->tris + 9 * (size_t)id;
            box3 bb = box3_empty();
            for (int c = 0; c < 3; c++) bb = box3_grow(bb, v3_load(t + 3 * c));
            boxes[k] = bb;
        } else {
            boxes[k] = accel_prim_bounds(m, id);
        }
        b->box = box3_union(b->box, boxes[k]);
    }
    const float *lo = &b->box.min.x, *hi = &b->box.max.x;
    for (int k = 0; k < 3; k++) b->box_lo[k] = lo[k], b->box_hi[k] = hi[k];
    b->abs_max = box_abs_max(b->box);
    /* The DDA's own rounding: a margin far above double error, far below a cell. */
    b->grid_pad = grid_pad + 0x1p-24 * b->abs_max + 1e-30;
    if (a->bottom_kind == INST_WALK) {
        free(boxes);
        return build_walk_bottom(a, b, err);
    }
    if (a->bottom_kind == INST_BVH) { /* the BVH's boxes are grown as bvh's are (core/geom.h) */
        float delta = box3_hit_delta((float)b->abs_max);
        for (uint32_t k = 0; k < n; k++) boxes[k] = box3_hit_pad(boxes[k], delta);
    }
    /* Items are box indices: ids makes them primitive ids. */
    int rc = a->bottom_kind == INST_BVH
                 ? inst_bvh_build(boxes, n, a->leaf, a->threads, ids, &b->bvh, err)
                 : inst_grid_build(boxes, n, a->lambda, b->grid_pad, &b->grid, err);
    free(boxes);
    if (rc == 0 && a->bottom_kind == INST_BVH && a->width == INST_WIDE)
        rc = inst_wide_build(&b->bvh, b->mesh, &b->wide, err);
    if (rc || !ids || a->bottom_kind == INST_BVH) return rc;
    for (uint64_t k = 0; k < b->grid.cells.ref_count; k++)
        b->grid.cells.refs[k] = ids[b->grid.cells.refs[k]];
    return 0;
}

/*
 * Per-instance data from the scene; grid_pad[i] (if not NULL) gets the
 * largest pad mesh i's grid needs. The pad is, in object units, how far a
 * flattened world vertex can be from the exact image of its mesh vertex
 * (float rounding of the result, and the double rounding of the fused
 * sum), taken through the inverse, doubled for safety.
 */
int inst_set_items(inst_accel *a, const accel_scene *scene, double *grid_pad, accel_error *err)
{
    const accel_instances *set = scene->instances;
    a->scene = scene;
    a->spheres = scene->sphere_count > 0;
    a->plain = set == NULL;
    /* The flattened scene's dead triangles (no area): never hit. */
    uint8_t *alive = NULL;
    if (set && scene->degenerate_count) {
        alive = calloc(scene->tri_count ? scene->tri_count : 1, 1);
        if (!alive) return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory");
        for (uint32_t k = 0; k < scene->live_count; k++)
            if (scene->live[k] < scene->tri_count) alive[scene->live[k]] = 1;
    }
    for (uint32_t i = 0; i < a->bottom_count; i++) {
        inst_bottom *b = &a->bottoms[i];
        b->mesh = set ? &set->meshes[i] : scene;
        /* Every vertex (dead triangles too: their world copies may live). */
        box3 mb = set ? box3_empty() : scene->bounds;
        for (size_t v = 0; set && v < 3 * (size_t)b->mesh->tri_count; v++)
            mb = box3_grow(mb, v3_load(b->mesh->tris + 3 * v));
        b->vert_abs_max = box_abs_max(mb);
        if (grid_pad) grid_pad[i] = 0.0;
    }
    for (uint32_t k = 0; k < a->item_count; k++) {
        inst_item *it = &a->items[k];
        if (!set) {
            static const double id[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
            memcpy(it->xform, id, sizeof id);
            memcpy(it->inverse, id, sizeof id);
            it->identity = 1;
            a->item_boxes[k] = scene->bounds;
            continue;
        }
        const accel_instance *in = &set->instances[k];
        if (in->mesh >= a->bottom_count) {
            free(alive);
            return accel_fail(err, ACCEL_ERR_INTERNAL, "instanced: instance %u of mesh %u", k,
                              in->mesh);
        }
        memcpy(it->xform, in->xform, sizeof it->xform);
        memcpy(it->inverse, in->inverse, sizeof it->inverse);
        it->bottom = in->mesh;
        it->base = in->base;
        it->identity = is_identity(in->xform);
        it->has_dead = 0;
        for (uint32_t q = 0; alive && q < set->meshes[in->mesh].tri_count && !it->has_dead; q++)
            it->has_dead = !alive[in->base + q];
        a->item_boxes[k] = in->bounds;
        double mesh_abs = a->bottoms[in->mesh].vert_abs_max;
        double t_abs = fmax(fabs(in->xform[3]), fmax(fabs(in->xform[7]), fabs(in->xform[11])));
        double e_world = 0x1p-24 * box_abs_max(in->bounds) +
                         0x1p-50 * (row_norm(in->xform) * mesh_abs + t_abs);
        it->pad = it->identity ? 0.0 : 2.0 * row_norm(in->inverse) * e_world;
        double gp = a->no_pad ? 0.0 : 2.0 * it->pad + 0x1p-20 * (mesh_abs + 2.0 * it->pad);
        if (grid_pad) grid_pad[in->mesh] = fmax(grid_pad[in->mesh], gp);
    }
    free(alive);
    return 0;
}

int inst_world_blocks(inst_accel *a, uint32_t k, accel_error *err)
{
    inst_item *it = &a->items[k];
    free(it->world);
    it->world = NULL;
    if (a->plain || a->world != INST_WORLD_BLOCKS || a->bottom_kind != INST_BVH ||
        a->width != INST_WIDE)
        return 0;
    const inst_wide *w = &a->bottoms[it->bottom].wide;
    if (!w->block_count) return 0;
    it->world = aligned_alloc(64, (size_t)w->block_count * sizeof *it->world);
    if (!it->world) return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory for world blocks");
    const float *tris = a->scene->tris;
    for (uint32_t i = 0; i < w->block_count; i++) {
        const accel_block8 *ob = &w->blocks[i];
        accel_block8 *wb = &it->world[i];
        for (int lane = 0; lane < 8; lane++) {
            uint32_t id = it->base + ob->id[lane];
            const float *t = tris + 9 * (size_t)id;
            float point[9];
            if (it->has_dead && accel_tri_is_degenerate(t)) { /* a point: U = V = W = 0, a miss */
                for (int c = 0; c < 9; c++) point[c] = t[c % 3];
                t = point;
            }
            accel_block_put_lane(wb->v[0][0], 8, lane, t);
            wb->id[lane] = id;
        }
    }
    return 0;
}

int inst_build_top(inst_accel *a, accel_error *err)
{
    bvh_box_tree_free(&a->top_bvh);
    inst_wide_free(&a->top_wide);
    inst_grid_free(&a->top_grid);
    if (a->top == INST_BVH) {
        /* Instance boxes grown as every BVH box is (core/geom.h). */
        float m = 0.0f;
        for (uint32_t k = 0; k < a->item_count; k++) m = fmaxf(m, box3_abs_max(a->item_boxes[k]));
        float delta = box3_hit_delta(m);
        box3 *grown = malloc((a->item_count ? a->item_count : 1) * sizeof *grown);
        if (!grown) return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory");
        for (uint32_t k = 0; k < a->item_count; k++) grown[k] = box3_hit_pad(a->item_boxes[k], delta);
        int rc = inst_bvh_build(grown, a->item_count, 1, a->threads, NULL, &a->top_bvh, err);
        free(grown);
        if (rc == 0 && a->width == INST_WIDE) rc = inst_wide_build(&a->top_bvh, NULL, &a->top_wide, err);
        return rc;
    }
    double top_pad = 0.0;
    for (uint32_t k = 0; k < a->item_count; k++)
        top_pad = fmax(top_pad, 0x1p-30 * box_abs_max(a->item_boxes[k]));
    return inst_grid_build(a->item_boxes, a->item_count, a->top_lambda, top_pad + 1e-30,
                           &a->top_grid, err);
}

void inst_fill_stats(const inst_accel *a, accel_build_stats *stats)
{
    memset(stats, 0, sizeof *stats);
    stats->sah_cost = NAN;
    int bottom_depth = 0;
    for (uint32_t i = 0; i < a->bottom_count; i++) {
        const inst_bottom *b = &a->bottoms[i];
        if (a->bottom_kind == INST_WALK) {
            stats->nodes += b->walk_stats.nodes;
            stats->refs += b->walk_stats.refs;
            if (b->walk_stats.depth > bottom_depth) bottom_depth = b->walk_stats.depth;
            continue;
        }
        stats->nodes += a->bottom_kind == INST_BVH ? b->bvh.node_count : b->grid.cells.cell_count;
        stats->refs += a->bottom_kind == INST_BVH ? b->bvh.count : b->grid.cells.ref_count;
        if (b->bvh.depth > bottom_depth) bottom_depth = b->bvh.depth;
    }
    stats->nodes += a->top == INST_BVH ? a->top_bvh.node_count : a->top_grid.cells.cell_count;
    stats->leaves = a->item_count;
    stats->depth = (a->top == INST_BVH ? a->top_bvh.depth : 1) + bottom_depth;
    for (int k = 0; k < 3; k++) stats->res[k] = a->top_grid.frame.res[k];
    stats->bytes = inst_memory(a);
    /* The 8-wide bottom level tests its leaves' world blocks with the
     * shared block test (k8_trace.c's test_blocks); the other bottoms meet
     * triangles one by one. */
    stats->test_lanes = a->bottom_kind == INST_BVH && a->width == INST_WIDE ? 8 : 0;
}

/* bottom=<text>: bvh and grid are the kind's own; anything else names a
 * kind with a walk, its parameters after ':' with ';' for ','. */
static int parse_bottom(inst_accel *a, const char *text, accel_error *err)
{
    if (!strcmp(text, "bvh") || !strcmp(text, "grid")) {
        a->bottom_kind = !strcmp(text, "bvh") ? INST_BVH : INST_GRID;
        return 0;
    }
    char name[64];
    const char *colon = strchr(text, ':');
    size_t n = colon ? (size_t)(colon - text) : strlen(text);
    snprintf(name, sizeof name, "%.*s", (int)n, text);
    snprintf(a->walk_kv, sizeof a->walk_kv, "%s", colon ? colon + 1 : "");
    for (char *c = a->walk_kv; *c; c++)
        if (*c == ';') *c = ',';
    const accel_kind *k = accel_find_kind(name);
    if (!k) {
        char names[300] = "";
        for (size_t i = 0; i < accel_kind_count; i++)
            if (accel_kinds[i]->walk) {
                size_t len = strlen(names);
                snprintf(names + len, sizeof names - len, " %s", accel_kinds[i]->name);
            }
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "instanced: bottom=%s: no kind '%s'; accepted: bvh, grid (the kind's "
                          "own), or a kind with a walk:%s (parameters as <kind>:k=v;k=v)",
                          text, name, names);
    }
    return inst_use_bottom_kind(a, k, err);
}

int inst_use_bottom_kind(inst_accel *a, const accel_kind *k, accel_error *err)
{
    if (!k->walk)
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "instanced: kind '%s' has no walk (accel_kind.walk, accel.h), so it "
                          "cannot be a bottom level: the world-space decisions need every "
                          "primitive the ray passes within the pad of, which a closest-hit "
                          "answer does not give (instanced/README.md)",
                          k->name);
    a->bottom_kind = INST_WALK;
    a->walk_kind = k;
    return 0;
}

int inst_build_with(const accel_scene *scene, const accel_params *params, int threads,
                    const accel_kind *bottom, const char *bottom_kv, void **out,
                    accel_build_stats *stats, accel_error *err)
{
    inst_accel *a = calloc(1, sizeof *a);
    if (!a) return accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory");
    const inst_spec *spec = ACCEL_SPEC(params, inst_spec);
    a->threads = threads;
    a->top = spec->top;
    int brc = 0;
    if (bottom) {
        snprintf(a->walk_kv, sizeof a->walk_kv, "%s", bottom_kv ? bottom_kv : "");
        brc = inst_use_bottom_kind(a, bottom, err);
    } else {
        brc = parse_bottom(a, spec->bottom, err);
    }
    if (brc) {
        free(a);
        return brc;
    }
    a->naive = params->naive;
    a->world = spec->world;
    a->no_pad = spec->pad == 0;
    a->leaf = spec->leaf;
    a->width = spec->width;
    a->packets = spec->traverse == 1;
    if (a->packets && (a->top != INST_BVH || a->bottom_kind != INST_BVH || a->width != INST_WIDE)) {
        free(a);
        return accel_fail(err, ACCEL_ERR_SPEC,
                          "instanced: traverse=packet needs top=bvh, bottom=bvh and width=8");
    }
    if (accel_isa_resolve(spec->isa, &a->isa, err)) {
        free(a);
        return ACCEL_ERR_SPEC;
    }
    a->lambda = spec->lambda;
    a->top_lambda = spec->top_lambda;
    const accel_instances *set = scene->instances;
    a->bottom_count = set ? set->mesh_count : 1;
    a->item_count = set ? set->instance_count : 1;
    a->bottoms = calloc(a->bottom_count ? a->bottom_count : 1, sizeof *a->bottoms);
    a->items = calloc(a->item_count ? a->item_count : 1, sizeof *a->items);
    a->item_boxes = calloc(a->item_count ? a->item_count : 1, sizeof *a->item_boxes);
    double *grid_pad = calloc(a->bottom_count ? a->bottom_count : 1, sizeof *grid_pad);
    int rc = 0;
    if (!a->bottoms || !a->items || !a->item_boxes || !grid_pad)
        rc = accel_fail(err, ACCEL_ERR_NOMEM, "instanced: out of memory");
    if (rc == 0) rc = inst_set_items(a, scene, grid_pad, err);
    for (uint32_t i = 0; rc == 0 && i < a->bottom_count; i++)
        rc = inst_build_bottom(a, i, grid_pad[i], err);
    free(grid_pad);
    for (uint32_t k = 0; rc == 0 && k < a->item_count; k++) rc = inst_world_blocks(a, k, err);
    if (rc == 0) rc = inst_build_top(a, err);
    if (rc) {
        inst_destroy(a);
        return rc;
    }
    inst_fill_stats(a, stats);
    stats->isa = accel_isa_label(a->isa);
    *out = a;
    return 0;
}

static int inst_build(const accel_scene *scene, const accel_params *params, int threads,
                      void **out, accel_build_stats *stats, accel_error *err)
{
    return inst_build_with(scene, params, threads, NULL, NULL, out, stats, err);
}

int instanced_build_with_bottom(const accel_scene *scene, const char *kv, const accel_kind *bottom,
                                const char *bottom_kv, int threads, void **out,
                                accel_build_stats *stats, accel_error *err)
{
    accel_params p;
    int rc = accel_params_parse_kind(&accel_kind_instanced, kv, &p, err);
    if (rc) return rc;
    double t0 = accel_now_ms();
    rc = inst_build_with(scene, &p, threads, bottom, bottom_kv, out, stats, err);
    if (rc == 0) stats->ms = accel_now_ms() - t0;
    return rc;
}

static const char *const inst_variants[] = {
    "", "top=grid", "bottom=grid", "top=grid,bottom=grid", "world=compute,leaf=1", "width=2",
    "bottom=bvh:width=8", "top=grid,bottom=nested_grid", "bottom=grid:", "traverse=packet",
    "traverse=packet,world=compute,leaf=1", "isa=avx2", NULL,
};

const accel_kind accel_kind_instanced = {
    .name = "instanced",
    .summary = "two levels: a BVH or grid over instances, a BVH or grid per mesh shared by its "
               "instances; hits decided on the world-space triangles",
    .step_name = "nodes",
    .params = inst_params,
    .param_count = INST_PARAM_COUNT,
    .spec_size = sizeof(inst_spec),
    .variants = inst_variants,
    .build = inst_build,
    .intersect = inst_intersect,
    .occluded = inst_occluded,
    .memory = inst_memory,
    .destroy = inst_destroy,
    .update = inst_update,
};
