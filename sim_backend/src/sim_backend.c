/* SPDX-License-Identifier: MIT */
/* The in-process sim backend: one firmware cycle per write, the newest feedback for read. */
#include "mca/sim_backend.h"

#include <stdlib.h> /* calloc, free */

#include "mca/err.h"

typedef struct sim_ctx {
    mca_sim_arm_t fw;
    mca_arm_feedback_t fb; /* newest feedback */
    int fresh;             /* 1 until read */
    mca_arm_stats_t st;
} sim_ctx_t;

static void sim_cycle(sim_ctx_t *c, const mca_arm_command_t *cmd) {
    if (mca_sim_arm_cycle(&c->fw, cmd, c->fw.cfg.dt, &c->fb) == MCA_OK) {
        c->fresh = 1;
        c->st.feedback_received++;
    }
}

static int sim_read(void *ctx, mca_arm_feedback_t *fb) {
    sim_ctx_t *c = ctx;
    if (!c->fresh) {
        return MCA_EAGAIN;
    }
    *fb = c->fb;
    c->fresh = 0;
    return MCA_OK;
}

static int sim_write(void *ctx, const mca_arm_command_t *cmd) {
    sim_ctx_t *c = ctx;
    if (cmd->n != c->fw.cfg.n) {
        return MCA_EINVAL;
    }
    c->st.commands_sent++;
    sim_cycle(c, cmd);
    return MCA_OK;
}

static int sim_stats(void *ctx, mca_arm_stats_t *st) {
    *st = ((sim_ctx_t *)ctx)->st;
    return MCA_OK;
}

static void sim_close(void *ctx) {
    free(ctx);
}

static const mca_arm_ops_t sim_ops = {
    .name = "sim",
    .read = sim_read,
    .write = sim_write,
    .stats = sim_stats,
    .close = sim_close,
};

int mca_sim_backend_open(mca_arm_t **arm, const mca_sim_arm_config_t *cfg, char *err, size_t errlen) {
    if (!arm) {
        return MCA_EINVAL;
    }
    sim_ctx_t *c = calloc(1, sizeof(*c));
    if (!c) {
        return MCA_ENOMEM;
    }
    int rc = mca_sim_arm_init(&c->fw, cfg, err, errlen);
    if (rc == MCA_OK) {
        mca_sim_arm_snapshot(&c->fw, &c->fb);
        c->fresh = 1;
        rc = mca_arm_wrap(arm, &sim_ops, c);
    }
    if (rc != MCA_OK) {
        free(c);
    }
    return rc;
}

mca_sim_arm_t *mca_sim_backend_firmware(mca_arm_t *arm) {
    sim_ctx_t *c = mca_arm_backend_ctx(arm, &sim_ops);
    return c ? &c->fw : NULL;
}

int mca_sim_backend_idle(mca_arm_t *arm, int cycles) {
    sim_ctx_t *c = mca_arm_backend_ctx(arm, &sim_ops);
    if (!c || cycles < 0) {
        return MCA_EINVAL;
    }
    for (int i = 0; i < cycles; i++) {
        sim_cycle(c, NULL);
    }
    return MCA_OK;
}
