/* SPDX-License-Identifier: MIT */
/* CANopen master on SocketCAN (see mca/canopen.h): blocking NMT/SDO start-up, non-blocking cyclic tick. */
#include "mca/canopen.h"

#include <errno.h>
#include <fcntl.h>  /* fcntl, O_NONBLOCK */
#include <math.h>   /* llround, isfinite */
#include <net/if.h> /* if_nametoindex, IFNAMSIZ */
#include <poll.h>
#include <stdio.h>  /* snprintf */
#include <string.h> /* memset, memcpy, strerror */
#include <sys/socket.h>
#include <time.h>   /* clock_gettime */
#include <unistd.h> /* close */

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>

#include "mca/can_sock.h" /* mca_can_sock_recv_batch, mca_can_sock_send */
#include "mca/err.h"

static int64_t mono_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

int mca_co_sock_open(int *fd, const char *iface, char *err, size_t errlen) {
    if (!fd || !iface || !iface[0] || strlen(iface) >= IFNAMSIZ) {
        if (err && errlen) {
            snprintf(err, errlen, "canopen: bad interface name");
        }
        return MCA_EINVAL;
    }
    int s = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (s < 0) {
        int e = errno;
        if (err && errlen) {
            snprintf(err, errlen, "canopen: socket(PF_CAN) for %s (kernel without SocketCAN?): %s", iface,
                     strerror(e));
        }
        return e == EAFNOSUPPORT ? MCA_ENOTSUP : MCA_EIO;
    }
    const unsigned idx = if_nametoindex(iface);
    if (idx == 0) {
        int e = errno;
        close(s);
        if (err && errlen) {
            snprintf(err, errlen, "canopen: interface %s: %s", iface, strerror(e));
        }
        return MCA_ENOENT;
    }
    /* standard-id data frames only; error frames for bus-off and controller problems */
    struct can_filter flt = {.can_id = 0, .can_mask = CAN_EFF_FLAG | CAN_RTR_FLAG};
    can_err_mask_t em = CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_RESTARTED;
    int on = 1;
    struct sockaddr_can addr;
    memset(&addr, 0, sizeof(addr));
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)idx;
    int fl = -1;
    if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_FILTER, &flt, sizeof(flt)) < 0 ||
        setsockopt(s, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &em, sizeof(em)) < 0 ||
        setsockopt(s, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof(on)) < 0 || (fl = fcntl(s, F_GETFL, 0)) < 0 ||
        fcntl(s, F_SETFL, fl | O_NONBLOCK) < 0 || bind(s, (struct sockaddr *)&addr, sizeof(addr)) < 0) {
        int e = errno;
        close(s);
        if (err && errlen) {
            snprintf(err, errlen, "canopen: socket options / bind on %s: %s", iface, strerror(e));
        }
        return MCA_EIO;
    }
    *fd = s;
    return MCA_OK;
}

void mca_co_master_config_default(mca_co_master_config_t *cfg, int n, uint8_t first_node) {
    if (!cfg) {
        return;
    }
    memset(cfg, 0, sizeof(*cfg));
    snprintf(cfg->iface, sizeof(cfg->iface), "vcan0");
    cfg->n = n < 1 ? 1 : n > MCA_CO_MAX_NODES ? MCA_CO_MAX_NODES : n;
    for (int j = 0; j < cfg->n; j++) {
        cfg->drive[j].node = (uint8_t)(first_node + j);
        cfg->drive[j].pos_scale = 1e6;
        cfg->drive[j].vel_scale = 1e6;
        cfg->drive[j].torque_scale = 1e3;
    }
    cfg->mode = MCA_CO402_MODE_CSV;
    cfg->sync_period_us = 4000;
    cfg->hb_period_ms = 100;
    cfg->hb_timeout_ms = 350;
    cfg->pdo_timeout_cycles = 5;
    cfg->sdo_timeout_ms = 200;
    cfg->boot_timeout_ms = 2000;
}

static void latch(mca_co_master_t *m, uint8_t kind, uint8_t node, uint32_t code) {
    m->faults++;
    if (m->fault.kind == MCA_CO_FAULT_NONE) {
        m->fault.node = node;
        m->fault.code = code;
        /* kind last, with release: a non-rt reader (mca_canopen_backend_fault) that sees it sees node and
         * code */
        __atomic_store_n(&m->fault.kind, kind, __ATOMIC_RELEASE);
    }
}

