/* SPDX-License-Identifier: MIT */
/* SocketCAN backend of mca/arm.h (see mca/arm_can.h). */
#include "mca/arm_can.h"

#include <math.h>   /* fabs */
#include <stdio.h>  /* snprintf */
#include <stdlib.h> /* calloc, free */
#include <string.h> /* memset, memcpy */

#include <linux/can.h>
#include <linux/can/error.h>

#include "mca/err.h"

int mca_can_link_init(mca_can_link_t *l, uint32_t id_base, int n) {
    if (!l || n < 1 || n > MCA_MAX_DOF || id_base % MCA_CAN_ID_BLOCK != 0 || id_base > MCA_CAN_ID_BASE_MAX) {
        return MCA_EINVAL;
    }
    memset(l, 0, sizeof(*l));
    l->id_base = id_base;
    l->n = n;
    mca_can_seq_reset(&l->seq_fb);
    mca_can_seq_reset(&l->seq_state);
    mca_can_seq_reset(&l->seq_fault);
    const int rc = mca_can_link_set_bounds(l, NULL, NULL);
    return rc == MCA_OK ? mca_can_link_set_rate(l, NULL) : rc;
}

int mca_can_link_set_rate(mca_can_link_t *l, const double *vel_max) {
    if (!l) {
        return MCA_EINVAL;
    }
    double v[MCA_MAX_DOF];
    for (int j = 0; j < MCA_MAX_DOF; j++) {
        v[j] = vel_max && j < l->n ? vel_max[j] : MCA_CAN_FB_JUMP_RATE;
        if (isnan(v[j])) {
            return MCA_EINVAL;
        }
        v[j] = v[j] > 0.0 && v[j] < MCA_CAN_FB_JUMP_RATE ? v[j] : MCA_CAN_FB_JUMP_RATE;
    }
    memcpy(l->vel_max, v, sizeof v);
    return MCA_OK;
}

int mca_can_link_set_bounds(mca_can_link_t *l, const double *lo, const double *hi) {
    if (!l) {
        return MCA_EINVAL;
    }
    double nlo[MCA_MAX_DOF], nhi[MCA_MAX_DOF];
    for (int j = 0; j < MCA_MAX_DOF; j++) {
        nlo[j] = lo && j < l->n ? lo[j] : -MCA_CAN_FB_POS_ABS_MAX;
        nhi[j] = hi && j < l->n ? hi[j] : MCA_CAN_FB_POS_ABS_MAX;
        if (isnan(nlo[j]) || isnan(nhi[j]) || nlo[j] > nhi[j]) {
            return MCA_EINVAL;
        }
        nlo[j] = nlo[j] < -MCA_CAN_FB_POS_ABS_MAX ? -MCA_CAN_FB_POS_ABS_MAX : nlo[j];
        nhi[j] = nhi[j] > MCA_CAN_FB_POS_ABS_MAX ? MCA_CAN_FB_POS_ABS_MAX : nhi[j];
    }
    memcpy(l->pos_lo, nlo, sizeof nlo);
    memcpy(l->pos_hi, nhi, sizeof nhi);
    return MCA_OK;
}

/* The link fault names the worst of what holds now (mca/arm.h: stats.link_fault). */
static void update_link_fault(mca_can_link_t *l) {
    l->st.link_fault = l->st.bus_off    ? MCA_ARM_FAULT_BUS
                       : l->bad_joints  ? MCA_ARM_FAULT_JOINT_COUNT
                       : l->implausible ? MCA_ARM_FAULT_FEEDBACK
                                        : MCA_ARM_FAULT_NONE;
}

/* bus_off and the link fault code that names it move together. */
static void set_bus_off(mca_can_link_t *l, int on) {
    if (on && !l->st.bus_off) {
        l->st.bus_off_events++;
    }
    l->st.bus_off = on;
    update_link_fault(l);
}

const char *mca_can_fb_check_name(unsigned kind) {
    switch (kind) {
    case MCA_CAN_FB_OK:
        return "OK";
    case MCA_CAN_FB_SATURATED:
        return "SATURATED";
    case MCA_CAN_FB_JUMP:
        return "JUMP";
    case MCA_CAN_FB_FRAME_AHEAD:
        return "FRAME_AHEAD";
    case MCA_CAN_FB_FRAME_BACKWARDS:
        return "FRAME_BACKWARDS";
    case MCA_CAN_FB_POSITION:
        return "POSITION";
    default:
        return "UNKNOWN";
    }
}

