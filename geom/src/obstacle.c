/* SPDX-License-Identifier: MIT */
/* Capsule vs obstacle / capsule distances: a GJK distance loop on libccd's support-function interface for
 * separated shapes, libccd's MPR (no allocation) for overlapping ones. libccd 2.1 has no distance query. */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include <ccd/ccd.h>

#include "mca/err.h"
#include "mca/obstacle.h"
#include "mca/segdist.h"
#include "mca/vec3.h"

/* One convex shape as libccd sees it (support + centre callbacks take a const void *). */
typedef enum { SH_CAPSULE, SH_BOX, SH_CYLINDER } shape_kind_t;

typedef struct shape {
    shape_kind_t kind;
    double a[3], b[3], r;      /* capsule: axis and radius (radius used only when with_radius) */
    int with_radius;           /* GJK runs on the bare axis, MPR on the full capsule */
    const mca_obstacle_t *obs; /* box / cylinder */
} shape_t;

/* Finite and small enough that squares cannot overflow (NaN fails the comparisons). */
static int finite3(const double *v) {
    return v != NULL && fabs(v[0]) <= MCA_SEGDIST_MAX_COORD && fabs(v[1]) <= MCA_SEGDIST_MAX_COORD &&
           fabs(v[2]) <= MCA_SEGDIST_MAX_COORD;
}

/* R^T x (world direction into the shape frame) */
static void rot_t(double out[3], const double R[3][3], const double x[3]) {
    for (int i = 0; i < 3; i++) {
        out[i] = R[0][i] * x[0] + R[1][i] * x[1] + R[2][i] * x[2];
    }
}

static void local_to_world(double out[3], const mca_pose_t *pose, const double xl[3]) {
    for (int i = 0; i < 3; i++) {
        out[i] = pose->R[i][0] * xl[0] + pose->R[i][1] * xl[1] + pose->R[i][2] * xl[2] + pose->p[i];
    }
}

static void support(const shape_t *s, const double dir[3], double out[3]) {
    double dl[3], xl[3], n;
    switch (s->kind) {
    case SH_CAPSULE:
        mca_v3_set(out, mca_v3_dot(s->b, dir) > mca_v3_dot(s->a, dir) ? s->b : s->a);
        if (s->with_radius && s->r > 0.0) {
            n = mca_v3_norm(dir);
            if (n > 0.0) {
                mca_v3_axpy(out, out, s->r / n, dir);
            }
        }
        return;
    case SH_BOX:
        rot_t(dl, s->obs->pose.R, dir);
        for (int i = 0; i < 3; i++) {
            xl[i] = dl[i] >= 0.0 ? s->obs->half[i] : -s->obs->half[i];
        }
        local_to_world(out, &s->obs->pose, xl);
        return;
    default: /* SH_CYLINDER, axis z */
        rot_t(dl, s->obs->pose.R, dir);
        n = sqrt(dl[0] * dl[0] + dl[1] * dl[1]);
        xl[0] = n > 0.0 ? s->obs->radius * dl[0] / n : 0.0;
        xl[1] = n > 0.0 ? s->obs->radius * dl[1] / n : 0.0;
        xl[2] = dl[2] >= 0.0 ? s->obs->half_height : -s->obs->half_height;
        local_to_world(out, &s->obs->pose, xl);
        return;
    }
}

static void ccd_support_cb(const void *obj, const ccd_vec3_t *dir, ccd_vec3_t *vec) {
    support((const shape_t *)obj, dir->v, vec->v);
}

static void ccd_center_cb(const void *obj, ccd_vec3_t *center) {
    const shape_t *s = (const shape_t *)obj;
    if (s->kind == SH_CAPSULE) {
        for (int i = 0; i < 3; i++) {
            center->v[i] = 0.5 * (s->a[i] + s->b[i]);
        }
    } else {
        mca_v3_set(center->v, s->obs->pose.p);
    }
}

/* ---- GJK distance: closest point of the Minkowski difference A - B to the origin ---- */

typedef struct gjk_vert {
    double w[3], pa[3], pb[3]; /* w = pa - pb */
} gjk_vert_t;

