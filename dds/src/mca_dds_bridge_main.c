/* SPDX-License-Identifier: MIT */
/* mca-dds-bridge: the DDS publisher process of mcad. mcad starts it with posix_spawn, the shared
 * region (dds_shm.h: snapshot ring, futex word, counters, stream-target mailboxes, settings) as a memfd on
 * --shm-fd; it alone owns a DDS participant, so a crash inside Cyclone (a peer on the network can cause one,
 * docs/dds.md) ends this process and not the controller. It publishes until mcad sets the region's stop
 * flag (then: what is queued, the final status, exit 0); it dies with mcad (PR_SET_PDEATHSIG). Not meant to
 * be run by hand: mcad finds it next to itself or in libexec/mca and restarts it (docs/daemon.md). */
#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/prctl.h> /* PR_SET_PDEATHSIG */
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "dds_shm.h"
#include "mca/dds_qos.h" /* mca_dds_log_capture, mca_dds_log_drain */
#include "mca/err.h"

#define PREFIX "mca-dds-bridge: "

static void usage(void) {
    fprintf(stderr, "usage: mca-dds-bridge --shm-fd FD [--owner PID]   (started by mcad, not by hand)\n");
}

/* Cyclone's own messages, printed from here so that a slow stderr never holds the publisher. They are mcad's
 * DDS side's, so they read as they did when DDS ran inside mcad: "<4>mcad: dds: ..." (operators' and tests'
 * patterns keep working). Before the DDS set-up has succeeded they stay queued: a failed set-up prints them
 * as errors ("<3>mcad: dds: ...", the reason mcad's start-up failed: a missing security file, a bad XML). */
static atomic_int drain_stop;

/* Cyclone's messages, as mcad's (this process speaks for mcad's DDS side): "<LEVEL>mcad: dds: TEXT". */
static void cyclone_line(void *arg, int level, const char *text) {
    (void)arg;
    fprintf(stderr, "<%d>mcad: dds: %s\n", level, text);
}

static void *drain_main(void *arg) {
    const mca_dds_shm_t *shm = arg;
    while (!atomic_load(&drain_stop)) {
        const struct timespec nap = {0, 200 * 1000 * 1000};
        nanosleep(&nap, NULL);
        if (atomic_load_explicit(&shm->ready_gen, memory_order_acquire) ==
                atomic_load_explicit(&shm->start_gen, memory_order_acquire) &&
            atomic_load_explicit(&shm->open_rc, memory_order_acquire) == MCA_OK) {
            mca_dds_log_drain(4, cyclone_line, NULL);
        }
    }
    return NULL;
}

int main(int argc, char **argv) {
    int fd = -1;
    long owner = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--shm-fd") == 0 && i + 1 < argc) {
            fd = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--owner") == 0 && i + 1 < argc) {
            owner = atol(argv[++i]);
        } else {
            usage();
            return 2;
        }
    }
    if (fd < 0) {
        usage();
        return 2;
    }
    setvbuf(stderr, NULL, _IOLBF, 0);
    /* mcad takes Ctrl-C and SIGHUP for the whole cell and ends this process through the region; SIGTERM (an
     * operator, systemd's KillMode=control-group) ends it as any signal would: mcad logs it and restarts it
     */
    signal(SIGINT, SIG_IGN);
    signal(SIGHUP, SIG_IGN);
    signal(SIGPIPE, SIG_IGN);
    if (owner > 0) {
        prctl(PR_SET_PDEATHSIG, SIGKILL); /* mcad gone: nothing left to publish */
        if (getppid() != (pid_t)owner) {
            return 1; /* it died before the line above */
        }
    }
    prctl(PR_SET_NAME, "mca-dds-bridge");
    struct stat st;
    if (fstat(fd, &st) != 0 || st.st_size <= 0) {
        fprintf(stderr, "<3>" PREFIX "fd %d is not the shared region: %s\n", fd, strerror(errno));
        return 1;
    }
    const size_t size = (size_t)st.st_size;
    mca_dds_shm_t *shm = mmap(NULL, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    if (shm == MAP_FAILED || mca_dds_shm_check(shm, size) != MCA_OK) {
        fprintf(stderr, "<3>" PREFIX "fd %d: not a shared region of this version\n", fd);
        return 1;
    }
    close(fd);
    mca_dds_log_capture(1);
    pthread_t drain;
    const int drain_started = pthread_create(&drain, NULL, drain_main, shm) == 0;
    const int rc = mca_dds_publisher_process(shm);
    atomic_store(&drain_stop, 1);
    if (drain_started) {
        pthread_join(drain, NULL); /* one drainer at a time (mca_dds_log_drain) */
    }
    mca_dds_log_drain(rc == MCA_OK ? 4 : 3, cyclone_line, NULL);
    if (rc != MCA_OK) {
        fprintf(stderr, "<3>" PREFIX "DDS set-up failed: %s: %.*s\n", mca_strerror(rc),
                (int)sizeof shm->open_err, shm->open_err);
        return 1;
    }
    return 0;
}
