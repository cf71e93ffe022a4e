/* SPDX-License-Identifier: MIT */
/* mca arm protocol codec (layout: docs/can-protocol.md, config/can/mca.dbc). */
#include "mca/can_proto.h"

#include <math.h>   /* isfinite, llround */
#include <string.h> /* memset */

#include "mca/err.h"

/* Byte offsets of the 64-byte frames. */
enum {
    CMD_COUNTER = 0,
    CMD_N = 1,
    CMD_FRAME_ID = 2, /* u16 */
    CMD_FLAGS = 4,    /* 8 x 4 bits */
    CMD_VEL = 8,      /* 8 x int32 */
    CMD_POS = 40,     /* 8 x int24 */
    FB_COUNTER = 0,
    FB_STATE = 1,    /* state bits 0-3, fault code bits 4-7 */
    FB_FRAME_ID = 2, /* u16 */
    FB_POS = 4,      /* 8 x int32 */
    FB_VEL = 36,     /* 8 x int16 */
    FB_TAU = 52,     /* 8 x int12 */
};

/* Little-endian bit field of up to 32 bits at bit offset `bit` (Intel layout, as the DBC says). */
static void put_bits(uint8_t *buf, unsigned bit, unsigned len, uint32_t v) {
    for (unsigned i = 0; i < len; i++, bit++) {
        uint8_t m = (uint8_t)(1u << (bit & 7u));
        if ((v >> i) & 1u) {
            buf[bit >> 3] |= m;
        } else {
            buf[bit >> 3] &= (uint8_t)~m;
        }
    }
}

static uint32_t get_bits(const uint8_t *buf, unsigned bit, unsigned len) {
    uint32_t v = 0;
    for (unsigned i = 0; i < len; i++, bit++) {
        v |= (uint32_t)((buf[bit >> 3] >> (bit & 7u)) & 1u) << i;
    }
    return v;
}

static int32_t sign_extend(uint32_t v, unsigned len) {
    if (len < 32 && (v & (1u << (len - 1)))) {
        v |= ~((1u << len) - 1u);
    }
    return (int32_t)v;
}

/* value / scale rounded to nearest and saturated to a signed len-bit integer. */
static uint32_t to_fixed(double value, double scale, unsigned len) {
    const double hi = (double)((1ll << (len - 1)) - 1);
    const double lo = -(double)(1ll << (len - 1));
    double x = value / scale;
    x = x > hi ? hi : (x < lo ? lo : x);
    return (uint32_t)(int32_t)llround(x);
}

static void put_fixed(uint8_t *buf, unsigned bit, unsigned len, double value, double scale) {
    put_bits(buf, bit, len, to_fixed(value, scale, len));
}

static double get_fixed(const uint8_t *buf, unsigned bit, unsigned len, double scale) {
    return (double)sign_extend(get_bits(buf, bit, len), len) * scale;
}

static void put_u16(uint8_t *buf, unsigned byte, uint16_t v) {
    buf[byte] = (uint8_t)v;
    buf[byte + 1] = (uint8_t)(v >> 8);
}

static uint16_t get_u16(const uint8_t *buf, unsigned byte) {
    return (uint16_t)(buf[byte] | (buf[byte + 1] << 8));
}

int mca_can_encode_command(const mca_arm_command_t *cmd, uint8_t counter, uint8_t out[MCA_CAN_LEN_COMMAND]) {
    if (!cmd || !out || cmd->n < 1 || cmd->n > MCA_MAX_DOF) {
        return MCA_EINVAL;
    }
    for (int j = 0; j < cmd->n; j++) {
        if (!isfinite(cmd->velocity[j]) || !isfinite(cmd->position_ref[j])) {
            return MCA_EINVAL;
        }
    }
    memset(out, 0, MCA_CAN_LEN_COMMAND);
    out[CMD_COUNTER] = counter;
    out[CMD_N] = (uint8_t)cmd->n;
    put_u16(out, CMD_FRAME_ID, (uint16_t)cmd->frame_id);
    for (int j = 0; j < cmd->n; j++) {
        put_bits(out, CMD_FLAGS * 8u + 4u * (unsigned)j, 4, cmd->flags[j] & 0xFu);
        put_fixed(out, (CMD_VEL + 4u * (unsigned)j) * 8u, 32, cmd->velocity[j], MCA_CAN_CMD_VEL_SCALE);
        put_fixed(out, (CMD_POS + 3u * (unsigned)j) * 8u, 24, cmd->position_ref[j], MCA_CAN_CMD_POS_SCALE);
    }
    return MCA_OK;
}

