/* SPDX-License-Identifier: MIT */
/* mca-armsim: arm firmware emulator behind CAN FD. Runs the simulated arm firmware (mca/sim_arm.h,
 * the same object the in-process backend runs) on a 1 kHz absolute-time cycle and speaks the mca
 * arm protocol (mca/can_proto.h): every cycle it takes the newest valid command frame, runs one
 * firmware cycle and answers with a feedback frame; heartbeat/state every MCA_CAN_HEARTBEAT_CYCLES
 * and on change; fault frame on change (and with the heartbeat while a fault is set).
 * --lockstep runs one firmware cycle per valid command instead of the clock (virtual time: used to
 * compare trajectories with the in-process backend; no watchdog without commands in that mode).
 * --log FILE writes every state and fault frame sent (as the values handed to the encoder) at exit:
 *   st <fw_cycle> <counter> <state> <fault_code> <missed> <n_joints> <rx_errors>
 *   ft <fw_cycle> <counter> <state> <fault_code> <flags0..7>
 * (recorded in a buffer allocated at start-up; nothing is written on the cycle path).
 * --lie KIND@CYCLE[:JOINT] (tests of the controller's plausibility checks): from firmware cycle
 * CYCLE on, the feedback on the wire lies, while the arm itself runs on truthfully:
 *   position  joint JOINT reported 0.3 rad beyond its upper limit
 *   velocity  joint JOINT reported at 2 x its velocity limit (at most what the int16 field holds)
 *   jump      joint JOINT reported 0.5 rad away from where it is, from one frame to the next
 *   backwards the frame id answered runs 100 behind the command's
 *   ahead     the frame id answered runs 100 ahead of the command's
 *   joints    the heartbeat (state frame) says one joint more than the arm has
 * Exits cleanly on SIGTERM/SIGINT, printing its counters. Bad arguments: message, exit 2. */
#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <limits.h> /* LONG_MAX */
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <linux/can.h>
#include <linux/can/error.h>

#include "mca/armsim_rx.h"
#include "mca/can_proto.h"
#include "mca/can_sock.h"
#include "mca/chain.h"
#include "mca/err.h"
#include "mca/sim_arm.h"
#include "mca/urdf.h"

static volatile sig_atomic_t g_stop;

static void on_signal(int sig) {
    (void)sig;
    g_stop = 1;
}

typedef struct armsim_counters {
    uint64_t tx_feedback, tx_state, tx_fault, tx_dropped, overruns;
} armsim_counters_t;

/* One sent state or fault frame (--log). */
typedef struct txrec {
    char kind; /* 's' state, 'f' fault */
    uint8_t counter;
    uint64_t cycle;
    mca_can_state_msg_t st;
    mca_can_fault_msg_t ft;
} txrec_t;

typedef struct armsim {
    int fd;
    uint32_t base;
    mca_sim_arm_t arm;
    mca_armsim_rx_t rx; /* receive rules (mca/armsim_rx.h): the cycle's command */
    uint8_t ctr_fb, ctr_state, ctr_fault;
    uint16_t sent_code;
    uint16_t sent_flags[MCA_MAX_DOF];
    int sent_state;
    armsim_counters_t c;
    txrec_t *log; /* --log: sent state/fault frames */
    size_t nlog, caplog;
    uint64_t log_lost;
    int lie;            /* --lie: lie_kind_t, LIE_NONE = none */
    uint64_t lie_cycle; /* from this firmware cycle on */
    int lie_joint;
} armsim_t;

typedef enum lie_kind {
    LIE_NONE,
    LIE_POSITION,
    LIE_VELOCITY,
    LIE_JUMP,
    LIE_BACKWARDS,
    LIE_AHEAD,
    LIE_JOINTS
} lie_kind_t;
static const char *const lie_names[] = {"none",      "position", "velocity", "jump",
                                        "backwards", "ahead",    "joints"};

/* --lie KIND@CYCLE[:JOINT] @return 0 ok, -1 bad */
static int parse_lie(armsim_t *s, const char *t, int n) {
    char kind[16];
    unsigned long long at = 0;
    int joint = 0, used = 0;
    if (sscanf(t, "%15[a-z]@%llu%n", kind, &at, &used) != 2) {
        return -1;
    }
    if (t[used] == ':' && (sscanf(t + used + 1, "%d", &joint) != 1 || joint < 0 || joint >= n)) {
        return -1;
    }
    for (int k = LIE_POSITION; k <= LIE_JOINTS; k++) {
        if (strcmp(kind, lie_names[k]) == 0) {
            s->lie = k;
            s->lie_cycle = at;
            s->lie_joint = joint;
            return 0;
        }
    }
    return -1;
}

