/* SPDX-License-Identifier: MIT */
/* cmocka: the firmware emulator's receive rules (mca/armsim_rx.h) with crafted command frames, through the
 * simulated firmware as mca-armsim runs it (what a hostile peer sends: a forged frame id, a flood). No
 * sockets. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include <linux/can.h>
#include <linux/can/error.h>

#include "mca/armsim_rx.h"
#include "mca/err.h"
#include "mca/sim_arm.h"

#define BASE 0x110u

static mca_can_frame_t cmd_frame(uint8_t ctr, uint32_t frame_id, double v, uint8_t flags) {
    mca_arm_command_t c;
    memset(&c, 0, sizeof(c));
    c.n = 6;
    c.frame_id = frame_id;
    for (int j = 0; j < 6; j++) {
        c.flags[j] = flags;
        c.velocity[j] = v;
    }
    mca_can_frame_t f;
    memset(&f, 0, sizeof(f));
    f.can_id = BASE + MCA_CAN_OFF_COMMAND;
    f.fd = 1;
    f.len = MCA_CAN_LEN_COMMAND;
    assert_int_equal(mca_can_encode_command(&c, ctr, f.data), MCA_OK);
    return f;
}

/* One firmware cycle as mca-armsim runs it: the cycle's command (if any) into mca_sim_arm_cycle(). */
static void fw_cycle(mca_sim_arm_t *arm, mca_armsim_rx_t *rx) {
    mca_arm_command_t c;
    mca_arm_feedback_t fb;
    mca_sim_arm_cycle(arm, mca_armsim_rx_take(rx, &c), 0.001, &fb);
}

static void arm_servoing(mca_sim_arm_t *arm, mca_armsim_rx_t *rx, uint8_t *ctr, uint32_t *id) {
    mca_sim_arm_config_t cfg;
    mca_sim_arm_config_default(&cfg, 6);
    char err[128];
    assert_int_equal(mca_sim_arm_init(arm, &cfg, err, sizeof err), MCA_OK);
    mca_armsim_rx_init(rx, BASE);
    for (int k = 0; k < 10; k++) {
        mca_can_frame_t f = cmd_frame((*ctr)++, (*id)++, 0.01, MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE);
        assert_int_equal(mca_armsim_rx_frame(rx, &f), 1);
        fw_cycle(arm, rx);
    }
    assert_int_equal(arm->state, MCA_ARM_SERVOING);
}

/* Issue 16: one forged command with frame id +32767 (and the right counter) makes none of the next 30
 * genuine commands stale: it is refused for its frame id and the firmware never sees it. Its counter was
 * taken, so the genuine command with the same counter is a repeat (one cycle without a command, below
 * the watchdog's 3); no stale command, no watchdog trip. */
static void test_forged_frame_id(void **state) {
    (void)state;
    static mca_sim_arm_t arm;
    mca_armsim_rx_t rx;
    uint8_t ctr = 0;
    uint32_t id = 1000;
    arm_servoing(&arm, &rx, &ctr, &id);
    const uint64_t stale0 = arm.cnt.cmd_stale;
    assert_int_equal(rx.frame_ref, id - 1);
    mca_can_frame_t forged = cmd_frame(ctr, (id - 1) + 32767u, -0.6, 0);
    assert_int_equal(mca_armsim_rx_frame(&rx, &forged), 0);
    assert_int_equal(rx.c.rx_bad_frame_id, 1);
    assert_int_equal(rx.frame_ref, id - 1); /* the reference did not move */
    for (int k = 0; k < 30; k++) {
        mca_can_frame_t f = cmd_frame(ctr++, id++, 0.01, MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE);
        assert_int_equal(mca_armsim_rx_frame(&rx, &f), k == 0 ? 0 : 1); /* k 0: the forged one's counter */
        fw_cycle(&arm, &rx);
    }
    assert_int_equal(rx.c.rx_bad_counter, 1);
    assert_int_equal(arm.cnt.cmd_stale, stale0);
    assert_int_equal(arm.cnt.watchdog_trips, 0);
    assert_int_equal(arm.state, MCA_ARM_SERVOING);
    /* a forged frame id backwards (-32767) does not drag the reference back either */
    forged = cmd_frame(ctr++, id - 32767u, -0.6, 0);
    mca_armsim_rx_frame(&rx, &forged);
    fw_cycle(&arm, &rx); /* the firmware counts it stale */
    for (int k = 0; k < 30; k++) {
        mca_can_frame_t f = cmd_frame(ctr++, id++, 0.01, MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE);
        assert_int_equal(mca_armsim_rx_frame(&rx, &f), 1);
        fw_cycle(&arm, &rx);
    }
    assert_int_equal(arm.cnt.cmd_stale, stale0 + 1);
    assert_int_equal(arm.cnt.watchdog_trips, 0);
    assert_int_equal(arm.state, MCA_ARM_SERVOING);
}

