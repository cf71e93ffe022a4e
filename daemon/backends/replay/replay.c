/* SPDX-License-Identifier: MIT */
/* The replay backend: a recorded run's feedback (mcad --record, mca/tick_rec.h) played into the loop again,
 * one recorded tick per read, so that the controller reads what it read then, bit for bit (docs/daemon.md,
 * "Recording and replay"). A cell arm takes it with
 *
 *     backend: replay
 *     replay: {file: run.rec}   # relative to the cell file, or in the search path
 *
 * The arm is the recording's arm of the same index (the cell's arms in the recorded cell's order). The first
 * read (the start-up handshake) answers the sample the recorded handshake took, every later read the next
 * tick's feedback: the recorded state, fault code and stamp; a tick that had no new feedback answers
 * MCA_EAGAIN, and so does every read after the last record (the arm falls silent: the daemon's lost-feedback
 * fault ends a replay that runs on). Commands only set the frame id the feedback answers; nothing moves.
 *
 * Calling context: as every backend (mca/arm.h): open and close at start-up and shut-down (the recording is
 * read whole at open), read, write and stats on the RT thread (no allocation, no system call). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/arm.h"
#include "mca/err.h"
#include "mca/errbuf.h" /* mca_errbuf_at, mca_errbuf_printf */
#include "mca/tick_rec.h"
#include "mca/yaml_marks.h" /* mca_yaml_marks_line_of */

#include "daemon__backends.h"

/* ---------------------------------------------------------------- the cell's keys */

/* The replay: section of a cell arm, as loaded. */
typedef struct replay_keys {
    char *file;
} replay_keys_t;

static const cyaml_schema_field_t replay_fields[] = {
    CYAML_FIELD_STRING_PTR("file", CYAML_FLAG_POINTER, replay_keys_t, file, 1, 400),
    CYAML_FIELD_END,
};

/* Its settings, kept in the cell arm's backend_own. */
typedef struct replay_own {
    char file[512 - 8];
} replay_own_t;
MCA_CELL_BACKEND_OWN(replay_own_t, replay_own)

static int replay_read(const mca_check_ctx_t *c, mca_cell_t *cell, int a, const mca_backend_keys_t *k) {
    const replay_keys_t *rk = k->section;
    if (!rk) {
        mca_errbuf_at(c->err, c->errlen, c->file, mca_yaml_marks_line_of(c->marks, "arms[%d]", a),
                      "arms[%d].replay.file: required with backend replay (the recording, mcad --record)", a);
        return MCA_EPARSE;
    }
    replay_own_t *own = replay_own(&cell->arm[a]);
    char field[48];
    snprintf(field, sizeof field, "arms[%d].replay.file", a);
    return mca_config_find(c, field, rk->file, own->file, sizeof own->file);
}

/* ---------------------------------------------------------------- the arm */

typedef struct replay_arm {
    mca_tick_rec_file_t rec;
    int arm, dof;
    int started;       /* the handshake's sample was answered */
    size_t next;       /* the record the next read answers */
    uint32_t frame_id; /* the last command's: the feedback answers it */
    mca_arm_stats_t st;
} replay_arm_t;

static int replay_arm_read(void *ctx, mca_arm_feedback_t *fb) {
    replay_arm_t *r = ctx;
    const mca_tick_rec_header_t *h = &r->rec.header;
    const int a = r->arm;
    if (!r->started) {
        r->started = 1;
        memset(fb, 0, sizeof *fb);
        fb->n = r->dof;
        fb->frame_id = r->frame_id;
        fb->state = MCA_ARM_READY;
        memcpy(fb->position, h->q0[a], sizeof(double) * (size_t)r->dof);
        memcpy(fb->velocity, h->v0[a], sizeof(double) * (size_t)r->dof);
        r->st.feedback_received++;
        return MCA_OK;
    }
    if (r->next >= r->rec.n) {
        return MCA_EAGAIN;
    }
    const mca_tick_rec_t *k = &r->rec.rec[r->next++];
    if (!(k->fresh & (1u << a))) {
        return MCA_EAGAIN;
    }
    memset(fb, 0, sizeof *fb);
    fb->n = r->dof;
    fb->frame_id = r->frame_id;
    fb->state = (mca_arm_state_t)k->arm_state[a];
    fb->fault_code = (uint16_t)k->fault_code[a];
    fb->stamp_ns = k->fb_stamp_ns[a];
    memcpy(fb->position, k->q[a], sizeof(double) * (size_t)r->dof);
    memcpy(fb->velocity, k->v[a], sizeof(double) * (size_t)r->dof);
    r->st.feedback_received++;
    return fb->state == MCA_ARM_FAULT ? MCA_EFAULT : MCA_OK;
}

static int replay_arm_write(void *ctx, const mca_arm_command_t *cmd) {
    replay_arm_t *r = ctx;
    r->frame_id = cmd->frame_id;
    r->st.commands_sent++;
    return MCA_OK;
}

static int replay_arm_stats(void *ctx, mca_arm_stats_t *st) {
    *st = ((replay_arm_t *)ctx)->st;
    return MCA_OK;
}

static void replay_arm_close(void *ctx) {
    replay_arm_t *r = ctx;
    mca_tick_rec_free(&r->rec);
    free(r);
}

static const mca_arm_ops_t replay_ops = {
    .name = "replay",
    .read = replay_arm_read,
    .write = replay_arm_write,
    .stats = replay_arm_stats,
    .close = replay_arm_close,
};

static int replay_open(mca_arm_t **arm, const mca_backend_open_args_t *o, char *err, size_t errlen) {
    const replay_own_t *own = replay_own_c(&o->cell->arm[o->arm]);
    replay_arm_t *r = calloc(1, sizeof *r);
    if (!r) {
        return MCA_ENOMEM;
    }
    r->arm = o->arm;
    r->dof = o->chain->dof;
    int rc = mca_tick_rec_read(own->file, &r->rec, err, errlen);
    if (rc == MCA_OK &&
        ((uint32_t)o->arm >= r->rec.header.n_arms || r->rec.header.dof[o->arm] != (uint32_t)r->dof ||
         r->rec.header.period_ns != o->cell->rt.period_ns)) {
        mca_errbuf_printf(
            err, errlen,
            "%s: recorded %u arms, arm %d with %u joints at %lld ns (this cell: %d joints at %lld ns)",
            own->file, r->rec.header.n_arms, o->arm,
            (uint32_t)o->arm < r->rec.header.n_arms ? r->rec.header.dof[o->arm] : 0u,
            (long long)r->rec.header.period_ns, r->dof, (long long)o->cell->rt.period_ns);
        rc = MCA_ECONFIG;
    }
    if (rc == MCA_OK) {
        rc = mca_arm_wrap(arm, &replay_ops, r);
    }
    if (rc != MCA_OK) {
        replay_arm_close(r);
    }
    return rc;
}

static void replay_describe(const mca_cell_arm_t *ca, int n_joints, char *buf, size_t len) {
    (void)n_joints;
    snprintf(buf, len, " %s", replay_own_c(ca)->file);
}

const mca_backend_def_t mca_backend_replay = {
    .name = "replay",
    .section = "replay",
    .section_fields = replay_fields,
    .section_size = sizeof(replay_keys_t),
    .read = replay_read,
    .open = replay_open,
    .describe = replay_describe,
};
