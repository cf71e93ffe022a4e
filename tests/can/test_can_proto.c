/* SPDX-License-Identifier: MIT */
/* cmocka: mca CAN protocol codec and the controller-side link (no sockets).
 * Truth: byte layouts computed by hand from docs/can-protocol.md, the fixed-point definition, and the
 * counter rule stated in mca/can_proto.h. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <math.h>

#include <cmocka.h>

#include <linux/can.h>
#include <linux/can/error.h>

#include "mca/arm_can.h"
#include "mca/can_proto.h"
#include "mca/err.h"

static uint32_t le32(const uint8_t *b) {
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static void test_command_layout(void **state) {
    (void)state;
    mca_arm_command_t c;
    memset(&c, 0, sizeof(c));
    c.n = 3;
    c.frame_id = 0x12345678u;
    c.flags[0] = MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE; /* 3 */
    c.flags[1] = MCA_ACT_CLEAR_FAULT;                          /* 4 */
    c.flags[2] = 0xF7;                                         /* only 4 bits travel: 7 */
    c.velocity[0] = 1.0;                                       /* 1000000 = 0x000F4240 */
    c.velocity[1] = -0.0000024;                                /* -2.4 -> -2 = 0xFFFFFFFE */
    c.velocity[2] = 1e9;                                       /* saturates at INT32_MAX */
    c.position_ref[0] = -1.0;                                  /* -100000 -> int24 0xFE7960 */
    c.position_ref[1] = 1000.0;                                /* saturates at 0x7FFFFF */
    uint8_t b[64];
    assert_int_equal(mca_can_encode_command(&c, 0xAB, b), MCA_OK);
    assert_int_equal(b[0], 0xAB);
    assert_int_equal(b[1], 3);
    assert_int_equal(b[2], 0x78);
    assert_int_equal(b[3], 0x56);
    assert_int_equal(b[4], 0x43); /* joint0 = 3 (low nibble), joint1 = 4 (high nibble) */
    assert_int_equal(b[5], 0x07);
    assert_int_equal(le32(b + 8), 0x000F4240u);
    assert_int_equal(le32(b + 12), 0xFFFFFFFEu);
    assert_int_equal(le32(b + 16), 0x7FFFFFFFu);
    assert_int_equal(le32(b + 20), 0u); /* joint 3 unused */
    assert_int_equal(b[40], 0x60);
    assert_int_equal(b[41], 0x79);
    assert_int_equal(b[42], 0xFE);
    assert_int_equal(b[43], 0xFF);
    assert_int_equal(b[44], 0xFF);
    assert_int_equal(b[45], 0x7F);

    mca_arm_command_t d;
    uint8_t ctr = 0;
    assert_int_equal(mca_can_decode_command(b, 64, &d, &ctr), MCA_OK);
    assert_int_equal(ctr, 0xAB);
    assert_int_equal(d.n, 3);
    assert_int_equal(d.frame_id, 0x5678u);
    assert_int_equal(d.flags[0], 3);
    assert_int_equal(d.flags[1], 4);
    assert_int_equal(d.flags[2], 7);
    assert_true(d.velocity[0] == 1.0);
    assert_true(fabs(d.velocity[1] + 2e-6) < 1e-15);
    assert_true(fabs(d.velocity[2] - 2147.483647) < 1e-9);
    assert_true(fabs(d.position_ref[0] + 1.0) < 1e-12);
    assert_true(fabs(d.position_ref[1] - 83.88607) < 1e-9);
}

static void test_command_bad(void **state) {
    (void)state;
    mca_arm_command_t c;
    memset(&c, 0, sizeof(c));
    uint8_t b[64];
    c.n = 0;
    assert_int_equal(mca_can_encode_command(&c, 0, b), MCA_EINVAL);
    c.n = 9;
    assert_int_equal(mca_can_encode_command(&c, 0, b), MCA_EINVAL);
    c.n = 2;
    c.velocity[1] = NAN;
    assert_int_equal(mca_can_encode_command(&c, 0, b), MCA_EINVAL);
    c.velocity[1] = 0;
    assert_int_equal(mca_can_encode_command(&c, 0, b), MCA_OK);
    mca_arm_command_t d;
    assert_int_equal(mca_can_decode_command(b, 63, &d, NULL), MCA_EINVAL);
    assert_int_equal(mca_can_decode_command(b, 8, &d, NULL), MCA_EINVAL);
    b[1] = 0;
    assert_int_equal(mca_can_decode_command(b, 64, &d, NULL), MCA_EINVAL);
    b[1] = 9;
    assert_int_equal(mca_can_decode_command(b, 64, &d, NULL), MCA_EINVAL);
}

