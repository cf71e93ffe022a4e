/* SPDX-License-Identifier: MIT */
/* The fixed bodies' rows of the tick; see mca/bodyrows.h and docs/scheme.md, "Fixed bodies". */
#include "mca/bodyrows.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"
#include "mca/vec3.h"
#include "bodyrows__cache.h"
#include "scheme__rows.h"

const char *mca_body_kind_name(int kind) {
    static const char *const names[] = {
        [MCA_BODY_PLANE] = "plane", [MCA_BODY_SPHERE] = "sphere",     [MCA_BODY_CAPSULE] = "capsule",
        [MCA_BODY_BOX] = "box",     [MCA_BODY_CYLINDER] = "cylinder",
    };
    return kind >= 0 && kind < (int)(sizeof names / sizeof names[0]) ? names[kind] : "unknown";
}

int mca_body_check(const mca_fixed_body_t *b) {
    if (!b || !isfinite(b->clearance) || !(b->clearance >= 0.0) || !isfinite(b->v[0]) || !isfinite(b->v[1]) ||
        !isfinite(b->v[2]) || !isfinite(b->grow) || !(b->grow >= 0.0)) {
        return MCA_EINVAL;
    }
    /* the distance functions check every kind's geometry: one probe answers */
    const mca_capsule_t probe = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, 0.0};
    mca_body_dist_t r;
    return mca_capsule_body_distance(&probe, &b->body, &r) == MCA_OK ? MCA_OK : MCA_EINVAL;
}

void mca_body_band(const mca_scheme_params_t *p, double clearance, mca_scheme_params_t *pb) {
    *pb = *p;
    pb->d1 = clearance;
    pb->d2 = clearance + (p->d2 - p->d1);
}

/* The sphere around a capsule (centre c, radius returned). */
static double capsule_sphere(const mca_capsule_t *cap, double c[3]) {
    for (int i = 0; i < 3; i++) {
        c[i] = 0.5 * (cap->a[i] + cap->b[i]);
    }
    return 0.5 * mca_v3_dist(cap->a, cap->b) + cap->radius;
}

/* A sphere around a finite body (centre c, radius returned); -1 for the half-space. */
static double body_sphere(const mca_body_t *b, double c[3]) {
    switch (b->kind) {
    case MCA_BODY_SPHERE:
        mca_v3_set(c, b->u.sphere.centre);
        return b->u.sphere.radius;
    case MCA_BODY_CAPSULE:
        return capsule_sphere(&b->u.capsule, c);
    case MCA_BODY_BOX:
        mca_v3_set(c, b->u.box.centre);
        return mca_v3_norm(b->u.box.half);
    case MCA_BODY_CYLINDER:
        mca_v3_set(c, b->u.cylinder.centre);
        return sqrt(b->u.cylinder.half_len * b->u.cylinder.half_len +
                    b->u.cylinder.radius * b->u.cylinder.radius);
    default:
        return -1.0;
    }
}

/* A lower bound on the surface distance of link capsule cap to the body whose sphere is (c, R): the sphere's
 * distance to the capsule; -INFINITY for the half-space (always measured; it costs ~30 ns). */
static double lower_bound(const mca_capsule_t *cap, const double c[3], double R) {
    if (R < 0.0) {
        return -INFINITY;
    }
    double u[3], w[3];
    mca_v3_sub(u, cap->b, cap->a);
    mca_v3_sub(w, c, cap->a);
    const double uu = mca_v3_dot(u, u);
    const double t = uu > 0.0 ? fmax(0.0, fmin(1.0, mca_v3_dot(w, u) / uu)) : 0.0;
    mca_v3_axpy(w, w, -t, u); /* c - (a + t u) */
    return mca_v3_norm(w) - cap->radius - R;
}

static mca_capsule_t link_capsule(const mca_chain_t *ch, const mca_kin_t *kn, int l);

/* (x0, y0, z0) comes before (x1, y1, z1) in the loops' order: of pairs at the same least distance the
 * first in that order is the answer, as without a seed. */
static int precedes(int x0, int y0, int z0, int x1, int y1, int z1) {
    return x0 != x1 ? x0 < x1 : y0 != y1 ? y0 < y1 : z0 < z1;
}

/* A pair whose lower bound lb cannot beat the least so far (early: it comes before that pair, so it wins a
 * tie). NaN: not skipped. */
