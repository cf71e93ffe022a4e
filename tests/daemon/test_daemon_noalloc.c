/* SPDX-License-Identifier: MIT */
/* Issue 13: no heap allocation anywhere in mca_drive_step after start-up, on every path: running ticks with
 * the DDS bridge (publishing every tick) and the CSV ring, a stop (braking through mca_controller_brake to
 * STOPPED), the controller's PDNN fault on the negative task and its braking, an injected controller fault,
 * lost feedback, an arm's own FAULT, an arm that does not servo, and the ticks in FAULT afterwards.
 *
 * The counter replaces malloc itself (this executable defines malloc, calloc, realloc, free, memalign,
 * posix_memalign, aligned_alloc, valloc and pvalloc, forwarding to glibc's __libc_* functions), so calls from
 * every library count, libc's own and C++ operator new included; it counts only on the thread that steps and
 * only while mca_drive_step runs (the DDS publisher and Cyclone's threads allocate on their own). It checks
 * itself first (a malloc while armed must count). Not under the sanitizers (they replace malloc too): nosan.
 * argv[1] = source dir, argv[2] = DDS domain, argv[3] = mca-dds-bridge (the DDS publisher process, as mcad
 * runs it). FAILS on any allocation. */
#include <limits.h> /* realpath */
#include <malloc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mca/cell.h"
#include "mca/daemon.h"
#include "mca/daemon_drive.h"
#include "mca/err.h"
#include "mca/sim_backend.h"

#include "log_sink.h" /* test_log_line */

extern void *__libc_malloc(size_t n);
extern void *__libc_calloc(size_t a, size_t b);
extern void *__libc_realloc(void *p, size_t n);
extern void __libc_free(void *p);
extern void *__libc_memalign(size_t a, size_t n);
extern void *__libc_valloc(size_t n);
extern void *__libc_pvalloc(size_t n);

static __thread int armed; /* initial-exec TLS of the executable: safe inside malloc */
static long allocs;        /* only the armed thread writes it */

void *malloc(size_t n) {
    allocs += armed;
    return __libc_malloc(n);
}
void *calloc(size_t a, size_t b) {
    allocs += armed;
    return __libc_calloc(a, b);
}
void *realloc(void *p, size_t n) {
    allocs += armed;
    return __libc_realloc(p, n);
}
void free(void *p) {
    allocs += armed && p;
    __libc_free(p);
}
void *memalign(size_t a, size_t n) {
    allocs += armed;
    return __libc_memalign(a, n);
}
void *aligned_alloc(size_t a, size_t n) {
    allocs += armed;
    return __libc_memalign(a, n);
}
int posix_memalign(void **p, size_t a, size_t n) {
    allocs += armed;
    void *q = __libc_memalign(a, n);
    if (!q) {
        return 12; /* ENOMEM */
    }
    *p = q;
    return 0;
}
void *valloc(size_t n) {
    allocs += armed;
    return __libc_valloc(n);
}
void *pvalloc(size_t n) {
    allocs += armed;
    return __libc_pvalloc(n);
}

static const char *src;
static unsigned domain;
static const char *bridge_exe;
static int failures;

/* one step, counted */
static int step(mca_daemon_t *d, double t) {
    armed = 1;
    const int st = mca_drive_step(d, t, (int64_t)llround(t * 1e9));
    armed = 0;
    return st;
}

static mca_daemon_t *open_cell(const char *path, int dds, char *csv) {
    static mca_cell_t cell;
    char err[1024] = "";
    if (mca_cell_load(path, &cell, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "cell: %s\n", err);
        exit(1);
    }
    cell.dds.enabled = dds;
    cell.dds.domain = domain;
    snprintf(cell.dds.config, sizeof cell.dds.config, "%s/config/dds/loopback.xml", src); /* traffic on lo */
    cell.dds.publish_divisor = 1;
    const mca_drive_opts_t o = {.daemon = {.no_dds = !dds,
                                           .log = test_log_line,
                                           .log_arg = stderr,
                                           .csv_path = csv,
                                           .dds_bridge_exe = bridge_exe}};
    mca_daemon_t *d = NULL;
    if (mca_drive_open(&d, &cell, &o, err, sizeof err) != MCA_OK) {
        fprintf(stderr, "open: %s\n", err);
        exit(1);
    }
    return d;
}

/* Step until the state is @p until (or n ticks); drains the log/CSV rings (non-rt, not counted) as mcad's
 * supervisor would. Returns ticks stepped. */
static int run(mca_daemon_t *d, double *t, int n, int until) {
    int k = 0;
    for (; k < n; k++) {
        *t += 0.001;
        const int st = step(d, *t);
        if (k % 100 == 0) {
            mca_daemon_service(d);
        }
        if (st == until) {
            break;
        }
    }
    mca_daemon_service(d);
    return k + 1;
}