static void test_feedback_layout(void **state) {
    (void)state;
    mca_arm_feedback_t f;
    memset(&f, 0, sizeof(f));
    f.n = 8;
    f.frame_id = 0x1BEEF;
    f.state = MCA_ARM_BRAKING;
    f.fault_code = MCA_ARM_FAULT_WATCHDOG;
    f.position[0] = 3.141593;  /* 3141593 = 0x002FEFD9 */
    f.position[7] = -0.000001; /* -1 */
    f.velocity[0] = -0.5;      /* -5000 = 0xEC78 */
    f.velocity[7] = 10.0;      /* saturates 32767 */
    f.torque[0] = 1.0;         /* 10 = 0x00A */
    f.torque[1] = -0.1;        /* -1 = 0xFFF */
    f.torque[7] = -1000;       /* saturates -2048 = 0x800 */
    uint8_t b[64];
    assert_int_equal(mca_can_encode_feedback(&f, 7, b), MCA_OK);
    assert_int_equal(b[0], 7);
    assert_int_equal(b[1], 0x13); /* state 3 | code 1 << 4 */
    assert_int_equal(b[2], 0xEF);
    assert_int_equal(b[3], 0xBE);
    assert_int_equal(le32(b + 4), 0x002FEFD9u);
    assert_int_equal(le32(b + 32), 0xFFFFFFFFu);
    assert_int_equal(b[36], 0x78);
    assert_int_equal(b[37], 0xEC);
    assert_int_equal(b[50], 0xFF);
    assert_int_equal(b[51], 0x7F);
    /* torques: 12 bits each from byte 52: j0 = 0x00A, j1 = 0xFFF -> bytes 0x0A, 0xF0, 0xFF */
    assert_int_equal(b[52], 0x0A);
    assert_int_equal(b[53], 0xF0);
    assert_int_equal(b[54], 0xFF);
    /* j7 occupies bits 84..95 of the torque field = high nibble of byte 62 and byte 63: 0x800 */
    assert_int_equal(b[62] >> 4, 0x0);
    assert_int_equal(b[63], 0x80);

    mca_arm_feedback_t d;
    memset(&d, 0, sizeof(d));
    d.fault_flags[2] = 0x55;
    d.stamp_ns = 42;
    uint8_t ctr;
    assert_int_equal(mca_can_decode_feedback(b, 64, 8, &d, &ctr), MCA_OK);
    assert_int_equal(ctr, 7);
    assert_int_equal(d.frame_id, 0xBEEF);
    assert_int_equal(d.state, MCA_ARM_BRAKING);
    assert_int_equal(d.fault_code, 1);
    assert_true(fabs(d.position[0] - 3.141593) < 1e-12);
    assert_true(fabs(d.position[7] + 1e-6) < 1e-15);
    assert_true(fabs(d.velocity[0] + 0.5) < 1e-12);
    assert_true(fabs(d.velocity[7] - 3.2767) < 1e-12);
    assert_true(fabs(d.torque[0] - 1.0) < 1e-12);
    assert_true(fabs(d.torque[1] + 0.1) < 1e-12);
    assert_true(fabs(d.torque[7] + 204.8) < 1e-9);
    assert_int_equal(d.fault_flags[2], 0x55); /* untouched: comes from the fault frame */
    assert_int_equal(d.stamp_ns, 42);
    b[1] = 0x05; /* state 5 does not exist */
    assert_int_equal(mca_can_decode_feedback(b, 64, 8, &d, NULL), MCA_EINVAL);
    assert_int_equal(mca_can_decode_feedback(b, 48, 8, &d, NULL), MCA_EINVAL);
}

