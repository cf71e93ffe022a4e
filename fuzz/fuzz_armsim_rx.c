/* SPDX-License-Identifier: MIT */
/* Fuzz target: the firmware emulator's receive side (mca_armsim_rx_frame, mca/armsim_rx.h: the command
 * decoder, the counter rule, the frame-id rule), on a sequence of crafted frames (fuzz/frames.h); a step
 * takes the cycle's command as mca-armsim's firmware cycle does. Checks: a taken command decodes to 1..8
 * joints with finite values, the reference never moves backwards, and never more than
 * MCA_ARMSIM_FRAME_JUMP_MAX ahead unless a run of consecutive frame ids confirmed it. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h> /* abort */

#include "frames.h"
#include "mca/armsim_rx.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define CHECK(x)                                                                                             \
    do {                                                                                                     \
        if (!(x)) {                                                                                          \
            abort();                                                                                         \
        }                                                                                                    \
    } while (0)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    fuzz_in_t in = {data, size};
    const uint32_t base = 0x110;
    mca_armsim_rx_t rx;
    mca_armsim_rx_init(&rx, base);
    int64_t stamp = 0;
    mca_can_frame_t f;
    unsigned arg = 0;
    int op;
    while ((op = fuzz_next(&in, base, &stamp, &f, &arg)) >= 0) {
        if (op == FUZZ_OP_FRAME || op == FUZZ_OP_ERROR) {
            const uint32_t ref = rx.frame_ref;
            const int had_ref = rx.have_ref;
            const int run = rx.jump_run;
            mca_armsim_rx_frame(&rx, &f);
            if (had_ref) {
                const int32_t moved = (int32_t)(rx.frame_ref - ref);
                CHECK(moved >= 0);
                CHECK(moved <= (int32_t)MCA_ARMSIM_FRAME_JUMP_MAX || run == MCA_CAN_SEQ_RESYNC_RUN - 1);
            }
            continue;
        }
        if (op == FUZZ_OP_STEP) {
            mca_arm_command_t c;
            const mca_arm_command_t *cmd = mca_armsim_rx_take(&rx, &c);
            if (cmd) {
                CHECK(cmd->n >= 1 && cmd->n <= MCA_MAX_DOF);
                for (int j = 0; j < cmd->n; j++) {
                    CHECK(isfinite(cmd->velocity[j]) && isfinite(cmd->position_ref[j]));
                }
            }
            CHECK(!rx.have_cmd);
        }
    }
    return 0;
}