/* Solve the n x n (n <= 3) system G x = r by Gaussian elimination with partial pivoting. */
static int solve_small(int n, double G[3][3], double r[3], double x[3], double scale) {
    for (int c = 0; c < n; c++) {
        int piv = c;
        for (int i = c + 1; i < n; i++) {
            if (fabs(G[i][c]) > fabs(G[piv][c])) {
                piv = i;
            }
        }
        /* singular (affinely dependent vertices): that subset is not a proper face */
        if (!(fabs(G[piv][c]) > 1e-13 * scale)) {
            return -1;
        }
        if (piv != c) {
            for (int j = 0; j < n; j++) {
                double t = G[c][j];
                G[c][j] = G[piv][j];
                G[piv][j] = t;
            }
            double t = r[c];
            r[c] = r[piv];
            r[piv] = t;
        }
        for (int i = c + 1; i < n; i++) {
            double f = G[i][c] / G[c][c];
            for (int j = c; j < n; j++) {
                G[i][j] -= f * G[c][j];
            }
            r[i] -= f * r[c];
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        double acc = r[i];
        for (int j = i + 1; j < n; j++) {
            acc -= G[i][j] * x[j];
        }
        x[i] = acc / G[i][i];
    }
    return 0;
}

/*
 * Closest point of conv(W) to the origin, by trying every subset of the (at most 4) vertices: the answer
 * is the affine projection of the origin onto the face that has it in its relative interior (all
 * barycentric weights > 0); every such candidate lies in the hull, so the nearest valid one is the
 * answer. 15 subsets at most: simple and robust. W is reduced to that face; lam holds its weights.
 */
static void simplex_closest(gjk_vert_t *W, int *n, double v[3], double lam[4]) {
    double best = INFINITY, best_v[3] = {0, 0, 0}, best_l[4] = {0, 0, 0, 0};
    int best_mask = 1;
    const int nv = *n;

    for (int mask = 1; mask < (1 << nv); mask++) {
        int idx[4], m = 0;
        double l[4], x[3] = {0, 0, 0}, G[3][3], rr[3], vv[3], scale = 0.0;
        for (int i = 0; i < nv; i++) {
            if (mask & (1 << i)) {
                idx[m++] = i;
            }
        }
        if (m == 1) {
            l[0] = 1.0;
        } else {
            double e[3][3];
            for (int i = 1; i < m; i++) {
                mca_v3_sub(e[i - 1], W[idx[i]].w, W[idx[0]].w);
                scale = fmax(scale, mca_v3_dot(e[i - 1], e[i - 1]));
            }
            for (int i = 0; i < m - 1; i++) {
                for (int j = 0; j < m - 1; j++) {
                    G[i][j] = mca_v3_dot(e[i], e[j]);
                }
                rr[i] = -mca_v3_dot(e[i], W[idx[0]].w);
            }
            if (solve_small(m - 1, G, rr, x, scale) != 0) {
                continue;
            }
            l[0] = 1.0;
            for (int i = 1; i < m; i++) {
                l[i] = x[i - 1];
                l[0] -= x[i - 1];
            }
        }
        int ok = 1;
        for (int i = 0; i < m; i++) {
            ok &= l[i] > 0.0;
        }
        if (!ok) {
            continue;
        }
        vv[0] = vv[1] = vv[2] = 0.0;
        for (int i = 0; i < m; i++) {
            mca_v3_axpy(vv, vv, l[i], W[idx[i]].w);
        }
        double d2 = mca_v3_dot(vv, vv);
        if (d2 < best) {
            best = d2;
            mca_v3_set(best_v, vv);
            best_mask = mask;
            for (int i = 0; i < 4; i++) {
                best_l[i] = i < m ? l[i] : 0.0;
            }
        }
    }
    /* compact W to the chosen face */
    int m = 0;
    for (int i = 0; i < nv; i++) {
        if (best_mask & (1 << i)) {
            W[m++] = W[i];
        }
    }
    *n = m;
    mca_v3_set(v, best_v);
    memcpy(lam, best_l, sizeof best_l);
}

/* GJK distance between shape a and shape b (bare axes for capsules). Returns the number of iterations
 * (> 0), or -iterations when the cap was hit; *inter = 1 when the shapes touch or overlap. */
static int gjk_distance(const shape_t *sa, const shape_t *sb, double pa[3], double pb[3], int *inter) {
    gjk_vert_t W[4];
    double v[3], lam[4] = {1, 0, 0, 0}, dir[3], ndir[3];
    int n = 1, it;

    *inter = 0;
    /* first vertex: towards B's centre from A's */
    ccd_vec3_t ca, cb;
    ccd_center_cb(sa, &ca);
    ccd_center_cb(sb, &cb);
    mca_v3_sub(dir, cb.v, ca.v);
    if (!(mca_v3_dot(dir, dir) > 0.0)) {
        dir[0] = 1.0;
        dir[1] = dir[2] = 0.0;
    }
    support(sa, dir, W[0].pa);
    mca_v3_set(ndir, dir);
    ndir[0] = -ndir[0];
    ndir[1] = -ndir[1];
    ndir[2] = -ndir[2];
    support(sb, ndir, W[0].pb);
    mca_v3_sub(W[0].w, W[0].pa, W[0].pb);
    mca_v3_set(v, W[0].w);

    for (it = 1; it <= MCA_GJK_MAX_ITER; it++) {
        double vv = mca_v3_dot(v, v), vn, w_new[3], pa_new[3], pb_new[3];
        if (!(vv > 1e-24)) {
            *inter = 1;
            break;
        }
        /* w = s_A(-v) - s_B(v) */
        mca_v3_set(ndir, v);
        ndir[0] = -ndir[0];
        ndir[1] = -ndir[1];
        ndir[2] = -ndir[2];
        support(sa, ndir, pa_new);
        support(sb, v, pb_new);
        mca_v3_sub(w_new, pa_new, pb_new);
        vn = sqrt(vv);
        /* duality gap: |v| - (v . w) / |v| bounds the error of |v| */
        if (vn - mca_v3_dot(v, w_new) / vn <= MCA_GJK_TOL) {
            break;
        }
        int dup = 0;
        for (int i = 0; i < n; i++) {
            double dw[3];
            mca_v3_sub(dw, W[i].w, w_new);
            dup |= mca_v3_dot(dw, dw) <= 1e-30;
        }
        if (dup || n == 4) {
            break; /* no progress possible: v is as good as this simplex gets */
        }
        /* Keep the previous simplex: when the new one does not bring v strictly closer (a flat face of
         * the Minkowski difference with v tiny, where the gap test drowns in rounding), the previous
         * v is as good as this arithmetic gets. */
        gjk_vert_t W_old[4];
        double lam_old[4], v_old[3];
        int n_old = n;
        memcpy(W_old, W, sizeof W);
        memcpy(lam_old, lam, sizeof lam_old);
        mca_v3_set(v_old, v);
        mca_v3_set(W[n].w, w_new);
        mca_v3_set(W[n].pa, pa_new);
        mca_v3_set(W[n].pb, pb_new);
        n++;
        simplex_closest(W, &n, v, lam);
        if (!(mca_v3_dot(v, v) < vv)) {
            memcpy(W, W_old, sizeof W);
            memcpy(lam, lam_old, sizeof lam_old);
            mca_v3_set(v, v_old);
            n = n_old;
            break;
        }
        if (n == 4) {
            *inter = 1; /* origin inside the tetrahedron */
            break;
        }
    }
    pa[0] = pa[1] = pa[2] = 0.0;
    pb[0] = pb[1] = pb[2] = 0.0;
    for (int i = 0; i < n; i++) {
        mca_v3_axpy(pa, pa, lam[i], W[i].pa);
        mca_v3_axpy(pb, pb, lam[i], W[i].pb);
    }
    if (n == 1) { /* lam may be stale from the start */
        mca_v3_set(pa, W[0].pa);
        mca_v3_set(pb, W[0].pb);
    }
    return it > MCA_GJK_MAX_ITER ? -MCA_GJK_MAX_ITER : it;
}

/* Closest point of segment a-b to x. */
static void closest_on_segment(const double a[3], const double b[3], const double x[3], double out[3]) {
    double u[3], w[3], uu, t = 0.0;
    mca_v3_sub(u, b, a);
    mca_v3_sub(w, x, a);
    uu = mca_v3_dot(u, u);
    if (uu > 0.0) {
        t = mca_v3_dot(w, u) / uu;
        t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    }
    mca_v3_axpy(out, a, t, u);
}

/* Crossing capsule axes: the least translation that separates them is r1 + r2 along u x v (exact). */
static int capsule_axes_cross(const shape_t *sa, const shape_t *sb, const double pa[3], double rsum,
                              mca_obst_dist_t *out) {
    double u[3], v[3], n[3], len;
    mca_v3_sub(u, sa->b, sa->a);
    mca_v3_sub(v, sb->b, sb->a);
    mca_v3_cross(n, u, v);
    len = mca_v3_norm(n);
    if (!(len > 1e-12 * mca_v3_norm(u) * mca_v3_norm(v))) {
        /* parallel / collinear / degenerate axes: any direction normal to the (longer) axis */
        const double *w = mca_v3_dot(u, u) >= mca_v3_dot(v, v) ? u : v;
        const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0};
        mca_v3_cross(n, w, fabs(w[0]) < fabs(w[1]) ? ex : ey);
        len = mca_v3_norm(n);
        if (!(len > 0.0)) {
            n[0] = n[1] = 0.0;
            n[2] = len = 1.0;
        }
    }
    out->penetrating = 1;
    out->d = 0.0 - rsum;
    for (int i = 0; i < 3; i++) {
        out->dir[i] = n[i] / len;
    }
    mca_v3_set(out->p, pa);
    mca_v3_set(out->q, pa);
    return MCA_OK;
}

