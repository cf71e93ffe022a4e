/* SPDX-License-Identifier: MIT */
/** @file mca/can_proto.h
 * The mca arm protocol on raw CAN FD (docs/can-protocol.md, config/can/mca.dbc): frame layout,
 * fixed-point encode/decode and the rolling-counter check. Pure functions on byte buffers, no
 * sockets, so the controller backend, the firmware emulator and the tests share one codec.
 *
 * Ids (11-bit, per arm, id_base a multiple of MCA_CAN_ID_BLOCK):
 *   base+0 command   controller -> arm, 64 B, every cycle
 *   base+1 feedback  arm -> controller, 64 B, every cycle (answers one command)
 *   base+2 state     arm -> controller,  8 B, heartbeat every MCA_CAN_HEARTBEAT_CYCLES and on change
 *   base+3 fault     arm -> controller, 20 B, on change of fault code/flags and with every heartbeat
 *                    while a fault is set
 * Every frame starts with its own 8-bit rolling counter (+1 per frame of that id, wraps 255 -> 0).
 * All multi-byte fields are little-endian (DBC byte order Intel, "@1").
 *
 * Context: every function here is real-time safe (no allocation, no I/O, bounded time).
 */
#ifndef MCA_CAN_PROTO_H
#define MCA_CAN_PROTO_H

#include <stddef.h>
#include <stdint.h>

#include "mca/arm.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Id offsets from the arm's id base. */
enum {
    MCA_CAN_OFF_COMMAND = 0,
    MCA_CAN_OFF_FEEDBACK = 1,
    MCA_CAN_OFF_STATE = 2,
    MCA_CAN_OFF_FAULT = 3,
};
/** Ids reserved per arm; the receive filter passes the whole block, so unknown ids inside it are seen
 *  and counted. id_base must be a multiple of it. */
#define MCA_CAN_ID_BLOCK 16u
/** Largest 11-bit id base (the block must fit under 0x800). */
#define MCA_CAN_ID_BASE_MAX (0x800u - MCA_CAN_ID_BLOCK)

/** Payload lengths [bytes]; all are valid CAN FD DLC lengths. */
#define MCA_CAN_LEN_COMMAND 64
#define MCA_CAN_LEN_FEEDBACK 64
#define MCA_CAN_LEN_STATE 8
#define MCA_CAN_LEN_FAULT 20
/** Heartbeat (state frame) period [firmware cycles]. */
#define MCA_CAN_HEARTBEAT_CYCLES 10

/** Fixed-point resolutions (value = raw * scale). */
#define MCA_CAN_CMD_VEL_SCALE 1e-6 /**< command velocity, int32 [rad/s] */
#define MCA_CAN_CMD_POS_SCALE 1e-5 /**< command position reference, int24 [rad] */
#define MCA_CAN_FB_POS_SCALE 1e-6  /**< feedback position, int32 [rad] */
#define MCA_CAN_FB_VEL_SCALE 1e-4  /**< feedback velocity, int16 [rad/s] */
#define MCA_CAN_FB_TAU_SCALE 0.1   /**< feedback torque, int12 [N m] */

/** State / heartbeat frame contents. */
typedef struct mca_can_state_msg {
    uint8_t state;       /**< mca_arm_state_t */
    uint8_t n;           /**< joints of the arm */
    uint16_t fault_code; /**< enum mca_arm_fault */
    uint16_t missed;     /**< consecutive firmware cycles without a valid command (saturates) */
    uint8_t rx_errors;   /**< bad frames the arm side ignored, modulo 256 */
} mca_can_state_msg_t;

/** Fault frame contents. */
typedef struct mca_can_fault_msg {
    uint8_t state;
    uint16_t fault_code;
    uint16_t fault_flags[MCA_MAX_DOF]; /**< MCA_ACT_FLT_* per joint */
} mca_can_fault_msg_t;

/**
 * Encode a command (64 bytes). Values outside a field's range saturate; frame_id travels as its low
 * 16 bits. @retval MCA_OK, MCA_EINVAL (NULL, n outside 1..MCA_MAX_DOF, non-finite value)
 */
