/* SPDX-License-Identifier: MIT */
/* Fuzz target: the controller side of the CAN protocol (mca_can_link_rx / _take / _sent, mca/arm_can.h)
 * and the codec's decoders, on a sequence of crafted frames (fuzz/frames.h). Checks what the link
 * promises: feedback it returns is finite, of the configured joint count, within +-MCA_CAN_FB_POS_ABS_MAX,
 * never jumps further than MCA_CAN_FB_JUMP_RATE allows, and never answers a command not sent; link_fault
 * is BUS exactly while bus-off; decoded frames re-encode to a frame that decodes to the same values. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h> /* abort */
#include <string.h>

#include "frames.h"
#include "mca/arm_can.h"
#include "mca/can_proto.h"
#include "mca/err.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define CHECK(x)                                                                                             \
    do {                                                                                                     \
        if (!(x)) {                                                                                          \
            abort();                                                                                         \
        }                                                                                                    \
    } while (0)

/* decode -> encode -> decode gives the same command */
static void codec_roundtrip(const mca_can_frame_t *f) {
    mca_arm_command_t c, c2;
    uint8_t ctr, ctr2, buf[64];
    if (mca_can_decode_command(f->data, f->len, &c, &ctr) == MCA_OK) {
        CHECK(c.n >= 1 && c.n <= MCA_MAX_DOF);
        CHECK(mca_can_encode_command(&c, ctr, buf) == MCA_OK);
        CHECK(mca_can_decode_command(buf, 64, &c2, &ctr2) == MCA_OK);
        CHECK(ctr == ctr2 && c.n == c2.n && (uint16_t)c.frame_id == (uint16_t)c2.frame_id);
        for (int j = 0; j < c.n; j++) {
            CHECK(c.velocity[j] == c2.velocity[j] && c.position_ref[j] == c2.position_ref[j]);
            CHECK(c.flags[j] == c2.flags[j]);
        }
    }
    mca_can_state_msg_t s;
    if (mca_can_decode_state(f->data, f->len, &s, &ctr) == MCA_OK) {
        CHECK(s.state <= MCA_ARM_FAULT);
    }
    mca_can_fault_msg_t m;
    if (mca_can_decode_fault(f->data, f->len, &m, &ctr) == MCA_OK) {
        CHECK(m.state <= MCA_ARM_FAULT);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1) {
        return 0;
    }
    fuzz_in_t in = {data, size};
    const int n = 1 + fuzz_byte(&in) % MCA_MAX_DOF;
    const uint32_t base = 0x100;
    mca_can_link_t l;
    CHECK(mca_can_link_init(&l, base, n) == MCA_OK);
    int64_t stamp = 1000000000;
    uint32_t frame_id = 0;
    mca_arm_feedback_t last;
    memset(&last, 0, sizeof last);
    int have_last = 0;
    uint64_t last_received = 0;
    mca_can_frame_t f;
    unsigned arg = 0;
    int op;
    while ((op = fuzz_next(&in, base, &stamp, &f, &arg)) >= 0) {
        if (op == FUZZ_OP_FRAME || op == FUZZ_OP_ERROR) {
            if (op == FUZZ_OP_FRAME) {
                codec_roundtrip(&f);
            }
            CHECK(mca_can_link_rx(&l, &f) != MCA_EINVAL);
            CHECK((l.st.link_fault == MCA_ARM_FAULT_BUS) == (l.st.bus_off != 0));
            continue;
        }
        if (op != FUZZ_OP_STEP) {
            continue;
        }
        mca_arm_feedback_t fb;
        const int rc = mca_can_link_take(&l, &fb);
        CHECK(rc == MCA_OK || rc == MCA_EAGAIN || rc == MCA_EIO);
        if (rc == MCA_OK) {
            CHECK(fb.n == n);
            CHECK(l.st.hb_joints == 0 || l.st.hb_joints == n);
            for (int j = 0; j < n; j++) {
                CHECK(isfinite(fb.position[j]) && isfinite(fb.velocity[j]) && isfinite(fb.torque[j]));
                CHECK(fabs(fb.position[j]) <= MCA_CAN_FB_POS_ABS_MAX);
            }
            CHECK(l.st.commands_sent == 0 || (int32_t)(fb.frame_id - frame_id) <= 0);
            if (have_last) {
                const int64_t dt = fb.stamp_ns - last.stamp_ns > MCA_CAN_FB_JUMP_MIN_DT_NS
                                       ? fb.stamp_ns - last.stamp_ns
                                       : MCA_CAN_FB_JUMP_MIN_DT_NS;
                /* the link bounds each applied frame against the one before (the time floor and the
                 * margin per frame): k frames applied since the last take may add up to k of them */
                const double k = (double)(l.st.feedback_received - last_received);
                const double bound = MCA_CAN_FB_JUMP_RATE * (double)dt * 1e-9 +
                                     k * (MCA_CAN_FB_JUMP_MARGIN + MCA_CAN_FB_JUMP_RATE * 1e-3);
                for (int j = 0; j < n; j++) {
                    CHECK(fabs(fb.position[j] - last.position[j]) <= bound);
                }
                CHECK((int32_t)(fb.frame_id - last.frame_id) >= 0);
            }
            last = fb;
            last_received = l.st.feedback_received;
            have_last = 1;
        }
        /* the controller sends its next command (frame ids may skip, as after a full tx queue) */
        mca_arm_command_t c;
        memset(&c, 0, sizeof c);
        c.n = n;
        frame_id += 1u + (arg & 3u);
        c.frame_id = frame_id;
        uint8_t buf[MCA_CAN_LEN_COMMAND];
        CHECK(mca_can_link_encode(&l, &c, buf) == MCA_OK);
        mca_can_link_sent(&l, &c);
        stamp += 1000000;
    }
    return 0;
}
