/* SPDX-License-Identifier: MIT */
/** @file mca/sim_arm.h
 * Simulated arm firmware: joint physics + the arm-side state machine and watchdog, behind the
 * cyclic command/feedback types of mca/arm.h. Transport-independent and deterministic: the
 * in-process sim backend (mca/sim_backend.h) and the CAN firmware emulator `mca-armsim` run this
 * same object, so both move the arm identically.
 *
 * One call of mca_sim_arm_cycle() is one firmware cycle of length dt:
 *  1. fault injections scheduled for this cycle fire;
 *  2. the command (NULL: none arrived this cycle) enters the transport delay line; the command that
 *     is delivered now is the one handed in `latency_cycles` calls ago;
 *  3. the delivered command is checked: n must equal the arm's n, every velocity must be finite and
 *     its frame id must be newer (serial-number order, wrap-safe) than the last accepted one.
 *     Stale/repeated ids and invalid commands are counted and not applied;
 *  4. state machine (at most one transition per cycle, see below) and watchdog;
 *  5. physics over dt; 6. feedback.
 *
 * State machine (fb.state):
 *   INIT      --(init_cycles cycles done)---------------------------------> READY
 *   READY     --(valid cmd, every actuator SERVO_ENABLE|BRAKE_RELEASE)-----> SERVOING
 *   SERVOING  --(valid cmd without SERVO_ENABLE|BRAKE_RELEASE on any actuator)-> BRAKING (requested)
 *   SERVOING  --(watchdog / joint limit / velocity fault / injected fault)-> BRAKING (fault pending)
 *   BRAKING   --(all joints stopped, no fault pending)--------------------> READY
 *   BRAKING   --(all joints stopped, fault pending)-----------------------> FAULT
 *   READY/INIT --(injected fault)-----------------------------------------> FAULT
 *   FAULT     --(valid cmd with CLEAR_FAULT on any actuator)--------------> READY
 * In INIT, READY and FAULT the brakes hold the joints (velocity 0). While BRAKING, commands are
 * acknowledged (frame id) but not applied, and every joint decelerates at exactly its dec_limit.
 * fb.fault_code is the pending/latched fault (enum mca_arm_fault) in BRAKING and FAULT, else NONE.
 *
 * Watchdog (SERVOING only): `missed` counts consecutive cycles without a valid command. Until it
 * reaches watchdog_cycles the last accepted setpoint is held; in the cycle where missed ==
 * watchdog_cycles the arm enters BRAKING (fault WATCHDOG pending) and the first deceleration step
 * is taken in that same cycle. FAULT follows in the cycle the last joint reaches zero velocity.
 *
 * Physics, per joint j, in SERVOING (u = commanded velocity saturated to +-vel_limit):
 *   lag:  r_k = r_{k-1} + (u - r_{k-1}) (1 - exp(-dt / lag_tau))   (exact first-order hold; r = u if
 *         lag_tau == 0). Sampled step response r_k = u (1 - exp(-k dt / lag_tau)).
 *   rate: v_k = v_{k-1} + clamp(r_k - v_{k-1}, +-a dt), a = dec_limit while |v| shrinks towards 0,
 *         acc_limit while |v| grows; a zero crossing within a cycle uses dec to 0, then acc for the rest.
 *   pos:  q_k = q_{k-1} + dt (v_{k-1} + v_k) / 2 (trapezoid: exact for piecewise-constant
 *         acceleration); q outside [lower, upper] is clamped, v_k = 0, the MCA_ACT_FLT_LIMIT_* bit is
 *         set and fault JOINT_LIMIT is raised.
 *   torque: tau_k = inertia (v_k - v_{k-1}) / dt + damping v_k (gravity-free, no coupling).
 * Measured position/velocity = true value + sigma N(0, 1) from a seeded splitmix64 generator
 * (Box-Muller); the true state in the struct never carries noise.
 *
 * Context: mca_sim_arm_config_*() and mca_sim_arm_init() are start-up; mca_sim_arm_cycle() is real-time
 * safe (no allocation, no I/O, no locks, bounded time). The object is caller-provided storage; one
 * thread uses it at a time.
 */
#ifndef MCA_SIM_ARM_H
#define MCA_SIM_ARM_H

#include <stddef.h>
#include <stdint.h>

#include "mca/arm.h"
#include "mca/chain.h"
#include "mca/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Longest transport delay line [cycles]. */
#define MCA_SIM_MAX_LATENCY 64
/** Most scheduled fault injections per arm. */
#define MCA_SIM_MAX_INJECT 8

/** Kinds of injected faults (mca_sim_inject_t.kind). */
typedef enum mca_sim_inject_kind {
    MCA_SIM_INJ_NONE = 0,
    MCA_SIM_INJ_ACTUATOR = 1, /**< actuator `joint` faults: brake, then FAULT/INJECTED (latched) */
    MCA_SIM_INJ_FREEZE = 2,   /**< feedback frozen: the last frame is repeated verbatim (physics runs) */
    MCA_SIM_INJ_SILENT = 3,   /**< firmware stops answering: no feedback (physics and watchdog run) */
    MCA_SIM_INJ_DROP_RX = 4,  /**< commands lost before the firmware (drives the watchdog) */
} mca_sim_inject_kind_t;