int mca_co_master_open(mca_co_master_t *m, const mca_co_master_config_t *cfg) {
    if (!m || !cfg || cfg->n < 1 || cfg->n > MCA_CO_MAX_NODES ||
        (cfg->mode != MCA_CO402_MODE_CSV && cfg->mode != MCA_CO402_MODE_CSP) || cfg->sync_period_us == 0 ||
        cfg->pdo_timeout_cycles < 1 || cfg->hb_timeout_ms <= cfg->hb_period_ms) {
        if (m) {
            snprintf(m->err, sizeof(m->err), "canopen: bad master configuration");
        }
        return MCA_EINVAL;
    }
    for (int j = 0; j < cfg->n; j++) {
        const mca_co_drive_config_t *d = &cfg->drive[j];
        if (d->node == 0 || d->node > 127 || !(d->pos_scale > 0) || !(d->vel_scale > 0) ||
            !isfinite(d->pos_scale) || !isfinite(d->vel_scale)) {
            snprintf(m->err, sizeof(m->err), "canopen: drive %d: bad node id or scale", j);
            return MCA_EINVAL;
        }
    }
    mca_co_master_t tmp;
    memset(&tmp, 0, sizeof(tmp));
    tmp.cfg = *cfg;
    tmp.fd = -1;
    for (int j = 0; j < cfg->n; j++) {
        tmp.d[j].cfg = cfg->drive[j];
    }
    const int rc = mca_co_sock_open(&tmp.fd, cfg->iface, tmp.err, sizeof(tmp.err));
    if (rc != MCA_OK) {
        memcpy(m->err, tmp.err, sizeof(m->err));
        return rc;
    }
    tmp.phase = MCA_CO_PHASE_OPEN;
    *m = tmp;
    return MCA_OK;
}

static int send_frame(mca_co_master_t *m, const mca_co_frame_t *f) {
    const int rc = mca_can_sock_send(m->fd, f->id, f->data, f->len, 0, 0);
    if (rc == MCA_OK) {
        m->tx_frames++;
    } else if (rc == MCA_EAGAIN) {
        m->tx_again++;
    }
    return rc;
}

static int drive_of(const mca_co_master_t *m, uint8_t node) {
    for (int j = 0; j < m->cfg.n; j++) {
        if (m->d[j].cfg.node == node) {
            return j;
        }
    }
    return -1;
}

