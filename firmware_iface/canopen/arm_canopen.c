/* SPDX-License-Identifier: MIT */
/* The `canopen` backend of mca/arm.h: an arm whose joints are CiA 402 drives on one bus (mca/canopen.h). */
#include <limits.h> /* INT_MAX */
#include <math.h>   /* fabs */
#include <stdio.h>  /* snprintf */
#include <stdlib.h> /* calloc, free */
#include <string.h>
#include <time.h> /* clock_gettime */

#include "mca/arm.h"
#include "mca/canopen.h"
#include "mca/err.h"

typedef struct co_arm {
    mca_co_master_t m;
    uint32_t div;    /* controller writes per SYNC */
    double dt_ctrl;  /* controller period [s] */
    uint64_t writes; /* mca_arm_write calls accepted */
    uint64_t fb_t1[MCA_CO_MAX_NODES], fb_t2[MCA_CO_MAX_NODES];
    uint32_t sync_frame; /* frame id of the command sent with the newest SYNC */
    int servo;           /* the last command enabled every joint */
    double pos_cmd[MCA_CO_MAX_NODES];
    mca_arm_stats_t st;
} co_arm_t;

static int64_t mono_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

static uint16_t arm_fault(uint8_t kind) {
    switch (kind) {
    case MCA_CO_FAULT_DRIVE:
        return MCA_ARM_FAULT_DRIVE;
    case MCA_CO_FAULT_EMCY:
        return MCA_ARM_FAULT_EMCY;
    case MCA_CO_FAULT_HEARTBEAT:
        return MCA_ARM_FAULT_HEARTBEAT;
    case MCA_CO_FAULT_PDO:
        return MCA_ARM_FAULT_PDO;
    case MCA_CO_FAULT_SDO:
        return MCA_ARM_FAULT_SDO;
    case MCA_CO_FAULT_BUS:
        return MCA_ARM_FAULT_BUS;
    case MCA_CO_FAULT_NMT:
        return MCA_ARM_FAULT_NMT;
    default:
        return MCA_ARM_FAULT_NONE;
    }
}

static int co_read(void *ctx, mca_arm_feedback_t *fb) {
    co_arm_t *a = ctx;
    mca_co_master_t *m = &a->m;
    const int64_t now = mono_ns();
    if (mca_co_master_poll(m, now) < 0) {
        a->st.bus_errors++;
    }
    a->st.bus_errors = m->bus_errors;
    a->st.rx_unknown_id = m->rx_unknown;
    const int bus = m->fault.kind == MCA_CO_FAULT_BUS;
    a->st.bus_off = bus;
    a->st.link_fault = bus ? MCA_ARM_FAULT_BUS : MCA_ARM_FAULT_NONE;
    /* A fault the master latched (a drive's TPDOs stopped, its heartbeat, an EMCY, ...) is reported at once
     * with the last values known, even while a node's TPDOs are missing: waiting for a complete sample would
     * hold the fault back until the daemon's lost-feedback limit, and the controller would meanwhile work
     * on a frozen arm (seen: the PDNN gave up 8 ticks after a node's TPDOs stopped, a fault without its
     * cause). Bus-off stays a link error (EIO): nothing is heard then. */
    const int latched = m->fault.kind != MCA_CO_FAULT_NONE && !bus;
    for (int j = 0; j < m->cfg.n && !latched; j++) {
        if (m->d[j].tpdo1_rx <= a->fb_t1[j] || m->d[j].tpdo2_rx <= a->fb_t2[j]) {
            return bus ? MCA_EIO : MCA_EAGAIN;
        }
    }
    int all_enabled = 1, drive_fault = 0, moving = 0, quick = 0;
    fb->n = m->cfg.n;
    fb->frame_id = a->sync_frame;
    for (int j = 0; j < m->cfg.n; j++) {
        a->fb_t1[j] = m->d[j].tpdo1_rx;
        a->fb_t2[j] = m->d[j].tpdo2_rx;
        mca_co_master_joint(m, j, &fb->position[j], &fb->velocity[j], &fb->torque[j]);
        const mca_co402_state_t s = mca_co402_state(m->d[j].statusword);
        all_enabled &= s == MCA_CO402_OPERATION_ENABLED;
        drive_fault |= s == MCA_CO402_FAULT || s == MCA_CO402_FAULT_REACTION_ACTIVE;
        quick |= s == MCA_CO402_QUICK_STOP_ACTIVE;
        moving |= fabs(fb->velocity[j]) > 1e-6;
        fb->fault_flags[j] =
            (s == MCA_CO402_FAULT || s == MCA_CO402_FAULT_REACTION_ACTIVE) ? MCA_ACT_FLT_ACTUATOR : 0;
    }
    const int faulted = m->fault.kind != MCA_CO_FAULT_NONE || drive_fault;
    fb->fault_code = m->fault.kind != MCA_CO_FAULT_NONE ? arm_fault(m->fault.kind)
                     : drive_fault                      ? MCA_ARM_FAULT_DRIVE
                                                        : MCA_ARM_FAULT_NONE;
    (void)quick;
    if (faulted) {
        fb->state = moving ? MCA_ARM_BRAKING : MCA_ARM_FAULT;
    } else if (all_enabled) {
        fb->state = MCA_ARM_SERVOING;
    } else if (moving) {
        fb->state = MCA_ARM_BRAKING; /* quick stop or disable-operation ramp */
    } else {
        fb->state = MCA_ARM_READY;
    }
    fb->stamp_ns = m->last_rx_ns ? m->last_rx_ns : now;
    a->st.feedback_received++;
    a->st.rx_stamp_user++;
    return fb->state == MCA_ARM_FAULT ? MCA_EFAULT : MCA_OK;
}