/* Plausibility of a decoded feedback (frame id already unwrapped) against what the link knows: the
 * field's range, the last applied feedback and the last command sent. @return enum mca_can_fb_check */
static int feedback_check(const mca_can_link_t *l, const mca_arm_feedback_t *fb) {
    const double q_hi = (double)INT32_MAX * MCA_CAN_FB_POS_SCALE;
    const double q_lo = (double)INT32_MIN * MCA_CAN_FB_POS_SCALE;
    for (int j = 0; j < fb->n; j++) {
        if (fb->position[j] >= q_hi || fb->position[j] <= q_lo) {
            return MCA_CAN_FB_SATURATED;
        }
    }
    for (int j = 0; j < fb->n; j++) {
        if (fb->position[j] < l->pos_lo[j] || fb->position[j] > l->pos_hi[j]) {
            return MCA_CAN_FB_POSITION;
        }
    }
    if (l->st.commands_sent > 0 && (int32_t)(fb->frame_id - l->last_frame_id) > 0) {
        return MCA_CAN_FB_FRAME_AHEAD;
    }
    if (!l->have_fb) {
        return MCA_CAN_FB_OK;
    }
    if ((int32_t)(fb->frame_id - l->fb.frame_id) < 0) {
        return MCA_CAN_FB_FRAME_BACKWARDS;
    }
    int64_t dt = fb->stamp_ns - l->fb.stamp_ns;
    dt = dt > MCA_CAN_FB_JUMP_MIN_DT_NS ? dt : MCA_CAN_FB_JUMP_MIN_DT_NS;
    for (int j = 0; j < fb->n; j++) {
        if (fabs(fb->position[j] - l->fb.position[j]) >
            l->vel_max[j] * (double)dt * 1e-9 + MCA_CAN_FB_JUMP_MARGIN) {
            return MCA_CAN_FB_JUMP;
        }
    }
    return MCA_CAN_FB_OK;
}

static int ignored(uint64_t *counter) {
    (*counter)++;
    return MCA_EAGAIN;
}

int mca_can_link_rx(mca_can_link_t *l, const mca_can_frame_t *f) {
    if (!l || !f) {
        return MCA_EINVAL;
    }
    if (f->can_id & CAN_ERR_FLAG) {
        l->st.bus_errors++;
        l->err_pending = 1;
        /* Bus-off ends only when feedback gets through again: a CAN_ERR_RESTARTED frame (alone, or in the
         * same frame as BUSOFF) says the controller restarted, not that the bus works. */
        if (f->can_id & CAN_ERR_BUSOFF) {
            set_bus_off(l, 1);
        }
        return MCA_OK;
    }
    if ((f->can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) || (f->can_id & CAN_SFF_MASK) < l->id_base ||
        (f->can_id & CAN_SFF_MASK) >= l->id_base + MCA_CAN_ID_BLOCK) {
        return ignored(&l->st.rx_unknown_id);
    }
    uint8_t counter = 0;
    switch ((f->can_id & CAN_SFF_MASK) - l->id_base) {
    case MCA_CAN_OFF_FEEDBACK: {
        mca_arm_feedback_t fb = l->fb;
        if (!f->fd || mca_can_decode_feedback(f->data, f->len, l->n, &fb, &counter) != MCA_OK) {
            return ignored(&l->st.rx_bad_length);
        }
        if (!mca_can_seq_accept(&l->seq_fb, counter)) {
            return ignored(&l->st.rx_bad_counter);
        }
        fb.frame_id = mca_can_unwrap16(l->last_frame_id, (uint16_t)fb.frame_id);
        memcpy(fb.fault_flags, l->fault_flags, sizeof(fb.fault_flags));
        fb.stamp_ns = f->stamp_ns;
        const int kind = feedback_check(l, &fb);
        if (kind != MCA_CAN_FB_OK) {
            /* refused and named; the counter was consumed, so a forged frame costs the genuine stream
             * one frame (its repeat), never more */
            l->st.implausible_kind = (uint16_t)kind;
            l->implausible = 1;
            l->err_pending = 1;
            update_link_fault(l);
            return ignored(&l->st.rx_implausible);
        }
        if (f->kstamp) {
            l->st.rx_stamp_kernel++;
        } else {
            l->st.rx_stamp_user++;
        }
        l->fb = fb;
        l->fb_new = 1;
        l->have_fb = 1;
        l->implausible = 0;
        l->st.feedback_received++;
        set_bus_off(l, 0); /* feedback got through: the bus works again */
        return MCA_OK;
    }
    case MCA_CAN_OFF_STATE: {
        mca_can_state_msg_t m;
        if (mca_can_decode_state(f->data, f->len, &m, &counter) != MCA_OK) {
            return ignored(&l->st.rx_bad_length);
        }
        if (!mca_can_seq_accept(&l->seq_state, counter)) {
            return ignored(&l->st.rx_bad_counter);
        }
        l->state = m;
        l->have_state = 1;
        l->st.hb_joints = m.n;
        /* the arm's own joint count against the configured one (the decoder's fb.n is ours) */
        l->bad_joints = m.n != l->n;
        if (l->bad_joints) {
            l->st.rx_bad_joints++;
        }
        update_link_fault(l);
        return MCA_OK;
    }
    case MCA_CAN_OFF_FAULT: {
        mca_can_fault_msg_t m;
        if (mca_can_decode_fault(f->data, f->len, &m, &counter) != MCA_OK) {
            return ignored(&l->st.rx_bad_length);
        }
        if (!mca_can_seq_accept(&l->seq_fault, counter)) {
            return ignored(&l->st.rx_bad_counter);
        }
        memcpy(l->fault_flags, m.fault_flags, sizeof(l->fault_flags));
        return MCA_OK;
    }
    default: /* our own command id from another node, or an id the protocol does not define */
        return ignored(&l->st.rx_unknown_id);
    }
}

