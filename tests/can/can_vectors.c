/* SPDX-License-Identifier: MIT */
/* can-vectors: prints frames made by the C codec with the values put in, one per line, for the DBC
 * cross-check (test_dbc.py decodes them with python cantools and encodes the values back):
 *   <Message> <hex payload> <Signal>=<value> ... */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "mca/can_proto.h"

static uint64_t g_x = 0x9E3779B97F4A7C15ull;

static double uni(double lo, double hi) {
    g_x ^= g_x << 13, g_x ^= g_x >> 7, g_x ^= g_x << 17;
    return lo + (hi - lo) * ((double)(g_x >> 11) / 9007199254740992.0);
}

static void hex(const uint8_t *b, size_t n) {
    for (size_t i = 0; i < n; i++) {
        printf("%02x", b[i]);
    }
}

int main(void) {
    uint8_t b[64];
    for (int it = 0; it < 50; it++) {
        mca_arm_command_t c;
        memset(&c, 0, sizeof(c));
        c.n = 1 + it % 8;
        c.frame_id = (uint32_t)(it * 4099u);
        for (int j = 0; j < c.n; j++) {
            c.flags[j] = (uint8_t)(it + j) & 7u;
            c.velocity[j] = uni(-5, 5);
            c.position_ref[j] = uni(-80, 80);
        }
        mca_can_encode_command(&c, (uint8_t)it, b);
        printf("MCA_Command ");
        hex(b, 64);
        printf(" Counter=%d NJoints=%d FrameId=%u", it & 255, c.n, c.frame_id & 0xFFFFu);
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            printf(" Flags%d=%d Vel%d=%.9f PosRef%d=%.9f", j, c.flags[j], j, c.velocity[j], j,
                   c.position_ref[j]);
        }
        printf("\n");

        mca_arm_feedback_t f;
        memset(&f, 0, sizeof(f));
        f.n = 1 + (it + 3) % 8;
        f.frame_id = (uint32_t)(it * 7919u);
        f.state = (mca_arm_state_t)(it % 5);
        f.fault_code = (uint16_t)(it % 6);
        for (int j = 0; j < f.n; j++) {
            f.position[j] = uni(-2000, 2000);
            f.velocity[j] = uni(-3.2, 3.2);
            f.torque[j] = uni(-200, 200);
        }
        mca_can_encode_feedback(&f, (uint8_t)(255 - it), b);
        printf("MCA_Feedback ");
        hex(b, 64);
        printf(" Counter=%d State=%d FaultCode=%d FrameId=%u", 255 - it, (int)f.state, f.fault_code,
               f.frame_id & 0xFFFFu);
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            printf(" Pos%d=%.9f Vel%d=%.9f Tau%d=%.9f", j, f.position[j], j, f.velocity[j], j, f.torque[j]);
        }
        printf("\n");

        mca_can_state_msg_t s = {.state = (uint8_t)(it % 5),
                                 .n = (uint8_t)(1 + it % 8),
                                 .fault_code = (uint16_t)(it % 6),
                                 .missed = (uint16_t)(it * 1311),
                                 .rx_errors = (uint8_t)(it * 37)};
        mca_can_encode_state(&s, (uint8_t)it, b);
        printf("MCA_State ");
        hex(b, 8);
        printf(" Counter=%d State=%d FaultCode=%d Missed=%d NJoints=%d RxErrors=%d\n", it, s.state,
               s.fault_code, s.missed, s.n, s.rx_errors);

        mca_can_fault_msg_t m;
        memset(&m, 0, sizeof(m));
        m.state = (uint8_t)(it % 5);
        m.fault_code = (uint16_t)(it % 6);
        printf("MCA_Fault ");
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            m.fault_flags[j] = (uint16_t)((it * 31 + j * 977) & 0xFFFF);
        }
        mca_can_encode_fault(&m, (uint8_t)(it + 1), b);
        hex(b, 20);
        printf(" Counter=%d State=%d FaultCode=%d", it + 1, m.state, m.fault_code);
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            printf(" FaultFlags%d=%d", j, m.fault_flags[j]);
        }
        printf("\n");
    }
    return 0;
}
