/* SPDX-License-Identifier: MIT */
/* The real-time loop and its timing (daemon_loop.c): the loop thread (mcad-loop: pinned, SCHED_FIFO where
 * permitted, a warm-up on a scratch controller, then one mcad_step per period on a grid half a period
 * off CLOCK_MONOTONIC's whole periods; wake-up jitter, compute time, overruns), the process's real-time
 * set-up (mlockall, /dev/cpu_dma_latency, the non-rt threads off the loop's CPU) and what other threads ask
 * of the loop (mca/daemon.h: mca_daemon_start, _request_stop, _finished, _ticks, _state, _join,
 * _wake_histogram). Private to mca_daemon.
 *
 * Calling context: mcad_pin_non_rt and mca_daemon_start at start-up (the main thread, before the loop
 * runs); the loop's own code on the RT thread (no allocation, no locks, no blocking I/O); request_stop,
 * finished, ticks and state from any thread (atomics; request_stop async-signal safe); join and
 * wake_histogram from the main thread (join waits for the loop; the histogram once it has ended). */
#ifndef MCA_DAEMON__LOOP_H
#define MCA_DAEMON__LOOP_H

#include "daemon__state.h"

/* Start-up (rt.cpu set, before any other thread starts): the calling thread leaves the loop's CPU. */
void mcad_pin_non_rt(mca_daemon_t *d);

#endif