static int cannot_beat(double lb, double least, int early) {
    return early ? lb > least : lb >= least;
}

static void nearest_none(mca_body_nearest_t *out) {
    out->valid = 0;
    out->margin = out->d = INFINITY;
    out->arm = out->link = out->body = out->kind = -1;
}

/* Body k against link l of arm a into the least so far. */
static int nearest_try(const mca_fixed_body_t *fb, int k, int a, int l, const mca_capsule_t *cap, int early,
                       mca_body_nearest_t *out) {
    mca_body_dist_t r;
    if (mca_capsule_body_distance(cap, &fb->body, &r) != MCA_OK) {
        return MCA_EINVAL;
    }
    const double m = r.d - fb->clearance;
    if (m < out->margin || (early && m == out->margin)) {
        out->valid = 1;
        out->margin = m;
        out->d = r.d;
        out->arm = a;
        out->link = l;
        out->body = k;
        out->kind = (int)fb->body.kind;
        mca_v3_set(out->p, r.p_axis);
        mca_v3_set(out->q, r.q);
    }
    return MCA_OK;
}

/* Body k's link of least margin below out->margin (out unchanged when none is; on a tie the first link in the
 * order arm, link). The links are measured in the order of their bounding-sphere lower bound, so the least
 * usually comes first and the sphere test skips the rest. */
static int body_least(int n_arms, const mca_chain_t *const chain[], const mca_kin_t kin[],
                      const mca_fixed_body_t *bodies, int k, mca_body_nearest_t *out) {
    const mca_fixed_body_t *fb = &bodies[k];
    double c[3];
    const double R = body_sphere(&fb->body, c);
    double lb[MCA_MAX_ARMS * MCA_MAX_LINKS];
    int idx[MCA_MAX_ARMS * MCA_MAX_LINKS], n = 0;
    for (int a = 0; a < n_arms; a++) {
        for (int l = 0; l <= chain[a]->dof && l < MCA_MAX_LINKS; l++) {
            if (fb->allow[a] & (1u << l)) {
                continue;
            }
            const mca_capsule_t cap = link_capsule(chain[a], &kin[a], l);
            double b = lower_bound(&cap, c, R) - fb->clearance;
            b = isnan(b) ? -INFINITY : b; /* NaN: measured first, and the distance rejects it */
            int i = n++;
            for (; i > 0 && lb[i - 1] > b; i--) { /* insertion: ascending bound, stable */
                lb[i] = lb[i - 1];
                idx[i] = idx[i - 1];
            }
            lb[i] = b;
            idx[i] = a * MCA_MAX_LINKS + l;
        }
    }
    int best = -1; /* this body's link in out (a * MCA_MAX_LINKS + l), -1: none yet */
    for (int i = 0; i < n; i++) {
        const int a = idx[i] / MCA_MAX_LINKS, l = idx[i] % MCA_MAX_LINKS;
        const int tie_wins = best >= 0 && idx[i] < best;
        if (!(lb[i] < out->margin || (lb[i] == out->margin && tie_wins))) {
            continue; /* cannot be the least */
        }
        const mca_capsule_t cap = link_capsule(chain[a], &kin[a], l);
        if (nearest_try(fb, k, a, l, &cap, tie_wins, out) != MCA_OK) {
            return MCA_EINVAL;
        }
        if (out->valid && out->body == k && out->arm == a && out->link == l) {
            best = idx[i]; /* each link is tried once: out names it only if this try set it */
        }
    }
    return MCA_OK;
}

