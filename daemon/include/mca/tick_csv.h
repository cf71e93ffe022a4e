/* SPDX-License-Identifier: MIT */
/** @file mca/tick_csv.h
 * The per-tick CSV of a run, one writer for mcad (--csv, from its CSV ring) and mca-sim (--csv): a header,
 * then one row per tick with the time, the measured positions, each arm's end effector against its desired
 * point, the closest pair and the solver's figures (tools/plots and the tests parse them by column name).
 * The two callers differ only in what a layout selects: mcad writes positions, end effectors and the
 * closest points exactly (%.17g: DDS subscribers compare their samples with them) and adds its state, the
 * commanded velocities, the mca-ts clocks and the command gap; mca-sim writes 9 (points 6) significant
 * digits and, with three or more arms, the distance of every pair.
 *
 * Context: non-rt (formats text, writes a FILE); the real-time loop only fills the row's data.
 */
#ifndef MCA_TICK_CSV_H
#define MCA_TICK_CSV_H

#include <stdint.h>
#include <stdio.h>

#include "mca/controller.h" /* mca_tick_info_t, mca_arm_distances_t, MCA_MAX_ARMS, MCA_MAX_DOF */

#ifdef __cplusplus
extern "C" {
#endif

/** Which columns a CSV has and how its numbers are written. */
typedef struct mca_tick_csv_layout {
    int n_arms;
    int dof[MCA_MAX_ARMS];
    int exact;       /**< 1: q, ee, min_d, p, e in %.17g (mcad); 0: q, ee, min_d %.9g, p, e %.6g (mca-sim) */
    int daemon_cols; /**< 1: state, qdot<a>_<j> (commanded), tau<a>, sigma<a>, deadlock*, brake_fallback,
                          cmd_gap_us, wake_ns after fault (mcad) */
    int pair_cols;   /**< 1: with three or more arms, d_<a>_<b> of every pair last (min_d is only the
                          smallest of them; mca-sim) */
    int body_cols;   /**< 1: the arm-body pair of least margin last: body_d, body_margin, body_arm,
                          body_link, body, body_kind (a cell with fixed bodies) */
    int self_cols;   /**< 1: the self pair of least distance after them: self_d, self_arm, self_link,
                          self_other (a cell with self pairs) */
} mca_tick_csv_layout_t;

/** One tick's data. Fields a layout does not select are not read (NULL allowed). */
typedef struct mca_tick_csv_row {
    double t;                              /**< task time [s] */
    const double (*q)[MCA_MAX_DOF];        /**< measured positions [arm][joint] */
    const mca_tick_info_t *info;           /**< the tick's figures */
    int state;                             /**< daemon_cols: mca_daemon_state_t */
    const double (*qdot_cmd)[MCA_MAX_DOF]; /**< daemon_cols: commanded velocities [arm][joint] */
    int64_t cmd_gap_ns;                    /**< daemon_cols: this tick's commands after the last's */
    int64_t wake_ns;                       /**< daemon_cols: the tick's wake-up, CLOCK_MONOTONIC ns */
    const mca_arm_distances_t (*dist)[MCA_MAX_ARMS]; /**< pair_cols: the controller's dist[a][b], a < b */
} mca_tick_csv_row_t;

/** The header line. */
void mca_tick_csv_header(FILE *f, const mca_tick_csv_layout_t *l);

/** One row, its columns in the header's order. */
void mca_tick_csv_row(FILE *f, const mca_tick_csv_layout_t *l, const mca_tick_csv_row_t *r);

#ifdef __cplusplus
}
#endif
#endif
