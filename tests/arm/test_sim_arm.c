/* SPDX-License-Identifier: MIT */
/* Simulated arm firmware (mca/sim_arm.h) against closed forms: constant velocity, acceleration-limited
 * ramps, first-order lag, transport delay, noise statistics, joint limits, watchdog braking, frame ids,
 * fault injection and config validation. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "near.h"

#include "mca/err.h"
#include "mca/sim_arm.h"

#define DT 0.001
#define ON (MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE)

static mca_sim_arm_t g_arm; /* large (delay line): keep off the test stack */
static mca_sim_arm_t g_arm2;

static void base_cfg(mca_sim_arm_config_t *c, int n) {
    mca_sim_arm_config_default(c, n);
    for (int j = 0; j < n; j++) {
        c->vel_limit[j] = 1.0;
        c->acc_limit[j] = 1e9; /* effectively unlimited unless a test sets it */
        c->dec_limit[j] = 1e9;
    }
}

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

static void init_arm(mca_sim_arm_t *arm, const mca_sim_arm_config_t *cfg) {
    char err[160];
    int rc = mca_sim_arm_init(arm, cfg, err, sizeof(err));
    if (rc != MCA_OK) {
        fail_msg("init: %s", err);
    }
}

/* One cycle with a servo command of velocity v on every joint. */
static mca_arm_feedback_t step(mca_sim_arm_t *arm, uint32_t id, double v) {
    mca_arm_command_t c = cmd_all(id, arm->cfg.n, ON, v);
    mca_arm_feedback_t fb;
    assert_int_equal(mca_sim_arm_cycle(arm, &c, DT, &fb), MCA_OK);
    return fb;
}

static mca_arm_feedback_t idle(mca_sim_arm_t *arm) {
    mca_arm_feedback_t fb;
    assert_int_equal(mca_sim_arm_cycle(arm, NULL, DT, &fb), MCA_OK);
    return fb;
}

/* Once at speed, position grows by exactly v * elapsed time. */
static void test_constant_velocity_linear(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 2);
    cfg.q0[0] = 0.3;
    init_arm(&g_arm, &cfg);
    uint32_t id = 1;
    mca_arm_feedback_t fb = step(&g_arm, id++, 0.4);
    assert_int_equal(fb.state, MCA_ARM_SERVOING);
    assert_double_equal(fb.velocity[0], 0.4, 1e-15);
    double q_start = fb.position[0];
    for (int k = 1; k <= 1000; k++) {
        fb = step(&g_arm, id++, 0.4);
        assert_double_equal(fb.position[0], q_start + 0.4 * k * DT, 1e-12);
        assert_double_equal(fb.position[1], fb.position[0] - 0.3, 1e-12);
    }
    assert_double_equal(fb.position[0] - q_start, 0.4, 1e-12); /* 1 s at 0.4 rad/s */
    assert_int_equal(fb.frame_id, id - 1);
}

/* From rest with acceleration a to speed V: q = a t^2 / 2 while t <= V/a, then linear. */
static void test_acceleration_ramp_closed_form(void **state) {
    (void)state;
    const double a = 2.0, V = 0.5, T = V / a; /* 250 cycles: the ramp ends on a cycle boundary */
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 1);
    cfg.acc_limit[0] = a;
    init_arm(&g_arm, &cfg);
    double v_prev = 0.0;
    for (int k = 1; k <= 600; k++) {
        mca_arm_feedback_t fb = step(&g_arm, (uint32_t)k, V);
        double t = k * DT;
        double q = t <= T ? 0.5 * a * t * t : 0.5 * a * T * T + V * (t - T);
        double v = t <= T ? a * t : V;
        assert_double_equal(fb.position[0], q, 1e-12);
        assert_double_equal(fb.velocity[0], v, 1e-12);
        assert_true(fabs(fb.velocity[0] - v_prev) <= a * DT * (1 + 1e-12)); /* acceleration limit */
        assert_true(fb.velocity[0] <= V);
        v_prev = fb.velocity[0];
    }
}

/* Ramp end inside a cycle: the discrete model stays within a dt^2 bound of the continuous formula. */
static void test_acceleration_ramp_off_grid(void **state) {
    (void)state;
    const double a = 3.0, V = 0.5, T = V / a; /* 166.67 cycles */
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 1);
    cfg.acc_limit[0] = a;
    init_arm(&g_arm, &cfg);
    for (int k = 1; k <= 400; k++) {
        mca_arm_feedback_t fb = step(&g_arm, (uint32_t)k, V);
        double t = k * DT;
        double q = t <= T ? 0.5 * a * t * t : 0.5 * a * T * T + V * (t - T);
        assert_true(fabs(fb.position[0] - q) <= 0.5 * a * DT * DT);
    }
}

/* Slowing uses dec, speeding up acc, and a reversal spends |v|/dec to zero then accelerates. */
static void test_deceleration_and_reversal(void **state) {
    (void)state;
    const double acc = 2.0, dec = 4.0, V = 0.5;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 1);
    cfg.acc_limit[0] = acc;
    cfg.dec_limit[0] = dec;
    init_arm(&g_arm, &cfg);
    uint32_t id = 1;
    for (int k = 0; k < 300; k++) {
        step(&g_arm, id++, V);
    }
    assert_double_equal(g_arm.v[0], V, 1e-12);
    /* reverse to -V: 125 cycles to zero at dec (distance V^2/2dec), 250 cycles to -V at acc */
    double q0 = g_arm.q[0], v_prev = V;
    for (int k = 1; k <= 375; k++) {
        mca_arm_feedback_t fb = step(&g_arm, id++, -V);
        double dv = fb.velocity[0] - v_prev;
        double lim = (fb.velocity[0] >= 0 ? dec : acc) * DT;
        assert_true(fabs(dv) <= lim * (1 + 1e-9));
        if (k == 125) {
            assert_double_equal(fb.velocity[0], 0.0, 1e-12);
            assert_double_equal(fb.position[0] - q0, V * V / (2 * dec), 1e-12);
        }
        v_prev = fb.velocity[0];
    }
    assert_double_equal(g_arm.v[0], -V, 1e-12);
    assert_double_equal(g_arm.q[0] - q0, V * V / (2 * dec) - V * V / (2 * acc), 1e-12);
}

