/* SPDX-License-Identifier: MIT */
/* The mca_arm_* API: the generic layer (argument checks, FAULT -> MCA_EFAULT, downcast) against a
 * hand-written fake backend, then the in-process sim backend end to end (read/write/stats/close,
 * EAGAIN semantics, watchdog through the API, a closed position loop at 1 kHz). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "near.h"

#include "mca/arm.h"
#include "mca/err.h"
#include "mca/sim_backend.h"

#define ON (MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE)

/* ---- fake backend: records what the generic layer passes through ---- */
typedef struct fake {
    int reads, writes, closed;
    int read_rc;
    mca_arm_state_t state;
    mca_arm_command_t last;
} fake_t;

static int fake_read(void *ctx, mca_arm_feedback_t *fb) {
    fake_t *f = ctx;
    f->reads++;
    if (f->read_rc == MCA_OK) {
        memset(fb, 0, sizeof(*fb));
        fb->state = f->state;
        fb->n = 1;
    }
    return f->read_rc;
}

static int fake_write(void *ctx, const mca_arm_command_t *cmd) {
    fake_t *f = ctx;
    f->writes++;
    f->last = *cmd;
    return MCA_OK;
}

static void fake_close(void *ctx) {
    ((fake_t *)ctx)->closed++;
}

static const mca_arm_ops_t fake_ops = {
    .name = "fake", .read = fake_read, .write = fake_write, .close = fake_close};

static mca_arm_command_t cmd_all(uint32_t id, int n, uint8_t flags, double v) {
    mca_arm_command_t c;
    memset(&c, 0, sizeof(c));
    c.frame_id = id;
    c.n = n;
    for (int j = 0; j < n; j++) {
        c.flags[j] = flags;
        c.velocity[j] = v;
    }
    return c;
}

static void test_generic_layer(void **state) {
    (void)state;
    fake_t f = {0};
    mca_arm_t *arm = NULL;
    const mca_arm_ops_t no_read = {.name = "x", .write = fake_write};
    assert_int_equal(mca_arm_wrap(NULL, &fake_ops, &f), MCA_EINVAL);
    assert_int_equal(mca_arm_wrap(&arm, NULL, &f), MCA_EINVAL);
    assert_int_equal(mca_arm_wrap(&arm, &no_read, &f), MCA_EINVAL);
    assert_null(arm);
    assert_int_equal(mca_arm_wrap(&arm, &fake_ops, &f), MCA_OK);
    assert_string_equal(mca_arm_backend_name(arm), "fake");
    assert_ptr_equal(mca_arm_backend_ctx(arm, &fake_ops), &f);
    assert_null(mca_sim_backend_firmware(arm)); /* not a sim backend */
    assert_int_equal(mca_sim_backend_idle(arm, 1), MCA_EINVAL);

    mca_arm_feedback_t fb;
    f.state = MCA_ARM_SERVOING;
    assert_int_equal(mca_arm_read(arm, &fb), MCA_OK);
    f.state = MCA_ARM_FAULT;
    assert_int_equal(mca_arm_read(arm, &fb), MCA_EFAULT);
    assert_int_equal(fb.state, MCA_ARM_FAULT); /* filled */
    f.read_rc = MCA_EAGAIN;
    assert_int_equal(mca_arm_read(arm, &fb), MCA_EAGAIN);
    assert_int_equal(mca_arm_read(arm, NULL), MCA_EINVAL);
    assert_int_equal(f.reads, 3);

    mca_arm_command_t c = cmd_all(7, 2, ON, 0.25);
    assert_int_equal(mca_arm_write(arm, &c), MCA_OK);
    assert_int_equal(f.last.frame_id, 7);
    assert_double_equal(f.last.velocity[1], 0.25, 0);
    c.velocity[1] = NAN;
    assert_int_equal(mca_arm_write(arm, &c), MCA_EINVAL);
    c.velocity[1] = INFINITY;
    assert_int_equal(mca_arm_write(arm, &c), MCA_EINVAL);
    c = cmd_all(8, 0, ON, 0);
    assert_int_equal(mca_arm_write(arm, &c), MCA_EINVAL);
    c.n = MCA_MAX_DOF + 1;
    assert_int_equal(mca_arm_write(arm, &c), MCA_EINVAL);
    assert_int_equal(mca_arm_write(arm, NULL), MCA_EINVAL);
    assert_int_equal(f.writes, 1); /* nothing bad reached the backend */

    mca_arm_stats_t st;
    memset(&st, 0xff, sizeof(st));
    assert_int_equal(mca_arm_stats(arm, &st), MCA_OK); /* backend without stats: zeros */
    assert_int_equal(st.commands_sent, 0);
    assert_int_equal(st.bus_off, 0);

    assert_string_equal(mca_arm_state_name(MCA_ARM_BRAKING), "BRAKING");
    assert_string_equal(mca_arm_fault_name(MCA_ARM_FAULT_WATCHDOG), "WATCHDOG");
    assert_string_equal(mca_arm_fault_name(999), "UNKNOWN");

    mca_arm_close(arm);
    assert_int_equal(f.closed, 1);
    mca_arm_close(NULL);
    assert_string_equal(mca_arm_backend_name(NULL), "none");
}

