/* SPDX-License-Identifier: MIT */
/* mca-drivesim: CiA 402 drive emulator. One CANopen node per joint (node ids first..first+n-1)
 * on one classic CAN bus, each with its object dictionary (config/canopen/mca-drivesim.eds), NMT slave
 * (boot-up, start/stop/pre-op, reset node/communication), SDO server (expedited and segmented), two
 * RPDOs and two TPDOs mapped over SDO, heartbeat producer (0x1017), EMCY producer, and the CiA 402 state
 * machine in modes 8 (CSP) and 9 (CSV). Behind each drive runs one joint of the simulated arm firmware
 * (mca/sim_arm.h, n = 1 per drive: the same physics as the sim backend, whose joints are uncoupled).
 *
 * Cycle: every SYNC, each OPERATIONAL node takes the RPDO values received since the previous SYNC, steps
 * its CiA 402 state machine with the controlword, runs one firmware cycle of length 0x60C2 and sends its
 * synchronous TPDOs. SYNC-driven, so a slow master simply runs slower. When SYNCs stop for
 * --sync-timeout-ms while a drive is OPERATION_ENABLED (master gone), the drive runs on its own clock
 * without commands: the firmware watchdog brakes at the deceleration limit and the drive ends in FAULT
 * (EMCY 0x8250, RPDO timeout).
 *
 * Units: position counts = rad * --pos-scale, velocity counts = rad/s * --vel-scale (default 1e6 both),
 * torque (0x6077) = N m * 1000.
 * Fault injection (--inject KIND@SYNC:NODE, SYNC counted per node from its first SYNC):
 *   fault   actuator fault of the joint: brake, FAULT, EMCY 0xFF00
 *   emcy    an EMCY 0x4210 (temperature) with no state change
 *   hbloss  the node stops producing heartbeats
 *   pdoloss the node stops sending TPDOs
 * and --sdo-abort NODE:INDEX: the node refuses SDO writes to INDEX (abort 0x08000022, device state).
 * Writing 1 to 0x2000 (manufacturer: inject fault) over SDO faults the drive like `fault`.
 * --log FILE: "s <node> <sync> <state> <q> <v>" per node and SYNC, written at exit (buffered).
 * Exit on SIGTERM/SIGINT with counters on stderr; bad arguments: exit 2. */
#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <linux/can.h>

#include "mca/can_sock.h" /* mca_can_sock_recv_batch, mca_can_sock_send */
#include "mca/canopen.h"
#include "mca/chain.h"
#include "mca/err.h"
#include "mca/sim_arm.h"
#include "mca/urdf.h"

#define MAX_OD 64
#define MAX_INJ 16

static volatile sig_atomic_t g_stop;

static void on_signal(int sig) {
    (void)sig;
    g_stop = 1;
}

static int64_t mono_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

typedef struct pdo_comm {
    uint8_t n_sub; /* sub 0 */
    uint32_t cob;
    uint8_t type;
    uint16_t inhibit;
    uint16_t event_timer;
} pdo_comm_t;

typedef struct pdo_map {
    uint8_t count;
    uint32_t e[4];
} pdo_map_t;

/* the object dictionary values of one drive */
typedef struct od_values {
    uint32_t devtype;
    uint8_t errreg;
    char name[24];
    char hw_version[8];
    char sw_version[8];
    uint16_t hb_ms;
    uint8_t id_n;
    uint32_t vendor, product, revision, serial;
    pdo_comm_t rcomm[2], tcomm[2];
    pdo_map_t rmap[2], tmap[2];
    uint8_t inject;
    uint16_t error_code; /* 0x603F */
    uint16_t cw, sw;
    int8_t mode, mode_display;
    int32_t pos, vel, target_pos, target_vel;
    int16_t torque;
    uint8_t ip_n;
    uint8_t ip_value;
    int8_t ip_index;
    uint32_t supported_modes;
} od_values_t;

typedef struct drive {
    uint8_t node;
    uint8_t nmt;
    od_values_t v;
    mca_co_od_entry_t od[MAX_OD];
    size_t n_od;
    mca_co_sdo_server_t sdo;
    mca_sim_arm_t arm;
    mca_co402_state_t st;
    uint16_t prev_cw;
    uint32_t frame_id;
    int rpdo_fresh;
    uint64_t syncs;
    int64_t next_hb_ns;
    int hb_dead, pdo_dead;
    uint16_t sdo_refuse; /* index refused (0: none) */
    uint64_t rx_rpdo, tx_tpdo, rx_sdo, tx_emcy, nmt_cmds, faults;
    int64_t last_sync_ns;
    int self_clocked;
} drive_t;

typedef struct inj {
    int kind; /* 1 fault, 2 emcy, 3 hbloss, 4 pdoloss */
    uint64_t at;
    int node;
    int done;
} inj_t;

typedef struct logrec {
    uint8_t node;
    uint8_t st;
    uint64_t sync;
    double q, v;
} logrec_t;

