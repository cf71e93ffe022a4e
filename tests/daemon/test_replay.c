/* SPDX-License-Identifier: MIT */
/* Recording and replay (mcad --record, mca/tick_rec.h; daemon/backends/replay): an mca-ts run of cross
 * circles on sim arms, recorded, then played into the loop again through the replay backend, commands the
 * same velocities bit for bit on every tick, the same daemon state, and no budget event in either run. */
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
#include "mca/err.h"
#include "mca/tick_rec.h"

#include "log_sink.h" /* test_log_line */

#ifndef MCA_SOURCE_DIR
#error MCA_SOURCE_DIR must be defined
#endif

#define TICKS 3000 /* 3 s of the task: both arms on their circles, their rows active */

static char dir[64], sim_cell[128], replay_cell[128], rec_path[128];

/* The cell on sim arms, or (rec set) on replay arms playing rec. */
static void write_cell(const char *path, const char *rec) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f,
            "name: replay_test\ntask:\n  scenario: %s/config/scenarios/cross_circles.yaml\nscheme: mca-ts\n",
            MCA_SOURCE_DIR);
    fprintf(f, "arms:\n");
    const char *names[2] = {"left", "right"};
    for (int a = 0; a < 2; a++) {
        if (rec) {
            fprintf(f, "  - name: %s\n    backend: replay\n    replay: {file: %s}\n", names[a], rec);
        } else {
            fprintf(f, "  - name: %s\n    backend: sim\n", names[a]);
        }
    }
    fprintf(f, "dds:\n  enabled: false\n");
    fclose(f);
}

static mca_daemon_t *open_cell(const char *path, const char *record) {
    mca_cell_t *cell = calloc(1, sizeof *cell);
    assert_non_null(cell);
    char err[512] = "";
    int rc = mca_cell_load(path, cell, err, sizeof err);
    if (rc != MCA_OK) {
        fprintf(stderr, "%s\n", err);
    }
    assert_int_equal(rc, MCA_OK);
    const mca_drive_opts_t o = {
        .daemon = {.no_dds = 1, .log = test_log_line, .log_arg = stderr, .record_path = record}};
    mca_daemon_t *d = NULL;
    rc = mca_drive_open(&d, cell, &o, err, sizeof err);
    if (rc != MCA_OK) {
        fprintf(stderr, "%s\n", err);
    }
    assert_int_equal(rc, MCA_OK);
    free(cell);
    return d;
}

static void test_replay_bit_equal(void **state) {
    (void)state;
    /* the recorded run: mcad's tick in virtual time on sim arms */
    mca_daemon_t *d = open_cell(sim_cell, rec_path);
    const double dt = mca_controller_get_config(mca_drive_controller(d))->dt;
    int budget = 0;
    for (int k = 0; k < TICKS; k++) {
        const double t = k * dt;
        assert_int_equal(mca_drive_step(d, t, (int64_t)llround(t * 1e9)), MCA_DAEMON_RUNNING);
        mca_daemon_service(d);
        budget += mca_drive_tick_info(d)->pdnn_budget_hit != MCA_BUDGET_NONE;
    }
    mca_daemon_close(d);
    assert_int_equal(budget, 0);

    mca_tick_rec_file_t rf;
    char err[512] = "";
    assert_int_equal(mca_tick_rec_read(rec_path, &rf, err, sizeof err), MCA_OK);
    assert_int_equal(rf.n, TICKS);
    assert_int_equal(rf.header.n_arms, 2);

    /* the replay: the same cell on replay arms, stepped at the recorded times */
    d = open_cell(replay_cell, NULL);
    int differ = 0, moving = 0;
    for (size_t k = 0; k < rf.n; k++) {
        const mca_tick_rec_t *r = &rf.rec[k];
        assert_int_equal(mca_drive_step(d, r->t, r->stamp_ns), r->state);
        mca_daemon_service(d);
        budget += mca_drive_tick_info(d)->pdnn_budget_hit != MCA_BUDGET_NONE;
        for (int a = 0; a < 2; a++) {
            const mca_arm_command_t *c = mca_drive_last_command(d, a);
            const size_t n = sizeof(double) * (size_t)rf.header.dof[a];
            if (memcmp(c->velocity, r->qdot_cmd[a], n) != 0) {
                if (differ++ == 0) {
                    fprintf(stderr, "tick %zu arm %d: first command that differs\n", k, a);
                }
            }
            moving += fabs(c->velocity[0]) > 1e-3;
        }
    }
    mca_daemon_close(d);
    mca_tick_rec_free(&rf);
    assert_int_equal(differ, 0);
    assert_int_equal(budget, 0);
    assert_true(moving > TICKS / 2); /* the arms moved: the commands compared are not all zero */
}

/* A cell arm on the replay backend needs its recording. */
static void test_replay_needs_file(void **state) {
    (void)state;
    char path[160];
    snprintf(path, sizeof path, "%s/nofile.yaml", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f,
            "name: t\ntask:\n  scenario: %s/config/scenarios/cross_circles.yaml\narms:\n  - name: left\n    "
            "backend: replay\n  - name: right\n    backend: sim\n",
            MCA_SOURCE_DIR);
    fclose(f);
    mca_cell_t *cell = calloc(1, sizeof *cell);
    char err[512] = "";
    assert_int_equal(mca_cell_load(path, cell, err, sizeof err), MCA_EPARSE);
    assert_non_null(strstr(err, "arms[0].replay.file: required"));
    free(cell);
}

int main(void) {
    snprintf(dir, sizeof dir, "/tmp/mca-test-replay-XXXXXX");
    if (!mkdtemp(dir)) {
        return 1;
    }
    snprintf(sim_cell, sizeof sim_cell, "%s/sim.yaml", dir);
    snprintf(replay_cell, sizeof replay_cell, "%s/replay.yaml", dir);
    snprintf(rec_path, sizeof rec_path, "%s/run.rec", dir);
    write_cell(sim_cell, NULL);
    write_cell(replay_cell, rec_path);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_replay_bit_equal),
        cmocka_unit_test(test_replay_needs_file),
    };
    const int rc = cmocka_run_group_tests(tests, NULL, NULL);
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0) {
        return 1;
    }
    return rc;
}
