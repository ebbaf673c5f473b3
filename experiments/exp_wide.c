/*
 * exp_wide - issue 11's closing table: how much faster than the binary BVH
 * (`bvh`, single rays) are the 4- and 8-wide BVHs, single and coherent
 * (`traverse=packet`), per scene and ray set at the lecture's 800x600 (the
 * rays of one in 2 of its 8x8 tiles, one in 8 on the 1M-triangle scenes,
 * one in 32 on slivers: the budget; exp_sets_tiles), what
 * do they cost in build time and memory, and do 2 threads give 1.9x?
 *
 * Every kernel of a scene is measured in the same interleaved rounds
 * (group.h): one exp_group per scene holds bvh, bvh:width=4|8 single and
 * coherent, the 8-wide single-ray kernel with order=branchy and on
 * quantized nodes (quant=1), the 8-wide trees with blocks of 4, collapsed
 * greedily, and from binary leaves of at most 4 (leaf_below=4), the
 * 8-wide tree's ray streams (traverse=stream), and the
 * 8-wide kernels again on 2 threads, so every ratio is a
 * paired per-round ratio with its bootstrap interval. Builds are timed
 * apart, in their own interleaved rounds, once per tree (the coherent
 * kernels trace the same tree). Slow scenes get fewer rounds: a measured
 * time budget per configuration (the footer gives the range). On the first
 * mesh and teapot_stadium (or the first --scene), heatmaps of node visits
 * and primitive tests per primary ray for widths 2, 4 and 8 on one colour
 * scale per row.
 *
 *   bin/exp_wide [--scene SPEC]... [harness options]
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/group.h"
#include "wide_embree.h"

#define MASK (BENCH_PRIMARY | BENCH_SHADOW | BENCH_DIFFUSE)
#define MAX_SCENES 16
#define MAX_TREES 8 /* distinct trees of a scene: 7 today */
/* The 8-wide tree's single-ray kernel with the octant order pushed by
 * branches instead of the compress-store: the same tree and counts, so
 * measured although exp_group would call it "the same structure". */
#define BRANCHY "bvh:width=8,order=branchy"
/* The 8-wide tree with quantized child boxes (128-byte nodes; its push is
 * order=branchy's, so that is the kernel to compare it with). */
#define QUANT "bvh:width=8,quant=1"
/* The 8-wide tree with leaf blocks of 4 (the layout spheres get), with both
 * octant pushes: where leaves overlap the origins of secondary rays
 * (teapot_stadium) smaller leaves pay, elsewhere blocks of 8 do; the best
 * single kernel of a scene is picked among both. */
#define BLOCK4 "bvh:width=8,block=4"
#define BRANCHY4 BLOCK4 ",order=branchy"
/* The 8-wide packets, and the same packets without the hand-over to single
 * rays (hybrid=0; the default hands over a subtree hit by few rays of the
 * packet): the same tree, measured to show what the hand-over pays. */
#define PACKET8 "bvh:width=8,traverse=packet"
#define HYBRID0 PACKET8 ",hybrid=0"
/* The 8-wide tree collapsed greedily (largest child opened first, every
 * subtree of one block a leaf) instead of by the default dynamic
 * programme (collapse=dp): a control that prices the DP collapse on its
 * own, same binary tree. And the default collapse given binary leaves of
 * at most 4 primitives to choose from (leaf_below=4): it may keep two of
 * them apart in two padded blocks where the SAH says so, for a longer
 * binary build. */
#define GREEDY "bvh:width=8,collapse=greedy"
#define LEAF4 "bvh:width=8,leaf_below=4"
/* Ray streams over the same 8-wide tree (traverse=stream, bvh/wide/
 * stream.h): a batch's rays by octant, the tree walked once per stream of
 * 1024, each node fetched once for every ray still in it. Their answers are
 * order=branchy's (BRANCHY above), bit for bit; measured against the
 * default single-ray kernel on every set, the incoherent ones (diffuse,
 * shadow) being what they are for. */
