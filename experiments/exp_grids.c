/*
 * exp_grids - issue 13's closing table: the grids at their best against the
 * binary BVH. Per scene and ray set at the lecture's 800x600 (the rays of
 * one in 2 of its 8x8 tiles: the budget), one thread:
 * Mrays/s and steps and primitive tests per ray of `grid`, its empty-space
 * skipping (`skip=cloud`, `skip=macro`), coherent grid traversal (Wald,
 * Ize, Kensler, Knoll, Parker, SIGGRAPH 2006: `grid:traverse=packet`,
 * and the same walk through the nested grid's levels,
 * `nested_grid:traverse=packet`; primary and shadow rays only, beside the
 * BVH's own packets `bvh:traverse=packet`), `nested_grid`, `irregular_grid`
 * (Perard-Gayot, Kalojanov, Slusallek, EG 2017) with each of its three
 * steps turned off in turn, and `bvh`, all in the same interleaved rounds
 * (group.h), with build ms and memory (MB, bytes and references per
 * primitive). Issue 49: each grid kind on both triangle kernels (ids and
 * the shared block test), and `bvh:width=8` beside `bvh`, so that the
 * best grid of each kernel is judged against the BVH of that kernel and
 * the kernel's share (blocks over ids, per kind) shows apart.
 *
 * A configuration whose pass would take more than a few seconds (the
 * regular grid on teapot_stadium, one cell holding the teapot) is left out
 * on a 2048-ray probe (group.c); its probe's predicted time is quoted,
 * marked as such, where a target needs it.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/group.h"

#define MASK (BENCH_PRIMARY | BENCH_SHADOW | BENCH_DIFFUSE)
#define COHERENT (BENCH_PRIMARY | BENCH_SHADOW)

/* Every kind on both triangle kernels (issue 49): the block grids
 * (`grid`, `cells=blocks`) beside their per-id selves (`cells=ids`), the
 * binary BVH (per-id leaves) beside the 8-wide one (block leaves), so
 * that a grid is compared with the BVH on its own kernel and the kernel's
 * share shows apart from the structure's. */
static const char *const configs[] = {
    "bvh",          "bvh:width=8", "grid", "grid:cells=ids",
    "grid:skip=cloud", "grid:skip=macro",
    "grid:traverse=packet", "nested_grid", "nested_grid:cells=blocks",
    "nested_grid:layout=compact",
    "nested_grid:traverse=packet", "bvh:traverse=packet",
    "irregular_grid", "irregular_grid:cells=blocks", "irregular_grid:subdivide=0",
    "irregular_grid:merge=0", "irregular_grid:expand=0"};

/* 1 when a built configuration tests its triangles with the shared block
 * test (the 8- or 4-wide BVH's leaves, block grid cells), 0 when one by
 * one through ids (the binary BVH; a grid on ids, or on a scene with
 * spheres, where no blocks are built): its build statistics say so. */
static int block_kernel(const exp_cfg *cf)
{
    return cf->build.test_lanes > 0;
}

static const int set_bits[3] = {BENCH_PRIMARY, BENCH_SHADOW, BENCH_DIFFUSE};

typedef struct {
    exp_tally t; /* issue 38: every target comparison, Bonferroni intervals */
    exp_text findings;
    int n[3], met[3], tie[3]; /* per target: packets 5x, grid near bvh, irregular ahead */
    int met_est; /* of met[0]: on the collapse probe's estimate, no interval */
} study;

static void count(study *st, int which, const char *outcome)
{
    st->n[which]++;
    st->met[which] += !strncmp(outcome, "met", 3);
    st->met_est += !strncmp(outcome, "met", 3) && strstr(outcome, "on the estimate") != NULL;
    st->tie[which] += !strncmp(outcome, "a tie", 5) && which != 2; /* a tie is "not met" there */
}

/* One target comparison into the tally: r at the tally's level against
 * threshold t (sense +1: at least t; -1: at most t). */
