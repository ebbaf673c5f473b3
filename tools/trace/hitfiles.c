/*
 * hitfiles.c - `trace compare` and the any-hit answers of --dump-hits
 * (hitfiles.h).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "rays/rays.h"
#include "tools/trace/hitfiles.h"

size_t trace_anyhit_answers(const accel_kind *kind, const void *accel, const accel_scene *scene,
                            const accel_ray *rays, const uint8_t *occ, size_t n, int threads,
                            accel_hit *out)
{
    const accel_hit miss = {INFINITY, ACCEL_MISS, 0.0f, 0.0f};
    accel_trace(kind, accel, rays, out, n, threads, NULL);
    size_t lost = 0;
    for (size_t i = 0; i < n; i++) {
        if (!occ[i]) out[i] = miss;
        else if (out[i].prim == ACCEL_MISS) lost++;
    }
    if (!lost) return 0;
    /* Occluded, but the closest-hit query found nothing: the reference names a triangle. */
    accel_ray *r = malloc(lost * sizeof *r);
    accel_hit *h = malloc(lost * sizeof *h);
    size_t k = 0, left = lost;
    if (r && h) {
        for (size_t i = 0; i < n; i++)
            if (occ[i] && out[i].prim == ACCEL_MISS) r[k++] = rays[i];
        accel_reference_trace(scene, r, h, lost, threads);
        k = 0;
        for (size_t i = 0; i < n; i++)
            if (occ[i] && out[i].prim == ACCEL_MISS) {
                if (h[k].prim != ACCEL_MISS) out[i] = h[k], left--;
                k++;
            }
    }
    free(r), free(h);
    return left;
}

static int usage_error(void)
{
    fprintf(stderr, "usage: trace compare [--occluded] REFERENCE.hits OTHER.hits\n");
    return CLI_EXIT_USAGE;
}

static void compare_help(void)
{
    printf("usage: trace compare [--occluded] REFERENCE.hits OTHER.hits\n"
           "Compares two hit files (FORMATS.md) ray by ray against the first.\n\n"
           "  --occluded  any-hit answers (shadow, ao, --occluded rays): a ray agrees when both\n"
           "              miss or both hit, whatever the triangle; an occluded ray the other lets\n"
           "              through is a leak. Without it, the closest-hit rule: both miss, or\n"
           "              the same triangle, or the same t within 1e-4 * max(1, |t|).\n\n");
    cli_help_exit_codes(stdout);
}

/* FORMATS.md "Any-hit answers": only hit or miss counts. */
static int compare_anyhit(const char *na, const accel_hit *a, const char *nb, const accel_hit *b,
                          size_t n)
{
    size_t leaks = 0, false_occ = 0, first = SIZE_MAX;
    for (size_t i = 0; i < n; i++) {
        int ha = a[i].prim != ACCEL_MISS, hb = b[i].prim != ACCEL_MISS;
        leaks += ha && !hb;
        false_occ += !ha && hb;
        if (ha != hb && first == SIZE_MAX) first = i;
    }
    printf("any-hit rule: rays %zu  agree %zu  leaks %zu  false_occlusions %zu\n", n,
           n - leaks - false_occ, leaks, false_occ);
    if (first != SIZE_MAX)
        printf("first difference: ray %zu: %s %s, %s %s\n", first, na,
               a[first].prim != ACCEL_MISS ? "occluded" : "clear", nb,
               b[first].prim != ACCEL_MISS ? "occluded" : "clear");
    return leaks + false_occ ? CLI_EXIT_DIFFER : CLI_EXIT_OK;
}

int trace_compare(int argc, char **argv)
{
    int occluded = 0, first = 2;
    for (; first < argc && argv[first][0] == '-' && argv[first][1]; first++) {
        if (!strcmp(argv[first], "--help") || !strcmp(argv[first], "-h")) {
            compare_help();
            return CLI_EXIT_OK;
        }
        if (strcmp(argv[first], "--occluded")) {
            fprintf(stderr, "trace compare: unknown option %s\n", argv[first]);
            return usage_error();
        }
        occluded = 1;
    }
    if (argc - first != 2) return usage_error();
    const char *na = argv[first], *nb = argv[first + 1];
    accel_error err = {0};
    accel_hit *a = NULL, *b = NULL;
    size_t n_a = 0, n_b = 0;
    if (hits_read(na, &a, &n_a, &err) || hits_read(nb, &b, &n_b, &err)) {
        fprintf(stderr, "trace: %s\n", err.msg);
        free(a);
        return cli_exit_of(err.code);
    }
    if (n_a != n_b) {
        fprintf(stderr, "trace: %s has %zu hits, %s has %zu\n", na, n_a, nb, n_b);
        free(a), free(b);
        return CLI_EXIT_INPUT;
    }
    int rc;
    if (occluded) {
        rc = compare_anyhit(na, a, nb, b, n_a);
    } else {
        hits_diff d = hits_compare(a, b, n_a);
        printf("rays %zu  agree %zu  holes %zu  false_hits %zu  disagreements %zu\n", d.rays,
               d.agree, d.holes, d.false_hits, d.disagreements);
        if (d.first_bad != SIZE_MAX) {
            size_t i = d.first_bad;
            printf("first difference: ray %zu: %s prim %u t %.9g, %s prim %u t %.9g\n", i, na,
                   a[i].prim, a[i].t, nb, b[i].prim, b[i].t);
        }
        rc = d.agree == d.rays ? CLI_EXIT_OK : CLI_EXIT_DIFFER;
    }
    free(a), free(b);
    return rc;
}