int mca_can_decode_command(const uint8_t *data, size_t len, mca_arm_command_t *cmd, uint8_t *counter) {
    if (!data || !cmd || len != MCA_CAN_LEN_COMMAND) {
        return MCA_EINVAL;
    }
    int n = data[CMD_N];
    if (n < 1 || n > MCA_MAX_DOF) {
        return MCA_EINVAL;
    }
    memset(cmd, 0, sizeof(*cmd));
    cmd->n = n;
    cmd->frame_id = get_u16(data, CMD_FRAME_ID);
    for (int j = 0; j < n; j++) {
        cmd->flags[j] = (uint8_t)get_bits(data, CMD_FLAGS * 8u + 4u * (unsigned)j, 4);
        cmd->velocity[j] = get_fixed(data, (CMD_VEL + 4u * (unsigned)j) * 8u, 32, MCA_CAN_CMD_VEL_SCALE);
        cmd->position_ref[j] = get_fixed(data, (CMD_POS + 3u * (unsigned)j) * 8u, 24, MCA_CAN_CMD_POS_SCALE);
    }
    if (counter) {
        *counter = data[CMD_COUNTER];
    }
    return MCA_OK;
}

int mca_can_encode_feedback(const mca_arm_feedback_t *fb, uint8_t counter,
                            uint8_t out[MCA_CAN_LEN_FEEDBACK]) {
    if (!fb || !out || fb->n < 1 || fb->n > MCA_MAX_DOF) {
        return MCA_EINVAL;
    }
    for (int j = 0; j < fb->n; j++) {
        if (!isfinite(fb->position[j]) || !isfinite(fb->velocity[j]) || !isfinite(fb->torque[j])) {
            return MCA_EINVAL;
        }
    }
    memset(out, 0, MCA_CAN_LEN_FEEDBACK);
    out[FB_COUNTER] = counter;
    unsigned code = fb->fault_code > 15u ? 15u : fb->fault_code;
    out[FB_STATE] = (uint8_t)(((unsigned)fb->state & 0xFu) | (code << 4));
    put_u16(out, FB_FRAME_ID, (uint16_t)fb->frame_id);
    for (int j = 0; j < fb->n; j++) {
        put_fixed(out, (FB_POS + 4u * (unsigned)j) * 8u, 32, fb->position[j], MCA_CAN_FB_POS_SCALE);
        put_fixed(out, (FB_VEL + 2u * (unsigned)j) * 8u, 16, fb->velocity[j], MCA_CAN_FB_VEL_SCALE);
        put_fixed(out, FB_TAU * 8u + 12u * (unsigned)j, 12, fb->torque[j], MCA_CAN_FB_TAU_SCALE);
    }
    return MCA_OK;
}