static void judge(study *st, const char *what, const char *scene, int bit, const exp_est *r,
                  double t, int sense)
{
    char w[900];
    snprintf(w, sizeof w, "%s, %s, %s", what, scene, bench_set_name(bit));
    exp_decider d = exp_decider_of(w, r, t, sense);
    exp_tally_add(&st->t, &d);
}

static int is_mesh(const char *name) { return strstr(name, ".off") || strstr(name, ".obj") || strstr(name, ".ply"); }

/* Time of c relative to bvh on bit (> 1: slower than bvh), paired. */
static exp_est rel_bvh(const exp_group *g, int bvh, int c, int bit)
{
    return exp_group_speedup(g, c, bvh, bit);
}

/* One row of a scene's targets table, quoted by its finding. */
static void target_row(exp_ctx *x, exp_text *f, const char *what, int bit, const char *value,
                       const char *target, const char *outcome)
{
    exp_md(x, "| %s | %s | %s | %s | %s |\n", what, bench_set_name(bit), value, target, outcome);
    if (target[0] == '-' || target[0] == '(') /* no target: the row's outcome only */
        exp_text_add(f, " %s, %s: %s (%s);", what, bench_set_name(bit), value, outcome);
    else
        exp_text_add(f, " %s, %s: %s (target %s: %s);", what, bench_set_name(bit), value, target, outcome);
}

/* The grid configuration (any kind but the BVHs) with the lowest median
 * time on ray set `bit` among the packet kernels (packets = 1: specs with
 * traverse=packet) or the single-ray ones (packets = 0), on the block
 * kernel (kernel = 1), the per-id one (0) or either (-1); -1 when none. */
static int fastest(const exp_group *g, int bit, int packets, int kernel)
{
    int best = -1;
    for (int c = 0; c < g->count; c++) {
        const exp_cfg *cf = &g->cfg[c];
        if (!cf->ok || !strncmp(cf->spec, "bvh", 3) ||
            (strstr(cf->spec, "traverse=packet") != NULL) != packets ||
            (kernel >= 0 && block_kernel(cf) != kernel) || !cf->set[exp_set_index(bit)].have)
            continue;
        if (best < 0 || exp_group_ns(g, c, bit).median < exp_group_ns(g, best, bit).median) best = c;
    }
    return best;
}

