/*
 * test_verdict_rules.c - issue 38's verdict rules (experiments/claims.c):
 * confirmed only when the whole interval is on the claim's side, refuted
 * when the whole interval misses, on the line when it straddles; the
 * margin in units of the interval's half-width.
 */
#include <math.h>
#include <string.h>

#include "experiments/claims.h"
#include "test.h"

TEST(verdict_rules_judge_and_margin)
{
    /* "SAH doubles performance": value >= 2. */
    exp_decider d = {"speed-up", 2.4, 2.2, 2.6, 2.0, +1, 10};
    CHECKF(!strcmp(exp_judge(&d), EXP_CONFIRMED), "judge %s, want %s", exp_judge(&d), EXP_CONFIRMED);
    CHECKF(fabs(exp_margin(&d) - (2.0)) < 1e-9, "margin %g", exp_margin(&d)); /* 0.4 above, half-width 0.2 */
    d = (exp_decider){"speed-up", 1.4, 1.1, 1.7, 2.0, +1, 10};
    CHECKF(!strcmp(exp_judge(&d), EXP_REFUTED), "judge %s, want %s", exp_judge(&d), EXP_REFUTED);
    CHECKF(fabs(exp_margin(&d) - (-2.0)) < 1e-9, "margin %g", exp_margin(&d));
    d = (exp_decider){"speed-up", 1.95, 1.8, 2.1, 2.0, +1, 10};
    CHECKF(!strcmp(exp_judge(&d), EXP_ON_LINE), "judge %s, want %s", exp_judge(&d), EXP_ON_LINE);
    CHECK(fabs(exp_margin(&d)) < 1);
    /* "within 1.3x": value <= 1.3, interval given in either order. */
    d = (exp_decider){"ratio", 1.2, 1.25, 1.1, 1.3, -1, 12};
    CHECKF(!strcmp(exp_judge(&d), EXP_CONFIRMED), "judge %s, want %s", exp_judge(&d), EXP_CONFIRMED);
    CHECK(exp_margin(&d) > 1);
    d = (exp_decider){"ratio", 1.5, 1.4, 1.6, 1.3, -1, 12};
    CHECKF(!strcmp(exp_judge(&d), EXP_REFUTED), "judge %s, want %s", exp_judge(&d), EXP_REFUTED);
    /* A missing number never confirms. */
    d = (exp_decider){"ratio", NAN, NAN, NAN, 1.3, -1, 0};
    CHECKF(!strcmp(exp_judge(&d), EXP_ON_LINE), "judge %s, want %s", exp_judge(&d), EXP_ON_LINE);
    CHECK(exp_verdict_valid(EXP_ON_LINE) && exp_verdict_valid(EXP_ANSWERED));
    CHECK(!exp_verdict_valid("probably"));
}

/* "k of m scenes": confirmed only when every comparison confirms, refuted
 * when every one misses, partly when they contradict each other, else on
 * the line; the decider is the comparison nearest to the threshold. */
TEST(verdict_rules_tally)
{
    exp_tally t;
    exp_tally_init(&t, 4);
    CHECK(fabs(exp_tally_level(&t) - 0.9875) < 1e-12 && exp_tally_verdict(&t) == NULL);
    exp_decider a = {"scene a", 2.6, 2.3, 2.9, 2.0, +1, 12}, b = {"scene b", 2.15, 2.05, 2.3, 2.0, +1, 12};
    exp_tally_add(&t, &a);
    exp_tally_add(&t, &b);
    CHECKF(!strcmp(exp_tally_verdict(&t), EXP_CONFIRMED) && !strcmp(t.worst.what, "scene b"),
           "%s, decider %s", exp_tally_verdict(&t), t.worst.what);
    exp_decider c = {"scene c", 1.9, 1.7, 2.1, 2.0, +1, 12};
    exp_tally_add(&t, &c);
    CHECKF(!strcmp(exp_tally_verdict(&t), EXP_ON_LINE) && !strcmp(t.worst.what, "scene c"),
           "%s, decider %s", exp_tally_verdict(&t), t.worst.what);
    exp_decider d = {"scene d", 1.4, 1.2, 1.6, 2.0, +1, 12};
    exp_tally_add(&t, &d);
    CHECKF(!strcmp(exp_tally_verdict(&t), EXP_PARTLY) && !strcmp(t.worst.what, "scene d"),
           "%s, decider %s", exp_tally_verdict(&t), t.worst.what);
    exp_tally_init(&t, 2);
    exp_tally_add(&t, &d);
    d.what = "scene e", d.value = 1.7, d.lo = 1.5, d.hi = 1.8;
    exp_tally_add(&t, &d);
    CHECKF(!strcmp(exp_tally_verdict(&t), EXP_REFUTED) && !strcmp(t.worst.what, "scene e"),
           "%s, decider %s", exp_tally_verdict(&t), t.worst.what);
}
