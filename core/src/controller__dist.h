/* SPDX-License-Identifier: MIT */
/* The controller's distances (controller_dist.c): per link of every arm the closest link of any other arm and
 * the global minimum, and per link the near witness pairs that can bind the QP in hand (the input of mca-ts's
 * rows and of the braking rows). Private to mca_core.
 *
 * Calling context: RT, the thread that ticks the controller (mca_controller_tick, _observe, _brake); no
 * allocation, writes ctrl->dist, ctrl->crit and ctrl->near. */
#ifndef MCA_CONTROLLER__DIST_H
#define MCA_CONTROLLER__DIST_H

#include "controller__state.h" /* struct mca_controller */

/* RT: ctrl->crit (per link: the closest link of any other arm) and the tick report's distances, from
 * ctrl->kin. @retval MCA_OK, or mca_arm_distances' error. */
int mca_ctrl__distances(mca_controller_t *ctrl, mca_tick_info_t *info);
/* RT: ctrl->near, each link's MCA_NEAR_PAIRS nearest witness pairs that can bind qp (its box), after
 * mca_ctrl__distances; dec and priority: mca-ts's stop bound and shares (NULL: none). */
void mca_ctrl__near_links(mca_controller_t *ctrl, const mca_qp_t *qp, const mca_scheme_info_t *si,
                          const double *dec, const double *priority);

#endif
