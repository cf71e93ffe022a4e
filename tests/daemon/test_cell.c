/* SPDX-License-Identifier: MIT */
/* Cell files: a good cell loads with the values written in it; each kind of bad cell fails with its own
 * message naming the file, the line (found independently in the generated text) and the field.
 * Built twice: test_cell against the production library (debug_* keys are refused, naming the line) and
 * test_cell_hooks against the test build (MCA_TEST_HOOKS: the keys load). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <glob.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mca/cell.h"
#include "mca/err.h"

#ifndef MCA_SOURCE_DIR
#error MCA_SOURCE_DIR must be defined
#endif

static char tmpdir[256];

/* The good cell; bad variants replace one exact piece of it. */
static const char *good_cell(void) {
    static char buf[4096];
    snprintf(buf, sizeof buf,
             "# test cell\n"
             "name: unit-cell\n"
             "task:\n"
             "  duration: 3.5\n"
             "scheme: mvn\n"
             "d1: 0.04\n"
             "d2: 0.15\n"
             "solver:\n"
             "  K: 12\n"
             "  pdnn_max_steps: 321\n"
             "arms:\n"
             "  - name: left\n"
             "    backend: sim\n"
             "    urdf: %s/config/robots/pa10plus.urdf\n"
             "    base_xyz: [0.0, -0.6, 0.1]\n"
             "    base_rpy: [0.0, 0.0, 1.5]\n"
             "    q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]\n"
             "    dec_limit: 4.0\n"
             "  - name: right\n"
             "    backend: socketcan\n"
             "    interface: vcan1\n"
             "    id_base: 0x140\n"
             "    urdf: %s/config/robots/pa10plus.urdf\n"
             "    base_xyz: [0.0, 0.6, 0.0]\n"
             "    q0: [0.1, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]\n"
             "    path: {kind: circle, radius: 0.1, period: 3.0, u: [1, 0, 0], v: [0, 0, 1]}\n"
             "dds:\n"
             "  enabled: false\n"
             "  domain: 7\n"
             "  publish_divisor: 4\n"
             "rt:\n"
             "  period_us: 2000\n"
             "  priority: 70\n"
             "  overrun_limit: 3\n"
             "  lost_feedback_cycles: 6\n"
             "stop_after: 1.5\n",
             MCA_SOURCE_DIR, MCA_SOURCE_DIR);
    return buf;
}