#define STREAM8 "bvh:width=8,traverse=stream"

static const char *const configs[] = {"bvh",
                                      "bvh:width=4",
                                      "bvh:width=8",
                                      BRANCHY,
                                      QUANT,
                                      BLOCK4,
                                      BRANCHY4,
                                      GREEDY,
                                      LEAF4,
                                      "bvh:traverse=packet",
                                      "bvh:width=4,traverse=packet",
                                      PACKET8,
                                      HYBRID0,
                                      STREAM8};
/* Traversals of a tree another config already builds, measured anyway
 * (exp_group would otherwise call them "the same structure"). */
static const char *const same_tree[] = {BRANCHY, QUANT, BRANCHY4, HYBRID0, STREAM8};
/* Kernels measured again on 2 threads: the 8-wide tree's default single
 * kernel and its packets. A scene's 2-thread rows appear where one of them
 * is the best kernel of a ray set (the octant kernel mostly on diffuse
 * rays, the packets on primary and shadow rays). */
static const char *const threaded[] = {"bvh:width=8", PACKET8};

static const int set_bits[3] = {BENCH_PRIMARY, BENCH_SHADOW, BENCH_DIFFUSE};
/* Issue 11's targets for the best wide single-ray kernel over `bvh`. */
static const double target[3] = {2.8, 3.7, 3.7};

static int is_coherent(const char *spec) { return strstr(spec, "traverse=packet") != NULL; }
/* Streams are neither single rays nor packets: rows of their own. */
static int is_stream(const char *spec) { return strstr(spec, "traverse=stream") != NULL; }
static int is_wide(const char *spec) { return strstr(spec, "width=4") || strstr(spec, "width=8"); }

typedef struct {
    exp_text findings;
    int met[3], tie[3], scenes;
    int two[3]; /* rows of 2 threads over 1: met, not met, all */
    int heat;   /* scenes with heatmaps so far (their images' numbers) */
    wide_embree emb; /* Embree's rows and the verdict's comparison */
} study;

/* Embree beside the project's best wide single-thread kernel of primary
 * rays, chosen on the choosing half (wide_embree.h). */
static void embree_row(exp_ctx *x, study *st, const accel_scene *s, const bench_sets *sets,
                       exp_group *g, int first_twin)
{
    int bw = -1;
    g->half = 1;
    for (int c = 0; c < first_twin; c++)
        if (g->cfg[c].ok && is_wide(g->cfg[c].spec) && !is_coherent(g->cfg[c].spec) && !is_stream(g->cfg[c].spec) &&
            (bw < 0 || exp_group_mrays(g, c, BENCH_PRIMARY).median > exp_group_mrays(g, bw, BENCH_PRIMARY).median))
            bw = c;
    g->half = 0;
    if (bw >= 0) wide_embree_row(x, &st->emb, s, sets, g, bw);
}

/* One row of a scene's targets table, quoted by its finding (t == 0: no target). */
static void target_row(exp_ctx *x, exp_text *f, const char *what, int bit, const exp_est *r,
                       double t, const char *outcome)
{
    char a[96], tt[32] = "-";
    exp_fmt_x(a, sizeof a, r);
    if (t > 0) snprintf(tt, sizeof tt, "%gx", t);
    exp_md(x, "| %s | %s | %s | %s | %s |\n", what, bench_set_name(bit), a, tt, t > 0 ? outcome : "-");
    exp_text_add(f, " %s, %s: %s", what, bench_set_name(bit), a);
    if (t > 0) exp_text_add(f, " (target %s: %s)", tt, outcome);
    exp_text_add(f, ";");
}

/* The tree a spec builds: the spec without its traversal choices
 * (traverse=packet|stream, order=branchy, hybrid=0). */