void mca_co_master_rx(mca_co_master_t *m, const mca_co_frame_t *f, int64_t now_ns) {
    uint8_t node = 0, pdo = 0;
    const mca_co_kind_t k = mca_co_classify(f->id, &node, &pdo);
    const int j = drive_of(m, node);
    m->rx_frames++;
    m->last_rx_ns = now_ns;
    if (j < 0) {
        m->rx_unknown++; /* another node, SYNC/NMT echoes of other masters, ... */
        return;
    }
    mca_co_drive_t *d = &m->d[j];
    const int running = m->phase == MCA_CO_PHASE_RUNNING;
    switch (k) {
    case MCA_CO_K_HB:
        if (f->len < 1) {
            m->rx_unknown++;
            return;
        }
        d->nmt = f->data[0];
        d->hb_ns = now_ns;
        if (f->data[0] == MCA_CO_NMT_BOOTUP) {
            d->booted = 1;
            if (running) {
                latch(m, MCA_CO_FAULT_HEARTBEAT, node, 0); /* the drive rebooted under us */
            }
        } else if (running && f->data[0] == MCA_CO_NMT_OPERATIONAL) {
            d->op_seen = 1;
        } else if (running && d->op_seen) {
            latch(m, MCA_CO_FAULT_NMT, node, f->data[0]); /* left OPERATIONAL */
        }
        return;
    case MCA_CO_K_EMCY: {
        mca_co_emcy_t e;
        if (mca_co_emcy_decode(f, &e) != MCA_OK) {
            m->rx_unknown++;
            return;
        }
        d->emcy = e;
        d->emcy_rx++;
        if (e.code != 0) {
            latch(m, MCA_CO_FAULT_EMCY, node, e.code);
        }
        return;
    }
    case MCA_CO_K_TPDO:
        if (pdo == 1 && f->len >= 6) {
            d->statusword = (uint16_t)(f->data[0] | f->data[1] << 8);
            d->pos_counts = (int32_t)((uint32_t)f->data[2] | (uint32_t)f->data[3] << 8 |
                                      (uint32_t)f->data[4] << 16 | (uint32_t)f->data[5] << 24);
            d->tpdo1_sync = m->syncs;
            d->tpdo1_rx++;
            const mca_co402_state_t st = mca_co402_state(d->statusword);
            if (running && !m->fault_reset &&
                (st == MCA_CO402_FAULT || st == MCA_CO402_FAULT_REACTION_ACTIVE)) {
                latch(m, MCA_CO_FAULT_DRIVE, node, d->statusword);
            }
        } else if (pdo == 2 && f->len >= 4) {
            d->vel_counts = (int32_t)((uint32_t)f->data[0] | (uint32_t)f->data[1] << 8 |
                                      (uint32_t)f->data[2] << 16 | (uint32_t)f->data[3] << 24);
            d->torque_counts = f->len >= 6 ? (int16_t)(f->data[4] | f->data[5] << 8) : 0;
            d->tpdo2_sync = m->syncs;
            d->tpdo2_rx++;
        } else {
            m->rx_unknown++;
        }
        return;
    default:
        return; /* SDO answers outside a transfer, RPDOs/SYNC of this master echoed: ignored */
    }
}

/* read up to everything queued; SDO answers for @p sdo go there, the rest to mca_co_master_rx */
static int drain(mca_co_master_t *m, int64_t now_ns, mca_co_sdo_client_t *sdo, mca_co_frame_t *sdo_tx,
                 mca_co_sdo_status_t *sdo_st, int *fed) {
    int total = 0;
    for (int round = 0; round < 64; round++) {
        mca_can_frame_t fr[MCA_CAN_RX_BATCH];
        int bad = 0;
        const int n = mca_can_sock_recv_batch(m->fd, fr, MCA_CAN_RX_BATCH, &bad);
        if (n == MCA_EAGAIN) {
            return total;
        }
        if (n < 0) {
            latch(m, MCA_CO_FAULT_BUS, 0, 0);
            return MCA_EIO;
        }
        for (int i = 0; i < n; i++) {
            if (fr[i].can_id & CAN_ERR_FLAG) {
                m->bus_errors++;
                if (fr[i].can_id & CAN_ERR_BUSOFF) {
                    latch(m, MCA_CO_FAULT_BUS, 0, fr[i].can_id);
                }
                continue;
            }
            mca_co_frame_t f;
            if (!mca_co_frame_from_can(&f, &fr[i])) {
                continue;
            }
            total++;
            if (sdo && *sdo_st == MCA_CO_SDO_SEND && f.id == MCA_CO_COB_SDO_TX + sdo->node) {
                *sdo_st = mca_co_sdo_client_rx(sdo, &f, sdo_tx);
                if (*sdo_st == MCA_CO_SDO_WAIT) {
                    *sdo_st = MCA_CO_SDO_SEND;
                } else {
                    *fed = 1;
                    return total; /* the caller sends the next request (or ends) first */
                }
            } else {
                mca_co_master_rx(m, &f, now_ns);
            }
        }
        if (n < MCA_CAN_RX_BATCH) {
            return total;
        }
    }
    return total;
}

int mca_co_master_poll(mca_co_master_t *m, int64_t now_ns) {
    if (!m || m->fd < 0) {
        return MCA_EINVAL;
    }
    return drain(m, now_ns, NULL, NULL, NULL, NULL);
}

int mca_co_nmt_send(mca_co_master_t *m, uint8_t cmd, uint8_t node) {
    if (!m || m->fd < 0) {
        return MCA_EINVAL;
    }
    if (m->phase != MCA_CO_PHASE_OPEN) {
        return MCA_ESTATE;
    }
    mca_co_frame_t f;
    if (mca_co_nmt_encode(&f, cmd, node) != MCA_OK) {
        return MCA_EINVAL;
    }
    const int rc = send_frame(m, &f);
    return rc == MCA_OK ? MCA_OK : MCA_EIO;
}