/* A genuine jump of the frame ids (more than MCA_ARMSIM_FRAME_JUMP_MAX commands not sent) is taken after a
 * run of MCA_CAN_SEQ_RESYNC_RUN consecutive ids; a small gap at once. */
static void test_frame_id_jump(void **state) {
    (void)state;
    mca_armsim_rx_t rx;
    mca_armsim_rx_init(&rx, BASE);
    mca_arm_command_t c;
    mca_can_frame_t f = cmd_frame(0, 10, 0, 0);
    assert_int_equal(mca_armsim_rx_frame(&rx, &f), 1);
    f = cmd_frame(1, 10 + MCA_ARMSIM_FRAME_JUMP_MAX, 0, 0);
    assert_int_equal(mca_armsim_rx_frame(&rx, &f), 1);
    assert_non_null(mca_armsim_rx_take(&rx, &c));
    assert_int_equal(c.frame_id, 10 + MCA_ARMSIM_FRAME_JUMP_MAX);
    const uint32_t far = 5000;
    f = cmd_frame(2, far, 0, 0);
    assert_int_equal(mca_armsim_rx_frame(&rx, &f), 0);
    f = cmd_frame(3, far + 1, 0, 0);
    assert_int_equal(mca_armsim_rx_frame(&rx, &f), 0);
    f = cmd_frame(4, far + 2, 0, 0);
    assert_int_equal(mca_armsim_rx_frame(&rx, &f), 1);
    assert_non_null(mca_armsim_rx_take(&rx, &c));
    assert_int_equal(c.frame_id, far + 2);
    assert_int_equal(rx.frame_ref, far + 2);
    assert_int_equal(rx.c.rx_bad_frame_id, 2);
    /* an older command in the same cycle does not supersede the newer one */
    f = cmd_frame(5, far + 4, 0, 0);
    assert_int_equal(mca_armsim_rx_frame(&rx, &f), 1);
    f = cmd_frame(6, far + 3, 0, 0);
    assert_int_equal(mca_armsim_rx_frame(&rx, &f), 0);
    assert_non_null(mca_armsim_rx_take(&rx, &c));
    assert_int_equal(c.frame_id, far + 4);
    assert_null(mca_armsim_rx_take(&rx, &c));
}

typedef struct flood {
    int left;
    uint8_t ctr;
} flood_t;

static int flood_recv(void *ctx, mca_can_frame_t *f) {
    flood_t *fl = ctx;
    if (fl->left <= 0) {
        return MCA_EAGAIN;
    }
    fl->left--;
    *f = cmd_frame(fl->ctr++, 7, 0, 0);
    return MCA_OK;
}

/* Issue 16: a flood of frames cannot starve the firmware cycle: one drain takes at most
 * MCA_ARMSIM_RX_BURST frames. */
static void test_drain_bound(void **state) {
    (void)state;
    mca_armsim_rx_t rx;
    mca_armsim_rx_init(&rx, BASE);
    flood_t fl = {100000, 0};
    assert_int_equal(mca_armsim_rx_drain(&rx, flood_recv, &fl), MCA_ARMSIM_RX_BURST);
    assert_int_equal(fl.left, 100000 - MCA_ARMSIM_RX_BURST);
    assert_int_equal(rx.c.rx_burst_full, 1);
    assert_int_equal(rx.c.frames_rx, MCA_ARMSIM_RX_BURST);
    fl.left = 3;
    assert_int_equal(mca_armsim_rx_drain(&rx, flood_recv, &fl), 3);
    assert_int_equal(rx.c.rx_burst_full, 1);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_forged_frame_id),
        cmocka_unit_test(test_frame_id_jump),
        cmocka_unit_test(test_drain_bound),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
