/* SPDX-License-Identifier: MIT */
/* Simulated arm firmware: delay line, command checks, state machine, watchdog, joint physics.
 * Everything the two simulated backends share lives here; see mca/sim_arm.h for the model. */
#include "mca/sim_arm.h"

#include <errno.h>
#include <math.h>   /* exp, sqrt, log, cos, isfinite, isnan */
#include <stdio.h>  /* snprintf (start-up messages only) */
#include <stdlib.h> /* strtoull, strtol (injection text, start-up only) */
#include <string.h> /* memset, memcpy, strchr, strncmp */
#include <time.h>   /* clock_gettime */

#include "mca/err.h"

#define SIM_PI 3.14159265358979323846

void mca_sim_arm_config_default(mca_sim_arm_config_t *cfg, int n) {
    if (!cfg) {
        return;
    }
    memset(cfg, 0, sizeof(*cfg));
    cfg->n = n < 1 ? 1 : (n > MCA_MAX_DOF ? MCA_MAX_DOF : n);
    for (int j = 0; j < MCA_MAX_DOF; j++) {
        cfg->lower[j] = -INFINITY;
        cfg->upper[j] = INFINITY;
        cfg->vel_limit[j] = 1.0;
        cfg->acc_limit[j] = 10.0;
        cfg->dec_limit[j] = 10.0;
        cfg->inertia[j] = 0.05;
        cfg->damping[j] = 0.5;
    }
    cfg->dt = 0.001;
    cfg->seed = 1;
    cfg->watchdog_cycles = 3;
}

int mca_sim_arm_config_from_chain(mca_sim_arm_config_t *cfg, const mca_chain_t *chain) {
    if (!cfg || !chain || chain->dof < 1 || chain->dof > MCA_MAX_DOF) {
        return MCA_EINVAL;
    }
    mca_sim_arm_config_default(cfg, chain->dof);
    for (int j = 0; j < chain->dof; j++) {
        const mca_joint_model_t *jm = &chain->joint[j];
        if (!jm->continuous) {
            cfg->lower[j] = jm->lower;
            cfg->upper[j] = jm->upper;
        }
        if (isfinite(jm->vel_limit) && jm->vel_limit > 0) {
            cfg->vel_limit[j] = jm->vel_limit;
        }
        double q = 0.0;
        q = q < cfg->lower[j] ? cfg->lower[j] : q;
        q = q > cfg->upper[j] ? cfg->upper[j] : q;
        cfg->q0[j] = q;
    }
    return MCA_OK;
}

/* Format one error message; returns rc so checks read as `return fail(...)`. */
static int fail(char *err, size_t errlen, int rc, const char *field, int j, double val, const char *why) {
    if (err && errlen) {
        if (j >= 0) {
            snprintf(err, errlen, "sim arm config: %s[%d] = %g: %s", field, j, val, why);
        } else {
            snprintf(err, errlen, "sim arm config: %s = %g: %s", field, val, why);
        }
    }
    return rc;
}

static int pos_finite(double x) {
    return isfinite(x) && x > 0;
}

static int nonneg_finite(double x) {
    return isfinite(x) && x >= 0;
}

