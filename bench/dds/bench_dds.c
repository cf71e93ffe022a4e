/* SPDX-License-Identifier: MIT */
/* Benchmark: cost of DDS publishing to the 1 kHz loop. A synthetic tick (a fixed compute workload of
 * about --work-us microseconds, then the snapshot fill) runs at 1 kHz in alternating blocks with
 * publishing OFF (no push) and ON (mca_dds_bridge_push into the real bridge, whose publisher thread
 * writes the DDS samples). Prints the tick compute time for both, their ratio from this one run, the
 * cost of the push call itself, wake-up jitter, and the snapshots the bridge dropped.
 * Optionally a real subscriber process (--monitor PATH: mca-monitor) receives everything. */
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "mca/dds_bridge.h"
#include "mca/dds_qos.h" /* MCA_DDS_MAX_DOMAIN */
#include "mca/dds_synth.h"
#include "mca/err.h"
#include "mca/prog.h" /* mca_prog_parse_u64, mca_prog_ns_summary */

extern char **environ;

static int64_t now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

/* Deterministic floating-point work standing in for FK + distances + QP of one tick. */
static volatile double g_sink;
static void workload(long iters) {
    double x = 0.5, y = 0.25, acc = 0.0;
    for (long i = 0; i < iters; ++i) {
        x = x * 0.999999 + y * 1e-6;
        y = sqrt(y * y + 1e-9) * 0.9999995;
        acc += x * y;
    }
    g_sink = acc;
}

static void usage(FILE *f) {
    fprintf(f, "usage: bench_dds [--ticks N] [--work-us U] [--block B] [--domain D] [--config XML]\n"
               "                 [--monitor PATH] [--fifo PRIO]\n"
               "  --ticks N     ticks per mode (default 5000, i.e. 10 s in total at 1 kHz)\n"
               "  --work-us U   synthetic compute per tick in us (default 100)\n"
               "  --block B     alternate OFF/ON every B ticks (default 500)\n"
               "  --monitor P   run P (mca-monitor) as a subscriber during the benchmark\n"
               "  --fifo PRIO   run the loop SCHED_FIFO at PRIO (needs privileges)\n");
}

