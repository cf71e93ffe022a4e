/* SPDX-License-Identifier: MIT */
/* mca-dds-synth: a 1 kHz loop that pushes deterministic snapshots (mca/dds_synth.h) through the real
 * DDS bridge (ring + publisher thread). Used by the tests, the benchmark and as a demo source for
 * mca-monitor. Exit 0 on success, 2 on bad usage, 1 on a run-time error. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mca/dds_bridge.h"
#include "mca/dds_synth.h"
#include "mca/err.h"
#include "mca/prog.h" /* mca_prog_parse_u64, mca_prog_on_stop_signals */

static volatile sig_atomic_t g_stop;

static void on_signal(int sig) {
    (void)sig;
    g_stop = 1;
}

static void usage(FILE *f) {
    fprintf(f, "usage: mca-dds-synth [options]\n"
               "  --domain N         DDS domain id (default 0)\n"
               "  --config FILE      Cyclone DDS XML (default: CYCLONEDDS_URI or built-in)\n"
               "  --ticks N          ticks to run (default 10000; 0 = until Ctrl-C)\n"
               "  --hz F             loop rate (default 1000)\n"
               "  --divisor N        publish every Nth tick (default 1; the other ticks fill nothing)\n"
               "  --ring N           ring capacity, power of two (default 1024)\n"
               "  --partition NAME   publish in DDS partition NAME (default: the default partition)\n"
               "  --wait-readers N   before the first tick wait for N matched readers\n"
               "  --wait-topic NAME  ... on this topic only (default: on every topic)\n"
               "  --wait-timeout MS  give up waiting after MS ms (default 10000), exit 1\n"
               "  --linger MS        after the last tick keep the publisher alive MS ms (default 0)\n"
               "  --help\n");
}

/* every integer option: 0..max, the error said */
static int parse_u64(const char *s, const char *name, unsigned long long max, unsigned long long *out) {
    return mca_prog_parse_u64("mca-dds-synth", name, s, max, out);
}

static int64_t now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

