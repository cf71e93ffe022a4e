/* SPDX-License-Identifier: MIT */
/* The real-time loop and its timing (daemon__loop.h): the loop thread (RT), its start (start-up) and what
 * other threads ask of it. */
#include "daemon__loop.h"

#include <errno.h>
#include <fcntl.h>
#include <malloc.h>
#include <sched.h>
#ifdef MCA_TEST_HOOKS
#include <signal.h> /* raise (debug_kill_after_ticks) */
#endif
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include "mca/err.h"

#include "daemon__log.h"     /* mcad_log: the caller's sink */
#include "daemon__fault.h"   /* mcad_latch_fault */
#include "daemon__publish.h" /* mcad_dds_ab_publishes */
#include "daemon__tick.h"    /* mcad_step */

/* rt.cpu set: the calling (main, supervising) thread, and so every thread created from it later (DDS,
 * Cyclone's own, the loop before it pins itself), leaves the loop's CPU. Start-up. */
void mcad_pin_non_rt(mca_daemon_t *d) {
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) != 0) {
        return;
    }
    CPU_CLR(d->cell.rt.cpu, &set);
    if (CPU_COUNT(&set) == 0) {
        mcad_log(d, 4, "rt.cpu %d is the only CPU this process may use: the other threads share it",
                 d->cell.rt.cpu);
        return;
    }
    if (sched_setaffinity(0, sizeof set, &set) != 0) {
        mcad_log(d, 4, "cannot move the non-real-time threads off CPU %d: %s", d->cell.rt.cpu,
                 strerror(errno));
        return;
    }
    char list[128];
    size_t k = 0;
    for (int c = 0; c < CPU_SETSIZE && k + 8 < sizeof list; c++) {
        if (CPU_ISSET(c, &set)) {
            k += (size_t)snprintf(list + k, sizeof list - k, "%s%d", k ? "," : "", c);
        }
    }
    mcad_log(d, 6, "loop on CPU %d; supervisor, log/CSV drainer and DDS threads on CPUs %s", d->cell.rt.cpu,
             list);
    d->non_rt_pinned = 1;
}

static void prefault_stack(void) {
    volatile unsigned char buf[256 * 1024];
    for (size_t i = 0; i < sizeof buf; i += 4096) {
        buf[i] = 0;
    }
}

/* Run the loop's code once before the first command enables the servos. A process's first controller
 * ticks run cold (lazy binding, first touch, and under QEMU/TCG the translation of every new code path:
 * vcan_e2e saw tick 0 take 21 ms and ticks 1-2 1.5-3 ms against 0.5 ms after), long enough for an arm's
 * 3-cycle watchdog to trip right after the first tick enabled it. Ticks a scratch copy of the controller
 * from the start position, then brakes it: the arms see nothing (they stay READY, servo off, until the
 * first real tick), the controller's own state is untouched. */
static void warm_up(mca_daemon_t *d) {
    const double dt = (double)d->cell.rt.period_ns * 1e-9;
    double qdot[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}};
    const double *qp[MCA_MAX_ARMS], *vl[MCA_MAX_ARMS], *dl[MCA_MAX_ARMS], *vm[MCA_MAX_ARMS] = {NULL};
    double *qd[MCA_MAX_ARMS];
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        qp[a] = d->q[a];
        qd[a] = qdot[a];
        dl[a] = d->dec[a];
    }
    for (int a = 0; a < d->n_arms; a++) {
        vm[a] = d->have_fb[a] ? d->fb[a].velocity : NULL;
    }
    const int64_t t0 = now_ns();
    mca_controller_copy(d->warm_ctrl, d->ctrl);
    int64_t last = 0;
    int k;
    for (k = 0; k < MCA_DAEMON_WARM_TICKS; k++) {
        const int64_t s = now_ns();
        mca_controller_set_velocity(d->warm_ctrl, vm);
        mca_controller_tick(d->warm_ctrl, (double)k * dt, qp, qd, &d->warm_info);
        last = now_ns() - s;
    }
    double v0[MCA_MAX_ARMS][MCA_MAX_DOF];
    memcpy(v0, qdot, sizeof v0);
    for (int a = 0; a < MCA_MAX_ARMS; a++) {
        vl[a] = v0[a];
    }
    for (int b = 0; b < 3; b++) {
        mca_controller_brake(d->warm_ctrl, (double)(k + b) * dt, qp, vl, dl, qd, &d->warm_info);
    }
    mca_controller_observe(d->warm_ctrl, (double)k * dt, qp, &d->warm_info);
    LOGN(d, MCA_LOG_INFO,
         "warm-up: %g controller ticks and 3 braking ticks in %.1f ms (the last tick %.0f us)", 3, (double)k,
         (double)(now_ns() - t0) * 1e-6, (double)last * 1e-3, 0, NULL);
}

