/* SPDX-License-Identifier: MIT */
/* mca-co-arm: the `canopen` backend through the arm interface (mca/arm.h), as the daemon uses it: a 1 kHz
 * clock_nanosleep loop of mca_arm_read + mca_arm_write over --nodes CiA 402 drives, SYNC every
 * --sync-us / 1000 writes. Servo enable until SERVOING, one period of sinusoidal velocities (--cycles,
 * velocity 0 at both ends), then a brake request (flags 0) for --stop-cycles. Checks and prints
 * (key=value): SERVOING reached; the travel of each joint = the integral of the commanded velocity
 * (within --tol, default 1e-4 rad; CSV: the drives hold each SYNC's velocity); READY at
 * standstill after the brake. --expect-fault NAME: the run must end in fb.state FAULT with
 * mca_arm_fault_name(fb.fault_code) = NAME and every joint at rest; the backend's fault text is printed.
 * Exit 0 pass, 2 bad arguments, 3 open failed, 4 a check failed. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mca/arm.h"
#include "mca/canopen.h"
#include "mca/err.h"

static void add_ns(struct timespec *t, long ns) {
    t->tv_nsec += ns;
    while (t->tv_nsec >= 1000000000) {
        t->tv_nsec -= 1000000000;
        t->tv_sec++;
    }
}

int main(int argc, char **argv) {
    const char *iface = NULL, *mode = "csv", *expect = NULL;
    long nodes = 6, sync_us = 4000, cycles = 2000, stop_cycles = 600, enable_cycles = 3000;
    double amp = 0.3, tol = 0;
    static const struct option opts[] = {
        {"iface", required_argument, 0, 'i'},        {"nodes", required_argument, 0, 'n'},
        {"mode", required_argument, 0, 'm'},         {"sync-us", required_argument, 0, 's'},
        {"cycles", required_argument, 0, 'c'},       {"stop-cycles", required_argument, 0, 'S'},
        {"amp", required_argument, 0, 'a'},          {"tol", required_argument, 0, 't'},
        {"expect-fault", required_argument, 0, 'x'}, {0, 0, 0, 0},
    };
    int o;
    while ((o = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (o) {
        case 'i':
            iface = optarg;
            break;
        case 'n':
            nodes = atol(optarg);
            break;
        case 'm':
            mode = optarg;
            break;
        case 's':
            sync_us = atol(optarg);
            break;
        case 'c':
            cycles = atol(optarg);
            break;
        case 'S':
            stop_cycles = atol(optarg);
            break;
        case 'a':
            amp = atof(optarg);
            break;
        case 't':
            tol = atof(optarg);
            break;
        case 'x':
            expect = optarg;
            break;
        default:
            return 2;
        }
    }
    const int csp = strcmp(mode, "csp") == 0;
    if (!iface || nodes < 1 || nodes > MCA_CO_MAX_NODES || sync_us < 1000 || cycles < 1) {
        fprintf(stderr,
                "usage: mca-co-arm --iface IF [--nodes 6] [--mode csv|csp] [--sync-us 4000] [--cycles 2000]\n"
                "                  [--stop-cycles 600] [--amp 0.3] [--tol T] [--expect-fault NAME]\n");
        return 2;
    }
    if (tol <= 0) {
        tol = 1e-4; /* CSV too: the drives integrate every --sync-us / 1000-th velocity, a sine period of them
                     */
    }
    mca_co_master_config_t cfg;
    mca_co_master_config_default(&cfg, (int)nodes, 1);
    snprintf(cfg.iface, sizeof(cfg.iface), "%s", iface);
    cfg.mode = csp ? MCA_CO402_MODE_CSP : MCA_CO402_MODE_CSV;
    cfg.sync_period_us = (uint32_t)sync_us;
    cfg.hb_timeout_ms = 1000;
    cfg.pdo_timeout_cycles = 25;
    cfg.sdo_timeout_ms = 1000;
    mca_arm_t *arm = NULL;
    char err[320] = "";
    int rc = mca_canopen_backend_open(&arm, &cfg, 1000, err, sizeof(err));
    if (rc != MCA_OK) {
        printf("open=%s err=%s\n", mca_strerror(rc), err);
        return 3;
    }
    printf("backend=%s\n", mca_arm_backend_name(arm));
    mca_arm_command_t cmd;
    memset(&cmd, 0, sizeof(cmd));
    cmd.n = (int)nodes;
    mca_arm_feedback_t fb;
    memset(&fb, 0, sizeof(fb));
    int have_fb = 0, fails = 0;
    long k = 0, servo_at = -1, stop_at = -1, n_ok = 0, n_again = 0, n_fault = 0, n_eio = 0;
    double q0[MCA_MAX_DOF] = {0}, integ[MCA_MAX_DOF] = {0}, travel_err = 0;
    const double w = 2 * M_PI / (cycles * 1e-3);
    struct timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    for (;; k++) {
        add_ns(&next, 1000000);
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        if ((now.tv_sec - next.tv_sec) * 1000000000L + (now.tv_nsec - next.tv_nsec) > 1000000) {
            next = now; /* late: re-anchor, no burst */
        }
        rc = mca_arm_read(arm, &fb);
        if (rc == MCA_OK || rc == MCA_EFAULT) {
            have_fb = 1;
            n_ok += rc == MCA_OK;
            n_fault += rc == MCA_EFAULT;
        } else if (rc == MCA_EAGAIN) {
            n_again++;
        } else {
            n_eio++;
        }
        if (servo_at < 0 && have_fb && fb.state == MCA_ARM_SERVOING) {
            servo_at = k;
            memcpy(q0, fb.position, sizeof(q0));
            printf("servoing_after_cycles=%ld\n", k);
        }
        if (servo_at < 0 && k > enable_cycles) {
            printf("servoing=0 state=%s\n", mca_arm_state_name(fb.state));
            fails++;
            break;
        }
        const long t = servo_at >= 0 ? k - servo_at : -1;
        if (stop_at < 0 &&
            (t >= cycles || (have_fb && (fb.state == MCA_ARM_FAULT || fb.state == MCA_ARM_BRAKING)))) {
            stop_at = k;
        }
        const int servo = stop_at < 0;
        for (int j = 0; j < cmd.n; j++) {
            const double ph = 0.9 * j;
            cmd.flags[j] = servo ? (MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE) : 0;
            cmd.velocity[j] = (servo && t >= 0) ? amp * (sin(w * t * 1e-3 + ph) - sin(ph)) : 0.0;
            integ[j] += cmd.velocity[j] * 1e-3;
        }
        cmd.frame_id = (uint32_t)(k + 1);
        rc = mca_arm_write(arm, &cmd);
        if (rc != MCA_OK && rc != MCA_EAGAIN) {
            printf("write=%s at cycle %ld\n", mca_strerror(rc), k);
        }
        if (stop_at >= 0 && k - stop_at >= stop_cycles) {
            break;
        }
    }
    printf("reads_ok=%ld reads_again=%ld reads_fault=%ld reads_eio=%ld cycles=%ld\n", n_ok, n_again, n_fault,
           n_eio, k);
    int at_rest = 1;
    for (int j = 0; j < cmd.n; j++) {
        at_rest &= fabs(fb.velocity[j]) < 1e-6;
        const double e = fabs((fb.position[j] - q0[j]) - integ[j]);
        travel_err = e > travel_err ? e : travel_err;
    }
    char why[192] = "";
    mca_canopen_backend_fault(arm, why, sizeof(why));
    printf("state=%s fault=%s why=%s at_rest=%d travel_err=%.3g tol=%.3g\n", mca_arm_state_name(fb.state),
           mca_arm_fault_name(fb.fault_code), why, at_rest, travel_err, tol);
    if (expect) {
        const int ok =
            fb.state == MCA_ARM_FAULT && strcmp(mca_arm_fault_name(fb.fault_code), expect) == 0 && at_rest;
        printf("expected_fault=%s %s\n", expect, ok ? "seen" : "NOT seen");
        fails += !ok;
    } else {
        if (fb.state != MCA_ARM_READY || !at_rest) {
            printf("check: not READY at rest after the brake request\n");
            fails++;
        }
        if (travel_err > tol) {
            printf("check: travel differs from the commanded integral by %.3g > %.3g rad\n", travel_err, tol);
            fails++;
        }
    }
    mca_arm_close(arm);
    return fails ? 4 : 0;
}