/** One scheduled fault: fires at 0-based cycle `at_cycle` and lasts `duration` cycles (0 = forever;
 *  ignored for ACTUATOR, which latches until a clear-fault). */
typedef struct mca_sim_inject {
    int kind;          /**< mca_sim_inject_kind_t */
    uint64_t at_cycle; /**< index of the mca_sim_arm_cycle() call where it starts */
    uint64_t duration; /**< cycles; 0 = until the end */
    int joint;         /**< ACTUATOR only: 0..n-1 */
} mca_sim_inject_t;

typedef struct mca_sim_arm_config {
    int n;                     /**< joints, 1..MCA_MAX_DOF */
    double lower[MCA_MAX_DOF]; /**< position limits [rad]; +-INFINITY = none */
    double upper[MCA_MAX_DOF];
    double vel_limit[MCA_MAX_DOF]; /**< |v| limit [rad/s], > 0 */
    double acc_limit[MCA_MAX_DOF]; /**< speeding up [rad/s^2], > 0 */
    double dec_limit[MCA_MAX_DOF]; /**< slowing down and braking [rad/s^2], > 0 */
    double inertia[MCA_MAX_DOF];   /**< torque model [kg m^2], >= 0 */
    double damping[MCA_MAX_DOF];   /**< torque model [N m s/rad], >= 0 */
    double q0[MCA_MAX_DOF];        /**< initial positions [rad], within the limits */
    double dt;                     /**< cycle of the in-process backend [s] (default 0.001) */
    double lag_tau;                /**< first-order lag time constant [s]; 0 = none */
    int latency_cycles;            /**< command transport delay, 0..MCA_SIM_MAX_LATENCY */
    double noise_pos;              /**< measurement noise sigma [rad]; 0 = none */
    double noise_vel;              /**< measurement noise sigma [rad/s]; 0 = none */
    uint64_t seed;                 /**< noise generator seed */
    int watchdog_cycles;           /**< missed cycles before braking, >= 1 (PA-10: 3) */
    int init_cycles;               /**< cycles spent in INIT before READY, >= 0 */
    double vel_fault_ratio;        /**< |cmd| > ratio * vel_limit raises FAULT_VELOCITY; 0 = never
                                        (commands are only saturated) */
    int stamp_monotonic;           /**< 1: fb.stamp_ns = CLOCK_MONOTONIC; 0: virtual time k*dt */
    int ideal;    /**< 1: SERVOING follows the setpoint exactly, q += u dt (explicit Euler: no lag, no rate
                       limit; mca-sim --euler, which also lifts the position and velocity limits) */
    int n_inject; /**< entries used in inject[] */
    mca_sim_inject_t inject[MCA_SIM_MAX_INJECT];
} mca_sim_arm_config_t;

/** Firmware-side counters (only grow). */
typedef struct mca_sim_arm_counters {
    uint64_t cycles;       /**< mca_sim_arm_cycle() calls */
    uint64_t cmd_received; /**< non-NULL commands handed in */
    uint64_t cmd_dropped;  /**< lost by MCA_SIM_INJ_DROP_RX */
    uint64_t cmd_accepted; /**< delivered, valid and fresh */
    uint64_t cmd_stale;    /**< delivered with a stale or repeated frame id */
    uint64_t cmd_invalid;  /**< delivered with a wrong n or a non-finite velocity */
    uint64_t watchdog_trips;
    uint64_t feedback_sent; /**< cycles that produced feedback */
} mca_sim_arm_counters_t;

/** The simulated arm. Caller-provided storage; fields are read-only for users (q and v are the true,
 *  noise-free state), written only by mca_sim_arm_*(). */
typedef struct mca_sim_arm {
    mca_sim_arm_config_t cfg;
    mca_arm_state_t state;
    uint16_t fault_code; /**< latched (FAULT) or pending (BRAKING) fault */
    uint16_t fault_flags[MCA_MAX_DOF];
    double q[MCA_MAX_DOF];   /**< true position [rad] */
    double v[MCA_MAX_DOF];   /**< true velocity [rad/s] */
    double r[MCA_MAX_DOF];   /**< lagged setpoint [rad/s] */
    double u[MCA_MAX_DOF];   /**< held commanded setpoint [rad/s] (saturated) */
    double tau[MCA_MAX_DOF]; /**< modelled torque [N m] */
    uint64_t cycle;          /**< completed cycles */
    uint32_t last_frame_id;  /**< newest accepted frame id */
    int have_frame;          /**< 1 once a command was accepted */
    int missed;              /**< consecutive cycles without a valid command (SERVOING) */
    uint64_t rng;            /**< splitmix64 state */
    int64_t t_ns;            /**< virtual time: sum of dt [ns] */
    mca_sim_arm_counters_t cnt;
    /* transport delay line: slot (cycle % (latency + 1)) */
    mca_arm_command_t delay[MCA_SIM_MAX_LATENCY + 1];
    uint8_t delay_full[MCA_SIM_MAX_LATENCY + 1];
    mca_arm_feedback_t last_fb; /**< last feedback produced (what FREEZE repeats) */
    int have_last_fb;
} mca_sim_arm_t;