typedef struct sim {
    int fd;
    int n;
    drive_t d[MCA_CO_MAX_NODES];
    double pos_scale, vel_scale;
    double default_dt;
    int64_t sync_timeout_ns;
    inj_t inj[MAX_INJ];
    int n_inj;
    logrec_t *log;
    size_t nlog, caplog;
    uint64_t rx_frames, tx_frames, tx_fail, rx_sync, rx_other;
} sim_t;

static int send(sim_t *s, const mca_co_frame_t *f) {
    const int rc = mca_can_sock_send(s->fd, f->id, f->data, f->len, 0, 0);
    if (rc == MCA_OK) {
        s->tx_frames++;
    } else {
        s->tx_fail++;
    }
    return rc;
}

#define ENT(i, sb, acc, sz, str, sg, mn, mx, p)                                                              \
    do {                                                                                                     \
        d->od[d->n_od++] = (mca_co_od_entry_t){(i), (sb), (acc), (sz), (str), (sg), (mn), (mx), (p)};        \
    } while (0)

/* communication parameters back to the defaults (power-on, NMT reset communication) */
static void comm_defaults(drive_t *d) {
    od_values_t *v = &d->v;
    v->hb_ms = 0;
    for (int k = 0; k < 2; k++) {
        v->rcomm[k] = (pdo_comm_t){2, (uint32_t)(MCA_CO_COB_RPDO1 + 0x100 * k + d->node), 1, 0, 0};
        v->tcomm[k] = (pdo_comm_t){5, (uint32_t)(MCA_CO_COB_TPDO1 + 0x100 * k + d->node), 1, 0, 0};
    }
    /* defaults = the master's layout in CSV (mca/canopen.h mca_co_master_start) */
    v->rmap[0] = (pdo_map_t){2, {mca_co_map_entry(0x6040, 0, 16), mca_co_map_entry(0x60FF, 0, 32), 0, 0}};
    v->rmap[1] = (pdo_map_t){1, {mca_co_map_entry(0x607A, 0, 32), 0, 0, 0}};
    v->tmap[0] = (pdo_map_t){2, {mca_co_map_entry(0x6041, 0, 16), mca_co_map_entry(0x6064, 0, 32), 0, 0}};
    v->tmap[1] = (pdo_map_t){2, {mca_co_map_entry(0x606C, 0, 32), mca_co_map_entry(0x6077, 0, 16), 0, 0}};
}

static uint32_t on_written(void *user, const mca_co_od_entry_t *e);

static void od_build(drive_t *d) {
    od_values_t *v = &d->v;
    d->n_od = 0;
    const int RO = MCA_CO_ACC_RO, RW = MCA_CO_ACC_RW, P = MCA_CO_ACC_PDO;
    ENT(0x1000, 0, RO, 4, 0, 0, 1, 0, &v->devtype);
    ENT(0x1001, 0, RO | P, 1, 0, 0, 1, 0, &v->errreg);
    ENT(0x1008, 0, RO, sizeof(v->name), 1, 0, 1, 0, v->name);
    ENT(0x1009, 0, RO, sizeof(v->hw_version), 1, 0, 1, 0, v->hw_version);
    ENT(0x100A, 0, RO, sizeof(v->sw_version), 1, 0, 1, 0, v->sw_version);
    ENT(0x1017, 0, RW, 2, 0, 0, 1, 0, &v->hb_ms);
    ENT(0x1018, 0, RO, 1, 0, 0, 1, 0, &v->id_n);
    ENT(0x1018, 1, RO, 4, 0, 0, 1, 0, &v->vendor);
    ENT(0x1018, 2, RO, 4, 0, 0, 1, 0, &v->product);
    ENT(0x1018, 3, RO, 4, 0, 0, 1, 0, &v->revision);
    ENT(0x1018, 4, RO, 4, 0, 0, 1, 0, &v->serial);
    for (uint16_t k = 0; k < 2; k++) {
        ENT(0x1400 + k, 0, RO, 1, 0, 0, 1, 0, &v->rcomm[k].n_sub);
        ENT(0x1400 + k, 1, RW, 4, 0, 0, 1, 0, &v->rcomm[k].cob);
        ENT(0x1400 + k, 2, RW, 1, 0, 0, 1, 0, &v->rcomm[k].type);
        ENT(0x1600 + k, 0, RW, 1, 0, 0, 0, 4, &v->rmap[k].count);
        for (uint8_t i = 0; i < 4; i++) {
            ENT(0x1600 + k, i + 1, RW, 4, 0, 0, 1, 0, &v->rmap[k].e[i]);
        }
        ENT(0x1800 + k, 0, RO, 1, 0, 0, 1, 0, &v->tcomm[k].n_sub);
        ENT(0x1800 + k, 1, RW, 4, 0, 0, 1, 0, &v->tcomm[k].cob);
        ENT(0x1800 + k, 2, RW, 1, 0, 0, 1, 0, &v->tcomm[k].type);
        ENT(0x1800 + k, 3, RW, 2, 0, 0, 1, 0, &v->tcomm[k].inhibit);
        ENT(0x1800 + k, 5, RW, 2, 0, 0, 1, 0, &v->tcomm[k].event_timer);
        ENT(0x1A00 + k, 0, RW, 1, 0, 0, 0, 4, &v->tmap[k].count);
        for (uint8_t i = 0; i < 4; i++) {
            ENT(0x1A00 + k, i + 1, RW, 4, 0, 0, 1, 0, &v->tmap[k].e[i]);
        }
    }
    ENT(0x2000, 0, RW, 1, 0, 0, 0, 1, &v->inject);
    ENT(0x603F, 0, RO | P, 2, 0, 0, 1, 0, &v->error_code);
    ENT(0x6040, 0, RW | P, 2, 0, 0, 1, 0, &v->cw);
    ENT(0x6041, 0, RO | P, 2, 0, 0, 1, 0, &v->sw);
    ENT(0x6060, 0, RW | P, 1, 0, 1, 8, 9, &v->mode);
    ENT(0x6061, 0, RO | P, 1, 0, 1, 1, 0, &v->mode_display);
    ENT(0x6064, 0, RO | P, 4, 0, 1, 1, 0, &v->pos);
    ENT(0x606C, 0, RO | P, 4, 0, 1, 1, 0, &v->vel);
    ENT(0x6077, 0, RO | P, 2, 0, 1, 1, 0, &v->torque);
    ENT(0x607A, 0, RW | P, 4, 0, 1, 1, 0, &v->target_pos);
    ENT(0x60C2, 0, RO, 1, 0, 0, 1, 0, &v->ip_n);
    ENT(0x60C2, 1, RW, 1, 0, 0, 1, 0, &v->ip_value);
    ENT(0x60C2, 2, RW, 1, 0, 1, -6, 0, &v->ip_index);
    ENT(0x60FF, 0, RW | P, 4, 0, 1, 1, 0, &v->target_vel);
    ENT(0x6502, 0, RO, 4, 0, 0, 1, 0, &v->supported_modes);
    mca_co_sdo_server_init(&d->sdo, d->node, d->od, d->n_od, on_written, d);
}

