/* SPDX-License-Identifier: MIT */
/** @file mca/apf.h
 * Artificial-potential-field baseline of the paper, Section V-B (40)-(46), parameters of Table III.
 *   V_P   = (K_P e_P + D_P de_P/dt) (P_G - P_E)/|P_G - P_E|                      (40)
 *   V_V   = (K_V e_V + D_V de_V/dt) (S_G - S_E)/|S_G - S_E|                      (41)
 *   V_Att = rho V_P + (1 - rho) V_V                                             (42)
 *   V_Rep = v_max / (1 + exp(2 d_min theta / d)) (P_R - P_O)/|P_R - P_O|         (43)
 *   qdot  = J^+(P_E) V_Att + sum_i J^+(P_R^i) V_Rep^i                           (44)-(46)
 * The repulsion acts on every link whose critical point is closer than the influence distance d.
 * Real-time safe.
 */
#ifndef MCA_APF_H
#define MCA_APF_H

#include "mca/chain.h"
#include "mca/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mca_apf_params {
    double k_pos, d_pos; /**< K_Pos, D_Pos */
    double k_vel, d_vel; /**< K_Vel, D_Vel */
    double rho;          /**< weight of the position layer */
    double d;            /**< influence distance [m] */
    double v_rep_max;    /**< maximum repulsive speed */
    double theta;        /**< rate factor */
    double damping;      /**< damped pseudoinverse lambda^2 (0: plain) */
} mca_apf_params_t;

/** Table III: K_Pos 100, D_Pos 0.1, K_Vel 5, D_Vel 0.1, rho 0.8, d 0.12, v_Rep-max 0.001, theta 1. */
void mca_apf_default_params(mca_apf_params_t *p);

/** Repulsive speed (43): v_max / (1 + exp(2 d_min theta / d)). */
double mca_apf_rep_speed(const mca_apf_params_t *p, double d_min);

/**
 * Attractive velocity (40)-(42) of one end effector, solved as the continuous-time law it is.
 * In (40)-(41) the end-effector velocity S_E is the commanded V_Att itself (J J^+ = I), and
 * de_P/dt = n^T (S_G - S_E) with n = (P_G - P_E)/e_P. Evaluating S_E from the previous tick instead
 * makes the discrete loop oscillate (eigenvalue -1 with Table III's gains at 1 kHz), so the linear
 * equation V = rho (K_P e_P + D_P n^T (S_G - V)) n + (1 - rho) K_V (S_G - V) is solved for V
 * (Sherman-Morrison). de_V/dt would need the acceleration of the loop itself: D_V's term is left out.
 * @param ee    end-effector position P_E
 * @param goal  desired position P_G
 * @param goal_vel desired velocity S_G
 * @param[out] v_att V_Att
 */
void mca_apf_attractive(const mca_apf_params_t *p, const double ee[3], const double goal[3],
                        const double goal_vel[3], double v_att[3]);

/** Pseudoinverse J^+ v (3 x dof Jacobian, J^T (J J^T + damping I)^-1 v). @retval MCA_OK, MCA_EINFEASIBLE
 *  (singular J J^T) */
int mca_apf_pinv_apply(const double J[3][MCA_MAX_DOF], int dof, double damping, const double v[3],
                       double *qdot);

#ifdef __cplusplus
}
#endif
#endif
