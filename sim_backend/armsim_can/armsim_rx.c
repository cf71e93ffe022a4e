/* SPDX-License-Identifier: MIT */
/* Receive rules of the firmware emulator (see mca/armsim_rx.h). */
#include "mca/armsim_rx.h"

#include <string.h> /* memset */

#include <linux/can.h>
#include <linux/can/error.h>

#include "mca/err.h"

void mca_armsim_rx_init(mca_armsim_rx_t *rx, uint32_t base) {
    if (rx) {
        memset(rx, 0, sizeof(*rx));
        rx->base = base;
        mca_can_seq_reset(&rx->seq);
    }
}

int mca_armsim_rx_frame(mca_armsim_rx_t *rx, const mca_can_frame_t *f) {
    if (!rx || !f) {
        return 0;
    }
    rx->c.frames_rx++;
    if (f->can_id & CAN_ERR_FLAG) {
        rx->c.bus_errors++;
        return 0;
    }
    const uint32_t id = f->can_id & CAN_SFF_MASK;
    if ((f->can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) || id != rx->base + MCA_CAN_OFF_COMMAND) {
        rx->c.rx_unknown_id++; /* our own feedback ids from another node, or undefined ids */
        return 0;
    }
    mca_arm_command_t cmd;
    uint8_t ctr;
    if (!f->fd || mca_can_decode_command(f->data, f->len, &cmd, &ctr) != MCA_OK) {
        rx->c.rx_bad_length++;
        return 0;
    }
    if (!mca_can_seq_accept(&rx->seq, ctr)) {
        rx->c.rx_bad_counter++;
        return 0;
    }
    if (rx->have_ref) {
        cmd.frame_id = mca_can_unwrap16(rx->frame_ref, (uint16_t)cmd.frame_id);
        const int32_t ahead = (int32_t)(cmd.frame_id - rx->frame_ref);
        if (ahead > (int32_t)MCA_ARMSIM_FRAME_JUMP_MAX) {
            /* one frame far ahead is refused; a run of them with consecutive ids is a genuine jump */
            rx->jump_run = rx->jump_run > 0 && cmd.frame_id == rx->jump_last + 1u ? rx->jump_run + 1 : 1;
            rx->jump_last = cmd.frame_id;
            if (rx->jump_run < MCA_CAN_SEQ_RESYNC_RUN) {
                rx->c.rx_bad_frame_id++;
                return 0;
            }
        }
        rx->jump_run = 0;
        if (ahead > 0) {
            rx->frame_ref = cmd.frame_id; /* never backwards */
        }
    } else {
        rx->frame_ref = cmd.frame_id;
        rx->have_ref = 1;
    }
    if (rx->have_cmd) {
        rx->c.cmd_superseded++;
        if ((int32_t)(cmd.frame_id - rx->cmd.frame_id) <= 0) {
            return 0; /* older than the command already taken this cycle: keep that one */
        }
    }
    rx->cmd = cmd;
    rx->have_cmd = 1;
    rx->c.cmd_accepted++;
    return 1;
}

int mca_armsim_rx_drain(mca_armsim_rx_t *rx, mca_armsim_recv_fn recv, void *ctx) {
    if (!rx || !recv) {
        return 0;
    }
    mca_can_frame_t f;
    int n = 0;
    while (n < MCA_ARMSIM_RX_BURST && recv(ctx, &f) == MCA_OK) {
        mca_armsim_rx_frame(rx, &f);
        n++;
    }
    if (n == MCA_ARMSIM_RX_BURST) {
        rx->c.rx_burst_full++;
    }
    return n;
}

const mca_arm_command_t *mca_armsim_rx_take(mca_armsim_rx_t *rx, mca_arm_command_t *out) {
    if (!rx || !out || !rx->have_cmd) {
        return NULL;
    }
    *out = rx->cmd;
    rx->have_cmd = 0;
    return out;
}
