/* SPDX-License-Identifier: MIT */
/* The canopen backend's settings in a cell arm (mca_cell_arm_t.backend_own), as its read leaves them
 * (docs/canopen.md): joint j = CiA 402 drive first_node + j on the arm's interface. Private to the backend
 * and the tests that check what a cell file gives it. Start-up only. */
#ifndef MCA_CANOPEN_CELL_H
#define MCA_CANOPEN_CELL_H

#include <stdint.h>

#include "mca/cell.h"

typedef struct mca_canopen_cell {
    int first_node;    /* 1..127 (default 1) */
    uint32_t sync_us;  /* SYNC period, a multiple of the loop period (default 4000) */
    int mode;          /* 9 CSV (default), 8 CSP */
    double pos_scale;  /* counts per rad (default 1e6) */
    double vel_scale;  /* counts per rad/s (default 1e6) */
    int hb_timeout_ms; /* heartbeat consumer time (default 350) */
    int pdo_timeout;   /* SYNCs without a fresh TPDO before PDO_TIMEOUT (default 5) */
} mca_canopen_cell_t;
MCA_CELL_BACKEND_OWN(mca_canopen_cell_t, mca_canopen_cell)

#endif