/*
 * Segment entering a box: exact penetration depth by the separating-axis theorem (the least translation
 * separating two convex polytopes is along one of their SAT axes: the box's 3 face normals and the
 * segment direction crossed with the 3 box edges). Done in the box frame.
 */
static int segment_box_sat(const shape_t *sa, const mca_obstacle_t *box, double rsum, mca_obst_dist_t *out) {
    double al[3], bl[3], rel[3], u[3], axes[6][3], best = INFINITY, best_n[3] = {0, 0, 1}, pl[3], ql[3];
    int na = 3;
    mca_v3_sub(rel, sa->a, box->pose.p);
    rot_t(al, box->pose.R, rel);
    mca_v3_sub(rel, sa->b, box->pose.p);
    rot_t(bl, box->pose.R, rel);
    mca_v3_sub(u, bl, al);
    memset(axes, 0, sizeof axes);
    axes[0][0] = axes[1][1] = axes[2][2] = 1.0;
    for (int i = 0; i < 3; i++) {
        double e[3] = {0, 0, 0}, c[3], l;
        e[i] = 1.0;
        mca_v3_cross(c, u, e);
        l = mca_v3_norm(c);
        if (l > 1e-9 * mca_v3_norm(u)) {
            axes[na][0] = c[0] / l;
            axes[na][1] = c[1] / l;
            axes[na][2] = c[2] / l;
            na++;
        }
    }
    for (int k = 0; k < na; k++) {
        const double *n = axes[k];
        double h = box->half[0] * fabs(n[0]) + box->half[1] * fabs(n[1]) + box->half[2] * fabs(n[2]);
        double sa_ = mca_v3_dot(al, n), sb_ = mca_v3_dot(bl, n);
        double lo = fmin(sa_, sb_), hi = fmax(sa_, sb_);
        double up = h - lo;   /* push the segment along +n */
        double down = hi + h; /* push along -n */
        if (up < best) {
            best = up;
            mca_v3_set(best_n, n);
        }
        if (down < best) {
            best = down;
            best_n[0] = -n[0];
            best_n[1] = -n[1];
            best_n[2] = -n[2];
        }
    }
    if (best < 0.0) {
        best = 0.0; /* touching only (rounding) */
    }
    /* deepest axis point against the escape direction (midpoint on a tie), and its image on the surface */
    double da = mca_v3_dot(al, best_n), db = mca_v3_dot(bl, best_n);
    if (fabs(da - db) <= 1e-12) {
        for (int i = 0; i < 3; i++) {
            pl[i] = 0.5 * (al[i] + bl[i]);
        }
    } else {
        mca_v3_set(pl, da < db ? al : bl);
    }
    mca_v3_axpy(ql, pl, best, best_n);
    local_to_world(out->p, &box->pose, pl);
    local_to_world(out->q, &box->pose, ql);
    for (int i = 0; i < 3; i++) {
        out->dir[i] =
            box->pose.R[i][0] * best_n[0] + box->pose.R[i][1] * best_n[1] + box->pose.R[i][2] * best_n[2];
    }
    out->penetrating = 1;
    out->d = -(best + rsum);
    return MCA_OK;
}

