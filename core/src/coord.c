/* SPDX-License-Identifier: MIT */
/* Coordination of fixed paths: a start-up plan on each pair's coordination diagram, gates on the tick
 * (mca/coord.h says what and why). */
#include "mca/coord.h"

#include <math.h>
#include <string.h>

#include "mca/apf.h" /* mca_apf_pinv_apply */
#include "mca/err.h"
#include "mca/armdist.h"
#include "mca/segdist.h"
#include "mca/vec3.h"

/* The prediction's Euler step [s] and its damping (a singular pose must not throw the prediction). */
#define PREDICT_DT 0.005
#define PREDICT_DAMPING 1e-2

enum { CELL_BLOCKED = 1, CELL_LEFT = 2, CELL_BELOW = 4, CELL_DIAG = 6, CELL_FROM = 6, CELL_SEEN = 8 };

static int coordinated(const mca_coord_arm_t *arm) {
    const mca_path_t *p = arm->path;
    return p->path_first && (p->kind == MCA_PATH_CIRCLE || p->kind == MCA_PATH_WAYPOINTS) &&
           isfinite(mca_path_end_time(p));
}

/* One damped resolved-rate step toward the path (the arm alone: no rows, joint limits by clamping). */
static void predict_step(const mca_coord_arm_t *arm, mca_kin_t *kin, double q[], double t) {
    const mca_chain_t *c = arm->chain;
    const int dof = c->dof;
    double J[3][MCA_MAX_DOF], r[3], rdot[3], v[3];
    mca_jacobian_ee(kin, J);
    mca_path_eval(arm->path, t, r, rdot);
    for (int i = 0; i < 3; i++) {
        v[i] = rdot[i] + arm->K * (r[i] - kin->ee[i]);
    }
    double qd[MCA_MAX_DOF], scale = 1.0;
    mca_apf_pinv_apply(J, dof, PREDICT_DAMPING * PREDICT_DAMPING, v, qd); /* J^T (J J^T + lambda^2 I)^-1 v */
    for (int j = 0; j < dof; j++) {
        if (fabs(qd[j]) > c->joint[j].vel_limit) {
            scale = fmin(scale, c->joint[j].vel_limit / fabs(qd[j]));
        }
    }
    for (int j = 0; j < dof; j++) {
        q[j] += scale * qd[j] * PREDICT_DT;
    }
    mca_chain_clamp_q(c, q);
}

int mca_coord_predict(const mca_coord_arm_t *arm, double h, int n, double q_out[][MCA_MAX_DOF]) {
    if (!arm || !arm->chain || !arm->path || !arm->q0 || !q_out || !(h > 0.0) || n < 1 ||
        n > MCA_COORD_MAX_CELLS) {
        return MCA_EINVAL;
    }
    double q[MCA_MAX_DOF];
    memcpy(q, arm->q0, sizeof(double) * (size_t)arm->chain->dof);
    mca_kin_t kin;
    double t = 0.0;
    for (int k = 0; k < n; k++) {
        for (;;) {
            if (mca_fk(arm->chain, q, &kin) != MCA_OK) {
                return MCA_EINVAL;
            }
            if (t >= k * h - 1e-9) {
                break;
            }
            predict_step(arm, &kin, q, t);
            t += PREDICT_DT;
        }
        memcpy(q_out[k], q, sizeof q_out[k]);
    }
    return MCA_OK;
}

/* The arm's link points at the start of each cell of path time, predicted alone. */
static int predict(const mca_coord_arm_t *arm, double h, int n, double q[][MCA_MAX_DOF],
                   double pts[][MCA_MAX_POINTS][3]) {
    if (mca_coord_predict(arm, h, n, q) != MCA_OK) {
        return MCA_EINVAL;
    }
    for (int k = 0; k < n; k++) {
        mca_kin_t kin;
        if (mca_fk(arm->chain, q[k], &kin) != MCA_OK) {
            return MCA_EINVAL;
        }
        memcpy(pts[k], kin.point, sizeof pts[k]);
    }
    return MCA_OK;
}

/* The quickest monotone schedule from (0, 0) to (n_a - 1, n_b - 1) through free cells: each step advances
 * one arm by a cell or both (a diagonal step only where both cells beside it are free, so the gates derived
 * from it can never hold both arms at once). Predecessors are written into the cells. 1: found. */
