/*
 * test_loader_numbers.c - the loaders' number parsing: decimal text to
 * float exactly as strtof rounds it (ties to even, the double rounding
 * trap, subnormals, overflow, long digit strings, random decimals, every
 * float's shortest text), and 64-bit integers with their range.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "scene/load_common.h"
#include "test_loader.h"

/* ---- exact decimal parsing ------------------------------------------------ */

static void check_float_text(const char *txt)
{
    const char *end = txt + strlen(txt), *q;
    float got = 0;
    load_num_status st = load_parse_float(txt, end, &q, &got);
    float want = strtof(txt, NULL);
    if (!isfinite(want)) {
        CHECKF(st == LOAD_NUM_NONFINITE, "'%s': status %d, strtof gives %g", txt, (int)st, want);
        return;
    }
    CHECKF(st == LOAD_NUM_OK && q == end && memcmp(&got, &want, sizeof got) == 0,
           "'%s': parsed %.9g (status %d), strtof %.9g", txt, got, (int)st, want);
}

TEST(loader_float_parsing_is_exact)
{
    /* hand-picked: midpoints between floats (ties to even), the double
     * rounding trap, subnormals, overflow, long digit strings */
    static const char *const cases[] = {
        "0", "-0", "1", "0.1", "-2.5", "3.4028234e38", "3.4028235e38", "3.40282357e38",
        "3.4028236e38", "1e39", "1.17549435e-38", "1e-45", "1.4e-45", "7e-46", "7.1e-46", "1e-46",
        "16777216", "16777217", "16777217.0000000001", "16777218", "16777219", "33554435",
        "1.00000005960464477539062500", "1.000000059604644775390625001",
        "1.0000000596046447753906249999999999999999999999999", "9007199254740993",
        "0.000000000000000000000000000000000000000000001", "123456789012345678901234567890",
        "4.5035996e15", "1e22", "1e23", "1e-22", "1e-23", "8.589973e9", "2.8823036e+17",
        "1.5e-7", "0.6666666666666666666666666666666666666666666666667", ".5", "5.", "+.5e+1",
        "1E5", "1e-0", "1.7014118346046923173168730371588410572800000000000000001e38",
        "3.402823466385288598117041834845169254400000000000000000000000000000000000000000000000000000000000000000000000000000000000000001e38",
        "1.000000178813934326171875", "1.0000001788139343261718749",
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) check_float_text(cases[i]);

    /* random decimals: 1-25 digits, a point anywhere, exponents from -50 to 40 */
    test_seed(TEST_SEED);
    char buf[96];
    for (int it = 0; it < 300000; it++) {
        size_t n = 0;
        if (test_rand_u64() & 1) buf[n++] = '-';
        int digits = 1 + (int)(test_rand_u64() % 25);
        if (it % 3 == 0) digits = 1 + (int)(test_rand_u64() % 8); /* the common short forms */
        int point = (int)(test_rand_u64() % (uint64_t)(digits + 1));
        for (int d = 0; d < digits; d++) {
            if (d == point) buf[n++] = '.';
            buf[n++] = (char)('0' + test_rand_u64() % 10);
        }
        if (test_rand_u64() % 3 == 0)
            n += (size_t)snprintf(buf + n, sizeof buf - n, "e%d", (int)(test_rand_u64() % 91) - 50);
        buf[n] = 0;
        check_float_text(buf);
    }
    /* every float's shortest round-trip text ("%.9g") reads back to itself */
    for (int it = 0; it < 100000; it++) {
        uint32_t u = (uint32_t)test_rand_u64();
        float x;
        memcpy(&x, &u, 4);
        if (!isfinite(x)) continue;
        snprintf(buf, sizeof buf, it & 1 ? "%.9g" : "%.8e", x);
        check_float_text(buf);
    }
    /* integers */
    static const struct {
        const char *text;
        load_num_status st;
        int64_t value;
        size_t used;
    } ints[] = {
        {"-9223372036854775808", LOAD_NUM_OK, INT64_MIN, 20},
        {"9223372036854775807", LOAD_NUM_OK, INT64_MAX, 19},
        {"9223372036854775808", LOAD_NUM_RANGE, 0, 19},
        {"99999999999999999999999", LOAD_NUM_RANGE, 0, 23},
        {"+42x", LOAD_NUM_OK, 42, 3},
        {"-0", LOAD_NUM_OK, 0, 2},
        {"-", LOAD_NUM_NONE, 0, 0},
        {"x1", LOAD_NUM_NONE, 0, 0},
    };
    for (size_t i = 0; i < sizeof ints / sizeof ints[0]; i++) {
        const char *q;
        int64_t v = 0;
        load_num_status st = load_parse_int(ints[i].text, ints[i].text + strlen(ints[i].text), &q, &v);
        CHECKF(st == ints[i].st && (size_t)(q - ints[i].text) == ints[i].used &&
                   (st != LOAD_NUM_OK || v == ints[i].value),
               "'%s': status %d, value %lld, used %zu", ints[i].text, (int)st, (long long)v,
               (size_t)(q - ints[i].text));
    }
}
