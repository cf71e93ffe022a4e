/* SPDX-License-Identifier: MIT */
/* Fuzz helper: an input as a sequence of CAN frames and operations for the receive sides.
 * Record: op byte, then op-specific bytes (missing bytes read as 0):
 *   op % 4 == 0  frame: id byte (low 4 bits: offset in the arm's block; bit 4: outside the block;
 *                bit 5: EFF; bit 6: RTR; bit 7: classic, not FD), length byte (% 65), that many data bytes
 *   op % 4 == 1  error frame: 4 bytes of CAN_ERR_* class bits (CAN_ERR_FLAG is set)
 *   op % 4 == 2  host step (controller: send a command with frame id +1..+4 and take; emulator: cycle)
 *   op % 4 == 3  time: the next frames' stamp advances by byte * 0.1 ms
 */
#ifndef MCA_FUZZ_FRAMES_H
#define MCA_FUZZ_FRAMES_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <linux/can.h>
#include <linux/can/error.h>

#include "mca/can_sock.h"

typedef struct fuzz_in {
    const uint8_t *p;
    size_t n;
} fuzz_in_t;

static uint8_t fuzz_byte(fuzz_in_t *in) {
    if (!in->n) {
        return 0;
    }
    in->n--;
    return *in->p++;
}

enum { FUZZ_OP_FRAME = 0, FUZZ_OP_ERROR = 1, FUZZ_OP_STEP = 2, FUZZ_OP_TIME = 3 };

/* Next record into f (frame and error ops) or *arg (step/time). @return the op, -1 at the end. */
static int fuzz_next(fuzz_in_t *in, uint32_t base, int64_t *stamp, mca_can_frame_t *f, unsigned *arg) {
    if (!in->n) {
        return -1;
    }
    const int op = fuzz_byte(in) % 4;
    memset(f, 0, sizeof(*f));
    f->stamp_ns = *stamp;
    f->kstamp = 1;
    switch (op) {
    case FUZZ_OP_FRAME: {
        const uint8_t idb = fuzz_byte(in);
        uint32_t id = base + (idb & 0xFu);
        if (idb & 0x10u) {
            id = (id + 0x10u * (1u + (idb >> 5))) & CAN_SFF_MASK;
        }
        f->can_id = id | ((idb & 0x20u) ? CAN_EFF_FLAG : 0u) | ((idb & 0x40u) ? CAN_RTR_FLAG : 0u);
        f->fd = !(idb & 0x80u);
        f->len = (uint8_t)(fuzz_byte(in) % 65u);
        for (unsigned i = 0; i < f->len; i++) {
            f->data[i] = fuzz_byte(in);
        }
        break;
    }
    case FUZZ_OP_ERROR: {
        uint32_t v = 0;
        for (int i = 0; i < 4; i++) {
            v |= (uint32_t)fuzz_byte(in) << (8 * i);
        }
        f->can_id = CAN_ERR_FLAG | (v & CAN_ERR_MASK);
        f->len = 8;
        break;
    }
    case FUZZ_OP_STEP:
        *arg = fuzz_byte(in);
        break;
    default:
        *stamp += (int64_t)fuzz_byte(in) * 100000;
        break;
    }
    return op;
}

#endif
