/* SPDX-License-Identifier: MIT */
/* Cost per 1 ms cycle of the simulated arm (sim_backend/): one mca_sim_arm_cycle() of an 8-joint arm
 * with lag, latency and noise on, and one mca_arm_write() + mca_arm_read() through the in-process
 * backend. Usage: bench_simarm   Prints the median over repeated batches and its ratio to 1 ms. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mca/err.h"
#include "mca/sim_backend.h"

#define BATCH 5000
#define N_BATCH 41
#define ON (MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE)

static double now_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static volatile double sink;
static mca_sim_arm_t fw;

static void config(mca_sim_arm_config_t *cfg) {
    mca_sim_arm_config_default(cfg, MCA_MAX_DOF);
    for (int j = 0; j < MCA_MAX_DOF; j++) {
        cfg->lower[j] = -3.0;
        cfg->upper[j] = 3.0;
    }
    cfg->lag_tau = 0.01;
    cfg->latency_cycles = 4;
    cfg->noise_pos = 1e-4;
    cfg->noise_vel = 1e-3;
    cfg->seed = 3;
}

/* A slow sine so the arm keeps moving within its limits for the whole run. */
static void fill(mca_arm_command_t *c, uint32_t id) {
    c->frame_id = id;
    c->n = MCA_MAX_DOF;
    for (int j = 0; j < MCA_MAX_DOF; j++) {
        c->flags[j] = ON;
        c->velocity[j] = 0.5 * sin(1e-3 * id + j);
    }
}

int main(void) {
    mca_sim_arm_config_t cfg;
    config(&cfg);
    char err[256];
    if (mca_sim_arm_init(&fw, &cfg, err, sizeof(err)) != MCA_OK) {
        fprintf(stderr, "bench_simarm: %s\n", err);
        return 1;
    }
    mca_arm_t *arm = NULL;
    if (mca_sim_backend_open(&arm, &cfg, err, sizeof(err)) != MCA_OK) {
        fprintf(stderr, "bench_simarm: %s\n", err);
        return 1;
    }
    double t_fw[N_BATCH], t_api[N_BATCH];
    mca_arm_command_t c;
    memset(&c, 0, sizeof(c));
    mca_arm_feedback_t fb;
    uint32_t id = 0, id2 = 0;
    for (int b = 0; b < N_BATCH; b++) {
        double acc = 0;
        const double t0 = now_ns();
        for (int i = 0; i < BATCH; i++) {
            fill(&c, ++id);
            mca_sim_arm_cycle(&fw, &c, cfg.dt, &fb);
            acc += fb.position[0];
        }
        const double t1 = now_ns();
        for (int i = 0; i < BATCH; i++) {
            fill(&c, ++id2);
            mca_arm_write(arm, &c);
            mca_arm_read(arm, &fb);
            acc += fb.position[0];
        }
        const double t2 = now_ns();
        sink = acc;
        t_fw[b] = (t1 - t0) / BATCH;
        t_api[b] = (t2 - t1) / BATCH;
    }
    if (fw.state != MCA_ARM_SERVOING || fw.cnt.cmd_accepted + cfg.latency_cycles != fw.cnt.cycles) {
        fprintf(stderr, "bench_simarm: arm left SERVOING (%s, fault %s)\n", mca_arm_state_name(fw.state),
                mca_arm_fault_name(fw.fault_code));
        return 1;
    }
    qsort(t_fw, N_BATCH, sizeof(double), cmp_double);
    qsort(t_api, N_BATCH, sizeof(double), cmp_double);
    const double f = t_fw[N_BATCH / 2], a = t_api[N_BATCH / 2];
    printf("sim arm, %d joints, lag+latency+noise: firmware cycle %7.1f ns = %.5f of a 1 ms cycle\n",
           MCA_MAX_DOF, f, f / 1e6);
    printf("sim backend mca_arm_write + mca_arm_read    %7.1f ns = %.5f of a 1 ms cycle\n", a, a / 1e6);
    mca_arm_close(arm);
    return 0;
}
