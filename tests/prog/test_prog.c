/* SPDX-License-Identifier: MIT */
/* mca_prog (mca/prog.h): integer options in 0..max, the ns summary's order statistics. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <cmocka.h>

#include "mca/prog.h"

static void test_parse_u64(void **state) {
    (void)state;
    unsigned long long v = 7;
    assert_int_equal(mca_prog_parse_u64("t", "--n", "0", 10, &v), 0);
    assert_int_equal(v, 0);
    assert_int_equal(mca_prog_parse_u64("t", "--n", "10", 10, &v), 0);
    assert_int_equal(v, 10);
    /* refused, v untouched: above max, a sign, trailing text, empty, not a number, past 64 bits */
    const char *bad[] = {"11", "-1", "+1x", "3 ", "", "x", "99999999999999999999999"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(mca_prog_parse_u64("t", "--n", bad[i], 10, &v), -1);
        assert_int_equal(v, 10);
    }
}

static int usage_calls;
static void count_usage(FILE *f) {
    (void)f;
    usage_calls++;
}

static void test_no_operands(void **state) {
    (void)state;
    char *argv[] = {"prog", "--x", "left", NULL};
    usage_calls = 0;
    assert_int_equal(mca_prog_no_operands("prog", 3, argv, 3, count_usage), 0); /* all taken */
    assert_int_equal(usage_calls, 0);
    assert_int_equal(mca_prog_no_operands("prog", 3, argv, 2, count_usage), 2); /* "left" is left */
    assert_int_equal(usage_calls, 1);
}

static void test_ns_summary(void **state) {
    (void)state;
    int64_t v[100];
    for (int i = 0; i < 100; i++) {
        v[i] = (int64_t)(99 - i) * 1000; /* 0..99 us, reversed: the summary sorts */
    }
    const mca_prog_ns_summary_t s = mca_prog_ns_summary(v, 100);
    assert_true(s.p50 == 49.0); /* v[(n-1)/2] */
    assert_true(s.p99 == 98.0); /* v[floor(0.99 (n-1))] */
    assert_true(s.max == 99.0);
    assert_true(s.mean == 49.5);
    assert_true(v[0] == 0 && v[99] == 99000);
    const mca_prog_ns_summary_t z = mca_prog_ns_summary(v, 0);
    assert_true(z.p50 == 0.0 && z.max == 0.0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_u64),
        cmocka_unit_test(test_ns_summary),
        cmocka_unit_test(test_no_operands),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