int mca_body_nearest(int n_arms, const mca_chain_t *const chain[], const mca_kin_t kin[],
                     const mca_fixed_body_t *bodies, int n_bodies, const mca_body_cache_t *cache,
                     mca_body_nearest_t *out) {
    if (!out || (n_bodies > 0 && (!chain || !kin || !bodies)) || n_arms < 0 || n_arms > MCA_MAX_ARMS) {
        return MCA_EINVAL;
    }
    n_bodies = n_bodies < MCA_MAX_BODIES ? n_bodies : MCA_MAX_BODIES;
    out->valid = 0;
    out->margin = out->d = INFINITY;
    out->arm = out->link = out->body = out->kind = -1;
    double lbs[MCA_MAX_BODIES][MCA_MAX_ARMS][MCA_MAX_LINKS]; /* the cache's bounds on the margins */
    int seed_k = -1, seed_a = -1, seed_l = -1;
    if (cache && n_bodies > 0) {
        /* the pair of least bound first: its margin then skips most others before their distance */
        int ok[MCA_MAX_BODIES];
        mca_body__cache_bodies(cache, bodies, n_bodies, ok);
        double best = INFINITY;
        for (int a = 0; a < n_arms; a++) {
            double move[MCA_MAX_LINKS];
            mca_body__cache_moves(cache, chain[a], &kin[a], a, move);
            for (int l = 0; l <= chain[a]->dof; l++) {
                for (int k = 0; k < n_bodies; k++) {
                    const double lb =
                        mca_body__cache_bound(cache, ok[k], a, l, k, move[l]) - bodies[k].clearance;
                    lbs[k][a][l] = lb;
                    if (!(bodies[k].allow[a] & (1u << l)) && lb < best) {
                        best = lb;
                        seed_k = k;
                        seed_a = a;
                        seed_l = l;
                    }
                }
            }
        }
        if (seed_k >= 0) {
            const mca_capsule_t cap = link_capsule(chain[seed_a], &kin[seed_a], seed_l);
            if (nearest_try(&bodies[seed_k], seed_k, seed_a, seed_l, &cap, 0, out) != MCA_OK) {
                return MCA_EINVAL;
            }
        }
    }
    for (int k = 0; k < n_bodies; k++) {
        const mca_fixed_body_t *fb = &bodies[k];
        double c[3];
        const double R = body_sphere(&fb->body, c);
        for (int a = 0; a < n_arms; a++) {
            for (int l = 0; l <= chain[a]->dof; l++) {
                if ((fb->allow[a] & (1u << l)) || (cache && lbs[k][a][l] > out->margin)) {
                    continue; /* allowed, or the cache's bound: cannot be the least */
                }
                if (k == seed_k && a == seed_a && l == seed_l) {
                    continue;
                }
                const int early = out->valid && precedes(k, a, l, out->body, out->arm, out->link);
                if (cache && cannot_beat(lbs[k][a][l], out->margin, early)) {
                    continue;
                }
                const mca_capsule_t cap = link_capsule(chain[a], &kin[a], l);
                const double lb = lower_bound(&cap, c, R) - fb->clearance;
                if (!(early ? lb <= out->margin : lb < out->margin)) {
                    continue; /* cannot be the least (NaN: measured, and the distance rejects it) */
                }
                if (nearest_try(fb, k, a, l, &cap, early, out) != MCA_OK) {
                    return MCA_EINVAL;
                }
            }
        }
    }
    return MCA_OK;
}

int mca_body_nearest_each(int n_arms, const mca_chain_t *const chain[], const mca_kin_t kin[],
                          const mca_fixed_body_t *bodies, int n_bodies, mca_body_nearest_t out[]) {
    if (!out || (n_bodies > 0 && (!chain || !kin || !bodies)) || n_arms < 0 || n_arms > MCA_MAX_ARMS ||
        n_bodies < 0 || n_bodies > MCA_MAX_BODIES) {
        return MCA_EINVAL;
    }
    for (int k = 0; k < n_bodies; k++) {
        nearest_none(&out[k]);
        if (body_least(n_arms, chain, kin, bodies, k, &out[k]) != MCA_OK) {
            return MCA_EINVAL;
        }
        out[k].body = k;
        out[k].kind = (int)bodies[k].body.kind;
    }
    return MCA_OK;
}

/* Insert a witness into a link's list (sorted by margin, at most MCA_BODY_PAIRS); a pair found twice (the
 * closest points at an end) is listed once. body -1: a self pair against the arm's link `link`. */
static void witness_insert(mca_body_witness_t list[MCA_BODY_PAIRS], int body, int link, double clearance,
                           const mca_body_dist_t *r) {
    const double m = r->d - clearance;
    if (list[MCA_BODY_PAIRS - 1].valid && !(m < list[MCA_BODY_PAIRS - 1].margin)) {
        return;
    }
    for (int i = 0; i < MCA_BODY_PAIRS && list[i].valid; i++) {
        if (list[i].body == body && list[i].link == link && mca_v3_dist(list[i].p, r->p_axis) < 1e-9 &&
            mca_v3_dist(list[i].q, r->q) < 1e-9) {
            return;
        }
    }
    int k = MCA_BODY_PAIRS;
    while (k > 0 && (!list[k - 1].valid || m < list[k - 1].margin)) {
        k--;
    }
    if (k >= MCA_BODY_PAIRS) {
        return;
    }
    memmove(&list[k + 1], &list[k], (size_t)(MCA_BODY_PAIRS - 1 - k) * sizeof list[0]);
    mca_body_witness_t *w = &list[k];
    w->valid = 1;
    w->body = body;
    w->link = link;
    w->d = r->d;
    w->margin = m;
    mca_v3_set(w->p, r->p_axis);
    mca_v3_set(w->q, r->q);
    mca_v3_set(w->n, r->n);
}