int mca_can_decode_feedback(const uint8_t *data, size_t len, int n, mca_arm_feedback_t *fb,
                            uint8_t *counter) {
    if (!data || !fb || len != MCA_CAN_LEN_FEEDBACK || n < 1 || n > MCA_MAX_DOF) {
        return MCA_EINVAL;
    }
    unsigned state = data[FB_STATE] & 0xFu;
    if (state > MCA_ARM_FAULT) {
        return MCA_EINVAL;
    }
    fb->n = n;
    fb->state = (mca_arm_state_t)state;
    fb->fault_code = (uint16_t)(data[FB_STATE] >> 4);
    fb->frame_id = get_u16(data, FB_FRAME_ID);
    for (int j = 0; j < MCA_MAX_DOF; j++) {
        int used = j < n;
        fb->position[j] =
            used ? get_fixed(data, (FB_POS + 4u * (unsigned)j) * 8u, 32, MCA_CAN_FB_POS_SCALE) : 0.0;
        fb->velocity[j] =
            used ? get_fixed(data, (FB_VEL + 2u * (unsigned)j) * 8u, 16, MCA_CAN_FB_VEL_SCALE) : 0.0;
        fb->torque[j] =
            used ? get_fixed(data, FB_TAU * 8u + 12u * (unsigned)j, 12, MCA_CAN_FB_TAU_SCALE) : 0.0;
    }
    if (counter) {
        *counter = data[FB_COUNTER];
    }
    return MCA_OK;
}

int mca_can_encode_state(const mca_can_state_msg_t *m, uint8_t counter, uint8_t out[MCA_CAN_LEN_STATE]) {
    if (!m || !out) {
        return MCA_EINVAL;
    }
    out[0] = counter;
    out[1] = m->state;
    put_u16(out, 2, m->fault_code);
    put_u16(out, 4, m->missed);
    out[6] = m->n;
    out[7] = m->rx_errors;
    return MCA_OK;
}

int mca_can_decode_state(const uint8_t *data, size_t len, mca_can_state_msg_t *m, uint8_t *counter) {
    if (!data || !m || len != MCA_CAN_LEN_STATE || data[1] > MCA_ARM_FAULT) {
        return MCA_EINVAL;
    }
    m->state = data[1];
    m->fault_code = get_u16(data, 2);
    m->missed = get_u16(data, 4);
    m->n = data[6];
    m->rx_errors = data[7];
    if (counter) {
        *counter = data[0];
    }
    return MCA_OK;
}

int mca_can_encode_fault(const mca_can_fault_msg_t *m, uint8_t counter, uint8_t out[MCA_CAN_LEN_FAULT]) {
    if (!m || !out) {
        return MCA_EINVAL;
    }
    out[0] = counter;
    out[1] = m->state;
    put_u16(out, 2, m->fault_code);
    for (unsigned j = 0; j < MCA_MAX_DOF; j++) {
        put_u16(out, 4 + 2 * j, m->fault_flags[j]);
    }
    return MCA_OK;
}

int mca_can_decode_fault(const uint8_t *data, size_t len, mca_can_fault_msg_t *m, uint8_t *counter) {
    if (!data || !m || len != MCA_CAN_LEN_FAULT || data[1] > MCA_ARM_FAULT) {
        return MCA_EINVAL;
    }
    m->state = data[1];
    m->fault_code = get_u16(data, 2);
    for (unsigned j = 0; j < MCA_MAX_DOF; j++) {
        m->fault_flags[j] = get_u16(data, 4 + 2 * j);
    }
    if (counter) {
        *counter = data[0];
    }
    return MCA_OK;
}

void mca_can_seq_reset(mca_can_seq_t *s) {
    if (s) {
        memset(s, 0, sizeof(*s));
    }
}

int mca_can_seq_accept(mca_can_seq_t *s, uint8_t counter) {
    if (!s) {
        return 0;
    }
    if (!s->synced || counter == (uint8_t)(s->last + 1u)) {
        s->synced = 1;
        s->last = counter;
        s->run = 0;
        return 1;
    }
    s->run = s->run > 0 && counter == (uint8_t)(s->cand + 1u) ? s->run + 1 : 1;
    s->cand = counter;
    if (s->run >= MCA_CAN_SEQ_RESYNC_RUN) {
        s->last = counter;
        s->run = 0;
        return 1;
    }
    return 0;
}

uint32_t mca_can_unwrap16(uint32_t ref, uint16_t low) {
    /* Signed 16-bit difference gives the nearest candidate (serial-number arithmetic). */
    int16_t d = (int16_t)(uint16_t)(low - (uint16_t)ref);
    return ref + (uint32_t)(int32_t)d;
}
