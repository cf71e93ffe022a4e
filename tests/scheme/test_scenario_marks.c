/* SPDX-License-Identifier: MIT */
/* Issue 12: the YAML node locator (model/src/yaml_marks.c) and the exact "FILE:LINE: FIELD:" prefix of
 * every scenario error that names a field (model/src/scenario.c), with the bad field in either arm. */
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

#include "mca/err.h"
#include "mca/path.h"
#include "mca/scenario.h"
#include "mca/yaml_load.h" /* MCA_YAML_MAX_DEPTH */
#include "mca/yaml_marks.h"

static const char *write_tmp(const char *name, const char *text) {
    static char path[256];
    snprintf(path, sizeof path, "/tmp/mca_marks_test_%d_%s.yaml", (int)getpid(), name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    return path;
}

/* ------------------------------------------------------------------ yaml_marks */

static const char doc[] = "name: demo\n"            /* 1 */
                          "nested:\n"               /* 2 */
                          "  a:\n"                  /* 3 */
                          "    b: 1\n"              /* 4 */
                          "  c: 2\n"                /* 5 */
                          "list:\n"                 /* 6 */
                          "  - x: 1\n"              /* 7 */
                          "    y: [0, 0, 0]\n"      /* 8 */
                          "  - x: 2\n"              /* 9 */
                          "    # a comment\n"       /* 10 */
                          "    y:\n"                /* 11 */
                          "      - 1\n"             /* 12 */
                          "      - 2\n"             /* 13 */
                          "flow: [4,\n"             /* 14 */
                          "  5, 6]\n"               /* 15 */
                          "fm: {p: 1, q: [7, 8]}\n" /* 16 */
                          "pts:\n"                  /* 17 */
                          "  - [0, 0, 0]\n"         /* 18 */
                          "  -\n"                   /* 19 */
                          "    - 1\n"               /* 20 */
                          "d1: 0.05\n";             /* 21 */

static void check_doc(const mca_yaml_marks_t *m) {
    static const struct {
        const char *path;
        int line;
    } want[] = {
        {"name", 1},    {"nested", 2},     {"nested.a", 3},   {"nested.a.b", 4},    {"nested.c", 5},
        {"list", 6},    {"list[0]", 7},    {"list[0].x", 7},  {"list[0].y", 8},     {"list[0].y[2]", 8},
        {"list[1]", 9}, {"list[1].x", 9},  {"list[1].y", 11}, {"list[1].y[0]", 12}, {"list[1].y[1]", 13},
        {"flow", 14},   {"flow[0]", 14},   {"flow[1]", 15},   {"flow[2]", 15},      {"fm", 16},
        {"fm.p", 16},   {"fm.q[1]", 16},   {"pts", 17},       {"pts[0]", 18},       {"pts[0][2]", 18},
        {"pts[1]", 20}, {"pts[1][0]", 20}, {"d1", 21},
    };
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        if (mca_yaml_marks_line(m, want[i].path) != want[i].line) {
            print_error("%s: line %d, want %d\n", want[i].path, mca_yaml_marks_line(m, want[i].path),
                        want[i].line);
        }
        assert_int_equal(mca_yaml_marks_line(m, want[i].path), want[i].line);
    }
    /* absent nodes: 0, or the nearest present parent */
    assert_int_equal(mca_yaml_marks_line(m, "list[2]"), 0);
    assert_int_equal(mca_yaml_marks_line(m, "nested.z"), 0);
    assert_int_equal(mca_yaml_marks_line(m, ""), 0);
    assert_int_equal(mca_yaml_marks_line(m, "list[1].y[7]"), 0);
    assert_int_equal(mca_yaml_marks_line_or_parent(m, "list[1].y[7]"), 11);
    assert_int_equal(mca_yaml_marks_line_or_parent(m, "list[1].z.w"), 9);
    assert_int_equal(mca_yaml_marks_line_or_parent(m, "nested.a.q"), 3);
    assert_int_equal(mca_yaml_marks_line_or_parent(m, "list[5].x"), 6);
    assert_int_equal(mca_yaml_marks_line_or_parent(m, "d1"), 21);
    assert_int_equal(mca_yaml_marks_line_or_parent(m, "zz"), 0);
    assert_int_equal(mca_yaml_marks_line_or_parent(m, "zz.y[1]"), 0);
    /* the scalars that are values are not nodes of their own */
    assert_int_equal(mca_yaml_marks_line(m, "demo"), 0);
    assert_int_equal(mca_yaml_marks_line(m, "name.demo"), 0);
}

