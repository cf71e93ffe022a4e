/* SPDX-License-Identifier: MIT */
/* Arm-to-arm link distances (paper Fig. 4(d)): every link pair once, kept per link of each arm. */
#include <math.h>
#include <stddef.h>

#include "mca/armdist.h"
#include "mca/err.h"
#include "mca/segdist.h"
#include "mca/vec3.h"

static int kin_ok(const mca_chain_t *chain, const mca_kin_t *kin) {
    return chain != NULL && kin != NULL && chain->dof >= 1 && chain->dof <= MCA_MAX_DOF &&
           kin->dof == chain->dof && kin->n_points == chain->dof + 2;
}

static int points_ok(const mca_kin_t *kin) {
    for (int i = 0; i < kin->n_points; i++) {
        for (int k = 0; k < 3; k++) {
            if (!(fabs(kin->point[i][k]) <= MCA_SEGDIST_MAX_COORD)) {
                return 0;
            }
        }
    }
    return 1;
}

static void set_pair(mca_link_pair_t *lp, int link, int other, double d, double d_axis, const double p[3],
                     const double e[3]) {
    lp->link = link;
    lp->other_link = other;
    lp->d = d;
    lp->d_axis = d_axis;
    mca_v3_set(lp->p, p);
    mca_v3_set(lp->e, e);
}

int mca_arm_distances(const mca_chain_t *chain_a, const mca_kin_t *kin_a, const mca_chain_t *chain_b,
                      const mca_kin_t *kin_b, mca_dist_method_t method, mca_arm_distances_t *out) {
    const mca_lsdm_params_t params = {MCA_LSDM_DEFAULT_TOL, MCA_LSDM_DEFAULT_MAX_ITER};
    mca_segdist_t sd;
    int na, nb, i, j, rc, iters = 0;
    double ds;

    if (!kin_ok(chain_a, kin_a) || !kin_ok(chain_b, kin_b) || out == NULL ||
        (method != MCA_DIST_CLOSED && method != MCA_DIST_LSDM)) {
        return MCA_EINVAL;
    }
    na = kin_a->dof + 1;
    nb = kin_b->dof + 1;
    /* Validate every point first (the segdist range) so an error leaves *out untouched. */
    if (!points_ok(kin_a) || !points_ok(kin_b)) {
        return MCA_EINVAL;
    }
    out->n_links_a = na;
    out->n_links_b = nb;
    for (i = 0; i < na; i++) {
        out->a_to_b[i].d = INFINITY;
    }
    for (j = 0; j < nb; j++) {
        out->b_to_a[j].d = INFINITY;
    }
    out->min.d = INFINITY;
    for (i = 0; i < na; i++) {
        for (j = 0; j < nb; j++) {
            if (method == MCA_DIST_LSDM) {
                /* ENOTCONV still leaves the best pair found; the cap bounds the time. */
                rc = mca_segdist_lsdm(kin_a->point[i], kin_a->point[i + 1], kin_b->point[j],
                                      kin_b->point[j + 1], &params, &sd);
                iters += sd.iterations;
            } else {
                rc = mca_segdist_closed(kin_a->point[i], kin_a->point[i + 1], kin_b->point[j],
                                        kin_b->point[j + 1], &sd);
            }
            if (rc != MCA_OK && rc != MCA_ENOTCONV) {
                return rc; /* unreachable: inputs validated above */
            }
            ds = sd.d - chain_a->link_radius[i] - chain_b->link_radius[j];
            set_pair(&out->pair[i][j], i, j, ds, sd.d, sd.p, sd.e);
            if (ds < out->a_to_b[i].d) {
                set_pair(&out->a_to_b[i], i, j, ds, sd.d, sd.p, sd.e);
            }
            if (ds < out->b_to_a[j].d) {
                set_pair(&out->b_to_a[j], j, i, ds, sd.d, sd.e, sd.p);
            }
            if (ds < out->min.d) {
                set_pair(&out->min, i, j, ds, sd.d, sd.p, sd.e);
            }
        }
    }
    out->iterations = iters;
    return MCA_OK;
}

static void mid(double out[3], const double a[3], const double b[3]) {
    for (int i = 0; i < 3; i++) {
        out[i] = 0.5 * (a[i] + b[i]);
    }
}

double mca_arm_least_distance(const mca_chain_t *A, const double pa[][3], const mca_chain_t *B,
                              const double pb[][3], double cap) {
    double best = cap;
    for (int i = 0; i <= A->dof; i++) {
        const double ra = A->link_radius[i];
        double ca[3];
        mid(ca, pa[i], pa[i + 1]);
        const double ba = 0.5 * mca_v3_dist(pa[i], pa[i + 1]) + ra;
        for (int j = i == 0; j <= B->dof; j++) {
            const double rb = B->link_radius[j];
            double cb[3];
            mid(cb, pb[j], pb[j + 1]);
            const double bb = 0.5 * mca_v3_dist(pb[j], pb[j + 1]) + rb;
            if (mca_v3_dist(ca, cb) - ba - bb >= best) {
                continue; /* the links' bounding spheres are farther than the best pair */
            }
            mca_segdist_t s;
            if (mca_segdist_closed(pa[i], pa[i + 1], pb[j], pb[j + 1], &s) == MCA_OK) {
                best = fmin(best, s.d - ra - rb);
            }
        }
    }
    return best;
}
