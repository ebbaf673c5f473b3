/*
 * test_verdict_rules.c - the study's verdict rules (experiments/engine/claims.c,
 * issue 38 and issue 52): confirmed only when the whole interval is on the
 * claim's side, refuted when the whole interval misses, on the line when
 * it straddles; a zero-width interval is not an interval; the margin is
 * measured to the interval's near end; one tally rule for every experiment
 * and for mkreport (exp_combine, exp_decisive); a noise floor widens an
 * interval, never overrules one. Every case is a constructed input whose
 * answer the rule fixes.
 */
#include <math.h>
#include <string.h>

#include "experiments/engine/claims.h"
#include "experiments/engine/stats.h"
#include "test.h"

#define WORD(got, want) CHECKF((got) && !strcmp((got), (want)), "word %s, want %s", (got) ? (got) : "(null)", (want))

TEST(verdict_rules_judge_and_margin)
{
    /* "SAH doubles performance": value >= 2. */
    exp_decider d = {"speed-up", 2.4, 2.2, 2.6, 2.0, +1, 10};
    WORD(exp_judge(&d), EXP_CONFIRMED);
    /* the near end 2.2 clears 2.0 by 10% of it */
    CHECKF(fabs(exp_margin(&d) - 0.1) < 1e-9, "margin %g", exp_margin(&d));
    d = (exp_decider){"speed-up", 1.4, 1.1, 1.7, 2.0, +1, 10};
    WORD(exp_judge(&d), EXP_REFUTED);
    CHECKF(fabs(exp_margin(&d) - (-0.15)) < 1e-9, "margin %g", exp_margin(&d)); /* hi 1.7 */
    d = (exp_decider){"speed-up", 1.95, 1.8, 2.1, 2.0, +1, 10};
    WORD(exp_judge(&d), EXP_ON_LINE);
    CHECK(exp_margin(&d) == 0);
    /* Issue 52: an asymmetric interval whose point lies 1.7 half-widths
     * from the threshold but whose low end reaches below it: the old
     * margin said > 1 beside "on the line"; the near end says 0. */
    d = (exp_decider){"speed-up", 3.0, 1.95, 3.1, 2.0, +1, 8};
    WORD(exp_judge(&d), EXP_ON_LINE);
    CHECKF(exp_margin(&d) == 0, "margin %g for a straddling interval", exp_margin(&d));
    /* "within 1.3x": value <= 1.3, interval given in either order. */
    d = (exp_decider){"ratio", 1.2, 1.25, 1.1, 1.3, -1, 12};
    WORD(exp_judge(&d), EXP_CONFIRMED);
    CHECKF(fabs(exp_margin(&d) - 0.05 / 1.3) < 1e-9, "margin %g", exp_margin(&d)); /* near end 1.25 */
    d = (exp_decider){"ratio", 1.5, 1.4, 1.6, 1.3, -1, 12};
    WORD(exp_judge(&d), EXP_REFUTED);
    CHECK(exp_margin(&d) < 0);
    /* A missing number never confirms. */
    d = (exp_decider){"ratio", NAN, NAN, NAN, 1.3, -1, 0};
    WORD(exp_judge(&d), EXP_ON_LINE);
    CHECK(isnan(exp_margin(&d)));
    /* A zero-width interval from 8 processes (a self-ratio, 1 [1, 1]) is
     * not an interval: it never decides. An exact count (n 1) does. */
    d = (exp_decider){"self-ratio", 1.0, 1.0, 1.0, 0.9, +1, 8};
    WORD(exp_judge(&d), EXP_ON_LINE);
    CHECK(exp_margin(&d) == 0);
    d.n = 1;
    WORD(exp_judge(&d), EXP_CONFIRMED);
    CHECK(exp_verdict_valid(EXP_ON_LINE) && exp_verdict_valid(EXP_ANSWERED));
    CHECK(!exp_verdict_valid("probably"));
}

/* "On every scene": one decisive counterexample refutes; confirmed only
 * when every comparison confirms; the quoted number is the one that makes
 * the word. */