static void test_marks_doc(void **state) {
    (void)state;
    char err[256];
    mca_yaml_marks_t m;
    const char *p = write_tmp("doc", doc);
    assert_int_equal(mca_yaml_marks_load(p, &m, err, sizeof err), MCA_OK);
    assert_int_equal(m.n, 34); /* every key and every entry of doc, once */
    check_doc(&m);
    mca_yaml_marks_free(&m);
    assert_null(m.mark);
    assert_int_equal(m.n, 0);
    mca_yaml_marks_free(&m); /* twice is fine */
    mca_yaml_marks_free(NULL);
    remove(p);

    assert_int_equal(mca_yaml_marks_parse(doc, strlen(doc), &m, err, sizeof err), MCA_OK);
    check_doc(&m);
    mca_yaml_marks_free(&m);
    /* the first document only (libcyaml loads one) */
    const char two[] = "a: 1\n---\nb: 2\n";
    assert_int_equal(mca_yaml_marks_parse(two, strlen(two), &m, err, sizeof err), MCA_OK);
    assert_int_equal(mca_yaml_marks_line(&m, "a"), 1);
    assert_int_equal(mca_yaml_marks_line(&m, "b"), 0);
    mca_yaml_marks_free(&m);
    /* empty and scalar documents: no marks */
    assert_int_equal(mca_yaml_marks_parse("", 0, &m, err, sizeof err), MCA_OK);
    assert_int_equal(m.n, 0);
    mca_yaml_marks_free(&m);
    assert_int_equal(mca_yaml_marks_parse("# only\n42\n", 10, &m, err, sizeof err), MCA_OK);
    assert_int_equal(m.n, 0);
    mca_yaml_marks_free(&m);
}

static void test_marks_errors(void **state) {
    (void)state;
    char err[256];
    mca_yaml_marks_t m;
    assert_int_equal(mca_yaml_marks_load("/nonexistent/x.yaml", &m, err, sizeof err), MCA_ENOENT);
    assert_non_null(strstr(err, "/nonexistent/x.yaml"));
    assert_int_equal(m.n, 0);
    assert_int_equal(mca_yaml_marks_load(NULL, &m, err, sizeof err), MCA_EINVAL);
    assert_int_equal(mca_yaml_marks_parse(NULL, 0, &m, NULL, 0), MCA_EINVAL);
    /* not YAML: the message names the line */
    const char bad[] = "a: 1\nb: [1, 2\nc: 3\n";
    const char *p = write_tmp("bad", bad);
    assert_int_equal(mca_yaml_marks_load(p, &m, err, sizeof err), MCA_EPARSE);
    assert_null(m.mark);
    char want[300];
    snprintf(want, sizeof want, "%s:", p);
    assert_memory_equal(err, want, strlen(want));
    remove(p);
    const char tab[] = "a:\n\tb: 1\n";
    assert_int_equal(mca_yaml_marks_parse(tab, strlen(tab), &m, err, sizeof err), MCA_EPARSE);
    assert_non_null(strstr(err, "<string>:2:"));
    /* lookups on empty marks */
    mca_yaml_marks_t empty = {.mark = NULL};
    assert_int_equal(mca_yaml_marks_line(&empty, "a"), 0);
    assert_int_equal(mca_yaml_marks_line_or_parent(&empty, "a.b[1]"), 0);
    assert_int_equal(mca_yaml_marks_line(NULL, "a"), 0);
    assert_int_equal(mca_yaml_marks_line_or_parent(&empty, NULL), 0);
}

/* "a: " and `deep` nested flow sequences, then "b: [1]" on line 2 (malloc'd, *n its length). */
static char *nested(int deep, size_t *n) {
    char *text = malloc((size_t)deep * 2 + 64);
    assert_non_null(text);
    *n = (size_t)snprintf(text, 16, "a: ");
    for (int i = 0; i < deep; i++) {
        text[(*n)++] = '[';
    }
    for (int i = 0; i < deep; i++) {
        text[(*n)++] = ']';
    }
    *n += (size_t)snprintf(text + *n, 32, "\nb: [1]\n");
    return text;
}

