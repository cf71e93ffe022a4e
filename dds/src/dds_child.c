/* SPDX-License-Identifier: MIT */
/* A program's DDS participant in a supervised child process (mca/dds_child.h): fork, a pipe of frames, the
 * capped back-off of mcad's bridge supervisor (dds__supervise.h), gaps counted. */
#include "mca/dds_child.h"

#include <errno.h>
#include <fcntl.h> /* F_SETPIPE_SZ, O_NONBLOCK */
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h> /* PR_SET_PDEATHSIG */
#include <sys/uio.h>   /* writev */
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "dds__supervise.h" /* mca_dds_backoff_s, mca_dds_describe_status, mca_dds_log_this_death */
#include "mca/dds_bridge.h" /* MCA_DDS_BRIDGE_STABLE_S */

typedef struct frame_hdr {
    uint32_t len; /* payload bytes after the header */
    uint32_t kind;
} frame_hdr_t;

/* A frame larger than this is a child gone wrong, not a sample (the largest, a URDF, is ~100 kB). */
enum { FRAME_MAX = 64u << 20, PIPE_BYTES = 1u << 20 };

static volatile sig_atomic_t g_child_stop;

static void child_on_term(int sig) {
    (void)sig;
    g_child_stop = 1;
}

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

int mca_dds_child_stopping(void) {
    return g_child_stop != 0;
}

static int write_all(int fd, struct iovec *iov, int n) {
    while (n > 0) {
        const ssize_t w = writev(fd, iov, n);
        if (w < 0) {
            if (errno == EINTR) {
                continue;
            }
            return -1;
        }
        size_t left = (size_t)w;
        while (n > 0 && left >= iov[0].iov_len) {
            left -= iov[0].iov_len;
            iov++;
            n--;
        }
        if (n > 0) {
            iov[0].iov_base = (char *)iov[0].iov_base + left;
            iov[0].iov_len -= left;
        }
    }
    return 0;
}

int mca_dds_child_send(int fd, uint32_t kind, const void *a, size_t na, const void *b, size_t nb) {
    if (na + nb > FRAME_MAX) {
        errno = EMSGSIZE;
        return -1;
    }
    frame_hdr_t h = {.len = (uint32_t)(na + nb), .kind = kind};
    struct iovec iov[3] = {{&h, sizeof h}, {(void *)(uintptr_t)a, na}, {(void *)(uintptr_t)b, nb}};
    return write_all(fd, iov, b != NULL && nb > 0 ? 3 : 2);
}

int mca_dds_child_ready(int fd) {
    frame_hdr_t h = {.len = 0, .kind = MCA_DDS_CHILD_READY};
    struct iovec iov[1] = {{&h, sizeof h}};
    return write_all(fd, iov, 1);
}

static void say(const mca_dds_child_t *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void say(const mca_dds_child_t *c, const char *fmt, ...) {
    if (c->log == NULL) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    fprintf(c->log, "%s: ", c->prog);
    vfprintf(c->log, fmt, ap);
    fputc('\n', c->log);
    va_end(ap);
    fflush(c->log);
}

/* The child's side of the fork: never returns. */
static void run_child(mca_dds_child_t *c, int wfd) {
    /* it dies with the parent; Ctrl-C reaches the whole process group, and the parent alone decides when
     * the child stops (SIGTERM), so that it can take what the child still sends */
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGPIPE, &sa, NULL); /* a parent gone: the send fails with EPIPE */
    sa.sa_handler = child_on_term;
    sigaction(SIGTERM, &sa, NULL);
    const int rc = c->main(wfd, c->arg);
    fflush(stderr); /* only its own stream: the parent's files are the parent's */
    _exit(rc);
}

static int spawn(mca_dds_child_t *c) {
    int p[2];
    if (pipe2(p, O_CLOEXEC) != 0) {
        return -1;
    }
    (void)fcntl(p[1], F_SETPIPE_SZ, (int)PIPE_BYTES); /* room for bursts; the default 64 kB if refused */
    fflush(NULL);                                     /* no buffered output written twice */
    const pid_t pid = fork();
    if (pid < 0) {
        const int e = errno;
        close(p[0]);
        close(p[1]);
        errno = e;
        return -1;
    }
    if (pid == 0) {
        close(p[0]);
        run_child(c, p[1]);
    }
    close(p[1]);
    (void)fcntl(p[0], F_SETFL, O_NONBLOCK);
    c->pid = pid;
    c->fd = p[0];
    c->up = 0;
    c->len = 0;
    c->started_s = now_s();
    c->starts++;
    return 0;
}

