/*
 * group_duel.c - the decider pass (group.h: exp_group_duel).
 */
#include <stdlib.h>
#include <string.h>
#include "group.h"
#include "cli/cli.h"

void exp_group_duel(const exp_group *g, int a, int b, int mask, int builds, exp_group *d)
{
    exp_ctx *x = g->x;
    exp_group_init(d, x, g->s, g->sets, mask & g->mask);
    d->cfg = malloc(2 * sizeof *d->cfg);
    if (!d->cfg) {
        fprintf(stderr, "%s: out of memory\n", x->name);
        exit(CLI_EXIT_INTERNAL);
    }
    d->count = d->cap = 2;
    d->duel = 1;
    d->control = 0;       /* two slots: A B, then B A (group_run.c's rotation) */
    d->time_builds = builds;
    d->build_twice = builds;
    d->proc_rounds = x->quick ? EXP_DUEL_ROUNDS_QUICK : EXP_DUEL_ROUNDS;
    if (builds && !x->quick) { /* group.h: a build ratio needs more processes */
        d->want_procs = EXP_DUEL_BUILD_PROCS;
        d->proc_rounds = EXP_MAX_SAMPLES / EXP_DUEL_BUILD_PROCS;
    }
    int from[2] = {a, b};
    for (int i = 0; i < 2; i++) {
        exp_cfg *c = &d->cfg[i];
        *c = g->cfg[from[i]]; /* the parent's structure, counts and warm-up pass */
        memset(c->build_samples, 0, sizeof c->build_samples);
        c->build_samples[0] = c->build.ms;
        exp_est_of(c->build_samples, 1, &c->build_ms);
        c->build_procs = 0;
        for (int s = 0; s < 4; s++) {
            exp_trace *t = &c->set[s];
            t->ray_steps = t->ray_prims = NULL; /* the parent's to free */
            memset(t->samples, 0, sizeof t->samples);
            t->n = 0;
            if (!(d->mask & (1 << s))) t->have = 0; /* set index s is bit 1 << s */
        }
    }
    exp_group_run(d);
}

void exp_group_duel_free(exp_group *d)
{
    /* The structures are the parent group's (exp_group_free frees them). */
    for (int i = 0; i < 4; i++) free(d->sub[i].rays);
    free(d->cfg);
    memset(d, 0, sizeof *d);
}