static int schedule(unsigned char cell[][MCA_COORD_MAX_CELLS], int n_a, int n_b) {
    static const int none = 0x7fff;
    unsigned short prev[MCA_COORD_MAX_CELLS], cur[MCA_COORD_MAX_CELLS];
    for (int y = 0; y < n_b; y++) {
        for (int x = 0; x < n_a; x++) {
            unsigned char *c = &cell[x][y];
            *c &= CELL_BLOCKED;
            int best = none, from = 0;
            if (*c & CELL_BLOCKED) {
                cur[x] = none;
                continue;
            }
            if (x == 0 && y == 0) {
                best = 0;
            }
            if (x > 0 && y > 0 && prev[x - 1] < best && !(cell[x - 1][y] & CELL_BLOCKED) &&
                !(cell[x][y - 1] & CELL_BLOCKED)) {
                best = prev[x - 1] + 1;
                from = CELL_DIAG;
            }
            if (x > 0 && cur[x - 1] + 1 < best) {
                best = cur[x - 1] + 1;
                from = CELL_LEFT;
            }
            if (y > 0 && prev[x] + 1 < best) {
                best = prev[x] + 1;
                from = CELL_BELOW;
            }
            cur[x] = (unsigned short)best;
            *c |= (unsigned char)from;
        }
        memcpy(prev, cur, sizeof(prev[0]) * (size_t)n_a);
    }
    return prev[n_a - 1] < none;
}

/* Gates from the schedule: mark its cells, then per column the blocked cells it passes above (b first) and
 * per row the blocked cells it passes to the right of (a first). */
static void gates(unsigned char cell[][MCA_COORD_MAX_CELLS], mca_coord_pair_t *p) {
    short low_col[MCA_COORD_MAX_CELLS], low_row[MCA_COORD_MAX_CELLS];
    for (int i = 0; i < MCA_COORD_MAX_CELLS; i++) {
        low_col[i] = low_row[i] = MCA_COORD_MAX_CELLS;
    }
    int x = p->n_a - 1, y = p->n_b - 1;
    for (;;) {
        low_col[x] = (short)(y < low_col[x] ? y : low_col[x]);
        low_row[y] = (short)(x < low_row[y] ? x : low_row[y]);
        const int from = cell[x][y] & CELL_FROM;
        if (from == 0) {
            break;
        }
        x -= from != CELL_BELOW;
        y -= from != CELL_LEFT;
    }
    p->gates_a = p->gates_b = 0;
    for (int i = 0; i < MCA_COORD_MAX_CELLS; i++) {
        p->need_b[i] = p->need_a[i] = 0;
    }
    for (x = 0; x < p->n_a; x++) {
        for (y = 0; y < p->n_b; y++) {
            if (!(cell[x][y] & CELL_BLOCKED)) {
                continue;
            }
            if (y < low_col[x]) {
                p->need_b[x] = (short)(y + 1 > p->need_b[x] ? y + 1 : p->need_b[x]);
            } else if (x < low_row[y]) {
                p->need_a[y] = (short)(x + 1 > p->need_a[y] ? x + 1 : p->need_a[y]);
            }
        }
    }
    for (x = 0; x < p->n_a; x++) {
        p->gates_a += p->need_b[x] > 0;
    }
    for (y = 0; y < p->n_b; y++) {
        p->gates_b += p->need_a[y] > 0;
    }
}

/* The part of the arm's path tube per cell the plan may count on to separate the arms (the rows push the tips
 * apart inside it); its largest value. */
static double tube_share(const mca_coord_arm_t *arm, double h, int n, double tube[]) {
    double m = 0.0;
    for (int x = 0; x < n; x++) {
        tube[x] = MCA_COORD_TUBE_SHARE * mca_path_tolerance(arm->path, x * h);
        m = fmax(m, tube[x]);
    }
    return m;
}

/* Block the cells closer than d less the tubes' share there (tube_a, tube_b; NULL: none) and their
 * neighbours: the arms move between the samples. */
static int block(unsigned char cell[][MCA_COORD_MAX_CELLS], const float dist[][MCA_COORD_MAX_CELLS], int n_a,
                 int n_b, double d, const double *tube_a, const double *tube_b) {
    int n = 0;
    for (int x = 0; x < n_a; x++) {
        for (int y = 0; y < n_b; y++) {
            const double t = tube_a ? tube_a[x] + tube_b[y] : 0.0;
            cell[x][y] = dist[x][y] < d - t ? CELL_SEEN : 0;
        }
    }
    for (int x = 0; x < n_a; x++) {
        for (int y = 0; y < n_b; y++) {
            int near = 0;
            for (int i = x > 0 ? x - 1 : 0; i <= x + 1 && i < n_a && !near; i++) {
                for (int j = y > 0 ? y - 1 : 0; j <= y + 1 && j < n_b && !near; j++) {
                    near = cell[i][j] & CELL_SEEN;
                }
            }
            if (near) {
                cell[x][y] |= CELL_BLOCKED;
                n++;
            }
        }
    }
    for (int x = 0; x < n_a; x++) {
        for (int y = 0; y < n_b; y++) {
            cell[x][y] &= CELL_BLOCKED;
        }
    }
    return n;
}

