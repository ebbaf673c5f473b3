/*
 * stab_offsets.h - exp_stability's study of secondary-ray origins
 * (stab_offsets.c): four epsilon rules against the robust offset.
 */
#ifndef EXP_STAB_OFFSETS_H
#define EXP_STAB_OFFSETS_H

#include "engine/harness.h"

#define STAB_OFFSET_RULES 5
#define STAB_OFFSET_ROBUST 4
#define STAB_OFFSET_ULPS 3
#define STAB_FAR_DISTANCE 1e5

typedef struct {
    double worst_self[STAB_OFFSET_RULES];  /* self-hits per million, worst case */
    double worst_false[STAB_OFFSET_RULES]; /* false hits per million, worst case */
    size_t leaks[STAB_OFFSET_RULES];     /* closest-hit and shadow leaks, all cases */
    size_t self[STAB_OFFSET_RULES];
    size_t rays, inside, min_n;          /* secondary rays; leaving inside hits; fewest of a case */
    /* Far geometry: the sphere cases at distance >= STAB_FAR_DISTANCE, per
     * rule the least and most of their inside rays that leak (closest hit)
     * and of their rays that hit their own triangle, as fractions */
    int far_cases;
    double far_d_lo, far_d_hi;
    double far_leak_lo[STAB_OFFSET_RULES], far_leak_hi[STAB_OFFSET_RULES];
    double far_self_lo[STAB_OFFSET_RULES], far_self_hi[STAB_OFFSET_RULES];
    int planted;                         /* GRIDBVH_STABILITY_PLANT was set */
} stab_offsets_result;

/* Writes the study's table and CSV rows (part "offset"). */
void stab_offsets(exp_ctx *x, int threads, stab_offsets_result *res);
/* The far-geometry leak of each origin rule, for the findings and (brief)
 * the summary: "leak at distance 1e5-1e6: robust offset 68-100%, 32 ulps
 * 0-90%, epsilons 0-0.006% (self-hits 49%)": the fractions of the inside
 * rays that leak over the far cases, least to most (the epsilon rules
 * together), and the epsilon rules' self-hits; "not measured" without a
 * far case (the quick budget). */
void stab_offsets_far_text(const stab_offsets_result *o, int brief, char *buf, size_t n);
/* The rule's name (0 .. STAB_OFFSET_RULES-1). */
const char *stab_offsets_name(int m);

#endif
