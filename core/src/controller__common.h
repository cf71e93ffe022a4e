/* SPDX-License-Identifier: MIT */
/* What every room of the controller uses (controller*.c): the tick's clock, the fault latch, the zero
 * command. Private to mca_core.
 *
 * Calling context: RT, the thread that ticks the controller (mca_controller_tick, _brake, _raise_fault);
 * no allocation, no text. */
#ifndef MCA_CONTROLLER__COMMON_H
#define MCA_CONTROLLER__COMMON_H

#include <stdint.h>
#include <time.h>

#include "controller__state.h" /* struct mca_controller */

static inline int64_t now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

/* A distance fault's cause: the pair and how near. */
static inline mca_ctrl_fault_why_t why_distance(int why, const mca_tick_info_t *info, double d1) {
    return (mca_ctrl_fault_why_t){.why = why,
                                  .i = {info->min_arm_a, info->min_link_a, info->min_arm_b, info->min_link_b},
                                  .x = {info->min_distance, d1}};
}

/* A fixed body's distance fault: the pair and how near (x[1] its clearance). */
static inline mca_ctrl_fault_why_t why_clearance(int why, const mca_tick_info_t *info) {
    return (mca_ctrl_fault_why_t){.why = why,
                                  .i = {info->body_arm, info->body_link, info->body_index},
                                  .x = {info->body_distance, info->body_distance - info->body_margin}};
}

/* A self pair's distance fault: the pair and how near. */
static inline mca_ctrl_fault_why_t why_self(int why, const mca_tick_info_t *info, double d1) {
    return (mca_ctrl_fault_why_t){
        .why = why, .i = {info->self_arm, info->self_link, info->self_other}, .x = {info->self_distance, d1}};
}

/* What the rows keep (mca_body_rows): the bodies unless measured only, the self pairs unless measured only.
 */
static inline int mca_ctrl__row_bodies(const mca_controller_config_t *cfg) {
    return cfg->body_rows ? cfg->n_bodies : 0;
}
static inline const mca_self_pairs_t *mca_ctrl__row_self(const mca_controller_config_t *cfg) {
    return cfg->self_rows && mca_controller_has_self(cfg) ? cfg->self : NULL;
}

/* Latch a fault (the first wins) as a code and numbers: no formatting here, on the 1 kHz path. */

static inline void raise_fault(mca_controller_t *ctrl, int code, mca_ctrl_fault_why_t why) {
    if (ctrl->fault != MCA_CTRL_FAULT_NONE) {
        return;
    }
    ctrl->fault = code;
    ctrl->fault_why = why;
}

static inline void zero_cmd(const mca_controller_t *ctrl, double *const qdot[MCA_MAX_ARMS]) {
    for (int a = 0; a < ctrl->cfg.n_arms; a++) {
        if (qdot[a]) {
            for (int j = 0; j < ctrl->cfg.chain[a].dof; j++) {
                qdot[a][j] = 0.0;
            }
        }
    }
}

#endif
