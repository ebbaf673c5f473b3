/*
 * exp_threads - how do build and trace scale with threads, and is ray
 * tracing real-time at the lecture's 800x600?
 *
 * Part 1, scaling: every kind's default (brute left out: it says nothing
 * about structures) and BVH packets build and trace primary and diffuse
 * rays at 800x600 with 1..N threads (N: every logical CPU, or --threads),
 * all thread counts in interleaved rounds; speed-ups are paired ratios.
 * Work is handed out in chunks that scale with the job
 * (accel_trace_chunk: about 16 per thread, whole 8x8 packets).
 * Part 2, real time: primary plus shadow rays at 800x600 on every thread,
 * the fastest configuration per scene; a frame is one primary and one
 * shadow pass (plus the rebuild, for an animated scene). The lecture:
 * "BVH + ray packets = real-time performance", 20 fps at 800x600, 9.6M
 * primary plus 9.6M shadow rays per second; "near-linear scaling in
 * cores, about +20% from hyper-threading"; past 100M rays/s "easily".
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/group.h"
#include "engine/machine.h"

#define SCALE_MASK (BENCH_PRIMARY | BENCH_DIFFUSE)
#define FRAME_MASK (BENCH_PRIMARY | BENCH_SHADOW)
#define TARGET_FPS 20.0
/* "Near-linear scaling in cores": a parallel efficiency (speed-up over 1
 * thread, divided by the threads) of at least 90%, i.e. less than a tenth
 * of each added core lost, on 2 cores at least 1.8x (issue 38 asks for the
 * claim's number; 0.85 before it). */
#define NEAR_LINEAR 0.90
/* Ray generation timed per frame (issue 38: one frame definition). */
#define GEN_REPS 10

/* The fastest kernel of exp_wide (8-wide packets) is among them, so that
 * the 100M rays/s verdict rests on the study's fastest primary rays. */
static const char *const scale_specs[] = {"bvh", "grid", "nested_grid", "bvh:traverse=packet",
                                          "bvh:width=8", "bvh:width=8,traverse=packet",
                                          "irregular_grid"};
static const char *const frame_specs[] = {"bvh", "bvh:traverse=packet",
                                          "bvh:traverse=packet,frustum=1", "bvh:width=4",
                                          "bvh:width=8", "grid:traverse=packet", "instanced"};

typedef struct {
    int linear, kinds;
    exp_tally lin, rt; /* issue 38's rules: efficiency >= NEAR_LINEAR, fps >= TARGET_FPS */
    int rt_count;      /* the scenes of the real-time test (the tally's m) */
    exp_est best_est;  /* the fastest primary Mrays/s, with its interval */
    exp_decider best_norm; /* best_est against 100 Mrays/s, normalized to the reference rate */
    const char *best_norm_v;
    char best_why[400];
    exp_text rt_norm;  /* the real-time rows' normalization, per scene */
    double best_mrays, best_per_thread;
    char best_spec[512];
    exp_text lin_ev, findings;
    int rt_yes, rt_scenes;
    exp_text rt_ev, rt_names, left;
    double ht_gain;
    int ht_tested;
    double probe_eff; /* the thread probe's efficiency, or -1 */
} study;

/* Long on purpose (105 lines): the thread-count runs, efficiency table and
 * findings, in the order the report prints them; the steps share the group,
 * its per-configuration arrays and the study's tallies, which separate
 * functions would take as a dozen parameters each. */
