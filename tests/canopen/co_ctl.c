/* SPDX-License-Identifier: MIT */
/* mca-co-ctl: test controller for the CANopen suite. Runs the CANopen master (mca/canopen.h) on one bus:
 * NMT reset + boot-ups, SDO/PDO configuration, NMT start, then a clock_nanosleep loop at --period-us:
 * CiA 402 enable, --cycles of sinusoidal joint velocities (CSV) or the matching positions (CSP), then a
 * quick stop held for --stop-cycles. Prints key=value lines (stdout) and exits:
 *   0 done (or the --expect-fault fault was latched and every drive then stopped), 2 bad arguments,
 *   3 a fault (the line "fault=..." names node and cause), 4 not enabled in time, 5 trajectory mismatch,
 *   6 not stopped after the quick stop.
 * --compare-robot URDF: the same velocities also drive the in-process simulated arm (mca/sim_arm.h, the
 * sim backend's model, all joints in one arm) from the SYNC where motion starts; "r <sync> q0..qn-1" lines
 * go to --log, to be joined with mca-drivesim's --log by the check. --read-name: SDO upload of 0x1008
 * (segmented) from every node. SIGTERM during motion: quick stop, wait for every drive to stand, exit 0
 * ("sigterm=1"). */
#include <getopt.h>
#include <inttypes.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mca/canopen.h"
#include "mca/chain.h"
#include "mca/err.h"
#include "mca/sim_arm.h"
#include "mca/urdf.h"

static volatile sig_atomic_t g_term;

static void on_term(int sig) {
    (void)sig;
    g_term = 1;
}

static int64_t ts_ns(const struct timespec *t) {
    return (int64_t)t->tv_sec * 1000000000 + t->tv_nsec;
}

static void add_ns(struct timespec *t, int64_t ns) {
    t->tv_nsec += (long)ns;
    while (t->tv_nsec >= 1000000000) {
        t->tv_nsec -= 1000000000;
        t->tv_sec++;
    }
}

static void usage(void) {
    fprintf(
        stderr,
        "usage: mca-co-ctl --iface IF [--nodes 6] [--first-node 1] [--mode csv|csp] [--period-us 4000]\n"
        "                  [--cycles 500] [--amp 0.3] [--freq 0.5] [--stop-cycles 150]\n"
        "                  [--enable-cycles 300] [--hb-ms 100] [--hb-timeout-ms 350] [--pdo-timeout 5]\n"
        "                  [--sdo-timeout-ms 200] [--boot-timeout-ms 3000] [--read-name]\n"
        "                  [--compare-robot URDF --q0 a,b,..] [--acc-limit A --dec-limit D] [--log FILE]\n"
        "                  [--expect-fault NAME]\n");
}