/* Hostile input: deep nesting and long keys are bounded, the rest is still right. */
static void test_marks_bounds(void **state) {
    (void)state;
    char err[256];
    mca_yaml_marks_t m;
    /* as deep as recorded (a: plus 63 sequences), then a key after them: all there */
    size_t n;
    char *text = nested(MCA_YAML_MARKS_MAX_DEPTH - 1, &n);
    assert_int_equal(mca_yaml_marks_parse(text, n, &m, err, sizeof err), MCA_OK);
    assert_int_equal(mca_yaml_marks_line(&m, "a"), 1);
    assert_int_equal(mca_yaml_marks_line(&m, "a[0][0]"), 1);
    assert_int_equal(mca_yaml_marks_line(&m, "b[0]"), 2);
    assert_true(m.n < 200);
    for (size_t i = 0; i < m.n; i++) {
        assert_true(strlen(m.mark[i].path) < MCA_YAML_MARKS_PATH_MAX);
    }
    mca_yaml_marks_free(&m);
    free(text);
    /* 1000 deep: refused at the bound, its line named, nothing kept (reading stops there: libyaml's
     * scanner costs the open depth per token, 0.6 s for 12 500 levels under ASan) */
    text = nested(1000, &n);
    m.n = 99;
    assert_int_equal(mca_yaml_marks_parse(text, n, &m, err, sizeof err), MCA_EPARSE);
    assert_string_equal(err, "<string>:1: nested deeper than 64 levels");
    assert_true(m.n == 0 && m.mark == NULL);
    /* a scenario file as deep: refused by the loader before libcyaml, FILE:LINE named */
    static mca_scenario_t scn;
    char want[512];
    const char *path = write_tmp("deep", text);
    assert_int_equal(mca_scenario_load(path, &scn, err, sizeof err), MCA_EPARSE);
    snprintf(want, sizeof want, "%s:1: nested deeper than %d levels", path, MCA_YAML_MAX_DEPTH);
    assert_string_equal(err, want);
    unlink(path);
    /* a key longer than a path: not recorded, nor anything below it; its siblings are */
    char key[300];
    memset(key, 'k', sizeof key - 1);
    key[sizeof key - 1] = 0;
    free(text);
    text = malloc(1024);
    assert_non_null(text);
    n = (size_t)snprintf(text, 1024, "top:\n  %s:\n    x: [1, 2]\n  after: {y: 3}\nend: 1\n", key);
    assert_int_equal(mca_yaml_marks_parse(text, n, &m, err, sizeof err), MCA_OK);
    assert_int_equal(m.n, 4); /* top, top.after, top.after.y, end + nothing from the long key */
    assert_int_equal(mca_yaml_marks_line(&m, "top"), 1);
    assert_int_equal(mca_yaml_marks_line(&m, "top.after"), 4);
    assert_int_equal(mca_yaml_marks_line(&m, "top.after.y"), 4);
    assert_int_equal(mca_yaml_marks_line(&m, "end"), 5);
    mca_yaml_marks_free(&m);
    free(text);
    /* more nodes than MCA_YAML_MARKS_MAX: an error, and nothing kept */
    const size_t many = MCA_YAML_MARKS_MAX + 10;
    text = malloc(many * 2 + 16);
    assert_non_null(text);
    n = 0;
    text[n++] = '[';
    for (size_t i = 0; i < many; i++) {
        text[n++] = '0';
        text[n++] = ',';
    }
    text[n - 1] = ']';
    assert_int_equal(mca_yaml_marks_parse(text, n, &m, err, sizeof err), MCA_ERANGE);
    assert_non_null(strstr(err, "more than"));
    assert_null(m.mark);
    assert_int_equal(m.n, 0);
    free(text);
    /* a complex key (a mapping as a key): it and its value are not recorded */
    const char cx[] = "? {a: 1}\n: {b: 2}\nc: 3\n";
    assert_int_equal(mca_yaml_marks_parse(cx, strlen(cx), &m, err, sizeof err), MCA_OK);
    assert_int_equal(m.n, 1);
    assert_int_equal(mca_yaml_marks_line(&m, "c"), 3);
    mca_yaml_marks_free(&m);
}

/* ------------------------------------------------------------------ scenario error lines */

/* "#@" ends the line the error must name; '*' in a field is the bad arm's index. */
struct scase {
    const char *name;
    const char *text; /* an arm (arm cases) or the top-level keys (top cases) */
    const char *field;
};

#define ARM_HEAD(n)                                                                                          \
    "  - name: " n "\n    urdf: " MCA_SOURCE_DIR                                                             \
    "/config/robots/pa10plus.urdf\n    base_xyz: [0, 0, 0]\n    q0: " Q0 "\n"
#define Q0 "[0, 0, 0, 0, 0, 0, 0, 0]" /* pa10plus: 8 joints, 0 within every limit */