static void scaling(exp_ctx *x, study *st, int max_t, const exp_machine *mach)
{
    const char *spec = x->scene_count ? x->scenes[0] : x->quick ? "soup:tris=20000"
                       : x->mesh_count ? x->meshes[0] : "soup:tris=200000";
    accel_scene s;
    exp_scene(x, spec, &s);
    bench_sets sets;
    exp_sets_wh(x, &s, SCALE_MASK, x->rt_size[0], x->rt_size[1], 1, &sets);
    exp_md(x, "\n### Scaling on %s (%u primitives), %dx%d\n\nRays are handed out from a shared "
              "counter in chunks of %zu primary rays at %d threads (about 16 per thread, at most "
              "%d).\n", s.name, s.live_count, x->rt_size[0], x->rt_size[1],
           accel_trace_chunk((size_t)x->rt_size[0] * x->rt_size[1], max_t), max_t, ACCEL_CHUNK);
    exp_list list;
    exp_list_make(x, scale_specs, (int)(sizeof scale_specs / sizeof scale_specs[0]), NULL, &list);
    exp_group g;
    exp_group_init(&g, x, &s, &sets, SCALE_MASK);
    g.collapse_ms = x->quick ? 1000 : 4000;
    g.thread_probe = 1; /* what the machine gave the threads in these rounds (group.h) */
    for (int i = 0; i < list.count; i++)
        for (int t = 1; t <= max_t; t++) {
            int c = exp_group_add(&g, list.spec[i], t);
            if (g.cfg[c].left == EXP_LEFT_UNPARSED) break;
        }
    exp_group_run(&g);
    int at_max = 0;
    for (int c = 0; c < g.count; c++) at_max += g.cfg[c].ok && g.cfg[c].threads == max_t && max_t > 1;
    exp_tally_init(&st->lin, 2 * at_max); /* primary and diffuse of each configuration */
    exp_md_table(x, "configuration|threads|build ms [95% CI]|build speed-up|primary Mrays/s|"
                    "speed-up|efficiency|diffuse Mrays/s|speed-up|efficiency");
    for (int c = 0; c < g.count; c++) {
        const exp_cfg *cf = &g.cfg[c];
        if (!cf->ok) continue;
        int one = -1;
        for (int d = 0; d < g.count; d++)
            if (g.cfg[d].ok && g.cfg[d].threads == 1 && !strcmp(g.cfg[d].spec, cf->spec)) one = d;
        if (one < 0) continue;
        exp_est bs, ps = exp_group_speedup(&g, one, c, BENCH_PRIMARY),
                    ds = exp_group_speedup(&g, one, c, BENCH_DIFFUSE);
        int m = cf->build_ms.n < g.cfg[one].build_ms.n ? cf->build_ms.n : g.cfg[one].build_ms.n;
        exp_est_ratio(g.cfg[one].build_samples, cf->build_samples, m, &bs);
        exp_est pm = exp_group_mrays(&g, c, BENCH_PRIMARY), dm = exp_group_mrays(&g, c, BENCH_DIFFUSE);
        char b[96], b2[96], p1[96], p2[96], d1[96], d2[96];
        double t = cf->threads;
        exp_md(x, "| `%s` | %d | %s | %s | %s | %s | %.0f%% | %s | %s | %.0f%% |\n", cf->spec,
               cf->threads, exp_fmt_est(b, sizeof b, &cf->build_ms, 1), exp_fmt_x(b2, sizeof b2, &bs),
               exp_fmt_est(p1, sizeof p1, &pm, 2), exp_fmt_x(p2, sizeof p2, &ps),
               100 * ps.median / t, exp_fmt_est(d1, sizeof d1, &dm, 2),
               exp_fmt_x(d2, sizeof d2, &ds), 100 * ds.median / t);
        exp_csv(x, "scaling,%s,%s,%d,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", s.name,
                cf->spec, cf->threads, cf->build_ms.median, cf->build_ms.lo, cf->build_ms.hi,
                pm.median, pm.lo, pm.hi, ps.median, dm.median, dm.lo, dm.hi, ds.median);
        if (pm.median > st->best_mrays)
            st->best_norm = exp_decider_of("the fastest primary Mrays/s of the scaling table, "
                                           "normalized to the reference rate", &pm, 100.0, +1),
            st->best_norm_v = exp_group_absolute(&g, &st->best_norm, 1, st->best_why, sizeof st->best_why),
            st->best_mrays = pm.median, st->best_per_thread = pm.median / t, st->best_est = pm,
            snprintf(st->best_spec, sizeof st->best_spec, "%s on %d thread%s, %s", cf->spec,
                     cf->threads, cf->threads > 1 ? "s" : "", s.name);
        if (cf->threads == max_t && max_t > 1) {
            /* Near-linear: the efficiency's whole interval at NEAR_LINEAR or
             * above on both sets (the report's rule for every target). */
            int ok = ps.lo / t >= NEAR_LINEAR && ds.lo / t >= NEAR_LINEAR;
            st->kinds++, st->linear += ok;
            for (int k = 0; k < 2; k++) {
                int bit = k ? BENCH_DIFFUSE : BENCH_PRIMARY;
                exp_est e = exp_group_speedup_level(&g, one, c, bit, exp_tally_level(&st->lin));
                e = exp_est_scale(&e, 1.0 / t);
                char what[700];
                snprintf(what, sizeof what, "efficiency of `%s` on %d threads, %s %u tris, %s "
                         "%dx%d", cf->spec, cf->threads, s.name, s.live_count,
                         bench_set_name(bit), x->rt_size[0], x->rt_size[1]);
                exp_decider d = exp_decider_of(what, &e, NEAR_LINEAR, +1);
                exp_tally_add(&st->lin, &d);
            }
            exp_text_add(&st->findings, "- `%s`: %d threads trace primary rays %s and diffuse rays "
                         "%s as fast as 1 (efficiency %.0f%% / %.0f%%); build %s.\n", cf->spec,
                         cf->threads, p2, d2, 100 * ps.median / t, 100 * ds.median / t, b2);
            exp_text_add(&st->lin_ev, "%s%s %.0f%%/%.0f%% (interval lower ends %.0f%%/%.0f%%)",
                         st->lin_ev.len ? ", " : "", cf->spec, 100 * ps.median / t,
                         100 * ds.median / t, 100 * ps.lo / t, 100 * ds.lo / t);
        }
        /* SMT: from one thread per core to every logical CPU. */
        if (mach->threads_per_core > 1 && cf->threads == max_t && max_t > mach->cores) {
            for (int d = 0; d < g.count; d++)
                if (g.cfg[d].ok && g.cfg[d].threads == mach->cores && !strcmp(g.cfg[d].spec, cf->spec)) {
                    exp_est h = exp_group_speedup(&g, d, c, SCALE_MASK);
                    st->ht_gain = fmax(st->ht_gain, h.median - 1), st->ht_tested = 1;
                }
        }
    }
    if (g.probe.n) {
        char pr[96];
        exp_fmt_x(pr, sizeof pr, &g.probe);
        exp_md(x, "\nThread probe (work that touches no memory, timed on 1 and on %d threads in the "
                  "same rounds): %s, efficiency %.0f%%: what this machine gave %d threads while "
                  "the table was measured (a kernel can pass it: two cores also bring two "
                  "caches).\n",
               g.probe_threads, pr, 100 * g.probe.median / g.probe_threads, g.probe_threads);
        exp_text_add(&st->findings, "- Thread probe (no memory traffic): %d threads %s as fast as 1 "
                     "(efficiency %.0f%%).\n", g.probe_threads, pr,
                     100 * g.probe.median / g.probe_threads);
        st->probe_eff = g.probe.median / g.probe_threads;
    }
    exp_group_note(&g);
    exp_group_free(&g);
    exp_list_free(&list);
    bench_sets_free(&sets);
    scene_free(&s);
}