int mca_dds_child_start(mca_dds_child_t *c, const char *prog, mca_dds_child_main_t main, void *arg,
                        FILE *log) {
    memset(c, 0, sizeof *c);
    c->prog = prog;
    c->main = main;
    c->arg = arg;
    c->log = log;
    c->fd = -1;
    return spawn(c);
}

static void close_gap(mca_dds_child_t *c, double t) {
    if (!c->in_gap) {
        return;
    }
    c->in_gap = 0;
    c->open.to_s = t;
    const double d = t - c->open.from_s;
    if (c->n_gaps < MCA_DDS_CHILD_GAPS) {
        c->gaps[c->n_gaps] = c->open;
    }
    c->n_gaps++;
    c->gap_total_s += d;
    if (d > c->gap_max_s) {
        c->gap_max_s = d;
    }
}

/* Whole frames out of the buffer. */
static int deliver(mca_dds_child_t *c, mca_dds_child_frame_t on_frame, void *ctx) {
    size_t at = 0;
    int rc = 0;
    while (rc == 0 && c->len - at >= sizeof(frame_hdr_t)) {
        frame_hdr_t h;
        memcpy(&h, c->buf + at, sizeof h);
        if (h.len > FRAME_MAX) {
            say(c, "DDS child (pid %d) sent a frame of %u bytes: killing it", (int)c->pid, h.len);
            kill(c->pid, SIGKILL);
            c->len = 0;
            return 0;
        }
        if (c->len - at - sizeof h < h.len) {
            break;
        }
        const unsigned char *payload = c->buf + at + sizeof h;
        if (h.kind == MCA_DDS_CHILD_READY) {
            const double t = now_s();
            if (c->in_gap) {
                if (mca_dds_log_this_death(c->quick_deaths)) {
                    say(c,
                        "DDS child (pid %d) up again (start %llu): %.2f s without a participant, %u death(s)",
                        (int)c->pid, (unsigned long long)c->starts, t - c->open.from_s, c->open.deaths);
                }
                close_gap(c, t);
            }
            c->up = 1;
            c->ever_up = 1;
        } else if (on_frame != NULL) {
            rc = on_frame(ctx, h.kind, payload, h.len);
        }
        at += sizeof h + h.len;
    }
    memmove(c->buf, c->buf + at, c->len - at);
    c->len -= at;
    return rc;
}

/* Read what the pipe holds; 1 at end of file (the child exited), 0 otherwise. */
static int fill(mca_dds_child_t *c) {
    for (;;) {
        if (c->cap - c->len < 65536) {
            const size_t cap = c->cap ? c->cap * 2 : 1u << 20;
            unsigned char *p = realloc(c->buf, cap);
            if (p == NULL) {
                return 0; /* read later */
            }
            c->buf = p;
            c->cap = cap;
        }
        const ssize_t n = read(c->fd, c->buf + c->len, c->cap - c->len);
        if (n > 0) {
            c->len += (size_t)n;
            continue;
        }
        if (n == 0) {
            return 1;
        }
        if (errno != EINTR) {
            return 0; /* EAGAIN: all read */
        }
    }
}

static int reap(pid_t pid) {
    int status = 0;
    for (int i = 0; i < 400; ++i) { /* the pipe closed: the child is exiting */
        const pid_t r = waitpid(pid, &status, WNOHANG);
        if (r == pid || (r < 0 && errno != EINTR)) {
            return status;
        }
        if (i == 200) {
            kill(pid, SIGKILL);
        }
        const struct timespec ms = {0, 10000000};
        nanosleep(&ms, NULL);
    }
    return status;
}