static void findings(exp_ctx *x, study *st, exp_group *g, const accel_scene *s)
{
    char a[96], what[640], tt[32];
    int bvh = exp_group_find(g, "bvh"), grid = exp_group_find(g, "grid");
    int bvh8 = exp_group_find(g, "bvh:width=8");
    int pk = exp_group_find(g, "grid:traverse=packet"), nested = exp_group_find(g, "nested_grid");
    int irr = exp_group_find(g, "irregular_grid");
    int npk = exp_group_find(g, "nested_grid:traverse=packet");
    int bpk = exp_group_find(g, "bvh:traverse=packet");
    exp_md(x, "\nThis section's targets on this scene (paired ratios of the rounds above):\n");
    exp_md_table(x, "comparison|ray set|ratio [95% CI]|target|outcome");
    exp_text_add(&st->findings, "- **%s**:", s->name);
    /* 1. Coherent grid traversal against the single-ray grid, primary rays. */
    if (pk >= 0 && g->cfg[pk].ok && grid >= 0) {
        if (g->cfg[grid].ok) {
            exp_est r = exp_group_speedup_level(g, grid, pk, BENCH_PRIMARY, exp_tally_level(&st->t));
            const char *o = exp_target_outcome(&r, 5, 1);
            judge(st, "speed of `grid:traverse=packet` over `grid`", s->name, BENCH_PRIMARY, &r, 5, +1);
            target_row(x, &st->findings, "speed of `grid:traverse=packet` over `grid`",
                       BENCH_PRIMARY, exp_fmt_x(a, sizeof a, &r), "at least 5x", o);
            count(st, 0, o);
        } else if (g->cfg[grid].left == EXP_LEFT_COLLAPSED && g->cfg[grid].counted_ms > 0) {
            /* Only the probe's prediction exists for the collapsed grid. */
            double est = g->cfg[grid].counted_ms / g->cfg[pk].set[0].ms.median;
            snprintf(a, sizeof a, "about %.0fx (estimate)", est);
            snprintf(what, sizeof what, "speed of `grid:traverse=packet` over `grid` (collapsed: "
                     "its probe predicts %.1f s per pass)", g->cfg[grid].counted_ms / 1e3);
            const char *o = est >= 5 ? "met on the estimate" : "not met on the estimate";
            target_row(x, &st->findings, what, BENCH_PRIMARY, a, "at least 5x", o);
            count(st, 0, o);
        }
    }
    /* 1b. The same walk through the nested grid's levels, against its
     * single-ray walk. */
    if (npk >= 0 && nested >= 0 && g->cfg[npk].ok && g->cfg[nested].ok) {
        exp_est r = exp_group_speedup_level(g, nested, npk, BENCH_PRIMARY, exp_tally_level(&st->t));
        const char *o = exp_target_outcome(&r, 5, 1);
        judge(st, "speed of `nested_grid:traverse=packet` over `nested_grid`", s->name,
              BENCH_PRIMARY, &r, 5, +1);
        target_row(x, &st->findings, "speed of `nested_grid:traverse=packet` over `nested_grid`",
                   BENCH_PRIMARY, exp_fmt_x(a, sizeof a, &r), "at least 5x", o);
        count(st, 0, o);
    }
    /* 1c. Packets against packets: the faster coherent grid against the
     * BVH's packets (no target: the fair coherent comparison). */
    if (bpk >= 0 && g->cfg[bpk].ok) {
        for (int k = 0; k < 2; k++) {
            const int bit = set_bits[k], best = fastest(g, bit, 1, -1);
            if (best < 0) continue;
            exp_est r = exp_group_speedup(g, bpk, best, bit); /* > 1: the grid is faster */
            const int cmp = exp_ratio_cmp(&r, g->floor);
            snprintf(what, sizeof what, "speed of the faster grid packets `%s` over "
                     "`bvh:traverse=packet`", g->cfg[best].spec);
            target_row(x, &st->findings, what, bit, exp_fmt_x(a, sizeof a, &r), "-",
                       cmp > 0 ? "the grid is faster" : cmp < 0 ? "the BVH is faster" : "a tie");
        }
    }
    /* 2. The best single-ray grid against the BVH on the same triangle
     * kernel, primary and diffuse: per-id grids against `bvh` (binary,
     * per-id leaves), block grids against `bvh:width=8` (block leaves). */
    for (int kern = 0; kern < 2; kern++) {
        const int base = kern ? bvh8 : bvh;
        if (base < 0 || !g->cfg[base].ok) continue;
        double t = is_mesh(s->name) ? 1.3 : strstr(s->name, "teapot_stadium") ? 2.0 : 0;
        for (int k = 0; k < 3; k += 2) {
            /* issue 52: the best chosen on half the rounds, judged on the other */
            g->half = 1;
            int bit = set_bits[k], best = fastest(g, bit, 0, kern);
            g->half = 2;
            exp_est r = best < 0 ? (exp_est){0}
                        : t > 0 ? exp_group_speedup_level(g, best, base, bit, exp_tally_level(&st->t))
                                : rel_bvh(g, base, best, bit);
            g->half = 0;
            if (best < 0) continue;
            snprintf(what, sizeof what, "time of the best single-ray %s grid `%s` over `%s`",
                     kern ? "block" : "per-id", g->cfg[best].spec, g->cfg[base].spec);
            snprintf(tt, sizeof tt, t > 0 ? "at most %gx" : "-", t);
            const char *o = t > 0 ? exp_target_outcome(&r, t, 0) : "no target on this scene";
            target_row(x, &st->findings, what, bit, exp_fmt_x(a, sizeof a, &r), tt, o);
            if (t > 0) count(st, 1, o), judge(st, what, s->name, bit, &r, t, -1);
        }
    }
    /* 2b. The kernel's share: each grid kind on blocks against itself on
     * ids (the same structure but for grid's density), diffuse rays (no
     * target here: issue 49's targets are at each kind's best resolution,
     * exp_grid_resolution and exp_nested_grid). */
    static const char *const share[3][2] = {{"grid:cells=ids", "grid"},
                                            {"nested_grid", "nested_grid:cells=blocks"},
                                            {"irregular_grid", "irregular_grid:cells=blocks"}};
    for (int k = 0; k < 3; k++) {
        const int ids = exp_group_find(g, share[k][0]), blk = exp_group_find(g, share[k][1]);
        if (ids < 0 || blk < 0 || !g->cfg[ids].ok || !g->cfg[blk].ok ||
            !g->cfg[blk].set[exp_set_index(BENCH_DIFFUSE)].have)
            continue;
        exp_est r = exp_group_speedup(g, ids, blk, BENCH_DIFFUSE); /* > 1: blocks faster */
        const int cmp = exp_ratio_cmp(&r, g->floor);
        snprintf(what, sizeof what, "speed of `%s` over `%s` (the kernel's share)", share[k][1],
                 share[k][0]);
        target_row(x, &st->findings, what, BENCH_DIFFUSE, exp_fmt_x(a, sizeof a, &r), "-",
                   cmp > 0 ? "blocks are faster" : cmp < 0 ? "ids are faster" : "a tie");
    }
    /* 3. Irregular against nested where nested beats the regular grid. */
    if (nested >= 0 && irr >= 0 && g->cfg[nested].ok && g->cfg[irr].ok && grid >= 0) {
        for (int k = 0; k < 3; k++) {
            int bit = set_bits[k];
            if (g->cfg[grid].ok) {
                exp_est r = exp_group_speedup(g, grid, nested, bit); /* > 1: nested faster */
                int beats = exp_ratio_cmp(&r, g->floor) > 0;
                target_row(x, &st->findings, "speed of `nested_grid` over `grid`", bit,
                           exp_fmt_x(a, sizeof a, &r), "(condition)",
                           beats ? "nested beats regular: the next row applies"
                                 : "nested does not beat regular: no irregular target here");
                if (!beats) continue;
            }
            exp_est r = exp_group_speedup_level(g, nested, irr, bit, exp_tally_level(&st->t));
            int cmp = exp_ratio_cmp(&r, g->floor);
            judge(st, "speed of `irregular_grid` over `nested_grid`", s->name, bit, &r, 1.0, +1);
            target_row(x, &st->findings, g->cfg[grid].ok ? "speed of `irregular_grid` over "
                       "`nested_grid`" : "speed of `irregular_grid` over `nested_grid` (`grid` "
                       "collapsed, so nested beats it)", bit, exp_fmt_x(a, sizeof a, &r), "ahead",
                       cmp > 0 ? "met" : cmp < 0 ? "not met" : "a tie, not met");
            count(st, 2, cmp > 0 ? "met" : "not met");
        }
    }
    size_t len = st->findings.len;
    if (len && st->findings.s[len - 1] == ';') st->findings.s[len - 1] = '.';
    exp_text_add(&st->findings, "\n");
}

