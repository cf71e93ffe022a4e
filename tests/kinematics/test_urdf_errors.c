/* SPDX-License-Identifier: MIT */
/* mca_chain_load_urdf on bad and unusual URDFs (tests/kinematics/data/): each error returns its
 * code, names the file and the faulty element, and leaves the chain untouched; fixed joints are
 * folded correctly and side branches are ignored when the tip is named. */
#include "kin_test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifndef KIN_DATA_DIR
#error "KIN_DATA_DIR must be set by CMake"
#endif

#define ERRLEN 512

typedef struct {
    char path[512];
    char err[ERRLEN];
    mca_chain_t chain;
    int rc;
} load_t;

/* Load data/<file>; the chain starts filled with a sentinel byte to detect writes on error. */
static void load_data(load_t *l, const char *file, const char *tip) {
    snprintf(l->path, sizeof(l->path), "%s/%s", KIN_DATA_DIR, file);
    memset(&l->chain, 0xA5, sizeof(l->chain));
    memset(l->err, 0, sizeof(l->err));
    l->rc = mca_chain_load_urdf(&l->chain, l->path, tip, l->err, sizeof(l->err));
    print_message("%s -> rc %d: %s\n", file, l->rc, l->err);
}

static void assert_error(const load_t *l, int rc, const char *needle1, const char *needle2) {
    assert_int_equal(l->rc, rc);
    /* the message starts with the file path, then names the element */
    assert_int_equal(strncmp(l->err, l->path, strlen(l->path)), 0);
    if (needle1) {
        assert_non_null(strstr(l->err, needle1));
    }
    if (needle2) {
        assert_non_null(strstr(l->err, needle2));
    }
    mca_chain_t sentinel;
    memset(&sentinel, 0xA5, sizeof(sentinel));
    assert_memory_equal(&l->chain, &sentinel, sizeof(sentinel));
}

static void test_missing_file(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "does_not_exist.urdf", "tool_tip");
    assert_error(&l, MCA_ENOENT, "cannot open", "No such file");
}

static void test_malformed_xml(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "malformed.urdf", NULL);
    assert_error(&l, MCA_EPARSE, "malformed XML", "line ");
}

static void test_prismatic(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "prismatic.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "joint 'slider'", "prismatic");
    assert_non_null(strstr(l.err, "line 12"));
}

static void test_revolute_without_limit(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "nolimit.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "joint 'j2'", "revolute joint has no <limit>");
    assert_non_null(strstr(l.err, "line 12"));
}

static void test_continuous_without_limit(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "continuous_nolimit.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "joint 'spin'", "<limit>");
}

static void test_zero_velocity_limit(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "no_velocity.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "joint 'j1'", "velocity");
}

/* velocity="1e300" would switch the velocity bounds off; limits are in (0, MCA_JOINT_VEL_MAX] */
static void test_huge_velocity_limit(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "huge_velocity.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "line 5: joint 'j1'",
                 "<limit velocity> must be in (0, 100] rad/s (got 1e+300)");
}

static void test_zero_axis(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "zero_axis.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "joint 'j1'", "<axis>");
}

static void test_too_many_joints(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "toomany.urdf", "tool_tip");
    assert_error(&l, MCA_ERANGE, "9 revolute joints", "MCA_MAX_DOF (8)");
}

static void test_unknown_tip(void **state) {
    (void)state;
    load_t l;
    snprintf(l.path, sizeof(l.path), "%s/jaco2.urdf", MCA_ROBOTS_DIR);
    memset(&l.chain, 0xA5, sizeof(l.chain));
    l.rc = mca_chain_load_urdf(&l.chain, l.path, "no_such_link", l.err, sizeof(l.err));
    print_message("jaco2.urdf tip 'no_such_link' -> rc %d: %s\n", l.rc, l.err);
    assert_error(&l, MCA_ENOENT, "tip link 'no_such_link'", NULL);
}

static void test_unknown_parent_link(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "bad_parent.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "ghost_link", NULL);
}

/* Issue 16, found by fuzz/fuzz_urdf (fuzz/regress/urdf/leak-*): a link that is its own parent, and a loop
 * of links, made urdfdom leak its shared_ptr cycles; refused before urdfdom, named. */