/* Commands above vel_limit are saturated (flag, no fault) or, with a fault ratio, fault the arm. */
static void test_velocity_limit(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 2);
    cfg.vel_limit[1] = 0.7;
    init_arm(&g_arm, &cfg);
    mca_arm_feedback_t fb;
    for (uint32_t id = 1; id <= 50; id++) {
        fb = step(&g_arm, id, 5.0);
        assert_true(fb.velocity[0] <= 1.0 && fb.velocity[1] <= 0.7);
    }
    assert_double_equal(fb.velocity[0], 1.0, 0);
    assert_double_equal(fb.velocity[1], 0.7, 0);
    assert_true(fb.fault_flags[0] & MCA_ACT_FLT_VEL_SAT);
    assert_int_equal(fb.state, MCA_ARM_SERVOING);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_NONE);
    fb = step(&g_arm, 51, 0.5); /* back within the limit: the saturation flag clears */
    assert_false(fb.fault_flags[0] & MCA_ACT_FLT_VEL_SAT);

    cfg.vel_fault_ratio = 1.5;
    cfg.dec_limit[0] = cfg.dec_limit[1] = 10.0;
    init_arm(&g_arm, &cfg);
    for (uint32_t id = 1; id <= 10; id++) {
        fb = step(&g_arm, id, 1.4); /* 1.4 <= 1.5 * 1.0, but above 1.5 * 0.7 on joint 1 */
    }
    assert_true(fb.fault_flags[1] & MCA_ACT_FLT_VELOCITY);
    assert_false(fb.fault_flags[0] & MCA_ACT_FLT_VELOCITY);
    assert_int_equal(fb.state, MCA_ARM_FAULT); /* v was ~0 when it faulted, so braking was immediate */
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_VELOCITY);
}

/* First-order lag: sampled step response u (1 - exp(-t / T)). */
static void test_lag_step_response(void **state) {
    (void)state;
    const double tau = 0.05, u = 0.6;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 1);
    cfg.lag_tau = tau;
    init_arm(&g_arm, &cfg);
    for (int k = 1; k <= 300; k++) {
        mca_arm_feedback_t fb = step(&g_arm, (uint32_t)k, u);
        assert_double_equal(fb.velocity[0], u * (1.0 - exp(-k * DT / tau)), 1e-12);
    }
    /* after 6 time constants the residue is u e^-6 */
    assert_true(fabs(g_arm.v[0] - u) < u * exp(-6.0) * 1.0001);
}

/* Transport latency of k cycles shifts the whole response by exactly k cycles. */
static void run_profile(mca_sim_arm_t *arm, double *v, uint32_t *ids, int cycles) {
    for (int k = 0; k < cycles; k++) {
        double u = k < 20 ? 0.1 : (k < 60 ? 0.8 : -0.3);
        mca_arm_feedback_t fb = step(arm, (uint32_t)(k + 1), u);
        v[k] = fb.velocity[0];
        ids[k] = fb.frame_id;
    }
}

static void test_latency_exact_shift(void **state) {
    (void)state;
    enum { N = 150, L = 7 };
    static double v0[N], vL[N];
    static uint32_t id0[N], idL[N];
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 1);
    cfg.acc_limit[0] = 20.0; /* make the response non-trivial */
    init_arm(&g_arm, &cfg);
    run_profile(&g_arm, v0, id0, N);
    cfg.latency_cycles = L;
    init_arm(&g_arm2, &cfg);
    run_profile(&g_arm2, vL, idL, N);
    for (int k = 0; k < L; k++) {
        assert_double_equal(vL[k], 0.0, 0);
        assert_int_equal(idL[k], 0); /* nothing delivered yet */
    }
    for (int k = L; k < N; k++) {
        assert_double_equal(vL[k], v0[k - L], 1e-15);
        assert_int_equal(idL[k], id0[k - L]);
    }
    /* and not by L - 1 or L + 1 */
    int diff_m = 0, diff_p = 0;
    for (int k = L + 1; k < N - 1; k++) {
        diff_m |= fabs(vL[k] - v0[k - L + 1]) > 1e-9;
        diff_p |= fabs(vL[k] - v0[k - L - 1]) > 1e-9;
    }
    assert_true(diff_m && diff_p);
}