int mca_sim_arm_config_check(const mca_sim_arm_config_t *cfg, char *err, size_t errlen) {
    if (!cfg) {
        return fail(err, errlen, MCA_EINVAL, "config", -1, 0, "NULL");
    }
    if (cfg->n < 1) {
        return fail(err, errlen, MCA_EINVAL, "n", -1, cfg->n, "need at least 1 joint");
    }
    if (cfg->n > MCA_MAX_DOF) {
        return fail(err, errlen, MCA_ERANGE, "n", -1, cfg->n, "more than MCA_MAX_DOF joints");
    }
    for (int j = 0; j < cfg->n; j++) {
        if (isnan(cfg->lower[j]) || cfg->lower[j] == INFINITY) {
            return fail(err, errlen, MCA_EINVAL, "lower", j, cfg->lower[j], "must be a number or -inf");
        }
        if (isnan(cfg->upper[j]) || cfg->upper[j] == -INFINITY) {
            return fail(err, errlen, MCA_EINVAL, "upper", j, cfg->upper[j], "must be a number or +inf");
        }
        if (cfg->lower[j] > cfg->upper[j]) {
            return fail(err, errlen, MCA_EINVAL, "upper", j, cfg->upper[j], "below lower");
        }
        if (!pos_finite(cfg->vel_limit[j])) {
            return fail(err, errlen, MCA_EINVAL, "vel_limit", j, cfg->vel_limit[j], "must be > 0");
        }
        if (!pos_finite(cfg->acc_limit[j])) {
            return fail(err, errlen, MCA_EINVAL, "acc_limit", j, cfg->acc_limit[j], "must be > 0");
        }
        if (!pos_finite(cfg->dec_limit[j])) {
            return fail(err, errlen, MCA_EINVAL, "dec_limit", j, cfg->dec_limit[j], "must be > 0");
        }
        if (!nonneg_finite(cfg->inertia[j])) {
            return fail(err, errlen, MCA_EINVAL, "inertia", j, cfg->inertia[j], "must be >= 0");
        }
        if (!nonneg_finite(cfg->damping[j])) {
            return fail(err, errlen, MCA_EINVAL, "damping", j, cfg->damping[j], "must be >= 0");
        }
        if (!isfinite(cfg->q0[j]) || cfg->q0[j] < cfg->lower[j] || cfg->q0[j] > cfg->upper[j]) {
            return fail(err, errlen, MCA_EINVAL, "q0", j, cfg->q0[j], "outside [lower, upper]");
        }
    }
    if (!pos_finite(cfg->dt)) {
        return fail(err, errlen, MCA_EINVAL, "dt", -1, cfg->dt, "must be > 0");
    }
    if (!nonneg_finite(cfg->lag_tau)) {
        return fail(err, errlen, MCA_EINVAL, "lag_tau", -1, cfg->lag_tau, "must be >= 0");
    }
    if (cfg->latency_cycles < 0) {
        return fail(err, errlen, MCA_EINVAL, "latency_cycles", -1, cfg->latency_cycles, "must be >= 0");
    }
    if (cfg->latency_cycles > MCA_SIM_MAX_LATENCY) {
        return fail(err, errlen, MCA_ERANGE, "latency_cycles", -1, cfg->latency_cycles,
                    "above MCA_SIM_MAX_LATENCY");
    }
    if (!nonneg_finite(cfg->noise_pos)) {
        return fail(err, errlen, MCA_EINVAL, "noise_pos", -1, cfg->noise_pos, "must be >= 0");
    }
    if (!nonneg_finite(cfg->noise_vel)) {
        return fail(err, errlen, MCA_EINVAL, "noise_vel", -1, cfg->noise_vel, "must be >= 0");
    }
    if (cfg->watchdog_cycles < 1) {
        return fail(err, errlen, MCA_EINVAL, "watchdog_cycles", -1, cfg->watchdog_cycles, "must be >= 1");
    }
    if (cfg->init_cycles < 0) {
        return fail(err, errlen, MCA_EINVAL, "init_cycles", -1, cfg->init_cycles, "must be >= 0");
    }
    if (!nonneg_finite(cfg->vel_fault_ratio) || (cfg->vel_fault_ratio > 0 && cfg->vel_fault_ratio < 1)) {
        return fail(err, errlen, MCA_EINVAL, "vel_fault_ratio", -1, cfg->vel_fault_ratio,
                    "must be 0 (off) or >= 1");
    }
    if (cfg->n_inject < 0 || cfg->n_inject > MCA_SIM_MAX_INJECT) {
        return fail(err, errlen, cfg->n_inject < 0 ? MCA_EINVAL : MCA_ERANGE, "n_inject", -1, cfg->n_inject,
                    "must be 0..MCA_SIM_MAX_INJECT");
    }
    for (int i = 0; i < cfg->n_inject; i++) {
        const mca_sim_inject_t *in = &cfg->inject[i];
        if (in->kind < MCA_SIM_INJ_ACTUATOR || in->kind > MCA_SIM_INJ_DROP_RX) {
            return fail(err, errlen, MCA_EINVAL, "inject.kind", i, in->kind, "unknown fault kind");
        }
        if (in->kind == MCA_SIM_INJ_ACTUATOR && (in->joint < 0 || in->joint >= cfg->n)) {
            return fail(err, errlen, MCA_EINVAL, "inject.joint", i, in->joint, "outside 0..n-1");
        }
    }
    if (err && errlen) {
        err[0] = '\0';
    }
    return MCA_OK;
}

