/* SPDX-License-Identifier: MIT */
/* CANopen codec: NMT, heartbeat, EMCY, SDO client and server state machines, CiA 402 state machine
 * (see mca/canopen.h). No sockets, no clocks: unit-tested on the host (tests/canopen/test_co_proto.c). */
#include "mca/canopen.h"

#include <string.h> /* memcpy, memset, strnlen */

#include "mca/err.h"

static uint32_t le32(const uint8_t *b) {
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static void put32(uint8_t *b, uint32_t v) {
    b[0] = (uint8_t)v;
    b[1] = (uint8_t)(v >> 8);
    b[2] = (uint8_t)(v >> 16);
    b[3] = (uint8_t)(v >> 24);
}

static void frame8(mca_co_frame_t *f, uint16_t id) {
    memset(f, 0, sizeof(*f));
    f->id = id;
    f->len = 8;
}

mca_co_kind_t mca_co_classify(uint16_t id, uint8_t *node, uint8_t *pdo) {
    uint8_t nd = (uint8_t)(id & 0x7F), p = 0;
    mca_co_kind_t k = MCA_CO_K_OTHER;
    const uint16_t fn = id & 0x780;
    if (id == MCA_CO_COB_NMT) {
        k = MCA_CO_K_NMT;
    } else if (id == MCA_CO_COB_SYNC) {
        k = MCA_CO_K_SYNC;
    } else if (nd == 0) {
        k = MCA_CO_K_OTHER;
    } else if (fn == MCA_CO_COB_EMCY) {
        k = MCA_CO_K_EMCY;
    } else if (fn >= 0x180 && fn <= 0x500) {
        /* 0x180 T1, 0x200 R1, 0x280 T2, 0x300 R2, ... 0x480 T4, 0x500 R4 */
        const unsigned slot = (fn - 0x180u) >> 7; /* 0..7 */
        k = (slot & 1u) ? MCA_CO_K_RPDO : MCA_CO_K_TPDO;
        p = (uint8_t)(slot / 2u + 1u);
    } else if (fn == MCA_CO_COB_SDO_TX) {
        k = MCA_CO_K_SDO_TX;
    } else if (fn == MCA_CO_COB_SDO_RX) {
        k = MCA_CO_K_SDO_RX;
    } else if (fn == MCA_CO_COB_HB) {
        k = MCA_CO_K_HB;
    }
    if (node) {
        *node = (k == MCA_CO_K_NMT || k == MCA_CO_K_SYNC || k == MCA_CO_K_OTHER) ? 0 : nd;
    }
    if (pdo) {
        *pdo = p;
    }
    return k;
}

int mca_co_nmt_encode(mca_co_frame_t *f, uint8_t cmd, uint8_t node) {
    if (!f || node > 127) {
        return MCA_EINVAL;
    }
    memset(f, 0, sizeof(*f));
    f->id = MCA_CO_COB_NMT;
    f->len = 2;
    f->data[0] = cmd;
    f->data[1] = node;
    return MCA_OK;
}

int mca_co_hb_encode(mca_co_frame_t *f, uint8_t node, uint8_t state) {
    if (!f || node == 0 || node > 127) {
        return MCA_EINVAL;
    }
    memset(f, 0, sizeof(*f));
    f->id = (uint16_t)(MCA_CO_COB_HB + node);
    f->len = 1;
    f->data[0] = state;
    return MCA_OK;
}

int mca_co_emcy_encode(mca_co_frame_t *f, uint8_t node, const mca_co_emcy_t *e) {
    if (!f || !e || node == 0 || node > 127) {
        return MCA_EINVAL;
    }
    frame8(f, (uint16_t)(MCA_CO_COB_EMCY + node));
    f->data[0] = (uint8_t)e->code;
    f->data[1] = (uint8_t)(e->code >> 8);
    f->data[2] = e->reg;
    memcpy(f->data + 3, e->mfr, 5);
    return MCA_OK;
}

int mca_co_emcy_decode(const mca_co_frame_t *f, mca_co_emcy_t *e) {
    if (!f || !e || f->len != 8) {
        return MCA_EINVAL;
    }
    e->code = (uint16_t)(f->data[0] | f->data[1] << 8);
    e->reg = f->data[2];
    memcpy(e->mfr, f->data + 3, 5);
    return MCA_OK;
}

const char *mca_co_emcy_text(uint16_t code) {
    switch (code) {
    case 0x0000:
        return "error reset or no error";
    case 0x8110:
        return "CAN overrun (objects lost)";
    case 0x8120:
        return "CAN in error passive mode";
    case 0x8130:
        return "life guard or heartbeat error";
    case 0x8140:
        return "recovered from bus off";
    case 0x8611:
        return "following error";
    case 0xFF00:
        return "device specific (injected fault)";
    default:
        break;
    }
    switch (code >> 12) {
    case 0x1:
        return "generic error";
    case 0x2:
        return "current";
    case 0x3:
        return "voltage";
    case 0x4:
        return "temperature";
    case 0x5:
        return "device hardware";
    case 0x6:
        return "device software";
    case 0x7:
        return "additional modules";
    case 0x8:
        return (code >> 8) == 0x81 ? "communication" : (code >> 8) == 0x82 ? "protocol error" : "monitoring";
    case 0x9:
        return "external error";
    case 0xF:
        return (code >> 8) == 0xFF ? "device specific" : "additional functions";
    default:
        return "unknown error code";
    }
}

const char *mca_co_abort_text(uint32_t code) {
    switch (code) {
    case 0x05030000u:
        return "toggle bit not alternated";
    case 0x05040000u:
        return "SDO protocol timed out";
    case 0x05040001u:
        return "client/server command specifier not valid or unknown";
    case 0x05040002u:
        return "invalid block size";
    case 0x05040005u:
        return "out of memory";
    case 0x06010000u:
        return "unsupported access to an object";
    case 0x06010001u:
        return "attempt to read a write only object";
    case 0x06010002u:
        return "attempt to write a read only object";
    case 0x06020000u:
        return "object does not exist in the object dictionary";
    case 0x06040041u:
        return "object cannot be mapped to the PDO";
    case 0x06040042u:
        return "the number and length of the objects to be mapped would exceed PDO length";
    case 0x06040043u:
        return "general parameter incompatibility";
    case 0x06040047u:
        return "general internal incompatibility in the device";
    case 0x06060000u:
        return "access failed due to a hardware error";
    case 0x06070010u:
        return "data type does not match, length of service parameter does not match";
    case 0x06070012u:
        return "data type does not match, length of service parameter too high";
    case 0x06070013u:
        return "data type does not match, length of service parameter too low";
    case 0x06090011u:
        return "sub-index does not exist";
    case 0x06090030u:
        return "invalid value for parameter";
    case 0x06090031u:
        return "value of parameter written too high";
    case 0x06090032u:
        return "value of parameter written too low";
    case 0x08000000u:
        return "general error";
    case 0x08000020u:
        return "data cannot be transferred or stored to the application";
    case 0x08000021u:
        return "data cannot be transferred or stored to the application because of local control";
    case 0x08000022u:
        return "data cannot be transferred or stored to the application because of the present device state";
    default:
        return "unknown abort code";
    }
}

/* ---- SDO client ---- */

static void sdo_abort_frame(mca_co_frame_t *tx, uint16_t id, uint16_t index, uint8_t sub, uint32_t code) {
    frame8(tx, id);
    tx->data[0] = 0x80;
    tx->data[1] = (uint8_t)index;
    tx->data[2] = (uint8_t)(index >> 8);
    tx->data[3] = sub;
    put32(tx->data + 4, code);
}

static void sdo_head(mca_co_frame_t *tx, uint16_t id, uint8_t cmd, uint16_t index, uint8_t sub) {
    frame8(tx, id);
    tx->data[0] = cmd;
    tx->data[1] = (uint8_t)index;
    tx->data[2] = (uint8_t)(index >> 8);
    tx->data[3] = sub;
}

int mca_co_sdo_download_start(mca_co_sdo_client_t *c, mca_co_frame_t *tx, uint8_t node, uint16_t index,
                              uint8_t sub, const void *data, size_t len) {
    if (!c || !tx || !data || node == 0 || node > 127 || len == 0 || len > MCA_CO_SDO_MAX) {
        return MCA_EINVAL;
    }
    memset(c, 0, sizeof(*c));
    c->node = node;
    c->index = index;
    c->sub = sub;
    c->len = len;
    memcpy(c->data, data, len);
    c->status = MCA_CO_SDO_SEND;
    const uint16_t id = (uint16_t)(MCA_CO_COB_SDO_RX + node);
    if (len <= 4) {
        sdo_head(tx, id, (uint8_t)(0x23 | (4 - len) << 2), index, sub);
        memcpy(tx->data + 4, data, len);
    } else {
        c->segmented = 1;
        sdo_head(tx, id, 0x21, index, sub);
        put32(tx->data + 4, (uint32_t)len);
    }
    return MCA_OK;
}

int mca_co_sdo_upload_start(mca_co_sdo_client_t *c, mca_co_frame_t *tx, uint8_t node, uint16_t index,
                            uint8_t sub) {
    if (!c || !tx || node == 0 || node > 127) {
        return MCA_EINVAL;
    }
    memset(c, 0, sizeof(*c));
    c->node = node;
    c->upload = 1;
    c->index = index;
    c->sub = sub;
    c->status = MCA_CO_SDO_SEND;
    sdo_head(tx, (uint16_t)(MCA_CO_COB_SDO_RX + node), 0x40, index, sub);
    return MCA_OK;
}

static mca_co_sdo_status_t client_abort(mca_co_sdo_client_t *c, mca_co_frame_t *tx, uint32_t code) {
    sdo_abort_frame(tx, (uint16_t)(MCA_CO_COB_SDO_RX + c->node), c->index, c->sub, code);
    c->abort_code = code;
    c->by_server = 0;
    c->status = MCA_CO_SDO_ABORTED;
    return c->status;
}

/* next download segment from c->pos */
static void client_dl_segment(mca_co_sdo_client_t *c, mca_co_frame_t *tx) {
    const size_t rest = c->len - c->pos;
    const size_t n = rest > 7 ? 7 : rest;
    const int last = rest <= 7;
    frame8(tx, (uint16_t)(MCA_CO_COB_SDO_RX + c->node));
    tx->data[0] = (uint8_t)(c->toggle << 4 | (7 - n) << 1 | (last ? 1 : 0));
    memcpy(tx->data + 1, c->data + c->pos, n);
    c->pos += n;
}

mca_co_sdo_status_t mca_co_sdo_client_rx(mca_co_sdo_client_t *c, const mca_co_frame_t *rx,
                                         mca_co_frame_t *tx) {
    if (!c || !rx || !tx) {
        return MCA_CO_SDO_WAIT;
    }
    if (c->status != MCA_CO_SDO_SEND || rx->id != MCA_CO_COB_SDO_TX + c->node) {
        return MCA_CO_SDO_WAIT;
    }
    if (rx->len != 8) {
        return client_abort(c, tx, MCA_CO_ABORT_CMD);
    }
    const uint8_t b0 = rx->data[0];
    const uint8_t scs = b0 >> 5;
    const uint16_t idx = (uint16_t)(rx->data[1] | rx->data[2] << 8);
    if (b0 == 0x80) {
        c->abort_code = le32(rx->data + 4);
        c->by_server = 1;
        c->status = MCA_CO_SDO_ABORTED;
        return c->status;
    }
    const int initiated = c->pos > 0 || (c->upload && c->segmented);
    if (!c->upload) {
        if (!c->segmented || (c->pos == 0)) {
            /* initiate download response */
            if (scs != 3 || idx != c->index || rx->data[3] != c->sub) {
                return client_abort(c, tx, MCA_CO_ABORT_CMD);
            }
            if (!c->segmented) {
                c->status = MCA_CO_SDO_DONE;
                return c->status;
            }
            client_dl_segment(c, tx);
            return MCA_CO_SDO_SEND;
        }
        /* download segment response */
        if (scs != 1) {
            return client_abort(c, tx, MCA_CO_ABORT_CMD);
        }
        if (((b0 >> 4) & 1) != c->toggle) {
            return client_abort(c, tx, MCA_CO_ABORT_TOGGLE);
        }
        c->toggle ^= 1;
        if (c->pos >= c->len) {
            c->status = MCA_CO_SDO_DONE;
            return c->status;
        }
        client_dl_segment(c, tx);
        return MCA_CO_SDO_SEND;
    }
    if (!initiated) {
        /* initiate upload response */
        if (scs != 2 || idx != c->index || rx->data[3] != c->sub) {
            return client_abort(c, tx, MCA_CO_ABORT_CMD);
        }
        if (b0 & 0x02) { /* expedited */
            const size_t n = (b0 & 0x01) ? 4u - ((b0 >> 2) & 3u) : 4u;
            memcpy(c->data, rx->data + 4, n);
            c->len = n;
            c->status = MCA_CO_SDO_DONE;
            return c->status;
        }
        const uint32_t size = (b0 & 0x01) ? le32(rx->data + 4) : MCA_CO_SDO_MAX;
        if (size > MCA_CO_SDO_MAX) {
            return client_abort(c, tx, MCA_CO_ABORT_NO_MEM);
        }
        c->segmented = 1;
        c->len = 0;
        c->pos = 0;
        frame8(tx, (uint16_t)(MCA_CO_COB_SDO_RX + c->node));
        tx->data[0] = (uint8_t)(0x60 | c->toggle << 4);
        return MCA_CO_SDO_SEND;
    }
    /* upload segment response */
    if (scs != 0) {
        return client_abort(c, tx, MCA_CO_ABORT_CMD);
    }
    if (((b0 >> 4) & 1) != c->toggle) {
        return client_abort(c, tx, MCA_CO_ABORT_TOGGLE);
    }
    const size_t n = 7u - ((b0 >> 1) & 7u);
    if (c->len + n > MCA_CO_SDO_MAX) {
        return client_abort(c, tx, MCA_CO_ABORT_NO_MEM);
    }
    memcpy(c->data + c->len, rx->data + 1, n);
    c->len += n;
    c->pos = c->len;
    if (b0 & 0x01) {
        c->status = MCA_CO_SDO_DONE;
        return c->status;
    }
    c->toggle ^= 1;
    frame8(tx, (uint16_t)(MCA_CO_COB_SDO_RX + c->node));
    tx->data[0] = (uint8_t)(0x60 | c->toggle << 4);
    return MCA_CO_SDO_SEND;
}

void mca_co_sdo_client_timeout(mca_co_sdo_client_t *c, mca_co_frame_t *tx) {
    if (c && tx) {
        (void)client_abort(c, tx, MCA_CO_ABORT_TIMEOUT);
    }
}

/* ---- object dictionary and SDO server ---- */

const mca_co_od_entry_t *mca_co_od_find(const mca_co_od_entry_t *od, size_t n, uint16_t index, uint8_t sub,
                                        uint32_t *abort) {
    int have_index = 0;
    for (size_t i = 0; od && i < n; i++) {
        if (od[i].index == index) {
            have_index = 1;
            if (od[i].sub == sub) {
                return &od[i];
            }
        }
    }
    if (abort) {
        *abort = have_index ? MCA_CO_ABORT_NO_SUB : MCA_CO_ABORT_NO_OBJECT;
    }
    return NULL;
}

int mca_co_sdo_server_init(mca_co_sdo_server_t *s, uint8_t node, const mca_co_od_entry_t *od, size_t n_od,
                           mca_co_od_written_fn written, void *user) {
    if (!s || !od || node == 0 || node > 127) {
        return MCA_EINVAL;
    }
    memset(s, 0, sizeof(*s));
    s->node = node;
    s->od = od;
    s->n_od = n_od;
    s->written = written;
    s->user = user;
    return MCA_OK;
}

static size_t entry_len(const mca_co_od_entry_t *e) {
    return e->is_str ? strnlen((const char *)e->ptr, e->size) : e->size;
}

/* write @p len bytes into entry e (range check, callback); returns 0 or an abort code */
static uint32_t entry_write(mca_co_sdo_server_t *s, const mca_co_od_entry_t *e, const uint8_t *v,
                            size_t len) {
    uint8_t old[MCA_CO_SDO_MAX];
    if (e->is_str) {
        if (len > e->size) {
            return MCA_CO_ABORT_TYPE_HIGH;
        }
        memcpy(old, e->ptr, e->size);
        memset(e->ptr, 0, e->size);
        memcpy(e->ptr, v, len);
    } else {
        if (len != e->size) {
            return len > e->size ? MCA_CO_ABORT_TYPE_HIGH : MCA_CO_ABORT_TYPE_LOW;
        }
        if (e->min <= e->max) {
            uint64_t u = 0;
            for (size_t i = 0; i < len; i++) {
                u |= (uint64_t)v[i] << (8 * i);
            }
            int64_t x = (int64_t)u;
            if (e->is_signed && len < 8 && (u >> (8 * len - 1)) & 1u) {
                x = (int64_t)(u | ~((UINT64_C(1) << (8 * len)) - 1));
            }
            if (x < e->min || x > e->max) {
                return MCA_CO_ABORT_VALUE;
            }
        }
        memcpy(old, e->ptr, e->size);
        memcpy(e->ptr, v, len); /* little-endian host (x86, arm): the value's own layout */
    }
    if (s->written) {
        const uint32_t ab = s->written(s->user, e);
        if (ab) {
            memcpy(e->ptr, old, e->size);
            return ab;
        }
    }
    return 0;
}

int mca_co_sdo_server_rx(mca_co_sdo_server_t *s, const mca_co_frame_t *rx, mca_co_frame_t *tx) {
    if (!s || !rx || !tx) {
        return MCA_EINVAL;
    }
    if (rx->id != MCA_CO_COB_SDO_RX + s->node || rx->len != 8) {
        return 0;
    }
    const uint16_t txid = (uint16_t)(MCA_CO_COB_SDO_TX + s->node);
    const uint8_t b0 = rx->data[0];
    const uint8_t ccs = b0 >> 5;
    const uint16_t idx = (uint16_t)(rx->data[1] | rx->data[2] << 8);
    const uint8_t sub = rx->data[3];
    uint32_t ab = 0;
    const mca_co_od_entry_t *e = NULL;
    switch (ccs) {
    case 1: /* initiate download */
        s->active = 0;
        e = mca_co_od_find(s->od, s->n_od, idx, sub, &ab);
        if (!e) {
            break;
        }
        if (!(e->access & MCA_CO_ACC_WO)) {
            ab = MCA_CO_ABORT_READ_ONLY;
            break;
        }
        if (b0 & 0x02) {
            const size_t n = (b0 & 0x01) ? 4u - ((b0 >> 2) & 3u) : (e->size < 4 ? e->size : 4u);
            ab = entry_write(s, e, rx->data + 4, n);
            if (!ab) {
                sdo_head(tx, txid, 0x60, idx, sub);
                return 1;
            }
            break;
        }
        {
            const uint32_t size = (b0 & 0x01) ? le32(rx->data + 4) : e->size;
            if (size > MCA_CO_SDO_MAX || size > e->size) {
                ab = MCA_CO_ABORT_TYPE_HIGH;
                break;
            }
            s->active = 1;
            s->upload = 0;
            s->toggle = 0;
            s->e = e;
            s->len = size;
            s->pos = 0;
            sdo_head(tx, txid, 0x60, idx, sub);
            return 1;
        }
    case 0: /* download segment */
        if (!s->active || s->upload) {
            ab = MCA_CO_ABORT_CMD;
            break;
        }
        if (((b0 >> 4) & 1) != s->toggle) {
            s->active = 0;
            sdo_abort_frame(tx, txid, s->e->index, s->e->sub, MCA_CO_ABORT_TOGGLE);
            return 1;
        }
        {
            const size_t n = 7u - ((b0 >> 1) & 7u);
            if (s->pos + n > MCA_CO_SDO_MAX) {
                s->active = 0;
                sdo_abort_frame(tx, txid, s->e->index, s->e->sub, MCA_CO_ABORT_TYPE_HIGH);
                return 1;
            }
            memcpy(s->buf + s->pos, rx->data + 1, n);
            s->pos += n;
            if (b0 & 0x01) {
                s->active = 0;
                ab = entry_write(s, s->e, s->buf, s->pos);
                if (ab) {
                    sdo_abort_frame(tx, txid, s->e->index, s->e->sub, ab);
                    return 1;
                }
            }
            frame8(tx, txid);
            tx->data[0] = (uint8_t)(0x20 | s->toggle << 4);
            s->toggle ^= 1;
            return 1;
        }
    case 2: /* initiate upload */
        s->active = 0;
        e = mca_co_od_find(s->od, s->n_od, idx, sub, &ab);
        if (!e) {
            break;
        }
        if (!(e->access & MCA_CO_ACC_RO)) {
            ab = MCA_CO_ABORT_WRITE_ONLY;
            break;
        }
        {
            const size_t n = entry_len(e);
            if (n <= 4 && !e->is_str) {
                sdo_head(tx, txid, (uint8_t)(0x43 | (4 - n) << 2), idx, sub);
                memcpy(tx->data + 4, e->ptr, n);
                return 1;
            }
            s->active = 1;
            s->upload = 1;
            s->toggle = 0;
            s->e = e;
            s->len = n > MCA_CO_SDO_MAX ? MCA_CO_SDO_MAX : n;
            memcpy(s->buf, e->ptr, s->len);
            s->pos = 0;
            sdo_head(tx, txid, 0x41, idx, sub);
            put32(tx->data + 4, (uint32_t)s->len);
            return 1;
        }
    case 3: /* upload segment */
        if (!s->active || !s->upload) {
            ab = MCA_CO_ABORT_CMD;
            break;
        }
        if (((b0 >> 4) & 1) != s->toggle) {
            s->active = 0;
            sdo_abort_frame(tx, txid, s->e->index, s->e->sub, MCA_CO_ABORT_TOGGLE);
            return 1;
        }
        {
            const size_t rest = s->len - s->pos;
            const size_t n = rest > 7 ? 7 : rest;
            const int last = rest <= 7;
            frame8(tx, txid);
            tx->data[0] = (uint8_t)(s->toggle << 4 | (7 - n) << 1 | (last ? 1 : 0));
            memcpy(tx->data + 1, s->buf + s->pos, n);
            s->pos += n;
            s->toggle ^= 1;
            if (last) {
                s->active = 0;
            }
            return 1;
        }
    case 4: /* abort from the client: no answer */
        s->active = 0;
        return 0;
    default:
        ab = MCA_CO_ABORT_CMD;
        break;
    }
    sdo_abort_frame(tx, txid, idx, sub, ab ? ab : MCA_CO_ABORT_GENERAL);
    return 1;
}

/* ---- CiA 402 ---- */

mca_co402_state_t mca_co402_state(uint16_t sw) {
    switch (sw & 0x4F) {
    case 0x00:
        return MCA_CO402_NOT_READY;
    case 0x40:
        return MCA_CO402_SWITCH_ON_DISABLED;
    case 0x0F:
        return MCA_CO402_FAULT_REACTION_ACTIVE;
    case 0x08:
        return MCA_CO402_FAULT;
    default:
        break;
    }
    switch (sw & 0x6F) {
    case 0x21:
        return MCA_CO402_READY_TO_SWITCH_ON;
    case 0x23:
        return MCA_CO402_SWITCHED_ON;
    case 0x27:
        return MCA_CO402_OPERATION_ENABLED;
    case 0x07:
        return MCA_CO402_QUICK_STOP_ACTIVE;
    default:
        return MCA_CO402_NOT_READY;
    }
}

const char *mca_co402_state_name(mca_co402_state_t s) {
    static const char *const names[] = {
        "NOT_READY",         "SWITCH_ON_DISABLED", "READY_TO_SWITCH_ON",    "SWITCHED_ON",
        "OPERATION_ENABLED", "QUICK_STOP_ACTIVE",  "FAULT_REACTION_ACTIVE", "FAULT"};
    return (unsigned)s < sizeof(names) / sizeof(names[0]) ? names[s] : "UNKNOWN";
}

uint16_t mca_co402_statusword(mca_co402_state_t s) {
    switch (s) {
    case MCA_CO402_SWITCH_ON_DISABLED:
        return 0x0040;
    case MCA_CO402_READY_TO_SWITCH_ON:
        return 0x0031;
    case MCA_CO402_SWITCHED_ON:
        return 0x0033;
    case MCA_CO402_OPERATION_ENABLED:
        return 0x0037;
    case MCA_CO402_QUICK_STOP_ACTIVE:
        return 0x0017;
    case MCA_CO402_FAULT_REACTION_ACTIVE:
        return 0x001F;
    case MCA_CO402_FAULT:
        return 0x0008;
    default:
        return 0x0000;
    }
}

uint16_t mca_co402_controlword(mca_co402_state_t s, mca_co402_goal_t goal, int fault_reset,
                               uint16_t prev_cw) {
    switch (s) {
    case MCA_CO402_FAULT:
        if (!fault_reset) {
            return MCA_CO402_CW_DISABLE_VOLTAGE;
        }
        /* rising edge of bit 7: a 0 first if the last controlword already had it */
        return (prev_cw & MCA_CO402_CW_FAULT_RESET) ? MCA_CO402_CW_DISABLE_VOLTAGE : MCA_CO402_CW_FAULT_RESET;
    case MCA_CO402_NOT_READY:
    case MCA_CO402_FAULT_REACTION_ACTIVE:
        return MCA_CO402_CW_DISABLE_VOLTAGE;
    default:
        break;
    }
    if (goal == MCA_CO402_GOAL_QUICK_STOP) {
        return (s == MCA_CO402_OPERATION_ENABLED || s == MCA_CO402_QUICK_STOP_ACTIVE)
                   ? MCA_CO402_CW_QUICK_STOP
                   : MCA_CO402_CW_DISABLE_VOLTAGE;
    }
    if (goal == MCA_CO402_GOAL_DISABLED) {
        return MCA_CO402_CW_DISABLE_VOLTAGE;
    }
    if (goal == MCA_CO402_GOAL_SWITCHED_ON) {
        switch (s) {
        case MCA_CO402_SWITCH_ON_DISABLED:
            return MCA_CO402_CW_SHUTDOWN;
        case MCA_CO402_READY_TO_SWITCH_ON:
        case MCA_CO402_SWITCHED_ON:
        case MCA_CO402_OPERATION_ENABLED:
            return MCA_CO402_CW_SWITCH_ON; /* from OPERATION_ENABLED: disable operation */
        default:
            return MCA_CO402_CW_DISABLE_VOLTAGE;
        }
    }
    switch (s) {
    case MCA_CO402_SWITCH_ON_DISABLED:
        return MCA_CO402_CW_SHUTDOWN;
    case MCA_CO402_READY_TO_SWITCH_ON:
        return MCA_CO402_CW_SWITCH_ON;
    case MCA_CO402_SWITCHED_ON:
    case MCA_CO402_OPERATION_ENABLED:
        return MCA_CO402_CW_ENABLE_OPERATION;
    case MCA_CO402_QUICK_STOP_ACTIVE:
    default:
        return MCA_CO402_CW_DISABLE_VOLTAGE; /* back through SWITCH_ON_DISABLED */
    }
}

mca_co402_state_t mca_co402_drive_next(mca_co402_state_t s, uint16_t cw, uint16_t prev_cw) {
    const int shutdown = (cw & 0x87) == 0x06;
    const int switch_on = (cw & 0x8F) == 0x07;
    const int enable = (cw & 0x8F) == 0x0F;
    const int disable_voltage = (cw & 0x82) == 0x00;
    const int quick_stop = (cw & 0x86) == 0x02;
    switch (s) {
    case MCA_CO402_SWITCH_ON_DISABLED:
        return shutdown ? MCA_CO402_READY_TO_SWITCH_ON : s;
    case MCA_CO402_READY_TO_SWITCH_ON:
        if (switch_on) {
            return MCA_CO402_SWITCHED_ON;
        }
        return (disable_voltage || quick_stop) ? MCA_CO402_SWITCH_ON_DISABLED : s;
    case MCA_CO402_SWITCHED_ON:
        if (enable) {
            return MCA_CO402_OPERATION_ENABLED;
        }
        if (shutdown) {
            return MCA_CO402_READY_TO_SWITCH_ON;
        }
        return (disable_voltage || quick_stop) ? MCA_CO402_SWITCH_ON_DISABLED : s;
    case MCA_CO402_OPERATION_ENABLED:
        if (switch_on) {
            return MCA_CO402_SWITCHED_ON; /* disable operation */
        }
        if (shutdown) {
            return MCA_CO402_READY_TO_SWITCH_ON;
        }
        if (quick_stop) {
            return MCA_CO402_QUICK_STOP_ACTIVE;
        }
        return disable_voltage ? MCA_CO402_SWITCH_ON_DISABLED : s;
    case MCA_CO402_QUICK_STOP_ACTIVE:
        if (enable) {
            return MCA_CO402_OPERATION_ENABLED;
        }
        return disable_voltage ? MCA_CO402_SWITCH_ON_DISABLED : s;
    case MCA_CO402_FAULT:
        return ((cw & 0x80) && !(prev_cw & 0x80)) ? MCA_CO402_SWITCH_ON_DISABLED : s;
    default:
        return s;
    }
}

const char *mca_co_fault_name(unsigned kind) {
    static const char *const names[] = {"NONE",        "DRIVE_FAULT", "EMCY", "HEARTBEAT",
                                        "PDO_TIMEOUT", "SDO_ABORT",   "BUS",  "NMT"};
    return kind < sizeof(names) / sizeof(names[0]) ? names[kind] : "UNKNOWN";
}