static void report(const char *what, mca_daemon_t *d, int ticks, long before) {
    mca_daemon_summary_t s;
    mca_daemon_summary(d, &s);
    const long n = allocs - before;
    printf("%-60s %6d ticks, state %-8s allocations %ld%s%s\n", what, ticks, mca_daemon_state_name(s.state),
           n, s.fault ? ", fault: " : "", s.fault ? s.fault_text : "");
    if (n != 0) {
        failures++;
    }
}

static void write_inline_cell(const char *path) {
    FILE *f = fopen(path, "w");
    if (!f) {
        exit(1);
    }
    fprintf(f,
            "name: noalloc\n"
            "task: {duration: 4.0}\n"
            "arms:\n"
            "  - name: left\n"
            "    backend: sim\n"
            "    urdf: %s/config/robots/pa10plus.urdf\n"
            "    base_xyz: [0.0, -0.6, 0.0]\n"
            "    q0: [0.0, 0.5, 0.0, 1.0, 0.0, 0.6, 0.0, 0.0]\n"
            "    dec_limit: 4.0\n"
            "    path: {kind: circle, radius: 0.15, period: 4.0, u: [1, 0, 0], v: [0, 0, 1]}\n"
            "  - name: right\n"
            "    backend: sim\n"
            "    urdf: %s/config/robots/pa10plus.urdf\n"
            "    base_xyz: [0.0, 0.6, 0.0]\n"
            "    q0: [0.0, 0.5, 0.0, 1.0, 0.0, 0.6, 0.0, 0.0]\n"
            "    dec_limit: 2.5\n"
            "dds: {enabled: false}\n"
            "rt: {period_us: 1000, lost_feedback_cycles: 5}\n",
            src, src);
    fclose(f);
}

/* an inline-cell daemon that runs @p pre ticks, then gets @p kind on arm @p arm; steps to FAULT and 50 more
 */
static void injected(const char *what, const char *cell, int pre, int arm, mca_sim_inject_kind_t kind) {
    mca_daemon_t *d = open_cell(cell, 0, NULL);
    double t = 0.0;
    int k = pre ? run(d, &t, pre, -1) : 0;
    const long before = allocs;
    mca_sim_arm_t *fw = mca_sim_backend_firmware(mca_drive_arm(d, arm));
    fw->cfg.inject[0] = (mca_sim_inject_t){.kind = kind, .at_cycle = fw->cycle, .joint = 1, .duration = 0};
    fw->cfg.n_inject = 1;
    k = run(d, &t, 5000, MCA_DAEMON_FAULT);
    k += run(d, &t, 50, -1);
    report(what, d, k, before);
    mca_daemon_close(d);
}