/* The feedback as it goes on the wire: true until --lie's cycle, then the lie (the arm runs on truthfully).
 */
static void lie_feedback(const armsim_t *s, mca_arm_feedback_t *fb) {
    const mca_sim_arm_t *a = &s->arm;
    if (s->lie == LIE_NONE || a->cycle < s->lie_cycle) {
        return;
    }
    const int j = s->lie_joint;
    const double vmax = 32767 * MCA_CAN_FB_VEL_SCALE;
    switch (s->lie) {
    case LIE_POSITION:
        fb->position[j] = a->cfg.upper[j] + 0.3;
        break;
    case LIE_VELOCITY:
        fb->velocity[j] = fmin(2.0 * a->cfg.vel_limit[j], vmax);
        break;
    case LIE_JUMP:
        fb->position[j] += a->cycle % 2 ? 0.5 : -0.5;
        break;
    case LIE_BACKWARDS:
        fb->frame_id -= 100;
        break;
    case LIE_AHEAD:
        fb->frame_id += 100;
        break;
    default:
        break;
    }
}

static void log_tx(armsim_t *s, char kind, uint8_t counter, const mca_can_state_msg_t *st,
                   const mca_can_fault_msg_t *ft) {
    if (!s->log) {
        return;
    }
    if (s->nlog >= s->caplog) {
        s->log_lost++;
        return;
    }
    txrec_t *r = &s->log[s->nlog++];
    memset(r, 0, sizeof(*r));
    r->kind = kind;
    r->counter = counter;
    r->cycle = s->arm.cycle;
    if (st) {
        r->st = *st;
    }
    if (ft) {
        r->ft = *ft;
    }
}

static void write_log(const armsim_t *s, const char *path) {
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "mca-armsim: --log %s: %s\n", path, strerror(errno));
        return;
    }
    for (size_t i = 0; i < s->nlog; i++) {
        const txrec_t *r = &s->log[i];
        if (r->kind == 's') {
            fprintf(f, "st %" PRIu64 " %u %u %u %u %u %u\n", r->cycle, r->counter, r->st.state,
                    r->st.fault_code, r->st.missed, r->st.n, r->st.rx_errors);
        } else {
            fprintf(f, "ft %" PRIu64 " %u %u %u", r->cycle, r->counter, r->ft.state, r->ft.fault_code);
            for (int j = 0; j < MCA_MAX_DOF; j++) {
                fprintf(f, " %u", r->ft.fault_flags[j]);
            }
            fputc('\n', f);
        }
    }
    fclose(f);
}

static void usage(FILE *f) {
    fprintf(
        f,
        "usage: mca-armsim --iface IF (--robot URDF | --joints N) [--id-base 0x100] [--watchdog-cycles 3]\n"
        "                  [--period-us 1000] [--acc-limit A] [--dec-limit D] [--q0 a,b,...]\n"
        "                  [--lockstep] [--duration S] [--stats FILE] [--log FILE]\n"
        "                  [--lag-ms T] [--latency-cycles N] [--noise-pos S] [--noise-vel S] [--seed N]\n"
        "                  [--inject KIND@CYCLE[+CYCLES][:JOINT] ...] [--lie KIND@CYCLE[:JOINT]] "
        "[--print-config]\n"
        "  the in-process sim backend's model options (mca/sim_arm.h); KIND: actuator, freeze, silent,\n"
        "  drop-rx; --print-config prints the arm configuration and exits (no bus needed)\n");
}

static int parse_inject(const char *s, int n_joints, mca_sim_inject_t *inj) {
    if (mca_sim_inject_parse(s, n_joints, inj) != MCA_OK) {
        fprintf(stderr,
                "mca-armsim: --inject '%s': expected " MCA_SIM_INJECT_SYNTAX
                " with KIND actuator (needs :JOINT, 0..%d), freeze, silent or drop-rx\n",
                s, n_joints - 1);
        return -1;
    }
    return 0;
}