static void *rt_main(void *arg) {
    mca_daemon_t *d = arg;
    pthread_setname_np(pthread_self(), "mcad-loop"); /* visible in ps -L, top -H */
    prefault_stack();
    if (d->cell.rt.cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(d->cell.rt.cpu, &set);
        if (pthread_setaffinity_np(pthread_self(), sizeof set, &set) != 0) {
            LOGN(d, MCA_LOG_WARNING, "cannot pin the loop to CPU %g", 1, d->cell.rt.cpu, 0, 0, 0, NULL);
        }
    }
    if (!d->drive.virtual_time) {
        warm_up(d);
    }
    const int64_t period = d->cell.rt.period_ns;
    const double stop_after = d->opts.stop_after > 0 ? d->opts.stop_after : d->cell.stop_after;
    /* The grid sits half a period off the whole periods of CLOCK_MONOTONIC. The kernel's tick lands on
     * whole multiples of 1/HZ (here every 4 ms on the dot, perf timer:hrtimer_expire_entry): a loop on whole
     * milliseconds would wake with it every 4th tick (cyclictest on this VM: p90 17 vs 15 us, p99.9 63 vs 45
     * at whole ms + 500 us). A known phase also lets other periodic work keep clear of the loop. */
    int64_t next = (now_ns() / period + 1) * period + period / 2;
#ifdef MCA_TEST_HOOKS
    int stalled_logged = 0;
#endif
    for (;;) {
        struct timespec ts = {(time_t)(next / NS_PER_S), (long)(next % NS_PER_S)};
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
        }
        const int64_t wake = now_ns();
        const uint64_t ticks = atomic_load_explicit(&d->ticks, memory_order_relaxed);
#ifdef MCA_TEST_HOOKS
        if (d->cell.debug_kill_after_ticks && ticks >= d->cell.debug_kill_after_ticks) {
            /* test hook: die mid-task at an exact tick, as a crash would (vcan_e2e phase D: only the
             * arms' own watchdogs brake them); a kill from outside lands late when the host is slow */
            raise(SIGKILL);
        }
        if (atomic_load_explicit(&d->stall_request, memory_order_relaxed) ||
            (d->cell.debug_stall_after_ticks && ticks >= d->cell.debug_stall_after_ticks)) {
            /* test hook: stop ticking (the supervisor must notice and stop the watchdog pings) */
            if (!stalled_logged) {
                LOGN(d, MCA_LOG_WARNING, "debug stall after %g ticks: the loop stops ticking", 1,
                     (double)ticks, 0, 0, 0, NULL);
                stalled_logged = 1;
            }
            if (atomic_load(&d->stop_request)) {
                break;
            }
            next = wake + 10 * 1000000LL;
            continue;
        }
#endif
        mca_hist_record(&d->jitter, wake - next);
        d->jitter_first_due_ns = d->jitter_first_due_ns ? d->jitter_first_due_ns : next;
        d->jitter_last_due_ns = next;
        /* task time advances one period per tick: a missed deadline delays the task instead of skipping
         * path points (a sim or lockstep arm did not move meanwhile; real arms' drift is fed back) */
        const double t = (double)ticks * (double)period * 1e-9;
        if (stop_after > 0 && t >= stop_after) {
            atomic_store(&d->stop_request, 1);
        }
        d->wake_late_ns = wake - next;
        const int state = mcad_step(d, t, wake);
        const int64_t end = now_ns();
        mca_hist_record(&d->compute, end - wake);
        if (d->opts.dds_ab_block) {
            const int k = mcad_dds_ab_publishes(d, ticks);
            mca_hist_record(&d->compute_ab[k], end - wake);
            /* a tick of half a period or more is a stall of this machine, not a cost of publishing: one in
             * either kind of block moves its mean more than publishing does (bench/rt/jitter_dds.sh) */
            if (end - wake < period / 2) {
                d->compute_ab_short_sum_ns[k] += (double)(end - wake);
                d->compute_ab_short_n[k]++;
            }
        }
        if (state == MCA_DAEMON_STOPPED || (state == MCA_DAEMON_FAULT && atomic_load(&d->stop_request))) {
            /* one more zero command so the arms see the servo released, then leave (before the overrun
             * count: the last tick has no next period to miss, and the wake-up histogram's span ends at its
             * wake-up, so periods skipped after it would count outside that span) */
            mcad_step(d, t + (double)period * 1e-9, now_ns());
            break;
        }
        next += period;
        if (end > next) {
            /* every period missed counts: one 20 ms stall is 20 consecutive overruns */
            d->overruns++;
            while (next <= end) {
                next += period;
                d->skipped++;
                d->consecutive_overruns++;
            }
            if (d->consecutive_overruns >= d->cell.rt.overrun_limit &&
                atomic_load_explicit(&d->state, memory_order_relaxed) == MCA_DAEMON_RUNNING) {
                mcad_latch_fault(d, MCA_DAEMON_FAULT_OVERRUN, MCA_ETIMEDOUT, t, -1, 0, 0,
                                 d->consecutive_overruns, NULL);
            }
        } else {
            d->consecutive_overruns = 0;
        }
    }
    atomic_store(&d->finished, 1);
    return NULL;
}