/* ---- sim backend ---- */
static mca_sim_arm_config_t sim_cfg(int n) {
    mca_sim_arm_config_t cfg;
    mca_sim_arm_config_default(&cfg, n);
    for (int j = 0; j < n; j++) {
        cfg.q0[j] = 0.1 * (j + 1);
        cfg.acc_limit[j] = 5.0;
        cfg.dec_limit[j] = 5.0;
    }
    return cfg;
}

static void test_sim_open_errors(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg = sim_cfg(2);
    cfg.dt = -1;
    mca_arm_t *arm = (mca_arm_t *)0x1;
    char err[160] = "";
    assert_int_equal(mca_sim_backend_open(&arm, &cfg, err, sizeof(err)), MCA_EINVAL);
    assert_ptr_equal(arm, (mca_arm_t *)0x1);
    assert_non_null(strstr(err, "dt"));
    assert_int_equal(mca_sim_backend_open(&arm, NULL, err, sizeof(err)), MCA_EINVAL);
    assert_int_equal(mca_sim_backend_open(NULL, &cfg, err, sizeof(err)), MCA_EINVAL);
}

static void test_sim_read_write_eagain(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg = sim_cfg(3);
    mca_arm_t *arm = NULL;
    char err[160];
    assert_int_equal(mca_sim_backend_open(&arm, &cfg, err, sizeof(err)), MCA_OK);
    assert_string_equal(mca_arm_backend_name(arm), "sim");
    mca_arm_feedback_t fb;
    /* initial state once, then nothing new */
    assert_int_equal(mca_arm_read(arm, &fb), MCA_OK);
    assert_int_equal(fb.n, 3);
    assert_int_equal(fb.state, MCA_ARM_READY);
    assert_double_equal(fb.position[2], cfg.q0[2], 0);
    assert_int_equal(fb.stamp_ns, 0);
    memset(&fb, 0x33, sizeof(fb));
    assert_int_equal(mca_arm_read(arm, &fb), MCA_EAGAIN);
    assert_int_equal(fb.n, 0x33333333); /* untouched */

    for (uint32_t id = 1; id <= 100; id++) {
        mca_arm_command_t c = cmd_all(id, 3, ON, 0.5);
        assert_int_equal(mca_arm_write(arm, &c), MCA_OK);
        assert_int_equal(mca_arm_read(arm, &fb), MCA_OK);
        assert_int_equal(fb.frame_id, id);
        assert_int_equal(fb.stamp_ns, (int64_t)id * 1000000); /* virtual clock: one dt per write */
        assert_int_equal(mca_arm_read(arm, &fb), MCA_EAGAIN);
    }
    /* 100 ms from rest at 5 rad/s^2 to 0.5 rad/s: exactly the ramp, q = q0 + a t^2 / 2 */
    assert_double_equal(fb.velocity[0], 0.5, 1e-12);
    assert_double_equal(fb.position[0], 0.1 + 0.5 * 5.0 * 0.1 * 0.1, 1e-12);
    assert_int_equal(fb.state, MCA_ARM_SERVOING);

    /* wrong joint count: refused, nothing run */
    mca_arm_command_t bad = cmd_all(101, 2, ON, 0.5);
    assert_int_equal(mca_arm_write(arm, &bad), MCA_EINVAL);
    assert_int_equal(mca_arm_read(arm, &fb), MCA_EAGAIN);

    mca_arm_stats_t st;
    assert_int_equal(mca_arm_stats(arm, &st), MCA_OK);
    assert_int_equal(st.commands_sent, 100);
    assert_int_equal(st.feedback_received, 100);
    assert_int_equal(st.rx_bad_length + st.rx_bad_counter + st.rx_unknown_id + st.bus_errors, 0);

    mca_sim_arm_t *fw = mca_sim_backend_firmware(arm);
    assert_non_null(fw);
    assert_int_equal(fw->cnt.cmd_accepted, 100);
    assert_double_equal(fw->q[0], fb.position[0], 0);
    mca_arm_close(arm);
}