/* Write the good cell with `from` replaced by `to` (from must occur); returns the file name. */
static const char *write_variant(const char *name, const char *from, const char *to) {
    static char path[512];
    const char *g = good_cell();
    char text[4096];
    if (from) {
        const char *at = strstr(g, from);
        assert_non_null(at);
        snprintf(text, sizeof text, "%.*s%s%s", (int)(at - g), g, to, at + strlen(from));
    } else {
        snprintf(text, sizeof text, "%s", g);
    }
    snprintf(path, sizeof path, "%s/%s.yaml", tmpdir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    return path;
}

/* 1-based line of the first line containing `needle` in the file. */
static int line_of(const char *path, const char *needle) {
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char buf[1024];
    int line = 0, found = 0;
    while (fgets(buf, sizeof buf, f)) {
        line++;
        if (strstr(buf, needle)) {
            found = line;
            break;
        }
    }
    fclose(f);
    return found;
}

static mca_cell_t cell;

/* Load `path`, expect rc, and expect "path:LINE:" and every given piece in the message. */
static void expect_error(const char *path, int rc_want, int line, ...) {
    char err[1024] = "";
    const int rc = mca_cell_load(path, &cell, err, sizeof err);
    print_message("  %s\n", err);
    assert_int_equal(rc, rc_want);
    char prefix[600];
    snprintf(prefix, sizeof prefix, "%s:%d:", path, line);
    if (strncmp(err, prefix, strlen(prefix)) != 0) {
        fail_msg("message '%s' does not start with '%s'", err, prefix);
    }
    va_list ap;
    va_start(ap, line);
    for (const char *piece = va_arg(ap, const char *); piece; piece = va_arg(ap, const char *)) {
        if (!strstr(err, piece)) {
            fail_msg("message '%s' lacks '%s'", err, piece);
        }
    }
    va_end(ap);
}

static void test_good_cell(void **state) {
    (void)state;
    const char *p = write_variant("good", NULL, NULL);
    char err[1024] = "";
    int rc = mca_cell_load(p, &cell, err, sizeof err);
    if (rc != MCA_OK) {
        fail_msg("%s", err);
    }
    assert_string_equal(cell.name, "unit-cell");
    assert_int_equal(cell.scheme, MCA_SCHEME_MVN);
    assert_int_equal(cell.scn.n_arms, 2);
    assert_true(cell.scn.duration == 3.5);
    assert_true(cell.scn.params.d1 == 0.04 && cell.scn.params.d2 == 0.15 && cell.scn.params.K == 12.0);
    assert_int_equal(cell.pdnn_max_steps, 321);
    assert_string_equal(cell.scn.arm[0].name, "left");
    assert_int_equal(cell.arm[0].backend, MCA_CELL_BACKEND_SIM);
    assert_true(cell.arm[0].dec_limit[0] == 4.0 && cell.arm[0].dec_limit[7] == 4.0);
    assert_true(cell.scn.arm[0].base_xyz[1] == -0.6 && cell.scn.arm[0].base_xyz[2] == 0.1);
    assert_true(cell.scn.arm[0].base_rpy[2] == 1.5);
    assert_int_equal(cell.scn.arm[0].n_q0, 8);
    assert_true(cell.scn.arm[0].q0[3] == 0.8);
    assert_int_equal(cell.scn.arm[0].path.kind, MCA_PATH_HOLD);
    assert_int_equal(cell.arm[1].backend, MCA_CELL_BACKEND_SOCKETCAN);
    assert_string_equal(cell.arm[1].interface, "vcan1");
    assert_int_equal(cell.arm[1].id_base, 0x140);
    assert_true(cell.arm[1].dec_limit[0] == 10.0); /* default */
    assert_true(cell.scn.arm[1].q0[0] == 0.1);
    assert_int_equal(cell.scn.arm[1].path.kind, MCA_PATH_CIRCLE);
    assert_true(cell.scn.arm[1].path.radius == 0.1 && cell.scn.arm[1].path.period == 3.0);
    assert_true(cell.scn.arm[1].path.v[2] == 1.0);
    assert_int_equal(cell.dds.enabled, 0);
    assert_int_equal(cell.dds.domain, 7);
    assert_int_equal(cell.dds.publish_divisor, 4);
    assert_true(cell.rt.period_ns == 2000000);
    assert_true(fabs(cell.scn.params.dt - 0.002) < 1e-15); /* controller dt follows the period */
    assert_int_equal(cell.rt.priority, 70);
    assert_int_equal(cell.rt.cpu, -1);
    assert_int_equal(cell.rt.overrun_limit, 3);
    assert_int_equal(cell.rt.lost_feedback_cycles, 6);
    assert_true(cell.stop_after == 1.5);
#ifdef MCA_TEST_HOOKS
    assert_true(cell.debug_stall_after_ticks == 0);
    assert_true(cell.debug_kill_after_ticks == 0);
    assert_true(cell.debug_start_in_fault == 0);
#endif
}

static void test_missing_file(void **state) {
    (void)state;
    char p[512];
    snprintf(p, sizeof p, "%s/no-such-cell.yaml", tmpdir);
    expect_error(p, MCA_ENOENT, 0, "cannot open cell file", NULL);
}

static void test_yaml_syntax(void **state) {
    (void)state;
    const char *p = write_variant("syntax", "[0.0, 0.6, 0.0]", "[0.0, 0.6, 0.0");
    expect_error(p, MCA_EPARSE, line_of(p, "[0.0, 0.6, 0.0"), "arms[1].base_xyz", "did not find expected",
                 NULL);
}

static void test_wrong_type(void **state) {
    (void)state;
    const char *p = write_variant("type", "priority: 70", "priority: high");
    expect_error(p, MCA_EPARSE, line_of(p, "priority: high"), "rt.priority", "Invalid INT value: 'high'",
                 NULL);
}

static void test_wrong_type_in_arm(void **state) {
    (void)state;
    const char *p = write_variant("type2", "dec_limit: 4.0", "dec_limit: fast");
    expect_error(p, MCA_EPARSE, line_of(p, "dec_limit: fast"), "arms[0].dec_limit", "Invalid FLOAT value",
                 NULL);
}

static void test_unknown_key(void **state) {
    (void)state;
    const char *p = write_variant("unknown", "    dec_limit: 4.0\n", "    dec_limit: 4.0\n    colour: red\n");
    expect_error(p, MCA_EPARSE, line_of(p, "colour: red"), "arms[0].colour", "Unexpected key: colour", NULL);
}

static void test_unknown_top_key(void **state) {
    (void)state;
    const char *p = write_variant("unknown_top", "stop_after: 1.5", "stop_afterwards: 1.5");
    expect_error(p, MCA_EPARSE, line_of(p, "stop_afterwards"), "stop_afterwards", "Unexpected key", NULL);
}

static void test_missing_required(void **state) {
    (void)state;
    const char *p = write_variant("missing", "  - name: left\n    backend: sim\n", "  - name: left\n");
    expect_error(p, MCA_EPARSE, line_of(p, "- name: left"), "arms[0].backend",
                 "Missing required mapping field", NULL);
}

static void test_d1_ge_d2(void **state) {
    (void)state;
    const char *p = write_variant("d1d2", "d1: 0.04", "d1: 0.15");
    expect_error(p, MCA_ECONFIG, line_of(p, "d1: 0.15"), "d1/d2", "d1 < d2", "d1 = 0.15, d2 = 0.15", NULL);
}

static void test_missing_urdf(void **state) {
    (void)state;
    char from[512];
    snprintf(from, sizeof from, "%s/config/robots/pa10plus.urdf\n    base_xyz: [0.0, 0.6", MCA_SOURCE_DIR);
    const char *p = write_variant("nourdf", from, "/nonexistent/pa11.urdf\n    base_xyz: [0.0, 0.6");
    expect_error(p, MCA_ENOENT, line_of(p, "pa11.urdf"), "arms[1].urdf", "'/nonexistent/pa11.urdf' not found",
                 NULL);
}

static void test_unknown_backend(void **state) {
    (void)state;
    const char *p = write_variant("backend", "backend: socketcan", "backend: ethercat");
    expect_error(p, MCA_ECONFIG, line_of(p, "ethercat"), "arms[1].backend", "unknown backend 'ethercat'",
                 NULL);
}

static void test_dof_mismatch(void **state) {
    (void)state;
    const char *p =
        write_variant("dof", "q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]", "q0: [0.0, 0.3, 0.0]");
    expect_error(p, MCA_ECONFIG, line_of(p, "q0: [0.0, 0.3, 0.0]"), "arms[0].q0", "3 values", "has 8 joints",
                 "DOF mismatch", NULL);
}

static void test_q0_outside_limits(void **state) {
    (void)state;
    const char *p = write_variant("q0lim", "q0: [0.1, 0.3,", "q0: [9.0, 0.3,");
    expect_error(p, MCA_ECONFIG, line_of(p, "q0: [9.0"), "arms[1].q0[0] = 9", "outside joint", NULL);
}

#ifdef MCA_TEST_HOOKS
/* The crash hook (test build): set, and refused when negative with the field named. */
static void test_debug_kill_hook(void **state) {
    (void)state;
    const char *p =
        write_variant("kill_hook", "stop_after: 1.5", "stop_after: 1.5\ndebug_kill_after_ticks: 1500");
    char err[1024] = "";
    if (mca_cell_load(p, &cell, err, sizeof err) != MCA_OK) {
        fail_msg("%s", err);
    }
    assert_true(cell.debug_kill_after_ticks == 1500);
    p = write_variant("kill_hook_neg", "stop_after: 1.5", "stop_after: 1.5\ndebug_kill_after_ticks: -1");
    expect_error(p, MCA_ECONFIG, line_of(p, "debug_kill_after_ticks"), "debug_kill_after_ticks",
                 "must be >= 0", NULL);
    p = write_variant("fault_hook", "stop_after: 1.5", "stop_after: 1.5\ndebug_start_in_fault: true");
    if (mca_cell_load(p, &cell, err, sizeof err) != MCA_OK) {
        fail_msg("%s", err);
    }
    assert_true(cell.debug_start_in_fault == 1 && cell.debug_kill_after_ticks == 0);
}
#else
/* Issue 16: the production build has no test hooks; each debug_* key (whatever its value, 0 and false
 * too) is refused with the file, its line and the key, before anything else is checked. */
static void test_debug_kill_hook(void **state) {
    (void)state;
    static const char *const keys[] = {"debug_kill_after_ticks: 1500", "debug_kill_after_ticks: 0",
                                       "debug_stall_after_ticks: 400", "debug_start_in_fault: false"};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        char to[128], key[64];
        snprintf(to, sizeof to, "stop_after: 1.5\n%s", keys[i]);
        snprintf(key, sizeof key, "%.*s", (int)(strchr(keys[i], ':') - keys[i]), keys[i]);
        const char *p = write_variant("hook_refused", "stop_after: 1.5", to);
        const int line = line_of(p, key);
        assert_true(line > 1);
        expect_error(p, MCA_ENOTSUP, line, key, "test hook", "production build", NULL);
    }
}
#endif

