/* SPDX-License-Identifier: MIT */
/** @file mca/dds_child.h
 * A program's DDS participant in a supervised child process, for the tools that watch a cell (mca-monitor,
 * mca-record).
 *
 * libddsc 0.10.2 dies of SIGSEGV when a peer with a type it cannot build subscribes to one of our topics
 * (docs/dds.md, "The crash in Cyclone DDS 0.10.2"); a program whose participant lives in its own process
 * dies with it and loses what it holds (a recording, the monitor's view). With this module the program
 * forks, before it creates any DDS entity, a child that owns the participant and hands what it receives to
 * the parent over a pipe, one frame per sample. The parent keeps the file or the display, reaps a child that
 * died, starts another after the same capped back-off as mcad's DDS bridge (MCA_DDS_BRIDGE_BACKOFF_S doubling
 * to MCA_DDS_BRIDGE_BACKOFF_MAX_S, for as long as it runs), says so on its log, and counts the gaps: the time
 * from the death of a child that was up to the next child being up, during which nothing can be received.
 *
 * A frame is written whole by the child or not seen at all: a child that dies in the middle of one leaves a
 * partial frame, which the parent drops.
 *
 * Context: non-rt, one thread of the parent. The parent must not create DDS entities (fork() copies the
 * calling thread only: a child of a parent that had Cyclone's threads would inherit a library without them).
 */
#ifndef MCA_DDS_CHILD_H
#define MCA_DDS_CHILD_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <sys/types.h>

#ifdef __cplusplus
extern "C" {
#endif

/** In the child: the program's DDS side. Create the participant, call mca_dds_child_ready(), then send
 *  frames with mca_dds_child_send() until mca_dds_child_stopping() or a send fails. Returns the child's exit
 *  status (0: stopped when asked; non-zero before it was ever ready: a set-up error the parent reports as
 *  fatal). */
typedef int (*mca_dds_child_main_t)(int fd, void *arg);

/** In the parent: one frame of a child. Non-zero: an error of the parent (a write error): the poll stops and
 *  returns it. */
typedef int (*mca_dds_child_frame_t)(void *ctx, uint32_t kind, const void *data, size_t len);

/** Frame kinds from 1 are the program's; 0 is "ready" (mca_dds_child_ready). */
#define MCA_DDS_CHILD_READY 0u
/** Gaps kept one by one (all are counted). */
#define MCA_DDS_CHILD_GAPS 64

typedef struct mca_dds_child_gap {
    double from_s, to_s; /**< CLOCK_MONOTONIC [s]: the death of a child that was up, the next one up */
    uint32_t deaths;     /**< children that died in it */
} mca_dds_child_gap_t;

typedef struct mca_dds_child {
    const char *prog; /**< prefix of the log lines */
    mca_dds_child_main_t main;
    void *arg;
    FILE *log;
    pid_t pid;          /**< the running child, 0: none */
    int fd;             /**< the pipe from it, -1: none */
    int up;             /**< this child said ready */
    int ever_up;        /**< some child said ready */
    unsigned char *buf; /**< received bytes not yet a whole frame */
    size_t len, cap;
    double started_s, next_start_s;
    int quick_deaths; /**< deaths in a row, each within MCA_DDS_BRIDGE_STABLE_S of its start */
    uint64_t starts, deaths;
    int in_gap;
    mca_dds_child_gap_t open; /**< the gap in progress (in_gap) */
    uint32_t n_gaps;          /**< gaps closed (a child up again, or the end) */
    double gap_total_s, gap_max_s;
    mca_dds_child_gap_t gaps[MCA_DDS_CHILD_GAPS]; /**< the first MCA_DDS_CHILD_GAPS of them */
} mca_dds_child_t;

/**
 * Start the first child (fork, then main(fd, arg) in it).
 * @param[out] c    the supervisor's state (caller storage)
 * @param[in]  log  where deaths, restarts and gaps are said (stderr), or NULL
 * @retval 0 @retval -1 no pipe or no fork (errno set)
 */
int mca_dds_child_start(mca_dds_child_t *c, const char *prog, mca_dds_child_main_t main, void *arg,
                        FILE *log);

/**
 * Receive for up to timeout_ms: each whole frame to on_frame; a child that died is reaped and said, and
 * restarted once its back-off has passed.
 * @retval 0 @retval 1 on_frame returned non-zero @retval -1 a child that was never ready exited with a
 *   non-zero status on its own (it said why on stderr): no restart, the program should end
 */
int mca_dds_child_poll(mca_dds_child_t *c, int timeout_ms, mca_dds_child_frame_t on_frame, void *ctx);

/** End: SIGTERM to the child, the frames it still sends to on_frame until it exits (SIGKILL after 5 s), an
 *  open gap closed now. The state stays readable (counts, gaps); then mca_dds_child_free. */
void mca_dds_child_stop(mca_dds_child_t *c, mca_dds_child_frame_t on_frame, void *ctx);

/** Frees what stop left (the frame buffer). */
void mca_dds_child_free(mca_dds_child_t *c);

/** One line with the deaths, restarts and gaps ("DDS child: died 3 times, restarted 3 times; 2 gaps, 1.21 s
 *  without a participant, the longest 0.83 s"). */
void mca_dds_child_describe(const mca_dds_child_t *c, char *buf, size_t len);

/** In the child: its participant is up (the parent closes a gap on it). 0 or -1 (the parent is gone). */
int mca_dds_child_ready(int fd);

/** In the child: one frame of kind (>= 1) whose payload is a then b (b may be NULL). Safe from several
 *  threads only under one lock of the caller. 0 or -1 (the parent is gone). */
int mca_dds_child_send(int fd, uint32_t kind, const void *a, size_t na, const void *b, size_t nb);

/** In the child: 1 once the parent asked it to stop. */
int mca_dds_child_stopping(void);

#ifdef __cplusplus
}
#endif
#endif