/**
 * Defaults for an n-joint arm (start-up): no position limits, vel 1 rad/s, acc = dec = 10 rad/s^2,
 * inertia 0.05 kg m^2, damping 0.5 N m s/rad, q0 = 0, dt 1 ms, no lag/latency/noise, seed 1,
 * watchdog 3 cycles, init 0 cycles, no velocity fault, virtual stamps, no injections.
 * n is clamped to 1..MCA_MAX_DOF.
 */
void mca_sim_arm_config_default(mca_sim_arm_config_t *cfg, int n);

/**
 * Defaults (as mca_sim_arm_config_default()) with n, lower, upper and vel_limit from a URDF chain;
 * continuous joints get no position limits. q0 = 0 clamped into the limits.
 * @retval MCA_OK, MCA_EINVAL (NULL, dof out of range)
 */
int mca_sim_arm_config_from_chain(mca_sim_arm_config_t *cfg, const mca_chain_t *chain);

/**
 * Check a configuration; on error writes "field[j] = value: reason" into err.
 * @retval MCA_OK, MCA_EINVAL (NULL or a bad field), MCA_ERANGE (n or latency above a maximum)
 */
int mca_sim_arm_config_check(const mca_sim_arm_config_t *cfg, char *err, size_t errlen);

/**
 * Initialise an arm at q0 in state INIT (READY at once when init_cycles == 0). Start-up only.
 * @retval as mca_sim_arm_config_check(); @p arm untouched on error
 */
int mca_sim_arm_init(mca_sim_arm_t *arm, const mca_sim_arm_config_t *cfg, char *err, size_t errlen);

/**
 * Run one firmware cycle (real-time safe).
 * @param[in]  cmd command received this cycle, NULL when none arrived
 * @param[in]  dt  cycle length [s], finite and > 0
 * @param[out] fb  this cycle's feedback (untouched when the arm does not answer)
 * @retval MCA_OK      cycle run, fb filled
 * @retval MCA_EAGAIN  cycle run, but the firmware sent no feedback (MCA_SIM_INJ_SILENT)
 * @retval MCA_EINVAL  NULL arm/fb or bad dt (nothing run)
 */
int mca_sim_arm_cycle(mca_sim_arm_t *arm, const mca_arm_command_t *cmd, double dt, mca_arm_feedback_t *fb);

/**
 * Schedule a fault injection starting with the next cycle (real-time safe; e.g. a daemon or demo
 * command "fail this arm now"). Same meaning as a cfg.inject[] entry with at_cycle = arm->cycle.
 * @retval MCA_OK, MCA_EINVAL (NULL, unknown kind, joint out of range), MCA_ERANGE (table full)
 */
int mca_sim_arm_inject_now(mca_sim_arm_t *arm, int kind, uint64_t duration, int joint);

/** The text form of one injection, as the tools take it (`mca-armsim --inject`, `mca-simarm-trace --inject`).
 */
#define MCA_SIM_INJECT_SYNTAX "KIND@CYCLE[+CYCLES][:JOINT]"

/**
 * Parse one injection in MCA_SIM_INJECT_SYNTAX: KIND is actuator (needs :JOINT, 0..n_joints-1), freeze,
 * silent or drop-rx; CYCLE the 0-based cycle where it starts; CYCLES how long (default 0 = until the end).
 * E.g. "actuator@5000:1", "silent@9000+20". Start-up only; prints nothing (the caller names the option).
 * @retval MCA_OK, MCA_EINVAL (NULL or bad text: *out zeroed)
 */
int mca_sim_inject_parse(const char *text, int n_joints, mca_sim_inject_t *out);

/**
 * Parse the emulators' --q0: exactly n comma-separated finite numbers (joint positions [rad]) into q.
 * Start-up only; prints nothing (the caller names the option).
 * @retval MCA_OK, MCA_EINVAL (NULL, n < 1, not n numbers, or one not finite: q unchanged)
 */
int mca_sim_parse_joint_list(const char *text, int n, double *q);

/** KIND's name in MCA_SIM_INJECT_SYNTAX ("actuator", "freeze", "silent", "drop-rx"), "none" otherwise. */
const char *mca_sim_inject_kind_name(int kind);

/** Noise-free feedback of the current state without running a cycle (e.g. the initial pose). */
void mca_sim_arm_snapshot(const mca_sim_arm_t *arm, mca_arm_feedback_t *fb);

#ifdef __cplusplus
}
#endif
#endif
