/* SPDX-License-Identifier: MIT */
/* The solve (controller_solve.c): the PDNN's parameters and budget for a tick, whether an answer stopped at
 * the budget, the repair of an answer that missed the tolerance (mca-ts: capped into the rows; mca: scaled),
 * and the compact row layout handed to the PDNN with its duals kept per slot. Private to mca_core.
 *
 * Calling context: RT, the thread that ticks the controller (mca_controller_tick, mca_controller_brake); no
 * allocation. mca_pdnn_budget_steps and mca_controller_step_budget (public, mca/controller.h) also at
 * start-up. */
#ifndef MCA_CONTROLLER__SOLVE_H
#define MCA_CONTROLLER__SOLVE_H

#include <stdint.h>

#include "controller__state.h" /* struct mca_controller */

/* RT: mca-ts, an answer that missed the tolerance made one each arm can follow and that keeps the rows. */
void mca_ctrl__repair_capped(mca_controller_t *ctrl, const mca_scheme_info_t *si, int na, const int ts_off[],
                             const double target[]);
/* RT: mca, an answer stopped by its budget scaled into the rows and the box. @return the factor, or -1. */
double mca_ctrl__repair_scaled(mca_controller_t *ctrl);
/* RT: the solver's parameters for a solve in the tick that began at t_enter (cap or budget, deadline). */
mca_pdnn_params_t mca_ctrl__pdnn_params(const mca_controller_config_t *cfg, int64_t t_enter);
/* RT: MCA_BUDGET_* when a solve that returned rc stopped at the budget, else MCA_BUDGET_NONE. */
int mca_ctrl__budget_hit(const mca_controller_config_t *cfg, int rc, const mca_pdnn_result_t *pr);
/* RT: only the active rows of qp to the PDNN; key/n_key keep each row's slot for the duals' warm start. */
void mca_ctrl__compact_rows(mca_qp_t *qp, double big, mca_scheme_info_t *si, mca_pdnn_t *pdnn, int *key,
                            int *n_key);

#endif
