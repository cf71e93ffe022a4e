/* SPDX-License-Identifier: MIT */
/* mca-sim: run a scenario in virtual time through mcad's tick (mca_drive_step: the same controller tick,
 * fault latching and braking) and print a Table-I style report.
 *   mca-sim --scenario FILE [--scheme mca|mca-ts|mvn|apf[,...]] [--csv OUT] [--dump-qp DIR] [--dump-every N]
 *           [--dump-max N] [--form componentwise|normal] [--euler] [--duration S] [--summary FILE]
 *           [--stop-at T] [--fault-at T:KIND] [--dec-limit X]
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "mca/daemon.h"
#include "mca/err.h"
#include "mca/qp_dump.h"
#include "mca/scenario.h"
#include "simrun.h"

static void usage(FILE *f) {
    fprintf(
        f,
        "usage: mca-sim --scenario FILE [--scheme mca|mca-ts|mvn|apf[,...]] [--csv OUT] [--dump-qp DIR]\n"
        "               [--dump-every N] [--dump-max N] [--form componentwise|normal] [--euler]\n"
        "               [--duration S] [--summary FILE.json] [--v-normal V] [--v-floor V]\n"
        "               [--pdnn-max-steps N] [--dist closed|lsdm] [--stop-at T] [--fault-at T:KIND]\n"
        "               [--dec-limit X] [--pdnn-budget-us U] [--w-path W] [--w-tube W] [--dump-capped]\n"
        "               [--no-coordinate] [--no-body-rows] [--no-self-rows]\n"
        "  --csv OUT      per-tick CSV (with several schemes: OUT-<scheme>.csv, OUT's .csv suffix dropped)\n"
        "  --dump-qp DIR  write every tick's QP (mca_qp_dump_json with the PDNN's phi) for tools/qp-check;\n"
        "                 --dump-every N keeps every Nth tick (and every N/5th with binding rows);\n"
        "                 --dump-capped adds the unconverged ones as NAME.json.capped (QPs to look at)\n"
        "  --euler        integrate qdot directly instead of the in-process sim backend\n"
        "  --summary F    JSON summary of every run (for tests)\n"
        "  --no-coordinate  mca-ts without the start-up plan of who passes first where fixed paths meet\n"
        "                 (docs/scheme.md, Coordination)\n"
        "  --no-body-rows the scenario's fixed bodies measured only: no rows, no clearance fault (what the "
        "run\n"
        "                 does without them; docs/scheme.md, Fixed bodies)\n"
        "  --no-self-rows the scenario's self pairs measured only: no rows, no d1 fault (docs/scheme.md, "
        "Self "
        "pairs)\n"
        "  --stop-at T    stop request at task time T s, as SIGTERM to mcad (brakes through the controller)\n"
        "  --fault-at T:KIND  latch controller fault KIND at T s (pdnn-not-converged, fake-attractor, "
        "distance,\n"
        "                 nan, infeasible, input), then brake as mcad does on that fault\n"
        "  --dec-limit X  every joint's deceleration limit [rad/s^2]: the daemon's braking and the sim "
        "arm's\n"
        "                 (default 10)\n"
        "  --w-path W, --w-tube W  mca-ts's exact and quadratic slack weights for paths with a tube\n"
        "                 (docs/scheme.md section 11)\n"
        "  --pdnn-budget-us U  the PDNN's budget per tick as mcad's rt.pdnn_budget_us, applied as its step\n"
        "                 budget (U / 0.7 us steps, below the step cap; 0: none; default half the period)\n");
}

static int parse_int(const char *s, int *out) {
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || *end || end == s || v < 0 || v > 100000000) {
        return -1;
    }
    *out = (int)v;
    return 0;
}

static void csv_name(char *out, size_t len, const char *base, const char *scheme, int multi) {
    if (!multi) {
        snprintf(out, len, "%s", base);
        return;
    }
    const char *dot = strrchr(base, '.');
    if (dot && strcmp(dot, ".csv") == 0) {
        snprintf(out, len, "%.*s-%s.csv", (int)(dot - base), base, scheme);
    } else {
        snprintf(out, len, "%s-%s.csv", base, scheme); /* OUT without .csv: still OUT-<scheme>.csv */
    }
}