int mca_co_frame_from_can(mca_co_frame_t *f, const mca_can_frame_t *c) {
    if (c->can_id & (CAN_ERR_FLAG | CAN_EFF_FLAG | CAN_RTR_FLAG)) {
        return 0;
    }
    memset(f, 0, sizeof *f);
    f->id = (uint16_t)(c->can_id & CAN_SFF_MASK);
    f->len = c->len > 8 ? 8 : c->len;
    memcpy(f->data, c->data, f->len);
    return 1;
}

/* wait up to timeout_ms for readable input */
static void wait_rx(int fd, int timeout_ms) {
    struct pollfd p = {.fd = fd, .events = POLLIN};
    (void)poll(&p, 1, timeout_ms < 0 ? 0 : timeout_ms);
}

static int sdo_run(mca_co_master_t *m, mca_co_sdo_client_t *c, mca_co_frame_t *tx, uint32_t *abort) {
    mca_co_sdo_status_t st = MCA_CO_SDO_SEND;
    if (abort) {
        *abort = 0;
    }
    if (send_frame(m, tx) != MCA_OK) {
        snprintf(m->err, sizeof(m->err), "canopen: node %u: SDO request not sent (socket)", c->node);
        return MCA_EIO;
    }
    int64_t deadline = mono_ns() + (int64_t)m->cfg.sdo_timeout_ms * 1000000;
    for (;;) {
        const int64_t now = mono_ns();
        if (now >= deadline) {
            mca_co_sdo_client_timeout(c, tx);
            (void)send_frame(m, tx);
            if (abort) {
                *abort = MCA_CO_ABORT_TIMEOUT;
            }
            snprintf(m->err, sizeof(m->err), "canopen: node %u: SDO %s 0x%04X:%u: no answer within %d ms",
                     c->node, c->upload ? "upload" : "download", c->index, c->sub, m->cfg.sdo_timeout_ms);
            return MCA_ETIMEDOUT;
        }
        wait_rx(m->fd, (int)((deadline - now) / 1000000) + 1);
        int fed = 0;
        if (drain(m, mono_ns(), c, tx, &st, &fed) < 0) {
            snprintf(m->err, sizeof(m->err), "canopen: node %u: socket error during SDO", c->node);
            return MCA_EIO;
        }
        if (!fed) {
            continue;
        }
        if (st == MCA_CO_SDO_DONE) {
            return MCA_OK;
        }
        if (st == MCA_CO_SDO_ABORTED) {
            if (!c->by_server) {
                (void)send_frame(m, tx);
            }
            if (abort) {
                *abort = c->abort_code;
            }
            snprintf(m->err, sizeof(m->err), "canopen: node %u: SDO %s 0x%04X:%u aborted by %s: 0x%08X %s",
                     c->node, c->upload ? "upload" : "download", c->index, c->sub,
                     c->by_server ? "the drive" : "the master", (unsigned)c->abort_code,
                     mca_co_abort_text(c->abort_code));
            return MCA_EIO;
        }
        /* the answer produced the next request (segments) */
        if (send_frame(m, tx) != MCA_OK) {
            snprintf(m->err, sizeof(m->err), "canopen: node %u: SDO segment not sent (socket)", c->node);
            return MCA_EIO;
        }
        deadline = mono_ns() + (int64_t)m->cfg.sdo_timeout_ms * 1000000;
    }
}

int mca_co_sdo_download(mca_co_master_t *m, uint8_t node, uint16_t index, uint8_t sub, const void *data,
                        size_t len, uint32_t *abort) {
    if (!m || m->fd < 0) {
        return MCA_EINVAL;
    }
    if (m->phase != MCA_CO_PHASE_OPEN) {
        return MCA_ESTATE;
    }
    mca_co_sdo_client_t c;
    mca_co_frame_t tx;
    if (mca_co_sdo_download_start(&c, &tx, node, index, sub, data, len) != MCA_OK) {
        return MCA_EINVAL;
    }
    return sdo_run(m, &c, &tx, abort);
}

