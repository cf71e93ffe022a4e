/* SPDX-License-Identifier: MIT */
/** @file mca/armsim_rx.h
 * Receive side of the firmware emulator mca-armsim (sim_backend/armsim_can/): the arm's rules for the
 * command frames it hears (docs/can-protocol.md, "Receive rules"), socket-free so that the tests and the
 * fuzz target drive it with crafted frames.
 *
 * A frame is taken as the cycle's command when its id is the arm's command id (base+0), it is a CAN FD
 * frame of 64 bytes that decodes, its rolling counter continues the stream (mca_can_seq_accept()) and its
 * frame id is plausible: the 16-bit wire id is unwrapped against the newest accepted one (the reference)
 * and may be at most MCA_ARMSIM_FRAME_JUMP_MAX ahead of it. A frame further ahead is refused
 * (rx_bad_frame_id) and does not move the reference, so one forged command with frame id +32767 does not
 * make the genuine ones that follow stale; a run of MCA_CAN_SEQ_RESYNC_RUN frames with
 * consecutive ids that all jump ahead is a genuine jump and its last frame is taken. The reference never
 * moves backwards; a frame at or behind the command already taken this cycle does not supersede it.
 *
 * Context: every function real-time safe (no allocation, no I/O).
 */
#ifndef MCA_ARMSIM_RX_H
#define MCA_ARMSIM_RX_H

#include <stdint.h>

#include "mca/arm.h"
#include "mca/can_proto.h"
#include "mca/can_sock.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most command frames ahead of the reference taken without confirmation (a few commands lost on the
 *  controller's side: the MCA_EAGAIN of a full tx queue does not consume a counter, only a frame id). */
#define MCA_ARMSIM_FRAME_JUMP_MAX 16u
/** Most frames the emulator drains per firmware cycle; the rest wait in the socket (and the kernel drops
 *  what overflows it), so a flood cannot starve the firmware cycle. */
#define MCA_ARMSIM_RX_BURST 64

typedef struct mca_armsim_rx_counters {
    uint64_t frames_rx, cmd_accepted, cmd_superseded, rx_bad_length, rx_bad_counter, rx_unknown_id;
    uint64_t bus_errors;
    uint64_t rx_bad_frame_id; /**< commands refused for a frame id too far ahead */
    uint64_t rx_burst_full;   /**< cycles whose drain stopped at MCA_ARMSIM_RX_BURST frames */
} mca_armsim_rx_counters_t;

typedef struct mca_armsim_rx {
    uint32_t base;
    mca_can_seq_t seq;
    uint32_t frame_ref; /**< newest accepted (unwrapped) command frame id */
    int have_ref;
    int jump_run;          /**< commands in a row that jumped ahead with consecutive ids */
    uint32_t jump_last;    /**< unwrapped id of the newest of them */
    mca_arm_command_t cmd; /**< the cycle's command (newest valid) */
    int have_cmd;
    mca_armsim_rx_counters_t c;
} mca_armsim_rx_t;

/** Reset (base: the arm's id base). */
void mca_armsim_rx_init(mca_armsim_rx_t *rx, uint32_t base);

/** Apply one received frame. @return 1 when it became the cycle's command, 0 when counted and dropped. */
int mca_armsim_rx_frame(mca_armsim_rx_t *rx, const mca_can_frame_t *f);

/** Source of received frames for mca_armsim_rx_drain(): @return MCA_OK (a frame in *f), else nothing more
 *  now (MCA_EAGAIN) or an error. */
typedef int (*mca_armsim_recv_fn)(void *ctx, mca_can_frame_t *f);

/** Drain one cycle's frames: at most MCA_ARMSIM_RX_BURST from @p recv, each through mca_armsim_rx_frame()
 *  (a cycle that stops at the bound counts in rx_burst_full). @return frames taken from recv. */
int mca_armsim_rx_drain(mca_armsim_rx_t *rx, mca_armsim_recv_fn recv, void *ctx);

/** The cycle's command, if any (NULL: none), and forget it: the next cycle starts without one. */
const mca_arm_command_t *mca_armsim_rx_take(mca_armsim_rx_t *rx, mca_arm_command_t *out);

#ifdef __cplusplus
}
#endif
#endif