int mca_can_link_encode(const mca_can_link_t *l, const mca_arm_command_t *cmd,
                        uint8_t out[MCA_CAN_LEN_COMMAND]) {
    if (!l || !cmd || cmd->n != l->n) {
        return MCA_EINVAL;
    }
    return mca_can_encode_command(cmd, l->tx_counter, out);
}

void mca_can_link_sent(mca_can_link_t *l, const mca_arm_command_t *cmd) {
    if (!l || !cmd) {
        return;
    }
    l->tx_counter++;
    l->last_frame_id = cmd->frame_id;
    l->st.commands_sent++;
}

int mca_can_link_take(mca_can_link_t *l, mca_arm_feedback_t *fb) {
    if (!l || !fb) {
        return MCA_EINVAL;
    }
    /* New feedback wins over a link error seen in the same read (mca/arm.h, read contract): the error
     * stays pending until a take without new feedback reports it. */
    if (l->bad_joints) {
        l->fb_new = 0; /* laid out for another arm: never handed on */
        l->err_pending = 0;
        return MCA_EIO;
    }
    if (l->fb_new) {
        *fb = l->fb;
        l->fb_new = 0;
        return MCA_OK;
    }
    if (l->err_pending || l->st.bus_off) {
        l->err_pending = 0;
        return MCA_EIO;
    }
    return MCA_EAGAIN;
}

void mca_can_options_default(mca_can_options_t *opt) {
    if (opt) {
        opt->brs = 1;
        opt->err_mask = CAN_ERR_MASK;
        opt->rx_burst = 64;
        for (int j = 0; j < MCA_MAX_DOF; j++) {
            opt->pos_lo[j] = -MCA_CAN_FB_POS_ABS_MAX;
            opt->pos_hi[j] = MCA_CAN_FB_POS_ABS_MAX;
            opt->vel_max[j] = MCA_CAN_FB_JUMP_RATE;
        }
    }
}

typedef struct can_backend {
    int fd;
    mca_can_options_t opt;
    mca_can_link_t link;
} can_backend_t;

/* Drain the socket in batches (one recvmmsg each; usually one call a tick, as a short batch says the
 * socket is empty), at most rx_burst frames. */