/* Cylinder: libccd MPR on the full capsule (no allocation). MPR measures the depth along the portal it
 * converges to from the centre line, an upper bound on the least translation (approximate). */
static int cylinder_mpr(shape_t *sa, shape_t *sb, const double pa[3], const double pb[3], double rsum,
                        mca_obst_dist_t *out) {
    ccd_t ccd;
    ccd_real_t depth;
    ccd_vec3_t dir, pos;
    CCD_INIT(&ccd);
    ccd.support1 = ccd_support_cb;
    ccd.support2 = ccd_support_cb;
    ccd.center1 = ccd_center_cb;
    ccd.center2 = ccd_center_cb;
    ccd.max_iterations = 100;
    ccd.mpr_tolerance = 1e-9;
    sa->with_radius = 1;
    sb->with_radius = 1;
    /* obj2 = the capsule, so dir moves the capsule out */
    if (ccdMPRPenetration(sb, sa, &ccd, &depth, &dir, &pos) == 0 && isfinite(depth)) {
        double n = mca_v3_norm(dir.v);
        out->penetrating = 1;
        out->d = -depth;
        if (n > 0.0) {
            for (int i = 0; i < 3; i++) {
                out->dir[i] = dir.v[i] / n;
            }
        } else {
            out->dir[0] = out->dir[1] = 0.0;
            out->dir[2] = 1.0;
        }
        closest_on_segment(sa->a, sa->b, pos.v, out->p);
        mca_v3_axpy(out->q, out->p, -(out->d + rsum), out->dir);
        return MCA_OK;
    }
    /* MPR saw no volume overlap (touching with zero radius): d = -rsum at the touch point */
    out->penetrating = 0;
    out->d = 0.0 - rsum;
    mca_v3_set(out->p, pa);
    mca_v3_set(out->q, pb);
    out->dir[0] = out->dir[1] = 0.0;
    out->dir[2] = 1.0;
    return MCA_OK;
}

