/* SPDX-License-Identifier: MIT */
/* The per-tick CSV of mcad and mca-sim (see mca/tick_csv.h). */
#include "mca/tick_csv.h"

void mca_tick_csv_header(FILE *f, const mca_tick_csv_layout_t *l) {
    fprintf(f, "t");
    for (int a = 0; a < l->n_arms; a++) {
        for (int j = 0; j < l->dof[a]; j++) {
            fprintf(f, ",q%d_%d", a, j);
        }
    }
    for (int a = 0; a < l->n_arms; a++) {
        fprintf(f, ",ee%d_x,ee%d_y,ee%d_z,rd%d_x,rd%d_y,rd%d_z,err%d_x,err%d_y,err%d_z,err%d", a, a, a, a, a,
                a, a, a, a, a);
    }
    fprintf(f, ",min_d,arm_a,link_a,arm_b,link_b,p_x,p_y,p_z,e_x,e_y,e_z,brake,active_rows,binding_rows,"
               "pdnn_steps,pdnn_residual,eq_residual,compute_ns,fault");
    if (l->daemon_cols) {
        fprintf(f, ",state");
        for (int a = 0; a < l->n_arms; a++) {
            for (int j = 0; j < l->dof[a]; j++) {
                fprintf(f, ",qdot%d_%d", a, j);
            }
        }
        /* mca-ts path clocks and deadlock state; braking fallback (appended: older readers unaffected) */
        for (int a = 0; a < l->n_arms; a++) {
            fprintf(f, ",tau%d,sigma%d", a, a);
        }
        fprintf(f, ",deadlock,deadlock_arm,deadlocks,brake_fallback,cmd_gap_us,wake_ns");
    }
    for (int a = 0; l->pair_cols && l->n_arms >= 3 && a < l->n_arms; a++) {
        for (int b = a + 1; b < l->n_arms; b++) {
            fprintf(f, ",d_%d_%d", a, b);
        }
    }
    if (l->body_cols) {
        fprintf(f, ",body_d,body_margin,body_arm,body_link,body,body_kind");
    }
    if (l->self_cols) {
        fprintf(f, ",self_d,self_arm,self_link,self_other");
    }
    fprintf(f, "\n");
}

void mca_tick_csv_row(FILE *f, const mca_tick_csv_layout_t *l, const mca_tick_csv_row_t *r) {
    const mca_tick_info_t *in = r->info;
    /* mcad's exact digits: DDS subscribers compare their samples with these columns */
    const int x = l->exact ? 17 : 9, pt = l->exact ? 17 : 6;
    fprintf(f, "%.4f", r->t);
    for (int a = 0; a < l->n_arms; a++) {
        for (int j = 0; j < l->dof[a]; j++) {
            fprintf(f, ",%.*g", x, r->q[a][j]);
        }
    }
    for (int a = 0; a < l->n_arms; a++) {
        for (int c = 0; c < 3; c++) {
            fprintf(f, ",%.*g", x, in->ee[a][c]);
        }
        fprintf(f, ",%.9g,%.9g,%.9g,%.4g,%.4g,%.4g,%.4g", in->ee_desired[a][0], in->ee_desired[a][1],
                in->ee_desired[a][2], in->ee_desired[a][0] - in->ee[a][0],
                in->ee_desired[a][1] - in->ee[a][1], in->ee_desired[a][2] - in->ee[a][2], in->ee_error[a]);
    }
    fprintf(f, ",%.*g", x, in->min_distance);
    fprintf(f, ",%d,%d,%d,%d", in->min_arm_a, in->min_link_a, in->min_arm_b, in->min_link_b);
    for (int c = 0; c < 3; c++) {
        fprintf(f, ",%.*g", pt, in->min_p[c]);
    }
    for (int c = 0; c < 3; c++) {
        fprintf(f, ",%.*g", pt, in->min_e[c]);
    }
    fprintf(f, ",%.6g,%d,%d,%d,%.3g,%.3g,%lld,%d", in->brake, in->active_rows, in->binding_rows,
            in->pdnn_steps, in->pdnn_residual, in->eq_residual, (long long)in->compute_ns, in->fault);
    if (l->daemon_cols) {
        fprintf(f, ",%d", r->state);
        for (int a = 0; a < l->n_arms; a++) {
            for (int j = 0; j < l->dof[a]; j++) {
                fprintf(f, ",%.6g", r->qdot_cmd[a][j]);
            }
        }
        for (int a = 0; a < l->n_arms; a++) {
            fprintf(f, ",%.6f,%.6g", in->tau[a], in->sigma[a]);
        }
        fprintf(f, ",%d,%d,%d,%d,%.1f,%lld", in->deadlock, in->deadlock_arm, in->deadlocks,
                in->brake_fallback, (double)r->cmd_gap_ns * 1e-3, (long long)r->wake_ns);
    }
    for (int a = 0; l->pair_cols && l->n_arms >= 3 && a < l->n_arms; a++) {
        for (int b = a + 1; b < l->n_arms; b++) {
            fprintf(f, ",%.*g", x, r->dist[a][b].min.d);
        }
    }
    if (l->body_cols) {
        fprintf(f, ",%.*g,%.*g,%d,%d,%d,%s", x, in->body_distance, x, in->body_margin, in->body_arm,
                in->body_link, in->body_index, mca_body_kind_name(in->body_kind));
    }
    if (l->self_cols) {
        fprintf(f, ",%.*g,%d,%d,%d", x, in->self_distance, in->self_arm, in->self_link, in->self_other);
    }
    fputc('\n', f);
}
