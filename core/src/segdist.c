/* SPDX-License-Identifier: MIT */
/* Segment-segment minimum distance: the paper's LSDM (Section III-B, Steps 1-3) and a robust closed form.
 * See docs/segdist.md for the accuracy study behind the choices made here. */
#include <math.h>
#include <stddef.h>

#include "mca/err.h"
#include "mca/segdist.h"
#include "mca/vec3.h"

/* Finite and small enough that squared differences cannot overflow (MCA_SEGDIST_MAX_COORD). */
static int finite3(const double *v) {
    return v != NULL && fabs(v[0]) <= MCA_SEGDIST_MAX_COORD && fabs(v[1]) <= MCA_SEGDIST_MAX_COORD &&
           fabs(v[2]) <= MCA_SEGDIST_MAX_COORD;
}

/* NaN (e.g. 0/0 on a degenerate segment) maps to 0 so the result stays a feasible point. */
static double clamp01(double x) {
    if (!(x > 0.0)) {
        return 0.0;
    }
    return x > 1.0 ? 1.0 : x;
}

/* Parameter of the point of segment c + t v closest to p (dot-product form, exact clamping). */
static double seg_param(const double p[3], const double c[3], const double v[3], double vv) {
    double w[3];
    if (!(vv > 0.0)) {
        return 0.0;
    }
    mca_v3_sub(w, p, c);
    return clamp01(mca_v3_dot(w, v) / vv);
}

/* |s u - (c + t v)|^2 in the frame where A is the origin. */
static double pair_d2(const double u[3], const double c[3], const double v[3], double s, double t) {
    double p[3], e[3], w[3];
    p[0] = s * u[0];
    p[1] = s * u[1];
    p[2] = s * u[2];
    mca_v3_axpy(e, c, t, v);
    mca_v3_sub(w, p, e);
    return mca_v3_dot(w, w);
}

static void fill_out(const double a[3], const double b[3], const double c[3], const double d[3], double s,
                     double t, mca_segdist_t *out) {
    double u[3], v[3];
    mca_v3_sub(u, b, a);
    mca_v3_sub(v, d, c);
    /* Endpoints exactly, so P == B when s == 1 (a + (b - a) may round). */
    if (s == 1.0) {
        mca_v3_set(out->p, b);
    } else {
        mca_v3_axpy(out->p, a, s, u);
    }
    if (t == 1.0) {
        mca_v3_set(out->e, d);
    } else {
        mca_v3_axpy(out->e, c, t, v);
    }
    out->s = s;
    out->t = t;
}

/*
 * The minimum of the convex quadratic F(s,t) = |A + s u - C - t v|^2 over [0,1]^2 is either on one of the
 * four edges (each an exact point-segment problem) or at the unconstrained line-line minimiser. The
 * line-line solution uses the cross-product form (error ~ eps / sin(angle), not eps / sin^2 as the normal
 * equations ac - b^2 have), then two projections make it optimal in t and s. Every candidate is a feasible
 * pair evaluated directly, so the best is never below the true minimum and never above the exact candidate
 * that attains it. Coordinates are taken relative to A to keep large offsets from eating precision.
 */
int mca_segdist_closed(const double a[3], const double b[3], const double c[3], const double d[3],
                       mca_segdist_t *out) {
    double u[3], c0[3], d0[3], v[3], n[3], tmp[3], x[3];
    double uu, vv, nn, s, t, d2, best_d2, best_s, best_t;
    static const double zero[3] = {0.0, 0.0, 0.0};

    if (!finite3(a) || !finite3(b) || !finite3(c) || !finite3(d) || out == NULL) {
        return MCA_EINVAL;
    }
    mca_v3_sub(u, b, a);
    mca_v3_sub(c0, c, a);
    mca_v3_sub(d0, d, a);
    mca_v3_sub(v, d, c);
    uu = mca_v3_dot(u, u);
    vv = mca_v3_dot(v, v);

    /* Edge s = 0: A against CD. */
    best_s = 0.0;
    best_t = seg_param(zero, c0, v, vv);
    best_d2 = pair_d2(u, c0, v, best_s, best_t);
    /* Edge s = 1: B against CD. */
    t = seg_param(u, c0, v, vv);
    d2 = pair_d2(u, c0, v, 1.0, t);
    if (d2 < best_d2) {
        best_d2 = d2;
        best_s = 1.0;
        best_t = t;
    }
    /* Edge t = 0: C against AB. */
    s = seg_param(c0, zero, u, uu);
    d2 = pair_d2(u, c0, v, s, 0.0);
    if (d2 < best_d2) {
        best_d2 = d2;
        best_s = s;
        best_t = 0.0;
    }
    /* Edge t = 1: D against AB. */
    s = seg_param(d0, zero, u, uu);
    d2 = pair_d2(u, c0, v, s, 1.0);
    if (d2 < best_d2) {
        best_d2 = d2;
        best_s = s;
        best_t = 1.0;
    }
    /* Interior: line-line closest points, then one projection each way. */
    mca_v3_cross(n, u, v);
    nn = mca_v3_dot(n, n);
    if (nn > 0.0 && best_d2 > 0.0) {
        mca_v3_cross(tmp, c0, v);
        s = clamp01(mca_v3_dot(tmp, n) / nn);
        x[0] = s * u[0];
        x[1] = s * u[1];
        x[2] = s * u[2];
        t = seg_param(x, c0, v, vv);
        mca_v3_axpy(x, c0, t, v);
        s = seg_param(x, zero, u, uu);
        d2 = pair_d2(u, c0, v, s, t);
        if (d2 < best_d2) {
            best_d2 = d2;
            best_s = s;
            best_t = t;
        }
    }
    fill_out(a, b, c, d, best_s, best_t, out);
    out->d = sqrt(best_d2);
    out->iterations = 0;
    return MCA_OK;
}