/* x as a JSON number (%.9g), or null when it is not finite (one arm has no arm pair: +INF is no JSON). */
static const char *json_num(char out[32], double x) {
    if (!isfinite(x)) {
        return "null";
    }
    snprintf(out, 32, "%.9g", x);
    return out;
}

/* s as the inside of a JSON string (quotes and backslashes escaped, control characters dropped). */
static const char *json_text(char *out, size_t len, const char *s) {
    size_t k = 0;
    for (; *s && k + 3 < len; s++) {
        if (*s == '"' || *s == '\\') {
            out[k++] = '\\';
            out[k++] = *s;
        } else if ((unsigned char)*s >= 0x20) {
            out[k++] = *s;
        }
    }
    out[k] = 0;
    return out;
}

static void print_dist(double d) {
    if (isnan(d)) {
        printf(" %12s", "-");
    } else {
        printf(" %10.5f m", d);
    }
}

int main(int argc, char **argv) {
    const char *scenario = NULL, *schemes = "mca", *csv = NULL, *dump = NULL, *summary = NULL;
    mca_simrun_opts_t o;
    mca_simrun_default_opts(&o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--euler")) {
            o.use_backend = 0;
            continue;
        } else if (!strcmp(a, "--no-coordinate")) {
            o.no_coordinate = 1;
            continue;
        } else if (!strcmp(a, "--no-body-rows")) {
            o.no_body_rows = 1;
            continue;
        } else if (!strcmp(a, "--no-self-rows")) {
            o.no_self_rows = 1;
            continue;
        } else if (!strcmp(a, "--dump-capped")) {
            o.dump_capped = 1;
            continue;
        }
        if (!v) {
            fprintf(stderr, "mca-sim: %s needs a value\n", a);
            usage(stderr);
            return 2;
        }
        i++;
        if (!strcmp(a, "--scenario")) {
            scenario = v;
        } else if (!strcmp(a, "--scheme")) {
            schemes = v;
        } else if (!strcmp(a, "--csv")) {
            csv = v;
        } else if (!strcmp(a, "--dump-qp")) {
            dump = v;
        } else if (!strcmp(a, "--summary")) {
            summary = v;
        } else if (!strcmp(a, "--dump-every")) {
            if (parse_int(v, &o.dump_every) || o.dump_every < 1) {
                fprintf(stderr, "mca-sim: --dump-every: bad value '%s'\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--w-tube") || !strcmp(a, "--w-path")) {
            char *end;
            const double x = strtod(v, &end);
            if (*end || !(x > 0.0)) {
                fprintf(stderr, "mca-sim: %s: bad value '%s' (> 0)\n", a, v);
                return 2;
            }
            if (a[4] == 't') {
                o.w_tube = x;
            } else {
                o.w_path = x;
            }
        } else if (!strcmp(a, "--dump-max")) {
            if (parse_int(v, &o.dump_max)) {
                fprintf(stderr, "mca-sim: --dump-max: bad value '%s'\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--pdnn-max-steps")) {
            if (parse_int(v, &o.pdnn_max_steps)) {
                fprintf(stderr, "mca-sim: --pdnn-max-steps: bad value '%s'\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--pdnn-budget-us")) {
            if (parse_int(v, &o.pdnn_budget_us)) {
                fprintf(stderr, "mca-sim: --pdnn-budget-us: bad value '%s'\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--v-normal") || !strcmp(a, "--v-floor")) {
            char *end;
            const double x = strtod(v, &end);
            if (*end || !(x >= 0.0) || !isfinite(x)) {
                fprintf(stderr, "mca-sim: %s: bad value '%s'\n", a, v);
                return 2;
            }
            if (a[4] == 'n') {
                o.v_normal = x;
            } else {
                o.v_floor = x;
            }
        } else if (!strcmp(a, "--stop-at") || !strcmp(a, "--dec-limit")) {
            char *end;
            const double x = strtod(v, &end);
            if (*end || !isfinite(x) || (a[2] == 's' ? !(x >= 0.0) : !(x > 0.0))) {
                fprintf(stderr, "mca-sim: %s: bad value '%s'\n", a, v);
                return 2;
            }
            if (a[2] == 's') {
                o.stop_at = x;
            } else {
                o.dec_limit = x;
            }
        } else if (!strcmp(a, "--fault-at")) {
            char *end;
            const double x = strtod(v, &end);
            if (*end != ':' || !isfinite(x) || !(x >= 0.0) ||
                (o.fault_kind = mca_simrun_fault_from_name(end + 1)) < 0) {
                fprintf(
                    stderr,
                    "mca-sim: --fault-at: bad value '%s' (want T:KIND, KIND one of nan, pdnn-not-converged, "
                    "infeasible, distance, fake-attractor, input)\n",
                    v);
                return 2;
            }
            o.fault_at = x;
        } else if (!strcmp(a, "--duration")) {
            char *end;
            o.duration = strtod(v, &end);
            if (*end || !(o.duration > 0.0)) {
                fprintf(stderr, "mca-sim: --duration: bad value '%s'\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--dist")) {
            if (!strcmp(v, "lsdm")) {
                o.dist_lsdm = 1;
            } else if (!strcmp(v, "closed")) {
                o.dist_lsdm = 0;
            } else {
                fprintf(stderr, "mca-sim: --dist: '%s' is not closed or lsdm\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--form")) {
            if (!strcmp(v, "componentwise")) {
                o.form = MCA_FORM_COMPONENTWISE;
            } else if (!strcmp(v, "normal")) {
                o.form = MCA_FORM_NORMAL;
            } else {
                fprintf(stderr, "mca-sim: --form: '%s' is not componentwise or normal\n", v);
                return 2;
            }
        } else {
            fprintf(stderr, "mca-sim: unknown option '%s'\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (!scenario) {
        fprintf(stderr, "mca-sim: --scenario is required\n");
        usage(stderr);
        return 2;
    }
    mca_scheme_kind_t list[4];
    int n_list = 0;
    {
        char buf[64];
        snprintf(buf, sizeof buf, "%s", schemes);
        for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
            if (n_list == 4) {
                fprintf(stderr, "mca-sim: --scheme: at most 4 schemes\n");
                return 2;
            }
            if (mca_scheme_from_name(tok, &list[n_list]) != MCA_OK) {
                fprintf(stderr, "mca-sim: --scheme: '%s' is not mca, mca-ts, mvn or apf\n", tok);
                return 2;
            }
            n_list++;
        }
    }
    if (dump && mkdir(dump, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "mca-sim: --dump-qp %s: %s\n", dump, strerror(errno));
        return 1;
    }
    static mca_scenario_t scn;
    char err[1024] = "";
    int rc = mca_scenario_load(scenario, &scn, err, sizeof err);
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-sim: %s\n", err);
        return 1;
    }
    if (o.duration > 0.0) {
        /* the file's duration was checked as it loaded; an override gets the same range and tick count */
        char why[160];
        if (mca_scenario_check_duration(o.duration, scn.params.dt, why, sizeof why) != MCA_OK) {
            fprintf(stderr, "mca-sim: --duration: %s\n", why);
            return 2;
        }
    }
    static mca_simrun_result_t res[4];
    for (int s = 0; s < n_list; s++) {
        char csvp[1024];
        o.scheme = list[s];
        if (csv) {
            csv_name(csvp, sizeof csvp, csv, mca_scheme_name(list[s]), n_list > 1);
            o.csv_path = csvp;
        }
        o.dump_dir = dump;
        rc = mca_simrun(&scn, &o, &res[s], err, sizeof err);
        if (rc != MCA_OK) {
            fprintf(stderr, "mca-sim: %s\n", err);
            return 1;
        }
    }
    const double d1 = scn.params.d1, d2 = scn.params.d2;
    printf("scenario %s (%s), d1 %.3f m, d2 %.3f m, form %s, distances %s, arms simulated by %s\n", scn.name,
           scenario, d1, d2,
           (o.form >= 0 ? o.form : scn.params.form) == MCA_FORM_COMPONENTWISE ? "componentwise" : "normal",
           o.dist_lsdm ? "LSDM" : "closed form", o.use_backend ? "the sim backend" : "Euler integration");
    if (scn.n_sample_times > 0) {
        printf("\nminimum distance at sampled instants (Table I style)\n%8s %8s %8s", "t", "d1", "d2");
        for (int s = 0; s < n_list; s++) {
            printf(" %9s scheme", res[s].scheme);
        }
        printf("\n");
        for (int i = 0; i < scn.n_sample_times; i++) {
            printf("%7.1fs %6.2fm %6.2fm", scn.sample_times[i], d1, d2);
            for (int s = 0; s < n_list; s++) {
                print_dist(res[s].sample_d[i]);
                printf("    ");
            }
            printf("\n");
        }
    }
    printf("\nmax err: over all ticks before any fault; err free: over ticks where no collision row binds;\n"
           "err S=1: over ticks with no link inside d2 (brake factor 1)\n");
    printf("%-6s %12s %9s %12s %12s %12s %12s %9s %9s %10s %10s %10s\n", "scheme", "min d [m]", "at [s]",
           "max err [m]", "err free[m]", "err S=1 [m]", "eq res", "pdnn max", "pdnn avg", "tick p50",
           "tick p99", "tick max");
    for (int s = 0; s < n_list; s++) {
        const mca_simrun_result_t *r = &res[s];
        printf("%-6s %12.5f %9.3f %12.3e %12.3e %12.3e %12.3e %9d %9.1f %8.1fus %8.1fus %8.1fus\n", r->scheme,
               r->min_distance, r->min_distance_t, r->max_err, r->max_err_free, r->max_err_nobrake,
               r->eq_residual_max, r->pdnn_steps_max, r->pdnn_steps_mean, r->compute_p50 / 1e3,
               r->compute_p99 / 1e3, r->compute_max / 1e3);
    }
    for (int s = 0; s < n_list; s++) {
        const mca_simrun_result_t *r = &res[s];
        printf("%s: tick thread CPU time p50 %.1f us, p99 %.1f us, max %.1f us\n", r->scheme,
               r->cpu_p50 / 1e3, r->cpu_p99 / 1e3, r->cpu_max / 1e3);
    }
    for (int s = 0; s < n_list; s++) {
        const mca_simrun_result_t *r = &res[s];
        if (r->min_distance < d1) {
            printf("%s: distance below d1 (%.5f m at %.3f s)\n", r->scheme, r->min_distance,
                   r->min_distance_t);
        }
        if (r->fault) {
            printf("%s: FAULT %s at t = %.3f s (distance %.5f m): %s; %s at %.3f s, min distance after the "
                   "fault %.5f m\n",
                   r->scheme, mca_ctrl_fault_name(r->fault), r->fault_t, r->fault_distance, r->fault_text,
                   r->stopped ? "arms stopped" : "arms NOT stopped", r->stop_t, r->min_distance_after_fault);
        }
        printf("%s: path error max %.3e m, p99 %.3e m; exact points %d, missed %d (max %.3e m); PDNN steps "
               "p50 %d, p99.9 %d\n",
               r->scheme, r->path_error_max, r->path_error_p99, r->exact_points, r->exact_missed,
               r->exact_error_max, r->pdnn_steps_p50, r->pdnn_steps_p999);
        if (r->n_bodies > 0) {
            const int k = r->body_min_body;
            printf(
                "%s: fixed bodies: least margin %.5f m (distance %.5f m) at %.3f s, arm %d link %d against "
                "%s '%s'; %d ticks inside a clearance\n",
                r->scheme, r->body_min_margin, r->body_min_distance, r->body_min_t, r->body_min_arm,
                r->body_min_link, mca_body_kind_name(r->body_min_kind), k >= 0 ? scn.body[k].fb.name : "",
                r->body_ticks_below);
        }
        if (r->has_self) {
            printf("%s: self pairs: least distance %.5f m at %.3f s, arm %d links %d-%d; %d ticks below d1\n",
                   r->scheme, r->self_min_distance, r->self_min_t, r->self_min_arm, r->self_min_link,
                   r->self_min_other, r->self_ticks_below);
        }
        if (r->has_sphere) {
            printf(
                "%s: streamed sphere: %d samples delivered, %d lost; least margin d - S_p %.5f m at %.3f s "
                "(arm %d, S_p up to %.3f m); below S_p: %d arm-ticks at rest (the sphere walked in), %d "
                "moving (%d of them braking); least distance to the true sphere %.5f m\n",
                r->scheme, r->sphere_sent, r->sphere_lost, r->track_min_margin, r->track_min_t,
                r->track_min_arm, r->track_sp_max, r->track_ticks_rest, r->track_ticks_moving,
                r->track_ticks_braking, r->sphere_true_min_d);
        }
        if (r->budget_hits_steps + r->budget_hits_time) {
            printf("%s: %d ticks out of the PDNN's budget (%d at its %d steps, %d by the clock): repaired "
                   "answers, "
                   "no fault\n",
                   r->scheme, r->budget_hits_steps + r->budget_hits_time, r->budget_hits_steps,
                   r->budget_steps, r->budget_hits_time);
        }
        if (r->pdnn_capped) {
            printf("%s: %d ticks with the PDNN at its step cap (residual <= fault_residual, accepted)\n",
                   r->scheme, r->pdnn_capped);
        }
        if (dump) {
            printf("%s: %d QPs dumped to %s (%d with binding collision rows); %d capped ticks not dumped "
                   "(%d picked by --dump-every)\n",
                   r->scheme, r->dumped, dump, r->dumped_binding, r->pdnn_capped, r->dump_skipped_capped);
        }
    }
    if (summary) {
        FILE *f = fopen(summary, "w");
        if (!f) {
            fprintf(stderr, "mca-sim: --summary %s: %s\n", summary, strerror(errno));
            return 1;
        }
        fprintf(f, "{\"scenario\":\"%s\",\"d1\":%.9g,\"d2\":%.9g,\"runs\":[", scn.name, d1, d2);
        for (int s = 0; s < n_list; s++) {
            const mca_simrun_result_t *r = &res[s];
            char jt[400], num[32];
            fprintf(f,
                    "%s{\"scheme\":\"%s\",\"ticks\":%d,\"min_distance\":%s,\"min_distance_t\":%.6g,"
                    "\"max_err\":%.6g,\"max_err_free\":%.6g,\"max_err_nobrake\":%.6g,\"fault\":%d,"
                    "\"fault_name\":\"%s\",\"fault_t\":%.6g,\"fault_distance\":%.9g,\"stopped\":%d,"
                    "\"stop_t\":%.6g,\"min_distance_after_fault\":%.9g,\"pdnn_steps_max\":%d,"
                    "\"pdnn_steps_mean\":%.3f,\"pdnn_residual_max\":%.3g,\"eq_residual_max\":%.3g,"
                    "\"binding_ticks\":%d,\"pdnn_capped\":%d,\"compute_p50_ns\":%lld,\"compute_p99_ns\":%lld,"
                    "\"compute_max_ns\":%lld,\"cpu_p50_ns\":%lld,\"cpu_p99_ns\":%lld,\"cpu_max_ns\":%lld,"
                    "\"dumped\":%d,\"dumped_binding\":%d,\"dump_skipped_capped\":%d,\"pdnn_budget_steps\":%d,"
                    "\"budget_hits_steps\":%d,\"budget_hits_time\":%d,\"samples\":[",
                    s ? "," : "", r->scheme, r->ticks, json_num(num, r->min_distance), r->min_distance_t,
                    r->max_err, r->max_err_free, r->max_err_nobrake, r->fault, mca_ctrl_fault_name(r->fault),
                    r->fault_t, isfinite(r->fault_distance) ? r->fault_distance : -1.0, r->stopped, r->stop_t,
                    isfinite(r->min_distance_after_fault) ? r->min_distance_after_fault : -1.0,
                    r->pdnn_steps_max, r->pdnn_steps_mean, r->pdnn_residual_max, r->eq_residual_max,
                    r->binding_ticks, r->pdnn_capped, (long long)r->compute_p50, (long long)r->compute_p99,
                    (long long)r->compute_max, (long long)r->cpu_p50, (long long)r->cpu_p99,
                    (long long)r->cpu_max, r->dumped, r->dumped_binding, r->dump_skipped_capped,
                    r->budget_steps, r->budget_hits_steps, r->budget_hits_time);
            for (int i = 0; i < r->n_samples; i++) {
                fprintf(f, "%s[%.6g,%s]", i ? "," : "", r->sample_t[i],
                        isnan(r->sample_d[i]) ? "-1" : json_num(num, r->sample_d[i]));
            }
            fprintf(f, "],\"completed\":%d,\"path_time_lost_s\":%.6g,\"deadlocks\":%d,\"max_slack\":%.3g",
                    r->completed, r->path_time_lost_s, r->deadlocks, r->max_slack);
            fprintf(f,
                    ",\"path_error_max\":%.6g,\"path_error_p99\":%.6g,\"path_error_brake_max\":%.6g,"
                    "\"exact_points\":%d,\"exact_missed\":%d,\"exact_error_max\":%.6g,\"pdnn_steps_p50\":%d,"
                    "\"pdnn_steps_p999\":%d",
                    r->path_error_max, r->path_error_p99, r->path_error_brake_max, r->exact_points,
                    r->exact_missed, r->exact_error_max, r->pdnn_steps_p50, r->pdnn_steps_p999);
            fprintf(f, ",\"end_pair\":[%d,%d,%d,%d],\"end_distance\":%.6g,\"end_ee\":[", r->end_pair[0],
                    r->end_pair[1], r->end_pair[2], r->end_pair[3],
                    isfinite(r->end_distance) ? r->end_distance : -1.0);
            for (int a = 0; a < scn.n_arms; a++) {
                fprintf(f, "%s[%.5f,%.5f,%.5f]", a ? "," : "", r->end_ee[a][0], r->end_ee[a][1],
                        r->end_ee[a][2]);
            }
            fprintf(f, "],\"end_tau\":[");
            for (int a = 0; a < scn.n_arms; a++) {
                fprintf(f, "%s%.4f", a ? "," : "", r->end_tau[a]);
            }
            fprintf(f, "],\"end_done\":[");
            for (int a = 0; a < scn.n_arms; a++) {
                fprintf(f, "%s%d", a ? "," : "", r->end_done[a]);
            }
            fprintf(f, "],\"coord_pairs\":%d,\"coord_unplanned\":%d,\"arm_ticks_below\":%d", r->coord_pairs,
                    r->coord_unplanned, r->arm_ticks_below);
            if (r->n_bodies > 0) {
                const int k = r->body_min_body;
                fprintf(
                    f,
                    ",\"bodies\":%d,\"body_min_margin\":%.9g,\"body_min_distance\":%.9g,\"body_min_t\":%.6g,"
                    "\"body_min_pair\":[%d,%d,%d],\"body_min_name\":\"%s\",\"body_min_kind\":\"%s\","
                    "\"body_ticks_below\":%d",
                    r->n_bodies, r->body_min_margin, r->body_min_distance, r->body_min_t, r->body_min_arm,
                    r->body_min_link, k, k >= 0 ? scn.body[k].fb.name : "",
                    mca_body_kind_name(r->body_min_kind), r->body_ticks_below);
            }
            if (r->has_self) {
                fprintf(f,
                        ",\"self_min_distance\":%.9g,\"self_min_t\":%.6g,\"self_min_pair\":[%d,%d,%d],"
                        "\"self_ticks_below\":%d",
                        r->self_min_distance, r->self_min_t, r->self_min_arm, r->self_min_link,
                        r->self_min_other, r->self_ticks_below);
            }
            if (r->has_sphere) {
                fprintf(
                    f,
                    ",\"sphere_sent\":%d,\"sphere_lost\":%d,\"track_min_margin\":%.9g,\"track_min_t\":%.6g,"
                    "\"track_min_arm\":%d,\"track_sp_max\":%.9g,\"track_ticks_rest\":%d,"
                    "\"track_ticks_moving\":%d,\"track_ticks_braking\":%d,\"sphere_true_min_d\":%.9g",
                    r->sphere_sent, r->sphere_lost, isfinite(r->track_min_margin) ? r->track_min_margin : 1e9,
                    r->track_min_t, r->track_min_arm, r->track_sp_max, r->track_ticks_rest,
                    r->track_ticks_moving, r->track_ticks_braking,
                    isfinite(r->sphere_true_min_d) ? r->sphere_true_min_d : 1e9);
            }
            /* every kind of pair and each fixed body: the least distance over the run (null: no such pair) */
            fprintf(f, ",\"pair_kinds\":{");
            for (int k = 0; k < MCA_DDS_PAIR_KINDS; k++) {
                fprintf(f, "%s\"%s\":{\"min\":%s,\"t\":%.6g}", k ? "," : "", mca_dds_pair_kind_name(k),
                        json_num(num, r->kind_min[k]), isfinite(r->kind_min[k]) ? r->kind_min_t[k] : 0.0);
            }
            fprintf(f, "},\"body_min\":[");
            for (int k = 0; k < r->n_fixed_bodies && k < MCA_MAX_BODIES; k++) {
                fprintf(f, "%s{\"name\":\"%s\",\"min\":%s,\"t\":%.6g,\"arm\":%d,\"link\":%d}", k ? "," : "",
                        json_text(jt, sizeof jt, scn.body[k].fb.name), json_num(num, r->fixed_min[k]),
                        isfinite(r->fixed_min[k]) ? r->fixed_min_t[k] : 0.0, r->fixed_min_link[k][0],
                        r->fixed_min_link[k][1]);
            }
            fprintf(f, "]");
            fprintf(f,
                    ",\"solves\":%d,\"solves_unconverged\":%d,\"solve_steps\":[%d,%d,%d],"
                    "\"exact_solves\":[%d,%d,%d]",
                    r->solves, r->solves_unconverged, r->solve_steps_p50, r->solve_steps_p999,
                    r->solve_steps_max, r->exact_p50, r->exact_p999, r->exact_max);
            fprintf(
                f,
                ",\"fault_text\":\"%s\",\"stop_requested\":%d,\"brake_t\":%.6g,\"brake_fallback_ticks\":%d,"
                "\"brake_forced_ticks\":%"
                "d,"
                "\"stop_duration_s\":%.6g,\"max_dv_over_dt_dec\":%.9g,\"dec_limit\":%.6g,\"state\":\"%s\"}",
                json_text(jt, sizeof jt, r->fault_text), r->stop_requested, r->brake_t,
                r->brake_fallback_ticks, r->brake_forced_ticks, r->stop_duration_s, r->max_dv_over_dt_dec,
                o.dec_limit > 0.0 ? o.dec_limit : 10.0, mca_daemon_state_name(r->daemon_state));
        }
        fprintf(f, "]}\n");
        fclose(f);
    }
    return 0;
}