/* Shared path: shape a is the capsule whose axis carries p; rsum is the radius to subtract. */
static int shape_distance(shape_t *sa, shape_t *sb, double rsum, mca_obst_dist_t *out) {
    double pa[3], pb[3], w[3], len;
    int inter, it;

    sa->with_radius = 0;
    sb->with_radius = 0;
    it = gjk_distance(sa, sb, pa, pb, &inter);
    mca_v3_sub(w, pa, pb);
    len = mca_v3_norm(w);
    out->penetrating = 0;
    if (!inter && len > 0.0) {
        out->d = len - rsum;
        mca_v3_set(out->p, pa);
        mca_v3_set(out->q, pb);
        out->dir[0] = w[0] / len;
        out->dir[1] = w[1] / len;
        out->dir[2] = w[2] / len;
        out->iterations = it < 0 ? -it : it;
        return it < 0 ? MCA_ENOTCONV : MCA_OK;
    }
    out->iterations = it < 0 ? -it : it;
    if (sb->kind == SH_CAPSULE) {
        return capsule_axes_cross(sa, sb, pa, rsum, out);
    }
    if (sb->kind == SH_BOX) {
        return segment_box_sat(sa, sb->obs, rsum, out);
    }
    return cylinder_mpr(sa, sb, pa, pb, rsum, out);
}

