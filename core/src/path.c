/* SPDX-License-Identifier: MIT */
/* Desired end-effector paths (real-time safe); see mca/path.h and docs/scheme.md. */
#include "mca/path.h"

#include <math.h>
#include <stddef.h>

#include "mca/err.h"
#include "mca/segdist.h"
#include "mca/vec3.h"

void mca_path_anchor(mca_path_t *path, const double ee_start[3]) {
    mca_v3_set(path->anchor, ee_start);
    if (path->kind == MCA_PATH_STREAM) {
        mca_v3_set(path->stream_r, ee_start);
        path->stream_v[0] = path->stream_v[1] = path->stream_v[2] = 0.0;
    }
    if (path->kind == MCA_PATH_WAYPOINTS && path->n_points > 0) {
        /* p[0] is the start: the anchor itself (offset 0 for relative paths) */
        if (path->relative) {
            path->p[0][0] = path->p[0][1] = path->p[0][2] = 0.0;
        } else {
            mca_v3_set(path->p[0], ee_start);
        }
    }
}

void mca_path_point(const mca_path_t *path, int i, double out[3]) {
    if (path->relative) {
        mca_v3_add(out, path->anchor, path->p[i]);
    } else {
        mca_v3_set(out, path->p[i]);
    }
}

void mca_path_stream_advance(mca_path_t *path, double rate, double dt) {
    if (path->kind != MCA_PATH_STREAM) {
        return;
    }
    for (int i = 0; i < 3; i++) {
        const double x = path->stream_r[i] + rate * path->stream_v[i] * dt;
        /* a wall stops only the motion through it (a reference that started outside may move back in) */
        if ((x > path->box_hi[i] && x > path->stream_r[i]) ||
            (x < path->box_lo[i] && x < path->stream_r[i])) {
            continue;
        }
        path->stream_r[i] = x;
    }
}

double mca_path_end_time(const mca_path_t *path) {
    switch (path->kind) {
    case MCA_PATH_STREAM:
        return INFINITY;
    case MCA_PATH_CIRCLE:
        return path->t0 + path->period;
    case MCA_PATH_WAYPOINTS: {
        double t = path->t0;
        for (int i = 0; i + 1 < path->n_points; i++) {
            t += path->dur[i];
        }
        return t;
    }
    default:
        return path->t0;
    }
}

int mca_path_eval(const mca_path_t *path, double t, double r[3], double rdot[3]) {
    if (!path || !r || !rdot || !isfinite(t)) {
        return MCA_EINVAL;
    }
    double s = t - path->t0;
    rdot[0] = rdot[1] = rdot[2] = 0.0;
    switch (path->kind) {
    case MCA_PATH_STREAM:
        mca_v3_set(r, path->stream_r);
        mca_v3_set(rdot, path->stream_v);
        return MCA_OK;
    case MCA_PATH_CIRCLE: {
        const double T = path->period;
        if (s < 0.0) {
            s = 0.0;
        }
        if (s > T) {
            s = T;
        }
        /* phi = 2 pi turns sin^2(pi s / 2T): starts and ends at rest (as in the Zhang-group papers). */
        const double w = M_PI / (2.0 * T);
        const double sw = sin(w * s), cw = cos(w * s);
        const double k = 2.0 * M_PI * path->turns;
        const double phi = k * sw * sw;
        const double phidot = k * 2.0 * sw * cw * w;
        const double R = path->radius;
        for (int i = 0; i < 3; i++) {
            const double c = path->anchor[i] - R * path->u[i];
            r[i] = c + R * (cos(phi) * path->u[i] + sin(phi) * path->v[i]);
            rdot[i] = R * phidot * (-sin(phi) * path->u[i] + cos(phi) * path->v[i]);
        }
        return MCA_OK;
    }
    case MCA_PATH_WAYPOINTS: {
        if (path->n_points < 1) {
            mca_v3_set(r, path->anchor);
            return MCA_OK;
        }
        if (s <= 0.0 || path->n_points == 1) {
            mca_path_point(path, 0, r);
            return MCA_OK;
        }
        for (int i = 0; i + 1 < path->n_points; i++) {
            const double T = path->dur[i];
            if (s < T) {
                /* quintic 10u^3 - 15u^4 + 6u^5: rest to rest, zero acceleration at both ends */
                const double u = s / T;
                const double u2 = u * u, u3 = u2 * u;
                const double h = u3 * (10.0 - 15.0 * u + 6.0 * u2);
                const double hd = 30.0 * u2 * (1.0 - 2.0 * u + u2) / T;
                double a[3], b[3];
                mca_path_point(path, i, a);
                mca_path_point(path, i + 1, b);
                for (int k = 0; k < 3; k++) {
                    r[k] = a[k] + h * (b[k] - a[k]);
                    rdot[k] = hd * (b[k] - a[k]);
                }
                return MCA_OK;
            }
            s -= T;
        }
        mca_path_point(path, path->n_points - 1, r);
        return MCA_OK;
    }
    default:
        mca_v3_set(r, path->anchor);
        return MCA_OK;
    }
}

