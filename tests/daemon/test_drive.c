/* SPDX-License-Identifier: MIT */
/* The virtual-time driver (mca/daemon_drive.h) against the production library: what it promises beyond the
 * daemon's own tick, each checked so that taking it out fails here:
 *   - ideal arms: each tick's positions are the last ones plus the last command times dt, exactly; the same
 *     cell on plain sim arms is not (the control);
 *   - a stop and a fault scheduled at a task time act before the first tick at or after it, not before;
 *   - a driven daemon refuses mca_daemon_start; an ideal arm off the sim backend is refused at open;
 *   - the library prints nothing: its lines go to the caller's sink only. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h> /* dup, dup2 */

#include "mca/cell.h"
#include "mca/daemon.h"
#include "mca/daemon_drive.h"
#include "mca/err.h"
#include "mca/scenario.h"

#include "log_sink.h" /* test_log_line */

#ifndef MCA_SOURCE_DIR
#error MCA_SOURCE_DIR must be defined
#endif

/* cross circles under mca, every arm on the sim backend (as mca-sim builds it) */
static mca_cell_t *scenario_cell(void) {
    static mca_scenario_t scn;
    char err[512] = "";
    if (mca_scenario_load(MCA_SOURCE_DIR "/config/scenarios/cross_circles.yaml", &scn, err, sizeof err) !=
        MCA_OK) {
        fail_msg("%s", err);
    }
    mca_cell_t *cell = calloc(1, sizeof *cell);
    assert_non_null(cell);
    assert_int_equal(mca_cell_from_scenario(cell, &scn, MCA_SCHEME_MCA), MCA_OK);
    return cell;
}

static mca_daemon_t *open_driven(const mca_cell_t *cell, uint32_t ideal) {
    const mca_drive_opts_t o = {.daemon = {.no_dds = 1, .log = test_log_line, .log_arg = stderr},
                                .ideal_arms = ideal};
    mca_daemon_t *d = NULL;
    char err[512] = "";
    if (mca_drive_open(&d, cell, &o, err, sizeof err) != MCA_OK) {
        fail_msg("%s", err);
    }
    return d;
}

/* The largest |q_k - (q_{k-1} + cmd_{k-1} dt)| over 300 ticks of the task's start (every arm moving). */
static double euler_residual(mca_daemon_t *d, double dt) {
    const int na = mca_controller_get_config(mca_drive_controller(d))->n_arms;
    double q[MCA_MAX_ARMS][MCA_MAX_DOF], v[MCA_MAX_ARMS][MCA_MAX_DOF], worst = 0.0, moved = 0.0;
    for (int k = 0; k < 300; k++) {
        const double t = k * dt;
        assert_int_equal(mca_drive_step(d, t, (int64_t)llround(t * 1e9)), MCA_DAEMON_RUNNING);
        for (int a = 0; a < na; a++) {
            const double *p = mca_drive_positions(d, a);
            const mca_arm_command_t *c = mca_drive_last_command(d, a);
            for (int j = 0; j < c->n; j++) {
                if (k > 0) {
                    worst = fmax(worst, fabs(p[j] - (q[a][j] + v[a][j] * dt)));
                    moved = fmax(moved, fabs(p[j] - q[a][j]));
                }
                q[a][j] = p[j];
                v[a][j] = c->velocity[j];
            }
        }
    }
    assert_true(moved > 1e-6); /* the arms moved: the residual is not of arms at rest */
    return worst;
}

static void test_ideal_arms(void **state) {
    (void)state;
    mca_cell_t *cell = scenario_cell();
    const double dt = (double)cell->rt.period_ns * 1e-9;
    mca_daemon_t *d = open_driven(cell, 3u);
    const double ideal = euler_residual(d, dt);
    mca_daemon_close(d);
    d = open_driven(cell, 0u);
    const double plain = euler_residual(d, dt);
    mca_daemon_close(d);
    print_message("  q_k - (q_k-1 + cmd_k-1 dt): ideal arms %.3g rad, sim arms %.3g rad\n", ideal, plain);
    assert_true(ideal <= 1e-15);
    assert_true(plain > 1e-9);
    free(cell);
}

