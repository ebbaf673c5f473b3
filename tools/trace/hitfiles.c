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
#include "scene/scene.h"
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
    fprintf(stderr, "usage: trace compare [--occluded] [--scene SCENE --rays FILE.rays] "
                    "REFERENCE.hits OTHER.hits\n");
    return CLI_EXIT_USAGE;
}

static void compare_help(void)
{
    printf("usage: trace compare [--occluded] [--scene SCENE --rays FILE.rays] REFERENCE.hits "
           "OTHER.hits\n"
           "Compares two hit files (FORMATS.md) ray by ray against the first.\n\n"
           "  closest hits (default): a ray agrees when both miss, or both name the same\n"
           "              triangle with t within 1e-4 * max(1, |t|) and u, v within 1e-3, or\n"
           "              they name different triangles at that t and the ray really hits\n"
           "              both there (a true tie, checked on the scene).\n"
           "  --occluded  any-hit answers (shadow, ao, --occluded rays): a ray agrees when both\n"
           "              miss or both hit, whatever the triangle; an occluded ray the other lets\n"
           "              through is a leak. With --scene, OTHER's triangle must be hit at its t.\n"
           "  --scene S   the scene the hits were traced on (a built-in spec, a mesh or a .scene\n"
           "              file), with --rays, the rays they answer: ties are verified on it.\n"
           "              Without them, different triangles at the same t are counted apart\n"
           "              as \"unverified ties\", never as agreements (exit 1 if any).\n\n");
    cli_help_exit_codes(stdout);
}

/* FORMATS.md "Any-hit answers": hit or miss, and a real hit where the scene is given. */
static int compare_anyhit(const char *na, const accel_hit *a, const char *nb, const accel_hit *b,
                          size_t n, const accel_scene *s, const accel_ray *rays)
{
    hits_anyhit_diff d = hits_compare_anyhit(s, rays, a, b, n);
    printf("any-hit rule: rays %zu  agree %zu  leaks %zu  false_occlusions %zu", d.rays, d.agree,
           d.leaks, d.false_occlusions);
    if (s) printf("  false_hits %zu", d.false_hits);
    printf("\n");
    if (!s) printf("(triangles not checked: no --scene)\n");
    if (d.first_bad != SIZE_MAX) {
        size_t i = d.first_bad;
        printf("first difference: ray %zu: %s %s, %s %s (prim %u t %.9g)\n", i, na,
               a[i].prim != ACCEL_MISS ? "occluded" : "clear", nb,
               b[i].prim != ACCEL_MISS ? "occluded" : "clear", b[i].prim, b[i].t);
    }
    return d.agree == d.rays ? CLI_EXIT_OK : CLI_EXIT_DIFFER;
}

static int compare_closest(const char *na, const accel_hit *a, const char *nb, const accel_hit *b,
                           size_t n, const accel_scene *s, const accel_ray *rays)
{
    hits_diff d = hits_compare(s, rays, a, b, n);
    printf("rays %zu  agree %zu  holes %zu  false_hits %zu  disagreements %zu", d.rays, d.agree,
           d.holes, d.false_hits, d.disagreements);
    if (s) printf("  (of agree: %zu verified ties)\n", d.ties);
    else printf("  unverified_ties %zu\n", d.unverified);
    if (!s && d.unverified)
        printf("%zu rays name different triangles at the same t: a tie by distance, unverified "
               "(give --scene and --rays to check them)\n", d.unverified);
    if (d.first_bad != SIZE_MAX) {
        size_t i = d.first_bad;
        printf("first difference: ray %zu: %s prim %u t %.9g u %.6g v %.6g, %s prim %u t %.9g "
               "u %.6g v %.6g\n", i, na, a[i].prim, a[i].t, a[i].u, a[i].v, nb, b[i].prim, b[i].t,
               b[i].u, b[i].v);
    }
    return d.agree == d.rays ? CLI_EXIT_OK : CLI_EXIT_DIFFER;
}

int trace_compare(int argc, char **argv)
{
    int occluded = 0, first = 2;
    const char *scene_spec = NULL, *rays_path = NULL;
    for (; first < argc && argv[first][0] == '-' && argv[first][1]; first++) {
        const char *opt = argv[first];
        if (!strcmp(opt, "--help") || !strcmp(opt, "-h")) {
            compare_help();
            return CLI_EXIT_OK;
        }
        if (!strcmp(opt, "--occluded")) {
            occluded = 1;
        } else if ((!strcmp(opt, "--scene") || !strcmp(opt, "--rays")) && first + 1 < argc) {
            *(opt[2] == 's' ? &scene_spec : &rays_path) = argv[++first];
        } else {
            fprintf(stderr, "trace compare: unknown option or missing value: %s\n", opt);
            return usage_error();
        }
    }
    if (argc - first != 2) return usage_error();
    if (!scene_spec != !rays_path) {
        fprintf(stderr, "trace compare: --scene and --rays go together (the rays the hits "
                        "answer, on that scene)\n");
        return usage_error();
    }
    const char *na = argv[first], *nb = argv[first + 1];
    accel_error err = {0};
    accel_hit *a = NULL, *b = NULL;
    size_t n_a = 0, n_b = 0;
    accel_scene scene = {0};
    rays_set rays = {0};
    int rc = CLI_EXIT_OK;
    if (hits_read(na, &a, &n_a, &err) || hits_read(nb, &b, &n_b, &err) ||
        (scene_spec && (scene_create(scene_spec, &scene, &err) || rays_read(rays_path, &rays, &err)))) {
        fprintf(stderr, "trace: %s\n", err.msg);
        rc = cli_exit_of(err.code);
    } else if (n_a != n_b || (scene_spec && rays.count != n_a)) {
        fprintf(stderr, "trace: %s has %zu hits, %s has %zu%s", na, n_a, nb, n_b,
                scene_spec ? "" : "\n");
        if (scene_spec) fprintf(stderr, ", %s has %zu rays\n", rays_path, rays.count);
        rc = CLI_EXIT_INPUT;
    } else {
        const accel_scene *s = scene_spec ? &scene : NULL;
        rc = occluded ? compare_anyhit(na, a, nb, b, n_a, s, rays.rays)
                      : compare_closest(na, a, nb, b, n_a, s, rays.rays);
    }
    if (scene_spec) scene_free(&scene);
    rays_free(&rays);
    free(a), free(b);
    return rc;
}