static void test_negative_period(void **state) {
    (void)state;
    const char *p = write_variant("period", "period_us: 2000", "period_us: -1000");
    expect_error(p, MCA_ECONFIG, line_of(p, "period_us"), "rt.period_us", "got -1000", NULL);
}

static void test_bad_priority(void **state) {
    (void)state;
    const char *p = write_variant("prio", "priority: 70", "priority: 150");
    expect_error(p, MCA_ECONFIG, line_of(p, "priority: 150"), "rt.priority", "0..99", NULL);
}

static void test_scenario_missing(void **state) {
    (void)state;
    const char *p = write_variant("noscn", "  duration: 3.5\n", "  scenario: gone/cross.yaml\n");
    expect_error(p, MCA_ENOENT, line_of(p, "scenario: gone"), "task.scenario", "gone/cross.yaml' not found",
                 NULL);
}

static void test_socketcan_needs_interface(void **state) {
    (void)state;
    const char *p = write_variant("noif", "    interface: vcan1\n", "");
    /* a missing field names its enclosing mapping's line: the arm's entry (issue 12) */
    expect_error(p, MCA_EPARSE, line_of(p, "- name: right"), "arms[1].interface", "required", NULL);
}

static void test_dds_config_missing(void **state) {
    (void)state;
    const char *p = write_variant("ddscfg", "  domain: 7\n", "  domain: 7\n  config: nowhere/cyclone.xml\n");
    expect_error(p, MCA_ENOENT, line_of(p, "config: nowhere"), "dds.config", "not found", NULL);
}