static int can_read(void *ctx, mca_arm_feedback_t *fb) {
    can_backend_t *b = ctx;
    mca_can_frame_t f[MCA_CAN_RX_BATCH];
    for (int left = b->opt.rx_burst; left > 0;) {
        const int want = left < MCA_CAN_RX_BATCH ? left : MCA_CAN_RX_BATCH;
        int bad = 0;
        const int n = mca_can_sock_recv_batch(b->fd, f, want, &bad);
        if (n < 0) {
            if (n != MCA_EAGAIN) {
                b->link.err_pending = 1; /* reported like an error frame, never hiding feedback already in */
            }
            break;
        }
        for (int i = 0; i < n; i++) {
            mca_can_link_rx(&b->link, &f[i]);
            /* the kernel's count only grows (a u32 that wraps after 4 G drops) */
            if (f[i].rxq_drops > b->link.st.rx_dropped) {
                b->link.st.rx_dropped = f[i].rxq_drops;
            }
        }
        if (bad) {
            b->link.err_pending = 1;
        }
        left -= n + bad;
        if (n + bad < want) {
            break;
        }
    }
    return mca_can_link_take(&b->link, fb);
}

static int can_write(void *ctx, const mca_arm_command_t *cmd) {
    can_backend_t *b = ctx;
    uint8_t buf[MCA_CAN_LEN_COMMAND];
    int rc = mca_can_link_encode(&b->link, cmd, buf);
    if (rc != MCA_OK) {
        return rc;
    }
    rc = mca_can_sock_send(b->fd, b->link.id_base + MCA_CAN_OFF_COMMAND, buf, sizeof(buf), 1, b->opt.brs);
    if (rc == MCA_OK) {
        mca_can_link_sent(&b->link, cmd);
    }
    return rc;
}

static int can_stats(void *ctx, mca_arm_stats_t *st) {
    const can_backend_t *b = ctx;
    *st = b->link.st;
    return MCA_OK;
}

static void can_close(void *ctx) {
    can_backend_t *b = ctx;
    if (b) {
        mca_can_sock_close(b->fd);
        free(b);
    }
}

static const mca_arm_ops_t can_ops = {
    .name = "socketcan",
    .read = can_read,
    .write = can_write,
    .stats = can_stats,
    .close = can_close,
};

int mca_can_backend_open(mca_arm_t **arm, const char *iface, uint32_t id_base, int n_joints,
                         const mca_can_options_t *opt, char *err, size_t errlen) {
    if (!arm || !iface) {
        return MCA_EINVAL;
    }
    can_backend_t *b = calloc(1, sizeof(*b));
    if (!b) {
        return MCA_ENOMEM;
    }
    b->fd = -1;
    if (opt) {
        b->opt = *opt;
    } else {
        mca_can_options_default(&b->opt);
    }
    if (b->opt.rx_burst < 1) {
        b->opt.rx_burst = 1;
    }
    int rc = mca_can_link_init(&b->link, id_base, n_joints);
    if (rc == MCA_OK) {
        rc = mca_can_link_set_bounds(&b->link, b->opt.pos_lo, b->opt.pos_hi);
        rc = rc == MCA_OK ? mca_can_link_set_rate(&b->link, b->opt.vel_max) : rc;
    }
    if (rc != MCA_OK) {
        if (err && errlen) {
            snprintf(err, errlen, "can: bad id base 0x%x, joint count %d or position bounds",
                     (unsigned)id_base, n_joints);
        }
        free(b);
        return rc;
    }
    rc = mca_can_sock_open(&b->fd, iface, id_base, b->opt.err_mask, err, errlen);
    if (rc != MCA_OK) {
        free(b);
        return rc;
    }
    rc = mca_arm_wrap(arm, &can_ops, b);
    if (rc != MCA_OK) {
        can_close(b);
    }
    return rc;
}

int mca_can_backend_state(const mca_arm_t *arm, mca_can_state_msg_t *st) {
    const can_backend_t *b = mca_arm_backend_ctx(arm, &can_ops);
    if (!b || !st) {
        return MCA_EINVAL;
    }
    if (!b->link.have_state) {
        return MCA_EAGAIN;
    }
    *st = b->link.state;
    return MCA_OK;
}

int mca_can_backend_fd(const mca_arm_t *arm) {
    const can_backend_t *b = mca_arm_backend_ctx(arm, &can_ops);
    return b ? b->fd : MCA_EINVAL;
}
