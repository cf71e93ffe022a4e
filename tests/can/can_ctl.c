/* SPDX-License-Identifier: MIT */
/* mca-can-ctl: small test controller for the vcan suite. Drives one arm through the mca_arm API with
 * the SocketCAN backend and logs what it sent and received (written at exit, nothing on the 1 kHz path).
 *   --mode sine      1 kHz clock_nanosleep loop, sinusoidal joint velocities for --duration s. Lost
 *                    feedback (--lost-cycles consecutive cycles without new feedback) stops commanding
 *                    at once, is reported and exits 3.
 *   --mode lockstep  --cycles N commands, each waiting (poll) for the feedback that answers it: round
 *                    trip times; with --compare-robot URDF the same commands also go through the
 *                    in-process sim backend and the joint trajectories are compared (exit 5 if they
 *                    differ by more than the fixed-point resolution). Prints the rtt_us line: p50, p99,
 *                    max, min and how many measured feedback frames carried a kernel time stamp.
 *   --sat-from K --sat-len L --sat-vel V (sine): joint 0 is commanded V rad/s in cycles K..K+L-1 (above
 *                    its limit: the arm flags VEL_SAT, so fault frames go on the bus).
 * Sine mode sends position_ref = last feedback position + v dt (as the daemon does).
 * Log lines:  tx <cycle> <frame_id> <flags0..n-1> <v0..vn-1> <posref0..n-1>
 *             rx <cycle> <frame_id> <state> <fault_code> <q0..qn-1> <qd0..qdn-1>
 *             er <cycle> <eio> <bus_off> <bus_off_events> <bus_errors> <link_fault>   (sine mode: after
 *                every read that returned MCA_EIO, left bus_off set or changed those counters)
 * Stats file: key=value lines. */
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

#include "mca/arm.h"
#include "mca/arm_can.h"
#include "mca/chain.h"
#include "mca/err.h"
#include "mca/sim_arm.h"
#include "mca/sim_backend.h"
#include "mca/urdf.h"

typedef struct rec {
    int rx;
    uint32_t cycle, frame_id;
    int state, fault;
    uint8_t flags[MCA_MAX_DOF];
    double a[MCA_MAX_DOF], b[MCA_MAX_DOF], c[MCA_MAX_DOF];
} rec_t;

/* Link error record (bus-off / error-frame timing in cycles). */
typedef struct erec {
    uint32_t cycle;
    int eio, bus_off, link_fault;
    uint64_t bus_off_events, bus_errors;
} erec_t;

static volatile sig_atomic_t g_stop;

static void on_signal(int sig) {
    (void)sig;
    g_stop = 1;
}

static rec_t *g_log;
static size_t g_nlog, g_caplog;
static int g_n;
#define ER_CAP 20000
static erec_t g_er[ER_CAP];
static size_t g_ner;

static void log_push(const rec_t *r) {
    if (g_nlog < g_caplog) {
        g_log[g_nlog++] = *r;
    }
}

static int64_t now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

static int cmp_i64(const void *a, const void *b) {
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

static void write_log(const char *path) {
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "mca-can-ctl: --log %s: %s\n", path, strerror(errno));
        return;
    }
    for (size_t i = 0; i < g_nlog; i++) {
        const rec_t *r = &g_log[i];
        if (r->rx) {
            fprintf(f, "rx %u %u %d %d", r->cycle, r->frame_id, r->state, r->fault);
            for (int j = 0; j < g_n; j++) {
                fprintf(f, " %.7f", r->a[j]);
            }
            for (int j = 0; j < g_n; j++) {
                fprintf(f, " %.5f", r->b[j]);
            }
        } else {
            fprintf(f, "tx %u %u", r->cycle, r->frame_id);
            for (int j = 0; j < g_n; j++) {
                fprintf(f, " %u", (unsigned)r->flags[j]);
            }
            for (int j = 0; j < g_n; j++) {
                fprintf(f, " %.7f", r->a[j]);
            }
            for (int j = 0; j < g_n; j++) {
                fprintf(f, " %.7f", r->c[j]);
            }
        }
        fputc('\n', f);
    }
    for (size_t i = 0; i < g_ner; i++) {
        const erec_t *e = &g_er[i];
        fprintf(f, "er %u %d %d %" PRIu64 " %" PRIu64 " %d\n", e->cycle, e->eio, e->bus_off,
                e->bus_off_events, e->bus_errors, e->link_fault);
    }
    fclose(f);
}