/* Round trip of many values: |decoded - value| <= scale / 2 inside the range (fixed-point definition). */
static void test_roundtrip_resolution(void **state) {
    (void)state;
    uint64_t x = 88172645463325252ull;
    for (int it = 0; it < 2000; it++) {
        mca_arm_feedback_t f, d;
        memset(&f, 0, sizeof(f));
        f.n = 1 + it % 8;
        for (int j = 0; j < f.n; j++) {
            x ^= x << 13, x ^= x >> 7, x ^= x << 17;
            double u = (double)(x >> 11) / 9007199254740992.0 * 2.0 - 1.0;
            f.position[j] = 2000.0 * u;
            f.velocity[j] = 3.2 * u;
            f.torque[j] = 200.0 * u;
        }
        uint8_t b[64];
        assert_int_equal(mca_can_encode_feedback(&f, 0, b), MCA_OK);
        assert_int_equal(mca_can_decode_feedback(b, 64, f.n, &d, NULL), MCA_OK);
        for (int j = 0; j < f.n; j++) {
            assert_true(fabs(d.position[j] - f.position[j]) <= 0.5e-6 * (1 + 1e-6));
            assert_true(fabs(d.velocity[j] - f.velocity[j]) <= 0.5e-4 * (1 + 1e-9));
            assert_true(fabs(d.torque[j] - f.torque[j]) <= 0.05 * (1 + 1e-9));
        }
    }
}

static void test_state_fault_frames(void **state) {
    (void)state;
    mca_can_state_msg_t s = {.state = MCA_ARM_FAULT, .n = 6, .fault_code = 1, .missed = 300, .rx_errors = 9};
    uint8_t b[64];
    assert_int_equal(mca_can_encode_state(&s, 200, b), MCA_OK);
    const uint8_t want[8] = {200, 4, 1, 0, 0x2C, 0x01, 6, 9};
    assert_memory_equal(b, want, 8);
    mca_can_state_msg_t s2;
    uint8_t ctr;
    assert_int_equal(mca_can_decode_state(b, 8, &s2, &ctr), MCA_OK);
    assert_int_equal(ctr, 200);
    assert_int_equal(s2.missed, 300);
    assert_int_equal(mca_can_decode_state(b, 12, &s2, &ctr), MCA_EINVAL);

    mca_can_fault_msg_t m;
    memset(&m, 0, sizeof(m));
    m.state = MCA_ARM_BRAKING;
    m.fault_code = 2;
    m.fault_flags[0] = 0x0102;
    m.fault_flags[7] = 0x8001;
    assert_int_equal(mca_can_encode_fault(&m, 1, b), MCA_OK);
    assert_int_equal(b[4], 0x02);
    assert_int_equal(b[5], 0x01);
    assert_int_equal(b[18], 0x01);
    assert_int_equal(b[19], 0x80);
    mca_can_fault_msg_t m2;
    assert_int_equal(mca_can_decode_fault(b, 20, &m2, &ctr), MCA_OK);
    assert_memory_equal(m.fault_flags, m2.fault_flags, sizeof(m.fault_flags));
    assert_int_equal(mca_can_decode_fault(b, 24, &m2, &ctr), MCA_EINVAL);
}

static void test_seq(void **state) {
    (void)state;
    mca_can_seq_t s;
    mca_can_seq_reset(&s);
    assert_int_equal(mca_can_seq_accept(&s, 250), 1); /* first frame syncs */
    for (unsigned c = 251; c < 256 + 10; c++) {
        assert_int_equal(mca_can_seq_accept(&s, (uint8_t)c), 1); /* wraps 255 -> 0 */
    }
    /* last = 9. A stray frame costs nothing: */
    assert_int_equal(mca_can_seq_accept(&s, 77), 0);
    assert_int_equal(mca_can_seq_accept(&s, 10), 1);
    /* repeat (stale) is rejected, the stream goes on */
    assert_int_equal(mca_can_seq_accept(&s, 10), 0);
    assert_int_equal(mca_can_seq_accept(&s, 11), 1);
    /* a real loss (12 lost): 13 and 14 rejected, 15 completes the run of MCA_CAN_SEQ_RESYNC_RUN and resyncs
     */
    assert_int_equal(mca_can_seq_accept(&s, 13), 0);
    assert_int_equal(mca_can_seq_accept(&s, 14), 0);
    assert_int_equal(mca_can_seq_accept(&s, 15), 1);
    assert_int_equal(mca_can_seq_accept(&s, 16), 1);
    /* old frame replayed twice in a row (non-consecutive) never gets in */
    assert_int_equal(mca_can_seq_accept(&s, 3), 0);
    assert_int_equal(mca_can_seq_accept(&s, 3), 0);
    assert_int_equal(mca_can_seq_accept(&s, 17), 1);
}

/* Issue 16: a forged pair of consecutive counters (c, c+1) neither gets in nor resyncs the stream; the
 * genuine next frame is accepted and drops the candidate run. */
