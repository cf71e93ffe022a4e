/* SPDX-License-Identifier: MIT */
/* LVI-PDNN solver (paper (29)-(32)): input checks, row scaling, warm start, step-size rule.
 * The Euler loop itself is in pdnn_eigen.cpp. Real-time safe: no allocation, no I/O. */
#include "mca/pdnn.h"

#include <math.h>
#include <string.h>

#include "mca/err.h"
#include "pdnn__eigen.h"

#define PDNN_DEFAULT_GAMMA 1.9
#define PDNN_DEFAULT_FAR_WEIGHT 0.3
#define PDNN_FAR_SLACK 0.02 /* rows are unit-norm: slack in phi units, relative to 1 + ||phi|| */
#define PDNN_DEFAULT_POLISH_MAX 48

void mca_pdnn_default_params(mca_pdnn_params_t *params) {
    if (params == NULL) {
        return;
    }
    memset(params, 0, sizeof(*params));
    params->kappa = 0.0;
    params->tol = 1e-9;
    params->max_steps = 20000;
    params->big = 1e10;
    params->step_rule = MCA_PDNN_STEP_ADAPTIVE;
    params->gamma = PDNN_DEFAULT_GAMMA;
    params->precond = MCA_PDNN_PRECOND_ORTH;
    params->far_weight = PDNN_DEFAULT_FAR_WEIGHT;
}

void mca_pdnn_init(mca_pdnn_t *s) {
    if (s != NULL) {
        memset(s, 0, sizeof(*s));
    }
}

void mca_pdnn_remap_ineq(mca_pdnn_t *s, int n_ineq, const int *old_of_new) {
    if (!s || s->h <= 0 || n_ineq < 0 || n_ineq > MCA_QP_MAX_INEQ || !old_of_new) {
        return;
    }
    const int base = s->n + s->n_eq;
    double *t = s->ws_t;
    for (int i = 0; i < n_ineq; i++) {
        const int k = old_of_new[i];
        t[i] = k >= 0 && k < s->n_ineq ? s->y[base + k] : 0.0;
    }
    memcpy(&s->y[base], t, sizeof(double) * (size_t)n_ineq);
    s->n_ineq = n_ineq;
    s->h = base + n_ineq;
}

static int all_finite(const double *v, int len) {
    for (int i = 0; i < len; i++) {
        if (!isfinite(v[i])) {
            return 0;
        }
    }
    return 1;
}

/* Finite, and whether all zero (an inactive row). Most rows of a QP with many witness pairs are inactive
 * (memset to +0.0): memcmp against a zero row finds them at memory speed; any other row is checked element
 * by element (there -0.0 also counts as zero). */
static const double zero_row[MCA_QP_MAX_VARS];

static int scan_row(const double *v, int len, unsigned char *zero) {
    if (memcmp(v, zero_row, sizeof(double) * (size_t)len) == 0) {
        *zero = 1;
        return 1;
    }
    int nz = 0;
    for (int i = 0; i < len; i++) {
        if (!isfinite(v[i])) {
            return 0;
        }
        nz |= v[i] != 0.0;
    }
    *zero = (unsigned char)!nz;
    return 1;
}

/* Also marks the all-zero rows in zero[] (equality rows first, as in N). */
static int check_qp(const mca_qp_t *qp, unsigned char *zero) {
    if (qp->n < 1 || qp->n > MCA_QP_MAX_VARS || qp->n_eq < 0 || qp->n_eq > MCA_QP_MAX_EQ || qp->n_ineq < 0 ||
        qp->n_ineq > MCA_QP_MAX_INEQ) {
        return MCA_EINVAL;
    }
    for (int i = 0; i < qp->n_eq; i++) {
        if (!scan_row(qp->G[i], qp->n, &zero[i])) {
            return MCA_EINVAL;
        }
    }
    for (int i = 0; i < qp->n_ineq; i++) {
        if (!scan_row(qp->U[i], qp->n, &zero[qp->n_eq + i])) {
            return MCA_EINVAL;
        }
    }
    if (!all_finite(qp->alpha, qp->n_eq) || !all_finite(qp->beta, qp->n_ineq)) {
        return MCA_EINVAL;
    }
    for (int i = 0; i < qp->n; i++) {
        const double lb = qp->lb[i], ub = qp->ub[i];
        /* NaN fails every comparison below; an empty box is bad data, not an iteration problem. */
        if (!(lb <= ub) || lb == INFINITY || ub == -INFINITY) {
            return MCA_EINVAL;
        }
    }
    return MCA_OK;
}