static void measure_scene(exp_ctx *x, study *st, const char *spec, const exp_list *list)
{
    accel_scene s;
    bench_sets sets;
    exp_scene_section(x, spec, &s, MASK, 2, &sets); /* half the tiles: the budget */
    exp_group g;
    exp_group_init(&g, x, &s, &sets, MASK);
    g.collapse_ms = x->quick ? 500 : 3000;
    for (int i = 0; i < list->count; i++) {
        /* Coherent traversal is for coherent rays (issue 13): no diffuse. */
        g.add_mask = strstr(list->spec[i], "traverse=packet") ? COHERENT : 0;
        exp_group_add(&g, list->spec[i], 1);
    }
    g.add_mask = 0;
    exp_group_run(&g);
    int bvh = exp_group_find(&g, "bvh");
    if (bvh >= 0 && !g.cfg[bvh].ok) bvh = -1;
    exp_md(x, "\nPer ray set: Mrays/s [95%% CI], time relative to `bvh` in the same rounds "
              "(paired; < 1: faster than `bvh`), steps (cells, nodes) and primitive tests per "
              "ray; `-`: not traced. Memory: the whole structure (its copy of the primitives, "
              "references, blocks, cells or nodes) in MB and in bytes per primitive (B/prim), "
              "and references per primitive (refs/prim: the duplicates a grid's cells make). "
              "Kernel: `blocks` tests triangles with the shared block test (8 lanes), `ids` "
              "one by one; a grid is compared with the BVH of its own kernel in the findings "
              "below (`bvh` has per-id leaves, `bvh:width=8` block leaves).\n");
    exp_md_table(x, "kernel|test|build ms|MB|B/prim|refs/prim|primary Mrays/s|/ bvh|steps, tests|"
                    "shadow Mrays/s|/ bvh|steps, tests|diffuse Mrays/s|/ bvh|steps, tests");
    for (int c = 0; c < g.count; c++) {
        const exp_cfg *cf = &g.cfg[c];
        if (!cf->ok) continue;
        char b[96];
        const double prims = s.live_count ? (double)s.live_count : 1.0;
        const double bpp = (double)cf->build.bytes / prims, rpp = (double)cf->build.refs / prims;
        exp_md(x, "| `%s` | %s | %s | %.1f | %.0f | %.2f |", cf->spec,
               block_kernel(cf) ? "blocks" : "ids",
               exp_fmt_est(b, sizeof b, &cf->build_ms, 1), cf->build.bytes / 1048576.0, bpp, rpp);
        for (int k = 0; k < 3; k++) {
            int bit = set_bits[k];
            if (!cf->set[exp_set_index(bit)].have) {
                exp_md(x, " - | - | - |");
                continue;
            }
            exp_est m = exp_group_mrays(&g, c, bit);
            exp_est r = bvh >= 0 ? rel_bvh(&g, bvh, c, bit) : (exp_est){0};
            char a[96], rb[96];
            if (c == bvh) snprintf(rb, sizeof rb, "1.00 (base)");
            else if (bvh >= 0) exp_fmt_x(rb, sizeof rb, &r);
            else snprintf(rb, sizeof rb, "-");
            exp_md(x, " %s | %s | %.1f, %.1f |", exp_fmt_est(a, sizeof a, &m, 2), rb,
                   exp_group_steps(&g, c, bit), exp_group_prims(&g, c, bit));
            exp_csv(x,
                    "%s,%s,%s,%zu,%.3f,%.3f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.3f,%.3f,%s,%.1f,%.3f\n",
                    s.name, cf->spec, bench_set_name(bit), exp_group_rays(&g, c, bit),
                    cf->build_ms.median, cf->build.bytes / 1048576.0, m.median, m.lo, m.hi,
                    c == bvh ? 1.0 : r.median, c == bvh ? 1.0 : r.lo, c == bvh ? 1.0 : r.hi,
                    exp_group_steps(&g, c, bit), exp_group_prims(&g, c, bit),
                    block_kernel(cf) ? "blocks" : "ids", bpp, rpp);
        }
        exp_md(x, "\n");
    }
    exp_group_note(&g);
    findings(x, st, &g, &s);
    exp_group_free(&g);
    bench_sets_free(&sets);
    scene_free(&s);
}