static void drive_reset_app(drive_t *d) {
    od_values_t *v = &d->v;
    v->devtype = 0x00020192u; /* CiA 402, servo drive */
    v->errreg = 0;
    snprintf(v->name, sizeof(v->name), "mca-drivesim");
    snprintf(v->hw_version, sizeof(v->hw_version), "sim");
    snprintf(v->sw_version, sizeof(v->sw_version), "1.0");
    v->id_n = 4;
    v->vendor = 0x000004D2u; /* not a registered vendor id: an emulator */
    v->product = 402;
    v->revision = 0x00010000u;
    v->serial = d->node;
    v->inject = 0;
    v->error_code = 0;
    v->cw = 0;
    v->mode = MCA_CO402_MODE_CSV;
    v->mode_display = MCA_CO402_MODE_CSV;
    v->target_pos = v->pos;
    v->target_vel = 0;
    v->ip_n = 2;
    v->ip_value = 1;
    v->ip_index = -3;
    v->supported_modes = (1u << 7) | (1u << 8); /* csp, csv */
    d->st = MCA_CO402_SWITCH_ON_DISABLED;       /* NOT_READY passes at once: no self test */
    d->prev_cw = 0;
    v->sw = mca_co402_statusword(d->st);
    comm_defaults(d);
}

static const mca_co_od_entry_t *find(const drive_t *d, uint16_t index, uint8_t sub) {
    return mca_co_od_find(d->od, d->n_od, index, sub, NULL);
}

/* a mapping entry must name a mappable object of exactly that many bits */
static uint32_t check_map(const drive_t *d, const pdo_map_t *m) {
    unsigned bits = 0;
    for (int i = 0; i < m->count; i++) {
        const mca_co_od_entry_t *e = find(d, (uint16_t)(m->e[i] >> 16), (uint8_t)(m->e[i] >> 8));
        if (!e || !(e->access & MCA_CO_ACC_PDO) || e->size * 8u != (m->e[i] & 0xFF)) {
            return MCA_CO_ABORT_NO_MAP;
        }
        bits += m->e[i] & 0xFF;
    }
    return bits > 64 ? MCA_CO_ABORT_MAP_LEN : 0;
}

static uint32_t on_written(void *user, const mca_co_od_entry_t *e) {
    drive_t *d = user;
    if (d->sdo_refuse && e->index == d->sdo_refuse) {
        return 0x08000022u;
    }
    const uint16_t ix = e->index;
    for (int k = 0; k < 2; k++) {
        /* mapping changes only while the PDO is disabled (CiA 301), sub 0 is checked in full */
        if (ix == 0x1600 + k || ix == 0x1A00 + k) {
            const int tx = ix >= 0x1A00;
            const pdo_comm_t *c = tx ? &d->v.tcomm[k] : &d->v.rcomm[k];
            if (!(c->cob & 0x80000000u)) {
                return 0x08000022u;
            }
            if (e->sub == 0) {
                return check_map(d, tx ? &d->v.tmap[k] : &d->v.rmap[k]);
            }
        }
    }
    if (ix == 0x2000 && d->v.inject) {
        d->v.inject = 0;
        (void)mca_sim_arm_inject_now(&d->arm, MCA_SIM_INJ_ACTUATOR, 0, 0);
    }
    if (ix == 0x6060) {
        d->v.mode_display = d->v.mode;
    }
    return 0;
}