static void test_unknown_scheme(void **state) {
    (void)state;
    const char *p = write_variant("scheme", "scheme: mvn", "scheme: magic");
    expect_error(p, MCA_ECONFIG, line_of(p, "scheme: magic"), "scheme", "unknown scheme 'magic'", NULL);
}

/* ROS 2 (issue 14): dds.ros2 and task.stream keys; bad values name file, line and field. */
static void test_ros2_keys(void **state) {
    (void)state;
    const char *p = write_variant("r2ns", "  publish_divisor: 4\n",
                                  "  publish_divisor: 4\n  ros2: {namespace: bad-name}\n");
    expect_error(p, MCA_ECONFIG, line_of(p, "namespace: bad-name"), "dds.ros2.namespace", "not a ROS 2 name",
                 NULL);
    p = write_variant("r2ok", "  publish_divisor: 4\n", "  publish_divisor: 4\n  ros2: {markers: false}\n");
    char err[512] = "";
    assert_int_equal(mca_cell_load(p, &cell, err, sizeof err), MCA_OK);
    assert_string_equal(cell.dds.ros2.ns, "unit_cell"); /* the cell name */
    assert_int_equal(cell.dds.ros2.markers, 0);
    assert_int_equal(cell.dds.ros2.joint_states, 1);
    const char *stream = "  duration: 3.5\n  stream:\n    max_speed: %s\n    workspace_min: [-1, -1, 0]\n"
                         "    workspace_max: [1, 1, %s]\n";
    char text[256];
    snprintf(text, sizeof text, stream, "5.0", "1");
    p = write_variant("stspeed", "  duration: 3.5\n", text);
    expect_error(p, MCA_ECONFIG, line_of(p, "max_speed"), "task.stream.max_speed", "5 outside", NULL);
    snprintf(text, sizeof text, stream, "0.2", "-1");
    p = write_variant("stbox", "  duration: 3.5\n", text);
    expect_error(p, MCA_ECONFIG, line_of(p, "workspace_max"), "task.stream.workspace_max[2]", "not above",
                 NULL);
    snprintf(text, sizeof text, stream, "0.2", "1");
    p = write_variant("stdds", "  duration: 3.5\n", text); /* the good cell has DDS off */
    expect_error(p, MCA_ECONFIG, line_of(p, "stream:"), "task.stream", "needs dds.enabled", NULL);
    p = write_variant("starm", "    path: {kind: circle", "    stream: pose\n    path: {kind: circle");
    expect_error(p, MCA_EPARSE, line_of(p, "stream: pose"), "arms[1].stream", "only in a streamed task",
                 NULL);
}