/* Noise: same seed -> same sequence; other seed -> different; statistics match sigma; truth clean. */
static void test_noise_deterministic(void **state) {
    (void)state;
    enum { N = 20000 };
    const double sp = 0.01, sv = 0.002;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 1);
    cfg.noise_pos = sp;
    cfg.noise_vel = sv;
    cfg.seed = 42;
    init_arm(&g_arm, &cfg);
    init_arm(&g_arm2, &cfg);
    double sum = 0, sum2 = 0, sumv = 0, sumv2 = 0;
    for (int k = 0; k < N; k++) {
        mca_arm_feedback_t a = step(&g_arm, (uint32_t)k + 1, 0.1);
        mca_arm_feedback_t b = step(&g_arm2, (uint32_t)k + 1, 0.1);
        assert_memory_equal(a.position, b.position, sizeof(a.position));
        assert_memory_equal(a.velocity, b.velocity, sizeof(a.velocity));
        double e = a.position[0] - g_arm.q[0], ev = a.velocity[0] - g_arm.v[0];
        sum += e;
        sum2 += e * e;
        sumv += ev;
        sumv2 += ev * ev;
    }
    /* truth follows the noise-free closed form */
    assert_double_equal(g_arm.q[0], 0.1 * (N - 0.5) * DT, 1e-9);
    double mean = sum / N, sd = sqrt(sum2 / N - mean * mean);
    double meanv = sumv / N, sdv = sqrt(sumv2 / N - meanv * meanv);
    assert_true(fabs(mean) < 4 * sp / sqrt(N));
    assert_true(fabs(sd / sp - 1) < 0.03);
    assert_true(fabs(meanv) < 4 * sv / sqrt(N));
    assert_true(fabs(sdv / sv - 1) < 0.03);

    cfg.seed = 43;
    init_arm(&g_arm2, &cfg);
    cfg.seed = 42;
    init_arm(&g_arm, &cfg);
    int differ = 0;
    for (int k = 0; k < 10; k++) {
        mca_arm_feedback_t a = step(&g_arm, (uint32_t)k + 1, 0.1);
        mca_arm_feedback_t b = step(&g_arm2, (uint32_t)k + 1, 0.1);
        differ += a.position[0] != b.position[0];
    }
    assert_int_equal(differ, 10);
}

/* Position limits: clamp exactly at the limit, flag the joint, brake the others, FAULT JOINT_LIMIT. */
static void test_position_limits(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 2);
    cfg.lower[0] = -0.2;
    cfg.upper[0] = 0.1;
    cfg.dec_limit[1] = 5.0;
    init_arm(&g_arm, &cfg);
    mca_arm_feedback_t fb;
    uint32_t id = 1;
    int k = 0;
    do {
        fb = step(&g_arm, id++, 0.5);
        assert_true(fb.position[0] <= 0.1);
        k++;
    } while (fb.state == MCA_ARM_SERVOING && k < 1000);
    /* 0.1 rad at 0.5 rad/s: the limit is crossed in cycle 201 (q = 0.5 * (k - 0.5) ms) */
    assert_int_equal(k, 201);
    assert_double_equal(fb.position[0], 0.1, 0);
    assert_double_equal(fb.velocity[0], 0.0, 0);
    assert_true(fb.fault_flags[0] & MCA_ACT_FLT_LIMIT_HIGH);
    assert_false(fb.fault_flags[1] & (MCA_ACT_FLT_LIMIT_HIGH | MCA_ACT_FLT_LIMIT_LOW));
    assert_int_equal(fb.state, MCA_ARM_BRAKING);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_JOINT_LIMIT);
    /* joint 1 brakes at 5 rad/s^2: 0.5 / 0.005 = 100 cycles */
    for (int i = 1; i <= 100; i++) {
        fb = step(&g_arm, id++, 0.5);
        assert_double_equal(fb.position[0], 0.1, 0);
    }
    assert_int_equal(fb.state, MCA_ARM_FAULT);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_JOINT_LIMIT);
    /* clear, then move away from the limit and into the lower one */
    mca_arm_command_t c = cmd_all(id++, 2, MCA_ACT_CLEAR_FAULT, 0);
    assert_int_equal(mca_sim_arm_cycle(&g_arm, &c, DT, &fb), MCA_OK);
    assert_int_equal(fb.state, MCA_ARM_READY);
    assert_int_equal(fb.fault_flags[0], 0);
    do {
        fb = step(&g_arm, id++, -1.0);
        assert_true(fb.position[0] >= -0.2);
    } while (fb.state == MCA_ARM_SERVOING);
    assert_double_equal(fb.position[0], -0.2, 0);
    assert_true(fb.fault_flags[0] & MCA_ACT_FLT_LIMIT_LOW);
}

/* Watchdog: braking starts in exactly the watchdog_cycles-th missed cycle, at exactly dec. */
static void check_watchdog(int W) {
    const double V = 0.8, dec = 4.0;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 3);
    cfg.watchdog_cycles = W;
    for (int j = 0; j < 3; j++) {
        cfg.dec_limit[j] = dec;
    }
    init_arm(&g_arm, &cfg);
    uint32_t id = 1;
    for (int k = 0; k < 20; k++) {
        step(&g_arm, id++, V);
    }
    mca_arm_feedback_t fb;
    for (int m = 1; m < W; m++) { /* missed 1..W-1: setpoint held */
        fb = idle(&g_arm);
        assert_int_equal(fb.state, MCA_ARM_SERVOING);
        assert_double_equal(fb.velocity[0], V, 0);
    }
    fb = idle(&g_arm); /* missed W: braking starts in this cycle */
    assert_int_equal(fb.state, MCA_ARM_BRAKING);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_WATCHDOG);
    assert_double_equal(fb.velocity[0], V - dec * DT, 1e-12);
    assert_int_equal(g_arm.cnt.watchdog_trips, 1);
    double v_prev = fb.velocity[0];
    int cycles = 1;
    /* a valid command while braking does not resume motion */
    while (fb.state == MCA_ARM_BRAKING) {
        fb = cycles % 2 ? step(&g_arm, id++, V) : idle(&g_arm);
        assert_true(v_prev - fb.velocity[0] <= dec * DT * (1 + 1e-9)); /* never faster than dec */
        assert_true(v_prev - fb.velocity[0] >= dec * DT * (1 - 1e-9) || fb.velocity[0] == 0.0);
        assert_true(fb.velocity[0] >= 0.0);
        v_prev = fb.velocity[0];
        cycles++;
        assert_true(cycles < 1000);
    }
    assert_int_equal(cycles, 200); /* V / (dec dt) */
    assert_int_equal(fb.state, MCA_ARM_FAULT);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_WATCHDOG);
    for (int j = 0; j < 3; j++) {
        assert_double_equal(fb.velocity[j], 0.0, 0);
    }
    /* stopping distance V^2 / (2 dec) after the trip, within a cycle of held motion */
    double q_stop = g_arm.q[0];
    for (int k = 0; k < 5; k++) { /* servo commands do not leave FAULT */
        fb = step(&g_arm, id++, V);
        assert_int_equal(fb.state, MCA_ARM_FAULT);
        assert_double_equal(fb.position[0], q_stop, 0);
    }
    mca_arm_command_t c = cmd_all(id++, 3, MCA_ACT_CLEAR_FAULT, 0);
    c.flags[0] = 0;
    c.flags[1] = 0; /* one actuator carrying CLEAR_FAULT is enough */
    assert_int_equal(mca_sim_arm_cycle(&g_arm, &c, DT, &fb), MCA_OK);
    assert_int_equal(fb.state, MCA_ARM_READY);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_NONE);
    fb = step(&g_arm, id++, 0.1);
    assert_int_equal(fb.state, MCA_ARM_SERVOING);
}

