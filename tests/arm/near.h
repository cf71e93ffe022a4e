/* SPDX-License-Identifier: MIT */
/* assert_double_equal() for cmocka < 1.1.6 (Debian 12 ships 1.1.5): |a - b| <= eps, NaN fails. */
#ifndef MCA_TEST_NEAR_H
#define MCA_TEST_NEAR_H

#include <math.h>
#include <string.h>

#include "mca/arm.h"

#ifndef assert_double_equal
static inline void mca_assert_near(double a, double b, double eps, const char *expr, const char *file,
                                   int line) {
    if (!(fabs(a - b) <= eps)) {
        print_error("%s = %.17g, expected %.17g +- %g\n", expr, a, b, eps);
        _fail(file, line);
    }
}
#define assert_double_equal(a, b, eps) mca_assert_near((a), (b), (eps), #a, __FILE__, __LINE__)
#endif

/* Field-wise feedback equality (struct padding is not compared). */
#define assert_fb_equal(a, b) mca_assert_fb_equal((a), (b), __FILE__, __LINE__)
static inline void mca_assert_fb_equal(const mca_arm_feedback_t *a, const mca_arm_feedback_t *b,
                                       const char *file, int line) {
    int same = a->frame_id == b->frame_id && a->n == b->n && a->state == b->state &&
               a->fault_code == b->fault_code && a->stamp_ns == b->stamp_ns;
    for (int j = 0; same && j < MCA_MAX_DOF; j++) {
        same = memcmp(&a->position[j], &b->position[j], sizeof(double)) == 0 &&
               memcmp(&a->velocity[j], &b->velocity[j], sizeof(double)) == 0 &&
               memcmp(&a->torque[j], &b->torque[j], sizeof(double)) == 0 &&
               a->fault_flags[j] == b->fault_flags[j];
    }
    if (!same) {
        print_error("feedback differs: frame %u/%u state %d/%d q0 %.17g/%.17g\n", a->frame_id, b->frame_id,
                    (int)a->state, (int)b->state, a->position[0], b->position[0]);
        _fail(file, line);
    }
}

#endif
