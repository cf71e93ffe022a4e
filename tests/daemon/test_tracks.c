/* SPDX-License-Identifier: MIT */
/* Streamed bodies in the daemon, in virtual time (mca/daemon_drive.h; the tracks from
 * the driver's mca_drive_put_tracks in place of the DDS bridge):
 *   - a sphere streamed fresh, then silent: it grows once older than max_age (the controller's body is
 *     radius + growth of its age, measured from the last message), and after lost_after the arms brake to
 *     rest on their paths as the named fault "streamed bodies lost", never below d1 of each other nor inside
 *     S_p of the grown body; the same run with the stream never silent keeps running (the control);
 *   - a plain cell (no DDS Security) that declares streamed bodies is refused with FILE:LINE: field. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mca/cell.h"
#include "mca/daemon.h"
#include "mca/daemon_drive.h"
#include "log_sink.h" /* test_log_line */
#include "mca/daemon_test.h"
#include "mca/err.h"
#include "mca/scenario.h"
#include "mca/track.h"

#ifndef MCA_SOURCE_DIR
#error MCA_SOURCE_DIR must be defined
#endif

/* cross circles under mca-ts, sim arms, one streamed body */
static mca_cell_t *tracks_cell(void) {
    static mca_scenario_t scn;
    char err[512] = "";
    if (mca_scenario_load(MCA_SOURCE_DIR "/config/scenarios/cross_circles.yaml", &scn, err, sizeof err) !=
        MCA_OK) {
        fail_msg("%s", err);
    }
    mca_cell_t *cell = calloc(1, sizeof *cell);
    assert_non_null(cell);
    assert_int_equal(mca_cell_from_scenario(cell, &scn, MCA_SCHEME_MCA_TS), MCA_OK);
    cell->tracks.enabled = 1;
    cell->tracks.max_bodies = 1;
    snprintf(cell->tracks.topic, sizeof cell->tracks.topic, "tracked_bodies");
    mca_ssm_default(&cell->tracks.ssm);
    return cell;
}

/* A person 4 m from the arms' bases, walking slowly (a sphere of 0.3 m). */
static void put_person(mca_daemon_t *d, uint64_t n, int64_t recv_ns) {
    mca_ros2_tracks_t t = {.n = 1, .recv_ns = recv_ns, .accepted = n};
    t.body[0] = (mca_track_t){.id = 7,
                              .kind = MCA_BODY_SPHERE,
                              .a = {4.0, 0.0, 0.9},
                              .radius = 0.3,
                              .v = {-0.1, 0.0, 0.0},
                              .stamp = 0.02}; /* seen 20 ms before it was sent */
    mca_drive_put_tracks(d, &t);
}

typedef struct run {
    int state;                      /* at the end */
    int fault;                      /* mca_daemon_fault_t */
    char fault_text[256];           /* as the summary says it */
    double fault_t;                 /* first braking tick */
    double rest_t;                  /* first FAULT tick */
    double min_d;                   /* arm-arm over the run */
    double min_margin;              /* arm-body d - S_p over the run */
    double path_err_brake;          /* largest path error while braking */
    double radius_end, growth_want; /* the body at the last tick that moved the arms, and its closed form */
    double last_msg;
} run_t;

/* 3 s at 1 kHz: the person streamed at 100 Hz until silent_at (never: INFINITY). */
static void drive(double silent_at, run_t *r) {
    mca_cell_t *cell = tracks_cell();
    const double dt = (double)cell->rt.period_ns * 1e-9;
    const mca_drive_opts_t o = {.daemon = {.no_dds = 1, .log = test_log_line, .log_arg = stderr}};
    mca_daemon_t *d = NULL;
    char err[512] = "";
    if (mca_drive_open(&d, cell, &o, err, sizeof err) != MCA_OK) {
        fail_msg("%s", err);
    }
    const double d1 = mca_controller_get_config(mca_drive_controller(d))->sp.d1;
    memset(r, 0, sizeof *r);
    r->min_d = r->min_margin = INFINITY;
    r->fault_t = r->rest_t = -1.0;
    uint64_t n = 0;
    double last_msg = 0.0;
    for (int k = 0; k < 3000; k++) {
        const double t = k * dt;
        const int64_t stamp = (int64_t)llround(t * 1e9);
        if (k % 10 == 0 && t < silent_at) {
            put_person(d, ++n, stamp);
            last_msg = t;
        }
        const int st = mca_drive_step(d, t, stamp);
        const mca_tick_info_t *in = mca_drive_tick_info(d);
        if (isfinite(in->min_distance)) {
            r->min_d = fmin(r->min_d, in->min_distance);
        }
        if (in->body_index >= 0) {
            r->min_margin = fmin(r->min_margin, in->body_margin);
        }
        if (st == MCA_DAEMON_BRAKING && r->fault_t < 0.0) {
            r->fault_t = t;
        }
        if (st == MCA_DAEMON_BRAKING) {
            for (int a = 0; a < in->n_arms; a++) {
                r->path_err_brake = fmax(r->path_err_brake, in->path_error[a]);
            }
        }
        if (st == MCA_DAEMON_FAULT && r->rest_t < 0.0) {
            r->rest_t = t;
        }
        r->state = st;
        if (st == MCA_DAEMON_RUNNING || st == MCA_DAEMON_BRAKING) {
            /* the tracks follow the arms' motion: updated while they may move */
            const mca_controller_config_t *c = mca_controller_get_config(mca_drive_controller(d));
            r->radius_end = c->body[0].body.u.sphere.radius;
            r->growth_want = 0.3 + mca_track_growth(&c->ssm, t - last_msg + 0.02);
            r->last_msg = last_msg;
        }
    }
    assert_true(r->min_d >= d1);
    mca_daemon_summary_t s;
    mca_daemon_summary(d, &s);
    r->fault = s.fault;
    snprintf(r->fault_text, sizeof r->fault_text, "%s", s.fault_text);
    mca_daemon_close(d);
    free(cell);
}