/* The time to generate one frame's rays at x->rt_size (issue 38: one frame
 * definition, ray generation included): primary rays from the camera and
 * shadow rays from the primary hits, GEN_REPS times on one thread. */
static exp_est ray_gen_ms(exp_ctx *x, const accel_scene *s, const bench_sets *sets)
{
    double v[GEN_REPS];
    int n = 0;
    for (int r = 0; r < GEN_REPS; r++) {
        rays_set p = {0}, sh = {0};
        accel_error err = {0};
        double t0 = accel_now_ms();
        int rc = rays_primary(&s->camera, x->rt_size[0], x->rt_size[1], &p, &err);
        if (!rc && sets->primary_hits) rc = rays_shadow(s, &p, sets->primary_hits, &sh, &err);
        double t1 = accel_now_ms();
        rays_free(&p), rays_free(&sh);
        if (!rc) v[n++] = t1 - t0;
    }
    exp_est e;
    exp_est_of(v, n, &e);
    return e;
}

/* One scene of the real-time test: the fastest configuration's frame. */
static void frame_scene(exp_ctx *x, study *st, const char *spec, int max_t, int animated)
{
    accel_scene s;
    char why[600];
    if (exp_scene_try(x, spec, &s, why, sizeof why)) {
        exp_md(x, "\nLeft out: scene `%s` (not in this build: %s).\n", spec, why);
        exp_note_left(x, EXP_LEFT_UNPARSED);
        return;
    }
    bench_sets sets;
    exp_sets_wh(x, &s, FRAME_MASK, x->rt_size[0], x->rt_size[1], 1, &sets);
    exp_list list;
    exp_list_make(x, frame_specs, (int)(sizeof frame_specs / sizeof frame_specs[0]), NULL, &list);
    exp_group g;
    exp_group_init(&g, x, &s, &sets, FRAME_MASK);
    g.collapse_ms = x->quick ? 1000 : 3000;
    for (int i = 0; i < list.count; i++) exp_group_add(&g, list.spec[i], max_t);
    exp_group_run(&g);
    exp_est gen = ray_gen_ms(x, &s, &sets);
    int best = -1, pb[EXP_MAX_SAMPLES];
    g.half = 1; /* issue 52: the fastest chosen on half the rounds, judged on the other */
    for (int c = 0; c < g.count; c++)
        if (g.cfg[c].ok && (best < 0 || exp_group_ns(&g, c, FRAME_MASK).median <
                                            exp_group_ns(&g, best, FRAME_MASK).median))
            best = c;
    for (int c = 0; c < g.count; c++) {
        const exp_cfg *cf = &g.cfg[c];
        if (!cf->ok) continue;
        double v[EXP_MAX_SAMPLES];
        g.half = c == best ? 2 : 0;
        int n = exp_group_round_ms(&g, c, FRAME_MASK, v);
        exp_est frame, fps;
        exp_est_of_level(v, exp_group_procs(&g, pb), n, exp_tally_level(&st->rt), &frame);
        g.half = 0;
        /* The rays of the frame are made in the frame (ray generation's
         * interval added, as the build's below). */
        frame.median += gen.median, frame.lo += gen.lo, frame.hi += gen.hi;
        if (animated) { /* the structure is rebuilt every frame */
            frame.median += cf->build_ms.median, frame.lo += cf->build_ms.lo, frame.hi += cf->build_ms.hi;
        }
        fps = exp_est_inv(&frame, 1e3);
        exp_est rate = exp_est_inv(&frame, (double)exp_group_rays(&g, c, FRAME_MASK) / 1e3);
        char f[96], p[96], r[96];
        exp_md(x, "| %s | `%s` | %s | %s | %s | %s |\n", s.name, cf->spec,
               exp_fmt_est(f, sizeof f, &frame, 1), exp_fmt_est(p, sizeof p, &fps, 1),
               exp_fmt_est(r, sizeof r, &rate, 1),
               c == best ? "fastest (chosen on half the rounds, shown on the other half)" : "");
        exp_csv(x, "frame,%s,%s,%d,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,,,,,\n", s.name, cf->spec, max_t,
                frame.median, frame.lo, frame.hi, fps.median, fps.lo, fps.hi);
        if (c == best) {
            char what[700];
            snprintf(what, sizeof what, "fps of `%s` on %d threads, %s %u tris, primary+shadow "
                     "%dx%d, ray generation%s included", cf->spec, max_t, s.name, s.live_count,
                     x->rt_size[0], x->rt_size[1], animated ? " and rebuild" : "");
            exp_decider d = exp_decider_of(what, &fps, TARGET_FPS, +1);
            char why[400]; /* issue 52: judged on the fps normalized to the reference rate */
            if (strcmp(exp_group_absolute(&g, &d, 1, why, sizeof why), EXP_UNTESTABLE))
                exp_tally_add(&st->rt, &d);
            else
                exp_tally_untestable(&st->rt);
            exp_text_add(&st->rt_norm, "%s%s: %.1f fps normalized, %s", st->rt_norm.len ? "; " : "",
                         s.name, d.value, why);
            int yes = fps.lo >= TARGET_FPS;
            st->rt_scenes++, st->rt_yes += yes;
            exp_text_add(&st->rt_ev, "%s%s %s fps", st->rt_ev.len ? ", " : "", s.name, p);
            exp_text_add(&st->rt_names, "%s%s", st->rt_names.len ? ", " : "", s.name);
        }
    }
    exp_text left = {0};
    for (int c = 0; c < g.count; c++)
        if (g.cfg[c].left)
            exp_text_add(&left, "%s`%s` (%s)", left.len ? "; " : "", g.cfg[c].spec, g.cfg[c].why);
    if (left.len) exp_text_add(&st->left, "- %s: %s.\n", s.name, exp_text_str(&left));
    char gb[96];
    exp_md(x, "| %s | (ray generation, 1 thread, in every frame above) | %s | | | |\n", s.name,
           exp_fmt_est(gb, sizeof gb, &gen, 1));
    exp_text_free(&left);
    exp_group_free(&g);
    exp_list_free(&list);
    bench_sets_free(&sets);
    scene_free(&s);
}