static int co_write(void *ctx, const mca_arm_command_t *cmd) {
    co_arm_t *a = ctx;
    mca_co_master_t *m = &a->m;
    if (cmd->n != m->cfg.n) {
        return MCA_EINVAL;
    }
    int servo = 1, clear = 0;
    for (int j = 0; j < cmd->n; j++) {
        if (!isfinite(cmd->velocity[j])) {
            return MCA_EINVAL;
        }
        servo &= (cmd->flags[j] & (MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE)) ==
                 (MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE);
        clear |= (cmd->flags[j] & MCA_ACT_CLEAR_FAULT) != 0;
    }
    if (clear) {
        mca_co_master_fault_reset(m);
    }
    const int faulted = m->fault.kind != MCA_CO_FAULT_NONE;
    const int run = servo && !faulted;
    /* READY = SWITCHED_ON (operation disabled): the next servo enable is one controlword, taken at the
       next SYNC together with its setpoint, as the sim backend's READY -> SERVOING in one cycle */
    mca_co_master_set_goal(m, run       ? MCA_CO402_GOAL_ENABLED
                              : faulted ? MCA_CO402_GOAL_QUICK_STOP
                                        : MCA_CO402_GOAL_SWITCHED_ON);
    const int csp = m->cfg.mode == MCA_CO402_MODE_CSP;
    for (int j = 0; j < cmd->n; j++) {
        if (csp) {
            if (!run || !a->servo || !mca_co_master_all_enabled(m)) {
                /* hold where it stands until every drive is enabled (before its first TPDO the master
                   knows no position) */
                mca_co_master_joint(m, j, &a->pos_cmd[j], NULL, NULL);
            } else {
                a->pos_cmd[j] += cmd->velocity[j] * a->dt_ctrl;
            }
            (void)mca_co_master_set_target(m, j, a->pos_cmd[j]);
        } else {
            (void)mca_co_master_set_target(m, j, run ? cmd->velocity[j] : 0.0);
        }
    }
    a->servo = run;
    a->writes++;
    a->st.commands_sent++;
    if (a->writes % a->div != 0) {
        return MCA_OK; /* held until the next SYNC */
    }
    a->sync_frame = cmd->frame_id;
    const int rc = mca_co_master_tick(m, mono_ns());
    if (rc == MCA_EIO) {
        a->st.bus_errors++;
        return MCA_EIO;
    }
    return rc == MCA_EAGAIN ? MCA_EAGAIN : MCA_OK; /* a latched fault shows in the feedback */
}

static int co_stats(void *ctx, mca_arm_stats_t *st) {
    const co_arm_t *a = ctx;
    *st = a->st;
    return MCA_OK;
}

static void co_close(void *ctx) {
    co_arm_t *a = ctx;
    if (a) {
        mca_co_master_close(&a->m);
        free(a);
    }
}

static const mca_arm_ops_t co_ops = {
    .name = "canopen",
    .read = co_read,
    .write = co_write,
    .stats = co_stats,
    .close = co_close,
};