static void test_watchdog_braking(void **state) {
    (void)state;
    check_watchdog(3); /* PA-10 */
    check_watchdog(1);
    check_watchdog(7);
}

/* Stopping distance after a watchdog trip: (W - 1) held cycles + the braking ramp. */
static void test_watchdog_stop_distance(void **state) {
    (void)state;
    const double V = 0.6, dec = 3.0;
    const int W = 3;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 1);
    cfg.dec_limit[0] = dec;
    cfg.watchdog_cycles = W;
    init_arm(&g_arm, &cfg);
    for (uint32_t id = 1; id <= 10; id++) {
        step(&g_arm, id, V);
    }
    double q0 = g_arm.q[0];
    mca_arm_feedback_t fb;
    do {
        fb = idle(&g_arm);
    } while (fb.state != MCA_ARM_FAULT);
    assert_double_equal(g_arm.q[0] - q0, V * (W - 1) * DT + V * V / (2 * dec), 1e-12);
}

/* Repeated or older frame ids are not applied (and count as missed cycles for the watchdog). */
static void test_stale_frame_ids(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 1);
    cfg.watchdog_cycles = 3;
    cfg.dec_limit[0] = 1.0;
    init_arm(&g_arm, &cfg);
    step(&g_arm, 100, 0.2);
    mca_arm_feedback_t fb = step(&g_arm, 101, 0.2);
    fb = step(&g_arm, 99, 0.9); /* older */
    assert_double_equal(fb.velocity[0], 0.2, 0);
    assert_int_equal(fb.frame_id, 101);
    fb = step(&g_arm, 101, 0.9); /* repeated */
    assert_double_equal(fb.velocity[0], 0.2, 0);
    assert_int_equal(g_arm.cnt.cmd_stale, 2);
    fb = step(&g_arm, 101, 0.9); /* third missed cycle: watchdog */
    assert_int_equal(fb.state, MCA_ARM_BRAKING);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_WATCHDOG);

    /* wrap-around: 0xFFFFFFFF -> 0 is newer */
    init_arm(&g_arm, &cfg);
    step(&g_arm, 0xFFFFFFFEu, 0.1);
    step(&g_arm, 0xFFFFFFFFu, 0.1);
    fb = step(&g_arm, 0, 0.3);
    assert_int_equal(fb.frame_id, 0);
    assert_double_equal(fb.velocity[0], 0.3, 0);
    assert_int_equal(g_arm.cnt.cmd_stale, 0);

    /* wrong joint count / NaN: not applied, counted invalid */
    mca_arm_command_t c = cmd_all(1, 2, ON, 0.5);
    assert_int_equal(mca_sim_arm_cycle(&g_arm, &c, DT, &fb), MCA_OK);
    c = cmd_all(2, 1, ON, NAN);
    assert_int_equal(mca_sim_arm_cycle(&g_arm, &c, DT, &fb), MCA_OK);
    assert_int_equal(g_arm.cnt.cmd_invalid, 2);
    assert_int_equal(fb.frame_id, 0);
    assert_true(isfinite(fb.velocity[0]));
}

/* INIT -> READY after init_cycles; READY needs both flags on every actuator; requested stop -> READY. */
static void test_state_machine(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 2);
    cfg.init_cycles = 2;
    cfg.dec_limit[0] = cfg.dec_limit[1] = 10.0;
    init_arm(&g_arm, &cfg);
    mca_arm_feedback_t fb;
    mca_sim_arm_snapshot(&g_arm, &fb);
    assert_int_equal(fb.state, MCA_ARM_INIT);
    fb = step(&g_arm, 1, 0.5);
    assert_int_equal(fb.state, MCA_ARM_INIT);
    fb = step(&g_arm, 2, 0.5);
    assert_int_equal(fb.state, MCA_ARM_INIT);
    fb = step(&g_arm, 3, 0.5);
    assert_int_equal(fb.state, MCA_ARM_READY);
    assert_double_equal(fb.velocity[0], 0, 0);
    mca_arm_command_t c = cmd_all(4, 2, ON, 0.5);
    c.flags[1] = MCA_ACT_SERVO_ENABLE; /* brake still on for joint 1 */
    assert_int_equal(mca_sim_arm_cycle(&g_arm, &c, DT, &fb), MCA_OK);
    assert_int_equal(fb.state, MCA_ARM_READY);
    for (int k = 0; k < 10; k++) { /* no watchdog outside SERVOING */
        fb = idle(&g_arm);
        assert_int_equal(fb.state, MCA_ARM_READY);
    }
    fb = step(&g_arm, 5, 0.5);
    assert_int_equal(fb.state, MCA_ARM_SERVOING);
    for (uint32_t id = 6; id < 50; id++) {
        fb = step(&g_arm, id, 0.5);
    }
    c = cmd_all(50, 2, MCA_ACT_BRAKE_RELEASE, 0.5); /* servo disable: requested stop */
    assert_int_equal(mca_sim_arm_cycle(&g_arm, &c, DT, &fb), MCA_OK);
    assert_int_equal(fb.state, MCA_ARM_BRAKING);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_NONE);
    int k = 0;
    while (fb.state == MCA_ARM_BRAKING && k++ < 1000) {
        fb = idle(&g_arm); /* no watchdog either while braking */
    }
    assert_int_equal(k, 50 - 1); /* 0.5 / (10 * 1e-3) cycles, the first taken in the disable cycle */
    assert_int_equal(fb.state, MCA_ARM_READY);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_NONE);
}