int mca_can_encode_command(const mca_arm_command_t *cmd, uint8_t counter, uint8_t out[MCA_CAN_LEN_COMMAND]);

/**
 * Decode a command. cmd->frame_id receives the 16-bit wire value (see mca_can_unwrap16()).
 * @retval MCA_OK, MCA_EINVAL (NULL, len != 64, n outside 1..MCA_MAX_DOF)
 */
int mca_can_decode_command(const uint8_t *data, size_t len, mca_arm_command_t *cmd, uint8_t *counter);

/**
 * Encode a feedback (64 bytes): positions, velocities, torques of n joints (joints >= n are zero),
 * state, fault code and the low 16 bits of the answered frame id. Saturates out-of-range values.
 * @retval MCA_OK, MCA_EINVAL (NULL, n outside 1..MCA_MAX_DOF, non-finite value)
 */
int mca_can_encode_feedback(const mca_arm_feedback_t *fb, uint8_t counter, uint8_t out[MCA_CAN_LEN_FEEDBACK]);

/**
 * Decode a feedback for an arm of n joints. fb->frame_id gets the 16-bit wire value; fb->fault_flags
 * and fb->stamp_ns are left untouched (they come from the fault frame and the socket).
 * @retval MCA_OK, MCA_EINVAL (NULL, len != 64, n out of range, state outside mca_arm_state_t)
 */
int mca_can_decode_feedback(const uint8_t *data, size_t len, int n, mca_arm_feedback_t *fb, uint8_t *counter);

/** @retval MCA_OK, MCA_EINVAL (NULL) */
int mca_can_encode_state(const mca_can_state_msg_t *m, uint8_t counter, uint8_t out[MCA_CAN_LEN_STATE]);
/** @retval MCA_OK, MCA_EINVAL (NULL, len != 8, state out of range) */
int mca_can_decode_state(const uint8_t *data, size_t len, mca_can_state_msg_t *m, uint8_t *counter);
/** @retval MCA_OK, MCA_EINVAL (NULL) */
int mca_can_encode_fault(const mca_can_fault_msg_t *m, uint8_t counter, uint8_t out[MCA_CAN_LEN_FAULT]);
/** @retval MCA_OK, MCA_EINVAL (NULL, len != 20, state out of range) */
int mca_can_decode_fault(const uint8_t *data, size_t len, mca_can_fault_msg_t *m, uint8_t *counter);

/** Consecutive counters a new stream needs before it replaces the current one (mca_can_seq_accept()). */
#define MCA_CAN_SEQ_RESYNC_RUN 3

/**
 * Rolling-counter check of one receive stream. A frame is accepted when its counter is the last
 * accepted + 1. Any other counter (stale, repeated or skipped) is rejected and starts (or continues) a
 * candidate run; a run of MCA_CAN_SEQ_RESYNC_RUN consecutive counters (c, c+1, c+2) resyncs the stream at
 * its last frame, which is accepted. A frame that continues the current stream always wins and drops the
 * run. So a stray frame costs nothing, a forged pair of counters (c, c+1) never gets in nor resyncs the
 * stream, a real loss costs MCA_CAN_SEQ_RESYNC_RUN - 1 more frames. The first frame syncs.
 * (Counters are no authentication: a node that sends three consecutive counters before the next genuine
 * frame takes the stream over, until the genuine stream's own run takes it back.)
 */
typedef struct mca_can_seq {
    int synced;
    uint8_t last;
    int run;      /**< frames in the candidate run (0: none) */
    uint8_t cand; /**< counter of the candidate run's last frame */
} mca_can_seq_t;

/** Reset a stream (the next frame syncs it). */
void mca_can_seq_reset(mca_can_seq_t *s);
/** @return 1 accept, 0 reject (count it as a bad counter). */
int mca_can_seq_accept(mca_can_seq_t *s, uint8_t counter);

/** The 32-bit id whose low 16 bits are @p low, nearest to @p ref in serial-number order
 *  (within -32768..+32767 of ref). */
uint32_t mca_can_unwrap16(uint32_t ref, uint16_t low);

#ifdef __cplusplus
}
#endif
#endif
