/* SPDX-License-Identifier: MIT */
/* mcad: the controller daemon. Loads a cell, opens the arms and DDS, runs the 1 kHz loop in a real-time
 * thread and supervises it from the main thread (signals, systemd notification and watchdog, log and CSV
 * draining). See docs/daemon.md.
 * Built twice: mcad (production: no test hooks; SIGUSR1 prints a status line and changes nothing) and
 * mcad-test (MCA_TEST_HOOKS, tests only: SIGUSR1 stalls the loop, the cell's debug_* keys; exit 4 when
 * it ended stalled). */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <systemd/sd-daemon.h>
#include <time.h>
#include <unistd.h>

#include "mca/cell.h"
#include "mca/daemon.h"
#include "mca/err.h"
#ifdef MCA_TEST_HOOKS
#include "mca/daemon_test.h"
#include "mca/scenario.h"
#define MCAD_NAME "mcad-test"
#else
#define MCAD_NAME "mcad"
#endif

static void usage(FILE *f) {
    fprintf(
        f, "usage: " MCAD_NAME " [options] CELL.yaml\n"
           "  --check            load and check the cell file, print what it configures, exit\n"
           "  --csv FILE         write one CSV row per tick (from a non-real-time thread)\n"
           "  --record FILE      record what the controller read each tick, bit for bit (the replay backend\n"
           "                     plays it again; docs/daemon.md)\n"
           "  --stop-after SEC   brake and stop after SEC seconds of running (overrides the cell)\n"
           "  --no-dds           do not publish on DDS\n"
           "  --no-rt            no SCHED_FIFO / mlockall / cpu_dma_latency (debugging, sanitizers)\n"
           "  --clear-faults     clear a FAULT an arm reports at start-up (latched from an earlier run;\n"
           "                     logged); without it mcad refuses to start (exit 1)\n"
           "  --histogram FILE   at exit, write the loop's wake-up latency histogram to FILE, as\n"
           "                     cyclictest -h does (bench/rt compares the two)\n"
           "  --dds-ab N         DDS cost benchmark: publish only in every other block of N ticks and\n"
           "                     print the whole tick's time with publishing off and on (one run)\n"
           "  -h, --help\n"
#ifdef MCA_TEST_HOOKS
           "Signals: SIGTERM/SIGINT brake to zero and exit; SIGUSR1 stalls the loop (test hook).\n"
           "Exit status: 0 stopped cleanly, 1 start-up failed, 2 bad cell file or usage, 3 ended in fault,\n"
           "4 ended while stalled.\n"
           "This is the test build (test hooks: debug_* cell keys, SIGUSR1); never run it with real arms.\n"
#else
           "Signals: SIGTERM/SIGINT brake to zero and exit; SIGUSR1 prints a status line (nothing else);\n"
           "SIGHUP is ignored.\n"
           "Exit status: 0 stopped cleanly, 1 start-up failed, 2 bad cell file or usage, 3 ended in fault.\n"
#endif
    );
}

/* The daemon library's lines (mca/log.h) as mcad logs: the journald/syslog priority prefix, its name. */
static void log_line(void *arg, int level, const char *text) {
    fprintf((FILE *)arg, "<%d>mcad: %s\n", level, text);
}

