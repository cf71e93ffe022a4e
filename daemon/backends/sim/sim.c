/* SPDX-License-Identifier: MIT */
/* The sim backend: an in-process simulated arm (mca/sim_backend.h) with an optional model of the real one's
 * imperfections, a cell arm's
 *
 *     backend: sim
 *     sim: {lag_tau: 0.0, latency_cycles: 0, noise_pos: 0.0}   # optional, each key too
 *
 * It opens no bus: an interface or id_base given is only kept. Calling context: read and open at start-up
 * (daemon__backends.h); the arm's read and write on the RT thread (mca/sim_backend.h). */
#include <math.h>

#include "mca/err.h"
#include "mca/sim_backend.h"
#include "mca/yaml_load.h" /* MCA_YAML_OPT */

#include "daemon__backends.h"

/* The sim: section of a cell arm (NULL: key not in the file). */
typedef struct sim_keys {
    double *lag_tau;
    int *latency_cycles;
    double *noise_pos;
} sim_keys_t;

static const cyaml_schema_field_t sim_fields[] = {
    CYAML_FIELD_FLOAT_PTR("lag_tau", MCA_YAML_OPT, sim_keys_t, lag_tau),
    CYAML_FIELD_INT_PTR("latency_cycles", MCA_YAML_OPT, sim_keys_t, latency_cycles),
    CYAML_FIELD_FLOAT_PTR("noise_pos", MCA_YAML_OPT, sim_keys_t, noise_pos),
    CYAML_FIELD_END,
};

/* Its settings in the cell arm (all 0 when the cell gives none: a perfect arm, mca_cell_from_scenario's). */
typedef struct sim_own {
    double lag_tau;     /* first-order velocity lag [s] */
    int latency_cycles; /* command transport delay [cycles] */
    double noise_pos;   /* measurement noise sigma [rad] */
} sim_own_t;
MCA_CELL_BACKEND_OWN(sim_own_t, sim_own)

/* Ranges of the sim model's keys (docs/daemon.md) */
static const mca_range_t r_lag_tau = {"lag_tau", 0.0, 1.0, 0, 0, "s"};
static const mca_range_t r_latency_cycles = {"latency_cycles", 0, 64, 0, 1, "cycles"};
static const mca_range_t r_noise_pos = {"noise_pos", 0.0, 0.1, 0, 0, "rad"};

static int sim_read(const mca_check_ctx_t *c, mca_cell_t *cell, int a, const mca_backend_keys_t *k) {
    sim_own_t *own = sim_own(&cell->arm[a]);
    int rc = mca_backend_bus_keys(c, cell, a, k);
    const sim_keys_t *sk = k->section;
    if (rc != MCA_OK || !sk) {
        return rc;
    }
    if (sk->lag_tau) {
        MCA_BE_CHECK(&r_lag_tau, *sk->lag_tau, "arms[%d].sim.lag_tau", a);
        own->lag_tau = *sk->lag_tau;
    }
    if (sk->latency_cycles) {
        MCA_BE_CHECK(&r_latency_cycles, *sk->latency_cycles, "arms[%d].sim.latency_cycles", a);
        own->latency_cycles = *sk->latency_cycles;
    }
    if (sk->noise_pos) {
        MCA_BE_CHECK(&r_noise_pos, *sk->noise_pos, "arms[%d].sim.noise_pos", a);
        own->noise_pos = *sk->noise_pos;
    }
    return MCA_OK;
}

static int sim_open(mca_arm_t **arm, const mca_backend_open_args_t *o, char *err, size_t errlen) {
    const mca_cell_arm_t *ca = &o->cell->arm[o->arm];
    const sim_own_t *own = sim_own_c(ca);
    const mca_scenario_arm_t *sa = &o->cell->scn.arm[o->arm];
    mca_sim_arm_config_t sc;
    int rc = mca_sim_arm_config_from_chain(&sc, o->chain);
    if (rc != MCA_OK) {
        return rc;
    }
    for (int j = 0; j < sc.n; j++) {
        sc.q0[j] = sa->q0[j];
        sc.dec_limit[j] = ca->dec_limit[j];
        if (sc.acc_limit[j] < ca->dec_limit[j]) {
            sc.acc_limit[j] = ca->dec_limit[j];
        }
    }
    sc.dt = (double)o->cell->rt.period_ns * 1e-9;
    sc.lag_tau = own->lag_tau;
    sc.latency_cycles = own->latency_cycles;
    sc.noise_pos = own->noise_pos;
    sc.seed = 1 + (uint64_t)o->arm;
    sc.stamp_monotonic = !o->virtual_time;
    if (o->ideal) {
        /* mca-sim --euler: q += v dt with v the command, nothing limited */
        sc.ideal = 1;
        for (int j = 0; j < sc.n; j++) {
            sc.lower[j] = -INFINITY;
            sc.upper[j] = INFINITY;
            sc.vel_limit[j] = 1e300;
        }
    }
#ifdef MCA_TEST_HOOKS
    if (o->cell->debug_start_in_fault) {
        /* test hook: the firmware latches a fault in its first cycle (INIT -> FAULT), as a fault left from an
         * earlier run would be */
        sc.init_cycles = sc.init_cycles > 0 ? sc.init_cycles : 1;
        sc.n_inject = 1;
        sc.inject[0].kind = MCA_SIM_INJ_ACTUATOR;
        sc.inject[0].at_cycle = 0;
        sc.inject[0].joint = 0;
    }
#endif
    return mca_sim_backend_open(arm, &sc, err, errlen);
}

/* 6 sigma of the simulated measurement noise: a noisy sample is not a lie */
static double sim_feedback_margin(const mca_cell_arm_t *ca) {
    return 6.0 * sim_own_c(ca)->noise_pos;
}

const mca_backend_def_t mca_backend_sim = {
    .name = "sim",
    .section = "sim",
    .section_fields = sim_fields,
    .section_size = sizeof(sim_keys_t),
    .read = sim_read,
    .open = sim_open,
    .feedback_margin = sim_feedback_margin,
};