int mca_sim_arm_init(mca_sim_arm_t *arm, const mca_sim_arm_config_t *cfg, char *err, size_t errlen) {
    if (!arm) {
        return fail(err, errlen, MCA_EINVAL, "arm", -1, 0, "NULL");
    }
    int rc = mca_sim_arm_config_check(cfg, err, errlen);
    if (rc != MCA_OK) {
        return rc;
    }
    memset(arm, 0, sizeof(*arm));
    arm->cfg = *cfg;
    for (int j = 0; j < cfg->n; j++) {
        arm->q[j] = cfg->q0[j];
    }
    arm->state = cfg->init_cycles > 0 ? MCA_ARM_INIT : MCA_ARM_READY;
    arm->rng = cfg->seed;
    return MCA_OK;
}

/* splitmix64 (Steele, Lea, Flood 2014): full-period, seedable, no hidden global state. */
static uint64_t splitmix64(uint64_t *s) {
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Standard normal by Box-Muller; u1 in (0, 1] so log() is finite. */
static double gauss(uint64_t *s) {
    double u1 = ((double)(splitmix64(s) >> 11) + 1.0) * (1.0 / 9007199254740992.0);
    double u2 = (double)(splitmix64(s) >> 11) * (1.0 / 9007199254740992.0);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * SIM_PI * u2);
}

static double clampd(double x, double lo, double hi) {
    return x < lo ? lo : (x > hi ? hi : x);
}

/* Step towards target, at most lim; lands exactly on the target when within lim (1e-9 relative slack
 * so that accumulated rounding does not leave a 1e-17 rad/s residue for one more cycle). */
static double step_to(double v0, double target, double lim) {
    double dv = target - v0;
    if (fabs(dv) <= lim * (1.0 + 1e-9)) {
        return target;
    }
    return dv > 0 ? v0 + lim : v0 - lim;
}

/* One cycle of an acceleration-limited velocity: dec while |v| shrinks towards 0, acc while it grows;
 * a sign change spends |v0|/dec of the cycle reaching 0 and the rest accelerating. */
static double rate_limit(double v0, double target, double acc, double dec, double dt) {
    double dv = target - v0;
    if (dv == 0.0) {
        return target;
    }
    if (v0 == 0.0 || (v0 > 0) == (dv > 0)) {
        return step_to(v0, target, acc * dt);
    }
    if (fabs(dv) <= fabs(v0)) { /* target between 0 and v0: pure deceleration */
        return step_to(v0, target, dec * dt);
    }
    double t0 = fabs(v0) / dec; /* time to reach zero */
    if (t0 >= dt * (1.0 - 1e-9)) {
        return step_to(v0, 0.0, dec * dt);
    }
    double mag = fmin(fabs(target), acc * (dt - t0));
    return target > 0 ? mag : -mag;
}

/* Latch the first fault cause; a moving arm brakes first, a standing one faults at once. */
static void raise_fault(mca_sim_arm_t *arm, uint16_t code) {
    if (arm->fault_code == MCA_ARM_FAULT_NONE) {
        arm->fault_code = code;
    }
    switch (arm->state) {
    case MCA_ARM_SERVOING:
        arm->state = MCA_ARM_BRAKING;
        break;
    case MCA_ARM_BRAKING:
    case MCA_ARM_FAULT:
        break;
    default:
        arm->state = MCA_ARM_FAULT;
        break;
    }
}

static int all_flags(const mca_arm_command_t *c, int n, uint8_t mask) {
    for (int j = 0; j < n; j++) {
        if ((c->flags[j] & mask) != mask) {
            return 0;
        }
    }
    return 1;
}

static int any_flag(const mca_arm_command_t *c, int n, uint8_t mask) {
    for (int j = 0; j < n; j++) {
        if (c->flags[j] & mask) {
            return 1;
        }
    }
    return 0;
}

/* Take the setpoint of an accepted command (saturated); may raise FAULT_VELOCITY. */
static void take_setpoint(mca_sim_arm_t *arm, const mca_arm_command_t *c) {
    const mca_sim_arm_config_t *cfg = &arm->cfg;
    int over = 0;
    for (int j = 0; j < cfg->n; j++) {
        double lim = cfg->vel_limit[j];
        double w = c->velocity[j];
        arm->fault_flags[j] &= (uint16_t)~MCA_ACT_FLT_VEL_SAT;
        if (cfg->vel_fault_ratio > 0 && fabs(w) > cfg->vel_fault_ratio * lim) {
            arm->fault_flags[j] |= MCA_ACT_FLT_VELOCITY;
            over = 1;
        }
        if (fabs(w) > lim) {
            arm->fault_flags[j] |= MCA_ACT_FLT_VEL_SAT;
        }
        arm->u[j] = clampd(w, -lim, lim);
    }
    if (over) {
        raise_fault(arm, MCA_ARM_FAULT_VELOCITY);
    }
}