int main(int argc, char **argv) {
    mca_dds_config_t cfg;
    mca_dds_config_default(&cfg);
    unsigned long long ticks = 10000, wait_readers = 0, wait_timeout = 10000, linger = 0, v = 0;
    unsigned long long divisor = 1;
    double hz = 1000.0;
    const char *wait_topic = NULL;
    static const struct option opts[] = {
        {"domain", required_argument, NULL, 'd'},
        {"config", required_argument, NULL, 'c'},
        {"ticks", required_argument, NULL, 'n'},
        {"hz", required_argument, NULL, 'z'},
        {"divisor", required_argument, NULL, 'v'},
        {"ring", required_argument, NULL, 'r'},
        {"wait-readers", required_argument, NULL, 'w'},
        {"wait-timeout", required_argument, NULL, 't'},
        {"linger", required_argument, NULL, 'l'},
        {"wait-topic", required_argument, NULL, 'T'},
        {"partition", required_argument, NULL, 'P'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (c) {
        case 'd':
            if (parse_u64(optarg, "--domain", 230, &v) != 0) {
                return 2;
            }
            cfg.domain_id = (uint32_t)v;
            break;
        case 'c':
            cfg.config_path = optarg;
            break;
        case 'n':
            if (parse_u64(optarg, "--ticks", 1000000000ULL, &ticks) != 0) {
                return 2;
            }
            break;
        case 'z': {
            char *end = NULL;
            hz = strtod(optarg, &end);
            if (end == optarg || *end != '\0' || !(hz >= 1.0 && hz <= 10000.0)) {
                fprintf(stderr, "mca-dds-synth: --hz: '%s' is not a rate in 1..10000\n", optarg);
                return 2;
            }
            break;
        }
        case 'v':
            if (parse_u64(optarg, "--divisor", 1000000, &v) != 0 || v == 0) {
                fprintf(stderr, "mca-dds-synth: --divisor must be >= 1\n");
                return 2;
            }
            divisor = v;
            break;
        case 'r':
            if (parse_u64(optarg, "--ring", 1u << 20, &v) != 0 || v < 2 || (v & (v - 1)) != 0) {
                fprintf(stderr, "mca-dds-synth: --ring must be a power of two >= 2\n");
                return 2;
            }
            cfg.ring_capacity = (uint32_t)v;
            break;
        case 'w':
            if (parse_u64(optarg, "--wait-readers", 1000, &wait_readers) != 0) {
                return 2;
            }
            break;
        case 't':
            if (parse_u64(optarg, "--wait-timeout", 3600000, &wait_timeout) != 0) {
                return 2;
            }
            break;
        case 'P':
            cfg.partition = optarg;
            break;
        case 'T':
            wait_topic = optarg;
            break;
        case 'l':
            if (parse_u64(optarg, "--linger", 3600000, &linger) != 0) {
                return 2;
            }
            break;
        case 'h':
            usage(stdout);
            return 0;
        default:
            usage(stderr);
            return 2;
        }
    }
    if (mca_prog_no_operands("mca-dds-synth", argc, argv, optind, usage) != 0) {
        return 2;
    }

    mca_prog_on_stop_signals(on_signal);

    mca_dds_bridge_t *bridge = NULL;
    char err[320] = "";
    int rc = mca_dds_bridge_create(&bridge, &cfg, err, sizeof err);
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-dds-synth: bridge: %s: %s\n", mca_strerror(rc), err);
        return 1;
    }
    if (wait_readers > 0) {
        rc = mca_dds_bridge_wait_readers(bridge, wait_topic, (uint32_t)wait_readers, (uint32_t)wait_timeout);
        if (rc != MCA_OK) {
            fprintf(stderr, "mca-dds-synth: no %llu matched readers on %s after %llu ms (%s)\n", wait_readers,
                    wait_topic != NULL ? wait_topic : "every topic", wait_timeout, mca_strerror(rc));
            mca_dds_bridge_destroy(bridge, NULL);
            return 1;
        }
    }

    /* The loop: absolute-time sleeps, one snapshot per tick, never waits on DDS. */
    static mca_dds_snapshot_t snap;
    double min_so_far = INFINITY;
    int64_t min_stamp = 0;
    const int64_t period = (int64_t)llround(1e9 / hz);
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    uint64_t k = 0;
    for (; !g_stop && (ticks == 0 || k < ticks); ++k) {
        next.tv_nsec += period;
        while (next.tv_nsec >= 1000000000L) {
            next.tv_nsec -= 1000000000L;
            next.tv_sec += 1;
        }
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL) == EINTR && !g_stop) {
        }
        if (k % divisor == 0) { /* decimation here: a tick that does not publish fills nothing */
            mca_dds_synth_fill(&snap, k, now_ns(), &min_so_far, &min_stamp);
            mca_dds_bridge_push(bridge, &snap);
        }
    }
    if (linger > 0 && !g_stop) {
        const struct timespec ts = {(time_t)(linger / 1000), (long)(linger % 1000) * 1000000L};
        nanosleep(&ts, NULL);
    }
    mca_dds_stats_t st;
    mca_dds_bridge_destroy(bridge, &st); /* flushes first */
    printf("mca-dds-synth: ticks %llu offered %llu queued %llu published %llu dropped %llu "
           "samples %llu write_errors %llu max_pending %llu max_publish_us %lld wakes %llu parks %llu\n",
           (unsigned long long)k, (unsigned long long)st.offered, (unsigned long long)st.queued,
           (unsigned long long)st.published, (unsigned long long)st.dropped, (unsigned long long)st.samples,
           (unsigned long long)st.write_errors, (unsigned long long)st.max_pending,
           (long long)(st.max_publish_ns / 1000), (unsigned long long)st.wakes, (unsigned long long)st.parks);
    return st.write_errors == 0 ? 0 : 1;
}