/* Valid arms with every optional key, so a locator that counts occurrences would be misled. */
static const char *const good_arms[] = {
    ARM_HEAD("circle") "    base_rpy: [0, 0, 0]\n    path:\n      kind: circle\n      t0: 0.5\n"
                       "      radius: 0.1\n      period: 2\n      turns: 2\n      u: [0, 1, 0]\n"
                       "      v: [1, 0, 0]\n",
    ARM_HEAD("hold") "    path:\n      kind: hold\n",
    ARM_HEAD("wp") "    path:\n      kind: waypoints\n      t0: 1\n      points:\n        - [0, 0, 0]\n"
                   "        - [0.1, 0, 0]\n      durations: [1, 1]\n",
};

#define CIRCLE_TAIL "      radius: 0.1\n      period: 2\n      u: [0, 1, 0]\n      v: [1, 0, 0]\n"

static const struct scase arm_cases[] = {
    /* flow mappings: the field on the line of "path:" (a text scan for "t0:" at a line's start missed it) */
    {"t0_flow",
     ARM_HEAD(
         "bad") "    path: {kind: circle, t0: -1, radius: 0.1, period: 2, u: [0, 1, 0], v: [1, 0, 0]} #@\n",
     "arms[*].path.t0"},
    {"turns_flow",
     ARM_HEAD("bad") "    path: {kind: circle, radius: 0.1, period: 2,\n"
                     "           turns: -1, u: [0, 1, 0], v: [1, 0, 0]} #@\n",
     "arms[*].path.turns"},
    {"base_xyz",
     "  - name: bad\n    urdf: " MCA_SOURCE_DIR
     "/config/robots/pa10plus.urdf\n    base_xyz: [0, 0, 200] #@\n    q0: " Q0 "\n"
     "    path:\n      kind: hold\n",
     "arms[*].base_xyz[2]"},
    {"base_rpy", ARM_HEAD("bad") "    base_rpy: [0, 7, 0] #@\n    path:\n      kind: hold\n",
     "arms[*].base_rpy[1]"},
    {"t0", ARM_HEAD("bad") "    path:\n      kind: circle\n      t0: -1 #@\n" CIRCLE_TAIL, "arms[*].path.t0"},
    {"radius_missing",
     ARM_HEAD(
         "bad") "    path: #@\n      kind: circle\n      period: 2\n      u: [0, 1, 0]\n      v: [1, 0, 0]\n",
     "arms[*].path.radius"},
    {"period_missing",
     ARM_HEAD("bad") "    path: #@\n      kind: circle\n      radius: 0.1\n      u: [0, 1, 0]\n      v: [1, "
                     "0, 0]\n",
     "arms[*].path.period"},
    {"u_missing",
     ARM_HEAD("bad") "    path: #@\n      kind: circle\n      radius: 0.1\n      period: 2\n"
                     "      v: [1, 0, 0]\n",
     "arms[*].path.u/v"},
    {"v_missing",
     ARM_HEAD("bad") "    path: #@\n      kind: circle\n      radius: 0.1\n      period: 2\n"
                     "      u: [1, 0, 0]\n",
     "arms[*].path.u/v"},
    {"radius",
     ARM_HEAD("bad") "    path:\n      kind: circle\n      radius: 0 #@\n      period: 2\n"
                     "      u: [0, 1, 0]\n      v: [1, 0, 0]\n",
     "arms[*].path.radius"},
    {"period",
     ARM_HEAD("bad") "    path:\n      kind: circle\n      radius: 0.1\n      period: -2 #@\n"
                     "      u: [0, 1, 0]\n      v: [1, 0, 0]\n",
     "arms[*].path.period"},
    {"turns", ARM_HEAD("bad") "    path:\n      kind: circle\n" CIRCLE_TAIL "      turns: 0 #@\n",
     "arms[*].path.turns"},
    {"tracking_elastic_tube",
     ARM_HEAD("bad") "    path:\n      kind: circle\n" CIRCLE_TAIL "      tracking: elastic #@\n"
                     "      tolerance: 0.01\n",
     "arms[*].path.tracking"},
    {"u_zero",
     ARM_HEAD("bad") "    path:\n      kind: circle\n      radius: 0.1\n      period: 2\n"
                     "      u: [0, 0, 0] #@\n      v: [1, 0, 0]\n",
     "arms[*].path.u"},
    {"v_parallel",
     ARM_HEAD("bad") "    path:\n      kind: circle\n      radius: 0.1\n      period: 2\n"
                     "      u: [0, 1, 0]\n      v: [0, -3, 0] #@\n",
     "arms[*].path.v"},
    {"points_missing", ARM_HEAD("bad") "    path: #@\n      kind: waypoints\n      durations: [1]\n",
     "arms[*].path.points"},
    {"durations_count",
     ARM_HEAD("bad") "    path:\n      kind: waypoints\n      points:\n        - [0, 0, 0]\n"
                     "        - [1, 0, 0]\n      durations: [1] #@\n",
     "arms[*].path.durations"},
    {"durations_missing",
     ARM_HEAD("bad") "    path: #@\n      kind: waypoints\n      points:\n        - [0, 0, 0]\n",
     "arms[*].path.durations"},
    {"points_value",
     ARM_HEAD("bad") "    path:\n      kind: waypoints\n      points:\n        - [0, 0, 0]\n"
                     "        - [0, 500, 0] #@\n      durations: [1, 1]\n",
     "arms[*].path.points[1][1]"},
    {"points_flow_value",
     ARM_HEAD("bad") "    path:\n      kind: waypoints\n      points: [[0, 0, 0],\n"
                     "               [0, 0, -500]] #@\n      durations: [1, 1]\n",
     "arms[*].path.points[1][2]"},
    /* the model check (mca_scenario_arm_model, shared with cells): q0 against the URDF */
    {"q0_count",
     "  - name: bad\n    urdf: " MCA_SOURCE_DIR "/config/robots/pa10plus.urdf\n    base_xyz: [0, 0, 0]\n"
     "    q0: [0, 0, 0, 0, 0, 0, 0] #@\n    path:\n      kind: hold\n",
     "arms[*].q0"},
    {"q0_limit",
     "  - name: bad\n    urdf: " MCA_SOURCE_DIR "/config/robots/pa10plus.urdf\n    base_xyz: [0, 0, 0]\n"
     "    q0: [0, 1.7, 0, 0, 0, 0, 0, 0] #@\n    path:\n      kind: hold\n",
     "arms[*].q0[1]"},
    {"durations_value",
     ARM_HEAD("bad") "    path:\n      kind: waypoints\n      points:\n        - [0, 0, 0]\n"
                     "        - [1, 0, 0]\n      durations: [1, 0] #@\n",
     "arms[*].path.durations[1]"},
};