static int check_params(const mca_pdnn_params_t *p) {
    if (!isfinite(p->kappa) || !(p->tol > 0.0) || !isfinite(p->tol) || p->max_steps < 0 || !(p->big > 0.0) ||
        !isfinite(p->big) || !(p->gamma < 2.0) ||
        (p->step_rule != MCA_PDNN_STEP_ADAPTIVE && p->step_rule != MCA_PDNN_STEP_BOUND) ||
        p->precond < MCA_PDNN_PRECOND_ORTH || p->precond > MCA_PDNN_PRECOND_NONE || !(p->far_weight <= 1.0)) {
        return MCA_EINVAL;
    }
    return MCA_OK;
}

static double clampd(double x, double lo, double hi) {
    return x < lo ? lo : (x > hi ? hi : x);
}

/* The constraint rows in the iteration's form: row i of N x + q >= 0 (inequality) or = 0 (equality),
 * N = [G; -U], q = [-alpha; beta]. */
static const double *orig_row(const mca_qp_t *qp, int i, double *sign, double *qi) {
    if (i < qp->n_eq) {
        *sign = 1.0;
        *qi = -qp->alpha[i];
        return qp->G[i];
    }
    *sign = -1.0;
    *qi = qp->beta[i - qp->n_eq];
    return qp->U[i - qp->n_eq];
}

static double dot(const double *a, const double *b, int n) {
    double s = 0.0;
    for (int j = 0; j < n; j++) {
        s += a[j] * b[j];
    }
    return s;
}

/* Modified Gram-Schmidt (two passes) on the equality rows of ws_N: G = R^T Q, alpha' = R^-T alpha.
 * Returns 0 when G is numerically rank deficient (then ws_N/ws_q are left for a rebuild). */
static int orth_equalities(mca_pdnn_t *s, int n, int ne) {
    double *R = s->ws_R;
    memset(R, 0, sizeof(double) * (size_t)(ne * ne));
    for (int i = 0; i < ne; i++) {
        double *gi = &s->ws_N[i * n];
        const double norm0 = sqrt(dot(gi, gi, n));
        for (int pass = 0; pass < 2; pass++) {
            for (int k = 0; k < i; k++) {
                const double *qk = &s->ws_N[k * n];
                const double c = dot(qk, gi, n);
                for (int j = 0; j < n; j++) {
                    gi[j] -= c * qk[j];
                }
                s->ws_q[i] -= c * s->ws_q[k];
                R[k * ne + i] += c;
            }
        }
        const double rii = sqrt(dot(gi, gi, n));
        if (!(rii > 1e-7 * norm0) || !(norm0 > 0.0)) {
            return 0;
        }
        for (int j = 0; j < n; j++) {
            gi[j] /= rii;
        }
        s->ws_q[i] /= rii;
        R[i * ne + i] = rii;
    }
    return 1;
}

/* Build N, q and Omega in the workspace for the chosen rewriting (enum mca_pdnn_precond). Each rewriting
 * keeps the feasible set, hence phi: row scaling trivially; R^-T G phi = R^-T alpha iff G phi = alpha;
 * adding multiples of equality rows to an inequality row changes nothing where G phi = alpha. */