int main(int argc, char **argv) {
    static mca_co_master_t m;
    mca_co_master_config_t cfg;
    const char *iface = NULL, *mode = "csv", *robot = NULL, *q0s = NULL, *logp = NULL, *expect = NULL;
    long nodes = 6, first = 1, period = 4000, cycles = 500, stop_cycles = 150, enable_cycles = 300;
    long hb = 100, hb_tmo = 350, pdo_tmo = 5, sdo_tmo = 200, boot_tmo = 3000;
    double amp = 0.3, freq = 0.5, acc = 0, dec = 0;
    int read_name = 0;
    static const struct option opts[] = {
        {"iface", required_argument, 0, 'i'},
        {"nodes", required_argument, 0, 'n'},
        {"first-node", required_argument, 0, 'f'},
        {"mode", required_argument, 0, 'm'},
        {"period-us", required_argument, 0, 'p'},
        {"cycles", required_argument, 0, 'c'},
        {"amp", required_argument, 0, 'a'},
        {"freq", required_argument, 0, 'F'},
        {"stop-cycles", required_argument, 0, 's'},
        {"enable-cycles", required_argument, 0, 'e'},
        {"hb-ms", required_argument, 0, 'h'},
        {"hb-timeout-ms", required_argument, 0, 'H'},
        {"pdo-timeout", required_argument, 0, 'P'},
        {"sdo-timeout-ms", required_argument, 0, 'S'},
        {"boot-timeout-ms", required_argument, 0, 'B'},
        {"read-name", no_argument, 0, 'N'},
        {"compare-robot", required_argument, 0, 'r'},
        {"q0", required_argument, 0, 'q'},
        {"acc-limit", required_argument, 0, 'A'},
        {"dec-limit", required_argument, 0, 'D'},
        {"log", required_argument, 0, 'l'},
        {"expect-fault", required_argument, 0, 'x'},
        {0, 0, 0, 0},
    };
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        char *end = NULL;
        switch (o) {
        case 'i':
            iface = optarg;
            break;
        case 'n':
            nodes = strtol(optarg, &end, 10);
            break;
        case 'f':
            first = strtol(optarg, &end, 10);
            break;
        case 'm':
            mode = optarg;
            break;
        case 'p':
            period = strtol(optarg, &end, 10);
            break;
        case 'c':
            cycles = strtol(optarg, &end, 10);
            break;
        case 'a':
            amp = strtod(optarg, &end);
            break;
        case 'F':
            freq = strtod(optarg, &end);
            break;
        case 's':
            stop_cycles = strtol(optarg, &end, 10);
            break;
        case 'e':
            enable_cycles = strtol(optarg, &end, 10);
            break;
        case 'h':
            hb = strtol(optarg, &end, 10);
            break;
        case 'H':
            hb_tmo = strtol(optarg, &end, 10);
            break;
        case 'P':
            pdo_tmo = strtol(optarg, &end, 10);
            break;
        case 'S':
            sdo_tmo = strtol(optarg, &end, 10);
            break;
        case 'B':
            boot_tmo = strtol(optarg, &end, 10);
            break;
        case 'N':
            read_name = 1;
            break;
        case 'r':
            robot = optarg;
            break;
        case 'q':
            q0s = optarg;
            break;
        case 'A':
            acc = strtod(optarg, &end);
            break;
        case 'D':
            dec = strtod(optarg, &end);
            break;
        case 'l':
            logp = optarg;
            break;
        case 'x':
            expect = optarg;
            break;
        default:
            usage();
            return 2;
        }
        if (end && *end) {
            fprintf(stderr, "mca-co-ctl: bad number '%s'\n", optarg);
            return 2;
        }
    }
    const int csp = strcmp(mode, "csp") == 0;
    if (optind != argc || !iface || nodes < 1 || nodes > MCA_CO_MAX_NODES || first < 1 ||
        first + nodes > 128 || (!csp && strcmp(mode, "csv") != 0) || period < 100 || cycles < 0 ||
        (robot && csp)) {
        usage();
        return 2;
    }
    mca_co_master_config_default(&cfg, (int)nodes, (uint8_t)first);
    snprintf(cfg.iface, sizeof(cfg.iface), "%s", iface);
    cfg.mode = csp ? MCA_CO402_MODE_CSP : MCA_CO402_MODE_CSV;
    cfg.sync_period_us = (uint32_t)period;
    cfg.hb_period_ms = (uint16_t)hb;
    cfg.hb_timeout_ms = (uint16_t)hb_tmo;
    cfg.pdo_timeout_cycles = (int)pdo_tmo;
    cfg.sdo_timeout_ms = (int)sdo_tmo;
    cfg.boot_timeout_ms = (int)boot_tmo;

    /* reference: the sim backend's arm model with every joint in one arm */
    static mca_sim_arm_t ref;
    const double dt = period * 1e-6;
    if (robot) {
        static mca_chain_t chain;
        mca_sim_arm_config_t ac;
        char err[256] = "";
        if (mca_chain_load_urdf(&chain, robot, NULL, err, sizeof(err)) != MCA_OK) {
            fprintf(stderr, "mca-co-ctl: --compare-robot %s: %s\n", robot, err);
            return 2;
        }
        mca_sim_arm_config_from_chain(&ac, &chain);
        if (ac.n != nodes) {
            fprintf(stderr, "mca-co-ctl: %s has %d joints, --nodes %ld\n", robot, ac.n, nodes);
            return 2;
        }
        const char *p = q0s;
        for (int j = 0; p && j < ac.n; j++) {
            char *end = NULL;
            ac.q0[j] = strtod(p, &end);
            p = *end == ',' ? end + 1 : NULL;
        }
        for (int j = 0; j < ac.n; j++) {
            ac.acc_limit[j] = acc > 0 ? acc : ac.acc_limit[j];
            ac.dec_limit[j] = dec > 0 ? dec : ac.dec_limit[j];
        }
        ac.watchdog_cycles = 3;
        ac.dt = dt;
        if (mca_sim_arm_init(&ref, &ac, err, sizeof(err)) != MCA_OK) {
            fprintf(stderr, "mca-co-ctl: reference arm: %s\n", err);
            return 2;
        }
    }
    FILE *logf = logp ? fopen(logp, "w") : NULL;
    if (logp && !logf) {
        fprintf(stderr, "mca-co-ctl: cannot write %s\n", logp);
        return 2;
    }

    int rc = mca_co_master_open(&m, &cfg);
    if (rc != MCA_OK) {
        printf("open=%s err=%s\n", mca_strerror(rc), m.err);
        return 3;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof(sa));
    sa.sa_handler = on_term;
    sigaction(SIGTERM, &sa, NULL);
    char desc[192];
    if (read_name) {
        /* before the start: NMT pre-operational after a reset (the start resets again) */
        for (int j = 0; j < cfg.n; j++) {
            char name[MCA_CO_SDO_MAX + 1] = "";
            size_t len = 0;
            uint32_t ab = 0;
            rc = mca_co_sdo_upload(&m, cfg.drive[j].node, 0x1008, 0, name, MCA_CO_SDO_MAX, &len, &ab);
            if (rc != MCA_OK) {
                printf("read_name_fail=node%u err=%s\n", cfg.drive[j].node, m.err);
                return 3;
            }
            name[len] = 0;
            printf("name%u=%s\n", cfg.drive[j].node, name);
        }
    }
    rc = mca_co_master_start(&m);
    if (rc != MCA_OK) {
        mca_co_fault_describe(&m.fault, desc, sizeof(desc));
        printf("start=%s\nerr=%s\nfault=%s\nfault_kind=%s\n", mca_strerror(rc), m.err, desc,
               mca_co_fault_name(m.fault.kind));
        mca_co_master_close(&m);
        return expect && strcmp(expect, mca_co_fault_name(m.fault.kind)) == 0 ? 0 : 3;
    }
    printf("started=1 tx=%" PRIu64 "\n", m.tx_frames);
    mca_co_master_set_goal(&m, MCA_CO402_GOAL_ENABLED);
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    long k = 0, enabled_at = -1, motion0 = -1, stop0 = -1, fault_at = -1, late = 0;
    int exit_rc = 0, stopped = 0, ref_started = 0;
    double maxv_end = 0;
    const double w = 2 * M_PI * freq;
    double p0[MCA_CO_MAX_NODES] = {0};
    for (;; k++) {
        add_ns(&next, (int64_t)period * 1000);
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (ts_ns(&now) - ts_ns(&next) > (int64_t)period * 1000) {
            late++;
            next = now; /* a late cycle re-anchors the clock: never a burst of SYNCs to catch up */
        }
        /* phase: enabling -> motion -> stopping */
        if (enabled_at < 0) {
            (void)mca_co_master_poll(&m, ts_ns(&now));
            if (mca_co_master_all_enabled(&m)) {
                enabled_at = k;
                motion0 = k;
                for (int j = 0; j < cfg.n; j++) {
                    mca_co_master_joint(&m, j, &p0[j], NULL, NULL);
                }
                printf("enabled_after_cycles=%ld\n", k);
            } else if (k > enable_cycles) {
                printf("enabled=0 after %ld cycles:", k);
                for (int j = 0; j < cfg.n; j++) {
                    printf(" node%u=%s", cfg.drive[j].node,
                           mca_co402_state_name(mca_co402_state(m.d[j].statusword)));
                }
                printf("\n");
                exit_rc = 4;
                break;
            }
        }
        const long t = motion0 >= 0 ? k - motion0 : -1;
        if (stop0 < 0 && (g_term || (t >= cycles) || fault_at >= 0)) {
            stop0 = k;
            mca_co_master_set_goal(&m, MCA_CO402_GOAL_QUICK_STOP);
            if (g_term) {
                printf("sigterm=1 at_motion_cycle=%ld\n", t);
            }
        }
        double v[MCA_CO_MAX_NODES] = {0};
        for (int j = 0; j < cfg.n; j++) {
            if (t >= 0 && stop0 < 0) {
                const double ph = 0.7 * j;
                v[j] = amp * (sin(w * t * dt + ph) - sin(ph)); /* 0 at t = 0 */
                if (csp) {
                    const double pos =
                        p0[j] + amp * ((cos(ph) - cos(w * t * dt + ph)) / w - sin(ph) * t * dt);
                    mca_co_master_set_target(&m, j, pos);
                } else {
                    mca_co_master_set_target(&m, j, v[j]);
                }
            } else if (!csp) {
                mca_co_master_set_target(&m, j, 0.0);
            }
        }
        if (robot && t >= 0) {
            /* the drives apply this tick's RPDO at the SYNC sent now: number m.syncs + 1 */
            mca_arm_command_t c;
            memset(&c, 0, sizeof(c));
            c.n = cfg.n;
            c.frame_id = (uint32_t)(k + 1);
            for (int j = 0; j < cfg.n; j++) {
                c.flags[j] = stop0 < 0 ? (MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE) : 0;
                c.velocity[j] = v[j];
            }
            mca_arm_feedback_t fb;
            if (!ref_started) {
                /* the drives are SERVOING with v = 0 since they were enabled: so is the reference */
                mca_arm_command_t z = c;
                memset(z.velocity, 0, sizeof(z.velocity));
                z.frame_id = (uint32_t)k;
                for (int j = 0; j < cfg.n; j++) {
                    z.flags[j] = MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE;
                }
                mca_sim_arm_cycle(&ref, &z, dt, &fb);
                ref_started = 1;
            }
            mca_sim_arm_cycle(&ref, &c, dt, &fb);
            if (logf) {
                fprintf(logf, "r %" PRIu64, m.syncs + 1);
                for (int j = 0; j < cfg.n; j++) {
                    fprintf(logf, " %.9f", ref.q[j]);
                }
                fprintf(logf, "\n");
            }
        }
        rc = mca_co_master_tick(&m, ts_ns(&now));
        if (rc == MCA_EFAULT && fault_at < 0) {
            fault_at = k;
            mca_co_fault_describe(&m.fault, desc, sizeof(desc));
            printf("fault=%s\nfault_kind=%s\nfault_cycle=%ld\n", desc, mca_co_fault_name(m.fault.kind), k);
        } else if (rc == MCA_EIO) {
            printf("tick=EIO at cycle %ld\n", k);
            exit_rc = 3;
            break;
        }
        if (stop0 >= 0) {
            int still = 1;
            maxv_end = 0;
            for (int j = 0; j < cfg.n; j++) {
                double vel = 0;
                if (m.fault.kind == MCA_CO_FAULT_PDO && m.fault.node == cfg.drive[j].node) {
                    continue; /* its feedback is what stopped coming: mca-drivesim's log tells */
                }
                mca_co_master_joint(&m, j, NULL, &vel, NULL);
                maxv_end = fabs(vel) > maxv_end ? fabs(vel) : maxv_end;
                still &= fabs(vel) < 1e-3;
            }
            if (k - stop0 >= stop_cycles) {
                stopped = still;
                break;
            }
        }
    }
    printf("cycles=%ld syncs=%" PRIu64 " tx=%" PRIu64 " tx_again=%" PRIu64 " rx=%" PRIu64
           " late=%ld faults=%" PRIu64 "\n",
           k, m.syncs, m.tx_frames, m.tx_again, m.rx_frames, late, m.faults);
    for (int j = 0; j < cfg.n; j++) {
        double q = 0, vel = 0;
        mca_co_master_joint(&m, j, &q, &vel, NULL);
        printf("node%u state=%s q=%.6f v=%.6f tpdo1=%" PRIu64 " emcy=%" PRIu64 " emcy_code=0x%04X\n",
               cfg.drive[j].node, mca_co402_state_name(mca_co402_state(m.d[j].statusword)), q, vel,
               m.d[j].tpdo1_rx, m.d[j].emcy_rx, m.d[j].emcy.code);
    }
    printf("stopped=%d max_abs_v_end=%.6f\n", stopped, maxv_end);
    mca_co_master_close(&m);
    if (logf) {
        fclose(logf);
    }
    if (exit_rc) {
        return exit_rc;
    }
    if (fault_at >= 0) {
        const int want = expect && strcmp(expect, mca_co_fault_name(m.fault.kind)) == 0;
        return want && stopped ? 0 : want ? 6 : 3;
    }
    if (expect) {
        printf("expected fault %s not seen\n", expect);
        return 3;
    }
    return stopped ? 0 : 6;
}
