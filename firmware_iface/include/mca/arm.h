/* SPDX-License-Identifier: MIT */
/** @file mca/arm.h
 * Kinova-style cyclic arm interface (modelled on Kortex BaseCyclic: one command in, one feedback out,
 * every cycle), one C API over several backends (simulated arm in-process, SocketCAN + arm firmware).
 *
 * Cycle, as the controller runs it every 1 ms:
 *     mca_arm_read(arm, &fb);      // newest feedback (non-blocking)
 *     ... controller tick ...
 *     mca_arm_write(arm, &cmd);    // this cycle's command (non-blocking)
 * The arm side runs a watchdog: no valid command within its timeout -> it brakes to zero velocity
 * within its deceleration limit and enters MCA_ARM_FAULT until a command carries MCA_ACT_CLEAR_FAULT.
 *
 * Context: opening (a backend's open function, e.g. mca_sim_backend_open() or mca_can_backend_open(),
 * which ends in mca_arm_wrap()) and mca_arm_close() are start-up/shut-down only (they may allocate and
 * block); mca_arm_read/write/stats are real-time safe for every backend (no allocation, no blocking,
 * no locks).
 *
 * Read contract (every backend): the return code says what is in fb, and a read never discards
 * feedback. A link error (CAN error frame, bus-off, socket error) seen by a read that also has new
 * feedback does not hide it: that read returns the feedback (MCA_OK / MCA_EFAULT) and the error stays
 * pending; the next read without new feedback reports it (MCA_EIO). Bus-off is reported by every read
 * without new feedback while it lasts. Every error is also counted in mca_arm_stats(). A caller
 * therefore uses fb on MCA_OK / MCA_EFAULT and counts a lost cycle on MCA_EAGAIN / MCA_EIO.
 */
#ifndef MCA_ARM_H
#define MCA_ARM_H

#include <stddef.h>
#include <stdint.h>

#include "mca/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Arm state reported by the arm side. */
typedef enum mca_arm_state {
    MCA_ARM_INIT = 0,
    MCA_ARM_READY = 1,    /**< powered, brakes on, waiting for servo enable */
    MCA_ARM_SERVOING = 2, /**< following velocity commands */
    MCA_ARM_BRAKING = 3,  /**< decelerating to zero (watchdog or requested) */
    MCA_ARM_FAULT = 4,    /**< stopped; needs MCA_ACT_CLEAR_FAULT */
} mca_arm_state_t;

/** Per-actuator command flags. */
enum {
    MCA_ACT_SERVO_ENABLE = 1u << 0,
    MCA_ACT_BRAKE_RELEASE = 1u << 1,
    MCA_ACT_CLEAR_FAULT = 1u << 2,
};

/** Arm fault codes (feedback.fault_code). */
enum mca_arm_fault {
    MCA_ARM_FAULT_NONE = 0,
    MCA_ARM_FAULT_WATCHDOG = 1,    /**< no valid command within the timeout */
    MCA_ARM_FAULT_JOINT_LIMIT = 2, /**< position limit reached */
    MCA_ARM_FAULT_VELOCITY = 3,    /**< commanded velocity above the limit */
    MCA_ARM_FAULT_INJECTED = 4,    /**< test fault injection */
    MCA_ARM_FAULT_BUS = 5,         /**< bus error / bus-off */
    MCA_ARM_FAULT_FEEDBACK = 6,    /**< the link refused implausible feedback (link_fault only) */
    MCA_ARM_FAULT_JOINT_COUNT = 7, /**< the arm's heartbeat names another joint count (link_fault only) */
    /* CANopen backend (mca/canopen.h): which node and why via mca_canopen_backend_fault() */
    MCA_ARM_FAULT_DRIVE = 8,      /**< a CiA 402 drive in FAULT (statusword) */
    MCA_ARM_FAULT_EMCY = 9,       /**< a drive sent an emergency message */
    MCA_ARM_FAULT_HEARTBEAT = 10, /**< a drive's heartbeat missed its consumer time, or the drive rebooted */
    MCA_ARM_FAULT_PDO = 11,       /**< a drive's TPDO was not refreshed in time */
    MCA_ARM_FAULT_SDO = 12,       /**< an SDO abort or timeout at start-up */
    MCA_ARM_FAULT_NMT = 13,       /**< a drive left OPERATIONAL */
};

/** Per-actuator fault flag bits (feedback.fault_flags[j]); latched until MCA_ACT_CLEAR_FAULT. */
enum {
    MCA_ACT_FLT_LIMIT_LOW = 1u << 0,  /**< position clamped at the lower limit */
    MCA_ACT_FLT_LIMIT_HIGH = 1u << 1, /**< position clamped at the upper limit */
    MCA_ACT_FLT_VEL_SAT = 1u << 2,    /**< commanded velocity saturated at the velocity limit */
    MCA_ACT_FLT_VELOCITY = 1u << 3,   /**< commanded velocity above the fault ratio (fault raised) */
    MCA_ACT_FLT_ACTUATOR = 1u << 4,   /**< actuator fault (injected in simulation) */
};