TEST(verdict_rules_tally)
{
    exp_tally t;
    exp_tally_init(&t, 4);
    CHECK(fabs(exp_tally_level(&t) - 0.9875) < 1e-12 && exp_tally_verdict(&t) == NULL);
    exp_decider a = {"scene a", 2.6, 2.3, 2.9, 2.0, +1, 12}, b = {"scene b", 2.15, 2.05, 2.3, 2.0, +1, 12};
    exp_tally_add(&t, &a);
    exp_tally_add(&t, &b);
    /* confirmed: the nearest confirmation is quoted (it limits the word) */
    CHECKF(!strcmp(exp_tally_verdict(&t), EXP_CONFIRMED) && !strcmp(t.worst.what, "scene b"),
           "%s, decider %s", exp_tally_verdict(&t), t.worst.what);
    exp_decider c = {"scene c", 1.9, 1.7, 2.1, 2.0, +1, 12};
    exp_tally_add(&t, &c);
    CHECKF(!strcmp(exp_tally_verdict(&t), EXP_ON_LINE) && !strcmp(t.worst.what, "scene c"),
           "%s, decider %s", exp_tally_verdict(&t), t.worst.what);
    /* one decisive refutation among confirmations and a straddle: refuted
     * (issue 38's rule said partly) */
    exp_decider d = {"scene d", 1.7, 1.6, 1.9, 2.0, +1, 12};
    exp_tally_add(&t, &d);
    CHECKF(!strcmp(exp_tally_verdict(&t), EXP_REFUTED) && !strcmp(t.worst.what, "scene d"),
           "%s, decider %s", exp_tally_verdict(&t), t.worst.what);
    /* a more decisive refutation becomes the quoted number */
    exp_decider e = {"scene e", 1.2, 1.1, 1.3, 2.0, +1, 12};
    exp_tally_add(&t, &e);
    CHECKF(!strcmp(exp_tally_verdict(&t), EXP_REFUTED) && !strcmp(t.worst.what, "scene e") &&
               exp_margin(&t.worst) < 0,
           "%s, decider %s", exp_tally_verdict(&t), t.worst.what);
    /* Issue 52's real-time row: three decisive misses of 20 fps and the
     * rest on the line printed "on the line"; it is refuted. */
    exp_tally_init(&t, 6);
    double fps[6][3] = {{4.4, 4.0, 4.9}, {12.3, 11.0, 13.1}, {8.0, 7.1, 9.2},
                        {19.0, 15.0, 24.0}, {21.0, 17.0, 26.0}, {18.0, 14.5, 23.0}};
    for (int i = 0; i < 6; i++) {
        exp_decider f = {"frame", fps[i][0], fps[i][1], fps[i][2], 20.0, +1, 8};
        exp_tally_add(&t, &f);
    }
    WORD(exp_tally_verdict(&t), EXP_REFUTED);
    CHECKF(t.refuted == 3 && t.online == 3 && fabs(t.worst.value - 4.4) < 1e-12,
           "refuted %d on the line %d, quoted %g", t.refuted, t.online, t.worst.value);
    /* A self-ratio is left out of the word, and counted. */
    exp_tally_init(&t, 2);
    exp_decider self = {"self", 1.0, 1.0, 1.0, 1.1, +1, 8};
    exp_tally_add(&t, &a);
    exp_tally_add(&t, &self);
    CHECKF(!strcmp(exp_tally_verdict(&t), EXP_CONFIRMED) && t.added == 1 && t.degenerate == 1,
           "%s with a self-ratio (added %d, degenerate %d)", exp_tally_verdict(&t), t.added,
           t.degenerate);
}

/* The words of several rows (mkreport) and of the parts of a compound
 * claim: one rule in claims.c for both. */