static void make_feedback(mca_sim_arm_t *arm, mca_arm_feedback_t *fb, int noisy) {
    const mca_sim_arm_config_t *cfg = &arm->cfg;
    memset(fb, 0, sizeof(*fb));
    fb->frame_id = arm->last_frame_id;
    fb->n = cfg->n;
    for (int j = 0; j < cfg->n; j++) {
        fb->position[j] = arm->q[j];
        fb->velocity[j] = arm->v[j];
        if (noisy) {
            /* Always two draws per joint when enabled, so the sequence depends on the seed only. */
            if (cfg->noise_pos > 0) {
                fb->position[j] += cfg->noise_pos * gauss(&arm->rng);
            }
            if (cfg->noise_vel > 0) {
                fb->velocity[j] += cfg->noise_vel * gauss(&arm->rng);
            }
        }
        fb->torque[j] = arm->tau[j];
        fb->fault_flags[j] = arm->fault_flags[j];
    }
    fb->state = arm->state;
    fb->fault_code = arm->fault_code;
    if (cfg->stamp_monotonic) {
        struct timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        fb->stamp_ns = (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
    } else {
        fb->stamp_ns = arm->t_ns;
    }
}

void mca_sim_arm_snapshot(const mca_sim_arm_t *arm, mca_arm_feedback_t *fb) {
    if (!arm || !fb) {
        return;
    }
    /* make_feedback() only touches the rng when noisy, so the cast does not change the arm. */
    make_feedback((mca_sim_arm_t *)arm, fb, 0);
}

int mca_sim_arm_cycle(mca_sim_arm_t *arm, const mca_arm_command_t *cmd, double dt, mca_arm_feedback_t *fb) {
    if (!arm || !fb || !isfinite(dt) || dt <= 0) {
        return MCA_EINVAL;
    }
    const mca_sim_arm_config_t *cfg = &arm->cfg;
    const int n = cfg->n;
    const uint64_t k = arm->cycle;
    const mca_arm_state_t state_in = arm->state;
    arm->cnt.cycles++;

    /* 1. fault injections */
    int freeze = 0, silent = 0, drop = 0;
    for (int i = 0; i < cfg->n_inject; i++) {
        const mca_sim_inject_t *in = &cfg->inject[i];
        int active = k >= in->at_cycle && (in->duration == 0 || k - in->at_cycle < in->duration);
        switch (in->kind) {
        case MCA_SIM_INJ_ACTUATOR:
            if (k == in->at_cycle) {
                arm->fault_flags[in->joint] |= MCA_ACT_FLT_ACTUATOR;
                raise_fault(arm, MCA_ARM_FAULT_INJECTED);
            }
            break;
        case MCA_SIM_INJ_FREEZE:
            freeze |= active;
            break;
        case MCA_SIM_INJ_SILENT:
            silent |= active;
            break;
        case MCA_SIM_INJ_DROP_RX:
            drop |= active;
            break;
        default:
            break;
        }
    }

    /* 2. transport delay line: store this cycle's command, deliver the one from `latency` cycles ago */
    if (cmd) {
        arm->cnt.cmd_received++;
        if (drop) {
            arm->cnt.cmd_dropped++;
            cmd = NULL;
        }
    }
    const uint64_t slots = (uint64_t)cfg->latency_cycles + 1;
    if (cmd) {
        arm->delay[k % slots] = *cmd;
        arm->delay_full[k % slots] = 1;
    }
    const mca_arm_command_t *d = NULL;
    const uint64_t out = (k + 1) % slots; /* == (k - latency) mod slots */
    if (arm->delay_full[out]) {
        arm->delay_full[out] = 0;
        d = &arm->delay[out];
    }

    /* 3. command checks */
    int valid = 0;
    if (d) {
        int ok = d->n == n;
        for (int j = 0; ok && j < n; j++) {
            ok = isfinite(d->velocity[j]);
        }
        if (!ok) {
            arm->cnt.cmd_invalid++;
        } else if (arm->have_frame && (int32_t)(d->frame_id - arm->last_frame_id) <= 0) {
            arm->cnt.cmd_stale++;
        } else {
            valid = 1;
            arm->cnt.cmd_accepted++;
            arm->last_frame_id = d->frame_id;
            arm->have_frame = 1;
        }
    }

    /* 4. state machine: at most one transition per cycle (an injected fault counts as one) */
    if (arm->state == state_in) {
        switch (arm->state) {
        case MCA_ARM_INIT:
            if (k >= (uint64_t)cfg->init_cycles) {
                arm->state = MCA_ARM_READY;
            }
            break;
        case MCA_ARM_READY:
            if (valid && all_flags(d, n, MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE)) {
                arm->state = MCA_ARM_SERVOING;
                arm->missed = 0;
                for (int j = 0; j < n; j++) {
                    arm->r[j] = arm->v[j];
                }
                take_setpoint(arm, d);
            }
            break;
        case MCA_ARM_SERVOING:
            if (valid) {
                arm->missed = 0;
                if (!all_flags(d, n, MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE)) {
                    arm->state = MCA_ARM_BRAKING; /* requested stop: ends in READY */
                } else {
                    take_setpoint(arm, d);
                }
            } else if (++arm->missed >= cfg->watchdog_cycles) {
                arm->cnt.watchdog_trips++;
                raise_fault(arm, MCA_ARM_FAULT_WATCHDOG);
            }
            break;
        case MCA_ARM_FAULT:
            if (valid && any_flag(d, n, MCA_ACT_CLEAR_FAULT)) {
                arm->state = MCA_ARM_READY;
                arm->fault_code = MCA_ARM_FAULT_NONE;
                memset(arm->fault_flags, 0, sizeof(arm->fault_flags));
            }
            break;
        default:
            break;
        }
    }

    /* 5. physics */
    int hit = 0;
    const double lag = cfg->lag_tau > 0 ? 1.0 - exp(-dt / cfg->lag_tau) : 1.0;
    for (int j = 0; j < n; j++) {
        const double v0 = arm->v[j];
        double v1 = 0.0;
        if (arm->state == MCA_ARM_SERVOING && cfg->ideal) {
            arm->r[j] = arm->u[j];
            v1 = arm->u[j];
        } else if (arm->state == MCA_ARM_SERVOING) {
            arm->r[j] += (arm->u[j] - arm->r[j]) * lag;
            v1 = rate_limit(v0, arm->r[j], cfg->acc_limit[j], cfg->dec_limit[j], dt);
        } else if (arm->state == MCA_ARM_BRAKING) {
            v1 = rate_limit(v0, 0.0, cfg->acc_limit[j], cfg->dec_limit[j], dt);
            arm->r[j] = v1;
            arm->u[j] = 0.0;
        } else {
            /* brakes hold: v0 is already 0 here, every path into these states passes BRAKING */
            arm->r[j] = 0.0;
            arm->u[j] = 0.0;
        }
        double q1 = cfg->ideal && arm->state == MCA_ARM_SERVOING ? arm->q[j] + v1 * dt
                                                                 : arm->q[j] + 0.5 * dt * (v0 + v1);
        if (q1 > cfg->upper[j]) {
            q1 = cfg->upper[j];
            v1 = 0.0;
            arm->fault_flags[j] |= MCA_ACT_FLT_LIMIT_HIGH;
            hit = 1;
        } else if (q1 < cfg->lower[j]) {
            q1 = cfg->lower[j];
            v1 = 0.0;
            arm->fault_flags[j] |= MCA_ACT_FLT_LIMIT_LOW;
            hit = 1;
        }
        arm->q[j] = q1;
        arm->v[j] = v1;
        arm->tau[j] = cfg->inertia[j] * (v1 - v0) / dt + cfg->damping[j] * v1;
    }
    if (hit) {
        raise_fault(arm, MCA_ARM_FAULT_JOINT_LIMIT);
    }
    /* braking completes in the cycle the last joint reaches zero */
    if (arm->state == MCA_ARM_BRAKING) {
        int stopped = 1;
        for (int j = 0; j < n; j++) {
            stopped &= arm->v[j] == 0.0;
        }
        if (stopped) {
            arm->state = arm->fault_code != MCA_ARM_FAULT_NONE ? MCA_ARM_FAULT : MCA_ARM_READY;
        }
    }
    arm->cycle = k + 1;
    arm->t_ns += (int64_t)llround(dt * 1e9);

    /* 6. feedback */
    mca_arm_feedback_t now;
    make_feedback(arm, &now, 1);
    if (!freeze || !arm->have_last_fb) {
        arm->last_fb = now;
        arm->have_last_fb = 1;
    }
    if (silent) {
        return MCA_EAGAIN;
    }
    *fb = arm->last_fb;
    arm->cnt.feedback_sent++;
    return MCA_OK;
}

int mca_sim_arm_inject_now(mca_sim_arm_t *arm, int kind, uint64_t duration, int joint) {
    if (!arm || kind < MCA_SIM_INJ_ACTUATOR || kind > MCA_SIM_INJ_DROP_RX) {
        return MCA_EINVAL;
    }
    if (kind == MCA_SIM_INJ_ACTUATOR && (joint < 0 || joint >= arm->cfg.n)) {
        return MCA_EINVAL;
    }
    mca_sim_arm_config_t *cfg = &arm->cfg;
    /* reuse a slot whose injection is over, so a long run can inject repeatedly */
    int slot = -1;
    for (int i = 0; i < cfg->n_inject && slot < 0; i++) {
        const mca_sim_inject_t *in = &cfg->inject[i];
        int over = in->kind == MCA_SIM_INJ_ACTUATOR
                       ? in->at_cycle < arm->cycle
                       : (in->duration != 0 && in->at_cycle + in->duration <= arm->cycle);
        if (over) {
            slot = i;
        }
    }
    if (slot < 0) {
        if (cfg->n_inject >= MCA_SIM_MAX_INJECT) {
            return MCA_ERANGE;
        }
        slot = cfg->n_inject++;
    }
    cfg->inject[slot] =
        (mca_sim_inject_t){.kind = kind, .at_cycle = arm->cycle, .duration = duration, .joint = joint};
    return MCA_OK;
}

static const char *const inject_names[] = {"none", "actuator", "freeze", "silent", "drop-rx"};

const char *mca_sim_inject_kind_name(int kind) {
    return kind >= MCA_SIM_INJ_ACTUATOR && kind <= MCA_SIM_INJ_DROP_RX ? inject_names[kind] : inject_names[0];
}

/* an unsigned decimal/hex number at *p (no sign), *p moved past it */
static int parse_count(const char **p, uint64_t *out) {
    char *end = NULL;
    if (**p < '0' || **p > '9') {
        return MCA_EINVAL;
    }
    errno = 0;
    const unsigned long long v = strtoull(*p, &end, 0);
    if (errno || end == *p) {
        return MCA_EINVAL;
    }
    *out = v;
    *p = end;
    return MCA_OK;
}

int mca_sim_parse_joint_list(const char *text, int n, double *q) {
    if (!text || !q || n < 1 || n > MCA_MAX_DOF) {
        return MCA_EINVAL;
    }
    double v[MCA_MAX_DOF];
    const char *p = text;
    for (int j = 0; j < n; j++) {
        char *end = NULL;
        v[j] = strtod(p, &end);
        if (end == p || !isfinite(v[j]) || (j < n - 1 ? *end != ',' : *end != '\0')) {
            return MCA_EINVAL;
        }
        p = end + 1;
    }
    memcpy(q, v, (size_t)n * sizeof *q);
    return MCA_OK;
}

int mca_sim_inject_parse(const char *text, int n_joints, mca_sim_inject_t *out) {
    if (!out) {
        return MCA_EINVAL;
    }
    memset(out, 0, sizeof(*out));
    const char *at = text ? strchr(text, '@') : NULL;
    if (!at) {
        return MCA_EINVAL;
    }
    mca_sim_inject_t in = {0};
    for (int k = MCA_SIM_INJ_ACTUATOR; k <= MCA_SIM_INJ_DROP_RX; k++) {
        if (strlen(inject_names[k]) == (size_t)(at - text) &&
            strncmp(text, inject_names[k], (size_t)(at - text)) == 0) {
            in.kind = k;
        }
    }
    const char *p = at + 1;
    if (in.kind == MCA_SIM_INJ_NONE || parse_count(&p, &in.at_cycle) != MCA_OK) {
        return MCA_EINVAL;
    }
    if (*p == '+') {
        p++;
        if (parse_count(&p, &in.duration) != MCA_OK) {
            return MCA_EINVAL;
        }
    }
    int has_joint = 0;
    if (*p == ':') {
        p++;
        uint64_t j = 0;
        if (parse_count(&p, &j) != MCA_OK || j >= (uint64_t)(n_joints > 0 ? n_joints : 0)) {
            return MCA_EINVAL;
        }
        in.joint = (int)j;
        has_joint = 1;
    }
    if (*p != '\0' || (in.kind == MCA_SIM_INJ_ACTUATOR && !has_joint)) {
        return MCA_EINVAL;
    }
    *out = in;
    return MCA_OK;
}
