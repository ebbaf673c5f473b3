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