static void test_seq_forged_pair(void **state) {
    (void)state;
    mca_can_seq_t s;
    mca_can_seq_reset(&s);
    assert_int_equal(mca_can_seq_accept(&s, 10), 1);
    assert_int_equal(mca_can_seq_accept(&s, 11), 1);
    assert_int_equal(mca_can_seq_accept(&s, 200), 0); /* forged */
    assert_int_equal(mca_can_seq_accept(&s, 201), 0); /* forged, continues it: no resync (was accepted) */
    assert_int_equal(mca_can_seq_accept(&s, 12), 1);  /* genuine */
    assert_int_equal(mca_can_seq_accept(&s, 202), 0); /* the forged run was dropped by the genuine frame */
    assert_int_equal(mca_can_seq_accept(&s, 13), 1);
    assert_int_equal(s.last, 13);
    /* wrap: 255 -> 0 -> 1 as a run */
    assert_int_equal(mca_can_seq_accept(&s, 255), 0);
    assert_int_equal(mca_can_seq_accept(&s, 0), 0);
    assert_int_equal(mca_can_seq_accept(&s, 1), 1);
}

static void test_unwrap16(void **state) {
    (void)state;
    assert_int_equal(mca_can_unwrap16(100, 100), 100u);
    assert_int_equal(mca_can_unwrap16(100, 99), 99u);
    assert_int_equal(mca_can_unwrap16(0x1FFFFu, 0x0001), 0x20001u);
    assert_int_equal(mca_can_unwrap16(0x20001u, 0xFFFF), 0x1FFFFu);
    assert_int_equal(mca_can_unwrap16(0x12345678u, 0x5670), 0x12345670u);
    assert_int_equal(mca_can_unwrap16(5, 0xFFFE), 0xFFFFFFFEu); /* wraps below 0 as serial numbers do */
}

static mca_can_frame_t fb_frame(uint32_t base, uint8_t ctr, uint32_t frame_id, double q0, int n) {
    mca_arm_feedback_t f;
    memset(&f, 0, sizeof(f));
    f.n = n;
    f.frame_id = frame_id;
    f.state = MCA_ARM_SERVOING;
    f.position[0] = q0;
    mca_can_frame_t fr;
    memset(&fr, 0, sizeof(fr));
    fr.can_id = base + MCA_CAN_OFF_FEEDBACK;
    fr.fd = 1;
    fr.len = 64;
    fr.stamp_ns = 1000 + ctr;
    mca_can_encode_feedback(&f, ctr, fr.data);
    return fr;
}