/* Issue 12: a cell copied away from config/cells still finds the shipped scenario through the search path
 * ($MCA_PATH, default /etc/mca:/usr/share/mca), after its own folder. */
static void test_search_path(void **state) {
    (void)state;
    char path[600], text[256];
    snprintf(path, sizeof path, "%s/copied.yaml", tmpdir);
    snprintf(text, sizeof text,
             "name: copied\ntask:\n  scenario: ../scenarios/cross_circles.yaml\narms:\n"
             "  - {name: left, backend: sim}\n  - {name: right, backend: sim}\ndds: {enabled: false}\n");
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    char err[1024] = "";
    unsetenv("MCA_PATH");
    if (access("/usr/share/mca/scenarios/cross_circles.yaml", R_OK) != 0) {
        expect_error(path, MCA_ENOENT, line_of(path, "scenario:"), "task.scenario", "not found", NULL);
    }
    char env[600];
    snprintf(env, sizeof env, "/nonexistent:%s/config", MCA_SOURCE_DIR);
    setenv("MCA_PATH", env, 1);
    const int rc = mca_cell_load(path, &cell, err, sizeof err);
    unsetenv("MCA_PATH");
    if (rc != MCA_OK) {
        fail_msg("with MCA_PATH=%s: %s", env, err);
    }
    assert_int_equal(cell.scn.n_arms, 2);
}

/* mca-ts (issue 11): the default without a scheme key; its keys: arms[i].priority, solver.deadlock_time and
 * solver.back_off_time reach the controller config; bad values name file, line and field. */
static void test_mca_ts_keys(void **state) {
    (void)state;
    const char *p = write_variant("ts", "scheme: mvn\n", "");
    char err[1024] = "";
    assert_int_equal(mca_cell_load(p, &cell, err, sizeof err), MCA_OK);
    assert_int_equal(cell.scheme, MCA_SCHEME_MCA_TS);
    p = write_variant("ts2", "scheme: mvn\nd1: 0.04\n", "scheme: mca-ts\nd1: 0.04\n");
    assert_int_equal(mca_cell_load(p, &cell, err, sizeof err), MCA_OK);
    assert_int_equal(cell.scheme, MCA_SCHEME_MCA_TS);
    p = write_variant("ts3", "  pdnn_max_steps: 321\n",
                      "  pdnn_max_steps: 321\n  deadlock_time: 0.25\n  back_off_time: 0.75\n");
    assert_int_equal(mca_cell_load(p, &cell, err, sizeof err), MCA_OK);
    p = write_variant("ts4", "    dec_limit: 4.0\n", "    dec_limit: 4.0\n    priority: 3\n");
    assert_int_equal(mca_cell_load(p, &cell, err, sizeof err), MCA_OK);
    assert_true(cell.arm[0].priority == 3.0 && cell.arm[1].priority == 0.0);
    static mca_controller_config_t cfg;
    /* socketcan arm: the controller config does not open it */
    if (mca_cell_controller_config(&cell, &cfg, err, sizeof err) != MCA_OK) {
        fail_msg("%s", err);
    }
    assert_true(cfg.ts.priority[0] == 3.0 && cfg.ts.priority[1] == 1.0);
    assert_true(cfg.ts.dec_limit[0] == 4.0 && cfg.ts.dec_limit[1] == 10.0);
    p = write_variant("ts5", "    dec_limit: 4.0\n", "    dec_limit: 4.0\n    priority: 0\n");
    expect_error(p, MCA_ECONFIG, line_of(p, "priority: 0"), "arms[0].priority",
                 "must be in (0, 1000] (got 0)", NULL);
    p = write_variant("ts6", "  pdnn_max_steps: 321\n", "  pdnn_max_steps: 321\n  deadlock_time: -1\n");
    expect_error(p, MCA_ECONFIG, line_of(p, "deadlock_time: -1"), "solver.deadlock_time",
                 "must be in (0, 60] s (got -1)", NULL);
    p = write_variant("ts7", "  pdnn_max_steps: 321\n", "  pdnn_max_steps: 321\n  back_off_time: 0\n");
    expect_error(p, MCA_ECONFIG, line_of(p, "back_off_time: 0"), "solver.back_off_time",
                 "must be in (0, 60] s (got 0)", NULL);
}