static const struct scase top_cases[] = {
    {"dt", "duration: 1\ndt: 1 #@\n", "dt"},
    {"duration", "duration: 7200 #@\n", "duration"},
    {"duration_ticks", "dt: 0.0001\nduration: 3600 #@\n", "duration"},
    {"d1", "duration: 1\nd1: 2 #@\n", "d1"},
    {"d2", "duration: 1\nd2: 5 #@\n", "d2"},
    {"d1d2", "duration: 1\nd1: 0.2 #@\nd2: 0.1\n", "d1/d2"},
    {"d1d2_no_d1", "duration: 1\nd2: 0.01 #@\n", "d1/d2"},
    {"K", "duration: 1\nK: -1 #@\n", "K"},
    {"epsilon", "duration: 1\nepsilon: 0 #@\n", "epsilon"},
    {"v_normal", "duration: 1\nv_normal: 0 #@\n", "v_normal"},
    {"v_floor", "duration: 1\nv_floor: -1 #@\n", "v_floor"},
    {"sample_times", "duration: 1\nsample_times: [0, 1, 9999] #@\n", "sample_times[2]"},
};

/* Load text (which holds one "#@") and require the error to start with "FILE:LINE: FIELD: ". */
static void expect_rc(const char *name, const char *text, const char *field, int arm, int want_rc) {
    const char *mark = strstr(text, "#@");
    assert_non_null(mark);
    assert_null(strstr(mark + 2, "#@"));
    int line = 1;
    for (const char *c = text; c < mark; c++) {
        line += *c == '\n';
    }
    char f[96];
    snprintf(f, sizeof f, "%s", field);
    char *star = strchr(f, '*');
    if (star) {
        *star = (char)('0' + arm);
    }
    static mca_scenario_t s;
    char err[1024] = "";
    const char *p = write_tmp(name, text);
    const int rc = mca_scenario_load(p, &s, err, sizeof err);
    char want[512];
    snprintf(want, sizeof want, "%s:%d: %s: ", p, line, f);
    if (rc != want_rc || strncmp(err, want, strlen(want)) != 0) {
        print_error("case %s (bad arm %d): rc %d\n  got  %s\n  want %s...\n--\n%s--\n", name, arm, rc, err,
                    want, text);
    }
    assert_int_equal(rc, want_rc);
    assert_memory_equal(err, want, strlen(want));
    remove(p);
}

static void expect(const char *name, const char *text, const char *field, int arm) {
    expect_rc(name, text, field, arm, MCA_ECONFIG);
}