static void tree_of(const char *spec, char *out, size_t n)
{
    snprintf(out, n, "%s", spec);
    static const char *const drop[] = {"traverse=packet", "traverse=stream", "order=branchy", "hybrid=0"};
    for (int d = 0; d < 4; d++) {
        char *p = strstr(out, drop[d]);
        if (!p) continue;
        size_t len = strlen(drop[d]);
        if (p[len] == ',') len++;
        memmove(p, p + len, strlen(p + len) + 1);
    }
    size_t l = strlen(out);
    while (l && (out[l - 1] == ',' || out[l - 1] == ':')) out[--l] = 0;
}

/* Interleaved builds of every distinct tree: build ms, Mtri/s, bytes/tri. */
static void build_table(exp_ctx *x, const accel_scene *s, const exp_group *g)
{
    char trees[MAX_TREES][256];
    int n = 0;
    for (int c = 0; c < g->count && n < MAX_TREES; c++) {
        if (!g->cfg[c].ok || g->cfg[c].threads != 1) continue;
        char t[256];
        tree_of(g->cfg[c].spec, t, sizeof t);
        int dup = 0;
        for (int i = 0; i < n; i++) dup |= !strcmp(trees[i], t);
        if (!dup) snprintf(trees[n++], sizeof trees[0], "%s", t);
    }
    double ms[MAX_TREES][EXP_MAX_SAMPLES];
    accel_build_stats st[MAX_TREES];
    int reps = x->quick ? 3 : 5, done[MAX_TREES] = {0};
    bench_progress_begin(x->progress, "interleaved builds", 0, 0);
    for (int r = 0; r < reps; r++)
        for (int k = 0; k < n; k++) {
            int i = (k + r) % n;
            /* Builds of a second or more get fewer rounds (at least 3). */
            if (r >= 3 && done[i] && ms[i][0] * reps > x->build_budget_ms) continue;
            const accel_kind *kind;
            void *a;
            accel_error err = {0};
            if (accel_build_spec(trees[i], s, 1, &kind, &a, &st[i], &err)) continue;
            kind->destroy(a);
            ms[i][done[i]++] = st[i].ms;
        }
    bench_progress_end(x->progress);
    exp_md_table(x, "tree|build ms [95% CI]|Mtri/s|bytes/tri|nodes|build rounds");
    for (int i = 0; i < n; i++) {
        if (!done[i]) continue;
        exp_est e;
        exp_est_of(ms[i], done[i], &e);
        char b[96];
        double mtri = e.median > 0 ? s->live_count / (e.median * 1e3) : 0;
        double bpt = s->live_count ? (double)st[i].bytes / s->live_count : 0;
        exp_md(x, "| `%s` | %s | %.2f | %.1f | %zu | %d |\n", trees[i], exp_fmt_est(b, sizeof b, &e, 1),
               mtri, bpt, (size_t)st[i].nodes, done[i]);
        exp_csv(x, "%s,%s,build,1,,,,,,,,%.3f,%.3f,%.3f,%.4f,%.2f,,,\n", s->name, trees[i],
                e.median, e.lo, e.hi, mtri, bpt);
    }
}

/* The default scenes, each with its divisor: rays of one in 2 * div^2 of
 * the image's 8x8 tiles, so that the 1M-triangle scenes (div 2) and
 * slivers (div 4: the binary BVH's worst case, about 0.1 Mrays/s) fit the
 * section's budget. The scene heading says so. */
typedef struct {
    const char *spec;
    int div;
    int heat; /* heatmaps of the widths on this scene (heatmaps()) */
} scene_def;

/* Issue 11's "heatmaps of the wide trees look right": node visits and
 * primitive tests per primary ray of each width, and of the 8-wide packets,
 * on one colour scale per row so that the widths compare colour for
 * colour, at 320x240 (the structure shows; the report stays small). */
static const char *const heat_steps[] = {"bvh", "bvh:width=4", "bvh:width=8", PACKET8};
static const char *const heat_prims[] = {"bvh", "bvh:width=4", "bvh:width=8"};