static void test_link(void **state) {
    (void)state;
    mca_can_link_t l;
    assert_int_equal(mca_can_link_init(&l, 0x105, 6), MCA_EINVAL); /* not a block start */
    assert_int_equal(mca_can_link_init(&l, 0x100, 9), MCA_EINVAL);
    assert_int_equal(mca_can_link_init(&l, 0x100, 6), MCA_OK);
    mca_arm_feedback_t fb;
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EAGAIN);

    /* commands: counter advances only when sent; frame id recorded for unwrapping */
    mca_arm_command_t c;
    memset(&c, 0, sizeof(c));
    c.n = 6;
    c.frame_id = 0x10005;
    uint8_t b[64];
    assert_int_equal(mca_can_link_encode(&l, &c, b), MCA_OK);
    assert_int_equal(b[0], 0);
    mca_can_link_sent(&l, &c);
    assert_int_equal(mca_can_link_encode(&l, &c, b), MCA_OK);
    assert_int_equal(b[0], 1);
    c.n = 5;
    assert_int_equal(mca_can_link_encode(&l, &c, b), MCA_EINVAL);

    mca_can_frame_t f = fb_frame(0x100, 0, 0x10004, 0.25, 6);
    f.kstamp = 1; /* kernel time stamp; the frames below carry the user-space fallback (kstamp 0) */
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    assert_int_equal(l.st.rx_stamp_kernel, 1);
    assert_int_equal(l.st.rx_stamp_user, 0);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_OK);
    assert_int_equal(fb.frame_id, 0x10004u); /* unwrapped against 0x10005 */
    assert_true(fabs(fb.position[0] - 0.25) < 1e-12);
    assert_int_equal(fb.stamp_ns, 1000);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EAGAIN);

    /* wrong length (classic frame, 8 bytes), CAN FD 48 bytes: counted, not applied */
    mca_can_frame_t bad = fb_frame(0x100, 1, 0x10005, 3.0, 6);
    bad.fd = 0;
    bad.len = 8;
    assert_int_equal(mca_can_link_rx(&l, &bad), MCA_EAGAIN);
    bad.fd = 1;
    bad.len = 48;
    assert_int_equal(mca_can_link_rx(&l, &bad), MCA_EAGAIN);
    /* bad counter (skipped), unknown id in the block, extended id, our own command id */
    bad = fb_frame(0x100, 9, 0x10005, 3.0, 6);
    assert_int_equal(mca_can_link_rx(&l, &bad), MCA_EAGAIN);
    bad = fb_frame(0x100, 1, 0x10005, 3.0, 6);
    bad.can_id = 0x107;
    assert_int_equal(mca_can_link_rx(&l, &bad), MCA_EAGAIN);
    bad.can_id = 0x101 | CAN_EFF_FLAG;
    assert_int_equal(mca_can_link_rx(&l, &bad), MCA_EAGAIN);
    bad.can_id = 0x100;
    assert_int_equal(mca_can_link_rx(&l, &bad), MCA_EAGAIN);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EAGAIN); /* nothing was applied */
    mca_arm_stats_t st = l.st;
    assert_int_equal(st.rx_bad_length, 2);
    assert_int_equal(st.rx_bad_counter, 1);
    assert_int_equal(st.rx_unknown_id, 3);
    assert_int_equal(st.feedback_received, 1);
    assert_int_equal(st.rx_stamp_kernel + st.rx_stamp_user, 1); /* ignored frames are not counted */

    /* the genuine next frame is still accepted after the stray counter (positions move by at most
     * MCA_CAN_FB_JUMP_RATE between frames: the stamps here are 1 ns apart, taken as 1 ms) */
    f = fb_frame(0x100, 1, 0x10005, 0.255, 6);
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_OK);
    assert_true(fabs(fb.position[0] - 0.255) < 1e-12);

    /* fault frame flags reach the next feedback */
    mca_can_fault_msg_t fm;
    memset(&fm, 0, sizeof(fm));
    fm.fault_flags[3] = MCA_ACT_FLT_LIMIT_LOW;
    mca_can_frame_t ff;
    memset(&ff, 0, sizeof(ff));
    ff.can_id = 0x103;
    ff.fd = 1;
    ff.len = 20;
    mca_can_encode_fault(&fm, 0, ff.data);
    assert_int_equal(mca_can_link_rx(&l, &ff), MCA_OK);
    f = fb_frame(0x100, 2, 0x10005, 0.255, 6);
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_OK);
    assert_int_equal(fb.fault_flags[3], MCA_ACT_FLT_LIMIT_LOW);

    /* error frames: counted, EIO once; bus-off holds EIO until feedback gets through */
    mca_can_frame_t ef;
    memset(&ef, 0, sizeof(ef));
    ef.can_id = CAN_ERR_FLAG | CAN_ERR_PROT;
    ef.len = 8;
    assert_int_equal(mca_can_link_rx(&l, &ef), MCA_OK);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EIO);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EAGAIN);
    assert_int_equal(l.st.bus_off_events, 0);
    assert_int_equal(l.st.link_fault, MCA_ARM_FAULT_NONE);
    ef.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
    assert_int_equal(mca_can_link_rx(&l, &ef), MCA_OK);
    assert_int_equal(l.st.bus_off, 1);
    assert_int_equal(l.st.bus_off_events, 1);
    assert_int_equal(l.st.link_fault, MCA_ARM_FAULT_BUS);
    assert_string_equal(mca_arm_fault_name(l.st.link_fault), "BUS");
    assert_int_equal(mca_can_link_rx(&l, &ef), MCA_OK); /* still bus-off: not a new event */
    assert_int_equal(l.st.bus_off_events, 1);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EIO);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EIO);
    f = fb_frame(0x100, 3, 0x10005, 0.26, 6);
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    assert_int_equal(l.st.bus_off, 0);
    assert_int_equal(l.st.link_fault, MCA_ARM_FAULT_NONE);
    fb.position[0] = 0;
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_OK); /* error already reported */
    assert_true(fabs(fb.position[0] - 0.26) < 1e-12);
    assert_int_equal(l.st.bus_errors, 3);
    /* a restarted controller (CAN_ERR_RESTARTED) does not end bus-off (a restart proves no frame got
     * through): only feedback does; a second bus-off is a second event */
    ef.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
    assert_int_equal(mca_can_link_rx(&l, &ef), MCA_OK);
    ef.can_id = CAN_ERR_FLAG | CAN_ERR_RESTARTED;
    assert_int_equal(mca_can_link_rx(&l, &ef), MCA_OK);
    assert_int_equal(l.st.bus_off, 1);
    assert_int_equal(l.st.bus_off_events, 2);
    assert_int_equal(l.st.link_fault, MCA_ARM_FAULT_BUS);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EIO);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EIO); /* while bus-off */
    f = fb_frame(0x100, 4, 0x10005, 0.26, 6);
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    assert_int_equal(l.st.bus_off, 0);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_OK);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EAGAIN);
    assert_int_equal(l.st.rx_stamp_kernel, 1);
    assert_int_equal(l.st.rx_stamp_user, 4);
}

