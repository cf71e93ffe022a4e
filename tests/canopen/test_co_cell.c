/* SPDX-License-Identifier: MIT */
/* cmocka: `backend: canopen` in cell files (daemon/src/cell.c): the shipped cells load with the fields the
 * backend needs, defaults apply, and each bad canopen key is refused naming it. The shipped cell's path is
 * argv[1]; variants go to /tmp with the cell's relative paths made absolute. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <stdio.h>
#include <limits.h> /* realpath */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mca/cell.h"
#include "mca/err.h"

#include "canopen_cell.h" /* the canopen backend's settings in a cell arm */

static const char *g_src;  /* config/cells/cup_stacking_canopen.yaml */
static const char *g_src2; /* config/cells/cup_stacking_canopen_can.yaml */
static mca_cell_t cell;

/* the shipped cell with the first occurrence of `from` replaced by `to`, in the cell's own directory (its
 * relative scenario path must resolve) */
static const char *variant(const char *tag, const char *from, const char *to) {
    static char path[1024];
    FILE *f = fopen(g_src, "r");
    assert_non_null(f);
    static char buf[65536];
    const size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = 0;
    char *at = from ? strstr(buf, from) : NULL;
    if (from) {
        assert_non_null(at);
    }
    /* written to a temporary file: the cell's relative paths ("../") made absolute (the shipped cell's dir)
     */
    const char *slash = strrchr(g_src, '/');
    char dir[512];
    snprintf(dir, sizeof dir, "%.*s/", (int)(slash - g_src), g_src);
    snprintf(path, sizeof path, "/tmp/test_co_cell_%s_%d.yaml", tag, (int)getpid());
    FILE *o = fopen(path, "w");
    assert_non_null(o);
    for (const char *c = buf; *c; c++) {
        if (at && c == at) {
            fputs(to, o);
            c += strlen(from) - 1;
        } else if (strncmp(c, "../", 3) == 0) {
            fputs(dir, o);
            fputc('.', o);
        } else {
            fputc(*c, o);
        }
    }
    fclose(o);
    return path;
}

static void test_shipped(void **state) {
    (void)state;
    char err[1024] = "";
    assert_int_equal(mca_cell_load(g_src, &cell, err, sizeof err), MCA_OK);
    assert_int_equal(cell.scn.n_arms, 2);
    for (int a = 0; a < 2; a++) {
        assert_int_equal(cell.arm[a].backend, mca_cell_backend_id("canopen"));
        assert_int_equal(mca_canopen_cell_c(&cell.arm[a])->first_node, 1);
        assert_int_equal(mca_canopen_cell_c(&cell.arm[a])->sync_us, 1000);
        assert_int_equal(mca_canopen_cell_c(&cell.arm[a])->mode, 9);
        assert_true(mca_canopen_cell_c(&cell.arm[a])->pos_scale == 1e6 &&
                    mca_canopen_cell_c(&cell.arm[a])->vel_scale == 1e6);
        assert_int_equal(mca_canopen_cell_c(&cell.arm[a])->hb_timeout_ms, 350);
        assert_int_equal(mca_canopen_cell_c(&cell.arm[a])->pdo_timeout, 5);
    }
    assert_string_equal(cell.arm[0].interface, "vcan0");
    assert_string_equal(cell.arm[1].interface, "vcan1");
    assert_string_equal(mca_cell_backend_name(cell.arm[0].backend), "canopen");
    assert_int_equal(mca_cell_load(g_src2, &cell, err, sizeof err), MCA_OK);
    assert_string_equal(cell.arm[0].interface, "can0");
    assert_int_equal(mca_canopen_cell_c(&cell.arm[1])->sync_us, 4000);
}

static void expect_bad(const char *tag, const char *from, const char *to, const char *piece) {
    char err[1024] = "";
    const char *p = variant(tag, from, to);
    const int rc = mca_cell_load(p, &cell, err, sizeof err);
    unlink(p);
    print_message("  %s: %s\n", tag, err);
    assert_int_not_equal(rc, MCA_OK);
    if (!strstr(err, piece)) {
        fail_msg("message '%s' lacks '%s'", err, piece);
    }
}

static void test_bad(void **state) {
    (void)state;
    expect_bad("node0", "first_node: 1", "first_node: 0", "canopen.first_node: 1..127");
    expect_bad("mode", "mode: csv", "mode: pp1", "canopen.mode: csv or csp");
    expect_bad("scale", "pos_scale: 1000000", "pos_scale: -1", "pos_scale and vel_scale must be > 0");
    expect_bad("sync", "sync_us: 1000", "sync_us: 10", "canopen.sync_us: >= 100");
    expect_bad("hb", "vel_scale: 1000000", "vel_scale: 1000000\n      heartbeat_timeout_ms: 50",
               "heartbeat_timeout_ms");
    expect_bad("samebus", "interface: vcan1", "interface: vcan0", "one bus per canopen arm");
    expect_bad("noif", "    interface: vcan0\n", "", "interface: required with backend canopen");
    expect_bad("simblock", "backend: canopen", "backend: sim", "canopen: only with backend canopen");
}

static void test_defaults_and_csp(void **state) {
    (void)state;
    char err[1024] = "";
    const char *p = variant("csp", "      mode: csv\n", "      mode: csp\n      pdo_timeout_syncs: 40\n");
    const int rc = mca_cell_load(p, &cell, err, sizeof err);
    unlink(p);
    assert_int_equal(rc, MCA_OK);
    assert_int_equal(mca_canopen_cell_c(&cell.arm[0])->mode, 8);
    assert_int_equal(mca_canopen_cell_c(&cell.arm[0])->pdo_timeout, 40);
    assert_int_equal(mca_canopen_cell_c(&cell.arm[1])->mode, 9);
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: test_co_cell CUP_STACKING_CANOPEN.yaml CUP_STACKING_CANOPEN_CAN.yaml\n");
        return 2;
    }
    static char abs1[4096], abs2[4096];
    if (!realpath(argv[1], abs1) || !realpath(argv[2], abs2)) {
        fprintf(stderr, "test_co_cell: %s or %s not found\n", argv[1], argv[2]);
        return 1;
    }
    g_src = abs1;
    g_src2 = abs2;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shipped),
        cmocka_unit_test(test_bad),
        cmocka_unit_test(test_defaults_and_csp),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