static void test_scenario_arm_errors(void **state) {
    (void)state;
    static char text[16384];
    for (size_t c = 0; c < sizeof arm_cases / sizeof arm_cases[0]; c++) {
        for (size_t g = 0; g < sizeof good_arms / sizeof good_arms[0]; g++) {
            for (int bad = 0; bad < 2; bad++) {
                snprintf(text, sizeof text, "name: t\nduration: 1\narms:\n%s%s",
                         bad == 0 ? arm_cases[c].text : good_arms[g],
                         bad == 0 ? good_arms[g] : arm_cases[c].text);
                expect(arm_cases[c].name, text, arm_cases[c].field, bad);
            }
        }
    }
}

/* A URDF that is not there (nor along the search path): MCA_ENOENT with its line, in either arm. */
static void test_scenario_urdf_missing(void **state) {
    (void)state;
    static char text[16384];
    const char *bad_arm = "  - name: bad\n    urdf: ../robots/nothere.urdf #@\n    base_xyz: [0, 0, 0]\n"
                          "    q0: " Q0 "\n    path:\n      kind: hold\n";
    for (int bad = 0; bad < 2; bad++) {
        snprintf(text, sizeof text, "name: t\nduration: 1\narms:\n%s%s", bad == 0 ? bad_arm : good_arms[1],
                 bad == 0 ? good_arms[1] : bad_arm);
        expect_rc("urdf_missing", text, "arms[*].urdf", bad, MCA_ENOENT);
    }
}

/* More points than a path takes (MCA_PATH_MAX_POINTS - 1): the line of "points:", in either arm. */
static void test_scenario_too_many_points(void **state) {
    (void)state;
    static char arm[8192], text[16384];
    size_t n = (size_t)snprintf(arm, sizeof arm,
                                ARM_HEAD("bad") "    path:\n      kind: waypoints\n      points: #@\n");
    for (int i = 0; i < MCA_PATH_MAX_POINTS; i++) {
        n += (size_t)snprintf(arm + n, sizeof arm - n, "        - [0, 0, %d]\n", i);
    }
    snprintf(arm + n, sizeof arm - n, "      durations: [1]\n");
    for (size_t g = 0; g < sizeof good_arms / sizeof good_arms[0]; g++) {
        for (int bad = 0; bad < 2; bad++) {
            snprintf(text, sizeof text, "name: t\nduration: 1\narms:\n%s%s", bad == 0 ? arm : good_arms[g],
                     bad == 0 ? good_arms[g] : arm);
            expect("too_many_points", text, "arms[*].path.points", bad);
        }
    }
}

static void test_scenario_top_errors(void **state) {
    (void)state;
    static char text[8192];
    for (size_t c = 0; c < sizeof top_cases / sizeof top_cases[0]; c++) {
        snprintf(text, sizeof text, "name: t\n%sarms:\n%s%s", top_cases[c].text, good_arms[0], good_arms[1]);
        expect(top_cases[c].name, text, top_cases[c].field, 0);
    }
    /* and the valid arms load */
    snprintf(text, sizeof text, "name: t\nduration: 1\narms:\n%s%s%s", good_arms[0], good_arms[1],
             good_arms[2]);
    static mca_scenario_t s;
    char err[512];
    const char *p = write_tmp("good", text);
    assert_int_equal(mca_scenario_load(p, &s, err, sizeof err), MCA_OK);
    assert_int_equal(s.n_arms, 3);
    remove(p);
}

