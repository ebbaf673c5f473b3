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
/* The deciding interval straddles the claim's threshold: neither confirmed
 * nor refuted at this n (issue 38's rules). */
#define EXP_ON_LINE "on the line"
/* A request (claims of source "request") is answered with its numbers,
 * never confirmed. */
#define EXP_ANSWERED "answered"
/* 1 when v is one of the six labels. */
int exp_verdict_valid(const char *v);

/* The number that decides a verdict: its value and interval [lo, hi] from
 * n rounds (or samples), against the claim's threshold. sense is +1 when
 * the claim says value >= threshold ("at least 2x"), -1 when it says
 * value <= threshold ("within 1.3x"). what names it ("SAH / median
 * traversal speed-up, bunny 69k tris, primary 800x600"). */
typedef struct {
    const char *what;
    double value, lo, hi, threshold;
    int sense, n;
} exp_decider;
/* Issue 38's rule: EXP_CONFIRMED when the whole interval lies on the
 * claim's side of the threshold, EXP_REFUTED when the whole interval
 * misses it, EXP_ON_LINE when it straddles (or any number is NaN). */
const char *exp_judge(const exp_decider *d);
/* The distance from value to threshold in units of the interval's
 * half-width, positive on the claim's side (|margin| > 1: the interval
 * does not reach the threshold). A zero-width interval counts as 1e-12
 * wide. NaN when a number is missing. */
double exp_margin(const exp_decider *d);

/* A verdict over m comparisons ("on k of m scenes"): each comparison's
 * interval is taken at the Bonferroni level 1 - 0.05 / m (stats.h:
 * exp_bonferroni_level), so that all m hold together with 95%. Confirmed
 * when every comparison confirms, refuted when every one misses, partly
 * when some confirm and some miss (the evidence says which), on the line
 * otherwise (some straddle and none contradicts the rest). The decider is
 * the comparison with the smallest |margin| among those that decide the
 * word (the one nearest to flipping it). */
typedef struct {
    int m;                      /* comparisons announced (for the level) */
    int added, confirmed, refuted, online;
    exp_decider worst;          /* the deciding comparison so far */
    char what[256];             /* worst.what's text */
} exp_tally;
/* Starts a tally of m comparisons. */
void exp_tally_init(exp_tally *t, int m);
/* The per-comparison coverage its intervals must have. */
double exp_tally_level(const exp_tally *t);
/* Adds one comparison (its interval at exp_tally_level). */
void exp_tally_add(exp_tally *t, const exp_decider *d);
/* The word; NULL when nothing was added. */
const char *exp_tally_verdict(const exp_tally *t);
/* A compound claim from its parts (tallies with nothing added: parts not
 * measured): one word everywhere is the word; parts that confirm and parts
 * that miss (or a part "partly") make it partly; else on the line. *dec:
 * the deciding part's decider (for partly, a part that misses). NULL when
 * no part was measured. */
const char *exp_compound(exp_tally *const *parts, int n, const exp_decider **dec);

#endif