/* Torque model: inertia * acceleration + damping * velocity. */
static void test_torque_model(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 1);
    cfg.acc_limit[0] = 2.0;
    cfg.inertia[0] = 0.3;
    cfg.damping[0] = 1.5;
    init_arm(&g_arm, &cfg);
    for (uint32_t id = 1; id <= 400; id++) {
        mca_arm_feedback_t fb = step(&g_arm, id, 0.5);
        double acc = id <= 250 ? 2.0 : 0.0;
        assert_double_equal(fb.torque[0], 0.3 * acc + 1.5 * fb.velocity[0], 1e-9);
    }
}

/* Fault injection: actuator fault, frozen feedback, silent firmware, dropped commands. */
static void test_fault_injection(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 2);
    cfg.dec_limit[0] = cfg.dec_limit[1] = 10.0;
    cfg.n_inject = 1;
    cfg.inject[0] = (mca_sim_inject_t){.kind = MCA_SIM_INJ_ACTUATOR, .at_cycle = 30, .joint = 1};
    init_arm(&g_arm, &cfg);
    mca_arm_feedback_t fb;
    uint32_t id = 1;
    for (; id <= 30; id++) {
        fb = step(&g_arm, id, 0.3);
        assert_int_equal(fb.state, MCA_ARM_SERVOING);
    }
    fb = step(&g_arm, id++, 0.3); /* cycle index 30 */
    assert_int_equal(fb.state, MCA_ARM_BRAKING);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_INJECTED);
    assert_true(fb.fault_flags[1] & MCA_ACT_FLT_ACTUATOR);
    while (fb.state == MCA_ARM_BRAKING) {
        fb = step(&g_arm, id++, 0.3);
    }
    assert_int_equal(fb.state, MCA_ARM_FAULT);

    /* freeze for 5 cycles from cycle 10: the same frame verbatim, then fresh again */
    cfg.inject[0] = (mca_sim_inject_t){.kind = MCA_SIM_INJ_FREEZE, .at_cycle = 10, .duration = 5};
    init_arm(&g_arm, &cfg);
    mca_arm_feedback_t frozen;
    for (id = 1; id <= 10; id++) {
        frozen = step(&g_arm, id, 0.3);
    }
    for (int k = 0; k < 5; k++) {
        fb = step(&g_arm, id++, 0.3);
        assert_fb_equal(&fb, &frozen);
    }
    fb = step(&g_arm, id++, 0.3);
    assert_int_equal(fb.frame_id, id - 1);
    assert_double_equal(fb.position[0], g_arm.q[0], 0); /* physics ran meanwhile */
    assert_true(fb.position[0] > frozen.position[0]);

    /* silent for 4 cycles: no feedback, but the firmware keeps following commands */
    cfg.inject[0] = (mca_sim_inject_t){.kind = MCA_SIM_INJ_SILENT, .at_cycle = 10, .duration = 4};
    init_arm(&g_arm, &cfg);
    for (id = 1; id <= 10; id++) {
        step(&g_arm, id, 0.3);
    }
    for (int k = 0; k < 4; k++) {
        mca_arm_command_t c = cmd_all(id++, 2, ON, 0.3);
        memset(&fb, 0x5a, sizeof(fb));
        assert_int_equal(mca_sim_arm_cycle(&g_arm, &c, DT, &fb), MCA_EAGAIN);
        assert_int_equal(fb.n, 0x5a5a5a5a); /* untouched */
    }
    fb = step(&g_arm, id++, 0.3);
    assert_int_equal(fb.state, MCA_ARM_SERVOING);
    assert_int_equal(g_arm.cnt.feedback_sent, 11);
    assert_int_equal(g_arm.cnt.cycles, 15);

    /* dropped commands trip the watchdog after watchdog_cycles */
    cfg.inject[0] = (mca_sim_inject_t){.kind = MCA_SIM_INJ_DROP_RX, .at_cycle = 10};
    init_arm(&g_arm, &cfg);
    for (id = 1; id <= 12; id++) {
        fb = step(&g_arm, id, 0.3);
        assert_int_equal(fb.state, MCA_ARM_SERVOING);
    }
    fb = step(&g_arm, id++, 0.3); /* cycle index 12: third lost command */
    assert_int_equal(fb.state, MCA_ARM_BRAKING);
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_WATCHDOG);
    assert_int_equal(g_arm.cnt.cmd_dropped, 3);
}