static void send_emcy(sim_t *s, drive_t *d, uint16_t code) {
    mca_co_emcy_t e = {.code = code, .reg = code ? 0x01 : 0x00, .mfr = {0}};
    mca_co_frame_t f;
    mca_co_emcy_encode(&f, d->node, &e);
    if (send(s, &f) == MCA_OK) {
        d->tx_emcy++;
    }
}

static void send_hb(sim_t *s, drive_t *d, uint8_t state) {
    mca_co_frame_t f;
    mca_co_hb_encode(&f, d->node, state);
    (void)send(s, &f);
}

static void boot(sim_t *s, drive_t *d, int app) {
    if (app) {
        drive_reset_app(d);
    } else {
        comm_defaults(d);
    }
    d->nmt = MCA_CO_NMT_PREOPERATIONAL;
    d->next_hb_ns = 0;
    send_hb(s, d, MCA_CO_NMT_BOOTUP);
}

/* pack/unpack a PDO by its mapping */
static int pdo_pack(const drive_t *d, const pdo_map_t *m, uint8_t *out) {
    int n = 0;
    for (int i = 0; i < m->count; i++) {
        const mca_co_od_entry_t *e = find(d, (uint16_t)(m->e[i] >> 16), (uint8_t)(m->e[i] >> 8));
        if (!e || n + e->size > 8) {
            return -1;
        }
        memcpy(out + n, e->ptr, e->size);
        n += e->size;
    }
    return n;
}

static int pdo_unpack(drive_t *d, const pdo_map_t *m, const uint8_t *in, int len) {
    int n = 0;
    for (int i = 0; i < m->count; i++) {
        const mca_co_od_entry_t *e = find(d, (uint16_t)(m->e[i] >> 16), (uint8_t)(m->e[i] >> 8));
        if (!e || n + e->size > len) {
            return -1; /* too short a PDO: ignored (CiA 301 would send an EMCY 0x8210) */
        }
        memcpy(e->ptr, in + n, e->size);
        n += e->size;
    }
    return n;
}

static uint16_t fault_emcy(uint16_t fault_code) {
    switch (fault_code) {
    case MCA_ARM_FAULT_WATCHDOG:
        return 0x8250; /* RPDO timeout */
    case MCA_ARM_FAULT_JOINT_LIMIT:
        return 0x8612; /* reference limit */
    case MCA_ARM_FAULT_VELOCITY:
        return 0x8400; /* velocity speed controller */
    case MCA_ARM_FAULT_INJECTED:
        return 0xFF00;
    default:
        return 0x1000;
    }
}

static int32_t counts(double x, double scale) {
    const double c = x * scale;
    return c >= 2147483647.0 ? INT32_MAX : c <= -2147483648.0 ? INT32_MIN : (int32_t)llround(c);
}

static double period_s(const sim_t *s, const drive_t *d) {
    if (d->v.ip_value == 0) {
        return s->default_dt;
    }
    return d->v.ip_value * pow(10.0, d->v.ip_index);
}