static void test_self_parent(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "self_parent.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "joint 'joint_3'", "its own parent");
}

static void test_link_loop(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "link_loop.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "link 'link_1' already has a parent", NULL);
}

static void test_branch_without_tip(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "branched.urdf", NULL);
    assert_error(&l, MCA_EPARSE, "leaf links", "'camera'");
}

static void test_branch_with_tip(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "branched.urdf", "tool_tip");
    assert_int_equal(l.rc, MCA_OK);
    assert_int_equal(l.chain.dof, 2);
    assert_string_equal(l.chain.joint[0].name, "j1");
    assert_string_equal(l.chain.joint[1].name, "j2");
    /* a tip inside the chain: the chain stops there */
    load_data(&l, "branched.urdf", "l1");
    assert_int_equal(l.rc, MCA_OK);
    assert_int_equal(l.chain.dof, 1);
}

static void test_fixed_fold(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "fixed_fold.urdf", NULL); /* single leaf: tool_tip */
    assert_int_equal(l.rc, MCA_OK);
    assert_string_equal(l.chain.name, "fixed_fold");
    assert_int_equal(l.chain.dof, 2);
    assert_true(l.chain.joint[1].continuous);
    assert_true(isinf(l.chain.joint[1].lower) && l.chain.joint[1].lower < 0);
    assert_true(isinf(l.chain.joint[1].upper) && l.chain.joint[1].upper > 0);
    assert_true(fabs(l.chain.joint[1].vel_limit - 2.5) < 1e-15);
    assert_true(fabs(l.chain.joint[1].axis[2] - 1.0) < 1e-15); /* (0 0 2) normalised */
    /* radii: link 0 = plate sphere, link 1 = cover cylinder on a fixed child, link 2 = max of two */
    assert_true(fabs(l.chain.link_radius[0] - 0.11) < 1e-15);
    assert_true(fabs(l.chain.link_radius[1] - 0.07) < 1e-15);
    assert_true(fabs(l.chain.link_radius[2] - 0.05) < 1e-15);
    uint64_t seed = 99;
    for (int n = 0; n < 100; n++) {
        const double q[2] = {kin_rand(&seed, -3, 3), kin_rand(&seed, -10, 10)};
        mca_kin_t k;
        assert_int_equal(mca_fk(&l.chain, q, &k), MCA_OK);
        /* expected, worked out by hand in data/fixed_fold.urdf */
        const double c1 = cos(q[0]), s1 = sin(q[0]);
        const double j2[3] = {c1 * 0.3 - s1 * 0.1, s1 * 0.3 + c1 * 0.1, 0.3};
        const double a = q[0] + KIN_PI / 2 + q[1];
        const double tip[3] = {j2[0] + 0.2 * cos(a), j2[1] + 0.2 * sin(a), 0.3};
        const double p1[3] = {0, 0, 0.3};
        for (int i = 0; i < 3; i++) {
            assert_true(fabs(k.point[0][i]) < 1e-15);
            assert_true(fabs(k.point[1][i] - p1[i]) < 1e-12);
            assert_true(fabs(k.point[2][i] - j2[i]) < 1e-12);
            assert_true(fabs(k.point[3][i] - tip[i]) < 1e-12);
        }
    }
}

static void test_null_arguments(void **state) {
    (void)state;
    char path[512], err[ERRLEN];
    snprintf(path, sizeof(path), "%s/jaco2.urdf", MCA_ROBOTS_DIR);
    mca_chain_t c;
    assert_int_equal(mca_chain_load_urdf(NULL, path, NULL, err, sizeof(err)), MCA_EINVAL);
    assert_int_equal(mca_chain_load_urdf(&c, NULL, NULL, err, sizeof(err)), MCA_EINVAL);
    /* err may be NULL, and a tiny buffer is truncated, not overrun */
    assert_int_equal(mca_chain_load_urdf(&c, path, "nope", NULL, 0), MCA_ENOENT);
    char tiny[8];
    memset(tiny, 'x', sizeof(tiny));
    assert_int_equal(mca_chain_load_urdf(&c, path, "nope", tiny, 5), MCA_ENOENT);
    assert_int_equal(tiny[4], '\0');
    assert_int_equal(tiny[5], 'x');
    /* success clears the message */
    strcpy(err, "stale");
    assert_int_equal(mca_chain_load_urdf(&c, path, "tool_tip", err, sizeof(err)), MCA_OK);
    assert_string_equal(err, "");
}

