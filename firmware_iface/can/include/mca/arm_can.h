/* SPDX-License-Identifier: MIT */
/** @file mca/arm_can.h
 * SocketCAN backend of the cyclic arm interface (mca/arm.h): the controller side of the mca arm
 * protocol (mca/can_proto.h) on a raw CAN FD socket (mca/can_sock.h).
 *
 * mca_arm_write(): encodes the command into one 64-byte CAN FD frame (id_base + 0) with the next
 *   rolling counter and sends it without blocking (MCA_EAGAIN when the tx queue is full: nothing sent,
 *   the counter is not consumed).
 * mca_arm_read(): drains the socket (at most rx_burst frames), applies every valid frame and returns
 *   the newest feedback. A frame is valid when its id is one the arm sends (base+1..3), its length is
 *   the protocol's (CAN FD for the 64-byte frames), its contents decode and its rolling counter
 *   continues its stream (mca_can_seq_accept()). Anything else is counted (rx_bad_length: wrong length
 *   or undecodable contents; rx_bad_counter; rx_unknown_id: other ids of the arm's block, including our
 *   own command id sent by another node) and never applied.
 *   A feedback frame that passes these is also checked for plausibility (enum
 *   mca_can_fb_check): a position at the end of its field (saturated: +-2147 rad) or outside the link's
 *   position bounds (mca_can_options_t.pos_lo/pos_hi; default +-MCA_CAN_FB_POS_ABS_MAX), a position that
 * moved further since the last applied feedback than the wire's fastest velocity allows in the time between
 *   their receive stamps, a frame id ahead of the last command sent, or behind the last applied feedback's.
 *   Such a frame is refused (stats.rx_implausible, implausible_kind), never applied, and names
 *   link_fault = MCA_ARM_FAULT_FEEDBACK until the next applied feedback (reported as a link error).
 *   A heartbeat whose joint count differs from the configured arm's (stats.rx_bad_joints, hb_joints)
 *   sets link_fault = MCA_ARM_FAULT_JOINT_COUNT: while the newest heartbeat disagrees, no feedback is
 *   returned (every read is MCA_EIO), since its layout cannot be trusted.
 *   Error frames (CAN_ERR_FLAG) are counted in bus_errors; CAN_ERR_BUSOFF sets bus_off (counted in
 *   bus_off_events, and stats.link_fault = MCA_ARM_FAULT_BUS, so a controller that gets MCA_EIO can
 *   name the cause with mca_arm_fault_name()) until the next valid feedback gets through. A
 *   CAN_ERR_RESTARTED frame does not end it (the controller restarted; whether the bus works shows when
 *   feedback arrives), nor does a frame that says both BUSOFF and RESTARTED. Return codes:
 *     MCA_OK / MCA_EFAULT  new feedback (EFAULT: the arm reports FAULT), also when an error frame
 *                arrived in the same read: the feedback wins and the error stays pending (mca/arm.h)
 *     MCA_EIO    no new feedback, and an error frame (or a socket error) since the last MCA_EIO, or
 *                the link is bus-off; fb untouched
 *     MCA_EAGAIN no new feedback, no error; fb untouched.
 *   fb.frame_id is the 32-bit id of the command answered (the wire carries 16 bits, unwrapped against
 *   the last id sent), fb.fault_flags are those of the newest fault frame, fb.stamp_ns the kernel
 *   receive time (CLOCK_MONOTONIC). A feedback frame without a kernel stamp (no SO_TIMESTAMPNS
 *   cmsg) gets the user-space read time instead; stats.rx_stamp_kernel / rx_stamp_user count both.
 * Lost feedback is the caller's decision (count cycles of MCA_EAGAIN), as with every backend.
 *
 * Context: open/close start-up/shut-down only; read/write/stats and mca_can_link_*() real-time safe.
 */
#ifndef MCA_ARM_CAN_H
#define MCA_ARM_CAN_H

#include <stddef.h>
#include <stdint.h>

