/* SPDX-License-Identifier: MIT */
/* Capsule against the fixed-body kinds (plane, sphere, capsule, box, cylinder): closed forms and exact
 * finite algorithms, no libccd, no allocation. The segment distance is core's mca_segdist_closed(). */
#include <math.h>
#include <stddef.h>

#include "mca/body.h"
#include "mca/err.h"
#include "mca/segdist.h"
#include "mca/vec3.h"

/* Finite and small enough that squares cannot overflow (NaN fails the comparisons). */
static int finite3(const double *v) {
    return fabs(v[0]) <= MCA_SEGDIST_MAX_COORD && fabs(v[1]) <= MCA_SEGDIST_MAX_COORD &&
           fabs(v[2]) <= MCA_SEGDIST_MAX_COORD;
}

static int length_ok(double x) {
    return x >= 0.0 && x <= MCA_SEGDIST_MAX_COORD;
}

static int capsule_ok(const mca_capsule_t *c) {
    return c != NULL && finite3(c->a) && finite3(c->b) && length_ok(c->radius);
}

/* Unit copy of a direction; 0 when it is zero or not finite. */
static int unit(double out[3], const double v[3]) {
    double n;
    if (!finite3(v)) {
        return 0;
    }
    n = mca_v3_norm(v);
    if (!(n > 0.0) || !isfinite(n)) {
        return 0;
    }
    out[0] = v[0] / n;
    out[1] = v[1] / n;
    out[2] = v[2] / n;
    return 1;
}

/* A unit vector normal to v (any, deterministic); (0, 0, 1) when v is zero. */
static void perp_unit(double out[3], const double v[3]) {
    static const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0};
    double c[3];
    mca_v3_cross(c, v, fabs(v[0]) < fabs(v[1]) ? ex : ey);
    if (!unit(out, c)) {
        out[0] = out[1] = 0.0;
        out[2] = 1.0;
    }
}

/* Point on a-b at parameter t, end points exactly. */
static void seg_point(double out[3], const double a[3], const double b[3], const double u[3], double t) {
    if (t == 1.0) {
        mca_v3_set(out, b);
    } else {
        mca_v3_axpy(out, a, t, u);
    }
}

/* Fill the result from the axis witness, the body point the axis distance is measured to (its surface or,
 * for sphere and capsule, its core), the unit normal and the signed distance. */
static void finish(mca_body_dist_t *out, const double p_axis[3], double radius, const double q[3],
                   const double n[3], double d, int exact) {
    mca_v3_set(out->p_axis, p_axis);
    mca_v3_axpy(out->p, p_axis, -radius, n);
    mca_v3_set(out->q, q);
    mca_v3_set(out->n, n);
    out->d = d;
    out->exact = exact;
    out->iterations = 0;
}

/* ---- plane ---- */

int mca_capsule_plane_distance(const mca_capsule_t *cap, const mca_body_plane_t *pl, mca_body_dist_t *out) {
    double n[3], w[3], sa, sb, s, pa[3], q[3];
    if (!capsule_ok(cap) || pl == NULL || out == NULL || !finite3(pl->point) || !unit(n, pl->normal)) {
        return MCA_EINVAL;
    }
    mca_v3_sub(w, cap->a, pl->point);
    sa = mca_v3_dot(w, n);
    mca_v3_sub(w, cap->b, pl->point);
    sb = mca_v3_dot(w, n);
    if (sa < sb) {
        mca_v3_set(pa, cap->a);
        s = sa;
    } else if (sb < sa) {
        mca_v3_set(pa, cap->b);
        s = sb;
    } else { /* parallel: the midpoint */
        for (int i = 0; i < 3; i++) {
            pa[i] = 0.5 * (cap->a[i] + cap->b[i]);
        }
        s = sa;
    }
    mca_v3_axpy(q, pa, -s, n);
    finish(out, pa, cap->radius, q, n, s - cap->radius, 1);
    return MCA_OK;
}