int mca_co_sdo_upload(mca_co_master_t *m, uint8_t node, uint16_t index, uint8_t sub, void *buf, size_t cap,
                      size_t *len, uint32_t *abort) {
    if (!m || m->fd < 0 || !buf) {
        return MCA_EINVAL;
    }
    if (m->phase != MCA_CO_PHASE_OPEN) {
        return MCA_ESTATE;
    }
    mca_co_sdo_client_t c;
    mca_co_frame_t tx;
    if (mca_co_sdo_upload_start(&c, &tx, node, index, sub) != MCA_OK) {
        return MCA_EINVAL;
    }
    const int rc = sdo_run(m, &c, &tx, abort);
    if (rc != MCA_OK) {
        return rc;
    }
    if (c.len > cap) {
        snprintf(m->err, sizeof(m->err), "canopen: node %u: 0x%04X:%u has %zu bytes, room for %zu", node,
                 index, sub, c.len, cap);
        return MCA_ERANGE;
    }
    memcpy(buf, c.data, c.len);
    if (len) {
        *len = c.len;
    }
    return MCA_OK;
}

/* one SDO download of an integer of @p size bytes; on error latch SDO fault */
static int wr(mca_co_master_t *m, uint8_t node, uint16_t index, uint8_t sub, uint32_t v, size_t size) {
    const uint8_t b[4] = {(uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    uint32_t ab = 0;
    const int rc = mca_co_sdo_download(m, node, index, sub, b, size, &ab);
    if (rc != MCA_OK) {
        latch(m, MCA_CO_FAULT_SDO, node, ab);
    }
    return rc;
}

/* PDO communication (0x1400/0x1800 + k) and mapping (0x1600/0x1A00 + k): disable, map, type 1, enable */
static int map_pdo(mca_co_master_t *m, uint8_t node, uint16_t comm, uint16_t cob, const uint32_t *map,
                   int nmap) {
    const uint16_t mapidx = (uint16_t)(comm + 0x200);
    int rc = wr(m, node, comm, 1, 0x80000000u | cob, 4);
    rc = rc ? rc : wr(m, node, mapidx, 0, 0, 1);
    for (int i = 0; i < nmap && rc == MCA_OK; i++) {
        rc = wr(m, node, mapidx, (uint8_t)(i + 1), map[i], 4);
    }
    rc = rc ? rc : wr(m, node, mapidx, 0, (uint32_t)nmap, 1);
    rc = rc ? rc : wr(m, node, comm, 2, 1, 1); /* synchronous, every SYNC */
    rc = rc ? rc : wr(m, node, comm, 1, cob, 4);
    return rc;
}

/* 0x60C2: value and power-of-ten index for a period in us */
static int interp_period(uint32_t us, uint8_t *value, int8_t *index) {
    if (us % 1000 == 0 && us / 1000 <= 255) {
        *value = (uint8_t)(us / 1000);
        *index = -3;
    } else if (us % 100 == 0 && us / 100 <= 255) {
        *value = (uint8_t)(us / 100);
        *index = -4;
    } else if (us <= 255) {
        *value = (uint8_t)us;
        *index = -6;
    } else {
        return MCA_EINVAL;
    }
    return MCA_OK;
}

int mca_co_master_start(mca_co_master_t *m) {
    if (!m || m->fd < 0) {
        return MCA_EINVAL;
    }
    if (m->phase != MCA_CO_PHASE_OPEN) {
        return MCA_ESTATE;
    }
    uint8_t pv = 0;
    int8_t pi = 0;
    if (interp_period(m->cfg.sync_period_us, &pv, &pi) != MCA_OK) {
        snprintf(m->err, sizeof(m->err), "canopen: SYNC period %u us has no 0x60C2 form",
                 m->cfg.sync_period_us);
        return MCA_EINVAL;
    }
    /* NMT reset communication, then wait for every boot-up */
    for (int j = 0; j < m->cfg.n; j++) {
        m->d[j].booted = 0;
    }
    for (int j = 0; j < m->cfg.n; j++) {
        if (mca_co_nmt_send(m, MCA_CO_NMT_RESET_COMM, m->d[j].cfg.node) != MCA_OK) {
            snprintf(m->err, sizeof(m->err), "canopen: NMT reset not sent (socket)");
            latch(m, MCA_CO_FAULT_BUS, 0, 0);
            return MCA_EIO;
        }
    }
    const int64_t deadline = mono_ns() + (int64_t)m->cfg.boot_timeout_ms * 1000000;
    for (;;) {
        int all = 1;
        for (int j = 0; j < m->cfg.n; j++) {
            all &= m->d[j].booted;
        }
        if (all) {
            break;
        }
        const int64_t now = mono_ns();
        if (now >= deadline) {
            for (int j = 0; j < m->cfg.n; j++) {
                if (!m->d[j].booted) {
                    snprintf(m->err, sizeof(m->err),
                             "canopen: node %u: no boot-up within %d ms after NMT reset", m->d[j].cfg.node,
                             m->cfg.boot_timeout_ms);
                    latch(m, MCA_CO_FAULT_NMT, m->d[j].cfg.node, 0);
                    break;
                }
            }
            return MCA_ETIMEDOUT;
        }
        wait_rx(m->fd, (int)((deadline - now) / 1000000) + 1);
        if (drain(m, mono_ns(), NULL, NULL, NULL, NULL) < 0) {
            snprintf(m->err, sizeof(m->err), "canopen: socket error waiting for boot-ups");
            return MCA_EIO;
        }
    }
    const uint16_t target =
        m->cfg.mode == MCA_CO402_MODE_CSP ? MCA_CO402_TARGET_POSITION : MCA_CO402_TARGET_VELOCITY;
    for (int j = 0; j < m->cfg.n; j++) {
        const uint8_t node = m->d[j].cfg.node;
        uint8_t b[4] = {0};
        size_t n = 0;
        uint32_t ab = 0;
        int rc = mca_co_sdo_upload(m, node, 0x1000, 0, b, sizeof(b), &n, &ab);
        if (rc != MCA_OK) {
            latch(m, MCA_CO_FAULT_SDO, node, ab);
            return rc;
        }
        const uint32_t devtype =
            (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
        if (n != 4 || (devtype & 0xFFFFu) != 402) {
            snprintf(m->err, sizeof(m->err), "canopen: node %u: device type 0x%08X is not a CiA 402 drive",
                     node, (unsigned)devtype);
            latch(m, MCA_CO_FAULT_SDO, node, MCA_CO_ABORT_GENERAL);
            return MCA_EIO;
        }
        const uint32_t rpdo1[] = {mca_co_map_entry(MCA_CO402_CONTROLWORD, 0, 16),
                                  mca_co_map_entry(target, 0, 32)};
        const uint32_t tpdo1[] = {mca_co_map_entry(MCA_CO402_STATUSWORD, 0, 16),
                                  mca_co_map_entry(MCA_CO402_POSITION_ACTUAL, 0, 32)};
        const uint32_t tpdo2[] = {mca_co_map_entry(MCA_CO402_VELOCITY_ACTUAL, 0, 32),
                                  mca_co_map_entry(MCA_CO402_TORQUE_ACTUAL, 0, 16)};
        rc = wr(m, node, 0x1017, 0, m->cfg.hb_period_ms, 2);
        rc = rc ? rc : map_pdo(m, node, 0x1400, (uint16_t)(MCA_CO_COB_RPDO1 + node), rpdo1, 2);
        rc = rc ? rc : map_pdo(m, node, 0x1800, (uint16_t)(MCA_CO_COB_TPDO1 + node), tpdo1, 2);
        rc = rc ? rc : map_pdo(m, node, 0x1801, (uint16_t)(MCA_CO_COB_TPDO2 + node), tpdo2, 2);
        rc = rc ? rc : wr(m, node, MCA_CO402_MODE, 0, (uint32_t)m->cfg.mode, 1);
        rc = rc ? rc : wr(m, node, MCA_CO402_INTERP_PERIOD, 1, pv, 1);
        rc = rc ? rc : wr(m, node, MCA_CO402_INTERP_PERIOD, 2, (uint32_t)(uint8_t)pi, 1);
        if (rc != MCA_OK) {
            return rc;
        }
    }
    for (int j = 0; j < m->cfg.n; j++) {
        if (mca_co_nmt_send(m, MCA_CO_NMT_START, m->d[j].cfg.node) != MCA_OK) {
            snprintf(m->err, sizeof(m->err), "canopen: NMT start not sent (socket)");
            return MCA_EIO;
        }
    }
    const int64_t now = mono_ns();
    for (int j = 0; j < m->cfg.n; j++) {
        m->d[j].hb_ns = now;
        m->d[j].op_seen = 0;
        m->d[j].tpdo1_sync = m->syncs;
        m->d[j].tpdo2_sync = m->syncs;
        m->d[j].cw = 0;
        m->d[j].target = 0;
    }
    m->goal = MCA_CO402_GOAL_DISABLED;
    m->start_ns = now;
    m->phase = MCA_CO_PHASE_RUNNING;
    return MCA_OK;
}

void mca_co_master_set_goal(mca_co_master_t *m, mca_co402_goal_t goal) {
    if (m) {
        m->goal = goal;
    }
}

void mca_co_master_fault_reset(mca_co_master_t *m) {
    if (m) {
        m->fault_reset = 1;
        memset(&m->fault, 0, sizeof(m->fault));
    }
}

int mca_co_master_set_target(mca_co_master_t *m, int j, double target) {
    if (!m || j < 0 || j >= m->cfg.n || !isfinite(target)) {
        return MCA_EINVAL;
    }
    m->d[j].target = target;
    return MCA_OK;
}

static int32_t to_counts(double v, double scale) {
    const double c = v * scale;
    if (c >= 2147483647.0) {
        return INT32_MAX;
    }
    if (c <= -2147483648.0) {
        return INT32_MIN;
    }
    return (int32_t)llround(c);
}

int mca_co_master_tick(mca_co_master_t *m, int64_t now_ns) {
    if (!m || m->fd < 0) {
        return MCA_EINVAL;
    }
    if (m->phase != MCA_CO_PHASE_RUNNING) {
        return MCA_ESTATE;
    }
    if (drain(m, now_ns, NULL, NULL, NULL, NULL) < 0) {
        return MCA_EIO;
    }
    const int64_t hb_tmo = (int64_t)m->cfg.hb_timeout_ms * 1000000;
    int any_fault = 0;
    for (int j = 0; j < m->cfg.n; j++) {
        mca_co_drive_t *d = &m->d[j];
        if (now_ns - d->hb_ns > hb_tmo) {
            latch(m, MCA_CO_FAULT_HEARTBEAT, d->cfg.node, (uint32_t)((now_ns - d->hb_ns) / 1000000));
            d->hb_ns = now_ns; /* counted once per timeout */
        }
        if (!d->op_seen && now_ns - m->start_ns > hb_tmo) {
            latch(m, MCA_CO_FAULT_NMT, d->cfg.node, d->nmt); /* never reported OPERATIONAL */
            d->op_seen = 1;                                  /* counted once */
        }
        if (m->syncs - d->tpdo1_sync > (uint64_t)m->cfg.pdo_timeout_cycles) {
            latch(m, MCA_CO_FAULT_PDO, d->cfg.node, (uint32_t)(m->syncs - d->tpdo1_sync));
            d->tpdo1_sync = m->syncs;
        }
        any_fault |= mca_co402_state(d->statusword) == MCA_CO402_FAULT;
    }
    if (m->fault_reset && !any_fault) {
        m->fault_reset = 0;
    }
    int rc = MCA_OK;
    for (int j = 0; j < m->cfg.n; j++) {
        mca_co_drive_t *d = &m->d[j];
        const uint16_t cw =
            mca_co402_controlword(mca_co402_state(d->statusword), m->goal, m->fault_reset, d->cw);
        const double scale = m->cfg.mode == MCA_CO402_MODE_CSP ? d->cfg.pos_scale : d->cfg.vel_scale;
        const int32_t t = to_counts(d->target, scale);
        mca_co_frame_t f;
        memset(&f, 0, sizeof(f));
        f.id = (uint16_t)(MCA_CO_COB_RPDO1 + d->cfg.node);
        f.len = 6;
        f.data[0] = (uint8_t)cw;
        f.data[1] = (uint8_t)(cw >> 8);
        for (int b = 0; b < 4; b++) {
            f.data[2 + b] = (uint8_t)((uint32_t)t >> (8 * b));
        }
        const int r = send_frame(m, &f);
        if (r == MCA_OK) {
            d->cw = cw;
        } else if (rc == MCA_OK) {
            rc = r;
        }
    }
    mca_co_frame_t s;
    memset(&s, 0, sizeof(s));
    s.id = MCA_CO_COB_SYNC;
    const int r = send_frame(m, &s);
    if (r == MCA_OK) {
        m->syncs++;
    } else if (rc == MCA_OK) {
        rc = r;
    }
    if (rc == MCA_EIO) {
        latch(m, MCA_CO_FAULT_BUS, 0, 0);
        return MCA_EIO;
    }
    if (m->fault.kind != MCA_CO_FAULT_NONE) {
        return MCA_EFAULT;
    }
    return rc;
}

int mca_co_master_joint(const mca_co_master_t *m, int j, double *pos, double *vel, double *torque) {
    if (!m || j < 0 || j >= m->cfg.n) {
        return MCA_EINVAL;
    }
    const mca_co_drive_t *d = &m->d[j];
    if (pos) {
        *pos = d->pos_counts / d->cfg.pos_scale;
    }
    if (vel) {
        *vel = d->vel_counts / d->cfg.vel_scale;
    }
    if (torque) {
        *torque = d->cfg.torque_scale > 0 ? d->torque_counts / d->cfg.torque_scale : 0.0;
    }
    return MCA_OK;
}

int mca_co_master_all_enabled(const mca_co_master_t *m) {
    if (!m) {
        return 0;
    }
    for (int j = 0; j < m->cfg.n; j++) {
        if (mca_co402_state(m->d[j].statusword) != MCA_CO402_OPERATION_ENABLED) {
            return 0;
        }
    }
    return 1;
}

void mca_co_master_close(mca_co_master_t *m) {
    if (!m || m->fd < 0) {
        return;
    }
    if (m->phase == MCA_CO_PHASE_RUNNING) {
        m->phase = MCA_CO_PHASE_OPEN;
        (void)mca_co_nmt_send(m, MCA_CO_NMT_STOP, 0);
    }
    mca_can_sock_close(m->fd);
    m->fd = -1;
    m->phase = MCA_CO_PHASE_CLOSED;
}

void mca_co_fault_describe(const mca_co_fault_t *f, char *buf, size_t len) {
    if (!buf || !len) {
        return;
    }
    if (!f || f->kind == MCA_CO_FAULT_NONE) {
        snprintf(buf, len, "no fault");
        return;
    }
    switch (f->kind) {
    case MCA_CO_FAULT_EMCY:
        snprintf(buf, len, "node %u: EMCY 0x%04X (%s)", f->node, (unsigned)f->code,
                 mca_co_emcy_text((uint16_t)f->code));
        break;
    case MCA_CO_FAULT_SDO:
        snprintf(buf, len, "node %u: SDO_ABORT 0x%08X (%s)", f->node, (unsigned)f->code,
                 mca_co_abort_text(f->code));
        break;
    case MCA_CO_FAULT_DRIVE:
        snprintf(buf, len, "node %u: DRIVE_FAULT (statusword 0x%04X)", f->node, (unsigned)f->code);
        break;
    case MCA_CO_FAULT_HEARTBEAT:
        snprintf(buf, len, "node %u: HEARTBEAT %s", f->node,
                 f->code ? "lost" : "boot-up while running (reset)");
        break;
    case MCA_CO_FAULT_PDO:
        snprintf(buf, len, "node %u: PDO_TIMEOUT (TPDO1 not refreshed for %u SYNCs)", f->node,
                 (unsigned)f->code);
        break;
    case MCA_CO_FAULT_NMT:
        snprintf(buf, len, "node %u: NMT (state 0x%02X, not operational / no boot-up)", f->node,
                 (unsigned)f->code);
        break;
    default:
        snprintf(buf, len, "%s (node %u, code 0x%X)", mca_co_fault_name(f->kind), f->node, (unsigned)f->code);
        break;
    }
}