static double quant(double v, double scale) {
    return (double)llround(v / scale) * scale; /* what the wire carries, bit-exact (see can_proto.c) */
}

int main(int argc, char **argv) {
    const char *iface = "vcan0", *mode = "sine", *logp = NULL, *statp = NULL, *robot = NULL, *q0s = NULL;
    long base = 0x100, n = 6, lost_cycles = 5, cycles = 2000, wd = 3;
    double duration = 2.0, amp = 0.3, freq = 0.5, sat_vel = 0;
    long sat_from = -1, sat_len = 0;
    static const struct option opts[] = {
        {"iface", required_argument, 0, 'i'},       {"id-base", required_argument, 0, 'b'},
        {"joints", required_argument, 0, 'n'},      {"mode", required_argument, 0, 'm'},
        {"duration", required_argument, 0, 't'},    {"cycles", required_argument, 0, 'c'},
        {"lost-cycles", required_argument, 0, 'L'}, {"amp", required_argument, 0, 'A'},
        {"freq", required_argument, 0, 'f'},        {"log", required_argument, 0, 'l'},
        {"stats", required_argument, 0, 's'},       {"compare-robot", required_argument, 0, 'r'},
        {"q0", required_argument, 0, 'q'},          {"watchdog-cycles", required_argument, 0, 'w'},
        {"sat-from", required_argument, 0, 'S'},    {"sat-len", required_argument, 0, 'N'},
        {"sat-vel", required_argument, 0, 'V'},     {0, 0, 0, 0},
    };
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case 'i':
            iface = optarg;
            break;
        case 'b':
            base = strtol(optarg, NULL, 0);
            break;
        case 'n':
            n = strtol(optarg, NULL, 0);
            break;
        case 'm':
            mode = optarg;
            break;
        case 't':
            duration = strtod(optarg, NULL);
            break;
        case 'c':
            cycles = strtol(optarg, NULL, 0);
            break;
        case 'L':
            lost_cycles = strtol(optarg, NULL, 0);
            break;
        case 'A':
            amp = strtod(optarg, NULL);
            break;
        case 'f':
            freq = strtod(optarg, NULL);
            break;
        case 'l':
            logp = optarg;
            break;
        case 's':
            statp = optarg;
            break;
        case 'r':
            robot = optarg;
            break;
        case 'q':
            q0s = optarg;
            break;
        case 'w':
            wd = strtol(optarg, NULL, 0);
            break;
        case 'S':
            sat_from = strtol(optarg, NULL, 0);
            break;
        case 'N':
            sat_len = strtol(optarg, NULL, 0);
            break;
        case 'V':
            sat_vel = strtod(optarg, NULL);
            break;
        default:
            fprintf(stderr, "mca-can-ctl: bad arguments\n");
            return 2;
        }
    }
    int lockstep = strcmp(mode, "lockstep") == 0;
    if ((!lockstep && strcmp(mode, "sine") != 0) || n < 1 || n > MCA_MAX_DOF || duration <= 0 || cycles < 1 ||
        lost_cycles < 1) {
        fprintf(stderr, "mca-can-ctl: bad --mode/--joints/--duration/--cycles/--lost-cycles\n");
        return 2;
    }
    g_n = (int)n;
    long total = lockstep ? cycles : (long)(duration * 1000.0) + 10;
    g_caplog = (size_t)total * 2 + 16;
    g_log = calloc(g_caplog, sizeof(*g_log));
    int64_t *rtt = calloc((size_t)total + 1, sizeof(*rtt));
    if (!g_log || !rtt) {
        return 1;
    }
    mca_arm_t *arm = NULL;
    char err[256] = "";
    int rc = mca_can_backend_open(&arm, iface, (uint32_t)base, g_n, NULL, err, sizeof(err));
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-can-ctl: %s\n", err[0] ? err : mca_strerror(rc));
        return 1;
    }
    int fd = mca_can_backend_fd(arm);
    mca_arm_feedback_t fb;
    memset(&fb, 0, sizeof(fb));
    mca_arm_command_t cmd;
    memset(&cmd, 0, sizeof(cmd));
    cmd.n = g_n;
    for (int j = 0; j < g_n; j++) {
        cmd.flags[j] = MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE;
    }
    uint64_t eio = 0, rx_new = 0, overruns = 0, clears = 0, kstamped = 0, ustamped = 0;
    int64_t rtt_min = INT64_MAX;
    mca_arm_stats_t lst;
    memset(&lst, 0, sizeof(lst));
    long lost_at = -1, last_fb_cycle = -1, k = 0;
    int exit_code = 0;

    if (!lockstep) {
        /* Wait (not real-time yet) for the arm to talk before starting the clock. */
        struct sigaction sa;
        memset(&sa, 0, sizeof(sa));
        sa.sa_handler = on_signal; /* SIGTERM/SIGINT end the run normally (stats and log written) */
        sigaction(SIGTERM, &sa, NULL);
        sigaction(SIGINT, &sa, NULL);
        int64_t t_end = now_ns() + 30000000000LL;
        while ((rc = mca_arm_read(arm, &fb)) == MCA_EAGAIN && now_ns() < t_end) {
            struct pollfd p = {.fd = fd, .events = POLLIN};
            poll(&p, 1, 50);
        }
        if (rc != MCA_OK && rc != MCA_EFAULT) {
            fprintf(stderr, "mca-can-ctl: no feedback from the arm within 30 s (%s)\n", mca_strerror(rc));
            return 4;
        }
        struct timespec next;
        clock_gettime(CLOCK_MONOTONIC, &next);
        for (k = 0; k < total - 10 && !g_stop; k++) {
            rc = mca_arm_read(arm, &fb);
            if (rc == MCA_EIO) {
                eio++;
            }
            /* error-frame / bus-off timing: what this read returned and left in the link state */
            mca_arm_stats_t est;
            mca_arm_stats(arm, &est);
            if ((rc == MCA_EIO || est.bus_off || est.bus_off_events != lst.bus_off_events ||
                 est.bus_errors != lst.bus_errors) &&
                g_ner < ER_CAP) {
                g_er[g_ner++] = (erec_t){.cycle = (uint32_t)k,
                                         .eio = rc == MCA_EIO,
                                         .bus_off = est.bus_off,
                                         .link_fault = est.link_fault,
                                         .bus_off_events = est.bus_off_events,
                                         .bus_errors = est.bus_errors};
            }
            lst = est;
            if (rc == MCA_OK || rc == MCA_EFAULT || (rc == MCA_EIO && fb.stamp_ns != 0)) {
                rx_new++;
                last_fb_cycle = k;
                rec_t r = {.rx = 1,
                           .cycle = (uint32_t)k,
                           .frame_id = fb.frame_id,
                           .state = fb.state,
                           .fault = fb.fault_code};
                memcpy(r.a, fb.position, sizeof(r.a));
                memcpy(r.b, fb.velocity, sizeof(r.b));
                log_push(&r);
                fb.stamp_ns = 0; /* marks "taken" so an EIO read without new feedback is not counted */
            } else if (k - last_fb_cycle >= lost_cycles) {
                lost_at = k; /* lost feedback: stop commanding now */
                exit_code = 3;
                break;
            }
            double t = (double)k * 1e-3;
            cmd.frame_id = (uint32_t)(k + 1);
            /* An arm in FAULT (e.g. a watchdog trip while this process was preempted) is cleared and
             * re-enabled, so a run survives hiccups; the count is reported. */
            uint8_t fl = MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE;
            if (fb.state == MCA_ARM_FAULT) {
                fl = MCA_ACT_CLEAR_FAULT;
                clears++;
            }
            for (int j = 0; j < g_n; j++) {
                cmd.velocity[j] = amp * (1.0 - 0.1 * j) * sin(2.0 * M_PI * freq * (1.0 + 0.2 * j) * t);
                cmd.flags[j] = fl;
            }
            if (k >= sat_from && k < sat_from + sat_len) {
                cmd.velocity[0] = sat_vel;
            }
            for (int j = 0; j < g_n; j++) {
                cmd.position_ref[j] = fb.position[j] + cmd.velocity[j] * 1e-3;
            }
            if (mca_arm_write(arm, &cmd) == MCA_OK) {
                rec_t r = {.rx = 0, .cycle = (uint32_t)k, .frame_id = cmd.frame_id};
                memcpy(r.flags, cmd.flags, sizeof(r.flags));
                memcpy(r.a, cmd.velocity, sizeof(r.a));
                memcpy(r.c, cmd.position_ref, sizeof(r.c));
                log_push(&r);
            }
            next.tv_nsec += 1000000;
            if (next.tv_nsec >= 1000000000L) {
                next.tv_nsec -= 1000000000L;
                next.tv_sec++;
            }
            clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
            struct timespec now;
            clock_gettime(CLOCK_MONOTONIC, &now);
            if ((now.tv_sec - next.tv_sec) * 1000000000LL + (now.tv_nsec - next.tv_nsec) > 1000000LL) {
                /* Preempted for whole periods: restart the schedule instead of a catch-up burst of
                 * cycles (which would count as missed feedback without the arm having had time). */
                overruns++;
                next = now;
            }
        }
        if (exit_code == 0) {
            /* Done: request braking (no servo flags) so the arm stops without a watchdog fault. */
            cmd.frame_id = (uint32_t)(k + 1);
            for (int j = 0; j < g_n; j++) {
                cmd.velocity[j] = 0;
                cmd.flags[j] = 0;
            }
            mca_arm_write(arm, &cmd);
        }
    } else {
        /* Lockstep: one command, wait for its answer, next command. */
        mca_arm_t *sim = NULL;
        double maxdq = 0, maxdv = 0;
        long state_mismatch = 0;
        if (robot) {
            static mca_chain_t chain;
            mca_sim_arm_config_t cfg;
            if (mca_chain_load_urdf(&chain, robot, NULL, err, sizeof(err)) != MCA_OK ||
                mca_sim_arm_config_from_chain(&cfg, &chain) != MCA_OK || cfg.n != g_n) {
                fprintf(stderr, "mca-can-ctl: --compare-robot %s: %s\n", robot, err);
                return 2;
            }
            cfg.watchdog_cycles = (int)wd;
            if (q0s) {
                const char *p = q0s;
                for (int j = 0; j < g_n; j++) {
                    char *end;
                    cfg.q0[j] = strtod(p, &end);
                    p = *end ? end + 1 : end;
                }
            }
            if (mca_sim_backend_open(&sim, &cfg, err, sizeof(err)) != MCA_OK) {
                fprintf(stderr, "mca-can-ctl: sim backend: %s\n", err);
                return 2;
            }
            mca_arm_feedback_t f0;
            mca_arm_read(sim, &f0); /* initial state */
        }
        for (k = 0; k < cycles; k++) {
            double t = (double)k * 1e-3;
            cmd.frame_id = (uint32_t)(k + 1);
            for (int j = 0; j < g_n; j++) {
                cmd.velocity[j] =
                    quant(amp * (1.0 - 0.1 * j) * sin(2.0 * M_PI * freq * (1.0 + 0.2 * j) * t), 1e-6);
            }
            int64_t t0 = now_ns();
            if ((rc = mca_arm_write(arm, &cmd)) != MCA_OK) {
                fprintf(stderr, "mca-can-ctl: write %ld: %s\n", k, mca_strerror(rc));
                return 4;
            }
            rec_t r = {.rx = 0, .cycle = (uint32_t)k, .frame_id = cmd.frame_id};
            memcpy(r.flags, cmd.flags, sizeof(r.flags));
            memcpy(r.a, cmd.velocity, sizeof(r.a));
            log_push(&r);
            int got = 0;
            int64_t t_end = t0 + 2000000000LL;
            while (!got && now_ns() < t_end) {
                struct pollfd p = {.fd = fd, .events = POLLIN};
                poll(&p, 1, 100);
                while ((rc = mca_arm_read(arm, &fb)) != MCA_EAGAIN) {
                    if ((rc == MCA_OK || rc == MCA_EFAULT) && fb.frame_id == cmd.frame_id) {
                        got = 1;
                        break;
                    }
                }
            }
            if (!got) {
                fprintf(stderr, "mca-can-ctl: no feedback for frame %u within 2 s\n", cmd.frame_id);
                return 4;
            }
            rtt[k] = fb.stamp_ns - t0;
            rtt_min = rtt[k] < rtt_min ? rtt[k] : rtt_min;
            /* Did the measured feedback carry the kernel's receive stamp? Every feedback frame applied
             * since the last sample is counted by the link (one per command here). */
            mca_arm_stats_t kst;
            mca_arm_stats(arm, &kst);
            if (kst.rx_stamp_user == lst.rx_stamp_user && kst.rx_stamp_kernel > lst.rx_stamp_kernel) {
                kstamped++;
            } else {
                ustamped++;
            }
            lst = kst;
            rx_new++;
            r = (rec_t){.rx = 1,
                        .cycle = (uint32_t)k,
                        .frame_id = fb.frame_id,
                        .state = fb.state,
                        .fault = fb.fault_code};
            memcpy(r.a, fb.position, sizeof(r.a));
            memcpy(r.b, fb.velocity, sizeof(r.b));
            log_push(&r);
            if (sim) {
                mca_arm_feedback_t sf;
                mca_arm_write(sim, &cmd);
                mca_arm_read(sim, &sf);
                for (int j = 0; j < g_n; j++) {
                    maxdq = fmax(maxdq, fabs(sf.position[j] - fb.position[j]));
                    maxdv = fmax(maxdv, fabs(sf.velocity[j] - fb.velocity[j]));
                }
                state_mismatch += sf.state != fb.state;
            }
        }
        qsort(rtt, (size_t)cycles, sizeof(*rtt), cmp_i64);
        printf("rtt_us p50=%.1f p99=%.1f max=%.1f n=%ld min=%.1f kernel_stamped=%" PRIu64
               " user_stamped=%" PRIu64 "\n",
               rtt[cycles / 2] / 1e3, rtt[(cycles * 99) / 100] / 1e3, rtt[cycles - 1] / 1e3, cycles,
               rtt_min / 1e3, kstamped, ustamped);
        if (sim) {
            /* Resolution: feedback position 1e-6 rad (half a step when rounding), velocity 1e-4 rad/s. */
            int same = maxdq <= 0.5e-6 + 1e-12 && maxdv <= 0.5e-4 + 1e-12 && state_mismatch == 0;
            printf("compare max|dq|=%.3g rad max|dv|=%.3g rad/s state_mismatch=%ld -> %s\n", maxdq, maxdv,
                   state_mismatch, same ? "SAME" : "DIFFERENT");
            exit_code = same ? 0 : 5;
            mca_arm_close(sim);
        }
    }
    mca_arm_stats_t st;
    mca_arm_stats(arm, &st);
    FILE *sf = statp ? fopen(statp, "w") : NULL;
    FILE *outs[2] = {stderr, sf};
    for (int i = 0; i < 2; i++) {
        if (!outs[i]) {
            continue;
        }
        fprintf(outs[i],
                "cycles=%ld commands_sent=%" PRIu64 " feedback_received=%" PRIu64 " rx_bad_length=%" PRIu64
                " rx_bad_counter=%" PRIu64 " rx_unknown_id=%" PRIu64 " bus_errors=%" PRIu64
                " bus_off=%d eio=%" PRIu64 " fb_new=%" PRIu64
                " last_fb_cycle=%ld lost_at=%ld overruns=%" PRIu64 " fault_clears=%" PRIu64
                " bus_off_events=%" PRIu64 " link_fault=%u rx_stamp_kernel=%" PRIu64 " rx_stamp_user=%" PRIu64
                "\n",
                k, st.commands_sent, st.feedback_received, st.rx_bad_length, st.rx_bad_counter,
                st.rx_unknown_id, st.bus_errors, st.bus_off, eio, rx_new, last_fb_cycle, lost_at, overruns,
                clears, st.bus_off_events, (unsigned)st.link_fault, st.rx_stamp_kernel, st.rx_stamp_user);
    }
    if (sf) {
        fclose(sf);
    }
    if (lost_at >= 0) {
        fprintf(stderr,
                "mca-can-ctl: LOST feedback: last at cycle %ld, detected at cycle %ld; commanding stopped\n",
                last_fb_cycle, lost_at);
    }
    if (logp) {
        write_log(logp);
    }
    mca_arm_close(arm);
    free(g_log);
    free(rtt);
    return exit_code;
}
