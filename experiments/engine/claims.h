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
 * misses it, EXP_ON_LINE when it straddles (or any number is NaN). A
 * zero-width interval from 2 or more samples (a self-ratio: 1 [1, 1]) is
 * not an interval (issue 52): on the line. n <= 1 is an exact number
 * (counts), judged as a point. */
const char *exp_judge(const exp_decider *d);

/* The reference kernel's stated rate (engine/harness.h, reference.c):
 * brute force over the 250 triangles of soup:tris=250, 1024 primary rays,
 * one thread, in the quiet run of the committed report of 123ab8c
 * (report/exp_scaling.csv, soup,brute,250: 2,223 ns per ray [2,160,
 * 2,308]). */
#define EXP_REF_NS_PER_RAY 2222.6
/* Absolute verdicts whose word depends on the normalization are "not
 * testable here" when the reference strayed by more than this
 * (max / min - 1). */
#define EXP_REF_STRAY 0.10
/* The one normalization of an absolute decider (exp_group_absolute,
 * exp_ref_absolute): the value by the factor med / EXP_REF_NS_PER_RAY
 * (rate = 1: multiplied; 0: divided), each end of its interval by the
 * factor of the reference's end that widens it (fast and slow: the
 * reference's fast and slow ends, ns per ray; spread names them), so the
 * word holds whichever normalization is right. When the reference strayed
 * (stray, max / min - 1, above EXP_REF_STRAY) a word that straddles is
 * "not testable here"; a decided word stands, and why says both. */
const char *exp_ref_normalize(exp_decider *d, int rate, double med, double fast, double slow,
                              const char *spread, double stray, char *why, size_t why_n);
/* Issue 52: the distance from the threshold to the interval's NEAR end,
 * relative to the threshold (|threshold|; 1 when it is 0), positive on the
 * claim's side: > 0 exactly when confirmed (the near end is lo for "at
 * least"), < 0 exactly when refuted (the near end is hi), 0 when the
 * interval straddles or is not an interval. +0.05: the whole interval
 * clears the threshold by 5% of it. NaN when a number is missing. */
double exp_margin(const exp_decider *d);

/* THE tally rule of the study (issue 52), one place for every experiment
 * and for mkreport. Words of comparisons of one claim "on every scene"
 * (EXP_EVERY: scenes, ray sets, the rows of one claim in the summary): one
 * decisive refutation refutes, whatever else (a counterexample is
 * enough); a part "partly" makes it partly; confirmed only when every one
 * confirms; else on the line. Words of the parts of a compound claim
 * (EXP_PARTS: "A and B"): one word everywhere is the word; parts that
 * confirm and parts that refute (or a part "partly") make it partly; {on
 * the line, refuted} is refuted; {on the line, confirmed} on the line.
 * "Not testable here" words: on every scene, a scene not testable stops
 * "confirmed" (the word is then on the line if one straddles, else not
 * testable here); among parts they are left out (all of them: not
 * testable). "answered" only answers when every word is. NULL when n is 0
 * or every word NULL. */
enum { EXP_EVERY, EXP_PARTS };
const char *exp_combine(const char *const *words, int n, int mode);
/* exp_combine of counted words: `confirmed` comparisons that confirm,
 * `refuted` that refute, `online` that straddle. */
const char *exp_combine_counts(int confirmed, int refuted, int online, int mode);
/* Which of n comparisons (words[i], margins[i] from exp_margin) is the
 * number that makes `word`: for refuted the most decisive refutation (the
 * most negative margin), for confirmed the nearest confirmation (the
 * smallest margin), for partly the most decisive refutation, for on the
 * line the first that straddles; else the first with the word. -1: none. */
int exp_decisive(const char *word, const char *const *words, const double *margins, int n);

/* A verdict over m comparisons ("on every scene"): each comparison's
 * interval is taken at the Bonferroni level 1 - 0.05 / m (stats.h:
 * exp_bonferroni_level), so that all m hold together with 95%. The word
 * is exp_combine(EXP_EVERY) of the comparisons' exp_judge; the decider
 * (worst) is exp_decisive's. Zero-width intervals (self-ratios) are
 * counted in `degenerate` and left out of the word. */
#define EXP_TALLY_MAX 128
typedef struct {
    int m;                      /* comparisons announced (for the level) */
    int added, confirmed, refuted, online, degenerate;
    int untestable;             /* comparisons that could not be judged here (exp_tally_untestable) */
    exp_decider worst;          /* the deciding comparison so far */
    char what[256];             /* worst.what's text */
    exp_decider all[EXP_TALLY_MAX]; /* the comparisons (what points into whats) */
    char whats[EXP_TALLY_MAX][160];
} exp_tally;
/* Starts a tally of m comparisons. */
void exp_tally_init(exp_tally *t, int m);
/* The per-comparison coverage its intervals must have. */
double exp_tally_level(const exp_tally *t);
/* Adds one comparison (its interval at exp_tally_level). */
void exp_tally_add(exp_tally *t, const exp_decider *d);
/* Counts a comparison that could not be judged here (e.g. an absolute
 * threshold while the reference kernel strayed): on every scene, it stops
 * "confirmed". */
void exp_tally_untestable(exp_tally *t);
/* The word; NULL when nothing was added (nor counted untestable). */
const char *exp_tally_verdict(const exp_tally *t);
/* A compound claim from its parts (tallies with nothing added: parts not
 * measured): exp_combine(EXP_PARTS) of their words. *dec: the deciding
 * part's decider (for partly and refuted: a refuting part's; for on the
 * line: a part on the line). NULL when no part was measured. */
const char *exp_compound(exp_tally *const *parts, int n, const exp_decider **dec);

#endif
