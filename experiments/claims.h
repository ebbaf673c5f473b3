/*
 * claims.h - every claim the study answers: the lecture's (../shared/
 * LECTURE.md), the user's requests, and the study's own questions. Each has
 * an id that experiments write beside their verdicts (exp_verdict) and that
 * the report generator (mkreport) lists in the summary table, so that a
 * claim no experiment answered shows as such instead of disappearing.
 */
#ifndef EXP_CLAIMS_H
#define EXP_CLAIMS_H

typedef struct {
    const char *id;      /* "sah-2x" */
    const char *source;  /* "lecture", "request" or "study" */
    const char *topic;   /* short name for the summary table */
    const char *words;   /* the claim in the lecture's (or the user's) words */
    const char *section; /* the experiment that decides it */
} exp_claim;

extern const exp_claim exp_claims[];
extern const int exp_claim_count;
/* NULL when id names no claim. */
const exp_claim *exp_claim_find(const char *id);

/* The verdict labels, in this spelling everywhere. */
#define EXP_CONFIRMED "confirmed"
#define EXP_PARTLY "partly"
#define EXP_REFUTED "refuted"
#define EXP_UNTESTABLE "not testable here"
/* 1 when v is one of the four labels. */
int exp_verdict_valid(const char *v);

#endif