/* The larger of x and y; unlike fmax, a NaN is kept. */
static inline double max_or_nan(double x, double y) {
    return x < y ? y : (isnan(y) ? y : x);
}

/* The row bound of a witness at distance d (the band pb, stop time t_stop), the share of a fixed body or a
 * self pair (2: the whole budget) applied; p->big when no bound applies. */
static double body_bound(const mca_scheme_params_t *pb, double d, double t_stop) {
    const double b = mca_scheme_row_bound(pb, d, t_stop);
    return b < pb->big ? 2.0 * b : pb->big;
}

/* The fastest a body's surface approaches anything (0 for a fixed body). */
static double body_speed(const mca_fixed_body_t *fb) {
    return mca_v3_norm(fb->v) + fb->grow;
}

/* Link l's capsule. */
static mca_capsule_t link_capsule(const mca_chain_t *ch, const mca_kin_t *kn, int l) {
    return (mca_capsule_t){{kn->point[l][0], kn->point[l][1], kn->point[l][2]},
                           {kn->point[l + 1][0], kn->point[l + 1][1], kn->point[l + 1][2]},
                           ch->link_radius[l]};
}

/* One pair's witnesses into a link's list, those whose row can bind at the pair's approach speed `speed`
 * (band bp): the closest points, the link's two ends and, for a capsule body (a self pair's other link), the
 * body's own two ends against the link (two capsules' five witness functions). The pair is body `body`, or
 * the arm's link `link` (body -1). */
static int pair_witnesses(const mca_capsule_t *cap, const mca_body_t *body, int k, int link,
                          const mca_scheme_params_t *bp, double clearance, double t_stop, double speed,
                          mca_body_witness_t list[MCA_BODY_PAIRS]) {
    mca_body_dist_t r;
    if (mca_capsule_body_distance(cap, body, &r) != MCA_OK) {
        return MCA_EINVAL;
    }
    /* the ends are never nearer than the closest points: a pair whose closest points cannot bind has no end
     * that can (the bound grows with d) */
    if (body_bound(bp, r.d, t_stop) > speed) {
        return MCA_OK;
    }
    witness_insert(list, k, link, clearance, &r);
    const double *ends[2] = {cap->a, cap->b};
    for (int e = 0; e < 2; e++) {
        const mca_capsule_t pt = {
            {ends[e][0], ends[e][1], ends[e][2]}, {ends[e][0], ends[e][1], ends[e][2]}, cap->radius};
        if (mca_capsule_body_distance(&pt, body, &r) != MCA_OK) {
            return MCA_EINVAL;
        }
        if (!(body_bound(bp, r.d, t_stop) > speed)) {
            witness_insert(list, k, link, clearance, &r);
        }
    }
    if (body->kind == MCA_BODY_CAPSULE) {
        const mca_capsule_t *bc = &body->u.capsule;
        const double *bends[2] = {bc->a, bc->b};
        for (int e = 0; e < 2; e++) {
            const mca_body_sphere_t sp = {{bends[e][0], bends[e][1], bends[e][2]}, bc->radius};
            if (mca_capsule_sphere_distance(cap, &sp, &r) != MCA_OK) {
                return MCA_EINVAL;
            }
            if (!(body_bound(bp, r.d, t_stop) > speed)) {
                witness_insert(list, k, link, clearance, &r);
            }
        }
    }
    return MCA_OK;
}

/* Beyond this distance no row of a pair in band bp can bind: its S part ends at d2_b, its stop part
 * 2 (d - c') / (2 T) reaches the approach speed at c' + T speed (1 nm wider: rounding never drops a row that
 * binds). */
static double cut_distance(const mca_scheme_params_t *bp, double t_stop, double speed) {
    if (!isfinite(speed)) {
        return INFINITY;
    }
    return t_stop > 0.0 ? fmax(bp->d2, mca_scheme_rows_d1(bp) + t_stop * speed + 1e-9) : bp->d2;
}