/* The child's pipe ended: reap it and plan the restart. -1: a set-up error of a child never ready. */
static int on_exit_of_child(mca_dds_child_t *c) {
    const double t = now_s();
    const pid_t dead = c->pid;
    const int status = reap(dead);
    close(c->fd);
    c->fd = -1;
    c->pid = 0;
    c->len = 0; /* a frame cut short by the death is dropped */
    char why[96];
    mca_dds_describe_status(status, why, sizeof why);
    if (!c->ever_up && WIFEXITED(status) && WEXITSTATUS(status) != 0) {
        say(c, "DDS child (pid %d) could not start: %s", (int)dead, why);
        return -1;
    }
    c->deaths++;
    c->quick_deaths = t - c->started_s < MCA_DDS_BRIDGE_STABLE_S ? c->quick_deaths + 1 : 1;
    if (c->up && !c->in_gap) {
        c->in_gap = 1;
        c->open.from_s = t;
        c->open.deaths = 0;
    }
    if (c->in_gap) {
        c->open.deaths++;
    }
    c->up = 0;
    const double delay = mca_dds_backoff_s(c->quick_deaths);
    c->next_start_s = t + delay;
    if (mca_dds_log_this_death(c->quick_deaths)) {
        say(c,
            "DDS child (pid %d) died: %s; restart %llu in %.1f s (%d deaths in a row; what was received is "
            "kept)%s",
            (int)dead, why, (unsigned long long)c->starts, delay, c->quick_deaths,
            c->quick_deaths == MCA_DDS_BRIDGE_LOG_ALL
                ? "; it is restarted for as long as this program runs, from now on only some deaths are said"
                : "");
    }
    return 0;
}

int mca_dds_child_poll(mca_dds_child_t *c, int timeout_ms, mca_dds_child_frame_t on_frame, void *ctx) {
    if (c->fd < 0) {
        const double wait = c->next_start_s - now_s();
        if (wait > 0.0) {
            const double ms = wait * 1e3 < (double)timeout_ms ? wait * 1e3 : (double)timeout_ms;
            const struct timespec ts = {(time_t)(ms / 1e3),
                                        (long)((ms - 1e3 * (double)(time_t)(ms / 1e3)) * 1e6)};
            nanosleep(&ts, NULL);
            return 0;
        }
        if (spawn(c) != 0) {
            c->quick_deaths++;
            c->next_start_s = now_s() + MCA_DDS_BRIDGE_BACKOFF_MAX_S;
            say(c, "DDS child: cannot start one (%s): next try in %.1f s", strerror(errno),
                MCA_DDS_BRIDGE_BACKOFF_MAX_S);
            return 0;
        }
    }
    struct pollfd p = {.fd = c->fd, .events = POLLIN};
    (void)poll(&p, 1, timeout_ms);
    const int eof = fill(c);
    const int rc = deliver(c, on_frame, ctx);
    if (rc != 0) {
        return 1;
    }
    if (eof) {
        return on_exit_of_child(c);
    }
    return 0;
}

void mca_dds_child_stop(mca_dds_child_t *c, mca_dds_child_frame_t on_frame, void *ctx) {
    if (c->pid > 0) {
        kill(c->pid, SIGTERM);
        const double until = now_s() + 5.0;
        int eof = 0;
        while (!eof && now_s() < until) {
            struct pollfd p = {.fd = c->fd, .events = POLLIN};
            (void)poll(&p, 1, 50);
            eof = fill(c);
            (void)deliver(c, on_frame, ctx);
        }
        if (!eof) {
            kill(c->pid, SIGKILL);
        }
        (void)reap(c->pid);
        close(c->fd);
        c->fd = -1;
        c->pid = 0;
    }
    close_gap(c, now_s());
}

void mca_dds_child_free(mca_dds_child_t *c) {
    free(c->buf);
    c->buf = NULL;
    c->len = c->cap = 0;
}

void mca_dds_child_describe(const mca_dds_child_t *c, char *buf, size_t len) {
    snprintf(buf, len,
             "DDS child: died %llu times, restarted %llu times; %u gaps, %.2f s without a participant, the "
             "longest %.2f s",
             (unsigned long long)c->deaths, (unsigned long long)(c->starts > 0 ? c->starts - 1 : 0),
             c->n_gaps, c->gap_total_s, c->gap_max_s);
}