/* one drive cycle (a SYNC, or self-clocked without a master) */
static void drive_cycle(sim_t *s, drive_t *d, int with_cmd) {
    od_values_t *v = &d->v;
    const double dt = period_s(s, d);
    const mca_co402_state_t before = d->st;
    if (with_cmd && d->st != MCA_CO402_FAULT_REACTION_ACTIVE) {
        d->st = mca_co402_drive_next(d->st, v->cw, d->prev_cw);
    }
    const int reset_edge = before == MCA_CO402_FAULT && d->st == MCA_CO402_SWITCH_ON_DISABLED;
    d->prev_cw = v->cw;
    mca_arm_command_t cmd;
    memset(&cmd, 0, sizeof(cmd));
    cmd.n = 1;
    cmd.frame_id = ++d->frame_id;
    if (d->st == MCA_CO402_OPERATION_ENABLED) {
        cmd.flags[0] = MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE;
        if (v->mode == MCA_CO402_MODE_CSP) {
            cmd.velocity[0] = (v->target_pos / s->pos_scale - d->arm.q[0]) / dt;
        } else {
            cmd.velocity[0] = v->target_vel / s->vel_scale;
        }
    } else if (reset_edge) {
        cmd.flags[0] = MCA_ACT_CLEAR_FAULT;
    }
    /* no RPDO since the last SYNC while servoing: no command this cycle (the firmware watchdog counts) */
    const int give = with_cmd && (d->rpdo_fresh || d->st != MCA_CO402_OPERATION_ENABLED);
    mca_arm_feedback_t fb;
    memset(&fb, 0, sizeof(fb));
    if (mca_sim_arm_cycle(&d->arm, give ? &cmd : NULL, dt, &fb) != MCA_OK) {
        mca_sim_arm_snapshot(&d->arm, &fb);
    }
    d->rpdo_fresh = 0;
    /* the firmware's own stop or fault moves the drive */
    if (d->arm.state == MCA_ARM_BRAKING && d->arm.fault_code != MCA_ARM_FAULT_NONE &&
        d->st != MCA_CO402_FAULT) {
        d->st = MCA_CO402_FAULT_REACTION_ACTIVE;
    }
    if (d->arm.state == MCA_ARM_FAULT && d->st != MCA_CO402_FAULT && !reset_edge) {
        d->st = MCA_CO402_FAULT;
        v->error_code = fault_emcy(d->arm.fault_code);
        v->errreg = 0x01;
        d->faults++;
        send_emcy(s, d, v->error_code);
    }
    if (reset_edge) {
        v->error_code = 0;
        v->errreg = 0;
        send_emcy(s, d, 0x0000); /* error reset */
    }
    v->pos = counts(fb.position[0], s->pos_scale);
    v->vel = counts(fb.velocity[0], s->vel_scale);
    const double tq = fb.torque[0] * 1000.0;
    v->torque = (int16_t)(tq > 32767 ? 32767 : tq < -32768 ? -32768 : lround(tq));
    v->sw = (uint16_t)(mca_co402_statusword(d->st) | MCA_CO402_SW_REMOTE);
    if (d->st != MCA_CO402_OPERATION_ENABLED) {
        v->target_pos = v->pos; /* CSP: no jump when enabled later */
    }
    if (s->log && s->nlog < s->caplog) {
        s->log[s->nlog++] = (logrec_t){d->node, (uint8_t)d->st, d->syncs, d->arm.q[0], d->arm.v[0]};
    }
}

static void send_tpdos(sim_t *s, drive_t *d) {
    if (d->pdo_dead) {
        return;
    }
    for (int k = 0; k < 2; k++) {
        const pdo_comm_t *c = &d->v.tcomm[k];
        if ((c->cob & 0x80000000u) || c->type == 0 || c->type > 240 || d->syncs % c->type != 0) {
            continue;
        }
        mca_co_frame_t f;
        memset(&f, 0, sizeof(f));
        f.id = (uint16_t)(c->cob & 0x7FF);
        const int n = pdo_pack(d, &d->v.tmap[k], f.data);
        if (n < 0) {
            continue;
        }
        f.len = (uint8_t)n;
        if (send(s, &f) == MCA_OK) {
            d->tx_tpdo++;
        }
    }
}

static void injections(sim_t *s, drive_t *d) {
    for (int i = 0; i < s->n_inj; i++) {
        inj_t *x = &s->inj[i];
        if (x->done || x->node != d->node || d->syncs < x->at) {
            continue;
        }
        x->done = 1;
        fprintf(stderr, "mca-drivesim: node %u: inject kind %d at SYNC %" PRIu64 "\n", d->node, x->kind,
                d->syncs);
        switch (x->kind) {
        case 1:
            (void)mca_sim_arm_inject_now(&d->arm, MCA_SIM_INJ_ACTUATOR, 0, 0);
            break;
        case 2:
            send_emcy(s, d, 0x4210);
            break;
        case 3:
            d->hb_dead = 1;
            break;
        case 4:
            d->pdo_dead = 1;
            break;
        default:
            break;
        }
    }
}

static void on_sync(sim_t *s, int64_t now) {
    s->rx_sync++;
    for (int j = 0; j < s->n; j++) {
        drive_t *d = &s->d[j];
        if (d->nmt != MCA_CO_NMT_OPERATIONAL) {
            continue;
        }
        d->last_sync_ns = now;
        d->self_clocked = 0;
        d->syncs++;
        injections(s, d);
        drive_cycle(s, d, 1);
        send_tpdos(s, d);
    }
}