static void print_config(FILE *f, const mca_sim_arm_config_t *c) {
    fprintf(
        f,
        "joints=%d dt=%.9g watchdog_cycles=%d lag_tau=%.9g latency_cycles=%d noise_pos=%.9g noise_vel=%.9g "
        "seed=%" PRIu64 " injections=%d\n",
        c->n, c->dt, c->watchdog_cycles, c->lag_tau, c->latency_cycles, c->noise_pos, c->noise_vel, c->seed,
        c->n_inject);
    for (int i = 0; i < c->n_inject; i++) {
        const mca_sim_inject_t *in = &c->inject[i];
        fprintf(f, "inject %d: kind=%s at_cycle=%" PRIu64 " duration=%" PRIu64 " joint=%d\n", i,
                mca_sim_inject_kind_name(in->kind), in->at_cycle, in->duration, in->joint);
    }
    for (int j = 0; j < c->n; j++) {
        fprintf(f, "joint %d: q0=%.9g acc_limit=%.9g dec_limit=%.9g vel_limit=%.9g\n", j, c->q0[j],
                c->acc_limit[j], c->dec_limit[j], c->vel_limit[j]);
    }
}

static int parse_long(const char *opt, const char *s, long lo, long hi, long *out) {
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 0);
    if (errno || !end || *end || v < lo || v > hi) {
        fprintf(stderr, "mca-armsim: %s '%s': expected an integer in %ld..%ld\n", opt, s, lo, hi);
        return -1;
    }
    *out = v;
    return 0;
}

static int parse_double(const char *opt, const char *s, double lo, double *out) {
    char *end = NULL;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || !end || *end || !isfinite(v) || v < lo) {
        fprintf(stderr, "mca-armsim: %s '%s': expected a number >= %g\n", opt, s, lo);
        return -1;
    }
    *out = v;
    return 0;
}

/* Drain the socket, at most MCA_ARMSIM_RX_BURST frames (a flood waits, the firmware cycle runs): keep the
 * newest valid command; count and drop everything else (mca/armsim_rx.h). */
static int sock_recv(void *ctx, mca_can_frame_t *f) {
    return mca_can_sock_recv(*(const int *)ctx, f);
}

static void drain(armsim_t *s) {
    mca_armsim_rx_drain(&s->rx, sock_recv, &s->fd);
}

/* @return 1 sent, 0 dropped */
static int send_frame(armsim_t *s, uint32_t off, const uint8_t *buf, size_t len, uint64_t *ok, uint8_t *ctr) {
    if (mca_can_sock_send(s->fd, s->base + off, buf, len, 1, 1) == MCA_OK) {
        (*ok)++;
        (*ctr)++;
        return 1;
    }
    s->c.tx_dropped++;
    return 0;
}

/* One firmware cycle and its frames. */
static void cycle(armsim_t *s, double dt) {
    mca_arm_feedback_t fb;
    mca_arm_command_t cmd;
    int rc = mca_sim_arm_cycle(&s->arm, mca_armsim_rx_take(&s->rx, &cmd), dt, &fb);
    if (rc == MCA_OK) {
        uint8_t buf[MCA_CAN_LEN_FEEDBACK];
        lie_feedback(s, &fb);
        if (mca_can_encode_feedback(&fb, s->ctr_fb, buf) == MCA_OK) {
            send_frame(s, MCA_CAN_OFF_FEEDBACK, buf, sizeof(buf), &s->c.tx_feedback, &s->ctr_fb);
        }
    }
    const mca_sim_arm_t *a = &s->arm;
    int n = a->cfg.n;
    int beat = a->cycle % MCA_CAN_HEARTBEAT_CYCLES == 0;
    int flags_changed = memcmp(s->sent_flags, a->fault_flags, sizeof(s->sent_flags)) != 0;
    int any_fault = a->fault_code != 0;
    for (int j = 0; j < n; j++) {
        any_fault |= a->fault_flags[j] != 0;
    }
    if (beat || (int)a->state != s->sent_state) {
        mca_can_state_msg_t m = {
            .state = (uint8_t)a->state,
            .n = (uint8_t)(s->lie == LIE_JOINTS && a->cycle >= s->lie_cycle ? n + 1 : n),
            .fault_code = a->fault_code,
            .missed = (uint16_t)(a->missed > 65535 ? 65535 : a->missed),
            .rx_errors = (uint8_t)(s->rx.c.rx_bad_length + s->rx.c.rx_bad_counter + s->rx.c.rx_unknown_id +
                                   s->rx.c.rx_bad_frame_id),
        };
        uint8_t buf[MCA_CAN_LEN_STATE];
        const uint8_t ctr = s->ctr_state;
        mca_can_encode_state(&m, ctr, buf);
        if (send_frame(s, MCA_CAN_OFF_STATE, buf, sizeof(buf), &s->c.tx_state, &s->ctr_state)) {
            log_tx(s, 's', ctr, &m, NULL);
        }
        s->sent_state = (int)a->state;
    }
    if (flags_changed || a->fault_code != s->sent_code || (beat && any_fault)) {
        mca_can_fault_msg_t m;
        memset(&m, 0, sizeof(m));
        m.state = (uint8_t)a->state;
        m.fault_code = a->fault_code;
        memcpy(m.fault_flags, a->fault_flags, sizeof(m.fault_flags));
        uint8_t buf[MCA_CAN_LEN_FAULT];
        const uint8_t ctr = s->ctr_fault;
        mca_can_encode_fault(&m, ctr, buf);
        if (send_frame(s, MCA_CAN_OFF_FAULT, buf, sizeof(buf), &s->c.tx_fault, &s->ctr_fault)) {
            log_tx(s, 'f', ctr, NULL, &m);
        }
        s->sent_code = a->fault_code;
        memcpy(s->sent_flags, a->fault_flags, sizeof(s->sent_flags));
    }
}