#include "mca/arm.h"
#include "mca/can_proto.h"
#include "mca/can_sock.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Default position bound of the link's plausibility check [rad] (+-16 turns: far beyond any modelled
 *  joint, continuous ones included; the daemon passes each joint's limits plus its margin). */
#define MCA_CAN_FB_POS_ABS_MAX 100.0

typedef struct mca_can_options {
    int brs;           /**< 1: send with the CAN FD bit-rate switch (default 1) */
    uint32_t err_mask; /**< CAN_ERR_* classes received as error frames (default: all, CAN_ERR_MASK) */
    int rx_burst;      /**< most frames drained per read (default 64) */
    double pos_lo[MCA_MAX_DOF];  /**< feedback positions below are refused (default -MCA_CAN_FB_POS_ABS_MAX;
                                      values below that, -inf included, mean the default) */
    double pos_hi[MCA_MAX_DOF];  /**< ... above (default +MCA_CAN_FB_POS_ABS_MAX) */
    double vel_max[MCA_MAX_DOF]; /**< fastest plausible motion of each joint between two feedbacks [rad/s]
                                      (default MCA_CAN_FB_JUMP_RATE; the daemon passes 1.5 x the joint's
                                      limit): a position moved further than vel_max x dt + margin is a JUMP */
} mca_can_options_t;

/** Defaults (see the fields). Start every mca_can_options_t from these: a zeroed struct has position
 *  bounds 0..0, and the link would refuse every feedback (as POSITION). */
void mca_can_options_default(mca_can_options_t *opt);

/**
 * Open the SocketCAN backend for one arm (start-up: opens and configures the socket, allocates).
 * @param[out] arm       handle for mca_arm_*()
 * @param[in]  iface     CAN FD interface ("can0", "vcan0")
 * @param[in]  id_base   the arm's id base (multiple of MCA_CAN_ID_BLOCK)
 * @param[in]  n_joints  1..MCA_MAX_DOF
 * @param[in]  opt       NULL for defaults
 * @param[out] err       reason on failure (may be NULL)
 * @retval MCA_OK, MCA_EINVAL, MCA_ENOMEM, and the codes of mca_can_sock_open()
 */
int mca_can_backend_open(mca_arm_t **arm, const char *iface, uint32_t id_base, int n_joints,
                         const mca_can_options_t *opt, char *err, size_t errlen);

/** The newest state (heartbeat) frame of a CAN-backed arm. @retval MCA_OK, MCA_EAGAIN (none yet),
 *  MCA_EINVAL (NULL or not a CAN backend) */
int mca_can_backend_state(const mca_arm_t *arm, mca_can_state_msg_t *st);

/** The socket, e.g. to poll() for feedback outside the real-time loop. @return fd or MCA_EINVAL. */
int mca_can_backend_fd(const mca_arm_t *arm);

/** Feedback the link refuses as implausible (stats.implausible_kind). */
enum mca_can_fb_check {
    MCA_CAN_FB_OK = 0,
    MCA_CAN_FB_SATURATED = 1,       /**< a position at the end of its int32 field (+-2147 rad) */
    MCA_CAN_FB_JUMP = 2,            /**< a position moved faster than MCA_CAN_FB_JUMP_RATE since the last */
    MCA_CAN_FB_FRAME_AHEAD = 3,     /**< answers a command frame id not sent yet */
    MCA_CAN_FB_FRAME_BACKWARDS = 4, /**< frame id behind the last applied feedback's */
    MCA_CAN_FB_POSITION = 5,        /**< a position outside the link's bounds (mca_can_link_set_bounds()) */
};
/** Fastest plausible position change between two applied feedback frames [rad/s]: twice the largest
 *  velocity the feedback frame can carry (32767 x 1e-4 rad/s). */
#define MCA_CAN_FB_JUMP_RATE (2.0 * 32767.0 * MCA_CAN_FB_VEL_SCALE)
/** Plus this much [rad] (rounding, stamp jitter). */
#define MCA_CAN_FB_JUMP_MARGIN 0.01
/** The time between two feedback frames is taken as at least this [ns] (equal or missing stamps). */
#define MCA_CAN_FB_JUMP_MIN_DT_NS 1000000