/* ---- sphere and capsule: segment distances ---- */

/* Axis witness pa, core witness e (on the other segment or the centre), axis distance sd, both radii; u, v
 * the two segment directions (v zero for a sphere) for the escape direction of crossing axes. */
static void round_result(mca_body_dist_t *out, const mca_segdist_t *sd, double r1, double r2,
                         const double u[3], const double v[3]) {
    double n[3], q[3], w[3];
    mca_v3_sub(w, sd->p, sd->e);
    if (sd->d > 0.0 && unit(n, w)) {
        /* separated axes */
    } else {
        /* crossing axes: the least translation separating two crossing segments is 0 along u x v, so the
         * depth is r1 + r2 along it (exact); parallel, collinear or point axes: any normal of the longer */
        mca_v3_cross(w, u, v);
        if (!(mca_v3_norm(w) > 1e-12 * mca_v3_norm(u) * mca_v3_norm(v)) || !unit(n, w)) {
            perp_unit(n, mca_v3_dot(u, u) >= mca_v3_dot(v, v) ? u : v);
        }
    }
    mca_v3_axpy(q, sd->e, r2, n);
    finish(out, sd->p, r1, q, n, sd->d - r1 - r2, 1);
}

int mca_capsule_sphere_distance(const mca_capsule_t *cap, const mca_body_sphere_t *sp, mca_body_dist_t *out) {
    mca_segdist_t sd;
    double u[3];
    static const double zero[3] = {0.0, 0.0, 0.0};
    if (!capsule_ok(cap) || sp == NULL || out == NULL || !finite3(sp->centre) || !length_ok(sp->radius)) {
        return MCA_EINVAL;
    }
    if (mca_segdist_closed(cap->a, cap->b, sp->centre, sp->centre, &sd) != MCA_OK) {
        return MCA_EINVAL;
    }
    mca_v3_sub(u, cap->b, cap->a);
    round_result(out, &sd, cap->radius, sp->radius, u, zero);
    return MCA_OK;
}

int mca_capsule_capsule_distance(const mca_capsule_t *cap, const mca_capsule_t *other, mca_body_dist_t *out) {
    mca_segdist_t sd;
    double u[3], v[3];
    if (!capsule_ok(cap) || !capsule_ok(other) || out == NULL) {
        return MCA_EINVAL;
    }
    if (mca_segdist_closed(cap->a, cap->b, other->a, other->b, &sd) != MCA_OK) {
        return MCA_EINVAL;
    }
    mca_v3_sub(u, cap->b, cap->a);
    mca_v3_sub(v, other->b, other->a);
    round_result(out, &sd, cap->radius, other->radius, u, v);
    return MCA_OK;
}

/* ---- box ---- */

/* R^T x: world vector into the box frame (the box, not R[3][3]: gcc's -Wstringop-overflow under ASan took
 * the array parameter for 9 doubles read from a region of 3) */
static void rot_t(double out[3], const mca_body_box_t *box, const double x[3]) {
    for (int i = 0; i < 3; i++) {
        out[i] = box->R[0][i] * x[0] + box->R[1][i] * x[1] + box->R[2][i] * x[2];
    }
}

/* R x: box-frame vector into the world */
static void rot(double out[3], const mca_body_box_t *box, const double x[3]) {
    for (int i = 0; i < 3; i++) {
        out[i] = box->R[i][0] * x[0] + box->R[i][1] * x[1] + box->R[i][2] * x[2];
    }
}

static int box_ok(const mca_body_box_t *b) {
    if (b == NULL || !finite3(b->centre) || !length_ok(b->half[0]) || !length_ok(b->half[1]) ||
        !length_ok(b->half[2]) || !finite3(b->R[0]) || !finite3(b->R[1]) || !finite3(b->R[2])) {
        return 0;
    }
    for (int i = 0; i < 3; i++) {
        for (int j = i; j < 3; j++) {
            double g = b->R[0][i] * b->R[0][j] + b->R[1][i] * b->R[1][j] + b->R[2][i] * b->R[2][j];
            if (!(fabs(g - (i == j ? 1.0 : 0.0)) <= 1e-9)) {
                return 0;
            }
        }
    }
    return 1;
}