static void heatmaps(exp_ctx *x, const accel_scene *s, int index)
{
    bench_sets sets;
    exp_sets_wh(x, s, BENCH_PRIMARY, 320, 240, 1, &sets);
    char prefix[64];
    exp_md(x, "\nHeatmaps on %s, primary rays at 320x240 (brighter = more; one colour scale per "
              "row, so the widths compare colour for colour). A step of a wide tree is the visit "
              "of a node (its W child boxes tested at once) or of a leaf; its primitive tests "
              "count the distinct primitives of every leaf block tested. The packets charge each of "
              "their steps to the packet's rays from its first active ray on, so 8x8 tiles show:\n",
           s->name);
    snprintf(prefix, sizeof prefix, "wide_heat_steps_%d", index);
    exp_heatmaps_shared(x, heat_steps, (int)(sizeof heat_steps / sizeof heat_steps[0]), s, &sets, 's',
                        prefix);
    snprintf(prefix, sizeof prefix, "wide_heat_prims_%d", index);
    exp_heatmaps_shared(x, heat_prims, (int)(sizeof heat_prims / sizeof heat_prims[0]), s, &sets, 'p',
                        prefix);
    bench_sets_free(&sets);
}

/* Long on purpose (156 lines): one scene's widths: runs, tables, heat maps
 * and findings, in the order the report prints them; the steps share the
 * group, its per-configuration arrays and the study's tallies, which
 * separate functions would take as a dozen parameters each. */