/* A link of 6 joints that has sent one command (frame id 100) and applied one feedback (q = 0.1 rad,
 * counter 0, stamp 1 s). */
static void link_ready(mca_can_link_t *l) {
    assert_int_equal(mca_can_link_init(l, 0x100, 6), MCA_OK);
    mca_arm_command_t c;
    memset(&c, 0, sizeof(c));
    c.n = 6;
    c.frame_id = 100;
    mca_can_link_sent(l, &c);
    mca_can_frame_t f = fb_frame(0x100, 0, 100, 0.1, 6);
    f.stamp_ns = 1000000000;
    assert_int_equal(mca_can_link_rx(l, &f), MCA_OK);
    mca_arm_feedback_t fb;
    assert_int_equal(mca_can_link_take(l, &fb), MCA_OK);
}

/* Issue 16: feedback of 2147 rad (the saturated field, or inside it but beyond the bounds), and a jump
 * from 2147 to -1 rad in one frame, is never applied: refused at the link, counted, named. */
static void test_link_feedback_implausible(void **state) {
    (void)state;
    mca_can_link_t l;
    mca_arm_feedback_t fb;
    link_ready(&l);
    /* saturated: +2147.483647 rad (INT32_MAX) */
    mca_can_frame_t f = fb_frame(0x100, 1, 100, 1e9, 6);
    f.stamp_ns = 1001000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_EAGAIN);
    assert_int_equal(l.st.rx_implausible, 1);
    assert_int_equal(l.st.implausible_kind, MCA_CAN_FB_SATURATED);
    assert_string_equal(mca_can_fb_check_name(l.st.implausible_kind), "SATURATED");
    assert_int_equal(l.st.link_fault, MCA_ARM_FAULT_FEEDBACK);
    assert_string_equal(mca_arm_fault_name(l.st.link_fault), "FEEDBACK");
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EIO); /* reported once as a link error */
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EAGAIN);
    /* 2147.0 rad: inside the field, outside the bounds (default +-MCA_CAN_FB_POS_ABS_MAX) */
    f = fb_frame(0x100, 2, 100, 2147.0, 6);
    f.stamp_ns = 1002000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_EAGAIN);
    assert_int_equal(l.st.implausible_kind, MCA_CAN_FB_POSITION);
    /* a jump 0.1 -> -1 rad within 1 ms (bound 6.55 rad/s x 1 ms + 0.01 rad) */
    f = fb_frame(0x100, 3, 100, -1.0, 6);
    f.stamp_ns = 1003000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_EAGAIN);
    assert_int_equal(l.st.implausible_kind, MCA_CAN_FB_JUMP);
    assert_int_equal(l.st.rx_implausible, 3);
    assert_int_equal(l.st.feedback_received, 1);
    /* with the bounds of a real arm, 2147 and the jump from there to -1 (had 2147 been in) are refused */
    double lo[6] = {-3.2, -3.2, -3.2, -3.2, -3.2, -3.2}, hi[6] = {3.2, 3.2, 3.2, 3.2, 3.2, 3.2};
    assert_int_equal(mca_can_link_set_bounds(&l, lo, hi), MCA_OK);
    f = fb_frame(0x100, 4, 100, 2147.0, 6);
    f.stamp_ns = 1004000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_EAGAIN);
    assert_int_equal(l.st.implausible_kind, MCA_CAN_FB_POSITION);
    /* the same -1 rad after 0.5 s is a plausible move (6.55 rad/s x 0.5 s): applied, fault cleared */
    f = fb_frame(0x100, 5, 100, -1.0, 6);
    f.stamp_ns = 1500000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    assert_int_equal(l.st.link_fault, MCA_ARM_FAULT_NONE);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_OK);
    assert_true(fabs(fb.position[0] + 1.0) < 1e-12);
    /* bad bounds */
    lo[2] = 4.0;
    assert_int_equal(mca_can_link_set_bounds(&l, lo, hi), MCA_EINVAL);
    /* the joint's own rate (1.5 rad/s): -1 -> -0.5 rad after 0.1 s passes the default 6.55 rad/s x 0.1 s but
     * not 1.5 x 0.1 + 0.01, and stays refused frame after frame until 0.33 s have gone by (seen in the guest:
     * a persistent 0.5 rad lie passed after 75 ms of refused frames with the default rate) */
    const double vmax[6] = {1.5, 1.5, 1.5, 1.5, 1.5, 1.5};
    assert_int_equal(mca_can_link_set_rate(&l, vmax), MCA_OK);
    f = fb_frame(0x100, 6, 100, -0.5, 6);
    f.stamp_ns = 1600000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_EAGAIN);
    assert_int_equal(l.st.implausible_kind, MCA_CAN_FB_JUMP);
    f = fb_frame(0x100, 7, 100, -0.5, 6);
    f.stamp_ns = 1800000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_EAGAIN);
    f = fb_frame(0x100, 8, 100, -0.5, 6);
    f.stamp_ns = 1840000000; /* 0.34 s after the last applied: 1.5 x 0.34 + 0.01 = 0.52 > 0.5 */
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    const double nan_rate[6] = {NAN, 1, 1, 1, 1, 1};
    assert_int_equal(mca_can_link_set_rate(&l, nan_rate), MCA_EINVAL);
    assert_int_equal(mca_can_link_set_rate(NULL, vmax), MCA_EINVAL);
}