/* Injections scheduled at run time start with the next cycle; finished slots are reused. */
static void test_inject_now(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg;
    base_cfg(&cfg, 2);
    init_arm(&g_arm, &cfg);
    mca_arm_feedback_t fb;
    uint32_t id = 1;
    for (; id <= 5; id++) {
        step(&g_arm, id, 0.2);
    }
    assert_int_equal(mca_sim_arm_inject_now(NULL, MCA_SIM_INJ_SILENT, 1, 0), MCA_EINVAL);
    assert_int_equal(mca_sim_arm_inject_now(&g_arm, 0, 1, 0), MCA_EINVAL);
    assert_int_equal(mca_sim_arm_inject_now(&g_arm, MCA_SIM_INJ_ACTUATOR, 0, 2), MCA_EINVAL);
    assert_int_equal(mca_sim_arm_inject_now(&g_arm, MCA_SIM_INJ_SILENT, 2, 0), MCA_OK);
    for (int k = 0; k < 2; k++) {
        mca_arm_command_t c = cmd_all(id++, 2, ON, 0.2);
        assert_int_equal(mca_sim_arm_cycle(&g_arm, &c, DT, &fb), MCA_EAGAIN);
    }
    fb = step(&g_arm, id++, 0.2);
    assert_int_equal(fb.state, MCA_ARM_SERVOING);
    /* the finished SILENT slot is reused: the table does not grow */
    assert_int_equal(mca_sim_arm_inject_now(&g_arm, MCA_SIM_INJ_ACTUATOR, 0, 1), MCA_OK);
    assert_int_equal(g_arm.cfg.n_inject, 1);
    fb = step(&g_arm, id++, 0.2);
    assert_int_equal(fb.state, MCA_ARM_FAULT); /* dec 1e9: stops within the cycle */
    assert_int_equal(fb.fault_code, MCA_ARM_FAULT_INJECTED);
    assert_true(fb.fault_flags[1] & MCA_ACT_FLT_ACTUATOR);
    /* the ACTUATOR injection has fired: its slot is reused too */
    assert_int_equal(mca_sim_arm_inject_now(&g_arm, MCA_SIM_INJ_FREEZE, 0, 0), MCA_OK);
    assert_int_equal(g_arm.cfg.n_inject, 1);
    for (int i = 1; i < MCA_SIM_MAX_INJECT; i++) { /* never-ending freezes fill the table */
        assert_int_equal(mca_sim_arm_inject_now(&g_arm, MCA_SIM_INJ_FREEZE, 0, 0), MCA_OK);
    }
    assert_int_equal(g_arm.cfg.n_inject, MCA_SIM_MAX_INJECT);
    assert_int_equal(mca_sim_arm_inject_now(&g_arm, MCA_SIM_INJ_FREEZE, 0, 0), MCA_ERANGE);
    mca_arm_feedback_t frozen = fb;
    fb = step(&g_arm, id++, 0.2);
    assert_fb_equal(&fb, &frozen);
}

/* Random command streams (flags, stale ids, wrong n, NaN, gaps, huge velocities, injections):
 * the invariants hold in every cycle. */
static uint64_t t_rng = 12345;
static uint64_t t_next(void) {
    t_rng ^= t_rng << 13;
    t_rng ^= t_rng >> 7;
    t_rng ^= t_rng << 17;
    return t_rng;
}
static double t_unit(void) {
    return (double)(t_next() >> 11) / 9007199254740992.0;
}

static void test_random_invariants(void **state) {
    (void)state;
    const int n = 5;
    mca_sim_arm_config_t cfg;
    mca_sim_arm_config_default(&cfg, n);
    for (int j = 0; j < n; j++) {
        cfg.lower[j] = -0.5 - 0.1 * j;
        cfg.upper[j] = 0.4 + 0.1 * j;
        cfg.vel_limit[j] = 0.5 + 0.2 * j;
        cfg.acc_limit[j] = 3.0 + j;
        cfg.dec_limit[j] = 6.0 - j;
    }
    cfg.lag_tau = 0.004;
    cfg.latency_cycles = 2;
    cfg.watchdog_cycles = 4;
    cfg.noise_pos = 1e-3;
    cfg.n_inject = 2;
    cfg.inject[0] = (mca_sim_inject_t){.kind = MCA_SIM_INJ_ACTUATOR, .at_cycle = 30000, .joint = 2};
    cfg.inject[1] = (mca_sim_inject_t){.kind = MCA_SIM_INJ_DROP_RX, .at_cycle = 50000, .duration = 100};
    init_arm(&g_arm, &cfg);
    uint32_t id = 1;
    int seen[5] = {0};
    for (int k = 0; k < 100000; k++) {
        mca_arm_command_t c = cmd_all(id, n, ON, 0);
        uint64_t r = t_next();
        for (int j = 0; j < n; j++) {
            c.velocity[j] = (t_unit() * 2 - 1) * 1.5 * cfg.vel_limit[j] * sin(1e-3 * k + j);
        }
        if (r % 97 == 0) {
            c.flags[r % n] = 0; /* requested stop */
        }
        if (r % 89 == 0) {
            c.flags[0] |= MCA_ACT_CLEAR_FAULT;
        }
        if (r % 83 == 0) {
            c.frame_id = id - 3; /* stale */
        }
        if (r % 79 == 0) {
            c.n = n + 1;
        }
        if (r % 73 == 0) {
            c.velocity[1] = NAN;
        }
        if (r % 211 == 0) {
            c.velocity[0] = 1e6;
        }
        if (k % 5000 < 3000 || r % 500 == 0) { /* all flags clear-fault once FAULT is reached */
            if (g_arm.state == MCA_ARM_FAULT) {
                c.flags[0] |= MCA_ACT_CLEAR_FAULT;
            }
        }
        int gap = (k % 7000) > 6990; /* controller stalls: the watchdog trips */
        double v_prev[MCA_MAX_DOF];
        memcpy(v_prev, g_arm.v, sizeof(v_prev));
        mca_arm_feedback_t fb;
        assert_int_equal(mca_sim_arm_cycle(&g_arm, gap ? NULL : &c, DT, &fb), MCA_OK);
        id++;
        seen[fb.state]++;
        for (int j = 0; j < n; j++) {
            double v = g_arm.v[j], q = g_arm.q[j];
            assert_true(isfinite(v) && isfinite(q) && isfinite(fb.position[j]) && isfinite(fb.torque[j]));
            assert_true(fabs(v) <= cfg.vel_limit[j] * (1 + 1e-12));
            assert_true(q >= cfg.lower[j] && q <= cfg.upper[j]);
            /* the only velocity jump beyond acc/dec is a joint stopped by its position limit */
            int at_limit = q == cfg.lower[j] || q == cfg.upper[j];
            double amax = fmax(cfg.acc_limit[j], cfg.dec_limit[j]) * DT * (1 + 1e-9);
            assert_true(fabs(v - v_prev[j]) <= amax || (at_limit && v == 0.0));
            if (fb.state == MCA_ARM_READY || fb.state == MCA_ARM_FAULT) {
                assert_double_equal(v, 0.0, 0);
            }
        }
        assert_true(fb.state >= MCA_ARM_READY && fb.state <= MCA_ARM_FAULT);
        assert_true((fb.fault_code != MCA_ARM_FAULT_NONE) == (fb.state == MCA_ARM_FAULT) ||
                    fb.state == MCA_ARM_BRAKING);
    }
    print_message(
        "cycles per state READY %d SERVOING %d BRAKING %d FAULT %d; trips %lu stale %lu invalid %lu\n",
        seen[1], seen[2], seen[3], seen[4], (unsigned long)g_arm.cnt.watchdog_trips,
        (unsigned long)g_arm.cnt.cmd_stale, (unsigned long)g_arm.cnt.cmd_invalid);
    /* the stream visits every state except INIT (init_cycles = 0) */
    for (int s = MCA_ARM_READY; s <= MCA_ARM_FAULT; s++) {
        assert_true(seen[s] > 0);
    }
    assert_true(g_arm.cnt.watchdog_trips > 0 && g_arm.cnt.cmd_stale > 0 && g_arm.cnt.cmd_invalid > 0);
}

