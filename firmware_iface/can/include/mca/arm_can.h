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
 *   Error frames (CAN_ERR_FLAG) are counted in bus_errors; CAN_ERR_BUSOFF sets bus_off (counted in
 *   bus_off_events, and stats.link_fault = MCA_ARM_FAULT_BUS, so a controller that gets MCA_EIO can
 *   name the cause with mca_arm_fault_name()) until a CAN_ERR_RESTARTED frame or the next valid
 *   feedback. Return codes:
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

typedef struct mca_can_options {
    int brs;           /**< 1: send with the CAN FD bit-rate switch (default 1) */
    uint32_t err_mask; /**< CAN_ERR_* classes received as error frames (default: all, CAN_ERR_MASK) */
    int rx_burst;      /**< most frames drained per read (default 64) */
} mca_can_options_t;

/** Defaults (see the fields). */
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

/** Controller-side link state, socket-free (the backend is this plus a socket; tests drive it). */
typedef struct mca_can_link {
    uint32_t id_base;
    int n;
    uint8_t tx_counter;     /**< counter of the next command frame */
    uint32_t last_frame_id; /**< frame id of the last command sent */
    mca_can_seq_t seq_fb, seq_state, seq_fault;
    mca_arm_feedback_t fb; /**< newest valid feedback */
    int fb_new;            /**< 1 when fb has not been taken yet */
    uint16_t fault_flags[MCA_MAX_DOF];
    mca_can_state_msg_t state; /**< newest heartbeat */
    int have_state;
    int err_pending; /**< error frame (or socket error) not yet reported by a take */
    mca_arm_stats_t st;
} mca_can_link_t;

/** @retval MCA_OK, MCA_EINVAL (NULL, id_base not a block start, n out of range) */
int mca_can_link_init(mca_can_link_t *l, uint32_t id_base, int n);

/** Apply one received frame. @retval MCA_OK applied, MCA_EAGAIN ignored (and counted), MCA_EINVAL NULL */
int mca_can_link_rx(mca_can_link_t *l, const mca_can_frame_t *f);

/** Encode the next command frame (does not consume the counter). @retval as mca_can_encode_command() */
int mca_can_link_encode(const mca_can_link_t *l, const mca_arm_command_t *cmd,
                        uint8_t out[MCA_CAN_LEN_COMMAND]);

/** Record that the frame from mca_can_link_encode() went out (counter + 1, stats). */
void mca_can_link_sent(mca_can_link_t *l, const mca_arm_command_t *cmd);

/** Take the newest feedback. @retval MCA_OK (new; a pending error stays pending), MCA_EAGAIN (nothing
 *  new), MCA_EIO (nothing new, and an error frame since the last MCA_EIO or bus-off; fb untouched) */
int mca_can_link_take(mca_can_link_t *l, mca_arm_feedback_t *fb);

#ifdef __cplusplus
}
#endif
#endif