/* Arm a's witness lists: per link, the pairs whose row can bind with the joint speeds inside the QP's box
 * (the link's fastest point moves at most `speed`: sum_j max|qdot_j| |p - o_j|, largest at an end; a self
 * pair (l, q) approaches at most at that sum over joints q .. l - 1 alone). self: the arm's self pairs (NULL:
 * none), in band ps.
 */
static int arm_lists(const mca_qp_t *qp, int vo, const mca_chain_t *ch, const mca_kin_t *kn, int a,
                     const mca_fixed_body_t *bodies, int n_bodies, const unsigned *self,
                     const mca_scheme_params_t *pb, const mca_scheme_params_t *ps, const double (*sc)[3],
                     const double *sr, double t_stop, const mca_body_cache_t *cache, const int *ok,
                     mca_body_witness_t lists[][MCA_BODY_PAIRS]) {
    const int dof = ch->dof;
    double qmax[MCA_MAX_DOF], lever[MCA_MAX_POINTS][MCA_MAX_DOF], speed[MCA_MAX_LINKS], move[MCA_MAX_LINKS];
    for (int j = 0; j < dof; j++) {
        qmax[j] = max_or_nan(fabs(qp->lb[vo + j]), fabs(qp->ub[vo + j]));
        for (int m = j + 1; m <= dof + 1; m++) {
            lever[m][j] = mca_v3_dist(kn->point[m], kn->point[j + 1]);
        }
    }
    for (int l = 0; l <= dof; l++) {
        speed[l] = 0.0; /* NaN anywhere: NaN, so every pair may bind */
        for (int j = 0; j < l; j++) {
            speed[l] += qmax[j] * max_or_nan(lever[l][j], lever[l + 1][j]);
        }
    }
    mca_body__cache_moves(cache, ch, kn, a, move);
    for (int l = 0; l <= dof; l++) {
        mca_body_witness_t *list = lists[l];
        for (int k = 0; k < MCA_BODY_PAIRS; k++) {
            list[k].valid = 0;
        }
        const mca_capsule_t cap = link_capsule(ch, kn, l);
        for (int k = 0; k < n_bodies; k++) {
            const mca_fixed_body_t *fb = &bodies[k];
            if (fb->allow[a] & (1u << l)) {
                continue;
            }
            /* a streamed body's own approach lowers its rows' bounds by at most this (mca/track.h) */
            const double vs = speed[l] + body_speed(fb), cut = cut_distance(&pb[k], t_stop, vs);
            if (mca_body__cache_bound(cache, ok[k], a, l, k, move[l]) > cut ||
                !(lower_bound(&cap, sc[k], sr[k]) <= cut)) {
                continue;
            }
            const int rc = pair_witnesses(&cap, &fb->body, k, -1, &pb[k], fb->clearance, t_stop, vs, list);
            if (rc != MCA_OK) {
                return rc;
            }
        }
        for (int q = 0; self && q < l; q++) {
            if (!(self[l] & (1u << q))) {
                continue;
            }
            /* the joints before link q move both links as one body (their rows' columns are 0: P - Q lies
             * along n); only joints q .. l - 1 close the pair */
            double v = 0.0;
            for (int j = q; j < l; j++) {
                v += qmax[j] * max_or_nan(lever[l][j], lever[l + 1][j]);
            }
            const double cut = cut_distance(ps, t_stop, v);
            if (mca_body__cache_self_bound(cache, a, l, q, move[l], move[q]) > cut) {
                continue;
            }
            const mca_capsule_t cq = link_capsule(ch, kn, q);
            double c[3];
            if (!(lower_bound(&cap, c, capsule_sphere(&cq, c)) <= cut)) {
                continue;
            }
            const mca_body_t other = {.kind = MCA_BODY_CAPSULE, .u.capsule = cq};
            const int rc = pair_witnesses(&cap, &other, -1, q, ps, ps->d1, t_stop, v, list);
            if (rc != MCA_OK) {
                return rc;
            }
        }
    }
    return MCA_OK;
}