static void verdicts(exp_ctx *x, study *st, int max_t, const exp_machine *m)
{
    if (max_t < 2)
        exp_verdict(x, "threads-linear", EXP_UNTESTABLE, "-", "one thread only in this run");
    else if (exp_busy(x) && st->linear < st->kinds)
        exp_verdict(x, "threads-linear", EXP_UNTESTABLE, "-", "%.1f other runnable threads at the "
                    "start: other work held some of the %d CPUs, so efficiencies of %s measure "
                    "the sharing, not the scaling", x->others_start, m->logical,
                    exp_text_str(&st->lin_ev));
    else if (st->probe_eff >= 0 && st->probe_eff < NEAR_LINEAR && st->linear < st->kinds)
        exp_verdict(x, "threads-linear", EXP_UNTESTABLE, "-", "the thread probe (work that touches no "
                    "memory) reached %.0f%% efficiency on %d threads, below the %.0f%% asked of the "
                    "kernels: the machine, not the kernels, held them down (%s)", 100 * st->probe_eff,
                    max_t, 100 * NEAR_LINEAR, exp_text_str(&st->lin_ev));
    else if (st->lin.added)
        exp_verdict_num(x, "threads-linear", exp_tally_verdict(&st->lin), &st->lin.worst,
                        x->quick ? "soup:tris=20000" : "see the table",
                        "near-linear read as a parallel efficiency of at least %.0f%% on %d threads, "
                        "on each of %d comparisons (configuration x primary/diffuse; intervals at "
                        "%.2f%%, Bonferroni): %d confirm, %d miss, %d on the line (medians: %s)",
                        100 * NEAR_LINEAR, max_t, st->lin.added, 100 * exp_tally_level(&st->lin),
                        st->lin.confirmed, st->lin.refuted, st->lin.online,
                        exp_text_str(&st->lin_ev));
    if (!st->ht_tested)
        exp_verdict(x, "threads-ht", EXP_UNTESTABLE, "-", "the CPU presents %d thread%s per core "
                    "(%d logical CPUs, %d cores%s): no SMT siblings to add", m->threads_per_core,
                    m->threads_per_core > 1 ? "s" : "", m->logical, m->cores,
                    m->virtual_machine ? ", as the virtual machine shows them" : "");
    else
        exp_verdict(x, "threads-ht", fabs(st->ht_gain - 0.2) <= 0.1 ? EXP_CONFIRMED : EXP_PARTLY,
                    "see the table", "the SMT threads add %+.0f%% over one thread per core",
                    100 * st->ht_gain);
    if (st->best_mrays > 0) {
        exp_decider d = st->best_norm;
        const char *v = st->best_norm_v;
        /* A miss on a machine with few cores says nothing of "easily past
         * 100M with multithreading": not testable unless it is reached. */
        if (strcmp(v, EXP_CONFIRMED)) v = EXP_UNTESTABLE;
        exp_verdict_num(x, "threads-100m", v, &d, "see the table",
                        "%d logical CPUs reach %.1f Mrays/s on primary rays (%s, %.1f per thread); "
                        "100M would need about %.0f threads at that rate; %s", m->logical, st->best_mrays,
                        st->best_spec, st->best_per_thread, ceil(100 / st->best_per_thread),
                        st->best_why);
    }
    if (!st->rt.added && st->rt.untestable)
        exp_verdict(x, "realtime-20fps", EXP_UNTESTABLE, exp_text_str(&st->rt_names),
                    "no scene could be judged against 20 fps here (%s)", exp_text_str(&st->rt_norm));
    if (st->rt.added) {
        const char *v = exp_tally_verdict(&st->rt);
        v = x->quick ? EXP_UNTESTABLE : strcmp(v, EXP_REFUTED) ? v : exp_slow_verdict(x, v);
        char gate[300];
        v = exp_thread_gate(x, max_t, v, gate, sizeof gate);
        exp_verdict_num(x, "realtime-20fps", v, &st->rt.worst, exp_text_str(&st->rt_names),
                        "the fastest configuration per scene on %d thread%s against 20 fps at "
                        "%dx%d, a frame being ray generation plus primary and shadow traces, on "
                        "each of %d scenes (intervals at %.2f%%, Bonferroni): %d confirm, %d miss, "
                        "%d on the line, %d not testable (%s; %s)%s%s%s", max_t, max_t > 1 ? "s" : "", x->rt_size[0],
                        x->rt_size[1], st->rt.added, 100 * exp_tally_level(&st->rt),
                        st->rt.confirmed, st->rt.refuted, st->rt.online, st->rt.untestable,
                        exp_text_str(&st->rt_ev), exp_text_str(&st->rt_norm),
                        x->quick ? "; quick budget: not the lecture's image size"
                        : exp_busy(x) ? "; the machine was busy (other runnable threads at the "
                                        "start): these rates are lower bounds" : "",
                        gate[0] ? "; " : "", gate);
    }
}

