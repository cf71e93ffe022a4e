/* SPDX-License-Identifier: MIT */
/* The generic half of the cyclic arm interface: argument checks shared by every backend, then one
 * indirect call into the backend's vtable. No allocation after mca_arm_wrap(). */
#include "mca/arm.h"

#include <math.h>   /* isfinite */
#include <stdlib.h> /* calloc, free */
#include <string.h> /* memset */

#include "mca/err.h"

struct mca_arm {
    const mca_arm_ops_t *ops;
    void *ctx;
};

int mca_arm_wrap(mca_arm_t **arm, const mca_arm_ops_t *ops, void *ctx) {
    if (!arm || !ops || !ops->read || !ops->write) {
        return MCA_EINVAL;
    }
    mca_arm_t *a = calloc(1, sizeof(*a));
    if (!a) {
        return MCA_ENOMEM;
    }
    a->ops = ops;
    a->ctx = ctx;
    *arm = a;
    return MCA_OK;
}

int mca_arm_read(mca_arm_t *arm, mca_arm_feedback_t *fb) {
    if (!arm || !fb) {
        return MCA_EINVAL;
    }
    int rc = arm->ops->read(arm->ctx, fb);
    /* One place decides "the arm is in fault" for every backend, so callers see the same code. */
    if (rc == MCA_OK && fb->state == MCA_ARM_FAULT) {
        return MCA_EFAULT;
    }
    return rc;
}

int mca_arm_write(mca_arm_t *arm, const mca_arm_command_t *cmd) {
    if (!arm || !cmd || cmd->n < 1 || cmd->n > MCA_MAX_DOF) {
        return MCA_EINVAL;
    }
    /* A NaN must never reach an actuator, whatever the backend does with it. */
    for (int j = 0; j < cmd->n; j++) {
        if (!isfinite(cmd->velocity[j])) {
            return MCA_EINVAL;
        }
    }
    return arm->ops->write(arm->ctx, cmd);
}

int mca_arm_stats(mca_arm_t *arm, mca_arm_stats_t *st) {
    if (!arm || !st) {
        return MCA_EINVAL;
    }
    memset(st, 0, sizeof(*st));
    if (!arm->ops->stats) {
        return MCA_OK;
    }
    return arm->ops->stats(arm->ctx, st);
}

const char *mca_arm_backend_name(const mca_arm_t *arm) {
    if (!arm || !arm->ops->name) {
        return "none";
    }
    return arm->ops->name;
}

void *mca_arm_backend_ctx(const mca_arm_t *arm, const mca_arm_ops_t *ops) {
    if (!arm || arm->ops != ops) {
        return NULL;
    }
    return arm->ctx;
}

void mca_arm_close(mca_arm_t *arm) {
    if (!arm) {
        return;
    }
    if (arm->ops->close) {
        arm->ops->close(arm->ctx);
    }
    free(arm);
}

const char *mca_arm_state_name(mca_arm_state_t state) {
    switch (state) {
    case MCA_ARM_INIT:
        return "INIT";
    case MCA_ARM_READY:
        return "READY";
    case MCA_ARM_SERVOING:
        return "SERVOING";
    case MCA_ARM_BRAKING:
        return "BRAKING";
    case MCA_ARM_FAULT:
        return "FAULT";
    default:
        return "UNKNOWN";
    }
}

const char *mca_arm_fault_name(unsigned fault_code) {
    switch (fault_code) {
    case MCA_ARM_FAULT_NONE:
        return "NONE";
    case MCA_ARM_FAULT_WATCHDOG:
        return "WATCHDOG";
    case MCA_ARM_FAULT_JOINT_LIMIT:
        return "JOINT_LIMIT";
    case MCA_ARM_FAULT_VELOCITY:
        return "VELOCITY";
    case MCA_ARM_FAULT_INJECTED:
        return "INJECTED";
    case MCA_ARM_FAULT_BUS:
        return "BUS";
    case MCA_ARM_FAULT_FEEDBACK:
        return "FEEDBACK";
    case MCA_ARM_FAULT_JOINT_COUNT:
        return "JOINT_COUNT";
    case MCA_ARM_FAULT_DRIVE:
        return "DRIVE_FAULT";
    case MCA_ARM_FAULT_EMCY:
        return "EMCY";
    case MCA_ARM_FAULT_HEARTBEAT:
        return "HEARTBEAT";
    case MCA_ARM_FAULT_PDO:
        return "PDO_TIMEOUT";
    case MCA_ARM_FAULT_SDO:
        return "SDO_ABORT";
    case MCA_ARM_FAULT_NMT:
        return "NMT";
    default:
        return "UNKNOWN";
    }
}