int main(int argc, char **argv)
{
    const char *scenes[EXP_MAX_MESHES + 8];
    int n = 0;
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_grids",
             "How close do the best grids (coherent traversal, skipping, nested, irregular) come "
             "to the BVH?",
             "Scenes (without --scene): the meshes, sphereflake, teapot_stadium:n=8, tetra.\n");
    exp_limits(&x, EXP_MAX_MESHES, EXP_MAX_MESHES);
    exp_header(&x, "Grids at their best", "(not a lecture claim: the study's targets, in this section's findings) coherent "
               "grid traversal >= 5x the single-ray grid on primary rays; the best grid within "
               "1.3x of the BVH on the same triangle kernel (per-id grids against `bvh`, block "
               "grids against `bvh:width=8`) on the scanned meshes (primary, diffuse), within 2x "
               "on teapot_stadium; the irregular grid ahead of the nested grid wherever the nested "
               "grid beats the regular one",
               "how fast are the grid variants against each other and against the binary BVH, "
               "per scene and ray set at %dx%d (one in 2 of its 8x8 tiles), one thread, all in the "
               "same interleaved rounds? "
               "A target counts as met when the whole 95%% interval of the paired ratio clears "
               "it, not met when it misses it entirely, else a tie. `nested_grid:layout=compact` is "
               "the compact two-level layout (Kalojanov et al. 2011; exactly two levels, where "
               "the default nests up to three). Every grid kind runs on both triangle kernels: "
               "`cells=ids` tests a cell's triangles one by one, `cells=blocks` 8 at "
               "a time with the 8-wide BVH's block test (`grid`'s default; the nested and "
               "irregular grids default to ids).",
               x.rt_size[0], x.rt_size[1]);
    exp_csv(&x, "scene,spec,set,rays,build_ms,mb,mrays,mrays_lo,mrays_hi,time_vs_bvh,"
                "time_vs_bvh_lo,time_vs_bvh_hi,steps_per_ray,prims_per_ray,kernel,"
                "bytes_per_prim,refs_per_prim\n");
    if (x.scene_count) {
        n = exp_scene_list(&x, scenes, n, EXP_MAX_MESHES);
    } else if (x.quick) {
        scenes[n++] = "sphereflake:level=1";
        scenes[n++] = "teapot_stadium:n=2,stadium=16,tiers=4";
    } else {
        for (int i = 0; i < x.mesh_count; i++) scenes[n++] = x.meshes[i];
        scenes[n++] = "sphereflake";
        scenes[n++] = "teapot_stadium:n=8";
        scenes[n++] = "tetra"; /* a Sierpinski pyramid: mostly empty space */
    }
    if (!x.quick) x.set_budget_ms = 400, x.build_budget_ms = 800, x.repeats = 10;
    exp_list list;
    exp_list_make(&x, configs, (int)(sizeof configs / sizeof configs[0]), NULL, &list);
    study st = {0};
    exp_tally_init(&st.t, 9 * n); /* at most 9 target comparisons per scene */
    for (int i = 0; i < n; i++) measure_scene(&x, &st, scenes[i], &list);
    exp_md(&x, "\n**Findings** (this section's targets; \"best single-ray per-id (block) "
               "grid\": the grid configuration on that kernel with the lowest median time on "
               "that set, packets excluded, against the BVH on the same kernel; \"the faster grid "
               "packets\": `grid:traverse=packet` or `nested_grid:traverse=packet`, whichever has "
               "the lower median time):\n\n%s",
           exp_text_str(&st.findings));
    if (st.t.added) {
        const char *v = exp_tally_verdict(&st.t);
        /* a ratio of two configurations timed in the same rounds: a busy
         * machine slows both, so its refutation stands (issue 52) */
        exp_verdict_num(&x, "grids-best", v, &st.t.worst, "the scenes of the section",
                        "%d target comparisons (intervals at %.2f%%, Bonferroni): %d confirm, %d "
                        "miss, %d on the line; by target: packets 5x over their single-ray grid "
                        "met %d of %d (%d of them on the collapse probe's estimate, with no "
                        "interval, outside the tally); best single-ray grid within the target of "
                        "the BVH on its kernel met %d of %d; irregular ahead of nested where "
                        "nested beats regular: "
                        "%d of %d", st.t.added, 100 * exp_tally_level(&st.t), st.t.confirmed,
                        st.t.refuted, st.t.online, st.met[0], st.n[0], st.met_est, st.met[1],
                        st.n[1], st.met[2], st.n[2]);
    }
    exp_md(&x, "\nSteps: cells visited (for the packet: cells visited times the rays active "
               "there); tests: exact primitive tests. Rounds: at most %d, at least 3, fewer for "
               "slow passes (%.1f s of timed work per configuration and ray set).\n",
           x.repeats, x.set_budget_ms / 1e3);
    exp_text_free(&st.findings);
    exp_list_free(&list);
    return exp_finish(&x);
}