/* A controller that stops writing: the watchdog brakes the arm, read reports MCA_EFAULT, a
 * clear-fault command brings it back to READY. */
static void test_sim_watchdog_through_api(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg = sim_cfg(2);
    mca_arm_t *arm = NULL;
    assert_int_equal(mca_sim_backend_open(&arm, &cfg, NULL, 0), MCA_OK);
    mca_arm_feedback_t fb;
    uint32_t id = 1;
    for (; id <= 200; id++) {
        mca_arm_command_t c = cmd_all(id, 2, ON, 0.5);
        assert_int_equal(mca_arm_write(arm, &c), MCA_OK);
    }
    assert_int_equal(mca_sim_backend_idle(arm, 2), MCA_OK);
    assert_int_equal(mca_arm_read(arm, &fb), MCA_OK);
    assert_int_equal(fb.state, MCA_ARM_SERVOING);
    assert_int_equal(mca_sim_backend_idle(arm, 1), MCA_OK);
    assert_int_equal(mca_arm_read(arm, &fb), MCA_OK);
    assert_int_equal(fb.state, MCA_ARM_BRAKING);
    /* 0.5 rad/s at 5 rad/s^2: 100 cycles, the first already taken */
    assert_int_equal(mca_sim_backend_idle(arm, 98), MCA_OK);
    assert_int_equal(mca_arm_read(arm, &fb), MCA_OK);
    assert_int_equal(fb.state, MCA_ARM_BRAKING);
    assert_double_equal(fb.velocity[0], 0.005, 1e-12);
    assert_int_equal(mca_sim_backend_idle(arm, 1), MCA_OK);
    assert_int_equal(mca_arm_read(arm, &fb), MCA_EFAULT);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_WATCHDOG);
    assert_double_equal(fb.velocity[1], 0, 0);
    mca_arm_command_t c = cmd_all(id++, 2, MCA_ACT_CLEAR_FAULT, 0);
    assert_int_equal(mca_arm_write(arm, &c), MCA_OK);
    assert_int_equal(mca_arm_read(arm, &fb), MCA_OK);
    assert_int_equal(fb.state, MCA_ARM_READY);
    assert_int_equal(mca_sim_backend_idle(arm, -1), MCA_EINVAL);
    mca_arm_close(arm);
}

/* Silenced firmware: writes succeed, reads see nothing, then feedback resumes. */
static void test_sim_silent_eagain(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg = sim_cfg(1);
    cfg.n_inject = 1;
    cfg.inject[0] = (mca_sim_inject_t){.kind = MCA_SIM_INJ_SILENT, .at_cycle = 5, .duration = 2};
    mca_arm_t *arm = NULL;
    assert_int_equal(mca_sim_backend_open(&arm, &cfg, NULL, 0), MCA_OK);
    mca_arm_feedback_t fb;
    assert_int_equal(mca_arm_read(arm, &fb), MCA_OK);
    int got = 0;
    for (uint32_t id = 1; id <= 10; id++) {
        mca_arm_command_t c = cmd_all(id, 1, ON, 0.1);
        assert_int_equal(mca_arm_write(arm, &c), MCA_OK);
        int rc = mca_arm_read(arm, &fb);
        assert_int_equal(rc, (id == 6 || id == 7) ? MCA_EAGAIN : MCA_OK);
        got += rc == MCA_OK;
    }
    mca_arm_stats_t st;
    mca_arm_stats(arm, &st);
    assert_int_equal(st.commands_sent, 10);
    assert_int_equal(st.feedback_received, 8);
    assert_int_equal(got, 8);
    mca_arm_close(arm);
}