static void test_empty_file(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "empty.urdf", NULL);
    assert_error(&l, MCA_EPARSE, "malformed XML", NULL);
}

static void test_not_a_robot(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "not_robot.urdf", NULL);
    assert_error(&l, MCA_EPARSE, "<robot>", NULL);
}

static void test_bad_interval(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "bad_interval.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "joint 'j1'", "not a finite interval");
}

static void test_no_revolute_joint(void **state) {
    (void)state;
    load_t l;
    load_data(&l, "only_fixed.urdf", "tool_tip");
    assert_error(&l, MCA_EPARSE, "no revolute joint", NULL);
}

static void test_directory(void **state) {
    (void)state;
    load_t l;
    load_data(&l, ".", NULL); /* the data directory itself */
    assert_error(&l, MCA_EIO, "cannot read", "directory");
}

/* Issue 16: a URDF nested 50 000 deep overflowed the stack in TinyXML's recursive parser. The depth is now
 * bounded (256) by a scan before any parser runs: a clean EPARSE naming the line of the first element too
 * deep. The file is written here (about 400 kB): <robot> on line 2, one <link> per line after it, so the
 * element at depth 257 (link l256) is on line 258. */
static void write_nested(const char *path, int levels, const char *extra) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "<?xml version=\"1.0\"?>\n<robot name=\"deep\">");
    for (int i = 1; i < levels; i++) {
        fprintf(f, "\n<link name=\"l%d\"%s>", i, extra);
    }
    for (int i = 1; i < levels; i++) {
        fputs("</link>", f);
    }
    fputs("</robot>\n", f);
    fclose(f);
}

static void test_nested_too_deep(void **state) {
    (void)state;
    char path[] = "/tmp/mca-deep-XXXXXX";
    const int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    write_nested(path, 50000, "");
    load_t l;
    snprintf(l.path, sizeof(l.path), "%s", path);
    memset(&l.chain, 0xA5, sizeof(l.chain));
    l.rc = mca_chain_load_urdf(&l.chain, path, NULL, l.err, sizeof(l.err));
    print_message("50000 levels -> rc %d: %s\n", l.rc, l.err);
    assert_error(&l, MCA_EPARSE, "line 258: elements nested deeper than 256 levels", NULL);
    /* exactly 256 levels (attribute values with '>' and '/>' inside quotes, a comment with tags) pass the
     * depth scan and fail later for what they are: links without joints, no chain */
    write_nested(path, 256, " a=\"x > y\" b='/>' ");
    FILE *f = fopen(path, "a");
    assert_non_null(f);
    fputs("<!-- <a><a><a> -->\n", f);
    fclose(f);
    l.rc = mca_chain_load_urdf(&l.chain, path, NULL, l.err, sizeof(l.err));
    print_message("256 levels -> rc %d: %s\n", l.rc, l.err);
    assert_int_equal(l.rc, MCA_EPARSE);
    assert_null(strstr(l.err, "nested"));
    unlink(path);
}

/* jaco2.urdf with `insert` put in at the first occurrence of `at` (or appended when NULL) into a temp file
 * (`len` bytes of insert: it may hold NUL bytes); loads it with the tool tip. */