/* Link q of arm a against its link l into the least self distance so far. */
static int self_try(const mca_chain_t *ch, const mca_kin_t *kn, int a, int l, int q, int early,
                    mca_self_nearest_t *out) {
    const mca_capsule_t cap = link_capsule(ch, kn, l);
    const mca_body_t other = {.kind = MCA_BODY_CAPSULE, .u.capsule = link_capsule(ch, kn, q)};
    double c[3];
    if (cannot_beat(lower_bound(&cap, c, capsule_sphere(&other.u.capsule, c)), out->d, early)) {
        return MCA_OK; /* cannot be the least (NaN: measured, and the distance rejects it) */
    }
    mca_body_dist_t r;
    if (mca_capsule_body_distance(&cap, &other, &r) != MCA_OK) {
        return MCA_EINVAL;
    }
    if (r.d < out->d || (early && r.d == out->d)) {
        out->valid = 1;
        out->d = r.d;
        out->arm = a;
        out->link = l;
        out->other = q;
        mca_v3_set(out->p, r.p_axis);
        mca_v3_set(out->q, r.q);
    }
    return MCA_OK;
}

int mca_self_nearest(int n_arms, const mca_chain_t *const chain[], const mca_kin_t kin[],
                     const mca_self_pairs_t *self, const mca_body_cache_t *cache, mca_self_nearest_t *out) {
    if (!out || (self && (!chain || !kin)) || n_arms < 0 || n_arms > MCA_MAX_ARMS) {
        return MCA_EINVAL;
    }
    out->valid = 0;
    out->d = INFINITY;
    out->arm = out->link = out->other = -1;
    double move[MCA_MAX_ARMS][MCA_MAX_LINKS];
    int seed_a = -1, seed_l = -1, seed_q = -1;
    if (self && cache) {
        /* the pair of least bound first: its distance then skips most others */
        double best = INFINITY;
        for (int a = 0; a < n_arms; a++) {
            mca_body__cache_moves(cache, chain[a], &kin[a], a, move[a]);
            for (int l = 0; l <= chain[a]->dof; l++) {
                for (int q = 0; q < l; q++) {
                    if (!(self[a][l] & (1u << q))) {
                        continue;
                    }
                    const double lb = mca_body__cache_self_bound(cache, a, l, q, move[a][l], move[a][q]);
                    if (lb < best) {
                        best = lb;
                        seed_a = a;
                        seed_l = l;
                        seed_q = q;
                    }
                }
            }
        }
        if (seed_a >= 0 && self_try(chain[seed_a], &kin[seed_a], seed_a, seed_l, seed_q, 0, out) != MCA_OK) {
            return MCA_EINVAL;
        }
    }
    for (int a = 0; self && a < n_arms; a++) {
        for (int l = 0; l <= chain[a]->dof; l++) {
            for (int q = 0; q < l; q++) {
                if (!(self[a][l] & (1u << q)) || (a == seed_a && l == seed_l && q == seed_q)) {
                    continue;
                }
                const double lb =
                    cache ? mca_body__cache_self_bound(cache, a, l, q, move[a][l], move[a][q]) : -INFINITY;
                if (lb > out->d) {
                    continue; /* the cache's bound: cannot be the least */
                }
                const int early = out->valid && precedes(a, l, q, out->arm, out->link, out->other);
                if (cannot_beat(lb, out->d, early)) {
                    continue;
                }
                if (self_try(chain[a], &kin[a], a, l, q, early, out) != MCA_OK) {
                    return MCA_EINVAL;
                }
            }
        }
    }
    return MCA_OK;
}