static int setup(mca_pdnn_t *s, const mca_qp_t *qp, const mca_pdnn_params_t *prm, int warm) {
    const int n = qp->n, ne = qp->n_eq, m = qp->n_eq + qp->n_ineq;
    int pre = prm->precond;
    for (int i = 0; i < m; i++) {
        double sign, qi;
        const double *row = orig_row(qp, i, &sign, &qi);
        /* a zero inequality row's N is never read (ws_zero); equality rows feed orth_equalities */
        for (int j = 0; j < n && (i < ne || !s->ws_zero[i]); j++) {
            s->ws_N[i * n + j] = sign * row[j];
        }
        s->ws_q[i] = qi;
        s->ws_d[i] = 1.0;
        s->ws_lo[n + i] = i < ne ? -prm->big : 0.0;
        s->ws_hi[n + i] = prm->big;
    }
    if (pre == MCA_PDNN_PRECOND_ORTH && ne > 0 && !orth_equalities(s, n, ne)) {
        pre = MCA_PDNN_PRECOND_SCALE;
        for (int i = 0; i < ne; i++) { /* undo the partial orthogonalisation */
            for (int j = 0; j < n; j++) {
                s->ws_N[i * n + j] = qp->G[i][j];
            }
            s->ws_q[i] = -qp->alpha[i];
        }
    }
    for (int i = (pre == MCA_PDNN_PRECOND_ORTH ? ne : 0); i < m; i++) {
        if (s->ws_zero[i]) {
            continue; /* an inactive collision row: every step below would leave it as it is */
        }
        double *Ni = &s->ws_N[i * n];
        const double norm0 = sqrt(dot(Ni, Ni, n));
        if (pre == MCA_PDNN_PRECOND_ORTH) {
            for (int k = 0; k < ne; k++) {
                const double *qk = &s->ws_N[k * n];
                const double c = dot(qk, Ni, n);
                for (int j = 0; j < n; j++) {
                    Ni[j] -= c * qk[j];
                }
                s->ws_q[i] -= c * s->ws_q[k];
            }
        }
        if (pre == MCA_PDNN_PRECOND_NONE) {
            continue;
        }
        const double nrm = sqrt(dot(Ni, Ni, n));
        if (nrm > 1e-9 * norm0 && nrm > 0.0) {
            s->ws_d[i] = 1.0 / nrm;
            for (int j = 0; j < n; j++) {
                Ni[j] *= s->ws_d[i];
            }
            s->ws_q[i] *= s->ws_d[i];
        } else if (pre == MCA_PDNN_PRECOND_ORTH) {
            /* the row lies in the span of G: on G phi = alpha it is the constant test q_i >= 0 */
            for (int j = 0; j < n; j++) {
                Ni[j] = 0.0;
            }
        }
    }
    for (int j = 0; j < n; j++) {
        s->ws_lo[j] = clampd(qp->lb[j], -prm->big, prm->big);
        s->ws_hi[j] = clampd(qp->ub[j], -prm->big, prm->big);
    }
    /* Far rows: with a full warm start, an inequality row that was inactive (v_i = 0) with a clear slack at
     * the previous answer will most likely stay inactive. Its coupling in (I + M^T) still inflates
     * ||I + M|| and so shrinks every step; scaling the row down (a positive row scale, so phi is unchanged)
     * removes most of that. A wrong guess costs speed, never correctness: the row still acts. */
    const double w = prm->far_weight > 0.0 ? prm->far_weight : PDNN_DEFAULT_FAR_WEIGHT;
    if (warm == 2 && pre != MCA_PDNN_PRECOND_NONE && w < 1.0) {
        const double *x = s->y;
        const double tau = PDNN_FAR_SLACK * (1.0 + sqrt(dot(x, x, n)));
        for (int i = ne; i < m; i++) {
            double *Ni = &s->ws_N[i * n];
            if (s->y[n + i] < 1e-6 && (s->ws_zero[i] ? 0.0 : dot(Ni, x, n)) + s->ws_q[i] > tau) {
                /* v_i ~ 0 within the tolerance */
                for (int j = 0; j < n && !s->ws_zero[i]; j++) {
                    Ni[j] *= w;
                }
                s->ws_q[i] *= w;
                s->ws_d[i] *= w;
            }
        }
    }
    return pre;
}

/* out[j] = sum_i (-U)_ij v_i: the inequality rows' share of the stationarity point. */
static void ineq_sum(const mca_qp_t *qp, const double *vi, double *out) {
    for (int j = 0; j < qp->n; j++) {
        out[j] = 0.0;
    }
    for (int i = 0; i < qp->n_ineq; i++) {
        if (vi[i] != 0.0) {
            for (int j = 0; j < qp->n; j++) {
                out[j] -= qp->U[i][j] * vi[i];
            }
        }
    }
}