static void ts_add_ns(struct timespec *t, long ns) {
    t->tv_nsec += ns;
    while (t->tv_nsec >= 1000000000L) {
        t->tv_nsec -= 1000000000L;
        t->tv_sec++;
    }
}

static int64_t ts_ns(const struct timespec *t) {
    return (int64_t)t->tv_sec * 1000000000 + t->tv_nsec;
}

static void print_counters(FILE *f, const armsim_t *s) {
    const mca_sim_arm_counters_t *fw = &s->arm.cnt;
    fprintf(f,
            "cycles=%" PRIu64 " frames_rx=%" PRIu64 " cmd_accepted=%" PRIu64 " cmd_superseded=%" PRIu64
            " rx_bad_length=%" PRIu64 " rx_bad_counter=%" PRIu64 " rx_unknown_id=%" PRIu64
            " bus_errors=%" PRIu64 " tx_feedback=%" PRIu64 " tx_state=%" PRIu64 " tx_fault=%" PRIu64
            " tx_dropped=%" PRIu64 " overruns=%" PRIu64 " fw_cmd_accepted=%" PRIu64 " fw_cmd_stale=%" PRIu64
            " watchdog_trips=%" PRIu64 " state=%s fault_code=%u log_lost=%" PRIu64 " rx_bad_frame_id=%" PRIu64
            " rx_burst_full=%" PRIu64 "\n",
            fw->cycles, s->rx.c.frames_rx, s->rx.c.cmd_accepted, s->rx.c.cmd_superseded,
            s->rx.c.rx_bad_length, s->rx.c.rx_bad_counter, s->rx.c.rx_unknown_id, s->rx.c.bus_errors,
            s->c.tx_feedback, s->c.tx_state, s->c.tx_fault, s->c.tx_dropped, s->c.overruns, fw->cmd_accepted,
            fw->cmd_stale, fw->watchdog_trips, mca_arm_state_name(s->arm.state), (unsigned)s->arm.fault_code,
            s->log_lost, s->rx.c.rx_bad_frame_id, s->rx.c.rx_burst_full);
}

