/* SPDX-License-Identifier: MIT */
/* assert_double_equal() for cmocka < 1.1.6 (Debian 12 ships 1.1.5): |a - b| <= eps, NaN fails. */
#ifndef MCA_TEST_NEAR_H
#define MCA_TEST_NEAR_H

#include <math.h>

#ifndef assert_double_equal
static inline void mca_assert_near(double a, double b, double eps, const char *expr, const char *file, int line)
{
    if (!(fabs(a - b) <= eps)) {
        print_error("%s = %.17g, expected %.17g +- %g\n", expr, a, b, eps);
        _fail(file, line);
    }
}
#define assert_double_equal(a, b, eps) mca_assert_near((a), (b), (eps), #a, __FILE__, __LINE__)
#endif

#endif
