/* SPDX-License-Identifier: MIT */
/* mca-simarm-trace: drive the simulated arm firmware (mca/sim_arm.h) with a command profile and print
 * one CSV row per cycle: the command handed in and the feedback out. The header lines ("# ...") carry
 * the full configuration so a second implementation can replay the run (tests/arm/simarm_model.py).
 *
 * Usage: mca-simarm-trace [--profile step|watchdog|random] [--cycles N] [--joints N] [--lag S]
 *        [--latency K] [--noise-pos S] [--noise-vel S] [--seed N] [--watchdog W] [--vel V] [--acc A]
 *        [--dec D] [--range R] [--inject KIND@CYCLE[+CYCLES][:JOINT]]... [-o FILE]
 *   KIND: actuator | freeze | silent | drop-rx (mca-armsim's syntax: mca_sim_inject_parse()).
 *   Joint j gets vel V(1+j/4), acc A(1+j/8), dec D(1-j/16),
 *   limits +-R(1+j/10) (R = 0: none). */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/err.h"
#include "mca/sim_arm.h"

#define ON (MCA_ACT_SERVO_ENABLE | MCA_ACT_BRAKE_RELEASE)

static mca_sim_arm_t g_arm;

static int parse_double(const char *opt, const char *s, double *out) {
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || end == s || *end || !isfinite(v)) {
        fprintf(stderr, "mca-simarm-trace: --%s %s: not a number\n", opt, s);
        return -1;
    }
    *out = v;
    return 0;
}

static int parse_long(const char *opt, const char *s, long lo, long hi, long *out) {
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi) {
        fprintf(stderr, "mca-simarm-trace: --%s %s: expected an integer in %ld..%ld\n", opt, s, lo, hi);
        return -1;
    }
    *out = v;
    return 0;
}

