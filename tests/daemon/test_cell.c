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
#include "mca/daemon.h" /* mca_daemon_open */
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
    assert_int_equal(cell.arm[1].backend, mca_cell_backend_id("socketcan"));
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
    assert_int_equal(cell.dds.priority, 0); /* default: SCHED_OTHER */
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

/* A cell whose backend id was changed in code after its file was read: the daemon refuses to open it with
 * the file, the line of that arm's backend key and the field (the registry once took it for the sim). */
static void test_unknown_backend_id(void **state) {
    (void)state;
    const char *p = write_variant("backend_id", NULL, NULL);
    char err[1024] = "";
    assert_int_equal(mca_cell_load(p, &cell, err, sizeof err), MCA_OK);
    cell.arm[1].backend = (mca_cell_backend_t)7;
    assert_string_equal(mca_cell_backend_name(cell.arm[1].backend), "?");
    const mca_daemon_opts_t opts = {.no_rt = 1};
    mca_daemon_t *d = NULL;
    const int rc = mca_daemon_open(&d, &cell, &opts, err, sizeof err);
    print_message("  %s\n", err);
    assert_int_equal(rc, MCA_ECONFIG);
    assert_null(d);
    char prefix[600];
    snprintf(prefix, sizeof prefix,
             "%s:%d: arms[1].backend: unknown backend id 7 (known: sim, socketcan, canopen, replay)", p,
             line_of(p, "backend: socketcan"));
    assert_string_equal(err, prefix);
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
    expect_error(p, MCA_ECONFIG, line_of(p, "q0: [9.0"), "arms[1].q0[0]: 9", "outside joint", NULL);
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

/* dds.priority: 0..98 and below the loop's (rt.priority 70 in the base cell); accepted below it */
static void test_dds_priority(void **state) {
    (void)state;
    const char *p = write_variant("ddsprio_range", "  domain: 7\n", "  domain: 7\n  priority: 99\n");
    expect_error(p, MCA_ECONFIG, line_of(p, "priority: 99"), "dds.priority", "0..98", NULL);
    p = write_variant("ddsprio_above", "  domain: 7\n", "  domain: 7\n  priority: 75\n");
    expect_error(p, MCA_ECONFIG, line_of(p, "priority: 75"), "dds.priority",
                 "75 must be below rt.priority (70)", NULL);
    /* the dds section runs into the rt section: one piece sets both */
    p = write_variant("ddsprio_other", "  publish_divisor: 4\nrt:\n  period_us: 2000\n  priority: 70\n",
                      "  publish_divisor: 4\n  priority: 1\nrt:\n  period_us: 2000\n  priority: 0\n");
    expect_error(p, MCA_ECONFIG, line_of(p, "priority: 1"), "dds.priority",
                 "1 must be below rt.priority (0, SCHED_OTHER)", NULL);
    p = write_variant("ddsprio_ok", "  domain: 7\n", "  domain: 7\n  priority: 69\n");
    char err[1024] = "";
    if (mca_cell_load(p, &cell, err, sizeof err) != MCA_OK) {
        fail_msg("%s", err);
    }
    assert_int_equal(cell.dds.priority, 69);
}

static void test_scenario_missing(void **state) {
    (void)state;
    const char *p = write_variant("noscn", "  duration: 3.5\n", "  scenario: gone/cross.yaml\n");
    expect_error(p, MCA_ENOENT, line_of(p, "scenario: gone"), "task.scenario", "gone/cross.yaml' not found",
                 NULL);
}

/* Fixed bodies in a cell: the scenario's one check (file, line, field), against the cell's own arms. */
static void test_cell_bodies(void **state) {
    (void)state;
    const char *body = "bodies:\n"
                       "  - name: table\n"
                       "    kind: plane\n"
                       "    point: [0, 0, 0]\n"
                       "    normal: [0, 0, 1]\n"
                       "    clearance: 0.02\n"
                       "    allow: [left.base, right]\n"
                       "dds:\n";
    const char *p = write_variant("bodies", "dds:\n", body);
    char err[1024] = "";
    assert_int_equal(mca_cell_load(p, &cell, err, sizeof err), MCA_OK);
    assert_int_equal(cell.scn.n_bodies, 1);
    mca_controller_config_t *cfg = calloc(1, sizeof *cfg);
    assert_non_null(cfg);
    assert_int_equal(mca_cell_controller_config(&cell, cfg, err, sizeof err), MCA_OK);
    assert_int_equal(cfg->n_bodies, 1);
    assert_int_equal(cfg->body[0].allow[0], 1u);     /* left.base */
    assert_int_equal(cfg->body[0].allow[1], 0x1ffu); /* every link of the right arm */
    free(cfg);
    char bad[1024];
    snprintf(bad, sizeof bad, "%s", body);
    char *at = strstr(bad, "right]");
    memcpy(at, "rigt] ", 6);
    p = write_variant("bodies_arm", "dds:\n", bad);
    expect_error(p, MCA_ECONFIG, line_of(p, "allow:"), "bodies[0].allow[1]", "no arm 'rigt'", "left, right",
                 NULL);
    p = write_variant("bodies_clear", "dds:\n",
                      "bodies:\n  - {name: post, kind: capsule, a: [0, 0, 0], b: [0, 0, 1], radius: 0.05,\n"
                      "     clearance: 3}\ndds:\n");
    expect_error(p, MCA_ECONFIG, line_of(p, "clearance: 3"), "bodies[0].clearance", "got 3", NULL);
    p = write_variant(
        "bodies_kind", "dds:\n",
        "bodies:\n  - name: post\n    kind: capsule\n    centre: [0, 0, 0]\n    radius: 0.05\ndds:\n");
    expect_error(p, MCA_ECONFIG, line_of(p, "centre:"), "bodies[0].centre", "not a key of a capsule", NULL);
}

/* Self pairs in a cell: the scenario's one check (file, line, field), against the cell's own arms. */
static void test_cell_self_pairs(void **state) {
    (void)state;
    const char *p = write_variant("self", "dds:\n", "self_pairs: [left, -left.8-4, right.2-5]\ndds:\n");
    char err[1024] = "";
    assert_int_equal(mca_cell_load(p, &cell, err, sizeof err), MCA_OK);
    mca_controller_config_t *cfg = calloc(1, sizeof *cfg);
    assert_non_null(cfg);
    assert_int_equal(mca_cell_controller_config(&cell, cfg, err, sizeof err), MCA_OK);
    assert_int_equal(cfg->self[0][4], 1u << 2); /* pa10plus.self.yaml */
    assert_int_equal(cfg->self[0][8], 0xfu);    /* 8-0..8-3: 8-4 taken out */
    assert_int_equal(cfg->self[1][5], 1u << 2);
    assert_int_equal(cfg->self[1][8], 0u);
    free(cfg);
    p = write_variant("self_bad", "dds:\n", "self_pairs: [left, rigt.2-5]\ndds:\n");
    expect_error(p, MCA_ECONFIG, line_of(p, "self_pairs:"), "self_pairs[1]", "no such arm", NULL);
}

/* A cell over a scenario with bodies: they come with it, and a cell body of the same name replaces one. */
static void test_cell_bodies_over_scenario(void **state) {
    (void)state;
    char err[1024] = "";
    assert_int_equal(
        mca_cell_load(MCA_SOURCE_DIR "/config/cells/cup_stacking_bodies_sim.yaml", &cell, err, sizeof err),
        MCA_OK);
    assert_int_equal(cell.scn.n_bodies, 7);
    assert_string_equal(cell.scn.body[0].fb.name, "table");
    assert_true(cell.scn.body[0].clearance == 0.02); /* the cell's, over the scenario's 0.03 */
    assert_true(cell.scn.body[3].clearance == 0.05);
}

static void test_socketcan_needs_interface(void **state) {
    (void)state;
    const char *p = write_variant("noif", "    interface: vcan1\n", "");
    /* a missing field names its enclosing mapping's line: the arm's entry */
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

/* ROS 2: dds.ros2 and task.stream keys; bad values name file, line and field. */
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

/* mca-ts: the default without a scheme key; its keys: arms[i].priority, solver.deadlock_time and
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

/* ---- every error kind names its exact line and field (an operator goes straight to it) ---- */

/* Write `text` as tmpdir/NAME.yaml; returns the file name (static). */
static const char *write_text(const char *name, const char *text) {
    static char path[512];
    snprintf(path, sizeof path, "%s/%s.yaml", tmpdir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    return path;
}

/* Replace the first `from` in buf (size cap) by `to`; from must occur. */
static void replace_in(char *buf, size_t cap, const char *from, const char *to) {
    char *at = strstr(buf, from);
    if (!at) {
        fail_msg("test bug: '%s' not in '%s'", from, buf);
    }
    char tail[8192];
    snprintf(tail, sizeof tail, "%s", at + strlen(from));
    snprintf(at, cap - (size_t)(at - buf), "%s%s", to, tail);
}

/* Line of the first `needle` at or after the start of arm k (the k-th "  - " entry under arms:); the
 * entry's own line when needle is NULL. */
static int line_in_arm(const char *path, int k, const char *needle) {
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char buf[1024];
    int line = 0, arm = -1, found = 0;
    while (fgets(buf, sizeof buf, f)) {
        line++;
        if (strncmp(buf, "  - ", 4) == 0) {
            arm++;
        }
        if (arm == k && (!needle || strstr(buf, needle))) {
            found = line;
            break;
        }
    }
    fclose(f);
    assert_true(found > 0);
    return found;
}

/* Cells tested through every single value: one change of the good cell, the line holding NEEDLE. */
struct cell_case {
    const char *name, *from, *to, *from2, *to2, *needle;
    int rc;
    const char *field, *reason;
};

static void run_cell_cases(const struct cell_case *c, size_t n) {
    for (size_t i = 0; i < n; i++) {
        char text[8192];
        snprintf(text, sizeof text, "%s", good_cell());
        replace_in(text, sizeof text, c[i].from, c[i].to);
        if (c[i].from2) {
            replace_in(text, sizeof text, c[i].from2, c[i].to2);
        }
        const char *p = write_text(c[i].name, text);
        print_message("%s (line of '%s'):\n", c[i].name, c[i].needle);
        expect_error(p, c[i].rc, line_of(p, c[i].needle), c[i].field, c[i].reason, NULL);
    }
}

#define STREAM_OK "  duration: 3.5\n  stream:\n    workspace_min: [-1, -1, 0]\n    workspace_max: [1, 1, 1]\n"

static void test_cell_error_lines(void **state) {
    (void)state;
    /* a scenario file that loads to nothing: the scenario's own error, at task.scenario */
    write_text("empty_scn", "# nothing yet\n");
    static const struct cell_case cases[] = {
        {"c_task_nodur", "task:\n  duration: 3.5\n", "task: {}\n", NULL, NULL, "task: {}", MCA_EPARSE,
         "task: ", "an inline task needs 'duration'"},
        {"c_scn_empty", "  duration: 3.5\n", "  scenario: empty_scn.yaml\n", NULL, NULL,
         "scenario: empty_scn", MCA_EPARSE, "task.scenario", "empty document"},
        {"c_duration", "duration: 3.5", "duration: 1e7", NULL, NULL, "duration: 1e7", MCA_ECONFIG,
         "task.duration", "(got 10000000)"},
        {"c_ticks", "duration: 3.5", "duration: 3000", "period_us: 2000", "period_us: 100", "duration: 3000",
         MCA_ECONFIG, "task.duration", "30000000 ticks"},
        {"c_st_gain", "  duration: 3.5\n", STREAM_OK "    pose_gain: 100\n", NULL, NULL, "pose_gain",
         MCA_ECONFIG, "task.stream.pose_gain", "100 outside"},
        {"c_st_hold", "  duration: 3.5\n", STREAM_OK "    hold_after: 2\n    brake_after: 1\n", NULL, NULL,
         "hold_after", MCA_ECONFIG, "task.stream.hold_after", "after brake_after"},
        {"c_st_min", "  duration: 3.5\n",
         "  duration: 3.5\n  stream:\n    workspace_min: [-1, 1e308, 0]\n    workspace_max: [1, 1, 1]\n",
         NULL, NULL, "workspace_min", MCA_ECONFIG, "task.stream.workspace_min[1]", "must be in"},
        {"c_st_max", "  duration: 3.5\n",
         "  duration: 3.5\n  stream:\n    workspace_min: [-1, -1, 0]\n    workspace_max: [1, 1, 1e308]\n",
         NULL, NULL, "workspace_max", MCA_ECONFIG, "task.stream.workspace_max[2]", "must be in"},
        {"c_d1", "d1: 0.04", "d1: -1", NULL, NULL, "d1: -1", MCA_ECONFIG, "d1: ", "(got -1)"},
        {"c_d2", "d2: 0.15", "d2: 1e308", NULL, NULL, "d2: 1e308", MCA_ECONFIG, "d2: ", "(got 1e+308)"},
        {"c_K", "K: 12", "K: 1e308", NULL, NULL, "K: 1e308", MCA_ECONFIG, "solver.K", "must be in"},
        {"c_eps", "  K: 12\n", "  K: 12\n  epsilon: 1e308\n", NULL, NULL, "epsilon", MCA_ECONFIG,
         "solver.epsilon", "must be in"},
        {"c_vn", "  K: 12\n", "  K: 12\n  v_normal: 1e308\n", NULL, NULL, "v_normal", MCA_ECONFIG,
         "solver.v_normal", "must be in"},
        {"c_vf", "  K: 12\n", "  K: 12\n  v_floor: -5\n", NULL, NULL, "v_floor", MCA_ECONFIG,
         "solver.v_floor", "must be in"},
        {"c_steps", "pdnn_max_steps: 321", "pdnn_max_steps: 0", NULL, NULL, "pdnn_max_steps", MCA_ECONFIG,
         "solver.pdnn_max_steps", "(got 0)"},
        {"c_ptol", "  K: 12\n", "  K: 12\n  pdnn_tol: 5\n", NULL, NULL, "pdnn_tol", MCA_ECONFIG,
         "solver.pdnn_tol", "(got 5)"},
        {"c_eqtol", "  K: 12\n", "  K: 12\n  eq_tol: 5\n", NULL, NULL, "eq_tol", MCA_ECONFIG, "solver.eq_tol",
         "(got 5)"},
        {"c_fres", "  K: 12\n", "  K: 12\n  fault_residual: 5\n", NULL, NULL, "fault_residual", MCA_ECONFIG,
         "solver.fault_residual", "(got 5)"},
        {"c_domain", "domain: 7", "domain: 231", NULL, NULL, "domain: 231", MCA_ECONFIG, "dds.domain",
         "(got 231)"},
        {"c_pubdiv", "publish_divisor: 4", "publish_divisor: 0", NULL, NULL, "publish_divisor", MCA_ECONFIG,
         "dds.publish_divisor", "(got 0)"},
        {"c_frame", "  publish_divisor: 4\n", "  publish_divisor: 4\n  ros2:\n    world_frame: 9-lives\n",
         NULL, NULL, "world_frame", MCA_ECONFIG, "dds.ros2.world_frame", "not a frame name"},
        {"c_cpu", "  priority: 70\n", "  priority: 70\n  cpu: 99999\n", NULL, NULL, "cpu: 99999", MCA_ECONFIG,
         "rt.cpu", "(got 99999)"},
        {"c_overrun", "overrun_limit: 3", "overrun_limit: 0", NULL, NULL, "overrun_limit", MCA_ECONFIG,
         "rt.overrun_limit", "(got 0)"},
        {"c_overrun_s", "overrun_limit: 3", "overrun_limit: 2000000", NULL, NULL, "overrun_limit",
         MCA_ECONFIG, "rt.overrun_limit", "more than 3600 s"},
        {"c_budget", "overrun_limit: 3", "overrun_limit: 3\n  pdnn_budget_us: 0", NULL, NULL,
         "pdnn_budget_us", MCA_ECONFIG, "rt.pdnn_budget_us", "(got 0)"},
        {"c_lost", "lost_feedback_cycles: 6", "lost_feedback_cycles: 0", NULL, NULL, "lost_feedback_cycles",
         MCA_ECONFIG, "rt.lost_feedback_cycles", "(got 0)"},
        {"c_lost_s", "lost_feedback_cycles: 6", "lost_feedback_cycles: 600", NULL, NULL,
         "lost_feedback_cycles", MCA_ECONFIG, "rt.lost_feedback_cycles", "more than 1 s"},
        {"c_stop", "stop_after: 1.5", "stop_after: 1e9", NULL, NULL, "stop_after", MCA_ECONFIG,
         "stop_after: ", "(got 1000000000)"},
#ifdef MCA_TEST_HOOKS
        {"c_stall", "stop_after: 1.5", "stop_after: 1.5\ndebug_stall_after_ticks: -1", NULL, NULL,
         "debug_stall_after_ticks", MCA_ECONFIG, "debug_stall_after_ticks", "must be >= 0"},
#endif
    };
    run_cell_cases(cases, sizeof cases / sizeof cases[0]);
}

/* A two-arm cell whose arms are alike ('#' is the arm's index, @U@ its URDF); the bad arm takes one change.
 */
enum { B_SIM, B_SOCKETCAN, B_CANOPEN };
static const char *const arm_backend[] = {
    "    backend: sim\n",
    "    backend: socketcan\n    interface: vcan#\n    id_base: 0x140\n",
    "    backend: canopen\n    interface: can#\n    canopen:\n      first_node: 1\n      sync_us: 4000\n"
    "      mode: csv\n      pos_scale: 1000\n      vel_scale: 1000\n      heartbeat_timeout_ms: 350\n"
    "      pdo_timeout_syncs: 5\n",
};

struct arm_case {
    const char *name;
    int backend;
    const char *from, *to;
    const char *needle; /* in the bad arm; NULL: the arm's entry line (a missing field) */
    int rc;
    const char *field; /* "%d": the bad arm */
    const char *reason;
    int streamed;  /* task.stream (and DDS on) */
    int fast_urdf; /* the bad arm's URDF has joints of 10 rad/s */
    int only_arm1; /* a clash with an earlier arm */
};

static const char *pair_cell(const char *name, const struct arm_case *c, int bad) {
    char text[8192];
    snprintf(text, sizeof text,
             "# two alike arms\nname: pair-cell\ntask:\n  duration: 3.5\n%sd1: 0.04\nd2: 0.15\narms:\n",
             c && c->streamed ? "  stream:\n    workspace_min: [-1, -1, 0]\n    workspace_max: [1, 1, 1]\n"
                              : "");
    for (int k = 0; k < 2; k++) {
        char arm[2048];
        snprintf(
            arm, sizeof arm,
            "  - name: a#\n%s    urdf: @U@\n    base_xyz: [0.#, 0.6, 0.1]\n    base_rpy: [0.0, 0.0, 0.0]\n"
            "    q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]\n    dec_limit: 4.0\n",
            arm_backend[c ? c->backend : B_SIM]);
        if (c && k == bad) {
            replace_in(arm, sizeof arm, c->from, c->to);
        }
        char urdf[400];
        if (c && k == bad && c->fast_urdf) {
            snprintf(urdf, sizeof urdf, "%s/fast.urdf", tmpdir);
        } else {
            snprintf(urdf, sizeof urdf, "%s/config/robots/pa10plus.urdf", MCA_SOURCE_DIR);
        }
        while (strstr(arm, "@U@")) {
            replace_in(arm, sizeof arm, "@U@", urdf);
        }
        for (char *h = strchr(arm, '#'); h; h = strchr(h + 1, '#')) {
            *h = (char)('0' + k);
        }
        strncat(text, arm, sizeof text - strlen(text) - 1);
    }
    strncat(text, c && c->streamed ? "dds:\n  enabled: true\n" : "dds:\n  enabled: false\n",
            sizeof text - strlen(text) - 1);
    return write_text(name, text);
}

/* pa10plus with every joint's velocity limit 10 rad/s: dec_limit 0.05 brakes in 200 s */
static void write_fast_urdf(void) {
    char src[512], dst[512];
    snprintf(src, sizeof src, "%s/config/robots/pa10plus.urdf", MCA_SOURCE_DIR);
    snprintf(dst, sizeof dst, "%s/fast.urdf", tmpdir);
    FILE *in = fopen(src, "r"), *out = fopen(dst, "w");
    assert_non_null(in);
    assert_non_null(out);
    char line[2048];
    while (fgets(line, sizeof line, in)) {
        char *v = strstr(line, "velocity=\"");
        if (v) {
            char *end = strchr(v + 10, '"');
            assert_non_null(end);
            fprintf(out, "%.*svelocity=\"10\"%s", (int)(v - line), line, end + 1);
        } else {
            fputs(line, out);
        }
    }
    fclose(in);
    fclose(out);
}

#define PATH_CIRCLE(r, per, u, v)                                                                            \
    "    dec_limit: 4.0\n    path:\n      kind: circle\n      radius: " r "\n" per "      u: " u             \
    "\n      v: " v "\n"
#define ARM_TAIL "    dec_limit: 4.0\n"

static void test_arm_error_lines(void **state) {
    (void)state;
    write_fast_urdf();
    static const struct arm_case cases[] = {
        {"a_backend", B_SIM, "backend: sim", "backend: ethercat", "backend:", MCA_ECONFIG, "arms[%d].backend",
         "unknown backend 'ethercat' (known: sim, socketcan, canopen, replay)", 0, 0, 0},
        {"a_sc_noif", B_SOCKETCAN, "    interface: vcan#\n", "", NULL, MCA_EPARSE, "arms[%d].interface",
         "required with backend socketcan", 0, 0, 0},
        {"a_sc_noid", B_SOCKETCAN, "    id_base: 0x140\n", "", NULL, MCA_EPARSE, "arms[%d].id_base",
         "required with backend socketcan", 0, 0, 0},
        {"a_co_noif", B_CANOPEN, "    interface: can#\n", "", NULL, MCA_EPARSE, "arms[%d].interface",
         "required with backend canopen", 0, 0, 0},
        {"a_co_only", B_SIM, ARM_TAIL, ARM_TAIL "    canopen:\n      sync_us: 4000\n", "canopen:", MCA_EPARSE,
         "arms[%d].canopen", "only with backend canopen", 0, 0, 0},
        {"a_sim_only", B_SOCKETCAN, "    id_base: 0x140\n", "    id_base: 0x140\n    sim: {lag_tau: 0.01}\n",
         "sim:", MCA_EPARSE, "arms[%d].sim", "only with backend sim", 0, 0, 0},
        {"a_co_node", B_CANOPEN, "first_node: 1", "first_node: 128", "first_node", MCA_ECONFIG,
         "arms[%d].canopen.first_node", "1..127 (got 128)", 0, 0, 0},
        {"a_co_sync", B_CANOPEN, "sync_us: 4000", "sync_us: 50", "sync_us", MCA_ECONFIG,
         "arms[%d].canopen.sync_us", ">= 100 (got 50)", 0, 0, 0},
        {"a_co_mode", B_CANOPEN, "mode: csv", "mode: cst", "mode:", MCA_ECONFIG, "arms[%d].canopen.mode",
         "csv or csp (got 'cst')", 0, 0, 0},
        {"a_co_pos", B_CANOPEN, "pos_scale: 1000", "pos_scale: -1", "pos_scale", MCA_ECONFIG,
         "arms[%d].canopen: ", "pos_scale and vel_scale must be > 0", 0, 0, 0},
        {"a_co_vel", B_CANOPEN, "vel_scale: 1000", "vel_scale: 0", "vel_scale", MCA_ECONFIG,
         "arms[%d].canopen: ", "pos_scale and vel_scale must be > 0", 0, 0, 0},
        {"a_co_hb", B_CANOPEN, "heartbeat_timeout_ms: 350", "heartbeat_timeout_ms: 100",
         "heartbeat_timeout_ms", MCA_ECONFIG, "arms[%d].canopen: ", "heartbeat_timeout_ms 101..60000", 0, 0,
         0},
        {"a_co_pdo", B_CANOPEN, "pdo_timeout_syncs: 5", "pdo_timeout_syncs: 0", "pdo_timeout_syncs",
         MCA_ECONFIG, "arms[%d].canopen: ", "pdo_timeout_syncs 1..100000", 0, 0, 0},
        {"a_co_bus", B_CANOPEN, "interface: can#", "interface: can0", "interface:", MCA_ECONFIG,
         "arms[%d].interface", "can0 is already arms[0]'s", 0, 0, 1},
        {"a_id_base", B_SOCKETCAN, "id_base: 0x140", "id_base: 0x141", "id_base", MCA_ECONFIG,
         "arms[%d].id_base", "must be a multiple of", 0, 0, 0},
        {"a_id_clash", B_SOCKETCAN, "interface: vcan#", "interface: vcan0", "id_base", MCA_ECONFIG,
         "arms[%d].id_base", "0x140 on vcan0 is already arms[0]'s", 0, 0, 1},
        {"a_inline", B_SIM, "    q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]\n", "", NULL, MCA_EPARSE,
         "arms[%d]: ", "an inline task needs urdf, base_xyz and q0", 0, 0, 0},
        {"a_urdf", B_SIM, "urdf: @U@", "urdf: /nonexistent/pa11.urdf", "urdf:", MCA_ENOENT, "arms[%d].urdf",
         "'/nonexistent/pa11.urdf' not found", 0, 0, 0},
        {"a_urdf_tip", B_SIM, ARM_TAIL, ARM_TAIL "    tip_link: no_such_link\n", "urdf:", MCA_ENOENT,
         "arms[%d].urdf", "no_such_link", 0, 0, 0},
        {"a_xyz", B_SIM, "base_xyz: [0.#, 0.6, 0.1]", "base_xyz: [0.#, 0.6, 1e308]", "base_xyz", MCA_ECONFIG,
         "arms[%d].base_xyz[2]", "must be in [-100, 100] m", 0, 0, 0},
        {"a_rpy", B_SIM, "base_rpy: [0.0, 0.0, 0.0]", "base_rpy: [0.0, 150, 0.0]", "base_rpy", MCA_ECONFIG,
         "arms[%d].base_rpy[1]", "(got 150)", 0, 0, 0},
        {"a_radius", B_SIM, ARM_TAIL, PATH_CIRCLE("1e308", "      period: 3.0\n", "[1, 0, 0]", "[0, 0, 1]"),
         "radius:", MCA_ECONFIG, "arms[%d].path.radius", "must be in (0, 10] m", 0, 0, 0},
        {"a_circle", B_SIM, ARM_TAIL, PATH_CIRCLE("0.1", "", "[1, 0, 0]", "[0, 0, 1]"), "path:", MCA_ECONFIG,
         "arms[%d].path.period", "circle needs period > 0", 0, 0, 0},
        {"a_u", B_SIM, ARM_TAIL, PATH_CIRCLE("0.1", "      period: 3.0\n", "[0, 0, 0]", "[0, 0, 1]"),
         "u:", MCA_ECONFIG, "arms[%d].path.u", "zero vector", 0, 0, 0},
        {"a_v", B_SIM, ARM_TAIL, PATH_CIRCLE("0.1", "      period: 3.0\n", "[1, 0, 0]", "[2, 0, 0]"),
         "v:", MCA_ECONFIG, "arms[%d].path.v", "parallel to u", 0, 0, 0},
        {"a_waypoints", B_SIM, ARM_TAIL,
         ARM_TAIL
         "    path:\n      kind: waypoints\n      points:\n        - [0, 0, 0.1]\n      durations: [0]\n",
         "durations:", MCA_ECONFIG, "arms[%d].path.durations[0]", "must be in (0, 3600] s (got 0)", 0, 0, 0},
        {"a_stream", B_SIM, ARM_TAIL, ARM_TAIL "    stream: pose\n", "stream:", MCA_EPARSE, "arms[%d].stream",
         "only in a streamed task", 0, 0, 0},
        {"a_stream_kind", B_SIM, ARM_TAIL, ARM_TAIL "    stream: spin\n", "stream:", MCA_ECONFIG,
         "arms[%d].stream", "'spin' (known: twist, pose)", 1, 0, 0},
        {"a_dof", B_SIM, "q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]", "q0: [0.0, 0.3, 0.0]",
         "q0:", MCA_ECONFIG, "arms[%d].q0", "3 values but", 0, 0, 0},
        {"a_q0", B_SIM, "q0: [0.0, 0.3,", "q0: [0.0, 9.0,", "q0:", MCA_ECONFIG, "arms[%d].q0[1]: 9",
         "outside joint", 0, 0, 0},
        {"a_dec", B_SIM, "dec_limit: 4.0", "dec_limit: 1e-12", "dec_limit", MCA_ECONFIG, "arms[%d].dec_limit",
         "must be in [0.05, 100] rad/s^2", 0, 0, 0},
        {"a_dec_stop", B_SIM, "dec_limit: 4.0", "dec_limit: 0.05", "dec_limit", MCA_ECONFIG,
         "arms[%d].dec_limit", "in 200 s, more than 60 s", 0, 1, 0},
        {"a_prio", B_SIM, ARM_TAIL, ARM_TAIL "    priority: 0\n", "priority:", MCA_ECONFIG,
         "arms[%d].priority", "(got 0)", 0, 0, 0},
        {"a_lag", B_SIM, ARM_TAIL, ARM_TAIL "    sim:\n      lag_tau: 5\n", "lag_tau", MCA_ECONFIG,
         "arms[%d].sim.lag_tau", "(got 5)", 0, 0, 0},
        {"a_latency", B_SIM, ARM_TAIL, ARM_TAIL "    sim:\n      latency_cycles: 65\n", "latency_cycles",
         MCA_ECONFIG, "arms[%d].sim.latency_cycles", "(got 65)", 0, 0, 0},
        {"a_noise", B_SIM, ARM_TAIL, ARM_TAIL "    sim:\n      noise_pos: 5\n", "noise_pos", MCA_ECONFIG,
         "arms[%d].sim.noise_pos", "(got 5)", 0, 0, 0},
    };
    char err[1024];
    for (int b = B_SIM; b <= B_CANOPEN; b++) { /* the pair cell itself loads, on each backend */
        struct arm_case good = {"good", b, "", "", NULL, 0, "", "", 0, 0, 0};
        const char *p = pair_cell("pair_good", &good, -1);
        if (mca_cell_load(p, &cell, err, sizeof err) != MCA_OK) {
            fail_msg("good pair cell (backend %d): %s", b, err);
        }
    }
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const struct arm_case *c = &cases[i];
        for (int bad = c->only_arm1; bad < 2; bad++) { /* arm 0 bad with arm 1 good, and the other way */
            char name[64], field[96];
            snprintf(name, sizeof name, "%s_%d", c->name, bad);
            snprintf(field, sizeof field, c->field, bad);
            const char *p = pair_cell(name, c, bad);
            print_message("%s:\n", name);
            expect_error(p, c->rc, line_in_arm(p, bad, c->needle), field, c->reason, NULL);
        }
    }
}

/* With a scenario file: the cell's arms name the scenario's arms, as many as it has. */
static void test_scenario_arm_lines(void **state) {
    (void)state;
    for (int bad = 0; bad < 2; bad++) {
        char text[1024];
        snprintf(text, sizeof text,
                 "name: scn-cell\ntask:\n  scenario: %s/config/scenarios/cross_circles.yaml\narms:\n"
                 "  - name: %s\n    backend: sim\n  - name: %s\n    backend: sim\ndds: {enabled: false}\n",
                 MCA_SOURCE_DIR, bad == 0 ? "lefty" : "left", bad == 1 ? "righty" : "right");
        const char *p = write_text("scn_arm", text);
        char field[32];
        snprintf(field, sizeof field, "arms[%d].name", bad);
        expect_error(p, MCA_ECONFIG, line_of(p, bad == 0 ? "name: lefty" : "name: righty"), field,
                     bad == 0 ? "no arm 'lefty'" : "no arm 'righty'", NULL);
    }
    char text[1024];
    snprintf(text, sizeof text,
             "name: scn-cell\ntask:\n  scenario: %s/config/scenarios/cross_circles.yaml\narms:\n"
             "  - name: left\n    backend: sim\ndds: {enabled: false}\n",
             MCA_SOURCE_DIR);
    const char *p = write_text("scn_count", text);
    expect_error(p, MCA_ECONFIG, line_of(p, "arms:"), "arms: 1 arms but scenario", "has 2", NULL);
}

/* Every shipped cell file loads (they reference the scheme's scenario files and the URDFs). */
/* The bus clash does not depend on the arms' order: a canopen arm and a socketcan arm on one can0 are refused
 * both ways round, at the second arm's interface; a sim arm that names can0 (it opens no bus) is accepted
 * beside a canopen arm both ways round. */
static void test_bus_clash_order(void **state) {
    (void)state;
    static const char *const on_can0[] = {
        "    backend: socketcan\n    interface: can0\n    id_base: 0x140\n",
        "    backend: canopen\n    interface: can0\n",
        "    backend: sim\n    interface: can0\n",
    };
    static const char *const names[] = {"socketcan", "canopen", "sim"};
    static const struct {
        int first, second, refused;
    } cases[] = {{0, 1, 1}, {1, 0, 1}, {2, 1, 0}, {1, 2, 0}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char text[4096];
        int n = snprintf(text, sizeof text,
                         "name: bus-order\ntask:\n  duration: 3.5\nd1: 0.04\nd2: 0.15\narms:\n");
        for (int k = 0; k < 2; k++) {
            n += snprintf(
                text + n, sizeof text - (size_t)n,
                "  - name: a%d\n%s    urdf: %s/config/robots/pa10plus.urdf\n    base_xyz: [0.%d, 0.6, 0.1]\n"
                "    q0: [0.0, 0.3, 0.0, 0.8, 0.0, 0.5, 0.0, 0.0]\n",
                k, on_can0[k ? cases[i].second : cases[i].first], MCA_SOURCE_DIR, k);
        }
        snprintf(text + n, sizeof text - (size_t)n, "dds:\n  enabled: false\n");
        char name[32];
        snprintf(name, sizeof name, "bus_order_%zu", i);
        const char *p = write_text(name, text);
        print_message("%s then %s on can0:\n", names[cases[i].first], names[cases[i].second]);
        if (cases[i].refused) {
            /* the second arm's interface: the line after its backend's */
            expect_error(p, MCA_ECONFIG, line_of(p, "- name: a1") + 2, "arms[1].interface",
                         "can0 is already arms[0]'s (one bus per canopen arm)", NULL);
        } else {
            char err[1024] = "";
            const int rc = mca_cell_load(p, &cell, err, sizeof err);
            if (rc != MCA_OK) {
                fail_msg("refused: %s", err);
            }
        }
    }
}

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
        /* two arms, but the three-arm cell (three_arms_sim: JACO2, MICO2, JACO2) */
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
                                         b ? mca_cell_backend_id("socketcan") : MCA_CELL_BACKEND_SIM);
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
        cmocka_unit_test(test_good_cell),
        cmocka_unit_test(test_missing_file),
        cmocka_unit_test(test_yaml_syntax),
        cmocka_unit_test(test_wrong_type),
        cmocka_unit_test(test_wrong_type_in_arm),
        cmocka_unit_test(test_unknown_key),
        cmocka_unit_test(test_unknown_top_key),
        cmocka_unit_test(test_missing_required),
        cmocka_unit_test(test_d1_ge_d2),
        cmocka_unit_test(test_missing_urdf),
        cmocka_unit_test(test_unknown_backend),
        cmocka_unit_test(test_unknown_backend_id),
        cmocka_unit_test(test_bus_clash_order),
        cmocka_unit_test(test_dof_mismatch),
        cmocka_unit_test(test_q0_outside_limits),
        cmocka_unit_test(test_negative_period),
        cmocka_unit_test(test_debug_kill_hook),
        cmocka_unit_test(test_bad_priority),
        cmocka_unit_test(test_cell_bodies),
        cmocka_unit_test(test_cell_self_pairs),
        cmocka_unit_test(test_cell_bodies_over_scenario),
        cmocka_unit_test(test_scenario_missing),
        cmocka_unit_test(test_socketcan_needs_interface),
        cmocka_unit_test(test_dds_config_missing),
        cmocka_unit_test(test_unknown_scheme),
        cmocka_unit_test(test_dds_priority),
        cmocka_unit_test(test_ros2_keys),
        cmocka_unit_test(test_search_path),
        cmocka_unit_test(test_duplicate_arm),
        cmocka_unit_test(test_shipped_cells),
        cmocka_unit_test(test_mca_ts_keys),
        cmocka_unit_test(test_cell_error_lines),
        cmocka_unit_test(test_arm_error_lines),
        cmocka_unit_test(test_scenario_arm_lines),
    };
    const int failed = cmocka_run_group_tests(tests, NULL, NULL);
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    if (system(cmd) != 0) {
        fprintf(stderr, "could not remove %s\n", tmpdir);
    }
    return failed;
}