static void test_schedule(void **state) {
    (void)state;
    mca_cell_t *cell = scenario_cell();
    const double dt = (double)cell->rt.period_ns * 1e-9;
    /* a stop at 0.1 s: RUNNING through tick 99, braking from tick 100 */
    mca_daemon_t *d = open_driven(cell, 0u);
    mca_drive_stop_at(d, 0.1);
    for (int k = 0; k <= 100; k++) {
        const double t = k * dt;
        const int st = mca_drive_step(d, t, (int64_t)llround(t * 1e9));
        assert_int_equal(st, k < 100 ? MCA_DAEMON_RUNNING : MCA_DAEMON_BRAKING);
        assert_int_equal(mca_drive_fired(d), k < 100 ? 0u : (unsigned)MCA_DRIVE_STOPPED);
    }
    mca_daemon_close(d);
    /* a controller fault at 0.05 s: latched at tick 50, not before, named as injected */
    d = open_driven(cell, 0u);
    mca_drive_fault_at(d, MCA_CTRL_FAULT_NAN, 0.05);
    for (int k = 0; k <= 50; k++) {
        const double t = k * dt;
        const int st = mca_drive_step(d, t, (int64_t)llround(t * 1e9));
        if (k < 50) {
            assert_int_equal(st, MCA_DAEMON_RUNNING);
        } else { /* braking, done at once when the arms were barely moving */
            assert_true(st == MCA_DAEMON_BRAKING || st == MCA_DAEMON_FAULT);
        }
    }
    assert_int_equal(mca_drive_fired(d), (unsigned)MCA_DRIVE_FAULTED);
    mca_daemon_summary_t s;
    mca_daemon_summary(d, &s);
    print_message("  fault: %s\n", s.fault_text);
    assert_int_equal(s.fault, MCA_DAEMON_FAULT_CONTROLLER);
    assert_non_null(strstr(s.fault_text, "injected fault nan at t = 0.050 s"));
    /* one thread ticks a driven daemon: the loop refuses to start */
    assert_int_equal(mca_daemon_start(d), MCA_EINVAL);
    mca_daemon_close(d);
    free(cell);
}

/* A fault at 0.05 s, its lines drained, the summary logged, the daemon closed: every line to `sink`. */
static void run_and_log(const mca_cell_t *cell, mca_log_fn sink, void *arg) {
    const double dt = (double)cell->rt.period_ns * 1e-9;
    const mca_drive_opts_t o = {.daemon = {.no_dds = 1, .log = sink, .log_arg = arg}};
    mca_daemon_t *d = NULL;
    char err[512] = "";
    if (mca_drive_open(&d, cell, &o, err, sizeof err) != MCA_OK) {
        fail_msg("%s", err);
    }
    mca_drive_fault_at(d, MCA_CTRL_FAULT_NAN, 0.05);
    for (int k = 0; k <= 60; k++) {
        const double t = k * dt;
        mca_drive_step(d, t, (int64_t)llround(t * 1e9));
        mca_daemon_service(d);
    }
    mca_daemon_summary_t s;
    mca_daemon_summary(d, &s);
    mca_daemon_log_summary(&s, sink, arg);
    mca_daemon_close(d);
}

/* The library prints nothing: without a sink a run that faults leaves stdout and stderr empty; with one,
 * its lines (the fault, the summary) reach the sink. */
static void test_lines_only_to_the_sink(void **state) {
    (void)state;
    mca_cell_t *cell = scenario_cell();
    FILE *out = tmpfile(), *errf = tmpfile();
    assert_true(out && errf);
    fflush(stdout);
    fflush(stderr);
    const int saved_out = dup(1), saved_err = dup(2);
    assert_true(saved_out >= 0 && saved_err >= 0);
    assert_int_equal(dup2(fileno(out), 1), 1);
    assert_int_equal(dup2(fileno(errf), 2), 2);
    run_and_log(cell, NULL, NULL);
    fflush(stdout);
    fflush(stderr);
    dup2(saved_out, 1);
    dup2(saved_err, 2);
    close(saved_out);
    close(saved_err);
    fseek(out, 0, SEEK_END);
    fseek(errf, 0, SEEK_END);
    print_message("  without a sink: %ld bytes on stdout, %ld on stderr\n", ftell(out), ftell(errf));
    assert_int_equal(ftell(out), 0);
    assert_int_equal(ftell(errf), 0);
    fclose(out);
    fclose(errf);
    char *text = NULL;
    size_t len = 0;
    FILE *mf = open_memstream(&text, &len);
    assert_non_null(mf);
    run_and_log(cell, test_log_line, mf);
    fclose(mf);
    print_message("  with a sink: %zu bytes\n", len);
    assert_non_null(strstr(text, "<3>mcad: summary: faults: 1 (at t = 0.050 s: injected fault nan"));
    assert_non_null(strstr(text, "<6>mcad: summary: state "));
    free(text);
    free(cell);
}

static void test_ideal_needs_sim(void **state) {
    (void)state;
    mca_cell_t *cell = scenario_cell();
    cell->arm[1].backend = mca_cell_backend_id("socketcan");
    const mca_drive_opts_t o = {.daemon = {.no_dds = 1, .log = test_log_line, .log_arg = stderr},
                                .ideal_arms = 2u};
    mca_daemon_t *d = NULL;
    char err[512] = "";
    assert_int_equal(mca_drive_open(&d, cell, &o, err, sizeof err), MCA_EINVAL);
    assert_null(d);
    print_message("  %s\n", err);
    assert_non_null(strstr(err, "arm 1: an ideal arm must be a sim backend arm"));
    free(cell);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ideal_arms),
        cmocka_unit_test(test_schedule),
        cmocka_unit_test(test_ideal_needs_sim),
        cmocka_unit_test(test_lines_only_to_the_sink),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