static void on_frame(sim_t *s, const mca_co_frame_t *f, int64_t now) {
    uint8_t node = 0, pdo = 0;
    const mca_co_kind_t k = mca_co_classify(f->id, &node, &pdo);
    if (k == MCA_CO_K_SYNC) {
        on_sync(s, now);
        return;
    }
    for (int j = 0; j < s->n; j++) {
        drive_t *d = &s->d[j];
        if (k == MCA_CO_K_NMT) {
            if (f->len != 2 || (f->data[1] != 0 && f->data[1] != d->node)) {
                continue;
            }
            d->nmt_cmds++;
            const uint8_t before = d->nmt;
            switch (f->data[0]) {
            case MCA_CO_NMT_START:
                d->nmt = MCA_CO_NMT_OPERATIONAL;
                break;
            case MCA_CO_NMT_STOP:
                d->nmt = MCA_CO_NMT_STOPPED;
                break;
            case MCA_CO_NMT_PREOP:
                d->nmt = MCA_CO_NMT_PREOPERATIONAL;
                break;
            case MCA_CO_NMT_RESET_NODE:
                boot(s, d, 1);
                break;
            case MCA_CO_NMT_RESET_COMM:
                boot(s, d, 0);
                break;
            default:
                break;
            }
            if (before == MCA_CO_NMT_OPERATIONAL && d->nmt != MCA_CO_NMT_OPERATIONAL &&
                d->st == MCA_CO402_OPERATION_ENABLED) {
                d->st = MCA_CO402_QUICK_STOP_ACTIVE; /* communication lost: quick stop (0x6007 = 3) */
                d->self_clocked = 1;
                d->last_sync_ns = now;
            }
            continue;
        }
        if (node != d->node) {
            continue;
        }
        if (k == MCA_CO_K_SDO_RX && d->nmt != MCA_CO_NMT_STOPPED) {
            mca_co_frame_t tx;
            d->rx_sdo++;
            if (mca_co_sdo_server_rx(&d->sdo, f, &tx) == 1) {
                (void)send(s, &tx);
            }
        } else if (k == MCA_CO_K_RPDO && pdo <= 2 && d->nmt == MCA_CO_NMT_OPERATIONAL) {
            const pdo_comm_t *c = &d->v.rcomm[pdo - 1];
            if (!(c->cob & 0x80000000u) && (c->cob & 0x7FF) == f->id &&
                pdo_unpack(d, &d->v.rmap[pdo - 1], f->data, f->len) >= 0) {
                d->rx_rpdo++;
                d->rpdo_fresh = 1;
            }
        } else {
            s->rx_other++;
        }
    }
}

/* heartbeats, and the drive's own clock when SYNCs stopped while enabled */
static void timers(sim_t *s, int64_t now) {
    for (int j = 0; j < s->n; j++) {
        drive_t *d = &s->d[j];
        if (d->v.hb_ms && !d->hb_dead && now >= d->next_hb_ns) {
            send_hb(s, d, d->nmt);
            d->next_hb_ns = now + (int64_t)d->v.hb_ms * 1000000;
        }
        const int moving = d->st == MCA_CO402_OPERATION_ENABLED || d->st == MCA_CO402_QUICK_STOP_ACTIVE ||
                           d->st == MCA_CO402_FAULT_REACTION_ACTIVE;
        if (moving && !d->self_clocked && d->last_sync_ns && now - d->last_sync_ns > s->sync_timeout_ns) {
            d->self_clocked = 1; /* the master is gone */
            d->last_sync_ns = now;
            fprintf(stderr, "mca-drivesim: node %u: no SYNC for %.0f ms while %s: braking on its own clock\n",
                    d->node, s->sync_timeout_ns / 1e6, mca_co402_state_name(d->st));
        }
        if (d->self_clocked) {
            const int64_t per = (int64_t)(period_s(s, d) * 1e9);
            while (now - d->last_sync_ns >= per && d->st != MCA_CO402_FAULT &&
                   !(d->arm.state == MCA_ARM_READY && d->st != MCA_CO402_OPERATION_ENABLED)) {
                d->last_sync_ns += per;
                d->syncs++;
                if (d->st == MCA_CO402_QUICK_STOP_ACTIVE) {
                    /* quick stop: a braking request each cycle (no servo enable) */
                    d->v.cw = MCA_CO402_CW_QUICK_STOP;
                    d->rpdo_fresh = 1;
                    drive_cycle(s, d, 1);
                } else {
                    drive_cycle(s, d, 0);
                }
            }
        }
    }
}

static int parse_inject(sim_t *s, const char *t) {
    static const char *const kinds[] = {"", "fault", "emcy", "hbloss", "pdoloss"};
    if (s->n_inj >= MAX_INJ) {
        return -1;
    }
    const char *at = strchr(t, '@');
    const char *colon = at ? strchr(at, ':') : NULL;
    if (!at || !colon) {
        return -1;
    }
    inj_t x = {0, 0, 0, 0};
    for (int k = 1; k < 5; k++) {
        if ((size_t)(at - t) == strlen(kinds[k]) && strncmp(t, kinds[k], (size_t)(at - t)) == 0) {
            x.kind = k;
        }
    }
    char *end = NULL;
    x.at = strtoull(at + 1, &end, 10);
    if (!x.kind || end != colon) {
        return -1;
    }
    x.node = (int)strtol(colon + 1, &end, 10);
    if (*end || x.node < 1 || x.node > 127) {
        return -1;
    }
    s->inj[s->n_inj++] = x;
    return 0;
}