/* Duals of the QP as given (yt) -> duals of the rewritten rows (yw). Inequalities: v_i = d_i w_i.
 * Equalities (ORTH): G^T v_e + N0_I^T v_i = Q^T w_e + N'_I^T w_i and Q N'_I^T = 0, so w_e = R v_e +
 * Q N0_I^T v_i; otherwise v_e = d_e w_e. */
static void duals_to_iter(mca_pdnn_t *s, const mca_qp_t *qp, int pre, const double *yt, double *yw) {
    const int n = qp->n, ne = qp->n_eq, m = ne + qp->n_ineq;
    for (int i = 0; i < n; i++) {
        yw[i] = yt[i];
    }
    for (int i = ne; i < m; i++) {
        yw[n + i] = yt[n + i] / s->ws_d[i];
    }
    if (pre != MCA_PDNN_PRECOND_ORTH) {
        for (int i = 0; i < ne; i++) {
            yw[n + i] = yt[n + i] / s->ws_d[i];
        }
        return;
    }
    double a[MCA_QP_MAX_VARS];
    ineq_sum(qp, yt + n + ne, a);
    for (int i = 0; i < ne; i++) {
        double r = dot(&s->ws_N[i * n], a, n);
        for (int k = i; k < ne; k++) {
            r += s->ws_R[i * ne + k] * yt[n + k];
        }
        yw[n + i] = r;
    }
}

static void duals_from_iter(mca_pdnn_t *s, const mca_qp_t *qp, int pre, const double *yw, double *yt) {
    const int n = qp->n, ne = qp->n_eq, m = ne + qp->n_ineq;
    for (int i = 0; i < n; i++) {
        yt[i] = yw[i];
    }
    for (int i = ne; i < m; i++) {
        yt[n + i] = yw[n + i] * s->ws_d[i];
    }
    if (pre != MCA_PDNN_PRECOND_ORTH) {
        for (int i = 0; i < ne; i++) {
            yt[n + i] = yw[n + i] * s->ws_d[i];
        }
        return;
    }
    double a[MCA_QP_MAX_VARS];
    ineq_sum(qp, yt + n + ne, a);
    for (int i = ne - 1; i >= 0; i--) { /* R v_e = w_e - Q N0_I^T v_i, R upper triangular */
        double r = yw[n + i] - dot(&s->ws_N[i * n], a, n);
        for (int k = i + 1; k < ne; k++) {
            r -= s->ws_R[i * ne + k] * yt[n + k];
        }
        yt[n + i] = r / s->ws_R[i * ne + i];
    }
}

/* ||P_Omega(y - (M y + q)) - y||_inf for the QP as given (the reported residual and the stop test). */
static double true_residual(const mca_qp_t *qp, const mca_pdnn_t *s, double big, const double *y) {
    const int n = qp->n, ne = qp->n_eq;
    double a[MCA_QP_MAX_VARS], r = 0.0;
    ineq_sum(qp, y + n + ne, a);
    for (int i = 0; i < ne; i++) {
        for (int j = 0; j < n; j++) {
            a[j] += qp->G[i][j] * y[n + i];
        }
    }
    for (int j = 0; j < n; j++) {
        r = fmax(r, fabs(clampd(a[j], s->ws_lo[j], s->ws_hi[j]) - y[j]));
    }
    for (int i = 0; i < ne + qp->n_ineq; i++) {
        double sign, qi;
        const double *row = orig_row(qp, i, &sign, &qi);
        const double b = (s->ws_zero[i] ? 0.0 : sign * dot(row, y, n)) + qi, v = y[n + i];
        r = fmax(r, fabs(clampd(v - b, i < ne ? -big : 0.0, big) - v));
    }
    return r;
}

static int uf_find(int *par, int j) {
    while (par[j] != j) {
        par[j] = par[par[j]];
        j = par[j];
    }
    return j;
}