int main(int argc, char **argv) {
    if (argc < 4) {
        fprintf(stderr, "usage: %s SOURCE_DIR DDS_DOMAIN MCA_DDS_BRIDGE\n", argv[0]);
        return 2;
    }
    static char src_abs[4096];
    src = realpath(argv[1], src_abs) ? src_abs : argv[1];
    domain = (unsigned)atoi(argv[2]);
    bridge_exe = argv[3];
    /* the counter must be live: an allocation while armed counts */
    armed = 1;
    void *volatile p = malloc(32);
    armed = 0;
    free(p);
    if (allocs != 1) {
        fprintf(stderr, "FAIL: the malloc counter is not live (counted %ld of 1)\n", allocs);
        return 1;
    }
    allocs = 0;

    char path[1024], csv[512], inline_cell[512];
    snprintf(csv, sizeof csv, "/tmp/mca-noalloc-%d.csv", (int)getpid());
    snprintf(inline_cell, sizeof inline_cell, "/tmp/mca-noalloc-%d.yaml", (int)getpid());
    write_inline_cell(inline_cell);

    /* 1. cross circles (mca), DDS every tick, CSV: 3000 running ticks through the d2 band, a stop, braking
     *    to STOPPED, 50 ticks stopped */
    snprintf(path, sizeof path, "%s/config/cells/cross_circles_sim.yaml", src);
    mca_daemon_t *d = open_cell(path, 1, csv);
    double t = 0.0;
    long before = allocs;
    int k = run(d, &t, 3000, -1);
    report("cross circles: running, DDS every tick, CSV", d, k, before);
    before = allocs;
    mca_daemon_request_stop(d);
    k = run(d, &t, 20000, MCA_DAEMON_STOPPED);
    k += run(d, &t, 50, -1);
    report("cross circles: stop, braking (controller brake), stopped", d, k, before);
    mca_daemon_close(d);

    /* 2. the negative task (mca): the PDNN fault at 3.078 s, braking, FAULT */
    snprintf(path, sizeof path, "%s/config/cells/negative_sim.yaml", src);
    d = open_cell(path, 1, csv);
    t = 0.0;
    before = allocs;
    k = run(d, &t, 8000, MCA_DAEMON_BRAKING);
    report("negative task: running to the PDNN fault", d, k, before);
    before = allocs;
    k = run(d, &t, 20000, MCA_DAEMON_FAULT);
    k += run(d, &t, 100, -1);
    report("negative task: braking after the fault, FAULT", d, k, before);
    mca_daemon_close(d);

    /* 3. an injected controller fault (mca-sim --fault-at) mid-task */
    d = open_cell(inline_cell, 1, NULL);
    t = 0.0;
    run(d, &t, 500, -1);
    before = allocs;
    armed = 1;
    mca_drive_fault_at(d, MCA_CTRL_FAULT_NAN, t); /* latched in the next step, counted with it */
    armed = 0;
    k = run(d, &t, 20000, MCA_DAEMON_FAULT);
    k += run(d, &t, 50, -1);
    report("injected controller fault (NaN), braking, FAULT", d, k, before);
    {
        /* the scheduled fault acted: a run with no fault would count nothing for this path */
        mca_daemon_summary_t s;
        mca_daemon_summary(d, &s);
        if (s.state != MCA_DAEMON_FAULT || !strstr(s.fault_text, "injected")) {
            printf("FAIL: the scheduled fault did not end in FAULT (state %s, fault '%s')\n",
                   mca_daemon_state_name(s.state), s.fault_text);
            failures++;
        }
    }
    mca_daemon_close(d);

    /* 4. a streamed task (ROS 2 targets), DDS with its ROS 2 topics every tick: the loop reads the
     *    stream mailboxes each tick (no target comes: the arms hold), then a stop and braking */
    snprintf(path, sizeof path, "%s/config/cells/stream_sim.yaml", src);
    d = open_cell(path, 1, csv);
    t = 0.0;
    before = allocs;
    k = run(d, &t, 2000, -1);
    mca_daemon_request_stop(d);
    k += run(d, &t, 20000, MCA_DAEMON_STOPPED);
    report("streamed task: holding, ROS 2 topics every tick, stop, braking", d, k, before);
    mca_daemon_close(d);

    /* 5. streamed bodies (DDS, the bridge's box read every tick): none comes, so after lost_after the named
     *    fault, braking with the tracks still read, FAULT */
    snprintf(path, sizeof path, "%s/config/cells/tracks_secure_sim.yaml", src);
    d = open_cell(path, 1, csv);
    t = 0.0;
    before = allocs;
    k = run(d, &t, 20000, MCA_DAEMON_FAULT);
    k += run(d, &t, 50, -1);
    report("streamed bodies: silent, lost, braking, FAULT", d, k, before);
    {
        mca_daemon_summary_t s;
        mca_daemon_summary(d, &s);
        if (s.fault != MCA_DAEMON_FAULT_TRACKS_LOST) {
            printf("FAIL: the silent stream of bodies did not end in its fault (fault %d '%s')\n", s.fault,
                   s.fault_text);
            failures++;
        }
    }
    mca_daemon_close(d);

    /* 6. a cell with fixed bodies (cup stacking's table and cups), DDS every tick: each body's closest link
     * and the named pairs of every kind in each snapshot */
    snprintf(path, sizeof path, "%s/config/cells/cup_stacking_bodies_sim.yaml", src);
    d = open_cell(path, 1, csv);
    t = 0.0;
    before = allocs;
    k = run(d, &t, 3000, -1);
    mca_daemon_request_stop(d);
    k += run(d, &t, 20000, MCA_DAEMON_STOPPED);
    report("fixed bodies: running, each body's closest link, named pairs on DDS every tick, stop", d, k,
           before);
    mca_daemon_close(d);

    /* 7. the arms' faults */
    injected("lost feedback (right arm's firmware silent)", inline_cell, 500, 1, MCA_SIM_INJ_SILENT);
    injected("an arm's own FAULT (left actuator)", inline_cell, 500, 0, MCA_SIM_INJ_ACTUATOR);
    injected("an arm that does not servo (commands lost from the start)", inline_cell, 0, 1,
             MCA_SIM_INJ_DROP_RX);

    unlink(csv);
    unlink(inline_cell);
    if (failures) {
        printf("FAIL: %d of the runs above allocated inside mca_drive_step\n", failures);
        return 1;
    }
    printf("OK: no allocation inside mca_drive_step on any path\n");
    return 0;
}