double mca_point_segment_paper(const double o[3], const double a[3], const double b[3], double h[3],
                               double *s) {
    double ab[3], ob[3], oa[3];
    double ab2, ab_len, ob2, oa2, hb, sv;

    mca_v3_sub(ab, b, a);
    ab2 = mca_v3_dot(ab, ab);
    if (!(ab2 > 0.0)) {
        sv = 0.0; /* zero-length segment: the point itself */
    } else {
        ab_len = sqrt(ab2);
        mca_v3_sub(ob, o, b);
        mca_v3_sub(oa, o, a);
        ob2 = mca_v3_dot(ob, ob);
        oa2 = mca_v3_dot(oa, oa);
        /* Paper eq. after (9): HB = (OB^2 + AB^2 - OA^2) / (2 AB), measured from B towards A. */
        hb = (ob2 + ab2 - oa2) / (2.0 * ab_len);
        if (hb > ab_len) {
            sv = 0.0; /* case 1: H beyond A, P = A */
        } else if (hb < 0.0) {
            sv = 1.0; /* case 3: H beyond B, P = B */
        } else {
            sv = 1.0 - hb / ab_len; /* case 2: H on the segment */
        }
    }
    if (sv == 0.0) {
        mca_v3_set(h, a);
    } else if (sv == 1.0) {
        mca_v3_set(h, b);
    } else {
        mca_v3_axpy(h, a, sv, ab);
    }
    if (s != NULL) {
        *s = sv;
    }
    return mca_v3_dist(o, h);
}

double mca_segdist_lower_bound(const double a[3], const double b[3], const double c[3], const double d[3],
                               const double p[3], const double e[3]) {
    double w[3], r[3], len, lo_ab, hi_cd, x, lb;

    mca_v3_sub(w, p, e);
    len = mca_v3_norm(w);
    if (!(len > 0.0)) {
        return 0.0;
    }
    /* Support values relative to E keep large coordinates from cancelling. */
    mca_v3_sub(r, a, e);
    lo_ab = mca_v3_dot(r, w);
    mca_v3_sub(r, b, e);
    x = mca_v3_dot(r, w);
    lo_ab = x < lo_ab ? x : lo_ab;
    mca_v3_sub(r, c, e);
    hi_cd = mca_v3_dot(r, w);
    mca_v3_sub(r, d, e);
    x = mca_v3_dot(r, w);
    hi_cd = x > hi_cd ? x : hi_cd;
    lb = (lo_ab - hi_cd) / len;
    return lb > 0.0 ? lb : 0.0;
}

enum lsdm_rule { RULE_PAPER, RULE_GAP };

/*
 * Step 3: start at B, project onto CD (H1), project H1 onto AB (H2), ... Each projection counts as one
 * iteration. The paper's rule stops when the distance declines by less than tol; the gap rule stops when
 * the separating-plane certificate proves the pair within tol of the minimum.
 */
static int lsdm_run(const double a[3], const double b[3], const double c[3], const double d[3],
                    const mca_lsdm_params_t *params, enum lsdm_rule rule, mca_segdist_t *out) {
    mca_lsdm_params_t def = {MCA_LSDM_DEFAULT_TOL, MCA_LSDM_DEFAULT_MAX_ITER};
    double x[3], y[3], sx = 1.0, ty = 0.0, dcur, dprev = INFINITY;
    double best = INFINITY, bs = 1.0, bt = 0.0;
    int it = 0;

    if (!finite3(a) || !finite3(b) || !finite3(c) || !finite3(d) || out == NULL) {
        return MCA_EINVAL;
    }
    if (params == NULL) {
        params = &def;
    }
    if (!(params->tol >= 0.0) || !isfinite(params->tol) || params->max_iter < 2) {
        return MCA_EINVAL;
    }
    mca_v3_set(x, b);
    for (;;) {
        /* Odd iterations: x on AB -> y on CD; even: y on CD -> x on AB. */
        if ((it & 1) == 0) {
            dcur = mca_point_segment_paper(x, c, d, y, &ty);
        } else {
            dcur = mca_point_segment_paper(y, a, b, x, &sx);
        }
        it++;
        if (dcur < best) {
            best = dcur;
            bs = sx;
            bt = ty;
        }
        if (rule == RULE_PAPER) {
            if (it >= 2 && dprev - dcur < params->tol) {
                break;
            }
        } else if (dcur - mca_segdist_lower_bound(a, b, c, d, x, y) <= params->tol) {
            break;
        }
        if (it >= params->max_iter) {
            fill_out(a, b, c, d, bs, bt, out);
            out->d = best;
            out->iterations = it;
            return MCA_ENOTCONV;
        }
        dprev = dcur;
    }
    fill_out(a, b, c, d, bs, bt, out);
    out->d = best;
    out->iterations = it;
    return MCA_OK;
}

int mca_segdist_lsdm(const double a[3], const double b[3], const double c[3], const double d[3],
                     const mca_lsdm_params_t *params, mca_segdist_t *out) {
    return lsdm_run(a, b, c, d, params, RULE_PAPER, out);
}

int mca_segdist_lsdm_certified(const double a[3], const double b[3], const double c[3], const double d[3],
                               const mca_lsdm_params_t *params, mca_segdist_t *out) {
    return lsdm_run(a, b, c, d, params, RULE_GAP, out);
}