/* Squared distance of the box-frame point a + t u to the box, and the closest box point. */
static double box_g(const double al[3], const double ul[3], const double h[3], double t, double x[3],
                    double c[3]) {
    double g = 0.0;
    for (int i = 0; i < 3; i++) {
        x[i] = al[i] + t * ul[i];
        c[i] = x[i] > h[i] ? h[i] : (x[i] < -h[i] ? -h[i] : x[i]);
        g += (x[i] - c[i]) * (x[i] - c[i]);
    }
    return g;
}

/*
 * Axis inside the box: exact penetration depth by the separating-axis theorem. The faces of the Minkowski
 * difference box - segment have the box face normals and the normals e_i x u, so the least translation that
 * separates lies along one of them. Box frame in and out.
 */
static double box_sat(const double al[3], const double bl[3], const double ul[3], const double h[3],
                      double n_out[3], double pl[3]) {
    double axes[6][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, best = INFINITY, un = mca_v3_norm(ul);
    int na = 3;
    for (int i = 0; i < 3; i++) {
        double e[3] = {0, 0, 0}, c[3];
        e[i] = 1.0;
        mca_v3_cross(c, ul, e);
        if (mca_v3_norm(c) > 1e-9 * un && unit(axes[na], c)) {
            na++;
        }
    }
    n_out[0] = n_out[1] = 0.0;
    n_out[2] = 1.0;
    for (int k = 0; k < na; k++) {
        const double *n = axes[k];
        double hn = h[0] * fabs(n[0]) + h[1] * fabs(n[1]) + h[2] * fabs(n[2]);
        double sa = mca_v3_dot(al, n), sb = mca_v3_dot(bl, n);
        double up = hn - fmin(sa, sb);   /* push along +n */
        double down = fmax(sa, sb) + hn; /* push along -n */
        if (up < best) {
            best = up;
            mca_v3_set(n_out, n);
        }
        if (down < best) {
            best = down;
            n_out[0] = -n[0];
            n_out[1] = -n[1];
            n_out[2] = -n[2];
        }
    }
    if (!(best > 0.0)) {
        best = 0.0; /* touching (rounding) */
    }
    /* the axis point deepest against the escape direction (the midpoint on a tie) */
    double da = mca_v3_dot(al, n_out), db = mca_v3_dot(bl, n_out);
    if (da < db) {
        mca_v3_set(pl, al);
    } else if (db < da) {
        mca_v3_set(pl, bl);
    } else {
        for (int i = 0; i < 3; i++) {
            pl[i] = 0.5 * (al[i] + bl[i]);
        }
    }
    return best;
}

/* Sort up to 8 numbers (insertion sort). */
static void sort_small(double *v, int n) {
    for (int i = 1; i < n; i++) {
        double x = v[i];
        int j = i - 1;
        while (j >= 0 && v[j] > x) {
            v[j + 1] = v[j];
            j--;
        }
        v[j + 1] = x;
    }
}

int mca_capsule_box_distance(const mca_capsule_t *cap, const mca_body_box_t *box, mca_body_dist_t *out) {
    double rel[3], al[3], bl[3], ul[3], u[3], brk[8], x[3], c[3], best_t = 0.0, best_g, g;
    int nb = 0;
    if (!capsule_ok(cap) || !box_ok(box) || out == NULL) {
        return MCA_EINVAL;
    }
    mca_v3_sub(rel, cap->a, box->centre);
    rot_t(al, box, rel);
    mca_v3_sub(rel, cap->b, box->centre);
    rot_t(bl, box, rel);
    mca_v3_sub(u, cap->b, cap->a);
    rot_t(ul, box, u);

    /* g(t) = sum_i max(|a_i + t u_i| - h_i, 0)^2 is convex and piecewise quadratic; its breaks are where a
     * coordinate crosses a face plane. On each piece the active faces are fixed (read at the midpoint) and
     * the piece's minimiser is the clamped vertex of its quadratic. Every candidate is evaluated directly,
     * so the best is never below the true minimum. */
    brk[nb++] = 0.0;
    brk[nb++] = 1.0;
    for (int i = 0; i < 3; i++) {
        if (ul[i] != 0.0) {
            for (int sgn = -1; sgn <= 1; sgn += 2) {
                double t = (sgn * box->half[i] - al[i]) / ul[i];
                if (t > 0.0 && t < 1.0) {
                    brk[nb++] = t;
                }
            }
        }
    }
    sort_small(brk, nb);
    best_g = box_g(al, ul, box->half, 0.0, x, c);
    g = box_g(al, ul, box->half, 1.0, x, c);
    if (g < best_g) {
        best_g = g;
        best_t = 1.0;
    }
    for (int k = 0; k + 1 < nb && best_g > 0.0; k++) {
        double lo = brk[k], hi = brk[k + 1], m = 0.5 * (lo + hi), num = 0.0, den = 0.0, t;
        if (!(hi > lo)) {
            continue;
        }
        for (int i = 0; i < 3; i++) {
            double xi = al[i] + m * ul[i];
            if (xi > box->half[i]) {
                num += ul[i] * (al[i] - box->half[i]);
                den += ul[i] * ul[i];
            } else if (xi < -box->half[i]) {
                num += ul[i] * (al[i] + box->half[i]);
                den += ul[i] * ul[i];
            }
        }
        /* no active face: the whole piece is inside the box, and g(m) is exactly 0 */
        t = den > 0.0 ? -num / den : m;
        t = t < lo ? lo : (t > hi ? hi : t);
        g = box_g(al, ul, box->half, t, x, c);
        if (g < best_g) {
            best_g = g;
            best_t = t;
        }
    }

    double pa[3], q[3], n[3], diff[3], nl[3], ql[3];
    if (best_g > 0.0) {
        double dist;
        (void)box_g(al, ul, box->half, best_t, x, c);
        mca_v3_sub(diff, x, c);
        dist = mca_v3_norm(diff);
        if (dist > 0.0) {
            rot(nl, box, diff);
            n[0] = nl[0] / dist;
            n[1] = nl[1] / dist;
            n[2] = nl[2] / dist;
            rot(q, box, c);
            mca_v3_add(q, q, box->centre);
            seg_point(pa, cap->a, cap->b, u, best_t);
            finish(out, pa, cap->radius, q, n, dist - cap->radius, 1);
            return MCA_OK;
        }
    }
    /* the axis touches or enters the box */
    double depth = box_sat(al, bl, ul, box->half, nl, x);
    mca_v3_axpy(ql, x, depth, nl);
    rot(n, box, nl);
    rot(pa, box, x);
    mca_v3_add(pa, pa, box->centre);
    rot(q, box, ql);
    mca_v3_add(q, q, box->centre);
    finish(out, pa, cap->radius, q, n, -(depth + cap->radius), 1);
    return MCA_OK;
}

/* ---- cylinder ---- */

typedef struct cyl_frame {
    double a[3], u[3]; /* axis point a + t u relative to the centre */
    double w[3];       /* unit axis */
    double h, r;
} cyl_frame_t;

/* Distance from the axis point at t to the solid cylinder, its closest point (relative to the centre) and
 * the derivative of the distance along t (0 when the point is inside). */
static double cyl_eval(const cyl_frame_t *f, double t, double x[3], double c[3], double *deriv) {
    double z, rad[3], rho, cz, diff[3], dist;
    mca_v3_axpy(x, f->a, t, f->u);
    z = mca_v3_dot(x, f->w);
    mca_v3_axpy(rad, x, -z, f->w);
    rho = mca_v3_norm(rad);
    cz = z > f->h ? f->h : (z < -f->h ? -f->h : z);
    if (rho > f->r) {
        for (int i = 0; i < 3; i++) {
            c[i] = rad[i] * (f->r / rho) + cz * f->w[i];
        }
    } else {
        mca_v3_axpy(c, rad, cz, f->w);
    }
    mca_v3_sub(diff, x, c);
    dist = mca_v3_norm(diff);
    *deriv = dist > 0.0 ? mca_v3_dot(diff, f->u) / dist : 0.0;
    return dist;
}

static int cyl_ok(const mca_body_cylinder_t *c, double w[3]) {
    return c != NULL && finite3(c->centre) && unit(w, c->axis) && length_ok(c->half_len) &&
           length_ok(c->radius);
}

/* The axis enters the cylinder: the shallowest of the escapes along +w, -w and the best radial direction.
 * Each is a translation that separates, so the result is an upper bound on the least one (the rim swept
 * along the axis can give a shallower, oblique escape). */
static double cyl_escape(const cyl_frame_t *f, const double bl[3], double n[3], double pl[3]) {
    double za = mca_v3_dot(f->a, f->w), zb = mca_v3_dot(bl, f->w), ar[3], br[3], ur[3], best, dr, t, uu;
    double cp[3];
    /* along +w: the lowest end must rise above the top cap; along -w: the highest below the bottom */
    best = f->h - fmin(za, zb);
    mca_v3_set(n, f->w);
    mca_v3_set(pl, za <= zb ? f->a : bl);
    if (fmax(za, zb) + f->h < best) {
        best = fmax(za, zb) + f->h;
        n[0] = -f->w[0];
        n[1] = -f->w[1];
        n[2] = -f->w[2];
        mca_v3_set(pl, za >= zb ? f->a : bl);
    }
    /* radial: the segment's projection on the plane normal to w must leave the disc; the least push is
     * r - (its distance from the axis), along the direction to its closest point */
    mca_v3_axpy(ar, f->a, -za, f->w);
    mca_v3_axpy(br, bl, -zb, f->w);
    mca_v3_sub(ur, br, ar);
    uu = mca_v3_dot(ur, ur);
    t = uu > 0.0 ? -mca_v3_dot(ar, ur) / uu : 0.0;
    t = t > 0.0 ? (t < 1.0 ? t : 1.0) : 0.0;
    mca_v3_axpy(cp, ar, t, ur);
    dr = mca_v3_norm(cp);
    if (f->r - dr < best) {
        double nr[3];
        best = f->r - dr;
        if (!(dr > 0.0) || !unit(nr, cp)) {
            double c2[3]; /* the projection passes through the axis: normal to it and to w */
            mca_v3_cross(c2, f->w, ur);
            if (!unit(nr, c2)) {
                perp_unit(nr, f->w);
            }
        }
        mca_v3_set(n, nr);
        /* the axis point deepest against n */
        mca_v3_set(pl, mca_v3_dot(f->a, nr) <= mca_v3_dot(bl, nr) ? f->a : bl);
    }
    return best > 0.0 ? best : 0.0;
}

int mca_capsule_cylinder_distance(const mca_capsule_t *cap, const mca_body_cylinder_t *cyl,
                                  mca_body_dist_t *out) {
    cyl_frame_t f;
    double x[3], c[3], lo = 0.0, hi = 1.0, glo, ghi, flo, fhi, t = 0.0, best_t;
    int side = 0, inside = 0, iters = 0;
    if (!capsule_ok(cap) || !cyl_ok(cyl, f.w) || out == NULL) {
        return MCA_EINVAL;
    }
    mca_v3_sub(f.a, cap->a, cyl->centre);
    mca_v3_sub(f.u, cap->b, cap->a);
    f.h = cyl->half_len;
    f.r = cyl->radius;

    /* f(t) = dist(a + t u, cylinder) is convex, and C^1 where positive: its minimum is an end point or the
     * root of f'. */
    flo = cyl_eval(&f, 0.0, x, c, &glo);
    fhi = cyl_eval(&f, 1.0, x, c, &ghi);
    inside = flo == 0.0 || fhi == 0.0;
    if (inside) {
        best_t = flo == 0.0 ? 0.0 : 1.0;
    } else if (glo >= 0.0) {
        best_t = 0.0;
    } else if (ghi <= 0.0) {
        best_t = 1.0;
    } else {
        /* Illinois regula falsi on f' over the bracket [lo, hi] (f'(lo) < 0 < f'(hi)), bisection after 40
         * steps; stops when the bracket is MCA_BODY_CYL_TOL_T wide or f' is exactly 0. The answer is the
         * bracket's midpoint, not the evaluated point of least f: near the minimum f is flat to rounding,
         * and the least computed f can lie ~1e-8 away from the root (the sign of f' is what is accurate). */
        int stationary = 0;
        for (; iters < MCA_BODY_CYL_MAX_ITER && hi - lo > MCA_BODY_CYL_TOL_T; iters++) {
            double g, fv;
            t = iters < 40 ? lo - glo * (hi - lo) / (ghi - glo) : 0.5 * (lo + hi);
            if (!(t > lo && t < hi)) {
                t = 0.5 * (lo + hi);
            }
            fv = cyl_eval(&f, t, x, c, &g);
            if (fv == 0.0) {
                inside = 1;
                iters++;
                break;
            }
            if (g == 0.0) {
                stationary = 1;
                iters++;
                break;
            }
            if (g < 0.0) {
                lo = t;
                glo = g;
                if (side == -1) {
                    ghi *= 0.5;
                }
                side = -1;
            } else {
                hi = t;
                ghi = g;
                if (side == 1) {
                    glo *= 0.5;
                }
                side = 1;
            }
        }
        best_t = stationary || inside ? t : 0.5 * (lo + hi);
    }

    double pa[3], q[3], n[3], diff[3], dist, dummy;
    if (!inside) {
        dist = cyl_eval(&f, best_t, x, c, &dummy);
        mca_v3_sub(diff, x, c);
        if (dist > 0.0 && unit(n, diff)) {
            mca_v3_add(q, c, cyl->centre);
            seg_point(pa, cap->a, cap->b, f.u, best_t);
            finish(out, pa, cap->radius, q, n, dist - cap->radius, 1);
            out->iterations = iters;
            return MCA_OK;
        }
    }
    /* the axis touches or enters the cylinder */
    double bl[3], pl[3], depth;
    mca_v3_sub(bl, cap->b, cyl->centre);
    depth = cyl_escape(&f, bl, n, pl);
    mca_v3_add(pa, pl, cyl->centre);
    mca_v3_axpy(q, pa, depth, n);
    finish(out, pa, cap->radius, q, n, -(depth + cap->radius), depth > 0.0 ? 0 : 1);
    out->iterations = iters;
    return MCA_OK;
}

/* ---- dispatcher ---- */

int mca_capsule_body_distance(const mca_capsule_t *cap, const mca_body_t *body, mca_body_dist_t *out) {
    if (body == NULL) {
        return MCA_EINVAL;
    }
    switch (body->kind) {
    case MCA_BODY_PLANE:
        return mca_capsule_plane_distance(cap, &body->u.plane, out);
    case MCA_BODY_SPHERE:
        return mca_capsule_sphere_distance(cap, &body->u.sphere, out);
    case MCA_BODY_CAPSULE:
        return mca_capsule_capsule_distance(cap, &body->u.capsule, out);
    case MCA_BODY_BOX:
        return mca_capsule_box_distance(cap, &body->u.box, out);
    case MCA_BODY_CYLINDER:
        return mca_capsule_cylinder_distance(cap, &body->u.cylinder, out);
    default:
        return MCA_EINVAL;
    }
}
