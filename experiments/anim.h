/*
 * anim.h - the animated-scene parts of exp_twolevel (exp_twolevel.c says
 * what they measure and why).
 *
 * Refit against rebuild: two chains of the same two-level structure follow
 * the animated scene frame by frame, one refitting the changed meshes'
 * bottom BVHs, one rebuilding them (update ms per frame, medians over the
 * frames); at k = 1, 5, 20, 100 frames the refit tree is timed against a fresh
 * build of frame k in paired rounds (primary plus shadow rays, 1 thread).
 * Frames per second: the fastest two-level configuration (refit per frame)
 * and the fastest flattened one (a full build per frame) render frames 1..N
 * with 1 and 2 threads, interleaved frame by frame; update, primary and
 * shadow milliseconds per frame and the frames per second against 20.
 * Every answer is compared between the loops (refit against fresh; every
 * loop against the first): the tables count disagreements, which must be 0.
 */
#ifndef EXP_ANIM_H
#define EXP_ANIM_H

#include "engine/harness.h"

typedef struct {
    const char *anim;        /* the animated scene's spec, without frame= */
    const char *refit;       /* the two-level configuration refit (bottom=bvh) */
    const char *two, *flat;  /* the fastest two-level and flattened configurations */
    exp_text *findings;      /* findings are added here */
    /* For the verdicts: exp_ratio_cmp of refit's trace time over a fresh
     * build's after the last k (> 0: slower), and of refit's update speed
     * over a rebuild's (> 0: faster), with the numbers that decide. */
    int loss_cmp, update_cmp;
    char loss_ev[1024], update_ev[512];
    /* Issue 38's numbers: refit's trace time over a fresh build's after
     * the last k (loss), with box tests per ray refit over fresh
     * (box_ratio); the rebuild's update time over refit's (speed). */
    exp_est loss, speed;
    double box_ratio;
    int have_loss, have_speed;
} exp_anim;

/* Refit against rebuild on a->anim (tables, CSV part "refit", findings). */
void exp_anim_refit(exp_ctx *x, exp_anim *a);
/* Frames per second (tables, CSV part "fps", findings, the verdict on
 * realtime-animated). */
void exp_anim_fps(exp_ctx *x, exp_anim *a);

/* anim=SPEC plus frame=N ("animated:instances=48,frame=3"). */
void exp_anim_frame_spec(char *buf, size_t n, const char *anim, int frame);
/* One CSV record of exp_twolevel's schema:
 * part,scene,triangles,config,threads,frame,quantity,median,lo,hi,n, where
 * part is two_level (frame 0), refit (frame: k, the frames of refit; for the
 * update rows, the frames in their medians) or fps (frame: frames rendered);
 * n is the samples of the estimate (for a count of disagreements: the rays). */
void exp_anim_row(exp_ctx *x, const char *part, const accel_scene *s, const char *config,
                  int threads, int frame, const char *quantity, const exp_est *e);
/* "1.23x [1.10, 1.30]", with " (a tie)" when the ratio stays within floor. */
const char *exp_anim_ratio(char *buf, size_t n, const exp_est *r, double floor);

/* A single value as an estimate of n samples (a count, bytes). */
static inline exp_est exp_est_one(double v, int n)
{
    exp_est e = {v, v, v, v, v, n, 0, 0, 0, 0};
    return e;
}

#endif