static double mono_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void print_cell(const mca_cell_t *c) {
    char task[96];
    if (c->stream.enabled) {
        snprintf(task, sizeof task, "'%s' streamed (until stopped)", c->scn.name);
    } else {
        snprintf(task, sizeof task, "'%s' %.3g s", c->scn.name, c->scn.duration);
    }
    printf("cell %s (%s): scheme %s, task %s, d1 %.3g m, d2 %.3g m\n", c->name, c->source,
           mca_scheme_name(c->scheme), task, c->scn.params.d1, c->scn.params.d2);
    for (int a = 0; a < c->scn.n_arms; a++) {
        const mca_scenario_arm_t *sa = &c->scn.arm[a];
        printf("  arm %d '%s': %s, %d joints, base [%g %g %g], backend %s", a, sa->name, sa->urdf, sa->n_q0,
               sa->base_xyz[0], sa->base_xyz[1], sa->base_xyz[2], mca_cell_backend_name(c->arm[a].backend));
        char where[128];
        mca_cell_backend_describe(&c->arm[a], sa->n_q0, where, sizeof where);
        printf("%s", where);
        if (c->stream.enabled) {
            printf(", follows /%s/%s/%s", c->dds.ros2.ns, sa->name,
                   c->arm[a].stream == MCA_CELL_STREAM_POSE ? "target_pose" : "target_twist");
        }
        printf("\n");
    }
    for (int k = 0; k < c->scn.n_bodies; k++) {
        const mca_scenario_body_t *sb = &c->scn.body[k];
        printf("  body %d '%s': %s, clearance %.3g m%s, allowed:", k, sb->fb.name,
               mca_body_kind_name(sb->fb.body.kind), sb->clearance >= 0.0 ? sb->clearance : c->scn.params.d1,
               sb->clearance >= 0.0 ? "" : " (d1)");
        for (int j = 0; j < sb->n_allow; j++) {
            printf("%s %s", j ? "," : "", sb->allow[j]);
        }
        printf("%s\n", sb->n_allow ? "" : " none");
    }
    printf(
        "  rt: period %lld us, priority %d, cpu %d, overrun limit %d, lost feedback %d cycles, PDNN budget "
        "%lld us\n",
        (long long)(c->rt.period_ns / 1000), c->rt.priority, c->rt.cpu, c->rt.overrun_limit,
        c->rt.lost_feedback_cycles, (long long)(c->rt.pdnn_budget_ns / 1000));
    printf("  dds: %s, domain %u, config %s, publish every %u ticks\n", c->dds.enabled ? "on" : "off",
           c->dds.domain, c->dds.config[0] ? c->dds.config : "(default)", c->dds.publish_divisor);
    const mca_cell_ros2_t *r = &c->dds.ros2;
    if (c->dds.enabled && r->enabled) {
        printf("  ros2: namespace /%s, world frame %s,%s%s%s%s%s\n", r->ns, r->world_frame,
               r->joint_states ? " joint_states" : "", r->robot_description ? " robot_description" : "",
               r->tf_static ? " tf_static" : "", r->markers ? " distance_markers" : "",
               r->diagnostics ? " diagnostics" : "");
    }
    if (c->tracks.enabled) {
        static mca_controller_config_t cfg;
        char err[256];
        const mca_ssm_params_t *p = &c->tracks.ssm;
        printf("  streamed bodies: /%s/%s (up to %d), grow after %g s at %g m/s (%g m/s beyond %g m), lost "
               "after "
               "%g s\n",
               c->dds.ros2.ns, c->tracks.topic, c->tracks.max_bodies, p->max_age, p->approach_near,
               p->approach_far, p->approach_switch, p->lost_after);
        if (mca_cell_controller_config(c, &cfg, err, sizeof err) == MCA_OK) {
            double v_r, t_s;
            mca_controller_ssm_arms(&cfg, &v_r, &t_s);
            const double v_h[2] = {0.0, p->approach_near};
            for (int k = 0; k < 2; k++) {
                mca_ssm_terms_t t;
                mca_ssm_terms(p, v_h[k], v_r, t_s, &t);
                printf(
                    "    S_p %.3f m for a body %s: S_h %.3f + S_r %.3f + S_s %.3f + C %.3f + Z_d %.3f + Z_r "
                    "%.3f (v_r %.2f m/s, T_r %.3f s, T_s %.3f s)\n",
                    t.s_p, k ? "approaching at the approach speed (stale)" : "at rest", t.s_h, t.s_r, t.s_s,
                    t.c, t.z_d, t.z_r, v_r, p->reaction_time + p->latency, t_s);
            }
        }
    }
    if (c->stream.enabled) {
        printf("  stream: max speed %g m/s, pose gain %g 1/s, hold after %g s, brake after %g s, workspace "
               "[%g %g %g] .. [%g %g %g]\n",
               c->stream.max_speed, c->stream.pose_gain, c->stream.hold_after, c->stream.brake_after,
               c->stream.box_lo[0], c->stream.box_lo[1], c->stream.box_lo[2], c->stream.box_hi[0],
               c->stream.box_hi[1], c->stream.box_hi[2]);
    }
}