TEST(verdict_rules_combine)
{
    const char *w1[] = {EXP_ON_LINE, EXP_REFUTED, EXP_ON_LINE};
    WORD(exp_combine(w1, 3, EXP_EVERY), EXP_REFUTED);
    WORD(exp_combine(w1, 3, EXP_PARTS), EXP_REFUTED); /* {on the line, refuted}: refuted */
    const char *w2[] = {EXP_CONFIRMED, EXP_REFUTED};
    WORD(exp_combine(w2, 2, EXP_EVERY), EXP_REFUTED); /* a counterexample */
    WORD(exp_combine(w2, 2, EXP_PARTS), EXP_PARTLY);  /* one part holds, one does not */
    const char *w3[] = {EXP_CONFIRMED, EXP_ON_LINE};
    WORD(exp_combine(w3, 2, EXP_EVERY), EXP_ON_LINE);
    WORD(exp_combine(w3, 2, EXP_PARTS), EXP_ON_LINE);
    const char *w4[] = {EXP_CONFIRMED, EXP_CONFIRMED, EXP_UNTESTABLE};
    WORD(exp_combine(w4, 3, EXP_EVERY), EXP_UNTESTABLE); /* not every scene confirmed */
    WORD(exp_combine(w4, 3, EXP_PARTS), EXP_CONFIRMED);
    const char *w5[] = {EXP_CONFIRMED, EXP_CONFIRMED};
    WORD(exp_combine(w5, 2, EXP_EVERY), EXP_CONFIRMED);
    const char *w6[] = {NULL, NULL};
    CHECK(exp_combine(w6, 2, EXP_EVERY) == NULL);
    /* the quoted row: the most decisive refutation, the nearest confirmation */
    const char *w7[] = {EXP_REFUTED, EXP_CONFIRMED, EXP_REFUTED};
    double m7[] = {-0.02, 0.3, -0.4};
    CHECK(exp_decisive(EXP_REFUTED, w7, m7, 3) == 2);
    CHECK(exp_decisive(EXP_PARTLY, w7, m7, 3) == 2);
    const char *w8[] = {EXP_CONFIRMED, EXP_CONFIRMED, EXP_CONFIRMED};
    double m8[] = {0.3, 0.05, 0.2};
    CHECK(exp_decisive(EXP_CONFIRMED, w8, m8, 3) == 1);
    /* compound: the parts' words through exp_compound */
    exp_tally p1, p2;
    exp_tally_init(&p1, 1), exp_tally_init(&p2, 1);
    exp_decider yes = {"part 1", 2.6, 2.3, 2.9, 2.0, +1, 8}, no = {"part 2", 1.2, 1.1, 1.3, 2.0, +1, 8};
    exp_tally_add(&p1, &yes), exp_tally_add(&p2, &no);
    exp_tally *parts[2] = {&p1, &p2};
    const exp_decider *dec = NULL;
    WORD(exp_compound(parts, 2, &dec), EXP_PARTLY);
    CHECKF(dec && !strcmp(dec->what, "part 2"), "partly quotes %s", dec ? dec->what : "(none)");
}

/* A noise floor widens an interval by its factor; it never makes a tie of
 * an interval that clears 1 by more than the floor, nor a difference of
 * one that holds 1. */
TEST(verdict_rules_floor_widens)
{
    exp_est r = {1.30, 1.20, 1.45, 1.1, 1.6, 8, 0.95, 8, 0, 0};
    CHECK(exp_ratio_cmp(&r, 0.01) == 1);
    CHECK(exp_ratio_cmp(&r, 0.15) == 1);  /* 1.20 / 1.15 > 1 */
    CHECK(exp_ratio_cmp(&r, 0.25) == 0);  /* 1.20 / 1.25 < 1: widened past 1 */
    exp_est h = {1.30, 0.98, 1.60, 0.9, 1.7, 8, 0.95, 8, 0, 0};
    CHECK(exp_ratio_cmp(&h, 0.0) == 0);   /* holds 1: no floor makes it a difference */
    exp_est lo = {0.70, 0.62, 0.80, 0.6, 0.85, 8, 0.95, 8, 0, 0};
    CHECK(exp_ratio_cmp(&lo, 0.2) == -1 && exp_ratio_cmp(&lo, 0.3) == 0); /* 0.80 x 1.3 > 1 */
    /* Two estimates: each interval widened by sqrt(1 + floor). */
    exp_est a = {10.0, 9.8, 10.2, 9.7, 10.3, 8, 0.95, 8, 0, 0}, b = {10.6, 10.4, 10.8, 10.3, 10.9, 8, 0.95, 8, 0, 0};
    CHECK(!exp_tie(&a, &b, 0.01) && exp_tie(&a, &b, 0.03));
}