static void measure_scene(exp_ctx *x, study *st, const char *spec, int div, int heat,
                          const exp_list *list)
{
    accel_scene s;
    char why[640];
    if (exp_scene_try(x, spec, &s, why, sizeof why)) {
        exp_md(x, "\n### %s\n\nLeft out: %s.\n", spec, why);
        exp_note_left(x, EXP_LEFT_UNPARSED);
        return;
    }
    bench_sets sets;
    /* One in 2 * div^2 of the 800x600 image's 8x8 tiles: the image's
     * density and coherence (an 8x8 packet covers what it covers in the
     * full image) at a fraction of its work (issue 38's 20 minutes). */
    int stride = exp_sets_tiles(x, &s, MASK, 2 * div * div, &sets);
    exp_md(x, "\n### %s (%u primitives)\n\n", s.name, s.live_count);
    exp_md(x, "Rays of one in %d of the 8x8 pixel tiles of the %dx%d image (its density and "
              "coherence at 1/%d of its work: the section's budget).\n\n",
           stride, x->rt_size[0], x->rt_size[1], stride);
    exp_group g;
    exp_group_init(&g, x, &s, &sets, MASK);
    g.time_builds = 0; /* build_table times each tree once per round */
    g.collapse_ms = x->quick ? 500 : 3000;
    g.thread_probe = 1; /* what the machine gave 2 threads in these rounds (group.h) */
    for (int i = 0; i < list->count; i++) {
        for (size_t k = 0; k < sizeof same_tree / sizeof same_tree[0]; k++)
            g.keep_same |= !strcmp(list->spec[i], same_tree[k]);
        exp_group_add(&g, list->spec[i], 1);
        g.keep_same = 0;
    }
    int twin_of[EXP_MAX_ACCELS + 8];
    int first_twin = g.count;
    for (size_t i = 0; i < sizeof threaded / sizeof threaded[0]; i++) {
        int one = exp_group_find(&g, threaded[i]);
        if (one < 0 || !g.cfg[one].ok) continue;
        twin_of[g.count - first_twin] = one;
        exp_group_add(&g, threaded[i], 2);
    }
    exp_group_run(&g);
    exp_md(x, "\n<!-- appendix -->\n"); /* the build table: the report keeps the kernels' */
    build_table(x, &s, &g);
    exp_md(x, "\n<!-- /appendix -->\n");
    int base = exp_group_find(&g, "bvh");
    if (base < 0 || !g.cfg[base].ok || g.cfg[base].threads != 1) {
        exp_md(x, "\n(no `bvh` single-ray base on this scene: ratios left out)\n");
        base = -1;
    }
    exp_md(x, "\nMrays/s [95%% CI] and speed over `bvh` (single rays, 1 thread) in the same rounds "
              "[95%% CI of the paired ratio]:\n");
    exp_md_table(x, "kernel|threads|primary Mrays/s|x bvh|shadow Mrays/s|x bvh|diffuse Mrays/s|x bvh|"
                    "nodes/ray (p, s, d)|prims/ray (p, s, d)");
    for (int c = 0; c < g.count; c++) {
        const exp_cfg *cf = &g.cfg[c];
        if (!cf->ok) continue;
        exp_md(x, "| `%s` | %d |", cf->spec, cf->threads);
        for (int k = 0; k < 3; k++) {
            exp_est m = exp_group_mrays(&g, c, set_bits[k]);
            exp_est r = base >= 0 ? exp_group_speedup(&g, base, c, set_bits[k]) : (exp_est){0};
            char a[96], b[96];
            exp_md(x, " %s | %s |", exp_fmt_est(a, sizeof a, &m, 2),
                   c == base ? "1.00 (base)" : base >= 0 ? exp_fmt_x(b, sizeof b, &r) : "-");
            exp_csv(x, "%s,%s,%s,%d,%zu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,,,,,%.2f,%.3f,%.3f,%.3f\n",
                    s.name, cf->spec, bench_set_name(set_bits[k]), cf->threads,
                    exp_group_rays(&g, c, set_bits[k]), m.median, m.lo, m.hi,
                    c == base ? 1.0 : r.median, c == base ? 1.0 : r.lo, c == base ? 1.0 : r.hi,
                    s.live_count ? (double)cf->build.bytes / s.live_count : 0.0,
                    exp_group_steps(&g, c, set_bits[k]), exp_group_boxes(&g, c, set_bits[k]),
                    exp_group_prims(&g, c, set_bits[k]));
        }
        exp_md(x, " %.1f, %.1f, %.1f | %.1f, %.1f, %.1f |\n", exp_group_steps(&g, c, BENCH_PRIMARY),
               exp_group_steps(&g, c, BENCH_SHADOW), exp_group_steps(&g, c, BENCH_DIFFUSE),
               exp_group_prims(&g, c, BENCH_PRIMARY), exp_group_prims(&g, c, BENCH_SHADOW),
               exp_group_prims(&g, c, BENCH_DIFFUSE));
    }
    exp_group_note(&g);
    if (base < 0) goto done;
    /* The targets: best wide single kernel per set over bvh, the best
     * coherent one over the best single, 2 threads over 1; each a row of
     * the targets table, then quoted by the findings. */
    exp_md(x, "\nThis section's targets on this scene (paired ratios of the rounds above):\n");
    exp_md_table(x, "comparison|ray set|ratio [95% CI]|target|outcome");
    exp_text_add(&st->findings, "- **%s**:", s.name);
    st->scenes++;
    int hy = exp_group_find(&g, PACKET8), h0 = exp_group_find(&g, HYBRID0);
    int hand_over = hy >= 0 && h0 >= 0 && g.cfg[hy].ok && g.cfg[h0].ok && g.cfg[hy].threads == 1;
    int dp = exp_group_find(&g, "bvh:width=8"), gr = exp_group_find(&g, GREEDY);
    int dp_pair = dp >= 0 && gr >= 0 && g.cfg[dp].ok && g.cfg[gr].ok && g.cfg[dp].threads == 1;
    int sm = exp_group_find(&g, STREAM8);
    int stream_pair = dp >= 0 && sm >= 0 && g.cfg[dp].ok && g.cfg[sm].ok && g.cfg[sm].threads == 1;
    for (int k = 0; k < 3; k++) {
        int bit = set_bits[k], best = -1, bestc = -1;
        g.half = 1; /* issue 52: the bests chosen on half the rounds, judged on the other */
        for (int c = 0; c < first_twin; c++) {
            const exp_cfg *cf = &g.cfg[c];
            if (!cf->ok || !is_wide(cf->spec) || is_stream(cf->spec)) continue;
            int *b = is_coherent(cf->spec) ? &bestc : &best;
            if (*b < 0 || exp_group_ns(&g, c, bit).median < exp_group_ns(&g, *b, bit).median) *b = c;
        }
        g.half = 2;
        exp_est r = best >= 0 ? exp_group_speedup(&g, base, best, bit) : (exp_est){0};
        exp_est rc = best >= 0 && bestc >= 0 ? exp_group_speedup(&g, best, bestc, bit) : (exp_est){0};
        g.half = 0;
        if (best < 0) continue;
        char what[640];
        const char *v = exp_target_outcome(&r, target[k], 1);
        st->met[k] += !strcmp(v, "met");
        st->tie[k] += v[0] == 'a';
        snprintf(what, sizeof what, "best wide single `%s` over `bvh`", g.cfg[best].spec);
        target_row(x, &st->findings, what, bit, &r, target[k], v);
        if (bestc >= 0 && k < 2) {
            snprintf(what, sizeof what, "best coherent `%s` over `%s`", g.cfg[bestc].spec,
                     g.cfg[best].spec);
            target_row(x, &st->findings, what, bit, &rc, k == 0 ? 1.5 : 0,
                       exp_target_outcome(&rc, 1.5, 1));
        }
        /* What the hand-over to single rays pays, on its own: the default
         * 8-wide packets over the same packets with hybrid=0. */
        if (k < 2 && hand_over) {
            exp_est rh = exp_group_speedup(&g, h0, hy, bit);
            snprintf(what, sizeof what, "hand-over to single rays: `%s` (default hybrid) over `%s`", PACKET8,
                     HYBRID0);
            target_row(x, &st->findings, what, bit, &rh, 0, "-");
        }
        /* What the DP collapse pays, on its own: the default 8-wide tree
         * over the greedy collapse of the same binary tree. */
        if (dp_pair) {
            exp_est rd = exp_group_speedup(&g, gr, dp, bit);
            snprintf(what, sizeof what, "DP collapse: `bvh:width=8` (collapse=dp) over `%s`", GREEDY);
            target_row(x, &st->findings, what, bit, &rd, 0, "-");
        }
        /* Ray streams against single rays on the same tree (issue 50). */
        if (stream_pair) {
            exp_est rs = exp_group_speedup(&g, dp, sm, bit);
            snprintf(what, sizeof what, "ray streams: `%s` over `bvh:width=8` (single rays)", STREAM8);
            target_row(x, &st->findings, what, bit, &rs, 0, "-");
        }
        for (int t = first_twin; t < g.count; t++) {
            if (!g.cfg[t].ok) continue;
            /* Both twins (the 8-wide single and packet kernels) get their
             * row, whichever kernel was fastest in this run's rounds: a
             * row that came and went with the pick of the best made the
             * section's shape depend on the noise. */
            int one = twin_of[t - first_twin];
            exp_est rt = exp_group_speedup(&g, one, t, bit);
            char probe[96] = "";
            if (g.probe.n) {
                char pr[64];
                exp_fmt_x(pr, sizeof pr, &g.probe);
                snprintf(probe, sizeof probe, " (thread probe: %s)", pr);
            }
            snprintf(what, sizeof what, "`%s` on 2 threads over 1%s", g.cfg[t].spec, probe);
            /* A second thread needs a free core, and a miss is the
             * kernel's only when the thread probe of the same rounds
             * reached the target (exp_threads_outcome). */
            const char *v2 = exp_threads_outcome(&rt, &g.probe, exp_busy(x), 1.9);
            st->two[0] += !strcmp(v2, "met");
            st->two[1] += !strncmp(v2, "not met", 7);
            st->two[2]++;
            target_row(x, &st->findings, what, bit, &rt, 1.9, v2);
        }
    }
    size_t len = st->findings.len;
    if (len && st->findings.s[len - 1] == ';') st->findings.s[len - 1] = '.';
    exp_text_add(&st->findings, "\n");
    embree_row(x, st, &s, &sets, &g, first_twin);
done:
    exp_group_free(&g);
    bench_sets_free(&sets);
    if (heat) heatmaps(x, &s, st->heat++);
    scene_free(&s);
}