int mca_coord_plan(const mca_coord_arm_t *arms, int n_arms, double d_block, double d_floor,
                   mca_coord_work_t *work, mca_coord_t *out) {
    if (!arms || !work || !out || n_arms < 1 || n_arms > MCA_MAX_ARMS || !(d_floor <= d_block)) {
        return MCA_EINVAL;
    }
    memset(out, 0, sizeof *out);
    int n[MCA_MAX_ARMS];
    double h[MCA_MAX_ARMS];
    for (int a = 0; a < n_arms; a++) {
        n[a] = 0;
        if (!coordinated(&arms[a])) {
            continue;
        }
        const double T = mca_path_end_time(arms[a].path);
        h[a] = fmax(MCA_COORD_CELL_S, T / (MCA_COORD_MAX_CELLS - 2));
        n[a] = (int)ceil(T / h[a]) + 1;
        if (predict(&arms[a], h[a], n[a], work->q, work->pts[a]) != MCA_OK) {
            return MCA_EINVAL;
        }
    }
    for (int a = 0; a < n_arms; a++) {
        for (int b = a + 1; b < n_arms; b++) {
            if (n[a] == 0 || n[b] == 0) {
                continue;
            }
            mca_coord_pair_t *p = &out->pair[out->n_pairs];
            p->a = a;
            p->b = b;
            p->n_a = n[a];
            p->n_b = n[b];
            p->h_a = h[a];
            p->h_b = h[b];
            for (int x = 0; x < n[a]; x++) {
                for (int y = 0; y < n[b]; y++) {
                    work->dist[x][y] = (float)mca_arm_least_distance(
                        arms[a].chain, (const double(*)[3])work->pts[a][x], arms[b].chain,
                        (const double(*)[3])work->pts[b][y], d_block);
                }
            }
            const double tries[3] = {d_block, 0.5 * (d_block + d_floor), d_floor};
            int found = 0;
            for (int k = 0; k < 3 && !found; k++) {
                p->blocked = block(work->cell, (const float(*)[MCA_COORD_MAX_CELLS])work->dist, n[a], n[b],
                                   tries[k], NULL, NULL);
                p->d_block = tries[k];
                found = schedule(work->cell, n[a], n[b]);
            }
            if (!found && tube_share(&arms[a], h[a], n[a], work->tube[0]) +
                                  tube_share(&arms[b], h[b], n[b], work->tube[1]) >
                              0.0) {
                /* paths with a tube: the rows may push the tips apart inside it where the predicted arms meet
                 */
                p->blocked = block(work->cell, (const float(*)[MCA_COORD_MAX_CELLS])work->dist, n[a], n[b],
                                   d_floor, work->tube[0], work->tube[1]);
                p->d_block = d_floor;
                p->in_tubes = 1;
                found = schedule(work->cell, n[a], n[b]);
            }
            if (!found) {
                out->unplanned++;
                continue;
            }
            gates(work->cell, p);
            out->n_pairs++;
        }
    }
    return MCA_OK;
}

double mca_coord_gate(const mca_coord_t *c, int arm, const double tau[MCA_MAX_ARMS], double ahead) {
    double gate = INFINITY;
    for (int k = 0; k < c->n_pairs; k++) {
        const mca_coord_pair_t *p = &c->pair[k];
        if (p->a != arm && p->b != arm) {
            continue;
        }
        const int mine_a = p->a == arm;
        const double h = mine_a ? p->h_a : p->h_b, h_other = mine_a ? p->h_b : p->h_a;
        const int n = mine_a ? p->n_a : p->n_b;
        const short *need = mine_a ? p->need_b : p->need_a;
        const double other = tau[mine_a ? p->b : p->a];
        const int x0 = (int)floor(tau[arm] / h);
        const int x1 = x0 + (int)ceil(ahead / h) + 1;
        for (int x = x0 + 1; x <= x1 && x < n; x++) {
            if (need[x] > 0 && other < need[x] * h_other) {
                gate = fmin(gate, x * h);
                break;
            }
        }
    }
    return gate;
}