/* Issue 52: no printed interval spans more than 3x (EXP_MAX_SPAN): such an
 * estimate prints its median and "not resolved"; a narrower one its
 * interval, in every format. */
TEST(verdict_rules_wide_intervals_not_printed)
{
    exp_est wide = {2.0, 1.0, 4.0, 0.9, 4.2, 8, 0.95, 8, 0, 0};
    exp_est ok = {2.0, 1.0, 2.9, 0.9, 3.0, 8, 0.95, 8, 0, 0};
    char b[256];
    const char *s = exp_fmt_est(b, sizeof b, &wide, 2);
    CHECKF(strstr(s, "not resolved") && !strchr(s, '['), "est: %s", s);
    s = exp_fmt_x(b, sizeof b, &wide);
    CHECKF(strstr(s, "not resolved") && !strchr(s, '['), "x: %s", s);
    s = exp_fmt_pct(b, sizeof b, &wide);
    CHECKF(strstr(s, "not resolved") && !strchr(s, '['), "pct: %s", s);
    s = exp_fmt_est(b, sizeof b, &ok, 2);
    CHECKF(!strstr(s, "not resolved") && strstr(s, "[1.00, 2.90]"), "est: %s", s);
    s = exp_fmt_x(b, sizeof b, &ok);
    CHECKF(!strstr(s, "not resolved") && strchr(s, '['), "x: %s", s);
    CHECK(exp_span_unresolved(1.0, 3.01) && !exp_span_unresolved(1.0, 3.0) &&
          !exp_span_unresolved(0.0, 5.0));
}

/* The normalization of absolute verdicts (claims.h): the value by the
 * median reference, each end by the reference end that widens it; a word
 * that depends on the end is "not testable here" only when the reference
 * strayed by more than EXP_REF_STRAY. */
TEST(verdict_rules_reference_normalization)
{
    const double R = EXP_REF_NS_PER_RAY;
    char why[512];
    /* A rate (fps >= 20) on a machine 1.5x slower than stated: x 1.5. */
    exp_decider d = {"fps", 16, 15, 17, 20.0, +1, 8};
    const char *v = exp_ref_normalize(&d, 1, 1.5 * R, 1.45 * R, 1.55 * R, "ends", 0.07, why, sizeof why);
    CHECKF(fabs(d.value - 24) < 1e-9 && fabs(d.lo - 15 * 1.45) < 1e-9 && fabs(d.hi - 17 * 1.55) < 1e-9,
           "rate normalized to %g [%g, %g]", d.value, d.lo, d.hi);
    CHECKF(!strcmp(v, EXP_CONFIRMED), "%s: %s", v, why);
    /* A time (ms <= 33.3): divided, the low end by the slow reference. */
    exp_decider t = {"ms", 40, 38, 44, 33.3, -1, 8};
    v = exp_ref_normalize(&t, 0, 1.5 * R, 1.4 * R, 1.6 * R, "ends", 0.14, why, sizeof why);
    CHECKF(fabs(t.lo - 38 / 1.6) < 1e-9 && fabs(t.hi - 44 / 1.4) < 1e-9, "time ends %g %g", t.lo, t.hi);
    CHECKF(!strcmp(v, EXP_CONFIRMED) && strstr(why, "strayed by 14.0%") && strstr(why, "same at both"),
           "a decided word stands although the reference strayed: %s: %s", v, why);
    /* Straddling after normalization: on the line when the reference held,
     * not testable when it strayed. */
    exp_decider s1 = {"fps", 20, 19, 21, 20.0, +1, 8}, s2 = s1;
    v = exp_ref_normalize(&s1, 1, R, 0.98 * R, 1.02 * R, "ends", 0.04, why, sizeof why);
    CHECKF(!strcmp(v, EXP_ON_LINE), "held reference: %s", v);
    v = exp_ref_normalize(&s2, 1, R, 0.9 * R, 1.1 * R, "ends", 0.22, why, sizeof why);
    CHECKF(!strcmp(v, EXP_UNTESTABLE), "strayed reference: %s", v);
}