int main(int argc, char **argv)
{
    scene_def scenes[MAX_SCENES];
    int scene_count = 0;
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_wide",
             "How much faster than the binary BVH are 4- and 8-wide BVHs, single and coherent?",
             "Scenes (without --scene): the meshes, soup:tris=1000000, teapot_stadium,\n"
             "sphereflake:spheres=0, slivers; heatmaps of the first --scene.\n");
    exp_limits(&x, MAX_SCENES, EXP_MAX_MESHES);
    if (x.scene_count) {
        const char *given[MAX_SCENES];
        scene_count = exp_scene_list(&x, given, 0, MAX_SCENES);
        for (int i = 0; i < scene_count; i++) scenes[i] = (scene_def){given[i], 1, i == 0};
    } else {
        if (x.quick) {
            scenes[scene_count++] = (scene_def){"sphereflake:level=1,spheres=0", 1, 1};
            scenes[scene_count++] = (scene_def){"slivers:tris=3000,slivers=100", 1, 0};
        } else {
            for (int i = 0; i < x.mesh_count && scene_count < MAX_SCENES - 4; i++)
                scenes[scene_count++] = (scene_def){x.meshes[i], 1, i == 0};
            scenes[scene_count++] = (scene_def){"soup:tris=1000000", 2, 0};
            scenes[scene_count++] = (scene_def){"teapot_stadium", 1, 1};
            scenes[scene_count++] = (scene_def){"sphereflake:spheres=0", 2, 0};
            scenes[scene_count++] = (scene_def){"slivers", 4, 0};
        }
    }
    /* 800x600 passes of 1.4M-triangle scenes: a measured budget per
     * configuration and set, so that big scenes get fewer rounds. */
    if (!x.quick) x.set_budget_ms = 350, x.build_budget_ms = 800;
    exp_header(&x, "Wide BVHs", "(not a lecture claim: the study's targets, in this section's findings) best wide single-ray "
               "kernel >= 2.8x `bvh` on primary rays and >= 3.7x on shadow and diffuse rays; "
               "coherent mode >= 1.5x the best wide single-ray kernel on primary rays; 2 threads "
               ">= 1.9x 1 thread",
               "how much faster than the binary BVH (`bvh`, single rays) are the 4- and 8-wide "
               "BVHs with SIMD kernels, single-ray and coherent (`traverse=packet`, 8x8 tiles), "
               "and the 8-wide tree's ray streams (`traverse=stream`, rows of their own), "
               "on primary, shadow and diffuse rays at %dx%d, and what do they cost to build and "
               "to store? Every kernel of a scene runs in the same interleaved rounds, one "
               "thread, and the 8-wide kernels once more on 2 threads; ratios are paired per "
               "round, with 95%% intervals. A target counts as met when the whole "
               "interval clears it, not met when the whole interval is below it, else a tie; "
               "2 threads against 1 is not testable when other threads were runnable at the start "
               "(half a thread or more on average: no free core), nor when the thread probe "
               "(work that touches no memory, timed on 1 and on 2 threads in the same rounds) "
               "stayed below 1.9x too (its median): then the machine, not the kernel, held the "
               "ratio down. A probe at 1.9x whose interval reaches below it excuses nothing: "
               "such a row keeps its verdict and says so.",
               x.rt_size[0], x.rt_size[1]);
    exp_csv(&x, "scene,spec,set,threads,rays,mrays,mrays_lo,mrays_hi,ratio,ratio_lo,ratio_hi,"
                "build_ms,build_ms_lo,build_ms_hi,build_mtri_per_s,bytes_per_tri,steps_per_ray,"
                "box_per_ray,prims_per_ray\n");
    exp_list list;
    exp_list_make(&x, configs, (int)(sizeof configs / sizeof configs[0]), NULL, &list);
    study st = {0};
    for (int i = 0; i < scene_count; i++) measure_scene(&x, &st, scenes[i].spec, scenes[i].div, scenes[i].heat, &list);
    exp_md(&x, "\n**Findings** (best wide single kernel = the 4- or 8-wide single-ray kernel with "
               "the lowest median time on that set; coherent compared with it in the same rounds):\n\n%s",
           exp_text_str(&st.findings));
    if (st.scenes)
        exp_md(&x, "\nThis section's single-ray targets over %d scene%s: primary 2.8x met on %d (a tie "
                   "on %d), shadow 3.7x met on %d (a tie on %d), diffuse 3.7x met on %d (a tie on "
                   "%d).\n",
               st.scenes, st.scenes > 1 ? "s" : "", st.met[0], st.tie[0], st.met[1], st.tie[1],
               st.met[2], st.tie[2]);
    if (st.two[2])
        exp_md(&x, "\n2 threads over 1 (target 1.9x): met on %d of %d rows, not met on %d; the "
                   "others are ties or not testable, each row saying which.\n",
               st.two[0], st.two[2], st.two[1]);
    if (st.scenes) {
        int all = 3 * st.scenes, met = st.met[0] + st.met[1] + st.met[2];
        int tie = st.tie[0] + st.tie[1] + st.tie[2];
        /* claims.h's one rule: a target missed on one scene refutes */
        const char *v = exp_combine_counts(met, all - met - tie, tie, EXP_EVERY);
        /* a ratio of two configurations timed in the same rounds: a busy
         * machine slows both, so its refutation stands (issue 52) */
        if (st.emb.scenes) /* the industrial kernel measured here: the claim judged against it */
            exp_verdict_num(&x, "wide-bvh", exp_judge(&st.emb.d), &st.emb.d, st.emb.scene,
                            "this section's targets stand for about 1.1x the industrial kernel; "
                            "measured beside it in this run; %s", st.emb.runs);
        else
            exp_md(&x, "\nEmbree: not measured here (make embree needs libembree-dev); the "
                       "verdict is judged on the ratios to `bvh`.\n");
        exp_verdict(&x, "wide-bvh", v, "the scenes of the section",
                    "the best wide single-ray kernel over `bvh`, paired ratios per scene: primary "
                    "2.8x met on %d of %d scenes (a tie on %d), shadow 3.7x met on %d (a tie on "
                    "%d), diffuse 3.7x met on %d (a tie on %d)",
                    st.met[0], st.scenes, st.tie[0], st.met[1], st.tie[1], st.met[2], st.tie[2]);
    }
    exp_md(&x, "\nThe targets are ratios to `bvh` standing in for the industrial CPU kernels measured "
               "on another machine when the targets were set; this report runs no library (the project depends on "
               "none), so the industrial kernel itself is measured by hand on the same triangles and "
               "rays: bvh/README.md, \"Against an industrial kernel on the same rays\".\n");
    exp_md(&x, "\nBuilds: each tree built in its own interleaved rounds (3 for builds that take "
               "more than a fifth of %.1f s, else 5), 1 thread, wall time including the collapse "
               "and leaf packing; the coherent kernels trace the same trees. Trace rounds: at "
               "most %d, at least 3, fewer on the big scenes (a budget of %.1f s of timed work per "
               "configuration and ray set).\n",
           x.build_budget_ms / 1e3, x.repeats, x.set_budget_ms / 1e3);
    exp_text_free(&st.findings);
    exp_list_free(&list);
    return exp_finish(&x);
}
