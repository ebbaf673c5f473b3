/*
 * vs.c - bin/embree_ref --vs (vs.h). The pairs sit in one process so that a
 * slow spell of the host (tens to hundreds of ms) covers both passes of a
 * pair or neither. Armadillo's 1024x768 primary rays,
 * `bvh:width=8,order=branchy` against Embree 3: 6 pairs of fresh processes
 * of each tracer, one after the other, gave ratios from 0.74 to 1.12
 * (issue 52); 24 processes of the passes in turn, 22 between 1.04 and
 * 1.09 and two at 0.90 and 0.99 (a slow spell of the host in them).
 */
#include <stdio.h>
#include <stdlib.h>

#include "cli/cli.h"
#include "vs.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double vs_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int vs_time(const char *spec, const accel_scene *scene, const accel_ray *rays, size_t n, int threads,
            int occluded, int passes, vs_pass_fn other, void *ctx)
{
    const accel_kind *kind;
    void *a;
    accel_build_stats st;
    accel_error err = {0};
    if (passes < 1 || passes > 1000) passes = passes < 1 ? 1 : 1000;
    if (accel_build_spec(spec, scene, 1, &kind, &a, &st, &err)) {
        fprintf(stderr, "embree_ref: --vs %s: %s\n", spec, err.msg);
        return CLI_EXIT_USAGE;
    }
    accel_hit *hits = malloc((n ? n : 1) * sizeof *hits); /* the other tracer's answers stay */
    uint8_t *occ = malloc(n ? n : 1);
    if (!hits || !occ) {
        fprintf(stderr, "embree_ref: out of memory for --vs %s\n", spec);
        free(hits), free(occ), kind->destroy(a);
        return CLI_EXIT_INTERNAL;
    }
    double ours[1000], theirs[1000], ratio[1000];
    for (int p = -1; p < passes; p++) { /* pass -1: the warm-up of both */
        double t[2];
        for (int k = 0; k < 2; k++) {
            int mine = (p & 1) ? k == 1 : k == 0;
            if (!mine) {
                t[0] = other(ctx);
                continue;
            }
            double t0 = accel_now_ms();
            if (occluded) accel_trace_occluded(kind, a, rays, occ, n, threads, NULL);
            else accel_trace(kind, a, rays, hits, n, threads, NULL);
            t[1] = accel_now_ms() - t0;
        }
        if (p < 0) continue;
        ours[p] = t[1], theirs[p] = t[0], ratio[p] = t[1] > 0 ? t[0] / t[1] : 0;
    }
    double r = vs_median(ratio, passes), mo = vs_median(ours, passes), mt = vs_median(theirs, passes);
    printf("vs spec=%s mrays=%.3f embree_mrays=%.3f ratio=%.4f ratio_min=%.4f ratio_max=%.4f "
           "passes=%d\n", spec, n / (mo * 1e3), n / (mt * 1e3), r, ratio[0], ratio[passes - 1], passes);
    fflush(stdout);
    kind->destroy(a);
    free(hits), free(occ);
    return 0;
}