int main(int argc, char **argv) {
    const char *iface = NULL, *robot = NULL, *stats = NULL, *q0s = NULL, *logp = NULL;
    long base = 0x100, wd = 3, period_us = 1000, joints = 0;
    double acc = -1, dec = -1, duration = 0;
    double lag_ms = 0, noise_pos = 0, noise_vel = 0;
    long latency = 0, seed = 1;
    const char *inject_s[MCA_SIM_MAX_INJECT];
    const char *lie_s = NULL;
    int n_inject = 0, lockstep = 0, print_cfg = 0;
    static const struct option opts[] = {
        {"iface", required_argument, 0, 'i'},
        {"robot", required_argument, 0, 'r'},
        {"joints", required_argument, 0, 'n'},
        {"id-base", required_argument, 0, 'b'},
        {"watchdog-cycles", required_argument, 0, 'w'},
        {"period-us", required_argument, 0, 'p'},
        {"acc-limit", required_argument, 0, 'a'},
        {"dec-limit", required_argument, 0, 'd'},
        {"q0", required_argument, 0, 'q'},
        {"lockstep", no_argument, 0, 'l'},
        {"duration", required_argument, 0, 't'},
        {"stats", required_argument, 0, 's'},
        {"log", required_argument, 0, 'L'},
        {"lag-ms", required_argument, 0, 'g'},
        {"latency-cycles", required_argument, 0, 'y'},
        {"noise-pos", required_argument, 0, 'P'},
        {"noise-vel", required_argument, 0, 'V'},
        {"seed", required_argument, 0, 'S'},
        {"inject", required_argument, 0, 'j'},
        {"lie", required_argument, 0, 'X'},
        {"print-config", no_argument, 0, 'c'},
        {"help", no_argument, 0, 'h'},
        {0, 0, 0, 0},
    };
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        int bad = 0;
        switch (o) {
        case 'i':
            iface = optarg;
            break;
        case 'r':
            robot = optarg;
            break;
        case 'n':
            bad = parse_long("--joints", optarg, 1, MCA_MAX_DOF, &joints);
            break;
        case 'b':
            bad = parse_long("--id-base", optarg, 0, MCA_CAN_ID_BASE_MAX, &base);
            break;
        case 'w':
            bad = parse_long("--watchdog-cycles", optarg, 1, 100000, &wd);
            break;
        case 'p':
            bad = parse_long("--period-us", optarg, 100, 1000000, &period_us);
            break;
        case 'a':
            bad = parse_double("--acc-limit", optarg, 1e-9, &acc);
            break;
        case 'd':
            bad = parse_double("--dec-limit", optarg, 1e-9, &dec);
            break;
        case 'q':
            q0s = optarg;
            break;
        case 'l':
            lockstep = 1;
            break;
        case 't':
            bad = parse_double("--duration", optarg, 0, &duration);
            break;
        case 's':
            stats = optarg;
            break;
        case 'L':
            logp = optarg;
            break;
        case 'g':
            bad = parse_double("--lag-ms", optarg, 0, &lag_ms);
            break;
        case 'y':
            bad = parse_long("--latency-cycles", optarg, 0, MCA_SIM_MAX_LATENCY, &latency);
            break;
        case 'P':
            bad = parse_double("--noise-pos", optarg, 0, &noise_pos);
            break;
        case 'V':
            bad = parse_double("--noise-vel", optarg, 0, &noise_vel);
            break;
        case 'S':
            bad = parse_long("--seed", optarg, 0, LONG_MAX, &seed);
            break;
        case 'j':
            if (n_inject == MCA_SIM_MAX_INJECT) {
                fprintf(stderr, "mca-armsim: --inject: at most %d\n", MCA_SIM_MAX_INJECT);
                bad = -1;
            } else {
                inject_s[n_inject++] = optarg;
            }
            break;
        case 'X':
            lie_s = optarg;
            break;
        case 'c':
            print_cfg = 1;
            break;
        case 'h':
            usage(stdout);
            return 0;
        default:
            usage(stderr);
            return 2;
        }
        if (bad) {
            return 2;
        }
    }
    if (optind != argc || (!iface && !print_cfg) || (!robot == !joints)) {
        fprintf(stderr, "mca-armsim: %s\n",
                optind != argc ? "unexpected argument"
                               : (!iface && !print_cfg ? "--iface is required"
                                                       : "give exactly one of --robot and --joints"));
        usage(stderr);
        return 2;
    }
    if (base % MCA_CAN_ID_BLOCK) {
        fprintf(stderr, "mca-armsim: --id-base 0x%lx: must be a multiple of 0x%x\n", base, MCA_CAN_ID_BLOCK);
        return 2;
    }

    static armsim_t s; /* large (delay line): static storage */
    mca_sim_arm_config_t cfg;
    char err[256] = "";
    if (robot) {
        static mca_chain_t chain;
        int rc = mca_chain_load_urdf(&chain, robot, NULL, err, sizeof(err));
        if (rc != MCA_OK) {
            fprintf(stderr, "mca-armsim: --robot %s: %s\n", robot, err[0] ? err : mca_strerror(rc));
            return 2;
        }
        mca_sim_arm_config_from_chain(&cfg, &chain);
    } else {
        mca_sim_arm_config_default(&cfg, (int)joints);
    }
    cfg.watchdog_cycles = (int)wd;
    cfg.dt = (double)period_us * 1e-6;
    cfg.stamp_monotonic = 1;
    cfg.lag_tau = lag_ms * 1e-3;
    cfg.latency_cycles = (int)latency;
    cfg.noise_pos = noise_pos;
    cfg.noise_vel = noise_vel;
    cfg.seed = (uint64_t)seed;
    for (int i = 0; i < n_inject; i++) {
        if (parse_inject(inject_s[i], cfg.n, &cfg.inject[i]) != 0) {
            return 2;
        }
    }
    cfg.n_inject = n_inject;
    if (lie_s && parse_lie(&s, lie_s, cfg.n) != 0) {
        fprintf(stderr,
                "mca-armsim: --lie '%s': expected KIND@CYCLE[:JOINT], KIND position, velocity, jump, "
                "backwards, ahead or joints, JOINT 0..%d\n",
                lie_s, cfg.n - 1);
        return 2;
    }
    for (int j = 0; j < cfg.n; j++) {
        if (acc > 0) {
            cfg.acc_limit[j] = acc;
        }
        if (dec > 0) {
            cfg.dec_limit[j] = dec;
        }
    }
    if (q0s && mca_sim_parse_joint_list(q0s, cfg.n, cfg.q0) != MCA_OK) {
        fprintf(stderr, "mca-armsim: --q0 '%s': expected %d comma-separated numbers\n", q0s, cfg.n);
        return 2;
    }
    if (mca_sim_arm_init(&s.arm, &cfg, err, sizeof(err)) != MCA_OK) {
        fprintf(stderr, "mca-armsim: arm configuration: %s\n", err);
        return 2;
    }
    if (print_cfg) {
        print_config(stdout, &cfg);
        return 0;
    }
    s.base = (uint32_t)base;
    s.sent_state = -1;
    if (logp) {
        s.caplog = 400000; /* > 60 s of state + fault frames at 1 kHz (one state frame per 10 cycles) */
        s.log = calloc(s.caplog, sizeof(*s.log));
        if (!s.log) {
            fprintf(stderr, "mca-armsim: --log %s: out of memory\n", logp);
            return 1;
        }
    }
    mca_armsim_rx_init(&s.rx, s.base);
    int rc = mca_can_sock_open(&s.fd, iface, s.base, CAN_ERR_MASK, err, sizeof(err));
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-armsim: %s\n", err);
        return 1;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof(sa));
    sa.sa_handler = on_signal;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    fprintf(stderr, "mca-armsim: %s id base 0x%03lx, %d joints, watchdog %ld cycles, %s %ld us\n", iface,
            base, cfg.n, wd, lockstep ? "lockstep, dt" : "period", period_us);

    const long period_ns = period_us * 1000L;
    const double dt = cfg.dt;
    struct timespec start, next, now;
    clock_gettime(CLOCK_MONOTONIC, &start);
    next = start;
    const int64_t end_ns = duration > 0 ? ts_ns(&start) + (int64_t)(duration * 1e9) : INT64_MAX;
    while (!g_stop) {
        if (lockstep) {
            struct pollfd pfd = {.fd = s.fd, .events = POLLIN};
            poll(&pfd, 1, 100);
            drain(&s);
            if (s.rx.have_cmd) {
                cycle(&s, dt);
            }
            clock_gettime(CLOCK_MONOTONIC, &now);
        } else {
            drain(&s);
            cycle(&s, dt);
            ts_add_ns(&next, period_ns);
            while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL) == EINTR && !g_stop) {
            }
            clock_gettime(CLOCK_MONOTONIC, &now);
            if (ts_ns(&now) - ts_ns(&next) > period_ns) {
                /* Missed whole periods (preempted): count and restart the schedule from now. */
                s.c.overruns++;
                next = now;
            }
        }
        if (ts_ns(&now) >= end_ns) {
            break;
        }
    }
    /* Count the frames already queued when the signal came (received, never applied: no cycle follows), so
     * the counters describe every frame the bus delivered, not only those read before a slow last wake-up. */
    drain(&s);
    print_counters(stderr, &s);
    if (stats) {
        FILE *f = fopen(stats, "w");
        if (!f) {
            fprintf(stderr, "mca-armsim: --stats %s: %s\n", stats, strerror(errno));
        } else {
            print_counters(f, &s);
            fclose(f);
        }
    }
    if (logp) {
        write_log(&s, logp);
        free(s.log);
    }
    mca_can_sock_close(s.fd);
    return 0;
}