typedef struct mca_arm_command {
    uint32_t frame_id;                /**< sequence number, +1 per cycle */
    int n;                            /**< actuators */
    uint8_t flags[MCA_MAX_DOF];       /**< MCA_ACT_* */
    double velocity[MCA_MAX_DOF];     /**< joint velocity setpoint [rad/s] */
    double position_ref[MCA_MAX_DOF]; /**< position reference [rad] (informative) */
} mca_arm_command_t;

typedef struct mca_arm_feedback {
    uint32_t frame_id; /**< the command frame id this answers */
    int n;
    double position[MCA_MAX_DOF];      /**< [rad] */
    double velocity[MCA_MAX_DOF];      /**< [rad/s] */
    double torque[MCA_MAX_DOF];        /**< [N m] */
    uint16_t fault_flags[MCA_MAX_DOF]; /**< per actuator */
    mca_arm_state_t state;
    uint16_t fault_code; /**< enum mca_arm_fault */
    int64_t stamp_ns;    /**< receive time, CLOCK_MONOTONIC (kernel time stamp on CAN) */
} mca_arm_feedback_t;

/** Link statistics a backend keeps (counters only grow). */
typedef struct mca_arm_stats {
    uint64_t commands_sent;
    uint64_t feedback_received;
    uint64_t rx_bad_length;  /**< frames with a wrong length, ignored */
    uint64_t rx_bad_counter; /**< stale or skipped rolling counter, ignored */
    uint64_t rx_unknown_id;  /**< unexpected CAN ids, ignored */
    uint64_t bus_errors;     /**< error frames seen */
    int bus_off;             /**< 1 while the controller is bus-off */
    /* CAN backend (the sim backend leaves these 0): */
    uint64_t bus_off_events;   /**< times bus_off went 0 -> 1 */
    uint16_t link_fault;       /**< the link's own fault (enum mca_arm_fault, for mca_arm_fault_name()):
                                    MCA_ARM_FAULT_BUS while bus_off, else JOINT_COUNT while the arm's
                                    heartbeat names another joint count, else FEEDBACK from a refused
                                    implausible feedback frame until the next applied one, else NONE; the
                                    arm's own fault is fb.fault_code */
    uint64_t rx_stamp_kernel;  /**< feedback frames applied with the kernel's receive time stamp */
    uint64_t rx_stamp_user;    /**< feedback frames applied with the user-space read time (no kernel stamp) */
    uint64_t rx_implausible;   /**< feedback frames refused as implausible (CAN: mca_can_fb_check_name()) */
    uint16_t implausible_kind; /**< kind of the newest refused one (CAN: enum mca_can_fb_check) */
    uint64_t rx_bad_joints;    /**< heartbeats whose joint count differs from the configured arm */
    uint8_t hb_joints;         /**< joint count of the newest heartbeat (0: none yet) */
    uint64_t rx_dropped;       /**< frames the kernel dropped before the link read them (CAN: SO_RXQ_OVFL) */
} mca_arm_stats_t;

typedef struct mca_arm mca_arm_t; /**< opaque handle */

/** Backend contract: a function-pointer table + context (see sim_backend/, firmware_iface/can). */
typedef struct mca_arm_ops {
    const char *name;
    int (*read)(void *ctx, mca_arm_feedback_t *fb);
    int (*write)(void *ctx, const mca_arm_command_t *cmd);
    int (*stats)(void *ctx, mca_arm_stats_t *st);
    void (*close)(void *ctx);
} mca_arm_ops_t;

/** Wrap a backend (start-up only). @retval MCA_OK, MCA_EINVAL, MCA_ENOMEM */
int mca_arm_wrap(mca_arm_t **arm, const mca_arm_ops_t *ops, void *ctx);

/** Newest feedback (see "Read contract" above).
 *  @retval MCA_OK      new feedback in fb (even if the link also saw an error: it stays pending)
 *  @retval MCA_EFAULT  new feedback in fb, and the arm reports FAULT
 *  @retval MCA_EAGAIN  nothing new since the last read; fb untouched
 *  @retval MCA_EIO     nothing new, and a link error since the last read that reported one, or the
 *                      link is bus-off; fb untouched
 *  @retval MCA_EINVAL  NULL argument */
int mca_arm_read(mca_arm_t *arm, mca_arm_feedback_t *fb);
/** Send one cycle's command. @retval MCA_OK, MCA_EINVAL, MCA_EIO, MCA_EAGAIN (tx queue full) */
int mca_arm_write(mca_arm_t *arm, const mca_arm_command_t *cmd);
int mca_arm_stats(mca_arm_t *arm, mca_arm_stats_t *st);
const char *mca_arm_backend_name(const mca_arm_t *arm);
/** The backend context of @p arm if it was wrapped with @p ops, else NULL (safe downcast used by
 *  backend-specific extensions such as mca_sim_backend_*()). */
void *mca_arm_backend_ctx(const mca_arm_t *arm, const mca_arm_ops_t *ops);
/** Constant names for logs and tools ("SERVOING", "WATCHDOG", ...); never NULL. */
const char *mca_arm_state_name(mca_arm_state_t state);
const char *mca_arm_fault_name(unsigned fault_code);
/** Close the backend and free the handle (shut-down only). NULL is allowed. */
void mca_arm_close(mca_arm_t *arm);

#ifdef __cplusplus
}
#endif
#endif
