/*
 * lab.c - bin-lab/lab: runs the check of one lab step (LAB.md) on a kind.
 *
 *   make lab STEP=2                  the student's kind, step 2
 *   bin-lab/lab --step 2 --accel student:leaf=2 --out lab/out
 *
 * Exit status: 0 the step passes, 1 it fails, 2 usage error, 3 the check
 * could not run.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"

#ifdef GRIDBVH_LAB
void lab_top_student(const lab_top *top, const accel_ray *ray, accel_hit *hit); /* student.c */
#endif

static int usage(const char *msg)
{
    if (msg) fprintf(stderr, "lab: %s\n", msg);
    fprintf(stderr, "usage: lab --step N [--accel SPEC] [--threads N] [--out DIR] [--quick]\n"
                    "  --step N      lab step 1..%d (LAB.md; optional: 6 a grid, 7 your top level)\n"
                    "  --accel SPEC  the kind to check (default: student; step 6: student_grid)\n"
                    "  --threads N   threads for step 5 (default: all cores)\n"
                    "  --out DIR     where the depth view and images go (default: none)\n"
                    "  --quick       smaller sizes\n"
                    "exit status: 0 pass, 1 fail, 2 usage error, 3 the check could not run\n",
            LAB_STEPS);
    return 2;
}

int main(int argc, char **argv)
{
    int step = 0, threads = accel_cpu_count(), quick = 0;
    const char *spec = NULL, *out_dir = NULL;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        char *end;
        if (!strcmp(a, "--help")) return usage(NULL), 0;
        if (!strcmp(a, "--quick")) {
            quick = 1;
            continue;
        }
        if (!v) return usage("an option is missing its value");
        i++;
        if (!strcmp(a, "--step")) {
            step = (int)strtol(v, &end, 10);
            if (*end || step < 1 || step > LAB_STEPS) return usage("--step takes 1..7");
        } else if (!strcmp(a, "--accel")) {
            spec = v;
        } else if (!strcmp(a, "--threads")) {
            threads = (int)strtol(v, &end, 10);
            if (*end || threads < 1 || threads > 256) return usage("--threads takes 1..256");
        } else if (!strcmp(a, "--out")) {
            out_dir = v;
        } else {
            return usage("unknown option");
        }
    }
    if (!step) return usage("--step is required");
    if (!spec) spec = step == 6 ? "student_grid" : "student";
    accel_params p;
    accel_error err = {0};
    if (accel_params_parse(spec, &p, &err)) {
        fprintf(stderr, "lab: %s\n", err.msg);
        return 2;
    }
    const char *colon = strchr(spec, ':');
    lab_subject s = {p.kind, colon ? colon + 1 : "", threads, out_dir, quick, NULL};
#ifdef GRIDBVH_LAB
    if (!strcmp(p.kind->name, "student")) s.top = lab_top_student; /* step 7 */
#endif
    lab_result r;
    if (lab_check(step, &s, &r, &err)) {
        fprintf(stderr, "lab: %s\n", err.msg);
        return 3;
    }
    fputs(r.report, stdout);
    printf("step %d: %s\n", step, r.passed ? "PASSED" : "not yet");
    return r.passed ? 0 : 1;
}