/* start-up failed: no half-written result file */
static void drop_histogram(FILE *hist, const char *path) {
    if (hist) {
        fclose(hist);
        unlink(path);
    }
}

int main(int argc, char **argv) {
    static const struct option longopts[] = {
        {"check", no_argument, NULL, 'k'},
        {"csv", required_argument, NULL, 'c'},
        {"record", required_argument, NULL, 'r'},
        {"stop-after", required_argument, NULL, 's'},
        {"no-dds", no_argument, NULL, 'D'},
        {"no-rt", no_argument, NULL, 'R'},
        {"clear-faults", no_argument, NULL, 'F'},
        {"dds-ab", required_argument, NULL, 'A'},
        {"histogram", required_argument, NULL, 'H'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    mca_daemon_opts_t opts = {.log = log_line, .log_arg = stderr};
    int check = 0;
    const char *hist_path = NULL;
    for (;;) {
        const int o = getopt_long(argc, argv, "h", longopts, NULL);
        if (o < 0) {
            break;
        }
        switch (o) {
        case 'k':
            check = 1;
            break;
        case 'c':
            opts.csv_path = optarg;
            break;
        case 'r':
            opts.record_path = optarg;
            break;
        case 's': {
            char *end;
            opts.stop_after = strtod(optarg, &end);
            if (*end || !(opts.stop_after > 0) || !isfinite(opts.stop_after)) {
                fprintf(stderr, "<3>mcad: --stop-after: need a positive number of seconds, got '%s'\n",
                        optarg);
                return 2;
            }
            break;
        }
        case 'D':
            opts.no_dds = 1;
            break;
        case 'R':
            opts.no_rt = 1;
            break;
        case 'F':
            opts.clear_faults = 1;
            break;
        case 'A': {
            char *end;
            const unsigned long b = strtoul(optarg, &end, 10);
            if (*end || b == 0 || b > 1000000) {
                fprintf(stderr, "<3>mcad: --dds-ab: need a block length of 1..1000000 ticks, got '%s'\n",
                        optarg);
                return 2;
            }
            opts.dds_ab_block = (uint32_t)b;
            break;
        }
        case 'H':
            hist_path = optarg;
            break;
        case 'h':
            usage(stdout);
            return 0;
        default:
            usage(stderr);
            return 2;
        }
    }
    if (optind != argc - 1) {
        usage(stderr);
        return 2;
    }
    const char *cell_path = argv[optind];
    setvbuf(stderr, NULL, _IOLBF, 0);

    /* Signals are taken synchronously by this (supervising) thread; block them before any thread
     * (DDS, the loop) exists so they all inherit the mask. */
    sigset_t sigs;
    sigemptyset(&sigs);
    sigaddset(&sigs, SIGTERM);
    sigaddset(&sigs, SIGINT);
    sigaddset(&sigs, SIGUSR1);
    sigaddset(&sigs, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &sigs, NULL);

    /* Started with SCHED_FIFO for the whole process (systemd CPUSchedulingPolicy=fifo)? Only the loop
     * thread should be real-time: put this thread (and so the DDS and supervisor threads created from it)
     * back to SCHED_OTHER; the loop sets its own SCHED_FIFO priority (needs LimitRTPRIO or root). */
    const int inherited_policy = sched_getscheduler(0);
    if (inherited_policy == SCHED_FIFO || inherited_policy == SCHED_RR) {
        const struct sched_param sp0 = {.sched_priority = 0};
        if (sched_setscheduler(0, SCHED_OTHER, &sp0) == 0) {
            fprintf(stderr, "<6>mcad: started real-time: non-loop threads reset to SCHED_OTHER\n");
        }
    }

    /* Threads created from here on (DDS; the loop sets its own) get this default stack; with mlockall every
     * byte of it is resident: 1 MB instead of glibc's 8 MB (RLIMIT_STACK) per thread is plenty. */
    pthread_attr_t dattr;
    if (pthread_attr_init(&dattr) == 0) {
        if (pthread_attr_setstacksize(&dattr, 1u << 20) == 0) {
            pthread_setattr_default_np(&dattr);
        }
        pthread_attr_destroy(&dattr);
    }

    mca_cell_t *cell = calloc(1, sizeof *cell);
    if (!cell) {
        return 1;
    }
    char err[1024];
    int rc = mca_cell_load(cell_path, cell, err, sizeof err);
    if (rc != MCA_OK) {
        fprintf(stderr, "<3>mcad: bad cell file: %s\n", err);
        sd_notifyf(0, "STATUS=bad cell file: %s", err);
        free(cell);
        return 2;
    }
    if (check) {
        print_cell(cell);
        free(cell);
        return 0;
    }
    /* opened before anything starts: a path that cannot be written is a usage error, not a lost result */
    FILE *hist = NULL;
    if (hist_path && !(hist = fopen(hist_path, "w"))) {
        fprintf(stderr, "<3>mcad: --histogram: cannot open '%s' for writing: %s\n", hist_path,
                strerror(errno));
        free(cell);
        return 2;
    }
    fprintf(stderr, "<6>mcad: cell '%s' (%s): %d arms, task '%s'\n", cell->name, cell_path, cell->scn.n_arms,
            cell->scn.name);
    sd_notify(0, "STATUS=opening arms and DDS");

    mca_daemon_t *d = NULL;
    rc = mca_daemon_open(&d, cell, &opts, err, sizeof err);
    if (rc != MCA_OK) {
        fprintf(stderr, "<3>mcad: start-up failed: %s\n", err);
        sd_notifyf(0, "STATUS=start-up failed: %s", err);
        drop_histogram(hist, hist_path);
        free(cell);
        return 1;
    }
    uint64_t wd_usec = 0;
    const int wd = sd_watchdog_enabled(0, &wd_usec) > 0 && wd_usec > 0;
    rc = mca_daemon_start(d);
    if (rc != MCA_OK) {
        mca_daemon_close(d);
        drop_histogram(hist, hist_path);
        free(cell);
        return 1;
    }
    sd_notifyf(0, "READY=1\nSTATUS=running cell %s", cell->name);
    fprintf(stderr, "<6>mcad: ready%s\n", wd ? " (systemd watchdog on)" : "");

    /* Supervision: the watchdog is pinged only while the loop's tick counter advances. */
    const double wd_interval = wd ? (double)wd_usec * 1e-6 / 4.0 : 0.0;
    double next_wd = mono_s(), next_status = mono_s() + 1.0;
    uint64_t last_ticks = mca_daemon_ticks(d);
    int stopping = 0;
#ifdef MCA_TEST_HOOKS
    int stalled = 0;
    fprintf(stderr,
            "<4>mcad: test build (mcad-test): test hooks on (SIGUSR1 stalls the loop, debug_* keys)\n");
#endif
    while (!mca_daemon_finished(d)) {
        const struct timespec to = {0, 5 * 1000000L};
        const int sig = sigtimedwait(&sigs, NULL, &to);
        if (sig == SIGTERM || sig == SIGINT) {
            if (!stopping) {
                fprintf(stderr, "<5>mcad: %s: braking to zero and stopping\n",
                        sig == SIGTERM ? "SIGTERM" : "SIGINT");
                sd_notify(0, "STOPPING=1\nSTATUS=braking to zero");
                stopping = 1;
            }
            mca_daemon_request_stop(d);
        } else if (sig == SIGUSR1) {
#ifdef MCA_TEST_HOOKS
            fprintf(stderr, "<4>mcad: SIGUSR1: stalling the loop (test hook)\n");
            mca_daemon_request_stall(d);
            stalled = 1;
#else
            /* many setups send SIGUSR1 for log rotation. mcad logs to stderr (the journal) and
             * has no log file to re-open, so SIGUSR1 only prints where the loop is; the loop never sees it
             * (every signal is taken here, blocked in every other thread). */
            mca_daemon_summary_t s;
            mca_daemon_summary(d, &s);
            fprintf(
                stderr,
                "<6>mcad: SIGUSR1: state %s, ticks %llu, overruns %llu (skipped periods %llu) (status only: "
                "SIGUSR1 changes nothing)\n",
                mca_daemon_state_name(s.state), (unsigned long long)s.ticks, (unsigned long long)s.overruns,
                (unsigned long long)s.skipped_periods);
#endif
        }
        mca_daemon_service(d);
        const double now = mono_s();
        if (wd && now >= next_wd) {
            const uint64_t t = mca_daemon_ticks(d);
            if (t != last_ticks) {
                sd_notify(0, "WATCHDOG=1");
                last_ticks = t;
            } else if (!stopping) {
                fprintf(stderr,
                        "<3>mcad: the loop has not ticked for %.0f ms: withholding the watchdog ping\n",
                        wd_interval * 1e3);
            }
            next_wd = now + wd_interval;
        }
        if (now >= next_status) {
            mca_daemon_summary_t s;
            mca_daemon_summary(d, &s);
            sd_notifyf(0, "STATUS=%s: ticks %llu, overruns %llu, min distance %.4f m, deadlocks %d%s%s%s",
                       mca_daemon_state_name(s.state), (unsigned long long)s.ticks,
                       (unsigned long long)s.overruns, isfinite(s.min_distance) ? s.min_distance : -1.0,
                       s.deadlocks,
                       s.deadlock == MCA_DEADLOCK_BACK_OFF ? " (now: backing off)"
                       : s.deadlock == MCA_DEADLOCK_WAIT   ? " (now: waiting)"
                                                           : "",
                       s.fault ? ", fault: " : "", s.fault ? s.fault_text : "");
            next_status = now + 1.0;
        }
        (void)errno;
    }
    if (!stopping) {
        sd_notify(0, "STOPPING=1");
    }
    mca_daemon_join(d);
    mca_daemon_summary_t s;
    mca_daemon_summary(d, &s);
    mca_daemon_log_summary(&s, log_line, stderr);
    if (hist) {
        /* the span lets a reader take another tool's samples of exactly these milliseconds (bench/rt) */
        int64_t first, last;
        const mca_hist_t *h = mca_daemon_wake_histogram(d, &first, &last);
        char title[160];
        snprintf(title, sizeof title, "mcad wake-up latency: due from %lld to %lld ns of CLOCK_MONOTONIC",
                 (long long)first, (long long)last);
        if (mca_hist_write(h, title, hist) != MCA_OK) {
            fprintf(stderr, "<4>mcad: --histogram: cannot write '%s'\n", hist_path);
        }
        fclose(hist);
    }
    sd_notifyf(0, "STATUS=%s: ticks %llu, overruns %llu%s%s", mca_daemon_state_name(s.state),
               (unsigned long long)s.ticks, (unsigned long long)s.overruns, s.fault ? ", fault: " : "",
               s.fault ? s.fault_text : "");
    mca_daemon_close(d); /* publishes the final status on DDS */
    free(cell);
    if (s.fault) {
        return 3;
    }
#ifdef MCA_TEST_HOOKS
    if (stalled) {
        return 4;
    }
#endif
    if (s.state != MCA_DAEMON_STOPPED) {
        return 4;
    }
    return 0;
}
