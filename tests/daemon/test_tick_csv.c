/* SPDX-License-Identifier: MIT */
/* The per-tick CSV writer (mca/tick_csv.h): mcad's layout and mca-sim's, header and row, to the byte. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "mca/tick_csv.h"

/* Two arms of one joint each (three for the pair columns), every figure set to a value whose digits show. */
static void fill(mca_tick_info_t *in, double q[][MCA_MAX_DOF], double qd[][MCA_MAX_DOF]) {
    memset(in, 0, sizeof *in);
    for (int a = 0; a < 3; a++) {
        q[a][0] = 0.1 + a / 3.0;
        qd[a][0] = -0.25 * (a + 1);
        for (int c = 0; c < 3; c++) {
            in->ee[a][c] = 1.0 / (3 + a + c);
            in->ee_desired[a][c] = in->ee[a][c] + 1e-3;
        }
        in->ee_error[a] = 1.7320508e-3;
        in->tau[a] = 0.5 * a;
        in->sigma[a] = 1.0;
    }
    in->min_distance = 2.0 / 7.0;
    in->min_arm_b = 1;
    in->min_link_a = 2;
    in->min_link_b = 3;
    for (int c = 0; c < 3; c++) {
        in->min_p[c] = 1.0 / 9.0 + c;
        in->min_e[c] = 1.0 / 11.0 + c;
    }
    in->brake = 0.75;
    in->active_rows = 4;
    in->binding_rows = 1;
    in->pdnn_steps = 37;
    in->pdnn_residual = 1.25e-7;
    in->eq_residual = 3e-9;
    in->compute_ns = 21000;
}

static char *write_csv(const mca_tick_csv_layout_t *l, const mca_tick_csv_row_t *r) {
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    mca_tick_csv_header(f, l);
    mca_tick_csv_row(f, l, r);
    fclose(f);
    return buf;
}

static void test_mcad_layout(void **state) {
    (void)state;
    mca_tick_info_t in;
    double q[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}}, qd[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}};
    fill(&in, q, qd);
    const mca_tick_csv_layout_t l = {.n_arms = 2, .dof = {1, 1}, .exact = 1, .daemon_cols = 1};
    const mca_tick_csv_row_t r = {
        .t = 1.5, .q = q, .info = &in, .state = 2, .qdot_cmd = qd, .cmd_gap_ns = 1234, .wake_ns = 5000000123};
    char *s = write_csv(&l, &r);
    assert_string_equal(
        s,
        "t,q0_0,q1_0,ee0_x,ee0_y,ee0_z,rd0_x,rd0_y,rd0_z,err0_x,err0_y,err0_z,err0,ee1_x,ee1_y,ee1_z,rd1_x,"
        "rd1_y,rd1_z,err1_x,err1_y,err1_z,err1,min_d,arm_a,link_a,arm_b,link_b,p_x,p_y,p_z,e_x,e_y,e_z,brake,"
        "active_rows,binding_rows,pdnn_steps,pdnn_residual,eq_residual,compute_ns,fault,state,qdot0_0,"
        "qdot1_0,tau0,sigma0,tau1,sigma1,deadlock,deadlock_arm,deadlocks,brake_fallback,cmd_gap_us,wake_ns\n"
        "1.5000,0.10000000000000001,0.43333333333333335,0.33333333333333331,0.25,0.20000000000000001,"
        "0.334333333,0.251,0.201,0.001,0.001,0.001,0.001732,0.25,0.20000000000000001,0.16666666666666666,"
        "0.251,0.201,0.167666667,0.001,0.001,0.001,0.001732,0.2857142857142857,0,2,1,3,"
        "0.1111111111111111,1.1111111111111112,2.1111111111111112,0.090909090909090912,1.0909090909090908,"
        "2.0909090909090908,0.75,4,1,37,1.25e-07,3e-09,21000,0,2,-0.25,-0.5,0.000000,1,0.500000,1,0,0,0,0,"
        "1.2,5000000123\n");
    free(s);
}

static void test_sim_layout_pairs(void **state) {
    (void)state;
    mca_tick_info_t in;
    double q[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}}, qd[MCA_MAX_ARMS][MCA_MAX_DOF] = {{0}};
    fill(&in, q, qd);
    static mca_arm_distances_t dist[MCA_MAX_ARMS][MCA_MAX_ARMS];
    dist[0][1].min.d = 0.3;
    dist[0][2].min.d = 1.0 / 3.0;
    dist[1][2].min.d = 2.0 / 7.0;
    mca_tick_csv_layout_t l = {.n_arms = 3, .dof = {1, 1, 1}, .pair_cols = 1};
    const mca_tick_csv_row_t r = {.t = 0.001, .q = q, .info = &in, .dist = dist};
    char *s = write_csv(&l, &r);
    assert_string_equal(
        s,
        "t,q0_0,q1_0,q2_0,ee0_x,ee0_y,ee0_z,rd0_x,rd0_y,rd0_z,err0_x,err0_y,err0_z,err0,ee1_x,ee1_y,ee1_z,"
        "rd1_x,rd1_y,rd1_z,err1_x,err1_y,err1_z,err1,ee2_x,ee2_y,ee2_z,rd2_x,rd2_y,rd2_z,err2_x,err2_y,"
        "err2_z,err2,min_d,arm_a,link_a,arm_b,link_b,p_x,p_y,p_z,e_x,e_y,e_z,brake,active_rows,binding_rows,"
        "pdnn_steps,pdnn_residual,eq_residual,compute_ns,fault,d_0_1,d_0_2,d_1_2\n"
        "0.0010,0.1,0.433333333,0.766666667,0.333333333,0.25,0.2,0.334333333,0.251,0.201,0.001,0.001,0.001,"
        "0.001732,0.25,0.2,0.166666667,0.251,0.201,0.167666667,0.001,0.001,0.001,0.001732,0.2,0.166666667,"
        "0.142857143,0.201,0.167666667,0.143857143,0.001,0.001,0.001,0.001732,0.285714286,0,2,1,3,0.111111,"
        "1.11111,2.11111,0.0909091,1.09091,2.09091,0.75,4,1,37,1.25e-07,3e-09,21000,0,0.3,0.333333333,"
        "0.285714286\n");
    free(s);
    /* two arms: no pair columns (min_d is the one pair's distance) */
    l.n_arms = 2;
    s = write_csv(&l, &r);
    assert_non_null(strstr(s, ",compute_ns,fault\n"));
    assert_non_null(strstr(s, ",21000,0\n"));
    free(s);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mcad_layout),
        cmocka_unit_test(test_sim_layout_pairs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