int main(int argc, char **argv)
{
    exp_ctx x;
    exp_init(&x, argc, argv, "exp_threads",
             "How do build and trace times scale with threads, and is it real-time at 800x600?",
             NULL);
    exp_limits(&x, EXP_MAX_MESHES, 2);
    exp_machine mach;
    exp_machine_read(&mach);
    int max_t = x.threads_given ? x.threads : mach.logical;
    exp_header(&x, "Threads and real time", "\"BVH + ray packets = real-time performance\": "
               "800\xc3\x97" "600 at 20 fps is 9.6M primary plus 9.6M shadow rays per second; "
               "multithreading \"easily\" pushes past 100M rays/s, \"near-linear scaling in cores, "
               "and about +20%% from hyper-threading\"",
               "how do build and trace times scale from 1 to %d threads (%s; the CPU presents %d "
               "thread%s per core), and how many frames per second of primary plus shadow rays "
               "does the fastest configuration reach at %dx%d on every thread? Interleaved "
               "rounds; speed-ups are paired ratios.",
               max_t, x.threads_given ? "the --threads limit" : "every logical CPU",
               mach.threads_per_core, mach.threads_per_core > 1 ? "s" : "", x.rt_size[0],
               x.rt_size[1]);
    exp_csv(&x, "part,scene,spec,threads,build_or_frame_ms,lo,hi,primary_mrays_or_fps,lo2,hi2,"
                "primary_speedup,diffuse_mrays,diffuse_lo,diffuse_hi,diffuse_speedup\n");
    study st = {0};
    st.probe_eff = -1;
    if (!x.quick) x.set_budget_ms = 500; /* 800x600 passes: fewer, longer rounds */
    scaling(&x, &st, max_t, &mach);
    exp_md(&x, "\n### Real time: frames per second at %dx%d, primary plus shadow rays, %d "
               "thread%s\n", x.rt_size[0], x.rt_size[1], max_t, max_t > 1 ? "s" : "");
    exp_md_table(&x, "scene|configuration|frame ms [95% CI]|fps [95% CI]|Mrays/s [95% CI]|note");
    exp_tally_init(&st.rt, x.scene_count ? x.scene_count : x.quick ? 1
                           : (x.mesh_count < 2 ? x.mesh_count : 2) + 3);
    if (x.scene_count) {
        const char *given[EXP_MAX_MESHES];
        int n = exp_scene_list(&x, given, 0, EXP_MAX_MESHES);
        for (int i = 0; i < n; i++) frame_scene(&x, &st, given[i], max_t, 0);
    } else if (x.quick) {
        frame_scene(&x, &st, "sphereflake:level=2", max_t, 0);
    } else {
        for (int i = 0; i < x.mesh_count && i < 2; i++) frame_scene(&x, &st, x.meshes[i], max_t, 0);
        frame_scene(&x, &st, "sphereflake", max_t, 0);
        frame_scene(&x, &st, "teapot_stadium", max_t, 0);
        frame_scene(&x, &st, "animated:frame=0", max_t, 1);
    }
    if (st.left.len) exp_md(&x, "\nLeft out:\n\n%s", exp_text_str(&st.left));
    exp_md(&x, "\nA frame of an animated scene (`animated:...`) includes rebuilding its structure "
               "(the build time's interval added to the trace's).\n");
    exp_md(&x, "\n**Findings:**\n\n%s", exp_text_str(&st.findings));
    verdicts(&x, &st, max_t, &mach);
    exp_text_free(&st.findings);
    exp_text_free(&st.lin_ev);
    exp_text_free(&st.rt_ev);
    exp_text_free(&st.rt_names);
    exp_text_free(&st.rt_norm);
    exp_text_free(&st.left);
    return exp_finish(&x);
}