/* the joint range is checked again once --joints is known (mca_sim_arm_init) */
static int parse_inject(const char *s, mca_sim_inject_t *in) {
    if (mca_sim_inject_parse(s, MCA_MAX_DOF, in) != MCA_OK) {
        fprintf(stderr,
                "mca-simarm-trace: --inject %s: expected " MCA_SIM_INJECT_SYNTAX
                " with KIND actuator (needs :JOINT), freeze, silent or drop-rx\n",
                s);
        return -1;
    }
    return 0;
}

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static uint64_t xorshift(void) {
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

/* The command of cycle k; returns 0 when no command is sent this cycle. */
static int make_cmd(const char *profile, int k, int n, uint32_t *id, mca_arm_command_t *c) {
    memset(c, 0, sizeof(*c));
    c->n = n;
    c->frame_id = ++*id;
    for (int j = 0; j < n; j++) {
        c->flags[j] = ON;
    }
    if (strcmp(profile, "step") == 0) {
        for (int j = 0; j < n; j++) {
            c->velocity[j] = k < 10 ? 0.0 : (k < 600 ? 0.5 : -0.3);
        }
        return 1;
    }
    if (strcmp(profile, "watchdog") == 0) {
        for (int j = 0; j < n; j++) {
            c->velocity[j] = 0.5;
        }
        if (k >= 400 && k < 900) {
            return 0; /* the controller goes silent: watchdog, braking, FAULT */
        }
        if (k == 900) {
            c->flags[0] |= MCA_ACT_CLEAR_FAULT;
        }
        return 1;
    }
    /* random: every feature of the command path */
    uint64_t r = xorshift();
    for (int j = 0; j < n; j++) {
        double u = (double)(xorshift() >> 11) / 9007199254740992.0;
        c->velocity[j] = 0.8 * sin(1e-3 * k + j) + 0.7 * (2 * u - 1);
    }
    if (r % 97 == 0) {
        c->flags[r % (uint64_t)n] = 0;
    }
    if (r % 89 == 0 || r % 7 == 0) {
        c->flags[0] |= MCA_ACT_CLEAR_FAULT;
    }
    if (r % 83 == 0) {
        c->frame_id = *id - 3;
    }
    if (r % 79 == 0) {
        c->n = n + 1;
    }
    if (r % 73 == 0) {
        c->velocity[n - 1] = NAN;
    }
    return (k % 3000) < 2990;
}

int main(int argc, char **argv) {
    const char *profile = "step", *out_path = NULL;
    long cycles = 2000, joints = 3, latency = 0, watchdog = 3;
    unsigned long long seed = 1;
    double lag = 0, noise_pos = 0, noise_vel = 0, vel = 1.0, acc = 10.0, dec = 20.0, range = 0;
    mca_sim_inject_t inject[MCA_SIM_MAX_INJECT];
    int n_inject = 0;
    static const struct option opts[] = {{"profile", required_argument, 0, 'p'},
                                         {"cycles", required_argument, 0, 'c'},
                                         {"joints", required_argument, 0, 'j'},
                                         {"lag", required_argument, 0, 'l'},
                                         {"latency", required_argument, 0, 'L'},
                                         {"noise-pos", required_argument, 0, 'n'},
                                         {"noise-vel", required_argument, 0, 'N'},
                                         {"seed", required_argument, 0, 's'},
                                         {"watchdog", required_argument, 0, 'w'},
                                         {"vel", required_argument, 0, 'v'},
                                         {"acc", required_argument, 0, 'a'},
                                         {"dec", required_argument, 0, 'd'},
                                         {"range", required_argument, 0, 'r'},
                                         {"inject", required_argument, 0, 'i'},
                                         {"help", no_argument, 0, 'h'},
                                         {0, 0, 0, 0}};
    int o;
    while ((o = getopt_long(argc, argv, "o:h", opts, NULL)) != -1) {
        long lv;
        int bad = 0;
        switch (o) {
        case 'p':
            profile = optarg;
            bad = strcmp(profile, "step") && strcmp(profile, "watchdog") && strcmp(profile, "random");
            if (bad) {
                fprintf(stderr, "mca-simarm-trace: --profile %s: expected step, watchdog or random\n",
                        optarg);
            }
            break;
        case 'c':
            bad = parse_long("cycles", optarg, 1, 100000000, &cycles);
            break;
        case 'j':
            bad = parse_long("joints", optarg, 1, MCA_MAX_DOF - 1, &joints);
            break;
        case 'L':
            bad = parse_long("latency", optarg, 0, MCA_SIM_MAX_LATENCY, &latency);
            break;
        case 'w':
            bad = parse_long("watchdog", optarg, 1, 1000000, &watchdog);
            break;
        case 's':
            bad = parse_long("seed", optarg, 0, 2147483647L, &lv);
            seed = (unsigned long long)lv;
            break;
        case 'l':
            bad = parse_double("lag", optarg, &lag);
            break;
        case 'n':
            bad = parse_double("noise-pos", optarg, &noise_pos);
            break;
        case 'N':
            bad = parse_double("noise-vel", optarg, &noise_vel);
            break;
        case 'v':
            bad = parse_double("vel", optarg, &vel);
            break;
        case 'a':
            bad = parse_double("acc", optarg, &acc);
            break;
        case 'd':
            bad = parse_double("dec", optarg, &dec);
            break;
        case 'r':
            bad = parse_double("range", optarg, &range);
            break;
        case 'i':
            if (n_inject >= MCA_SIM_MAX_INJECT) {
                fprintf(stderr, "mca-simarm-trace: more than %d --inject\n", MCA_SIM_MAX_INJECT);
                return 2;
            }
            bad = parse_inject(optarg, &inject[n_inject++]);
            break;
        case 'o':
            out_path = optarg;
            break;
        case 'h':
            printf("usage: mca-simarm-trace [--profile step|watchdog|random] [--cycles N] [--joints N] "
                   "[--lag S] [--latency K] [--noise-pos S] [--noise-vel S] [--seed N] [--watchdog W] "
                   "[--vel V] [--acc A] [--dec D] [--range R] [--inject " MCA_SIM_INJECT_SYNTAX
                   "]... [-o FILE]\n");
            return 0;
        default:
            return 2;
        }
        if (bad) {
            return 2;
        }
    }
    const int n = (int)joints;
    mca_sim_arm_config_t cfg;
    mca_sim_arm_config_default(&cfg, n);
    for (int j = 0; j < n; j++) {
        cfg.vel_limit[j] = vel * (1 + j / 4.0);
        cfg.acc_limit[j] = acc * (1 + j / 8.0);
        cfg.dec_limit[j] = dec * (1 - j / 16.0);
        if (range > 0) {
            cfg.lower[j] = -range * (1 + j / 10.0);
            cfg.upper[j] = range * (1 + j / 10.0);
        }
    }
    cfg.lag_tau = lag;
    cfg.latency_cycles = (int)latency;
    cfg.noise_pos = noise_pos;
    cfg.noise_vel = noise_vel;
    cfg.seed = seed;
    cfg.watchdog_cycles = (int)watchdog;
    cfg.n_inject = n_inject;
    memcpy(cfg.inject, inject, sizeof(inject));
    char err[256];
    if (mca_sim_arm_init(&g_arm, &cfg, err, sizeof(err)) != MCA_OK) {
        fprintf(stderr, "mca-simarm-trace: %s\n", err);
        return 2;
    }
    FILE *f = stdout;
    if (out_path && !(f = fopen(out_path, "w"))) {
        fprintf(stderr, "mca-simarm-trace: %s: %s\n", out_path, strerror(errno));
        return 1;
    }
    fprintf(f,
            "# profile=%s n=%d dt=%.17g lag_tau=%.17g latency=%d noise_pos=%.17g noise_vel=%.17g seed=%llu "
            "watchdog=%d\n",
            profile, n, cfg.dt, lag, cfg.latency_cycles, noise_pos, noise_vel, seed, cfg.watchdog_cycles);
    for (int j = 0; j < n; j++) {
        fprintf(
            f,
            "# joint %d lower=%.17g upper=%.17g vel=%.17g acc=%.17g dec=%.17g inertia=%.17g damping=%.17g "
            "q0=%.17g\n",
            j, cfg.lower[j], cfg.upper[j], cfg.vel_limit[j], cfg.acc_limit[j], cfg.dec_limit[j],
            cfg.inertia[j], cfg.damping[j], cfg.q0[j]);
    }
    for (int i = 0; i < n_inject; i++) {
        fprintf(f, "# inject kind=%d at=%llu duration=%llu joint=%d\n", inject[i].kind,
                (unsigned long long)inject[i].at_cycle, (unsigned long long)inject[i].duration,
                inject[i].joint);
    }
    fprintf(f, "k,has_cmd,cmd_id,cmd_n");
    for (int j = 0; j < n; j++) {
        fprintf(f, ",flags%d,u%d", j, j);
    }
    fprintf(f, ",rc,fb_id,state,fault");
    for (int j = 0; j < n; j++) {
        fprintf(f, ",q%d,v%d,tau%d,flt%d", j, j, j, j);
    }
    fprintf(f, "\n");
    uint32_t id = 0;
    for (long k = 0; k < cycles; k++) {
        mca_arm_command_t c;
        int has = make_cmd(profile, (int)k, n, &id, &c);
        mca_arm_feedback_t fb;
        memset(&fb, 0, sizeof(fb));
        int rc = mca_sim_arm_cycle(&g_arm, has ? &c : NULL, cfg.dt, &fb);
        fprintf(f, "%ld,%d,%u,%d", k, has, c.frame_id, c.n);
        for (int j = 0; j < n; j++) {
            fprintf(f, ",%u,%.17g", (unsigned)c.flags[j], c.velocity[j]);
        }
        fprintf(f, ",%d,%u,%d,%u", rc, fb.frame_id, (int)fb.state, (unsigned)fb.fault_code);
        for (int j = 0; j < n; j++) {
            fprintf(f, ",%.17g,%.17g,%.17g,%u", fb.position[j], fb.velocity[j], fb.torque[j],
                    (unsigned)fb.fault_flags[j]);
        }
        fprintf(f, "\n");
    }
    if (f != stdout && fclose(f) != 0) {
        fprintf(stderr, "mca-simarm-trace: %s: write failed\n", out_path);
        return 1;
    }
    return 0;
}