static void usage(void) {
    fprintf(stderr,
            "usage: mca-drivesim --iface IF (--robot URDF | --joints N) [--first-node 1] [--q0 a,b,...]\n"
            "                    [--pos-scale 1e6] [--vel-scale 1e6] [--dec-limit D] [--acc-limit A]\n"
            "                    [--watchdog-cycles 3] [--sync-timeout-ms 200] [--inject KIND@SYNC:NODE]...\n"
            "                    [--sdo-abort NODE:INDEX] [--log FILE]\n"
            "  KIND: fault | emcy | hbloss | pdoloss\n");
}

int main(int argc, char **argv) {
    static sim_t s;
    const char *iface = NULL, *robot = NULL, *q0s = NULL, *logp = NULL;
    long joints = 0, first = 1, wd = 3, sync_tmo = 200;
    double acc = 0, dec = 0;
    s.pos_scale = 1e6;
    s.vel_scale = 1e6;
    s.default_dt = 1e-3;
    long refuse_node = 0, refuse_index = 0;
    static const struct option opts[] = {
        {"iface", required_argument, 0, 'i'},
        {"robot", required_argument, 0, 'r'},
        {"joints", required_argument, 0, 'n'},
        {"first-node", required_argument, 0, 'f'},
        {"q0", required_argument, 0, 'q'},
        {"pos-scale", required_argument, 0, 'p'},
        {"vel-scale", required_argument, 0, 'v'},
        {"dec-limit", required_argument, 0, 'd'},
        {"acc-limit", required_argument, 0, 'a'},
        {"watchdog-cycles", required_argument, 0, 'w'},
        {"sync-timeout-ms", required_argument, 0, 't'},
        {"inject", required_argument, 0, 'j'},
        {"sdo-abort", required_argument, 0, 'x'},
        {"log", required_argument, 0, 'l'},
        {"help", no_argument, 0, 'h'},
        {0, 0, 0, 0},
    };
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        char *end = NULL;
        switch (o) {
        case 'i':
            iface = optarg;
            break;
        case 'r':
            robot = optarg;
            break;
        case 'n':
            joints = strtol(optarg, &end, 10);
            break;
        case 'f':
            first = strtol(optarg, &end, 10);
            break;
        case 'q':
            q0s = optarg;
            break;
        case 'p':
            s.pos_scale = strtod(optarg, &end);
            break;
        case 'v':
            s.vel_scale = strtod(optarg, &end);
            break;
        case 'd':
            dec = strtod(optarg, &end);
            break;
        case 'a':
            acc = strtod(optarg, &end);
            break;
        case 'w':
            wd = strtol(optarg, &end, 10);
            break;
        case 't':
            sync_tmo = strtol(optarg, &end, 10);
            break;
        case 'j':
            if (parse_inject(&s, optarg) != 0) {
                fprintf(stderr, "mca-drivesim: --inject '%s': expected KIND@SYNC:NODE\n", optarg);
                return 2;
            }
            break;
        case 'x':
            refuse_node = strtol(optarg, &end, 0);
            if (*end == ':') {
                refuse_index = strtol(end + 1, &end, 0);
            }
            break;
        case 'l':
            logp = optarg;
            break;
        default:
            usage();
            return o == 'h' ? 0 : 2;
        }
        if (end && *end) {
            fprintf(stderr, "mca-drivesim: bad number '%s'\n", optarg);
            return 2;
        }
    }
    if (optind != argc || !iface || (!robot == !joints) || first < 1 || wd < 1 || sync_tmo < 1 ||
        !(s.pos_scale > 0) || !(s.vel_scale > 0)) {
        usage();
        return 2;
    }
    mca_sim_arm_config_t arm;
    char err[256] = "";
    if (robot) {
        static mca_chain_t chain;
        const int rc = mca_chain_load_urdf(&chain, robot, NULL, err, sizeof(err));
        if (rc != MCA_OK) {
            fprintf(stderr, "mca-drivesim: --robot %s: %s\n", robot, err[0] ? err : mca_strerror(rc));
            return 2;
        }
        mca_sim_arm_config_from_chain(&arm, &chain);
    } else {
        mca_sim_arm_config_default(&arm, (int)joints);
    }
    s.n = arm.n;
    if (s.n > MCA_CO_MAX_NODES || first + s.n - 1 > 127) {
        fprintf(stderr, "mca-drivesim: %d joints from node %ld: at most %d nodes, ids <= 127\n", s.n, first,
                MCA_CO_MAX_NODES);
        return 2;
    }
    if (q0s && mca_sim_parse_joint_list(q0s, arm.n, arm.q0) != MCA_OK) {
        fprintf(stderr, "mca-drivesim: --q0 '%s': expected %d comma-separated numbers\n", q0s, arm.n);
        return 2;
    }
    s.sync_timeout_ns = (int64_t)sync_tmo * 1000000;
    for (int j = 0; j < s.n; j++) {
        drive_t *d = &s.d[j];
        mca_sim_arm_config_t c;
        mca_sim_arm_config_default(&c, 1);
        c.lower[0] = arm.lower[j];
        c.upper[0] = arm.upper[j];
        c.vel_limit[0] = arm.vel_limit[j];
        c.acc_limit[0] = acc > 0 ? acc : arm.acc_limit[j];
        c.dec_limit[0] = dec > 0 ? dec : arm.dec_limit[j];
        c.inertia[0] = arm.inertia[j];
        c.damping[0] = arm.damping[j];
        c.q0[0] = arm.q0[j];
        c.watchdog_cycles = (int)wd;
        c.stamp_monotonic = 1;
        if (mca_sim_arm_init(&d->arm, &c, err, sizeof(err)) != MCA_OK) {
            fprintf(stderr, "mca-drivesim: joint %d: %s\n", j, err);
            return 2;
        }
        d->node = (uint8_t)(first + j);
        d->v.pos = counts(c.q0[0], s.pos_scale);
        if (refuse_node == d->node) {
            d->sdo_refuse = (uint16_t)refuse_index;
        }
        drive_reset_app(d);
        od_build(d);
    }
    if (logp) {
        s.caplog = 400000; /* 66 s of six drives at 1 kHz */
        s.log = calloc(s.caplog, sizeof(*s.log));
        if (!s.log) {
            fprintf(stderr, "mca-drivesim: --log: out of memory\n");
            return 1;
        }
    }
    const int rc = mca_co_sock_open(&s.fd, iface, err, sizeof(err));
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-drivesim: %s\n", err);
        return 1;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof(sa));
    sa.sa_handler = on_signal;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    for (int j = 0; j < s.n; j++) {
        boot(&s, &s.d[j], 1);
    }
    fprintf(stderr, "mca-drivesim: %d drives, nodes %ld..%ld on %s\n", s.n, first, first + s.n - 1, iface);
    while (!g_stop) {
        /* sleep until a frame, the next heartbeat, the SYNC timeout of an enabled drive, or the next cycle of
           a self-clocked one (at most 100 ms: SIGTERM is seen within that) */
        const int64_t t0 = mono_ns();
        int64_t wake = t0 + 100000000;
        for (int j = 0; j < s.n; j++) {
            const drive_t *d = &s.d[j];
            if (d->v.hb_ms && !d->hb_dead && d->next_hb_ns < wake) {
                wake = d->next_hb_ns;
            }
            if (d->self_clocked) {
                wake = t0; /* catch up, then 1 ms polls */
            } else if (d->last_sync_ns && d->last_sync_ns + s.sync_timeout_ns < wake &&
                       (d->st == MCA_CO402_OPERATION_ENABLED || d->st == MCA_CO402_QUICK_STOP_ACTIVE ||
                        d->st == MCA_CO402_FAULT_REACTION_ACTIVE)) {
                wake = d->last_sync_ns + s.sync_timeout_ns + 1;
            }
        }
        int tmo = wake <= t0 ? 1 : (int)((wake - t0 + 999999) / 1000000);
        struct pollfd p = {.fd = s.fd, .events = POLLIN};
        (void)poll(&p, 1, tmo);
        mca_can_frame_t fr[MCA_CAN_RX_BATCH];
        int bad = 0;
        const int n = mca_can_sock_recv_batch(s.fd, fr, MCA_CAN_RX_BATCH, &bad);
        const int64_t now = mono_ns();
        for (int i = 0; i < n; i++) {
            mca_co_frame_t f;
            if (!mca_co_frame_from_can(&f, &fr[i])) {
                continue;
            }
            s.rx_frames++;
            on_frame(&s, &f, now);
        }
        if (n == MCA_EIO) {
            fprintf(stderr, "mca-drivesim: socket error\n");
            break;
        }
        timers(&s, now);
    }
    for (int j = 0; j < s.n; j++) {
        const drive_t *d = &s.d[j];
        fprintf(stderr,
                "mca-drivesim: node %u nmt=0x%02X state=%s syncs=%" PRIu64 " rpdo=%" PRIu64 " tpdo=%" PRIu64
                " sdo=%" PRIu64 " emcy=%" PRIu64 " faults=%" PRIu64 " q=%.9f\n",
                d->node, d->nmt, mca_co402_state_name(d->st), d->syncs, d->rx_rpdo, d->tx_tpdo, d->rx_sdo,
                d->tx_emcy, d->faults, d->arm.q[0]);
    }
    fprintf(stderr, "mca-drivesim: rx=%" PRIu64 " tx=%" PRIu64 " tx_fail=%" PRIu64 " sync=%" PRIu64 "\n",
            s.rx_frames, s.tx_frames, s.tx_fail, s.rx_sync);
    if (s.log) {
        FILE *f = fopen(logp, "w");
        if (f) {
            for (size_t i = 0; i < s.nlog; i++) {
                const logrec_t *r = &s.log[i];
                fprintf(f, "s %u %" PRIu64 " %s %.9f %.9f\n", r->node, r->sync,
                        mca_co402_state_name((mca_co402_state_t)r->st), r->q, r->v);
            }
            fclose(f);
        }
        free(s.log);
    }
    mca_can_sock_close(s.fd);
    return 0;
}
