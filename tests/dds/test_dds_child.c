/* SPDX-License-Identifier: MIT */
/* mca/dds_child.h without DDS: children that send frames and then die as a crashing peer makes them die
 * (SIGSEGV), one cut short in the middle of a frame, one that cannot start. Asserted: every whole frame
 * reaches the parent in order and nothing of a cut frame does; each death is followed by a restart after the
 * bridge's capped back-off (0.1, 0.2, 0.4 s); a gap runs from the death of a child that was up to the next
 * one up and is counted; a child that fails before it was ever ready ends the supervision (-1), one that
 * died of a signal does not; stop takes what the child still sends and ends it. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h> /* setrlimit: no core files */
#include <time.h>
#include <unistd.h>

#include "mca/dds_bridge.h" /* MCA_DDS_BRIDGE_BACKOFF_S */
#include "mca/dds_child.h"

enum { KIND = 7 };

typedef struct script {
    const mca_dds_child_t *c; /* the child's copy tells how many started before it */
    int mode;                 /* 0: crash twice then live; 1: cut a frame short; 2: fail at start-up */
} script_t;

typedef struct got {
    int n;
    uint32_t value[256];
    int bad; /* a frame of another kind or size */
} got_t;

static double now_s(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int on_frame(void *ctx, uint32_t kind, const void *data, size_t len) {
    got_t *g = ctx;
    if (kind != KIND || len != sizeof(uint32_t) || g->n == 256) {
        g->bad++;
        return 0;
    }
    memcpy(&g->value[g->n++], data, sizeof(uint32_t));
    return 0;
}

/* Child k (k children started before it) sends 100 k + 1, 100 k + 2, 100 k + 3 after ready; then, per mode.
 */
static int child_main(int fd, void *arg) {
    const script_t *s = arg;
    const uint32_t k = (uint32_t)s->c->starts;
    if (s->mode == 2) {
        return 1; /* a set-up error, before ready */
    }
    if (mca_dds_child_ready(fd) != 0) {
        return 1;
    }
    for (uint32_t i = 1; i <= 3; ++i) {
        const uint32_t v = 100 * k + i;
        if (mca_dds_child_send(fd, KIND, &v, sizeof v, NULL, 0) != 0) {
            return 1;
        }
    }
    if (s->mode == 0 && k < 2) {
        const struct rlimit none = {0, 0};
        setrlimit(RLIMIT_CORE, &none);
        signal(SIGSEGV, SIG_DFL); /* as Cyclone's thread dies: no handler of ours (nor a sanitizer's) */
        raise(SIGSEGV);
    }
    if (s->mode == 1 && k == 0) {
        /* a header announcing 4 bytes, then 2 of them, then death */
        const uint32_t hdr[2] = {4, KIND};
        const uint16_t half = 0xabcd;
        if (write(fd, hdr, sizeof hdr) != (ssize_t)sizeof hdr || write(fd, &half, sizeof half) != 2) {
            return 1;
        }
        raise(SIGKILL);
    }
    while (!mca_dds_child_stopping()) {
        usleep(1000);
    }
    const uint32_t last = 100 * k + 99; /* sent after the stop request: stop must take it */
    return mca_dds_child_send(fd, KIND, &last, sizeof last, NULL, 0) != 0;
}

static void poll_for(mca_dds_child_t *c, double seconds, got_t *g) {
    const double until = now_s() + seconds;
    while (now_s() < until) {
        assert_int_equal(mca_dds_child_poll(c, 10, on_frame, g), 0);
    }
}

static void test_crash_restart_gaps(void **state) {
    (void)state;
    static mca_dds_child_t c;
    static script_t s = {.c = &c, .mode = 0};
    got_t g = {0};
    FILE *log = tmpfile();
    const double t0 = now_s();
    assert_int_equal(mca_dds_child_start(&c, "test", child_main, &s, log), 0);
    poll_for(&c, 1.5, &g); /* deaths at ~0, restart after 0.1 s, death, restart after 0.2 s, lives */
    mca_dds_child_stop(&c, on_frame, &g);
    const uint32_t want[] = {1, 2, 3, 101, 102, 103, 201, 202, 203, 299};
    assert_int_equal(g.bad, 0);
    assert_int_equal(g.n, 10);
    assert_memory_equal(g.value, want, sizeof want);
    assert_int_equal(c.deaths, 2);
    assert_int_equal(c.starts, 3);
    assert_int_equal(c.n_gaps, 2);
    /* each gap: the back-off of its death (0.1, 0.2 s) plus a fork, within 150 ms on a loaded machine */
    for (int i = 0; i < 2; ++i) {
        const double d = c.gaps[i].to_s - c.gaps[i].from_s;
        const double want_s = MCA_DDS_BRIDGE_BACKOFF_S * (double)(1 << i);
        printf("gap %d: %.3f s (back-off %.1f s), from %.3f s after the start\n", i + 1, d, want_s,
               c.gaps[i].from_s - t0);
        assert_true(d >= want_s && d < want_s + 0.15);
        assert_int_equal(c.gaps[i].deaths, 1);
    }
    char line[256];
    mca_dds_child_describe(&c, line, sizeof line);
    printf("%s\n", line);
    assert_non_null(strstr(line, "died 2 times, restarted 2 times; 2 gaps"));
    rewind(log);
    char text[4096] = "";
    const size_t n = fread(text, 1, sizeof text - 1, log);
    text[n] = '\0';
    fclose(log);
    printf("%s", text);
    assert_non_null(strstr(text, "died: signal 11 (SIGSEGV); restart 1 in 0.1 s"));
    assert_non_null(strstr(text, "died: signal 11 (SIGSEGV); restart 2 in 0.2 s"));
    mca_dds_child_free(&c);
}

static void test_cut_frame_dropped(void **state) {
    (void)state;
    static mca_dds_child_t c;
    static script_t s = {.c = &c, .mode = 1};
    got_t g = {0};
    assert_int_equal(mca_dds_child_start(&c, "test", child_main, &s, NULL), 0);
    poll_for(&c, 0.6, &g);
    mca_dds_child_stop(&c, on_frame, &g);
    const uint32_t want[] = {1, 2, 3, 101, 102, 103, 199};
    assert_int_equal(g.bad, 0); /* the half frame reached nobody, and did not shift the next child's frames */
    assert_int_equal(g.n, 7);
    assert_memory_equal(g.value, want, sizeof want);
    assert_int_equal(c.deaths, 1);
    mca_dds_child_free(&c);
}

static void test_setup_error_ends(void **state) {
    (void)state;
    static mca_dds_child_t c;
    static script_t s = {.c = &c, .mode = 2};
    got_t g = {0};
    assert_int_equal(mca_dds_child_start(&c, "test", child_main, &s, NULL), 0);
    int rc = 0;
    for (int i = 0; i < 500 && rc == 0; ++i) {
        rc = mca_dds_child_poll(&c, 10, on_frame, &g);
    }
    assert_int_equal(rc, -1);
    assert_int_equal(c.starts, 1); /* not restarted */
    assert_int_equal(c.deaths, 0);
    mca_dds_child_stop(&c, on_frame, &g);
    mca_dds_child_free(&c);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crash_restart_gaps),
        cmocka_unit_test(test_cut_frame_dropped),
        cmocka_unit_test(test_setup_error_ends),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