/* Fixed bodies (mca_scenario_bodies_apply, shared with cells): each error with its file, line and field. */
#define PLANE_HEAD "  - name: table\n    kind: plane\n    point: [0, 0, 0]\n"
static const struct scase body_cases[] = {
    {"clearance", PLANE_HEAD "    normal: [0, 0, 1]\n    clearance: 2 #@\n", "bodies[0].clearance"},
    {"normal_zero", PLANE_HEAD "    normal: [0, 0, 0] #@\n", "bodies[0].normal"},
    {"plane_radius", PLANE_HEAD "    normal: [0, 0, 1]\n    radius: 0.1 #@\n", "bodies[0].radius"},
    {"cylinder_no_radius",
     "  - name: cup #@\n    kind: cylinder\n    centre: [0, 0, 0]\n    half_length: 0.05\n",
     "bodies[0].radius"},
    {"centre_range", "  - name: ball\n    kind: sphere\n    centre: [0, 0, 500] #@\n    radius: 0.1\n",
     "bodies[0].centre[2]"},
    {"box_rpy",
     "  - name: box\n    kind: box\n    centre: [0, 0, 0]\n    half_extents: [0.1, 0.1, 0.1]\n"
     "    rpy: [0, 9, 0] #@\n",
     "bodies[0].rpy[1]"},
    {"box_half", "  - name: box\n    kind: box\n    centre: [0, 0, 0]\n    half_extents: [0.1, -1, 0.1] #@\n",
     "bodies[0].half_extents[1]"},
    {"capsule_radius",
     "  - name: post\n    kind: capsule\n    a: [0, 0, 0]\n    b: [0, 0, 1]\n    radius: -0.1 #@\n",
     "bodies[0].radius"},
    {"allow_arm", PLANE_HEAD "    normal: [0, 0, 1]\n    allow: [circle.base, nobody] #@\n",
     "bodies[0].allow[1]"},
    {"allow_link", PLANE_HEAD "    normal: [0, 0, 1]\n    allow: [hold.9] #@\n", "bodies[0].allow[0]"},
    {"name_twice",
     PLANE_HEAD "    normal: [0, 0, 1]\n  - name: table #@\n    kind: sphere\n"
                "    centre: [0, 0, 1]\n    radius: 0.1\n",
     "bodies[1].name"},
};

static void test_scenario_body_errors(void **state) {
    (void)state;
    static char text[16384];
    for (size_t c = 0; c < sizeof body_cases / sizeof body_cases[0]; c++) {
        snprintf(text, sizeof text, "name: t\nduration: 1\narms:\n%s%sbodies:\n%s", good_arms[0],
                 good_arms[1], body_cases[c].text);
        expect(body_cases[c].name, text, body_cases[c].field, 0);
    }
    /* a key libcyaml does not know: its own line, as every other key's */
    snprintf(text, sizeof text, "name: t\nduration: 1\narms:\n%s%sbodies:\n%s", good_arms[0], good_arms[1],
             PLANE_HEAD "    normal: [0, 0, 1]\n    colour: red #@\n");
    expect_rc("body_unknown_key", text, "bodies[0].colour", 0, MCA_EPARSE);
}

/* Every kind loads; the allow list resolves to link bits in the arms' order; clearance defaults to d1. */
static void test_scenario_bodies_good(void **state) {
    (void)state;
    static char text[16384];
    snprintf(text, sizeof text,
             "name: t\nduration: 1\nd1: 0.04\narms:\n%s%sbodies:\n" PLANE_HEAD
             "    normal: [0, 0, 2]\n    clearance: 0.02\n    allow: [circle.base, hold]\n"
             "  - {name: ball, kind: sphere, centre: [1, 0, 0], radius: 0.1, allow: [hold.tool, hold.3]}\n"
             "  - {name: post, kind: capsule, a: [0, 1, 0], b: [0, 1, 1], radius: 0.05}\n"
             "  - {name: box, kind: box, centre: [0, 0, 2], half_extents: [0.1, 0.2, 0.3], rpy: [0, 0, "
             "1.5707963267948966]}\n"
             "  - {name: cup, kind: cylinder, centre: [0.5, 0.5, 0.05], half_length: 0.05, radius: 0.04}\n",
             good_arms[0], good_arms[1]);
    static mca_scenario_t s;
    char err[512] = "";
    const char *p = write_tmp("bodies_good", text);
    const int rc = mca_scenario_load(p, &s, err, sizeof err);
    if (rc != MCA_OK) {
        print_error("%s\n", err);
    }
    assert_int_equal(rc, MCA_OK);
    remove(p);
    assert_int_equal(s.n_bodies, 5);
    mca_fixed_body_t fb[MCA_MAX_BODIES];
    assert_int_equal(mca_scenario_bodies_resolve(&s, fb, err, sizeof err), MCA_OK);
    assert_int_equal(fb[0].body.kind, MCA_BODY_PLANE);
    assert_true(fb[0].clearance == 0.02);
    assert_int_equal(fb[0].allow[0], 1u);     /* circle.base: link 0 */
    assert_int_equal(fb[0].allow[1], 0x1ffu); /* hold: every link of the 8-joint arm */
    assert_int_equal(fb[1].allow[0], 0u);
    assert_int_equal(fb[1].allow[1], (1u << 8) | (1u << 3)); /* hold.tool (link 8), hold.3 */
    assert_true(fb[1].clearance == 0.04);                    /* d1 */
    assert_int_equal(fb[2].body.kind, MCA_BODY_CAPSULE);
    assert_int_equal(fb[3].body.kind, MCA_BODY_BOX);
    /* the box's first axis turned by yaw 90 degrees: world y */
    assert_true(fabs(fb[3].body.u.box.R[1][0] - 1.0) < 1e-12 && fabs(fb[3].body.u.box.R[0][0]) < 1e-12);
    assert_int_equal(fb[4].body.kind, MCA_BODY_CYLINDER);
    assert_true(fb[4].body.u.cylinder.axis[2] == 1.0); /* axis defaults to z */
    /* the controller's config carries them */
    static mca_controller_config_t cfg;
    assert_int_equal(mca_controller_config_from_scenario(&cfg, &s, MCA_SCHEME_MCA_TS, err, sizeof err),
                     MCA_OK);
    assert_int_equal(cfg.n_bodies, 5);
    assert_int_equal(cfg.body[1].allow[1], (1u << 8) | (1u << 3));
}