static void test_lost_stream_stops(void **state) {
    (void)state;
    run_t r;
    drive(0.5, &r); /* silent from 0.5 s: stale at ~0.6 s, lost at ~1.0 s */
    print_message(
        "  silent at 0.5 s: braking from %.3f s, at rest %.3f s, fault %d '%s'; least arm-arm %.4f m, "
        "least body margin %.4f m, path error braking %.2e m; radius %.4f m (want %.4f)\n",
        r.fault_t, r.rest_t, r.fault, r.fault_text, r.min_d, r.min_margin, r.path_err_brake, r.radius_end,
        r.growth_want);
    assert_int_equal(r.fault, MCA_DAEMON_FAULT_TRACKS_LOST);
    assert_non_null(strstr(r.fault_text, "streamed bodies lost"));
    /* lost after lost_after (0.5 s) of silence since the last message (0.49 s): the first tick past 0.99 s */
    assert_true(fabs(r.last_msg - 0.49) < 1e-9);
    assert_true(r.fault_t > 0.99 - 1e-9 && r.fault_t < 0.99 + 0.0015);
    assert_int_equal(r.state, MCA_DAEMON_FAULT);
    assert_true(r.rest_t > r.fault_t && r.rest_t < r.fault_t + 1.0);
    assert_true(r.min_margin >= 0.0);     /* never inside S_p of the (grown) body */
    assert_true(r.path_err_brake < 2e-3); /* braked on the paths */
    /* the body kept growing while braking: radius + growth of its age since the last message */
    assert_true(r.radius_end > 0.3 + 0.5);
    assert_true(fabs(r.radius_end - r.growth_want) < 1e-6);

    /* the control: never silent, still running at 3 s, no fault, the body never grown */
    drive(INFINITY, &r);
    assert_int_equal(r.state, MCA_DAEMON_RUNNING);
    assert_int_equal(r.fault, MCA_DAEMON_FAULT_NONE);
    assert_true(fabs(r.radius_end - 0.3) < 1e-12);
}

/* A plain cell (dds.config without <Security>, or none) that declares streamed bodies: refused at load. */
static void test_plain_cell_refused(void **state) {
    (void)state;
    char path[] = "/tmp/mca_tracks_cell_XXXXXX.yaml";
    const int fd = mkstemps(path, 5);
    assert_true(fd >= 0);
    FILE *f = fdopen(fd, "w");
    assert_non_null(f);
    fprintf(f,
            "name: plain_tracks\n"
            "task:\n"
            "  scenario: %s/config/scenarios/cross_circles.yaml\n"
            "arms:\n"
            "  - name: left\n"
            "    backend: sim\n"
            "  - name: right\n"
            "    backend: sim\n"
            "dds:\n"
            "  enabled: true\n"
            "  config: %s/config/dds/ros2.xml\n"
            "streamed_bodies:\n"
            "  lost_after: 0.5\n",
            MCA_SOURCE_DIR, MCA_SOURCE_DIR);
    fclose(f);
    static mca_cell_t cell;
    char err[512] = "", want[600];
    assert_int_equal(mca_cell_load(path, &cell, err, sizeof err), MCA_ECONFIG);
    snprintf(want, sizeof want, "%s:12: streamed_bodies: ", path);
    print_message("  %s\n", err);
    assert_true(strncmp(err, want, strlen(want)) == 0);
    assert_non_null(strstr(err, "DDS Security"));
    /* the same cell with the secure configuration loads, its keys read */
    f = fopen(path, "w");
    fprintf(f,
            "name: secure_tracks\n"
            "task:\n"
            "  scenario: %s/config/scenarios/cross_circles.yaml\n"
            "arms:\n"
            "  - name: left\n"
            "    backend: sim\n"
            "  - name: right\n"
            "    backend: sim\n"
            "dds:\n"
            "  enabled: true\n"
            "  config: %s/config/dds/secure.xml\n"
            "streamed_bodies:\n"
            "  lost_after: 0.4\n"
            "  max_age: 0.5\n",
            MCA_SOURCE_DIR, MCA_SOURCE_DIR);
    fclose(f);
    assert_int_equal(mca_cell_load(path, &cell, err, sizeof err), MCA_ECONFIG);
    snprintf(want, sizeof want, "%s:13: streamed_bodies.lost_after: ", path);
    assert_true(strncmp(err, want, strlen(want)) == 0);
    f = fopen(path, "w");
    fprintf(f,
            "name: secure_tracks\n"
            "task:\n"
            "  scenario: %s/config/scenarios/cross_circles.yaml\n"
            "arms:\n"
            "  - name: left\n"
            "    backend: sim\n"
            "  - name: right\n"
            "    backend: sim\n"
            "dds:\n"
            "  enabled: true\n"
            "  config: %s/config/dds/secure.xml\n"
            "streamed_bodies:\n"
            "  lost_after: 0.4\n"
            "  latency: 0.05\n",
            MCA_SOURCE_DIR, MCA_SOURCE_DIR);
    fclose(f);
    if (mca_cell_load(path, &cell, err, sizeof err) != MCA_OK) {
        fail_msg("%s", err);
    }
    assert_true(cell.tracks.enabled && cell.tracks.ssm.lost_after == 0.4 && cell.tracks.ssm.latency == 0.05);
    assert_true(cell.tracks.ssm.max_age == 0.1 && cell.tracks.max_bodies == MCA_MAX_TRACKS);
    unlink(path);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lost_stream_stops),
        cmocka_unit_test(test_plain_cell_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