static void test_config_errors(void **state) {
    (void)state;
    mca_sim_arm_config_t cfg;
    char err[160];
    base_cfg(&cfg, 3);
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_OK);
    cfg.n = 0;
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_EINVAL);
    assert_non_null(strstr(err, "n = 0"));
    cfg.n = MCA_MAX_DOF + 1;
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_ERANGE);
    cfg.n = 3;
    cfg.vel_limit[2] = 0;
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_EINVAL);
    assert_non_null(strstr(err, "vel_limit[2]"));
    cfg.vel_limit[2] = 1;
    cfg.upper[1] = 0.5;
    cfg.q0[1] = 0.6;
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_EINVAL);
    assert_non_null(strstr(err, "q0[1]"));
    cfg.q0[1] = 0;
    cfg.dec_limit[0] = NAN;
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_EINVAL);
    assert_non_null(strstr(err, "dec_limit[0]"));
    cfg.dec_limit[0] = 1;
    cfg.latency_cycles = MCA_SIM_MAX_LATENCY + 1;
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_ERANGE);
    assert_non_null(strstr(err, "latency_cycles"));
    cfg.latency_cycles = MCA_SIM_MAX_LATENCY;
    cfg.watchdog_cycles = 0;
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_EINVAL);
    cfg.watchdog_cycles = 3;
    cfg.n_inject = 1;
    cfg.inject[0] = (mca_sim_inject_t){.kind = MCA_SIM_INJ_ACTUATOR, .joint = 3};
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_EINVAL);
    assert_non_null(strstr(err, "inject.joint[0]"));
    cfg.inject[0].joint = 2;
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_OK);
    cfg.vel_fault_ratio = 0.5;
    assert_int_equal(mca_sim_arm_config_check(&cfg, err, sizeof(err)), MCA_EINVAL);
    /* init refuses and leaves the arm untouched */
    memset(&g_arm, 0x77, sizeof(g_arm));
    assert_int_equal(mca_sim_arm_init(&g_arm, &cfg, NULL, 0), MCA_EINVAL);
    assert_int_equal(g_arm.cfg.n, 0x77777777);
    /* cycle argument checks */
    cfg.vel_fault_ratio = 0;
    init_arm(&g_arm, &cfg);
    mca_arm_feedback_t fb;
    assert_int_equal(mca_sim_arm_cycle(&g_arm, NULL, 0.0, &fb), MCA_EINVAL);
    assert_int_equal(mca_sim_arm_cycle(&g_arm, NULL, NAN, &fb), MCA_EINVAL);
    assert_int_equal(mca_sim_arm_cycle(&g_arm, NULL, DT, NULL), MCA_EINVAL);
    assert_int_equal(mca_sim_arm_cycle(NULL, NULL, DT, &fb), MCA_EINVAL);
    assert_int_equal(g_arm.cycle, 0);
}

/* The tools' injection text (mca-armsim / mca-simarm-trace --inject): every field lands where it should,
 * and each malformed form is refused with *out zeroed. */
