/* SPDX-License-Identifier: MIT */
/** @file mca/pdnn.h
 * LVI-PDNN solver (paper (29)-(32)) for mca_qp_t:
 *   y = [phi; v_e; v_i],  M = [I -G^T U^T; G 0 0; -U 0 0],  q = [0; -alpha; beta],
 *   Omega = box [lb, ub] x [-big, big]^{n_eq} x [0, big]^{n_ineq},
 *   ydot = lambda (I + M^T) (P_Omega(y - (M y + q)) - y),
 * integrated by explicit Euler steps y += kappa (I + M^T) e(y), kappa = lambda * dt, warm-started from the
 * previous solve. Stops when ||e(y)||_inf <= tol or after max_steps. Matrix work on fixed-size Eigen
 * matrices in a C++ shim; no allocation after mca_pdnn_init(). Real-time safe.
 */
#ifndef MCA_PDNN_H
#define MCA_PDNN_H

#include <stdint.h>

#include "mca/qp.h"

#ifdef __cplusplus
extern "C" {
#endif

/** How the Euler step kappa is chosen when params.kappa <= 0 (docs/pdnn.md derives both). */
enum mca_pdnn_step {
    /** kappa_k = gamma * ||e||^2 / ||(I+M^T) e||^2 each step (He's projection-contraction step; always
     *  >= gamma / ||I+M||^2, so it is never smaller than the fixed bound step). Default. */
    MCA_PDNN_STEP_ADAPTIVE = 0,
    /** One kappa = gamma / ||I+M||_2^2 per solve (the global stability bound, kappa < 2 / ||I+M||^2). */
    MCA_PDNN_STEP_BOUND = 1,
};

/** Equivalent rewriting of the constraints before integrating (32); phi and the reported duals are those
 *  of the QP as given in every case (docs/pdnn.md). */
enum mca_pdnn_precond {
    /** Rows of G orthonormalised (G -> R^-T G, alpha -> R^-T alpha), the G-components taken out of the
     *  rows of U (U_i -> U_i - c_i G, beta_i -> beta_i - c_i alpha: same set where G phi = alpha), then
     *  every row scaled to unit norm. Falls back to SCALE when G is (near) rank deficient. Default. */
    MCA_PDNN_PRECOND_ORTH = 0,
    /** Rows of G and U scaled to unit norm only. */
    MCA_PDNN_PRECOND_SCALE = 1,
    /** G, U as given: the paper's network verbatim. */
    MCA_PDNN_PRECOND_NONE = 2,
};

typedef struct mca_pdnn_params {
    double kappa;  /**< Euler step (lambda * dt); <= 0: chosen each solve from the stability bound */
    double tol;    /**< residual tolerance ||P_Omega(y - (My+q)) - y||_inf */
    int max_steps; /**< step cap per solve */
    double big;    /**< the paper's varpi, stands for +infinity in Omega */
    /* Added fields; a zeroed value means the default. */
    int step_rule;     /**< enum mca_pdnn_step, used when kappa <= 0 */
    double gamma;      /**< step factor in (0, 2) for the bound/adaptive rules; <= 0: 1.9 */
    int precond;       /**< enum mca_pdnn_precond */
    double far_weight; /**< full warm start, ORTH/SCALE: extra scale (0, 1] for inequality rows that were
                            inactive with a clear slack last solve (docs/pdnn.md); 1: off; <= 0: 0.3 */
    int no_split;  /**< 1: one network for the whole QP; 0: independent blocks (variables that share no row,
                        e.g. the two arms of the paper's block-diagonal G and U) are integrated as separate
                        sub-networks, each with its own adaptive step */
    int no_rescue; /**< 1: the network alone: return the last iterate, no cold restart. 0: when capped, return
                        the least-residual iterate seen, and a warm start that misses tol within half the
                        steps is followed by a cold restart for the other half (the better answer is kept) */
    int64_t deadline_ns; /**< CLOCK_MONOTONIC instant at which the solve stops as if capped (checked every 16
                              steps; timed_out says so); 0: none. The 1 kHz loop's time budget. */
    int no_polish;  /**< 1: the network alone. 0: active-set polish (docs/pdnn.md): at the first step and now
                         and then, the active set read off the iterate is corrected by a dual active-set method
                         and solved exactly; kept only if it meets tol, else the network goes on */
    int polish_max; /**< polish subproblem solves per block and run (warm, and the cold restart); <= 0: 48 */
} mca_pdnn_params_t;

typedef struct mca_pdnn_result {
    int steps;       /**< Euler steps taken */
    double residual; /**< final ||e(y)||_inf */
    int converged;   /**< residual <= tol */
    double kappa;    /**< step size used (adaptive rule: the last step taken) */
    /* Added fields. */
    int warm;           /**< 2: whole y reused, 1: phi and v_e reused (n_ineq changed), 0: cold */
    double kappa_bound; /**< gamma / ||I+M||_2^2 (upper-bounded norm) of the iterated problem; 0 when not
                             needed (adaptive rule) */
    int precond;        /**< enum mca_pdnn_precond actually used */
    int blocks;         /**< independent sub-networks integrated (steps: the most any of them took) */
    int steps_total;    /**< Euler steps summed over the blocks (the work done) */
    int restarted;      /**< 1: the warm start missed tol in half the steps and a cold restart had the rest
                             (the result is the better of the two) */
    int timed_out;      /**< 1: stopped at params.deadline_ns before tol (mca_pdnn_solve: MCA_ETIMEDOUT) */
    int polished;     /**< blocks whose answer is an accepted polish (the exact solution of an active set) */
    int polish_tries; /**< polish subproblem solves (exact KKT solves), summed over the blocks */
} mca_pdnn_result_t;

/** Solver state: the primal-dual vector kept between ticks for warm starts. */
typedef struct mca_pdnn {
    int h;                  /**< current length of y (0: cold) */
    double y[MCA_QP_MAX_H]; /**< [phi; v_e; v_i] of the last solve, duals of the unscaled QP */
    /* Added fields: sizes of the last solve (partial warm start) and the solver's private workspace, kept
     * here so that a solve needs no allocation and little stack. */
    int n, n_eq, n_ineq;
    double ws_N[(MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ) * MCA_QP_MAX_VARS]; /**< [G; -U] rewritten, m x n */
    double ws_q[MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ];                     /**< [-alpha; beta] rewritten */
    double ws_d[MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ];                     /**< row scale factors */
    double ws_R[MCA_QP_MAX_EQ * MCA_QP_MAX_EQ];                       /**< G = R^T Q (ORTH) */
    double ws_lo[MCA_QP_MAX_H], ws_hi[MCA_QP_MAX_H];                  /**< Omega */
    double ws_y[MCA_QP_MAX_H];                                        /**< iterate (rewritten duals) */
    double ws_t[MCA_QP_MAX_H];                                        /**< scratch */
    double ws_y2[MCA_QP_MAX_H], ws_t2[MCA_QP_MAX_H];                  /**< the warm attempt, kept */
    double ws_B[(MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ) * MCA_QP_MAX_VARS]; /**< per block N_b, compact */
    double ws_Bq[MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ];                    /**< per block q_b */
    double ws_Bf[MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ];  /**< per block: row factors to the given QP's residual */
    double ws_Bfi[MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ]; /**< their inverses */
    double ws_By[MCA_QP_MAX_H], ws_Blo[MCA_QP_MAX_H], ws_Bhi[MCA_QP_MAX_H]; /**< per block [x_b; w_b] */
    int ws_pv[MCA_QP_MAX_VARS], ws_pr[MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ];     /**< block order of vars, rows */
    int ws_nblk, ws_nzero;                                                  /**< blocks, all-zero rows */
    unsigned char ws_zero[MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ]; /**< row i of the QP as given is all zero */
    int ws_blk[MCA_QP_MAX_VARS][5];                         /**< c0, nc, r0, nr, offset in B */
    /** Per variable, the box side it sat at in the last answer a polish gave (0 unknown, 1 lower, 2 upper,
     *  4 free): the next warm polish starts from these, as a dual active-set solver keeps its working set. */
    unsigned char side[MCA_QP_MAX_VARS];
    unsigned char ws_Bside[MCA_QP_MAX_VARS]; /**< the same per block column (block order) */
} mca_pdnn_t;

/** Defaults: kappa from the rule (adaptive), tol 1e-9, max_steps 20000, big 1e10, gamma 1.9, ORTH,
 *  far_weight 0.3, blocks split, polish on (48 solves). For the 1 kHz loop set max_steps to the budget (~0.45
 * us per step for the dual-arm QP on the build machine, docs/pdnn.md). */
void mca_pdnn_default_params(mca_pdnn_params_t *params);

/** Keep the warm start across a change of the inequality rows: the next QP's row i was row old_of_new[i] of
 *  the last solve (-1: a new row, dual 0); the primal part and the equality duals stay. RT safe. */
void mca_pdnn_remap_ineq(mca_pdnn_t *s, int n_ineq, const int *old_of_new);

/** Cold state (y = 0). Call once before the first solve (the state is large: keep it static or in a
 *  struct allocated at start-up, not on a small stack). */
void mca_pdnn_init(mca_pdnn_t *s);

/**
 * Solve @p qp, starting from the state's y when its size matches the QP's (else from 0; when only n_ineq
 * changed, phi and v_e are still reused and v_i starts at 0).
 * @param params  NULL: defaults
 * @param result  may be NULL
 * @param[out] phi  the primal part (qp->n values)
 * @retval MCA_OK         converged: ||e(y)||_inf <= tol for the QP as given
 * @retval MCA_ENOTCONV   step cap hit, no progress (e.g. contradicting constraints) or diverged (a user
 *                        kappa above the stability edge); phi and result are filled from the iterate of
 *                        least residual seen (the state continues from there next tick)
 * @retval MCA_EINVAL     NULL, bad sizes, non-finite data, NaN or empty box (lb > ub), bad params
 */
int mca_pdnn_solve(mca_pdnn_t *s, const mca_qp_t *qp, const mca_pdnn_params_t *params, double *phi,
                   mca_pdnn_result_t *result);

#ifdef __cplusplus
}
#endif
#endif