double mca_path_point_time(const mca_path_t *path, int i) {
    double t = path->t0;
    for (int k = 0; k < i && k + 1 < path->n_points; k++) {
        t += path->dur[k];
    }
    return t;
}

int mca_path_dwell(const mca_path_t *path, int i) {
    return i + 1 < path->n_points && path->p[i][0] == path->p[i + 1][0] &&
           path->p[i][1] == path->p[i + 1][1] && path->p[i][2] == path->p[i + 1][2];
}

double mca_path_tolerance(const mca_path_t *path, double t) {
    if (path->kind != MCA_PATH_WAYPOINTS || path->n_points < 2) {
        return path->seg_tol[0];
    }
    double s = t - path->t0;
    const int last = path->n_points - 1;
    if (s <= 0.0) {
        return path->exact[0] ? fmin(path->exact_tol, path->seg_tol[0]) : path->seg_tol[0];
    }
    for (int i = 0; i < last; i++) {
        const double T = path->dur[i];
        if (s < T) {
            const double tol = path->seg_tol[i], ex = fmin(path->exact_tol, tol);
            const int a = path->exact[i], b = path->exact[i + 1];
            if (a && (b || mca_path_dwell(path, i))) {
                return ex; /* held at an exact point, or between two */
            }
            const double u = s / T;
            if (b) {
                return ex + (tol - ex) * (1.0 - u);
            }
            if (a) {
                return ex + (tol - ex) * u;
            }
            return tol;
        }
        s -= T;
    }
    const double tol = path->seg_tol[last - 1];
    return path->exact[last] ? fmin(path->exact_tol, tol) : tol;
}

double mca_path_distance(const mca_path_t *path, const double x[3]) {
    switch (path->kind) {
    case MCA_PATH_STREAM:
        return mca_v3_dist(x, path->stream_r);
    case MCA_PATH_CIRCLE: {
        /* the circle's plane through its centre, then the ring in it */
        double c[3], w[3], n[3];
        for (int k = 0; k < 3; k++) {
            c[k] = path->anchor[k] - path->radius * path->u[k];
        }
        mca_v3_sub(w, x, c);
        mca_v3_cross(n, path->u, path->v);
        const double h = mca_v3_dot(w, n);
        double wp[3];
        for (int k = 0; k < 3; k++) {
            wp[k] = w[k] - h * n[k];
        }
        const double radial = mca_v3_norm(wp) - path->radius;
        return sqrt(h * h + radial * radial);
    }
    case MCA_PATH_WAYPOINTS: {
        if (path->n_points < 1) {
            return mca_v3_dist(x, path->anchor);
        }
        double a[3], b[3];
        mca_path_point(path, 0, a);
        double d = mca_v3_dist(x, a);
        for (int i = 0; i + 1 < path->n_points; i++) {
            mca_path_point(path, i + 1, b);
            double h[3];
            d = fmin(d, mca_point_segment_paper(x, a, b, h, NULL));
            mca_v3_set(a, b);
        }
        return d;
    }
    default:
        return mca_v3_dist(x, path->anchor);
    }
}