int mca_daemon_start(mca_daemon_t *d) {
    if (d->drive.driven) {
        return MCA_EINVAL; /* its driver steps it (mca/daemon_drive.h): one thread ticks a daemon, never two
                            */
    }
    /* The loop's own clock: the PDNN's share of the period (rt.pdnn_budget_us, default half). Running out is
     * a named fault, not an overrun. A caller that steps the daemon itself (mca-sim in virtual time, the
     * tests) has no period to keep, and its runs stay deterministic. */
    d->ccfg.pdnn_budget_ns = d->cell.rt.pdnn_budget_ns;
    mca_controller_set_pdnn_budget(d->ctrl, d->ccfg.pdnn_budget_ns);
    if (!d->opts.no_rt && d->cell.rt.lock_memory) {
        /* keep freed memory in the process, never use mmap for malloc: no page faults after start-up */
        mallopt(M_TRIM_THRESHOLD, -1);
        mallopt(M_MMAP_MAX, 0);
        if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
            d->mem_locked = 1;
            void *p = malloc(4 << 20);
            if (p) {
                memset(p, 0, 4 << 20);
                free(p);
            }
        } else {
            mcad_log(d, 4, "mlockall failed (%s): page faults may delay the loop (raise LimitMEMLOCK)",
                     strerror(errno));
        }
    }
    if (!d->opts.no_rt && d->cell.rt.dma_latency) {
        d->dma_fd = open("/dev/cpu_dma_latency", O_WRONLY);
        const int32_t zero = 0;
        if (d->dma_fd < 0 || write(d->dma_fd, &zero, sizeof zero) != (ssize_t)sizeof zero) {
            mcad_log(d, 4,
                     "cannot hold /dev/cpu_dma_latency at 0 (%s): deep C-states may add wake-up "
                     "latency",
                     strerror(errno));
            if (d->dma_fd >= 0) {
                close(d->dma_fd);
            }
            d->dma_fd = -1;
        }
    }
    pthread_attr_t attr;
    pthread_attr_init(&attr);
    pthread_attr_setstacksize(&attr, 1 << 20);
    int rc = -1;
    if (!d->opts.no_rt && d->cell.rt.priority > 0) {
        struct sched_param sp = {.sched_priority = d->cell.rt.priority};
        pthread_attr_setinheritsched(&attr, PTHREAD_EXPLICIT_SCHED);
        pthread_attr_setschedpolicy(&attr, SCHED_FIFO);
        pthread_attr_setschedparam(&attr, &sp);
        rc = pthread_create(&d->thread, &attr, rt_main, d);
        if (rc == 0) {
            d->sched_fifo = 1;
        } else {
            mcad_log(d, 4,
                     "SCHED_FIFO priority %d not permitted (%s): running SCHED_OTHER, expect "
                     "jitter (run as root or with CPUSchedulingPolicy=fifo / LimitRTPRIO)",
                     d->cell.rt.priority, strerror(rc));
        }
    }
    if (rc != 0) {
        pthread_attr_setinheritsched(&attr, PTHREAD_INHERIT_SCHED);
        rc = pthread_create(&d->thread, &attr, rt_main, d);
    }
    pthread_attr_destroy(&attr);
    if (rc != 0) {
        mcad_log(d, 3, "cannot start the loop thread: %s", strerror(rc));
        return MCA_ENOMEM;
    }
    d->thread_started = 1;
    return MCA_OK;
}

void mca_daemon_request_stop(mca_daemon_t *d) {
    atomic_store(&d->stop_request, 1);
}

int mca_daemon_finished(const mca_daemon_t *d) {
    return atomic_load(&((mca_daemon_t *)d)->finished);
}

uint64_t mca_daemon_ticks(const mca_daemon_t *d) {
    return atomic_load_explicit(&((mca_daemon_t *)d)->ticks, memory_order_acquire);
}

int mca_daemon_state(const mca_daemon_t *d) {
    return atomic_load(&((mca_daemon_t *)d)->state);
}

int mca_daemon_join(mca_daemon_t *d) {
    if (d->thread_started) {
        pthread_join(d->thread, NULL);
        d->thread_started = 0;
    }
    if (d->dma_fd >= 0) {
        close(d->dma_fd);
        d->dma_fd = -1;
    }
    mca_daemon_service(d);
    return MCA_OK;
}

const mca_hist_t *mca_daemon_wake_histogram(const mca_daemon_t *d, int64_t *first_due_ns,
                                            int64_t *last_due_ns) {
    *first_due_ns = d->jitter_first_due_ns;
    *last_due_ns = d->jitter_last_due_ns;
    return &d->jitter;
}