/* Independent blocks. Variables joined by a row of N belong together (union-find). The objective is
 * separable, so the QP is one independent sub-QP per block, and (32) with M = [I -N^T; N 0] splits into
 * one sub-network per block (M is block diagonal after permuting): integrating them separately, each
 * with its own step, is still explicit Euler on (32) with a time scale lambda per block. Each block's
 * N_b is stored compactly, which also skips the zero blocks of the paper's blkdiag(J_L, J_R). Rows of
 * N that are all zero belong to no block (their dual has a closed form). */
static void split(mca_pdnn_t *s, int n, int m, int ne, const double *eqf, int no_split) {
    int par[MCA_QP_MAX_VARS], blk_of[MCA_QP_MAX_VARS], row_blk[MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ];
    for (int j = 0; j < n; j++) {
        par[j] = no_split ? 0 : j;
        blk_of[j] = -1;
    }
    for (int i = 0; i < m; i++) {
        const double *Ni = &s->ws_N[i * n];
        int first = -1;
        for (int j = 0; j < n && !s->ws_zero[i]; j++) {
            if (Ni[j] != 0.0) {
                const int r = uf_find(par, j);
                if (first < 0) {
                    first = r;
                } else if (r != first) {
                    par[r] = first;
                }
            }
        }
        row_blk[i] = first; /* a root for now, -1 for a zero row */
    }
    int nb = 0;
    for (int j = 0; j < n; j++) {
        const int r = uf_find(par, j);
        if (blk_of[r] < 0) {
            blk_of[r] = nb++;
        }
    }
    s->ws_nblk = nb;
    for (int b = 0; b < nb; b++) {
        for (int k = 0; k < 5; k++) {
            s->ws_blk[b][k] = 0;
        }
    }
    for (int j = 0; j < n; j++) {
        s->ws_blk[blk_of[uf_find(par, j)]][1]++;
    }
    int nzero = 0;
    for (int i = 0; i < m; i++) {
        if (row_blk[i] >= 0) {
            row_blk[i] = blk_of[uf_find(par, row_blk[i])];
            s->ws_blk[row_blk[i]][3]++;
        } else {
            nzero++;
        }
    }
    s->ws_nzero = nzero;
    int c0 = 0, r0 = 0, off = 0;
    for (int b = 0; b < nb; b++) {
        s->ws_blk[b][0] = c0;
        s->ws_blk[b][2] = r0;
        s->ws_blk[b][4] = off;
        c0 += s->ws_blk[b][1];
        r0 += s->ws_blk[b][3];
        off += s->ws_blk[b][1] * s->ws_blk[b][3];
    }
    /* permutations: block order, original order inside a block; zero rows last */
    int fill_c[MCA_QP_MAX_VARS], fill_r[MCA_QP_MAX_VARS];
    for (int b = 0; b < nb; b++) {
        fill_c[b] = s->ws_blk[b][0];
        fill_r[b] = s->ws_blk[b][2];
    }
    for (int j = 0; j < n; j++) {
        s->ws_pv[fill_c[blk_of[uf_find(par, j)]]++] = j;
    }
    int z = m - nzero;
    for (int i = 0; i < m; i++) {
        s->ws_pr[row_blk[i] >= 0 ? fill_r[row_blk[i]]++ : z++] = i;
    }
    /* compact N_b, q_b and Omega_b */
    for (int b = 0; b < nb; b++) {
        const int bc0 = s->ws_blk[b][0], nc = s->ws_blk[b][1], br0 = s->ws_blk[b][2], nr = s->ws_blk[b][3];
        double *B = &s->ws_B[s->ws_blk[b][4]];
        const int seg = bc0 + br0; /* start of block b in the [x_b; w_b] layout */
        for (int k = 0; k < nc; k++) {
            s->ws_Blo[seg + k] = s->ws_lo[s->ws_pv[bc0 + k]];
            s->ws_Bhi[seg + k] = s->ws_hi[s->ws_pv[bc0 + k]];
        }
        for (int r = 0; r < nr; r++) {
            const int i = s->ws_pr[br0 + r];
            for (int k = 0; k < nc; k++) {
                B[r * nc + k] = s->ws_N[i * n + s->ws_pv[bc0 + k]];
            }
            s->ws_Bq[br0 + r] = s->ws_q[i];
            s->ws_Bf[br0 + r] = i < ne ? 1.0 / eqf[i] : s->ws_d[i];
            s->ws_Bfi[br0 + r] = 1.0 / s->ws_Bf[br0 + r];
            s->ws_Blo[seg + nc + r] = s->ws_lo[n + i];
            s->ws_Bhi[seg + nc + r] = s->ws_hi[n + i];
        }
    }
}