int mca_canopen_backend_open(struct mca_arm **arm, const mca_co_master_config_t *cfg, uint32_t ctrl_period_us,
                             char *err, size_t errlen) {
    if (!arm || !cfg || ctrl_period_us == 0 || cfg->sync_period_us < ctrl_period_us ||
        cfg->sync_period_us % ctrl_period_us != 0) {
        if (err && errlen) {
            snprintf(err, errlen, "canopen: the SYNC period must be a multiple of the controller period");
        }
        return MCA_EINVAL;
    }
    co_arm_t *a = calloc(1, sizeof(*a));
    if (!a) {
        return MCA_ENOMEM;
    }
    a->div = cfg->sync_period_us / ctrl_period_us;
    a->dt_ctrl = ctrl_period_us * 1e-6;
    int rc = mca_co_master_open(&a->m, cfg);
    if (rc == MCA_OK) {
        rc = mca_co_master_start(&a->m);
    }
    if (rc != MCA_OK) {
        if (err && errlen) {
            char f[192];
            mca_co_fault_describe(&a->m.fault, f, sizeof(f));
            snprintf(err, errlen, "%s (%s)", a->m.err, f);
        }
        mca_co_master_close(&a->m);
        free(a);
        return rc;
    }
    /* start-up: bring every drive to SWITCHED_ON (READY), SYNC by SYNC, within 2 s + the boot timeout */
    mca_co_master_set_goal(&a->m, MCA_CO402_GOAL_SWITCHED_ON);
    const int64_t deadline = mono_ns() + 2000000000LL + (int64_t)cfg->boot_timeout_ms * 1000000;
    /* No PDO timeout during the walk: nothing moves yet, and the deadline already names a drive that never
     * answers (seen in the emulated guest: 4-6 SYNCs without a TPDO1 at start-up, with the shipped 5) */
    const int pdo_timeout = a->m.cfg.pdo_timeout_cycles;
    a->m.cfg.pdo_timeout_cycles = INT_MAX;
    int ready = 0;
    while (!ready && rc == MCA_OK) {
        struct timespec ts = {0, (long)cfg->sync_period_us * 1000};
        nanosleep(&ts, NULL);
        const int t = mca_co_master_tick(&a->m, mono_ns());
        ready = 1;
        for (int j = 0; j < a->m.cfg.n; j++) {
            ready &= mca_co402_state(a->m.d[j].statusword) == MCA_CO402_SWITCHED_ON;
        }
        if (t == MCA_EFAULT || t == MCA_EIO || (!ready && mono_ns() > deadline)) {
            char f[192];
            mca_co_fault_describe(&a->m.fault, f, sizeof(f));
            if (err && errlen) {
                snprintf(err, errlen, "canopen: the drives did not reach SWITCHED_ON (%s)", f);
            }
            rc = t == MCA_EIO ? MCA_EIO : t == MCA_EFAULT ? MCA_EFAULT : MCA_ETIMEDOUT;
        }
    }
    if (rc != MCA_OK) {
        mca_co_master_close(&a->m);
        free(a);
        return rc;
    }
    a->m.cfg.pdo_timeout_cycles = pdo_timeout;
    for (int j = 0; j < a->m.cfg.n; j++) {
        a->m.d[j].tpdo1_sync = a->m.syncs; /* counted from here */
    }
    rc = mca_arm_wrap(arm, &co_ops, a);
    if (rc != MCA_OK) {
        co_close(a);
    }
    return rc;
}

int mca_canopen_backend_fault(const struct mca_arm *arm, char *buf, size_t len) {
    const co_arm_t *a = arm ? mca_arm_backend_ctx(arm, &co_ops) : NULL;
    if (!a || !buf || !len) {
        return MCA_EINVAL;
    }
    /* the loop latches the fault while this (non-rt) reader may run: kind is published last (co_master.c) */
    mca_co_fault_t f = {.kind = __atomic_load_n(&a->m.fault.kind, __ATOMIC_ACQUIRE)};
    if (f.kind != MCA_CO_FAULT_NONE) {
        f.node = a->m.fault.node;
        f.code = a->m.fault.code;
    }
    mca_co_fault_describe(&f, buf, len);
    return MCA_OK;
}

const mca_co_master_t *mca_canopen_backend_master(const struct mca_arm *arm) {
    const co_arm_t *a = arm ? mca_arm_backend_ctx(arm, &co_ops) : NULL;
    return a ? &a->m : NULL;
}