static void test_inject_parse(void **state) {
    (void)state;
    static const struct {
        const char *text;
        int kind;
        uint64_t at, duration;
        int joint;
    } good[] = {
        {"actuator@5000:1", MCA_SIM_INJ_ACTUATOR, 5000, 0, 1},
        {"freeze@7000+50", MCA_SIM_INJ_FREEZE, 7000, 50, 0},
        {"silent@0", MCA_SIM_INJ_SILENT, 0, 0, 0},
        {"drop-rx@0x10+0x20:2", MCA_SIM_INJ_DROP_RX, 16, 32, 2},
        {"actuator@18446744073709551615:5", MCA_SIM_INJ_ACTUATOR, UINT64_MAX, 0, 5},
    };
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        mca_sim_inject_t in;
        assert_int_equal(mca_sim_inject_parse(good[i].text, 6, &in), MCA_OK);
        assert_int_equal(in.kind, good[i].kind);
        assert_true(in.at_cycle == good[i].at);
        assert_true(in.duration == good[i].duration);
        assert_int_equal(in.joint, good[i].joint);
        assert_string_equal(mca_sim_inject_kind_name(in.kind), good[i].text[0] == 'a'   ? "actuator"
                                                               : good[i].text[0] == 'f' ? "freeze"
                                                               : good[i].text[0] == 's' ? "silent"
                                                                                        : "drop-rx");
    }
    static const char *const bad[] = {
        "",
        "actuator",
        "actuator@5",
        "actuator@5:6",
        "actuator@5:-1",
        "bogus@1",
        "drop@1",
        "freeze@-3",
        "freeze@+3",
        "freeze@3+",
        "freeze@3+-1",
        "silent@1x",
        "silent@ 1",
        "@1",
        "silent@1:",
        "silent@1+2:",
        "FREEZE@1",
        "silent@99999999999999999999",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        mca_sim_inject_t in = {.kind = 9, .at_cycle = 9, .duration = 9, .joint = 9};
        if (mca_sim_inject_parse(bad[i], 6, &in) != MCA_EINVAL) {
            fail_msg("'%s' accepted", bad[i]);
        }
        assert_int_equal(in.kind, MCA_SIM_INJ_NONE);
        assert_true(in.at_cycle == 0 && in.duration == 0 && in.joint == 0);
    }
    mca_sim_inject_t in;
    assert_int_equal(mca_sim_inject_parse(NULL, 6, &in), MCA_EINVAL);
    assert_int_equal(mca_sim_inject_parse("silent@1", 6, NULL), MCA_EINVAL);
    assert_string_equal(mca_sim_inject_kind_name(0), "none");
    assert_string_equal(mca_sim_inject_kind_name(5), "none");
}

/* The emulators' --q0 (mca-armsim, mca-drivesim): exactly n finite numbers, else refused with q unchanged. */
static void test_parse_joint_list(void **state) {
    (void)state;
    double q[3] = {9, 9, 9};
    assert_int_equal(mca_sim_parse_joint_list("0.5,-1e-3,2", 3, q), MCA_OK);
    assert_true(q[0] == 0.5 && q[1] == -1e-3 && q[2] == 2.0);
    assert_int_equal(mca_sim_parse_joint_list("1.25", 1, q), MCA_OK);
    assert_true(q[0] == 1.25 && q[1] == -1e-3);
    static const char *const bad[] = {"",      "1,2",     "1,2,3,4", "1,,3",   "1,2,", "1;2;3",
                                      "1,2,x", "1,nan,3", "1,inf,3", "1,2,3 ", ",1,2", "1e999,0,0"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        double r[3] = {7, 7, 7};
        if (mca_sim_parse_joint_list(bad[i], 3, r) != MCA_EINVAL) {
            fail_msg("'%s' accepted", bad[i]);
        }
        assert_true(r[0] == 7 && r[1] == 7 && r[2] == 7);
    }
    assert_int_equal(mca_sim_parse_joint_list(NULL, 3, q), MCA_EINVAL);
    assert_int_equal(mca_sim_parse_joint_list("1", 0, q), MCA_EINVAL);
    assert_int_equal(mca_sim_parse_joint_list("1", 1, NULL), MCA_EINVAL);
}

/* Limits from a URDF chain model (filled by hand: the loader is tested elsewhere). */
static void test_config_from_chain(void **state) {
    (void)state;
    static mca_chain_t ch;
    memset(&ch, 0, sizeof(ch));
    ch.dof = 3;
    double lo[3] = {-1.0, 0.2, -INFINITY}, hi[3] = {1.0, 2.0, INFINITY}, vl[3] = {0.5, 0.8, 1.2};
    for (int j = 0; j < 3; j++) {
        ch.joint[j].lower = lo[j];
        ch.joint[j].upper = hi[j];
        ch.joint[j].vel_limit = vl[j];
    }
    ch.joint[2].continuous = 1;
    mca_sim_arm_config_t cfg;
    assert_int_equal(mca_sim_arm_config_from_chain(&cfg, &ch), MCA_OK);
    assert_int_equal(cfg.n, 3);
    assert_double_equal(cfg.lower[0], -1.0, 0);
    assert_double_equal(cfg.upper[1], 2.0, 0);
    assert_double_equal(cfg.vel_limit[2], 1.2, 0);
    assert_true(isinf(cfg.upper[2]) && isinf(cfg.lower[2]));
    assert_double_equal(cfg.q0[1], 0.2, 0); /* 0 clamped into [0.2, 2] */
    assert_int_equal(mca_sim_arm_config_check(&cfg, NULL, 0), MCA_OK);
    ch.dof = 0;
    assert_int_equal(mca_sim_arm_config_from_chain(&cfg, &ch), MCA_EINVAL);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_velocity_linear),
        cmocka_unit_test(test_acceleration_ramp_closed_form),
        cmocka_unit_test(test_acceleration_ramp_off_grid),
        cmocka_unit_test(test_deceleration_and_reversal),
        cmocka_unit_test(test_velocity_limit),
        cmocka_unit_test(test_lag_step_response),
        cmocka_unit_test(test_latency_exact_shift),
        cmocka_unit_test(test_noise_deterministic),
        cmocka_unit_test(test_position_limits),
        cmocka_unit_test(test_watchdog_braking),
        cmocka_unit_test(test_watchdog_stop_distance),
        cmocka_unit_test(test_stale_frame_ids),
        cmocka_unit_test(test_state_machine),
        cmocka_unit_test(test_torque_model),
        cmocka_unit_test(test_fault_injection),
        cmocka_unit_test(test_inject_now),
        cmocka_unit_test(test_inject_parse),
        cmocka_unit_test(test_parse_joint_list),
        cmocka_unit_test(test_random_invariants),
        cmocka_unit_test(test_config_errors),
        cmocka_unit_test(test_config_from_chain),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