static void test_duplicate_arm(void **state) {
    (void)state;
    const char *p = write_variant("dup", "  - name: right", "  - name: left");
    expect_error(p, MCA_ECONFIG, line_of(p, "backend: socketcan") - 1, "arms[1].name", "used twice", NULL);
}

/* Every shipped cell file loads (they reference the scheme's scenario files and the URDFs). */
static void test_shipped_cells(void **state) {
    (void)state;
    glob_t g;
    char pat[512];
    snprintf(pat, sizeof pat, "%s/config/cells/*.yaml", MCA_SOURCE_DIR);
    if (glob(pat, 0, NULL, &g) != 0) {
        fail_msg("no shipped cells: %s", pat); /* a missing directory is a failure, not a skip */
    }
    /* every task of the scheme on the sim backend and on vcan (a cell that goes missing fails here) */
    static const char *const want[] = {"cross_circles", "hui", "cup_stacking", "negative"};
    int seen[4][2] = {{0}};
    for (size_t i = 0; i < g.gl_pathc; i++) {
        char err[1024] = "";
        const int rc = mca_cell_load(g.gl_pathv[i], &cell, err, sizeof err);
        print_message("  %s: %s\n", g.gl_pathv[i], rc == MCA_OK ? "ok" : err);
        assert_int_equal(rc, MCA_OK);
        /* two arms, but the three-arm cell of issue 11 (three_arms_sim: JACO2, MICO2, JACO2) */
        assert_true(cell.scn.n_arms == (strcmp(cell.name, "three_arms_sim") == 0 ? 3 : 2));
        for (int k = 0; k < 4; k++) {
            for (int b = 0; b < 2; b++) {
                char name[64];
                snprintf(name, sizeof name, "%s_%s", want[k], b ? "vcan" : "sim");
                if (strcmp(cell.name, name) == 0) {
                    /* the cell runs its task's scenario, on the backend its name says */
                    assert_string_equal(cell.scn.name, want[k]);
                    for (int a = 0; a < cell.scn.n_arms; a++) {
                        assert_int_equal(cell.arm[a].backend,
                                         b ? MCA_CELL_BACKEND_SOCKETCAN : MCA_CELL_BACKEND_SIM);
                    }
                    seen[k][b]++;
                }
            }
        }
    }
    globfree(&g);
    for (int k = 0; k < 4; k++) {
        for (int b = 0; b < 2; b++) {
            if (seen[k][b] != 1) {
                fail_msg("shipped cell %s_%s.yaml: found %d times", want[k], b ? "vcan" : "sim", seen[k][b]);
            }
        }
    }
}

int main(void) {
    snprintf(tmpdir, sizeof tmpdir, "/tmp/mca-test-cell-XXXXXX");
    if (!mkdtemp(tmpdir)) {
        return 1;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_good_cell),          cmocka_unit_test(test_missing_file),
        cmocka_unit_test(test_yaml_syntax),        cmocka_unit_test(test_wrong_type),
        cmocka_unit_test(test_wrong_type_in_arm),  cmocka_unit_test(test_unknown_key),
        cmocka_unit_test(test_unknown_top_key),    cmocka_unit_test(test_missing_required),
        cmocka_unit_test(test_d1_ge_d2),           cmocka_unit_test(test_missing_urdf),
        cmocka_unit_test(test_unknown_backend),    cmocka_unit_test(test_dof_mismatch),
        cmocka_unit_test(test_q0_outside_limits),  cmocka_unit_test(test_negative_period),
        cmocka_unit_test(test_debug_kill_hook),    cmocka_unit_test(test_bad_priority),
        cmocka_unit_test(test_scenario_missing),   cmocka_unit_test(test_socketcan_needs_interface),
        cmocka_unit_test(test_dds_config_missing), cmocka_unit_test(test_unknown_scheme),
        cmocka_unit_test(test_ros2_keys),          cmocka_unit_test(test_search_path),
        cmocka_unit_test(test_duplicate_arm),      cmocka_unit_test(test_shipped_cells),
        cmocka_unit_test(test_mca_ts_keys),
    };
    const int failed = cmocka_run_group_tests(tests, NULL, NULL);
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    if (system(cmd) != 0) {
        fprintf(stderr, "could not remove %s\n", tmpdir);
    }
    return failed;
}