int main(int argc, char **argv) {
    long ticks = 5000, block = 500, fifo = 0;
    unsigned long long v = 0;
    double work_us = 100.0;
    const char *monitor = NULL;
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    cfg.domain_id = 7;
    static const struct option opts[] = {
        {"ticks", required_argument, NULL, 'n'},
        {"work-us", required_argument, NULL, 'w'},
        {"block", required_argument, NULL, 'b'},
        {"domain", required_argument, NULL, 'd'},
        {"config", required_argument, NULL, 'c'},
        {"monitor", required_argument, NULL, 'm'},
        {"fifo", required_argument, NULL, 'f'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (c) {
        case 'n':
            if (mca_prog_parse_u64("bench_dds", "--ticks", optarg, 1000000000ULL, &v) != 0) {
                return 2;
            }
            ticks = (long)v;
            break;
        case 'w':
            work_us = strtod(optarg, NULL);
            break;
        case 'b':
            if (mca_prog_parse_u64("bench_dds", "--block", optarg, 1000000000ULL, &v) != 0) {
                return 2;
            }
            block = (long)v;
            break;
        case 'd':
            if (mca_prog_parse_u64("bench_dds", "--domain", optarg, MCA_DDS_MAX_DOMAIN, &v) != 0) {
                return 2;
            }
            cfg.domain_id = (uint32_t)v;
            break;
        case 'c':
            cfg.config_path = optarg;
            break;
        case 'm':
            monitor = optarg;
            break;
        case 'f':
            if (mca_prog_parse_u64("bench_dds", "--fifo", optarg, 99, &v) != 0) {
                return 2;
            }
            fifo = (long)v;
            break;
        case 'h':
            usage(stdout);
            return 0;
        default:
            usage(stderr);
            return 2;
        }
    }
    if (ticks < 10 || block < 1 || !(work_us >= 0.0 && work_us < 900.0)) {
        fprintf(stderr, "bench_dds: need --ticks >= 10, --block >= 1, 0 <= --work-us < 900\n");
        return 2;
    }

    /* Calibrate the workload to work_us (median of 21 runs). */
    long iters = 1000;
    {
        int64_t t[21];
        for (int i = 0; i < 21; ++i) {
            const int64_t t0 = now_ns();
            workload(iters);
            t[i] = now_ns() - t0;
        }
        const double med_ns = mca_prog_ns_summary(t, 21).p50 * 1e3;
        iters = (long)((double)iters * work_us * 1e3 / (med_ns > 0 ? med_ns : 1));
    }

    mca_dds_bridge_t *bridge = NULL;
    char err[320] = "";
    int rc = mca_dds_bridge_create(&bridge, &cfg, err, sizeof err);
    if (rc != MCA_OK) {
        fprintf(stderr, "bench_dds: bridge: %s: %s\n", mca_strerror(rc), err);
        return 1;
    }
    pid_t mon_pid = 0;
    if (monitor != NULL) {
        char dom[16];
        snprintf(dom, sizeof dom, "%u", cfg.domain_id);
        char *args[12];
        int na = 0;
        args[na++] = (char *)monitor;
        args[na++] = "--domain";
        args[na++] = dom;
        if (cfg.config_path != NULL) {
            args[na++] = "--config";
            args[na++] = (char *)cfg.config_path;
        }
        args[na++] = "--no-color";
        args[na] = NULL;
        posix_spawn_file_actions_t fa; /* the live view to /dev/null; its summary (stderr) stays */
        posix_spawn_file_actions_init(&fa);
        posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
        const int sp_rc = posix_spawn(&mon_pid, monitor, &fa, NULL, args, environ);
        posix_spawn_file_actions_destroy(&fa);
        if (sp_rc != 0) {
            fprintf(stderr, "bench_dds: cannot start %s\n", monitor);
            mca_dds_bridge_destroy(bridge, NULL);
            return 1;
        }
        if (mca_dds_bridge_wait_readers(bridge, MCA_DDS_TOPIC_DISTANCES, 1, 10000) != MCA_OK) {
            fprintf(stderr, "bench_dds: the monitor did not match within 10 s\n");
        }
    }
    if (fifo > 0) {
        struct sched_param sp = {.sched_priority = (int)fifo};
        if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
            fprintf(stderr, "bench_dds: SCHED_FIFO %ld refused (%s); running SCHED_OTHER\n", fifo,
                    strerror(errno));
            fifo = 0;
        }
    }

    int64_t *comp[2], *jit[2], *push_t;
    for (int mode = 0; mode < 2; ++mode) {
        comp[mode] = calloc((size_t)ticks, sizeof(int64_t));
        jit[mode] = calloc((size_t)ticks, sizeof(int64_t));
    }
    push_t = calloc((size_t)ticks, sizeof(int64_t));
    if (comp[0] == NULL || comp[1] == NULL || jit[0] == NULL || jit[1] == NULL || push_t == NULL) {
        fprintf(stderr, "bench_dds: out of memory\n");
        return 1;
    }
    size_t n[2] = {0, 0};
    static mca_dds_snapshot_t snap;
    double min_so_far = INFINITY;
    int64_t min_stamp = 0;
    const int64_t period = 1000000;
    int64_t next = now_ns() + period;
    uint64_t k = 0;
    while (n[0] < (size_t)ticks || n[1] < (size_t)ticks) {
        const int mode = (int)((k / (uint64_t)block) % 2); /* 0 = OFF, 1 = ON */
        const struct timespec ts = {(time_t)(next / 1000000000LL), (long)(next % 1000000000LL)};
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
        }
        const int64_t t0 = now_ns();
        workload(iters);
        mca_dds_synth_fill(&snap, k, t0, &min_so_far, &min_stamp);
        int64_t tp = 0;
        if (mode == 1) {
            const int64_t p0 = now_ns();
            mca_dds_bridge_push(bridge, &snap);
            tp = now_ns() - p0;
        }
        const int64_t t1 = now_ns();
        if (n[mode] < (size_t)ticks) {
            comp[mode][n[mode]] = t1 - t0;
            jit[mode][n[mode]] = t0 - next;
            if (mode == 1) {
                push_t[n[mode]] = tp;
            }
            n[mode]++;
        }
        ++k;
        next += period;
        if (now_ns() > next) { /* overran: skip missed ticks rather than bursting */
            next = now_ns() + period;
        }
    }
    mca_dds_stats_t st;
    mca_dds_bridge_destroy(bridge, &st);
    if (mon_pid > 0) {
        kill(mon_pid, SIGINT);
        waitpid(mon_pid, NULL, 0);
    }

    const mca_prog_ns_summary_t off = mca_prog_ns_summary(comp[0], n[0]),
                                on = mca_prog_ns_summary(comp[1], n[1]);
    const mca_prog_ns_summary_t joff = mca_prog_ns_summary(jit[0], n[0]),
                                jon = mca_prog_ns_summary(jit[1], n[1]);
    const mca_prog_ns_summary_t ps = mca_prog_ns_summary(push_t, n[1]);
    printf("bench_dds: %ld ticks per mode at 1 kHz, blocks of %ld, workload %.0f us, snapshot %zu B, %s%s\n",
           ticks, block, work_us, sizeof(mca_dds_snapshot_t), fifo > 0 ? "SCHED_FIFO" : "SCHED_OTHER",
           monitor != NULL ? ", mca-monitor subscribed" : ", no subscriber");
    printf("tick compute  publishing OFF: p50 %7.1f us  p99 %7.1f us  max %7.1f us  mean %7.1f us\n", off.p50,
           off.p99, off.max, off.mean);
    printf("tick compute  publishing ON : p50 %7.1f us  p99 %7.1f us  max %7.1f us  mean %7.1f us\n", on.p50,
           on.p99, on.max, on.mean);
    printf("push call alone            : p50 %7.2f us  p99 %7.2f us  max %7.2f us\n", ps.p50, ps.p99, ps.max);
    printf("wake-up jitter OFF / ON    : p50 %.1f / %.1f us  p99 %.1f / %.1f us  max %.1f / %.1f us\n",
           joff.p50, jon.p50, joff.p99, jon.p99, joff.max, jon.max);
    printf("ratio ON/OFF  p50 %.3f  p99 %.3f  mean %.3f\n", on.p50 / off.p50, on.p99 / off.p99,
           on.mean / off.mean);
    printf("bridge: offered %llu published %llu dropped %llu samples %llu write errors %llu\n",
           (unsigned long long)st.offered, (unsigned long long)st.published, (unsigned long long)st.dropped,
           (unsigned long long)st.samples, (unsigned long long)st.write_errors);
    for (int mode = 0; mode < 2; ++mode) {
        free(comp[mode]);
        free(jit[mode]);
    }
    free(push_t);
    return 0;
}