static int obstacle_ok(const mca_obstacle_t *o) {
    if (o == NULL || !finite3(o->pose.p) || !finite3(o->pose.R[0]) || !finite3(o->pose.R[1]) ||
        !finite3(o->pose.R[2])) {
        return 0;
    }
    if (o->type == MCA_OBST_BOX) {
        return o->half[0] > 0.0 && o->half[1] > 0.0 && o->half[2] > 0.0 && finite3(o->half);
    }
    if (o->type == MCA_OBST_CYLINDER) {
        return o->radius > 0.0 && o->half_height > 0.0 && o->radius <= MCA_SEGDIST_MAX_COORD &&
               o->half_height <= MCA_SEGDIST_MAX_COORD;
    }
    return 0;
}

static int capsule_ok(const mca_capsule_t *c) {
    return c != NULL && finite3(c->a) && finite3(c->b) && c->radius >= 0.0 &&
           c->radius <= MCA_SEGDIST_MAX_COORD;
}

static void set_name(mca_obstacle_t *obs, const char *name) {
    memset(obs->name, 0, sizeof obs->name);
    if (name != NULL) {
        strncpy(obs->name, name, sizeof obs->name - 1);
    }
}

int mca_obstacle_box(mca_obstacle_t *obs, const char *name, const mca_pose_t *pose, const double half[3]) {
    mca_obstacle_t o;
    if (obs == NULL || pose == NULL || half == NULL) {
        return MCA_EINVAL;
    }
    memset(&o, 0, sizeof o);
    o.type = MCA_OBST_BOX;
    o.pose = *pose;
    mca_v3_set(o.half, half);
    if (!obstacle_ok(&o)) {
        return MCA_EINVAL;
    }
    *obs = o;
    set_name(obs, name);
    return MCA_OK;
}

int mca_obstacle_cylinder(mca_obstacle_t *obs, const char *name, const mca_pose_t *pose, double radius,
                          double height) {
    mca_obstacle_t o;
    if (obs == NULL || pose == NULL) {
        return MCA_EINVAL;
    }
    memset(&o, 0, sizeof o);
    o.type = MCA_OBST_CYLINDER;
    o.pose = *pose;
    o.radius = radius;
    o.half_height = 0.5 * height;
    if (!obstacle_ok(&o)) {
        return MCA_EINVAL;
    }
    *obs = o;
    set_name(obs, name);
    return MCA_OK;
}

int mca_obstacle_table(mca_obstacle_t *obs, const char *name, double top_z, double cx, double cy, double hx,
                       double hy, double thickness) {
    mca_pose_t pose;
    double half[3] = {hx, hy, 0.5 * thickness};
    if (!isfinite(top_z) || !isfinite(cx) || !isfinite(cy)) {
        return MCA_EINVAL;
    }
    memset(&pose, 0, sizeof pose);
    pose.R[0][0] = pose.R[1][1] = pose.R[2][2] = 1.0;
    pose.p[0] = cx;
    pose.p[1] = cy;
    pose.p[2] = top_z - 0.5 * thickness;
    return mca_obstacle_box(obs, name, &pose, half);
}

int mca_capsule_obstacle_distance(const mca_capsule_t *cap, const mca_obstacle_t *obs, mca_obst_dist_t *out) {
    shape_t sa, sb;
    if (!capsule_ok(cap) || !obstacle_ok(obs) || out == NULL) {
        return MCA_EINVAL;
    }
    memset(&sa, 0, sizeof sa);
    memset(&sb, 0, sizeof sb);
    sa.kind = SH_CAPSULE;
    mca_v3_set(sa.a, cap->a);
    mca_v3_set(sa.b, cap->b);
    sa.r = cap->radius;
    sb.kind = obs->type == MCA_OBST_BOX ? SH_BOX : SH_CYLINDER;
    sb.obs = obs;
    return shape_distance(&sa, &sb, cap->radius, out);
}

int mca_capsule_capsule_distance_ccd(const mca_capsule_t *c1, const mca_capsule_t *c2, mca_obst_dist_t *out) {
    shape_t sa, sb;
    if (!capsule_ok(c1) || !capsule_ok(c2) || out == NULL) {
        return MCA_EINVAL;
    }
    memset(&sa, 0, sizeof sa);
    memset(&sb, 0, sizeof sb);
    sa.kind = SH_CAPSULE;
    mca_v3_set(sa.a, c1->a);
    mca_v3_set(sa.b, c1->b);
    sa.r = c1->radius;
    sb.kind = SH_CAPSULE;
    mca_v3_set(sb.a, c2->a);
    mca_v3_set(sb.b, c2->b);
    sb.r = c2->radius;
    return shape_distance(&sa, &sb, c1->radius + c2->radius, out);
}