static void load_jaco_with(load_t *l, const char *at, const char *insert, size_t len) {
    char src[512];
    snprintf(src, sizeof src, "%s/jaco2.urdf", MCA_ROBOTS_DIR);
    FILE *f = fopen(src, "rb");
    assert_non_null(f);
    static char text[1 << 16];
    const size_t n = fread(text, 1, sizeof text, f);
    fclose(f);
    assert_true(n > 0 && n < sizeof text);
    text[n] = '\0';
    const char *p = at ? strstr(text, at) : text + n;
    assert_non_null(p);
    snprintf(l->path, sizeof l->path, "/tmp/mca-utf8-XXXXXX");
    const int fd = mkstemp(l->path);
    assert_true(fd >= 0);
    f = fdopen(fd, "wb");
    assert_non_null(f);
    fwrite(text, 1, (size_t)(p - text), f);
    fwrite(insert, 1, len, f);
    fwrite(p, 1, n - (size_t)(p - text), f);
    fclose(f);
    memset(&l->chain, 0xA5, sizeof l->chain);
    l->rc = mca_chain_load_urdf(&l->chain, l->path, "tool_tip", l->err, sizeof l->err);
    print_message("jaco2 + %zu bytes -> rc %d: %s\n", len, l->rc, l->err);
    unlink(l->path);
}

/* Issue 16 (fuzz/fuzz_urdf): a UTF-8 lead byte among the last bytes of the text made TinyXML read past the
 * string's end (heap overflow in TiXmlBase::ReadName under ASan; fuzz/regress/urdf/utf8-lead-at-end). The
 * loader takes UTF-8 text only and names the first byte that is not. */
static void test_not_utf8(void **state) {
    (void)state;
    load_t l;
    /* the fuzzer's case: a 4-byte lead at the end, inside a name */
    load_jaco_with(&l, NULL, "<a\n  io\xf4", 8);
    assert_error(&l, MCA_EPARSE, "line 98, column 5: byte 0xF4 is not UTF-8 text", NULL);
    /* inside the file: an overlong form, a surrogate, a lone continuation byte, a cut sequence, a NUL */
    static const struct {
        const char *bytes;
        size_t len;
        const char *want;
    } bad[] = {
        {"\xc0\xaf", 2, "byte 0xC0 is not UTF-8"},
        {"\xed\xa0\x80", 3, "byte 0xED is not UTF-8"},
        {"\x80", 1, "byte 0x80 is not UTF-8"},
        {"\xe2\x82 ", 3, "byte 0xE2 is not UTF-8"},
        {"\xf4\x90\x80\x80", 4, "byte 0xF4 is not UTF-8"},
        {"\0x", 2, "NUL byte: not a text file"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        load_jaco_with(&l, "<robot", bad[i].bytes, bad[i].len);
        assert_error(&l, MCA_EPARSE, bad[i].want, "line 8, column 1: ");
    }
    /* UTF-8 text loads: 2-, 3- and 4-byte characters in a comment */
    const char ok[] = "<!-- 60\xc2\xb0 wrist, \xe2\x80\x9cJACO\xe2\x80\x9d \xf0\x9f\xa6\xbe -->\n";
    load_jaco_with(&l, "<robot", ok, sizeof ok - 1);
    assert_int_equal(l.rc, MCA_OK);
    assert_int_equal(l.chain.dof, 6);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_missing_file),
        cmocka_unit_test(test_self_parent),
        cmocka_unit_test(test_link_loop),
        cmocka_unit_test(test_malformed_xml),
        cmocka_unit_test(test_not_utf8),
        cmocka_unit_test(test_prismatic),
        cmocka_unit_test(test_revolute_without_limit),
        cmocka_unit_test(test_continuous_without_limit),
        cmocka_unit_test(test_zero_velocity_limit),
        cmocka_unit_test(test_huge_velocity_limit),
        cmocka_unit_test(test_zero_axis),
        cmocka_unit_test(test_too_many_joints),
        cmocka_unit_test(test_unknown_tip),
        cmocka_unit_test(test_unknown_parent_link),
        cmocka_unit_test(test_branch_without_tip),
        cmocka_unit_test(test_branch_with_tip),
        cmocka_unit_test(test_fixed_fold),
        cmocka_unit_test(test_null_arguments),
        cmocka_unit_test(test_empty_file),
        cmocka_unit_test(test_not_a_robot),
        cmocka_unit_test(test_bad_interval),
        cmocka_unit_test(test_no_revolute_joint),
        cmocka_unit_test(test_directory),
        cmocka_unit_test(test_nested_too_deep),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
