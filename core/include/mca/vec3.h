/* SPDX-License-Identifier: MIT */
/** @file mca/vec3.h
 * Small inline 3-vector helpers (output first, inputs const), used by kinematics and distances.
 */
#ifndef MCA_VEC3_H
#define MCA_VEC3_H

#include <math.h>

static inline void mca_v3_set(double out[3], const double a[3]) {
    out[0] = a[0];
    out[1] = a[1];
    out[2] = a[2];
}
static inline void mca_v3_sub(double out[3], const double a[3], const double b[3]) {
    out[0] = a[0] - b[0];
    out[1] = a[1] - b[1];
    out[2] = a[2] - b[2];
}
static inline void mca_v3_add(double out[3], const double a[3], const double b[3]) {
    out[0] = a[0] + b[0];
    out[1] = a[1] + b[1];
    out[2] = a[2] + b[2];
}
/** out = a + s * b */
static inline void mca_v3_axpy(double out[3], const double a[3], double s, const double b[3]) {
    out[0] = a[0] + s * b[0];
    out[1] = a[1] + s * b[1];
    out[2] = a[2] + s * b[2];
}
static inline double mca_v3_dot(const double a[3], const double b[3]) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void mca_v3_cross(double out[3], const double a[3], const double b[3]) {
    const double x = a[1] * b[2] - a[2] * b[1];
    const double y = a[2] * b[0] - a[0] * b[2];
    const double z = a[0] * b[1] - a[1] * b[0];
    out[0] = x;
    out[1] = y;
    out[2] = z;
}
static inline double mca_v3_norm(const double a[3]) {
    return sqrt(mca_v3_dot(a, a));
}
static inline double mca_v3_dist(const double a[3], const double b[3]) {
    double d[3];
    mca_v3_sub(d, a, b);
    return mca_v3_norm(d);
}

#endif