/* Issue 16: the feedback's frame id is compared with the last command sent (ahead: refused) and with the
 * last applied feedback (backwards: refused). */
static void test_link_feedback_frame_id(void **state) {
    (void)state;
    mca_can_link_t l;
    mca_arm_feedback_t fb;
    link_ready(&l);
    mca_can_frame_t f = fb_frame(0x100, 1, 101, 0.1, 6); /* answers frame 101, only 100 was sent */
    f.stamp_ns = 1001000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_EAGAIN);
    assert_int_equal(l.st.implausible_kind, MCA_CAN_FB_FRAME_AHEAD);
    f = fb_frame(0x100, 2, 99, 0.1, 6); /* behind the applied feedback's 100 */
    f.stamp_ns = 1002000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_EAGAIN);
    assert_int_equal(l.st.implausible_kind, MCA_CAN_FB_FRAME_BACKWARDS);
    assert_string_equal(mca_can_fb_check_name(l.st.implausible_kind), "FRAME_BACKWARDS");
    f = fb_frame(0x100, 3, 100, 0.1, 6); /* the same command again (the arm missed the next): fine */
    f.stamp_ns = 1003000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_OK);
    assert_int_equal(fb.frame_id, 100u);
    assert_int_equal(l.st.rx_implausible, 2);
}

static mca_can_frame_t state_frame(uint8_t ctr, uint8_t n) {
    mca_can_state_msg_t m = {.state = MCA_ARM_SERVOING, .n = n};
    mca_can_frame_t f;
    memset(&f, 0, sizeof(f));
    f.can_id = 0x102;
    f.fd = 1;
    f.len = MCA_CAN_LEN_STATE;
    mca_can_encode_state(&m, ctr, f.data);
    return f;
}

/* Issue 16: the heartbeat's joint count is checked against the configured arm: another count is a named
 * link fault and no feedback gets through while it lasts. */
static void test_link_heartbeat_joints(void **state) {
    (void)state;
    mca_can_link_t l;
    mca_arm_feedback_t fb;
    link_ready(&l);
    mca_can_frame_t h = state_frame(0, 7);
    assert_int_equal(mca_can_link_rx(&l, &h), MCA_OK);
    assert_int_equal(l.st.rx_bad_joints, 1);
    assert_int_equal(l.st.hb_joints, 7);
    assert_int_equal(l.st.link_fault, MCA_ARM_FAULT_JOINT_COUNT);
    assert_string_equal(mca_arm_fault_name(l.st.link_fault), "JOINT_COUNT");
    mca_can_frame_t f = fb_frame(0x100, 1, 100, 0.1, 6);
    f.stamp_ns = 1001000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EIO); /* feedback of a 7-joint arm: not handed on */
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EIO);
    h = state_frame(1, 6); /* the arm's heartbeat agrees again */
    assert_int_equal(mca_can_link_rx(&l, &h), MCA_OK);
    assert_int_equal(l.st.link_fault, MCA_ARM_FAULT_NONE);
    f = fb_frame(0x100, 2, 100, 0.1, 6);
    f.stamp_ns = 1002000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_OK);
}