double mca_obstacle_point_distance(const mca_obstacle_t *obs, const double x[3], double closest[3]) {
    double rel[3], xl[3], cl[3];
    if (!obstacle_ok(obs) || !finite3(x) || closest == NULL) {
        return -1.0;
    }
    mca_v3_sub(rel, x, obs->pose.p);
    rot_t(xl, obs->pose.R, rel);
    if (obs->type == MCA_OBST_BOX) {
        for (int i = 0; i < 3; i++) {
            cl[i] = fmax(-obs->half[i], fmin(obs->half[i], xl[i]));
        }
    } else {
        double rr = sqrt(xl[0] * xl[0] + xl[1] * xl[1]);
        double f = rr > obs->radius ? obs->radius / rr : 1.0;
        cl[0] = xl[0] * f;
        cl[1] = xl[1] * f;
        cl[2] = fmax(-obs->half_height, fmin(obs->half_height, xl[2]));
    }
    local_to_world(closest, &obs->pose, cl);
    return mca_v3_dist(x, closest);
}

static void set_link_obstacle(mca_link_obstacle_t *lo, int link, int ob, const mca_obst_dist_t *r) {
    lo->link = link;
    lo->obstacle = ob;
    lo->d = r->d;
    mca_v3_set(lo->p, r->p);
    mca_v3_set(lo->q, r->q);
    mca_v3_set(lo->dir, r->dir);
    lo->penetrating = r->penetrating;
}

int mca_arm_obstacle_distances(const mca_chain_t *chain, const mca_kin_t *kin, const mca_obstacle_t *obs,
                               int n_obs, mca_arm_obstacles_t *out) {
    mca_capsule_t cap;
    mca_obst_dist_t r;
    int nl, it = 0;

    if (chain == NULL || kin == NULL || out == NULL || (obs == NULL && n_obs > 0) || n_obs < 0 ||
        chain->dof < 1 || chain->dof > MCA_MAX_DOF || kin->dof != chain->dof ||
        kin->n_points != chain->dof + 2) {
        return MCA_EINVAL;
    }
    if (n_obs > MCA_MAX_OBSTACLES) {
        return MCA_ERANGE;
    }
    nl = chain->dof + 1;
    /* validate everything first so an error leaves *out untouched */
    for (int k = 0; k < kin->n_points; k++) {
        if (!finite3(kin->point[k])) {
            return MCA_EINVAL;
        }
    }
    for (int k = 0; k < nl; k++) {
        if (!(chain->link_radius[k] >= 0.0 && chain->link_radius[k] <= MCA_SEGDIST_MAX_COORD)) {
            return MCA_EINVAL;
        }
    }
    for (int j = 0; j < n_obs; j++) {
        if (!obstacle_ok(&obs[j])) {
            return MCA_EINVAL;
        }
    }
    out->n_links = nl;
    memset(&out->min, 0, sizeof out->min);
    out->min.link = -1;
    out->min.obstacle = -1;
    out->min.d = INFINITY;
    for (int k = 0; k < nl; k++) {
        mca_link_obstacle_t *lo = &out->per_link[k];
        memset(lo, 0, sizeof *lo);
        lo->link = k;
        lo->obstacle = -1;
        lo->d = INFINITY;
        mca_v3_set(cap.a, kin->point[k]);
        mca_v3_set(cap.b, kin->point[k + 1]);
        cap.radius = chain->link_radius[k];
        for (int j = 0; j < n_obs; j++) {
            (void)mca_capsule_obstacle_distance(&cap, &obs[j], &r); /* OK or ENOTCONV (d still usable) */
            it += r.iterations;
            if (r.d < lo->d) {
                set_link_obstacle(lo, k, j, &r);
            }
        }
        if (lo->d < out->min.d) {
            out->min = *lo;
        }
    }
    out->iterations = it;
    return MCA_OK;
}