/* Self pairs (mca_scenario_self_apply, shared with cells): each error with its file, line and field; a good
 * list turns the robot's default list on (config/robots/pa10plus.self.yaml), adds and takes out pairs. */
static const struct scase self_cases[] = {
    {"self_arm", "self_pairs: [circle, nobody] #@\n", "self_pairs[1]"},
    {"self_link", "self_pairs: [hold.2-9] #@\n", "self_pairs[0]"},
    {"self_adjacent", "self_pairs: [hold.3-4] #@\n", "self_pairs[0]"},
    {"self_same", "self_pairs: [hold, hold.tool-8] #@\n", "self_pairs[1]"},
    {"self_no_pair", "self_pairs: [hold.2] #@\n", "self_pairs[0]"},
    {"self_block", "self_pairs:\n  - hold\n  - wp.0-x #@\n", "self_pairs[1]"},
};

static void test_scenario_self_pairs(void **state) {
    (void)state;
    static char text[16384];
    for (size_t c = 0; c < sizeof self_cases / sizeof self_cases[0]; c++) {
        snprintf(text, sizeof text, "name: t\nduration: 1\narms:\n%s%s%s%s", good_arms[0], good_arms[1],
                 good_arms[2], self_cases[c].text);
        expect(self_cases[c].name, text, self_cases[c].field, 0);
    }
    snprintf(
        text, sizeof text,
        "name: t\nduration: 1\narms:\n%s%s%sself_pairs: [hold, -hold.8-4, circle.2-5, circle.tool-base, wp, "
        "-wp]\n",
        good_arms[0], good_arms[1], good_arms[2]);
    static mca_scenario_t s;
    char err[512] = "";
    const char *p = write_tmp("self_good", text);
    const int rc = mca_scenario_load(p, &s, err, sizeof err);
    if (rc != MCA_OK) {
        print_error("%s\n", err);
    }
    assert_int_equal(rc, MCA_OK);
    remove(p);
    /* hold: the shipped list (4-2, 5-0..5-3, 6-0, 6-1, 6-4, 7-0, 7-1, 7-4, 8-0..8-4) without 8-4 */
    assert_int_equal(s.arm[1].self[4], 1u << 2);
    assert_int_equal(s.arm[1].self[5], 0xfu);
    assert_int_equal(s.arm[1].self[8], 0xfu);
    assert_int_equal(s.arm[1].self[3], 0u);
    /* circle: the two pairs given (stored at the outer link) */
    assert_int_equal(s.arm[0].self[5], 1u << 2);
    assert_int_equal(s.arm[0].self[8], 1u << 0);
    assert_int_equal(s.arm[0].self[4], 0u);
    /* wp: on, then off */
    for (int l = 0; l < MCA_MAX_LINKS; l++) {
        assert_int_equal(s.arm[2].self[l], 0u);
    }
    static mca_controller_config_t cfg;
    assert_int_equal(mca_controller_config_from_scenario(&cfg, &s, MCA_SCHEME_MCA_TS, err, sizeof err),
                     MCA_OK);
    assert_int_equal(cfg.self[1][5], 0xfu);
    assert_int_equal(cfg.self[0][8], 1u);
    assert_true(mca_controller_has_self(&cfg));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scenario_body_errors),
        cmocka_unit_test(test_scenario_bodies_good),
        cmocka_unit_test(test_scenario_self_pairs),
        cmocka_unit_test(test_marks_doc),
        cmocka_unit_test(test_marks_errors),
        cmocka_unit_test(test_marks_bounds),
        cmocka_unit_test(test_scenario_top_errors),
        cmocka_unit_test(test_scenario_arm_errors),
        cmocka_unit_test(test_scenario_too_many_points),
        cmocka_unit_test(test_scenario_urdf_missing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
