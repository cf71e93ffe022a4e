/* SPDX-License-Identifier: MIT */
/** @file mca/sim_backend.h
 * In-process simulated arm behind the mca/arm.h interface: a mca_sim_arm_t firmware model
 * (mca/sim_arm.h) wrapped in the backend vtable. Time is virtual: every mca_arm_write() runs exactly
 * one firmware cycle of cfg->dt, so the simulation clock advances with the controller's writes.
 *
 *   mca_arm_read()  -> feedback of the latest cycle; MCA_EAGAIN when there is none since the last
 *                      read (also while the firmware is silenced by fault injection); MCA_EFAULT
 *                      with fb filled when the arm reports FAULT. Right after open, one read returns
 *                      the initial (noise-free) state so the controller knows q before its first write.
 *   mca_arm_write() -> one firmware cycle with this command; MCA_EINVAL if cmd->n differs from the
 *                      arm's joint count (nothing run).
 *   mca_arm_stats() -> commands_sent (cycles run by writes), feedback_received (feedback produced);
 *                      the CAN link counters stay 0.
 *
 * Context: open/close start-up/shut-down; read/write/idle real-time safe; one thread at a time.
 */
#ifndef MCA_SIM_BACKEND_H
#define MCA_SIM_BACKEND_H

#include <stddef.h>

#include "mca/arm.h"
#include "mca/sim_arm.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Open an in-process simulated arm (start-up only; allocates).
 * @param[out] arm    handle for mca_arm_*(); untouched on error
 * @param[in]  cfg    arm configuration (copied), see mca_sim_arm_config_default()
 * @param[out] err    message naming the bad field (may be NULL)
 * @retval MCA_OK, MCA_EINVAL / MCA_ERANGE (bad config, see err), MCA_ENOMEM
 */
int mca_sim_backend_open(mca_arm_t **arm, const mca_sim_arm_config_t *cfg, char *err, size_t errlen);

/** The firmware model inside a sim backend (true state, counters), NULL if @p arm is not one. */
mca_sim_arm_t *mca_sim_backend_firmware(mca_arm_t *arm);

/**
 * Run @p cycles firmware cycles in which no command arrives (a controller that missed its
 * deadlines or a lost link); feedback stays readable as after a write.
 * @retval MCA_OK, MCA_EINVAL (not a sim backend, cycles < 0)
 */
int mca_sim_backend_idle(mca_arm_t *arm, int cycles);

#ifdef __cplusplus
}
#endif
#endif
