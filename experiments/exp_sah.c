/*
 * exp_sah - what does the Surface Area Heuristic buy?
 *
 * BVH builders mid (spatial median), median (object median), sah (full
 * sweep) and binned (16 bins): SAH cost of the tree (normalized by the root
 * area), build time and throughput, Mrays/s on primary, shadow and diffuse
 * rays with nodes and primitive tests per ray. The lecture claims that
 * "SAH will double performance, but construction becomes much slower".
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"

static const char *const builders[] = {"bvh:build=mid", "bvh:build=median", "bvh:build=sah",
                                       "bvh:build=binned,bins=16"};
#define NB 4

/* The claim: sah against each median builder, per ray set; binned against sah. */
static void sah_findings(const accel_scene *s, const exp_measure *m, const int *ok,
                         char *findings, size_t fn)
{
    if (!ok[2]) return;
    for (int b = 0; b < 2; b++) {
        if (!ok[b]) continue;
        double sp = m[2].res[0].mrays.median / m[b].res[0].mrays.median;
        double ss = m[2].res[1].mrays.median / m[b].res[1].mrays.median;
        double sd = m[2].res[2].mrays.median / m[b].res[2].mrays.median;
        double slow = m[2].build_ms.median / m[b].build_ms.median;
        exp_append(findings, fn,
                   "- %s: `sah` over `%s`: %.2fx on primary, %.2fx on shadow, %.2fx on "
                   "diffuse rays, for a %.1fx longer build (claim: 2x). %s\n",
                   s->name, builders[b] + 10, sp, ss, sd, slow,
                   (sp >= 1.8 && sd >= 1.8) ? "The claim holds here."
                   : (sp < 1.2 && sd < 1.2) ? "No real gain here."
                                            : "Partly: the gain depends on the ray set.");
    }
    if (ok[3])
        exp_append(findings, fn,
                   "- %s: binned (16 bins) SAH cost %+.1f%% over the full sweep, trace "
                   "speed %.2fx of it on diffuse rays, built %.1fx faster.\n",
                   s->name, 100 * (m[3].build.sah_cost / m[2].build.sah_cost - 1),
                   m[3].res[2].mrays.median / m[2].res[2].mrays.median,
                   m[2].build_ms.median / m[3].build_ms.median);
}

/* One scene: every builder on primary, shadow and diffuse rays. */
static void measure_scene(exp_ctx *x, const char *spec, char *findings, size_t fn)
{
    const int mask = BENCH_PRIMARY | BENCH_SHADOW | BENCH_DIFFUSE;
    accel_scene s;
    exp_scene(x, spec, &s);
    bench_sets sets;
    exp_sets(x, &s, mask, &sets);
    exp_md(x, "\n### %s (%u primitives)\n", s.name, s.live_count);
    exp_md_table(x, "builder|build ms|Mprims/s|SAH cost|primary Mrays/s|nodes/ray|"
                    "prims/ray|shadow Mrays/s|diffuse Mrays/s|nodes/ray|prims/ray");
    exp_measure m[NB];
    int ok[NB] = {0};
    for (int b = 0; b < NB; b++) {
        char why[600];
        if (exp_run(x, builders[b], &s, &sets, mask, &m[b], why, sizeof why)) {
            exp_md(x, "| `%s` | skipped: %s | | | | | | | | | |\n", builders[b], why);
            continue;
        }
        ok[b] = 1;
        const bench_result *p = &m[b].res[0], *sh = &m[b].res[1], *d = &m[b].res[2];
        char bt[64], pm[64], sm[64], dm[64];
        double mtps = s.live_count / (m[b].build_ms.median * 1e3);
        exp_md(x, "| `%s` | %s | %.2f | %.2f | %s | %.1f | %.1f | %s | %s | %.1f | %.1f |\n",
               builders[b] + 4, exp_fmt_timing(bt, sizeof bt, &m[b].build_ms, 1), mtps,
               m[b].build.sah_cost, exp_fmt_timing(pm, sizeof pm, &p->mrays, 2),
               exp_per_ray(p->counters.steps, p), exp_per_ray(p->counters.prim_tests, p),
               exp_fmt_timing(sm, sizeof sm, &sh->mrays, 2),
               exp_fmt_timing(dm, sizeof dm, &d->mrays, 2), exp_per_ray(d->counters.steps, d),
               exp_per_ray(d->counters.prim_tests, d));
        exp_csv(x, "%s,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%llu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,"
                   "%.4f,%.4f,%.3f,%.3f,%.3f,%.3f\n",
                s.name, builders[b], m[b].build_ms.median, m[b].build_ms.min,
                m[b].build_ms.max, mtps, m[b].build.sah_cost,
                (unsigned long long)m[b].build.nodes, p->mrays.median, p->mrays.min,
                p->mrays.max, sh->mrays.median, sh->mrays.min, sh->mrays.max, d->mrays.median,
                d->mrays.min, d->mrays.max, exp_per_ray(p->counters.steps, p),
                exp_per_ray(p->counters.prim_tests, p), exp_per_ray(d->counters.steps, d),
                exp_per_ray(d->counters.prim_tests, d));
    }
    sah_findings(&s, m, ok, findings, fn);
    bench_sets_free(&sets);
    scene_free(&s);
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_sah",
             "How much faster do SAH trees trace than median-split trees, and what does their "
             "build cost?",
             NULL);
    exp_md(&x, "## The Surface Area Heuristic (exp_sah)\n\n"
               "**Question:** how much faster do SAH-built BVHs trace than spatial-median "
               "(`mid`) and object-median (`median`) trees, and how much slower do they build? "
               "SAH cost is the expected cost of the tree with C_trav = 1, C_isect = 1 (the "
               "builder's defaults), normalized by the root's surface area. %dx%d primary rays, "
               "shadow rays to the scene's light, one diffuse bounce.\n\n"
               "**Lecture's claim:** \"SAH will double performance, but construction becomes "
               "much slower\".\n",
               x.size, x.size);
    if (!accel_find_kind("bvh")) {
        exp_md(&x, "\nSkipped: no `bvh` kind is registered.\n");
        return exp_finish(&x);
    }
    const char *scenes[12];
    int scene_count = 0;
    if (x.quick) {
        scenes[scene_count++] = "soup:tris=5000";
    } else {
        for (int i = 0; i < x.mesh_count && scene_count < 4; i++) scenes[scene_count++] = x.meshes[i];
        scenes[scene_count++] = "soup:tris=1000000";
        scenes[scene_count++] = "teapot_stadium";
        scenes[scene_count++] = "sphereflake";
        scenes[scene_count++] = "tetra";
    }
    exp_csv(&x, "scene,spec,build_ms,build_ms_min,build_ms_max,mtris_per_s,sah_cost,nodes,"
                "primary_mrays,primary_min,primary_max,shadow_mrays,shadow_min,shadow_max,"
                "diffuse_mrays,diffuse_min,diffuse_max,primary_nodes,primary_prims,diffuse_nodes,"
                "diffuse_prims\n");
    char findings[4096] = "";
    for (int si = 0; si < scene_count; si++)
        measure_scene(&x, scenes[si], findings, sizeof findings);
    exp_md(&x, "\n**Findings** (measured speed-ups, medians):\n\n%s", findings);
    return exp_finish(&x);
}