int mca_body_rows(mca_qp_t *qp, mca_scheme_info_t *si, int n_arms, const mca_chain_t *const chain[],
                  const mca_kin_t kin[], const mca_fixed_body_t *bodies, int n_bodies,
                  const mca_self_pairs_t *self, const mca_scheme_params_t *p, const double *dec,
                  const mca_body_cache_t *cache, mca_body_witness_t lists[][MCA_MAX_LINKS][MCA_BODY_PAIRS]) {
    if (!qp || !si || !p || n_arms < 1 || n_arms > MCA_MAX_ARMS || n_bodies < 0 ||
        n_bodies > MCA_MAX_BODIES) {
        return MCA_EINVAL;
    }
    if ((n_bodies == 0 && !self) || p->body_pairs <= 0) {
        return MCA_OK;
    }
    if (!chain || !kin || (n_bodies > 0 && !bodies) || p->body_pairs > MCA_BODY_PAIRS) {
        return MCA_EINVAL;
    }
    mca_scheme_params_t pb[MCA_MAX_BODIES], ps; /* each body's band; the self pairs' (clearance d1) */
    mca_body_band(p, p->d1, &ps);
    double sc[MCA_MAX_BODIES][3], sr[MCA_MAX_BODIES]; /* each body's bounding sphere */
    for (int k = 0; k < n_bodies; k++) {
        mca_body_band(p, bodies[k].clearance, &pb[k]);
        sr[k] = body_sphere(&bodies[k].body, sc[k]);
    }
    int ok[MCA_MAX_BODIES] = {0};
    mca_body__cache_bodies(cache, bodies, n_bodies, ok);
    const size_t row_bytes = sizeof(double) * (size_t)qp->n;
    for (int a = 0; a < n_arms; a++) {
        const mca_chain_t *ch = chain[a];
        const int dof = ch->dof, vo = si->var_off[a], b0 = si->body_off[a];
        if (b0 + p->body_pairs * (dof + 1) > qp->n_ineq) {
            return MCA_EINVAL; /* the QP keeps no slots for them */
        }
        const double t_stop = mca_scheme_stop_time(ch, dec ? dec[a] : 0.0);
        mca_body_witness_t own[MCA_MAX_LINKS][MCA_BODY_PAIRS];
        mca_body_witness_t(*ls)[MCA_BODY_PAIRS] = lists ? lists[a] : own;
        int rc = arm_lists(qp, vo, ch, &kin[a], a, bodies, n_bodies, self ? self[a] : NULL, pb, &ps,
                           (const double(*)[3])sc, sr, t_stop, cache, ok, ls);
        if (rc != MCA_OK) {
            return rc;
        }
        int kept[MCA_BODY_PAIRS * MCA_MAX_LINKS], n_kept = 0;
        double kept_norm[MCA_BODY_PAIRS * MCA_MAX_LINKS];
        for (int l = 0; l <= dof; l++) {
            for (int k = 0; k < p->body_pairs && ls[l][k].valid; k++) {
                const mca_body_witness_t *w = &ls[l][k];
                const mca_scheme_params_t *bp = w->body >= 0 ? &pb[w->body] : &ps;
                const int r = b0 + p->body_pairs * l + k;
                if (w->d < bp->d2) {
                    si->brake = fmin(si->brake, mca_brake_s(w->d, mca_scheme_rows_d1(bp), bp->d2));
                }
                double bound = body_bound(bp, w->d, t_stop);
                if (!(bound < p->big)) {
                    continue;
                }
                if (w->link < 0) {
                    /* a streamed body's approach along n (its velocity, or a stale track's growth) is taken
                     * off the link's share: the row keeps the relative approach within the bound */
                    const mca_fixed_body_t *fb = &bodies[w->body];
                    bound -= mca_v3_dot(w->n, fb->v) + fb->grow;
                }
                double Jp[3][MCA_MAX_DOF], Jq[3][MCA_MAX_DOF];
                rc = mca_jacobian_point(&kin[a], l, w->p, Jp);
                if (rc == MCA_OK && w->link >= 0) {
                    /* a self pair: the other witness moves with the arm too, J_P - J_Q */
                    rc = mca_jacobian_point(&kin[a], w->link, w->q, Jq);
                    for (int i = 0; i < 3 && rc == MCA_OK; i++) {
                        for (int j = 0; j < dof; j++) {
                            Jp[i][j] -= Jq[i][j];
                        }
                    }
                }
                if (rc != MCA_OK) {
                    return rc;
                }
                double reach =
                    0.0; /* the fastest approach the joint limits allow: a row above it never binds */
                memset(qp->U[r], 0, row_bytes);
                for (int j = 0; j < dof; j++) {
                    /* the approach speed towards the body (the other link): along -n */
                    const double u = -(w->n[0] * Jp[0][j] + w->n[1] * Jp[1][j] + w->n[2] * Jp[2][j]);
                    qp->U[r][vo + j] = u;
                    reach += fabs(u) * ch->joint[j].vel_limit;
                }
                if (bound >= reach) {
                    memset(qp->U[r], 0, row_bytes); /* inactive rows stay zero (the paper's layout) */
                    continue;
                }
                qp->beta[r] = bound;
                if (mca__scheme_merge_parallel(qp, vo, dof, r, kept, kept_norm, n_kept)) {
                    qp->beta[r] = p->big;
                    memset(qp->U[r], 0, row_bytes);
                    continue;
                }
                kept[n_kept++] = r;
                si->active_rows++;
            }
        }
    }
    return MCA_OK;
}