/* ws_y (original order) <-> ws_By (block layout) */
static void gather(mca_pdnn_t *s, int n, int to_blocks) {
    for (int b = 0; b < s->ws_nblk; b++) {
        const int bc0 = s->ws_blk[b][0], nc = s->ws_blk[b][1], br0 = s->ws_blk[b][2], nr = s->ws_blk[b][3];
        double *yb = &s->ws_By[bc0 + br0];
        for (int k = 0; k < nc; k++) {
            double *y = &s->ws_y[s->ws_pv[bc0 + k]];
            if (to_blocks) {
                yb[k] = *y;
            } else {
                *y = yb[k];
            }
        }
        for (int r = 0; r < nr; r++) {
            double *y = &s->ws_y[n + s->ws_pr[br0 + r]];
            if (to_blocks) {
                yb[nc + r] = *y;
            } else {
                *y = yb[nc + r];
            }
        }
    }
}

/* Block b of the split problem as the Eigen side takes it: its slices of ws_B, ws_Bq, Omega and the row
 * factors (filled by split()). */
static mca_pdnn__problem_t block_problem(mca_pdnn_t *s, int b, int64_t deadline_ns) {
    const int *bl = s->ws_blk[b];
    const mca_pdnn__problem_t p = {bl[1],
                                   bl[3],
                                   &s->ws_B[bl[4]],
                                   &s->ws_Bq[bl[2]],
                                   &s->ws_Blo[bl[0] + bl[2]],
                                   &s->ws_Bhi[bl[0] + bl[2]],
                                   &s->ws_Bf[bl[2]],
                                   &s->ws_Bfi[bl[2]],
                                   deadline_ns,
                                   &s->ws_Bside[bl[0]]};
    return p;
}

typedef struct pdnn_run {
    double r_true, kappa;
    int steps, total, diverged, timed_out;
    int polished, tries;
} pdnn_run_t;

/* Integrate every block from ws_By until the QP as given meets tol (checked on the mapped-back y, the
 * inner tolerance tightened if the rewriting's factors fooled the inner test), the cap, or no progress.
 * Leaves ws_y (iterate, original order) and ws_t (the QP's y) filled. */
static void run_passes(mca_pdnn_t *s, const mca_qp_t *qp, int pre, const mca_pdnn_params_t *prm,
                       const double *kfix, int cap, pdnn_run_t *run) {
    const int n = qp->n;
    double tol_it = prm->tol, r_prev = INFINITY;
    int bsteps[MCA_QP_MAX_VARS] = {0}, btries[MCA_QP_MAX_VARS] = {0};
    unsigned char bpol[MCA_QP_MAX_VARS] = {0};
    const int pmax = prm->no_polish ? 0 : prm->polish_max > 0 ? prm->polish_max : PDNN_DEFAULT_POLISH_MAX;
    run->r_true = INFINITY;
    for (int pass = 0; pass < 8; pass++) {
        for (int b = 0; b < s->ws_nblk; b++) {
            const int *bl = s->ws_blk[b];
            const mca_pdnn__problem_t p = block_problem(s, b, prm->deadline_ns);
            mca_pdnn_result_t it = {0};
            mca_pdnn__iterate(&p, &s->ws_By[bl[0] + bl[2]], kfix[b], prm->gamma, tol_it, cap - bsteps[b],
                              !prm->no_rescue, pmax - btries[b], &it);
            bsteps[b] += it.steps;
            btries[b] += it.polish_tries;
            run->tries += it.polish_tries;
            /* a block stays polished while later passes leave it where the polish put it */
            bpol[b] = (unsigned char)(it.polished || (bpol[b] && it.steps == 0));
            run->total += it.steps;
            if (bsteps[b] >= run->steps) {
                run->steps = bsteps[b];
                run->kappa = it.kappa;
            }
            if (!isfinite(it.residual)) {
                run->diverged = 1;
                run->r_true = it.residual;
            }
            run->timed_out |= it.timed_out;
        }
        gather(s, n, 0);
        run->polished = 0;
        for (int b = 0; b < s->ws_nblk; b++) {
            run->polished += bpol[b];
        }
        if (run->diverged) {
            return;
        }
        duals_from_iter(s, qp, pre, s->ws_y, s->ws_t);
        run->r_true = true_residual(qp, s, prm->big, s->ws_t);
        if (run->r_true <= prm->tol || run->steps >= cap || run->timed_out ||
            (pass >= 3 && run->r_true > 0.5 * r_prev)) {
            return; /* done, out of steps or time, or no progress (a contradiction the blocks cannot see) */
        }
        r_prev = run->r_true;
        tol_it *= fmax(1e-3, 0.5 * prm->tol / run->r_true);
    }
}