/* The backend adds nothing to the physics: the same commands give bit-identical feedback to the
 * firmware model driven directly (what mca-armsim runs behind CAN). */
static mca_sim_arm_t g_fw;

static void test_sim_backend_matches_firmware(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg = sim_cfg(4);
    cfg.lag_tau = 0.02;
    cfg.latency_cycles = 3;
    cfg.noise_pos = 1e-3;
    cfg.noise_vel = 1e-2;
    cfg.seed = 99;
    cfg.n_inject = 1;
    cfg.inject[0] = (mca_sim_inject_t){.kind = MCA_SIM_INJ_DROP_RX, .at_cycle = 400, .duration = 10};
    mca_arm_t *arm = NULL;
    assert_int_equal(mca_sim_backend_open(&arm, &cfg, NULL, 0), MCA_OK);
    assert_int_equal(mca_sim_arm_init(&g_fw, &cfg, NULL, 0), MCA_OK);
    mca_arm_feedback_t a, b;
    assert_int_equal(mca_arm_read(arm, &a), MCA_OK);
    for (uint32_t id = 1; id <= 1000; id++) {
        mca_arm_command_t c = cmd_all(id, 4, ON, 0);
        for (int j = 0; j < 4; j++) {
            c.velocity[j] = 0.7 * sin(0.01 * id + j);
        }
        assert_int_equal(mca_arm_write(arm, &c), MCA_OK);
        int ra = mca_arm_read(arm, &a);
        int rb = mca_sim_arm_cycle(&g_fw, &c, cfg.dt, &b);
        assert_int_equal(ra == MCA_EFAULT ? MCA_OK : ra, rb);
        assert_fb_equal(&a, &b);
    }
    assert_int_equal(b.state, MCA_ARM_FAULT); /* the dropped commands tripped the watchdog */
    assert_int_equal(b.fault_code, MCA_ARM_FAULT_WATCHDOG);
    mca_arm_close(arm);
}

/* The intended use: read, P control on position, write, every 1 ms; the arm reaches the target
 * within the time the velocity and acceleration limits allow. */
static void test_sim_closed_loop(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg = sim_cfg(2);
    cfg.lag_tau = 0.01;
    cfg.latency_cycles = 2;
    cfg.noise_pos = 1e-5;
    cfg.seed = 7;
    mca_arm_t *arm = NULL;
    assert_int_equal(mca_sim_backend_open(&arm, &cfg, NULL, 0), MCA_OK);
    const double target[2] = {0.6, -0.4};
    mca_arm_feedback_t fb;
    assert_int_equal(mca_arm_read(arm, &fb), MCA_OK);
    for (uint32_t id = 1; id <= 3000; id++) {
        mca_arm_command_t c = cmd_all(id, 2, ON, 0);
        for (int j = 0; j < 2; j++) {
            double v = 5.0 * (target[j] - fb.position[j]);
            c.velocity[j] = fmax(-0.8, fmin(0.8, v));
        }
        assert_int_equal(mca_arm_write(arm, &c), MCA_OK);
        assert_int_equal(mca_arm_read(arm, &fb), MCA_OK);
        /* the enable command reaches the firmware after the 2-cycle latency */
        assert_int_equal(fb.state, id <= 2 ? MCA_ARM_READY : MCA_ARM_SERVOING);
    }
    mca_sim_arm_t *fw = mca_sim_backend_firmware(arm);
    assert_double_equal(fw->q[0], 0.6, 1e-3);
    assert_double_equal(fw->q[1], -0.4, 1e-3);
    mca_arm_close(arm);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_generic_layer),         cmocka_unit_test(test_sim_open_errors),
        cmocka_unit_test(test_sim_read_write_eagain), cmocka_unit_test(test_sim_watchdog_through_api),
        cmocka_unit_test(test_sim_silent_eagain),     cmocka_unit_test(test_sim_backend_matches_firmware),
        cmocka_unit_test(test_sim_closed_loop),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