/** "OK", "SATURATED", "JUMP", "FRAME_AHEAD", "FRAME_BACKWARDS", "POSITION", "UNKNOWN". */
const char *mca_can_fb_check_name(unsigned kind);

/** Controller-side link state, socket-free (the backend is this plus a socket; tests drive it). */
typedef struct mca_can_link {
    uint32_t id_base;
    int n;
    uint8_t tx_counter;     /**< counter of the next command frame */
    uint32_t last_frame_id; /**< frame id of the last command sent */
    mca_can_seq_t seq_fb, seq_state, seq_fault;
    mca_arm_feedback_t fb; /**< newest valid feedback */
    int fb_new;            /**< 1 when fb has not been taken yet */
    int have_fb;           /**< 1 once a feedback was applied (fb is the reference of the checks) */
    int implausible;       /**< a refused feedback since the last applied one */
    int bad_joints;        /**< the newest heartbeat names another joint count */
    double pos_lo[MCA_MAX_DOF], pos_hi[MCA_MAX_DOF]; /**< position bounds of the plausibility check */
    double vel_max[MCA_MAX_DOF];                     /**< jump check rate per joint [rad/s] */
    uint16_t fault_flags[MCA_MAX_DOF];
    mca_can_state_msg_t state; /**< newest heartbeat */
    int have_state;
    int err_pending; /**< error frame (or socket error) not yet reported by a take */
    mca_arm_stats_t st;
} mca_can_link_t;

/** Bounds +-MCA_CAN_FB_POS_ABS_MAX. @retval MCA_OK, MCA_EINVAL (NULL, id_base not a block start, n out of
 *  range) */
int mca_can_link_init(mca_can_link_t *l, uint32_t id_base, int n);

/** Position bounds of the plausibility check, per joint (NULL: the default); each is clamped to
 *  +-MCA_CAN_FB_POS_ABS_MAX (so -inf / +inf, a continuous joint, mean the default). @retval MCA_OK,
 *  MCA_EINVAL (NULL link, NaN, lo > hi) */
int mca_can_link_set_bounds(mca_can_link_t *l, const double *lo, const double *hi);

/** Rate of the jump check, per joint [rad/s] (NULL or a value <= 0 or above MCA_CAN_FB_JUMP_RATE: that
 *  default). The bound grows with the time since the last applied feedback, so a lie that is refused
 *  frame after frame would pass once enough time went by: with the joint's own rate it passes only after
 *  the lost-feedback limit has long faulted the arm. @retval MCA_OK, MCA_EINVAL (NULL link, NaN) */
int mca_can_link_set_rate(mca_can_link_t *l, const double *vel_max);

/** Apply one received frame. @retval MCA_OK applied, MCA_EAGAIN ignored (and counted), MCA_EINVAL NULL */
int mca_can_link_rx(mca_can_link_t *l, const mca_can_frame_t *f);

/** Encode the next command frame (does not consume the counter). @retval as mca_can_encode_command() */
int mca_can_link_encode(const mca_can_link_t *l, const mca_arm_command_t *cmd,
                        uint8_t out[MCA_CAN_LEN_COMMAND]);

/** Record that the frame from mca_can_link_encode() went out (counter + 1, stats). */
void mca_can_link_sent(mca_can_link_t *l, const mca_arm_command_t *cmd);

/** Take the newest feedback. @retval MCA_OK (new; a pending error stays pending), MCA_EAGAIN (nothing
 *  new), MCA_EIO (nothing new, and an error frame or a refused feedback since the last MCA_EIO, or
 *  bus-off, or the heartbeat's joint count differs: then new feedback is dropped too; fb untouched) */
int mca_can_link_take(mca_can_link_t *l, mca_arm_feedback_t *fb);

#ifdef __cplusplus
}
#endif
#endif