int mca_pdnn_solve(mca_pdnn_t *s, const mca_qp_t *qp, const mca_pdnn_params_t *params, double *phi,
                   mca_pdnn_result_t *result) {
    mca_pdnn_params_t defaults;
    if (params == NULL) {
        mca_pdnn_default_params(&defaults);
        params = &defaults;
    }
    if (s == NULL || qp == NULL || phi == NULL || check_qp(qp, s->ws_zero) != MCA_OK ||
        check_params(params) != MCA_OK) {
        return MCA_EINVAL;
    }
    mca_pdnn_params_t prm = *params;
    if (!(prm.gamma > 0.0)) {
        prm.gamma = PDNN_DEFAULT_GAMMA;
    }
    const int n = qp->n, m = qp->n_eq + qp->n_ineq, h = n + m;

    /* Warm start: reuse what still means the same thing. A state left non-finite is dropped. */
    int warm = 0;
    if (s->h > 0 && s->n == n && s->n_eq == qp->n_eq && all_finite(s->y, s->h)) {
        warm = (s->n_ineq == qp->n_ineq) ? 2 : 1;
    }
    const int pre = setup(s, qp, &prm, warm);
    for (int i = 0; i < h; i++) {
        const int keep = i < n + qp->n_eq ? warm >= 1 : warm == 2;
        s->ws_t[i] = keep ? s->y[i] : 0.0;
    }
    duals_to_iter(s, qp, pre, s->ws_t, s->ws_y);
    /* equality rows in the QP as given: G x - alpha = R^T (Q x - alpha'), bounded by ||R^T||_inf times the
     * iterated row (ORTH); = row / d (SCALE). Stored as f = 1 / factor: row value b / f. */
    double eqf[MCA_QP_MAX_EQ];
    double rt = 0.0;
    for (int i = 0; i < qp->n_eq && pre == MCA_PDNN_PRECOND_ORTH; i++) {
        double row = 0.0; /* row i of R^T = column i of R */
        for (int k = 0; k <= i; k++) {
            row += fabs(s->ws_R[k * qp->n_eq + i]);
        }
        rt = fmax(rt, row);
    }
    for (int i = 0; i < qp->n_eq; i++) {
        eqf[i] = pre == MCA_PDNN_PRECOND_ORTH ? rt : 1.0 / s->ws_d[i];
    }
    split(s, n, m, qp->n_eq, eqf, prm.no_split);
    for (int k = 0; k < n; k++) {
        s->ws_Bside[k] = warm ? s->side[s->ws_pv[k]] : 0;
    }
    /* all-zero rows: the fixed point of w = P(w - q) is w = 0 when q >= 0 (inequality); otherwise there is
     * none (infeasible row) and the true residual below reports it */
    for (int k = m - s->ws_nzero; k < m; k++) {
        const int i = s->ws_pr[k];
        if (i >= qp->n_eq && s->ws_q[i] >= 0.0) {
            s->ws_y[n + i] = 0.0;
        }
    }
    gather(s, n, 1);

    mca_pdnn_result_t res = {0};
    double kfix[MCA_QP_MAX_VARS];
    for (int b = 0; b < s->ws_nblk; b++) {
        kfix[b] = prm.kappa;
        if (prm.kappa > 0.0 || prm.step_rule == MCA_PDNN_STEP_BOUND) {
            const mca_pdnn__problem_t p = block_problem(s, b, 0);
            /* ||I+M||_2^2 = (5 + 2 s^2 + sqrt(9 + 4 s^2)) / 2 with s = ||N||_2 (docs/pdnn.md), increasing in
             * s */
            const double s2 = mca_pdnn__norm_sq_bound(&p);
            const double kb = prm.gamma / (0.5 * (5.0 + 2.0 * s2 + sqrt(9.0 + 4.0 * s2)));
            res.kappa_bound = (b == 0 || kb < res.kappa_bound) ? kb : res.kappa_bound;
            if (kfix[b] <= 0.0) {
                kfix[b] = kb;
            }
        }
    }

    /* A warm start gets half the steps: when the QP jumped (a new active row with a large multiplier), the
     * old y can be far from the new solution and the linear convergence slow, while a restart from 0
     * (a re-initialised network) often gets close fast. The better of the two answers is kept. */
    pdnn_run_t run = {0};
    const int rescue = warm && !prm.no_rescue;
    const int cap1 = rescue ? (prm.max_steps + 1) / 2 : prm.max_steps;
    run_passes(s, qp, pre, &prm, kfix, cap1, &run);
    res.kappa = run.kappa;
    if (rescue && !run.diverged && !run.timed_out && !(run.r_true <= prm.tol) &&
        prm.max_steps - run.steps > 0) {
        pdnn_run_t run2 = {0};
        memcpy(s->ws_y2, s->ws_y, sizeof(double) * (size_t)h);
        memcpy(s->ws_t2, s->ws_t, sizeof(double) * (size_t)h);
        memset(s->ws_y, 0, sizeof(double) * (size_t)h);
        gather(s, n, 1);
        run_passes(s, qp, pre, &prm, kfix, prm.max_steps - run.steps, &run2);
        res.restarted = 1;
        if (run2.diverged || !(run2.r_true < run.r_true)) { /* keep the warm answer */
            memcpy(s->ws_y, s->ws_y2, sizeof(double) * (size_t)h);
            memcpy(s->ws_t, s->ws_t2, sizeof(double) * (size_t)h);
            run.steps += run2.steps;
            run.total += run2.total;
            run.tries += run2.tries;
            run.timed_out |= run2.timed_out;
        } else {
            run2.steps += run.steps;
            run2.total += run.total;
            run2.tries += run.tries;
            run = run2;
            res.kappa = run2.kappa;
        }
    }
    const double r_true = run.r_true;
    const int steps = run.steps, total = run.total;
    res.blocks = s->ws_nblk;
    res.steps_total = total;
    res.steps = steps;
    res.residual = r_true;
    res.converged = r_true <= prm.tol;
    res.timed_out = run.timed_out && !res.converged;
    res.warm = warm;
    res.precond = pre;
    res.polished = res.converged ? run.polished : 0;
    res.polish_tries = run.tries;

    for (int j = 0; j < n; j++) {
        phi[j] = s->ws_y[j];
    }
    for (int k = 0; k < n; k++) {
        s->side[s->ws_pv[k]] = s->ws_Bside[k];
    }
    if (isfinite(r_true)) {
        memcpy(s->y, s->ws_t, sizeof(double) * (size_t)h);
        s->h = h;
        s->n = n;
        s->n_eq = qp->n_eq;
        s->n_ineq = qp->n_ineq;
    } else {
        s->h = 0; /* diverged: next solve starts cold */
    }
    if (result != NULL) {
        *result = res;
    }
    return res.converged ? MCA_OK : res.timed_out ? MCA_ETIMEDOUT : MCA_ENOTCONV;
}