/* Issue 16: an error frame that says BUSOFF and RESTARTED at once takes the link down (BUS) until feedback
 * gets through. */
static void test_link_busoff_restarted(void **state) {
    (void)state;
    mca_can_link_t l;
    mca_arm_feedback_t fb;
    link_ready(&l);
    mca_can_frame_t ef;
    memset(&ef, 0, sizeof(ef));
    ef.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED;
    ef.len = 8;
    assert_int_equal(mca_can_link_rx(&l, &ef), MCA_OK);
    assert_int_equal(l.st.bus_off, 1);
    assert_int_equal(l.st.bus_off_events, 1);
    assert_int_equal(l.st.link_fault, MCA_ARM_FAULT_BUS);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(mca_can_link_take(&l, &fb), MCA_EIO);
    }
    mca_can_frame_t f = fb_frame(0x100, 1, 100, 0.1, 6);
    f.stamp_ns = 1001000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
    assert_int_equal(l.st.bus_off, 0);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_OK);
}

/* Issue 16: a forged pair of feedback frames with consecutive counters does not resync the stream: none
 * of the forged frames is applied and the genuine stream goes on. */
static void test_link_forged_counter_pair(void **state) {
    (void)state;
    mca_can_link_t l;
    mca_arm_feedback_t fb;
    link_ready(&l);
    mca_can_frame_t f = fb_frame(0x100, 77, 100, 0.11, 6);
    f.stamp_ns = 1001000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_EAGAIN);
    f = fb_frame(0x100, 78, 100, 0.11, 6);
    f.stamp_ns = 1001000000;
    assert_int_equal(mca_can_link_rx(&l, &f), MCA_EAGAIN);
    assert_int_equal(mca_can_link_take(&l, &fb), MCA_EAGAIN);
    for (uint8_t c = 1; c < 5; c++) {
        f = fb_frame(0x100, c, 100, 0.1, 6);
        f.stamp_ns = 1001000000 + c * 1000000;
        assert_int_equal(mca_can_link_rx(&l, &f), MCA_OK);
        assert_int_equal(mca_can_link_take(&l, &fb), MCA_OK);
        assert_true(fabs(fb.position[0] - 0.1) < 1e-12);
    }
    assert_int_equal(l.st.rx_bad_counter, 2);
}

static void test_backend_open_errors(void **state) {
    (void)state;
    mca_arm_t *arm = NULL;
    char err[256] = "";
    assert_int_equal(mca_can_backend_open(&arm, "vcan0", 0x101, 6, NULL, err, sizeof(err)), MCA_EINVAL);
    assert_non_null(strstr(err, "0x101"));
    assert_int_equal(mca_can_backend_open(&arm, "vcan0", 0x100, 0, NULL, err, sizeof(err)), MCA_EINVAL);
    assert_int_equal(mca_can_backend_open(NULL, "vcan0", 0x100, 6, NULL, err, sizeof(err)), MCA_EINVAL);
    /* No such interface (or no SocketCAN here): a clear error, never a crash. */
    int rc = mca_can_backend_open(&arm, "nosuchcan9", 0x100, 6, NULL, err, sizeof(err));
    assert_true(rc == MCA_ENOENT || rc == MCA_ENOTSUP);
    assert_non_null(strstr(err, "nosuchcan9"));
    assert_null(arm);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_command_layout),
        cmocka_unit_test(test_command_bad),
        cmocka_unit_test(test_feedback_layout),
        cmocka_unit_test(test_roundtrip_resolution),
        cmocka_unit_test(test_state_fault_frames),
        cmocka_unit_test(test_seq),
        cmocka_unit_test(test_unwrap16),
        cmocka_unit_test(test_seq_forged_pair),
        cmocka_unit_test(test_link),
        cmocka_unit_test(test_link_feedback_implausible),
        cmocka_unit_test(test_link_feedback_frame_id),
        cmocka_unit_test(test_link_heartbeat_joints),
        cmocka_unit_test(test_link_busoff_restarted),
        cmocka_unit_test(test_link_forged_counter_pair),
        cmocka_unit_test(test_backend_open_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
