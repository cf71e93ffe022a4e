/* SPDX-License-Identifier: MIT */
/* Shared helpers of the kinematics tests: robot paths, a deterministic PRNG, loading. */
#ifndef KIN_TEST_UTIL_H
#define KIN_TEST_UTIL_H

#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <cmocka.h>

#include "mca/chain.h"
#include "mca/err.h"
#include "mca/urdf.h"

#ifndef MCA_ROBOTS_DIR
#error "MCA_ROBOTS_DIR must be set by CMake"
#endif

#define KIN_PI 3.14159265358979323846
#define KIN_DEG (KIN_PI / 180.0)

/* splitmix64: deterministic, so a failure repeats exactly */
static inline uint64_t kin_rand_u64(uint64_t *s) {
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* uniform in [lo, hi) */
static inline double kin_rand(uint64_t *s, double lo, double hi) {
    return lo + (hi - lo) * (double)(kin_rand_u64(s) >> 11) * (1.0 / 9007199254740992.0);
}

/* Running maximum of an error that a NaN poisons: once e is NaN the result stays NaN, so a final
 * `!(worst <= tol)` check fails (fmax would drop the NaN and let the test pass). */
static inline double kin_worst(double worst, double e) {
    if (isnan(worst)) {
        return worst;
    }
    return (isnan(e) || e > worst) ? e : worst;
}

/* Load config/robots/<file> with tip "tool_tip"; fails the test with the message on error. */
static inline void kin_load_robot(mca_chain_t *c, const char *file) {
    char path[512], err[512];
    snprintf(path, sizeof(path), "%s/%s", MCA_ROBOTS_DIR, file);
    const int rc = mca_chain_load_urdf(c, path, "tool_tip", err, sizeof(err));
    if (rc != MCA_OK) {
        fail_msg("loading %s: rc %d: %s", path, rc, err);
    }
}

#endif
