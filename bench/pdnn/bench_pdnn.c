/* SPDX-License-Identifier: MIT */
/* LVI-PDNN benchmark on dual-arm-sized QPs (n = 16, n_eq = 6, n_ineq = 54; tests/pdnn/qpgen.h).
 *
 *   bench_pdnn time [OPTIONS]        ns and steps per solve (p50/p99/max), cold and warm, over runs of
 *                                    ticks: a fresh scene solved cold, then --ticks-1 moves of --eps solved
 *                                    warm (a 1 kHz controller's view)
 *   bench_pdnn dump DIR [OPTIONS]    the same QPs written for bench/pdnn/osqp_vs_pdnn.py, with
 *                                    DIR/pdnn_times.csv (file, ns, steps, warm)
 *   bench_pdnn edge [OPTIONS]        fixed Euler step kappa = f * kappa_bound for a range of f on cold
 *                                    solves: steps to converge (or capped, or diverged), and whether 5
 *                                    warm ticks (moves of --eps) after it converge too (the stability edge)
 *   bench_pdnn replay DIR [OPTIONS]  the QPs of DIR (mca_qp_dump_json files, e.g. mca-sim --dump-qp) solved
 *                                    in file-name order with one warm-started solver, as the loop would
 *                                    (but without the loop's row remapping): steps, polish tries, unconverged
 *                                    (--max-steps defaults to the controller's 2000 here)
 * OPTIONS: --runs R (100) --ticks T (10) --eps E (1e-3) --tol X (1e-9) --precond orth|scale|none
 *          --rule adaptive|bound --far W (0.3; 1 = off) --max-steps S (20000) --seed K (1) --tight P (0.15)
 *          --gamma G (1.9) --form componentwise|normal (componentwise: 3 rows per link, 54; normal: 1, 18)
 *          --no-polish 0|1 (0) --polish-max N (0: the solver's default) --verbose 1 (replay: name the
 *          QPs not converged or over 300 steps)
 *   bench_pdnn daqp DIR [--daqp-lib L] [--csv F] [OPTIONS]  PDNN (polish on unless --no-polish 1) against
 *                                    DAQP on the same QPs: every subfolder of DIR (or DIR itself) is one task
 *                                    whose QPs (NAME.json and the capped NAME.json.capped) are solved in
 *                                    file-name order, each solver warm from the previous QP, both started
 *                                    cold at each task; ns per solve of each, p50/p99/max, PDNN p99 / DAQP
 *                                    p99, max |phi_pdnn - phi_daqp|. DAQP is dlopened from L (default
 *                                    libmca_daqp.so; bench/daqp/build.sh builds it): without it one line
 *                                    "skipped: daqp not available" and exit 0. --csv F: per QP file, ns,
 * flags and both answers (bench/daqp/osqp_daqp.py checks them against OSQP).
 *                                    --runs R passes (default 3): the figures of the median-ratio pass
 * Not a test: numbers depend on the machine. */
#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "mca/err.h"
#include "mca/pdnn.h"
#include "mca/qp_dump.h"
#include "qpgen.h"

typedef struct opts {
    int runs, ticks, max_steps;
    double eps, tol, far, tight, gamma;
    int precond, rule, normal, no_polish, polish_max, verbose;
    unsigned long long seed;
    const char *dir, *lib, *csv;
} opts_t;

static mca_pdnn_t solver;

static double now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}

static int cmp_d(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double pct(double *v, int n, double p) {
    if (n == 0) {
        return NAN;
    }
    qsort(v, (size_t)n, sizeof(double), cmp_d);
    int i = (int)ceil(p / 100.0 * n) - 1;
    return v[i < 0 ? 0 : (i >= n ? n - 1 : i)];
}

static void usage(const char *argv0) {
    fprintf(stderr,
            "usage: %s time|dump DIR|edge|replay DIR|daqp DIR [--daqp-lib L] [--csv F] [--runs R] [--ticks "
            "T] [--eps E] [--tol X] [--precond "
            "orth|scale|none]\n"
            "       [--rule adaptive|bound] [--far W] [--max-steps S] [--seed K] [--tight P] [--gamma G]\n"
            "       [--form componentwise|normal] [--no-polish 0|1] [--polish-max N]\n",
            argv0);
}

static int parse(int argc, char **argv, int first, opts_t *o) {
    for (int i = first; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (v == NULL) {
            fprintf(stderr, "option %s needs a value\n", a);
            return -1;
        }
        char *end = NULL;
        i++;
        if (!strcmp(a, "--daqp-lib") || !strcmp(a, "--csv")) {
            *(!strcmp(a, "--csv") ? &o->csv : &o->lib) = v;
            continue;
        }
        if (!strcmp(a, "--runs")) {
            o->runs = (int)strtol(v, &end, 10);
        } else if (!strcmp(a, "--ticks")) {
            o->ticks = (int)strtol(v, &end, 10);
        } else if (!strcmp(a, "--max-steps")) {
            o->max_steps = (int)strtol(v, &end, 10);
        } else if (!strcmp(a, "--no-polish")) {
            o->no_polish = (int)strtol(v, &end, 10);
        } else if (!strcmp(a, "--verbose")) {
            o->verbose = (int)strtol(v, &end, 10);
        } else if (!strcmp(a, "--polish-max")) {
            o->polish_max = (int)strtol(v, &end, 10);
        } else if (!strcmp(a, "--seed")) {
            o->seed = strtoull(v, &end, 10);
        } else if (!strcmp(a, "--eps")) {
            o->eps = strtod(v, &end);
        } else if (!strcmp(a, "--tol")) {
            o->tol = strtod(v, &end);
        } else if (!strcmp(a, "--far")) {
            o->far = strtod(v, &end);
        } else if (!strcmp(a, "--gamma")) {
            o->gamma = strtod(v, &end);
        } else if (!strcmp(a, "--tight")) {
            o->tight = strtod(v, &end);
        } else if (!strcmp(a, "--form")) {
            o->normal = !strcmp(v, "normal") ? 1 : !strcmp(v, "componentwise") ? 0 : -1;
            end = o->normal < 0 ? (char *)v : (char *)v + strlen(v);
        } else if (!strcmp(a, "--precond")) {
            o->precond = !strcmp(v, "orth")    ? MCA_PDNN_PRECOND_ORTH
                         : !strcmp(v, "scale") ? MCA_PDNN_PRECOND_SCALE
                         : !strcmp(v, "none")  ? MCA_PDNN_PRECOND_NONE
                                               : -1;
            end = o->precond < 0 ? (char *)v : (char *)v + strlen(v);
        } else if (!strcmp(a, "--rule")) {
            o->rule = !strcmp(v, "adaptive") ? MCA_PDNN_STEP_ADAPTIVE
                      : !strcmp(v, "bound")  ? MCA_PDNN_STEP_BOUND
                                             : -1;
            end = o->rule < 0 ? (char *)v : (char *)v + strlen(v);
        } else {
            fprintf(stderr, "unknown option %s\n", a);
            return -1;
        }
        if (end == NULL || *end != '\0') {
            fprintf(stderr, "bad value '%s' for %s\n", v, a);
            return -1;
        }
    }
    if (o->runs < 1 || o->ticks < 1 || o->max_steps < 1 || !(o->eps >= 0) || !(o->tol > 0) ||
        !(o->far > 0 && o->far <= 1) || !(o->tight >= 0 && o->tight <= 1) ||
        !(o->gamma > 0 && o->gamma < 2)) {
        fprintf(stderr, "option out of range\n");
        return -1;
    }
    return 0;
}

static void params_of(const opts_t *o, mca_pdnn_params_t *prm) {
    mca_pdnn_default_params(prm);
    prm->tol = o->tol;
    prm->max_steps = o->max_steps;
    prm->precond = o->precond;
    prm->step_rule = o->rule;
    prm->far_weight = o->far;
    prm->gamma = o->gamma;
    prm->no_polish = o->no_polish;
    prm->polish_max = o->polish_max;
}

/* ---- replay: a reader for mca_qp_dump_json's output (model/src/qp_dump.c), that format only ---- */
/* The value after "key": in s, or NULL. */
static const char *json_key(const char *s, const char *key) {
    char pat[64];
    snprintf(pat, sizeof(pat), "\"%s\":", key);
    const char *p = strstr(s, pat);
    return p ? p + strlen(pat) : NULL;
}

/* [x, y, null, ...] into out (null -> null_val); the count, or -1 */
static int json_vec(const char **pp, double *out, int max, double null_val) {
    const char *p = *pp;
    while (*p == ' ' || *p == '\n' || *p == ',') {
        p++;
    }
    if (*p++ != '[') {
        return -1;
    }
    int k = 0;
    for (;;) {
        while (*p == ' ' || *p == '\n' || *p == ',') {
            p++;
        }
        if (*p == ']') {
            *pp = p + 1;
            return k;
        }
        if (k == max) {
            return -1;
        }
        if (!strncmp(p, "null", 4)) {
            out[k++] = null_val;
            p += 4;
        } else {
            char *end;
            out[k++] = strtod(p, &end);
            if (end == p) {
                return -1;
            }
            p = end;
        }
    }
}

static int json_int(const char *s, const char *key, int *v) {
    const char *p = json_key(s, key);
    return p && sscanf(p, "%d", v) == 1 ? 0 : -1;
}

/* [[row], [row], ...]: rows of len each */
static int json_mat(const char *s, const char *key, double *m, int rows, int stride, int len) {
    const char *p = json_key(s, key);
    if (p == NULL || *p++ != '[') {
        return -1;
    }
    for (int i = 0; i < rows; i++) {
        if (json_vec(&p, m + (size_t)i * (size_t)stride, len, NAN) != len) {
            return -1;
        }
    }
    return 0;
}

static int json_vec_key(const char *s, const char *key, double *v, int len, double null_val) {
    const char *p = json_key(s, key);
    return p && json_vec(&p, v, len, null_val) == len ? 0 : -1;
}

static char *slurp(const char *path) {
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return NULL;
    }
    fseek(f, 0, SEEK_END);
    const long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = len >= 0 ? malloc((size_t)len + 1) : NULL;
    if (buf != NULL && fread(buf, 1, (size_t)len, f) != (size_t)len) {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    if (buf != NULL) {
        buf[len] = '\0';
    }
    return buf;
}

/* One dumped QP (and the phi it was dumped with, when present: has_phi). 0 or -1. */
static int read_qp(const char *path, mca_qp_t *qp, double *phi, int *has_phi) {
    char *s = slurp(path);
    if (s == NULL) {
        return -1;
    }
    int n, ne, ni, rc = -1;
    if (json_int(s, "n", &n) == 0 && json_int(s, "n_eq", &ne) == 0 && json_int(s, "n_ineq", &ni) == 0 &&
        mca_qp_reset(qp, n, ne, ni) == MCA_OK &&
        json_mat(s, "G", &qp->G[0][0], ne, MCA_QP_MAX_VARS, n) == 0 &&
        json_vec_key(s, "alpha", qp->alpha, ne, NAN) == 0 &&
        json_mat(s, "U", &qp->U[0][0], ni, MCA_QP_MAX_VARS, n) == 0 &&
        json_vec_key(s, "beta", qp->beta, ni, NAN) == 0 && json_vec_key(s, "lb", qp->lb, n, -INFINITY) == 0 &&
        json_vec_key(s, "ub", qp->ub, n, INFINITY) == 0) {
        rc = 0;
        /* the dumped phi as a reference only where it was converged (mca-sim dumps capped ticks too when
           asked, tagged "capped") */
        const char *tag = json_key(s, "tag");
        *has_phi = json_vec_key(s, "phi", phi, n, NAN) == 0 && !(tag && strstr(tag, "capped"));
    }
    free(s);
    return rc;
}

static int cmp_str(const void *a, const void *b) {
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static int has_suffix(const char *s, const char *suf) {
    const size_t a = strlen(s), b = strlen(suf);
    return a >= b && !strcmp(s + a - b, suf);
}

/* The QP files of dir in name order (with capped: NAME.json.capped too; mca-sim's names carry the tick
   zero-padded, so name order is tick order); subdirs: the subfolders instead. The count, or -1. */
static int list_dir(const char *dir, int capped, int subdirs, char ***out) {
    DIR *d = opendir(dir);
    if (d == NULL) {
        fprintf(stderr, "cannot open %s: %s\n", dir, strerror(errno));
        return -1;
    }
    int nf = 0, cap = 0;
    char **names = NULL;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        if (subdirs) {
            char path[4096];
            struct stat sb;
            snprintf(path, sizeof(path), "%s/%s", dir, e->d_name);
            if (e->d_name[0] == '.' || stat(path, &sb) != 0 || !S_ISDIR(sb.st_mode)) {
                continue;
            }
        } else if (!has_suffix(e->d_name, ".json") && !(capped && has_suffix(e->d_name, ".json.capped"))) {
            continue;
        }
        if (nf == cap) {
            cap = cap ? 2 * cap : 256;
            names = realloc(names, sizeof(char *) * (size_t)cap);
        }
        names[nf++] = strdup(e->d_name);
    }
    closedir(d);
    if (nf > 0) {
        qsort(names, (size_t)nf, sizeof(char *), cmp_str);
    }
    *out = names;
    return nf;
}

static int run_replay(const opts_t *o) {
    char **names = NULL;
    const int nf = list_dir(o->dir, 0, 0, &names);
    if (nf <= 0) {
        fprintf(stderr, "no .json files in %s\n", o->dir);
        return 2;
    }
    double *st = calloc((size_t)nf, sizeof(double)), *tr = calloc((size_t)nf, sizeof(double));
    double *ns = calloc((size_t)nf, sizeof(double));
    mca_pdnn_params_t prm;
    params_of(o, &prm);
    mca_pdnn_init(&solver);
    static mca_qp_t qp;
    double phi[MCA_QP_MAX_VARS], phi_d[MCA_QP_MAX_VARS], dphi = 0.0;
    int ok = 0, unconv = 0, polished = 0, over300 = 0, cold = 0;
    for (int k = 0; k < nf; k++) {
        char path[4096];
        int has_phi = 0;
        snprintf(path, sizeof(path), "%s/%s", o->dir, names[k]);
        if (read_qp(path, &qp, phi_d, &has_phi) != 0) {
            fprintf(stderr, "cannot read %s\n", path);
            return 2;
        }
        mca_pdnn_result_t res;
        const double t0 = now_ns();
        const int rc = mca_pdnn_solve(&solver, &qp, &prm, phi, &res);
        ns[ok] = now_ns() - t0;
        st[ok] = res.steps;
        tr[ok++] = res.polish_tries;
        unconv += rc != MCA_OK;
        if (o->verbose && (rc != MCA_OK || res.steps > 300)) {
            printf("  %s: %s: %d steps, residual %.3g, %d polish tries, warm %d\n",
                   rc != MCA_OK ? "not converged" : "over 300 steps", names[k], res.steps, res.residual,
                   res.polish_tries, res.warm);
        }
        polished += res.polished > 0;
        over300 += res.steps > 300;
        cold += res.warm == 0;
        for (int j = 0; has_phi && rc == MCA_OK && j < qp.n; j++) {
            dphi = fmax(dphi, fabs(phi[j] - phi_d[j]));
        }
        free(names[k]);
    }
    free(names);
    printf("replay %s: %d QPs in order, one warm solver (%d cold), tol %g, cap %d, polish %s\n", o->dir, ok,
           cold, o->tol, o->max_steps, o->no_polish ? "off" : "on");
    printf("  steps p50 %.0f p99 %.0f p99.9 %.0f max %.0f | > 300: %d | not converged: %d | polished: %d\n",
           pct(st, ok, 50), pct(st, ok, 99), pct(st, ok, 99.9), pct(st, ok, 100), over300, unconv, polished);
    printf("  polish tries (exact solves) p50 %.0f p99 %.0f max %.0f | us p50 %.1f p99 %.1f max %.1f | "
           "max |phi - dumped phi| (converged) %.2g\n",
           pct(tr, ok, 50), pct(tr, ok, 99), pct(tr, ok, 100), pct(ns, ok, 50) / 1e3, pct(ns, ok, 99) / 1e3,
           pct(ns, ok, 100) / 1e3, dphi);
    free(st);
    free(tr);
    free(ns);
    return 0;
}

/* daqp: PDNN against DAQP (dlopened; bench/daqp/daqp_shim.c) on consecutive ticks, both warm */
typedef int (*daqp_solve_fn)(int, int, int, const double *, const double *, const double *, const double *,
                             const double *, const double *, int, int, double *, int *, int *);

typedef struct daqp_pass {
    int nt, tot, capped, dcold, unconv, dfail;
    double p[3], d[3], it[3], dphi; /* p50 p99 max (ns), iterations p50 p99 max */
} daqp_pass_t;

/* One pass over every task of o->dir (per-task lines printed on the first pass only); 0 or 2. */
static int daqp_pass(const opts_t *o, daqp_solve_fn dsolve, int pass, daqp_pass_t *ps) {
    char **tasks = NULL;
    int nt = list_dir(o->dir, 1, 1, &tasks);
    const int flat = nt <= 0;
    if (flat) {
        nt = 1;
    }
    FILE *csv = NULL;
    if (pass == 0 && o->csv && (csv = fopen(o->csv, "w")) == NULL) {
        fprintf(stderr, "cannot write %s: %s\n", o->csv, strerror(errno));
        return 2;
    }
    int cap = 1 << 16, tot = 0, unconv = 0, dfail = 0, capped = 0, dcold = 0;
    double *tp = malloc(sizeof(double) * (size_t)cap), *td = malloc(sizeof(double) * (size_t)cap);
    double *it = malloc(sizeof(double) * (size_t)cap), dphi = 0.0;
    mca_pdnn_params_t prm;
    params_of(o, &prm);
    static mca_qp_t qp;
    for (int t = 0; t < nt; t++) {
        char tdir[4096];
        snprintf(tdir, sizeof(tdir), "%s%s%s", o->dir, flat ? "" : "/", flat ? "" : tasks[t]);
        char **names = NULL;
        const int nf = list_dir(tdir, 1, 0, &names);
        if (nf <= 0) {
            fprintf(stderr, "no QP files in %s\n", tdir);
            return 2;
        }
        mca_pdnn_init(&solver); /* a task starts cold */
        int t_unconv = 0, t_capped = 0;
        double t_dphi = 0.0;
        const int first = tot;
        for (int k = 0; k < nf; k++) {
            char path[8192];
            double phi_d[MCA_QP_MAX_VARS], phi[MCA_QP_MAX_VARS], x[MCA_QP_MAX_VARS];
            int has_phi = 0, iter = 0, cold = 0;
            snprintf(path, sizeof(path), "%s/%s", tdir, names[k]);
            if (read_qp(path, &qp, phi_d, &has_phi) != 0) {
                fprintf(stderr, "cannot read %s\n", path);
                return 2;
            }
            if (tot == cap) {
                cap *= 2;
                tp = realloc(tp, sizeof(double) * (size_t)cap);
                td = realloc(td, sizeof(double) * (size_t)cap);
                it = realloc(it, sizeof(double) * (size_t)cap);
            }
            mca_pdnn_result_t res;
            double t0 = now_ns();
            const int rc = mca_pdnn_solve(&solver, &qp, &prm, phi, &res);
            tp[tot] = now_ns() - t0;
            t0 = now_ns();
            const int flag = dsolve(qp.n, qp.n_eq, qp.n_ineq, &qp.G[0][0], qp.alpha, &qp.U[0][0], qp.beta,
                                    qp.lb, qp.ub, MCA_QP_MAX_VARS, k > 0, x, &iter, &cold);
            td[tot] = now_ns() - t0;
            it[tot++] = iter;
            dcold += cold;
            t_unconv += rc != MCA_OK;
            dfail += flag <= 0;
            t_capped += has_suffix(names[k], ".capped");
            for (int j = 0; rc == MCA_OK && flag > 0 && j < qp.n; j++) {
                t_dphi = fmax(t_dphi, fabs(phi[j] - x[j]));
            }
            if (csv) {
                fprintf(csv, "%s,%.0f,%.0f,%d,%d,%d", path, tp[tot - 1], td[tot - 1], rc == MCA_OK, flag,
                        iter);
                for (int j = 0; j < qp.n; j++) {
                    fprintf(csv, ",%.17g", phi[j]);
                }
                for (int j = 0; j < qp.n; j++) {
                    fprintf(csv, ",%.17g", x[j]);
                }
                fputc('\n', csv);
            }
            free(names[k]);
        }
        free(names);
        const int n = tot - first;
        double *a = malloc(sizeof(double) * (size_t)n), *b = malloc(sizeof(double) * (size_t)n);
        memcpy(a, tp + first, sizeof(double) * (size_t)n);
        memcpy(b, td + first, sizeof(double) * (size_t)n);
        if (pass == 0)
            printf(
                "  %s: %d QPs (%d dumped capped), PDNN us p99 %.1f max %.1f (%d not converged) | DAQP us p99 "
                "%.1f max %.1f | max |dphi| %.2g\n",
                flat ? o->dir : tasks[t], n, t_capped, pct(a, n, 99) / 1e3, pct(a, n, 100) / 1e3, t_unconv,
                pct(b, n, 99) / 1e3, pct(b, n, 100) / 1e3, t_dphi);
        free(a);
        free(b);
        unconv += t_unconv;
        capped += t_capped;
        dphi = fmax(dphi, t_dphi);
        if (!flat) {
            free(tasks[t]);
        }
    }
    free(tasks);
    if (csv) {
        fclose(csv);
    }
    *ps = (daqp_pass_t){.nt = nt,
                        .tot = tot,
                        .capped = capped,
                        .dcold = dcold,
                        .unconv = unconv,
                        .dfail = dfail,
                        .dphi = dphi};
    for (int q = 0; q < 3; q++) {
        const double pc = q == 0 ? 50 : q == 1 ? 99 : 100;
        ps->p[q] = pct(tp, tot, pc);
        ps->d[q] = pct(td, tot, pc);
        ps->it[q] = pct(it, tot, pc);
    }
    printf("  pass %d: PDNN p99 %.2f us, DAQP p99 %.2f us, ratio %.2f\n", pass + 1, ps->p[1] / 1e3,
           ps->d[1] / 1e3, ps->p[1] / ps->d[1]);
    free(tp);
    free(td);
    free(it);
    return 0;
}

static int cmp_ratio(const void *a, const void *b) {
    const daqp_pass_t *x = a, *y = b;
    return cmp_d(&(double){x->p[1] / x->d[1]}, &(double){y->p[1] / y->d[1]});
}

/* --runs passes (3 unless given) over the same QPs; the figures of the pass with the median ratio (the host's
   load moves between passes) */
static int run_daqp(const opts_t *o, int passes) {
    const char *lib = o->lib ? o->lib : "libmca_daqp.so";
    void *h = dlopen(lib, RTLD_NOW | RTLD_LOCAL);
    daqp_solve_fn dsolve = h ? (daqp_solve_fn)dlsym(h, "mca_daqp_solve") : NULL;
    if (dsolve == NULL) {
        printf("daqp %s: skipped: daqp not available (%s)\n", o->dir, h ? "no mca_daqp_solve" : dlerror());
        return 0;
    }
    daqp_pass_t *ps = calloc((size_t)passes, sizeof(daqp_pass_t));
    for (int k = 0; k < passes; k++) {
        if (daqp_pass(o, dsolve, k, &ps[k]) != 0) {
            return 2;
        }
    }
    qsort(ps, (size_t)passes, sizeof(daqp_pass_t), cmp_ratio);
    const daqp_pass_t *m = &ps[(passes - 1) / 2];
    printf(
        "daqp %s: %d tasks, %d QPs (%d dumped capped), each solver warm from the previous tick; PDNN tol %g "
        "cap %d polish %s; DAQP default settings, working set carried (%d cold setups); %d passes, the "
        "median one's figures (ratio range %.2f - %.2f)\n",
        o->dir, m->nt, m->tot, m->capped, o->tol, o->max_steps, o->no_polish ? "off" : "on", m->dcold, passes,
        ps[0].p[1] / ps[0].d[1], ps[passes - 1].p[1] / ps[passes - 1].d[1]);
    printf("  PDNN us p50 %.2f p99 %.2f max %.1f | not converged %d\n", m->p[0] / 1e3, m->p[1] / 1e3,
           m->p[2] / 1e3, m->unconv);
    printf("  DAQP us p50 %.2f p99 %.2f max %.1f | failed %d | iterations p50 %.0f p99 %.0f max %.0f\n",
           m->d[0] / 1e3, m->d[1] / 1e3, m->d[2] / 1e3, m->dfail, m->it[0], m->it[1], m->it[2]);
    printf("  ratio PDNN p99 / DAQP p99 %.2f | max |phi_pdnn - phi_daqp| (both solved) %.2g\n",
           m->p[1] / m->d[1], m->dphi);
    free(ps);
    dlclose(h);
    return 0;
}

/* time and dump: runs of ticks */
static int run_ticks(const opts_t *o) {
    const int total = o->runs * o->ticks;
    double *ns_c = calloc((size_t)total, sizeof(double)), *ns_w = calloc((size_t)total, sizeof(double));
    double *st_c = calloc((size_t)total, sizeof(double)), *st_w = calloc((size_t)total, sizeof(double));
    double *nsps = calloc((size_t)total, sizeof(double));
    if (!ns_c || !ns_w || !st_c || !st_w || !nsps) {
        fprintf(stderr, "out of memory\n");
        return 2;
    }
    FILE *csv = NULL;
    if (o->dir != NULL) {
        char path[4096];
        if (mkdir(o->dir, 0777) != 0 && errno != EEXIST) {
            fprintf(stderr, "cannot create %s: %s\n", o->dir, strerror(errno));
            return 2;
        }
        snprintf(path, sizeof(path), "%s/pdnn_times.csv", o->dir);
        csv = fopen(path, "w");
        if (csv == NULL) {
            fprintf(stderr, "cannot write %s\n", path);
            return 2;
        }
        fprintf(csv, "file,ns,steps,warm,residual\n");
    }
    mca_pdnn_params_t prm;
    params_of(o, &prm);
    qpgen_rng_t rng = {o->seed};
    qpgen_scene_t sc;
    mca_qp_t qp;
    double phi[MCA_QP_MAX_VARS];
    int nc = 0, nw = 0, nsp = 0, fails = 0;

    for (int k = 0; k < total; k++) {
        if (k % o->ticks == 0) {
            qpgen_scene_random(&sc, &rng, o->tight);
            mca_pdnn_init(&solver);
        } else {
            qpgen_scene_perturb(&sc, &rng, o->eps);
        }
        if (o->normal) {
            qpgen_build_normal(&sc, &qp);
        } else {
            qpgen_build(&sc, &qp);
        }
        mca_pdnn_result_t res;
        const double t0 = now_ns();
        const int rc = mca_pdnn_solve(&solver, &qp, &prm, phi, &res);
        const double dt = now_ns() - t0;
        fails += rc != MCA_OK;
        if (res.warm) {
            ns_w[nw] = dt;
            st_w[nw++] = res.steps;
        } else {
            ns_c[nc] = dt;
            st_c[nc++] = res.steps;
        }
        if (res.steps_total >= 2000) { /* per-solve set-up negligible */
            nsps[nsp++] = dt / res.steps_total;
        }
        if (csv != NULL) {
            char path[4096], name[64];
            snprintf(name, sizeof(name), "qp_%06d.json", k);
            snprintf(path, sizeof(path), "%s/%s", o->dir, name);
            if (mca_qp_dump_json(&qp, phi, res.steps, res.residual, res.warm ? "warm" : "cold", path) !=
                MCA_OK) {
                fprintf(stderr, "cannot write %s\n", path);
                return 2;
            }
            fprintf(csv, "%s,%.0f,%d,%d,%.3g\n", name, dt, res.steps, res.warm, res.residual);
        }
    }
    if (csv != NULL) {
        fclose(csv);
    }
    printf("pdnn bench: %d solves (%d runs x %d ticks, eps %g), %s form (n_ineq %d), tol %g, precond %d, "
           "rule %d, "
           "far %g, cap %d: %d not converged\n",
           total, o->runs, o->ticks, o->eps, o->normal ? "normal" : "componentwise",
           o->normal ? QPGEN_NINEQ_NORMAL : QPGEN_NINEQ, o->tol, o->precond, o->rule, o->far, o->max_steps,
           fails);
    printf("  cold (%4d): us  p50 %8.1f p99 %8.1f max %8.1f | steps p50 %6.0f p99 %6.0f max %6.0f\n", nc,
           pct(ns_c, nc, 50) / 1e3, pct(ns_c, nc, 99) / 1e3, pct(ns_c, nc, 100) / 1e3, pct(st_c, nc, 50),
           pct(st_c, nc, 99), pct(st_c, nc, 100));
    if (nw > 0) {
        printf("  warm (%4d): us  p50 %8.1f p99 %8.1f max %8.1f | steps p50 %6.0f p99 %6.0f max %6.0f\n", nw,
               pct(ns_w, nw, 50) / 1e3, pct(ns_w, nw, 99) / 1e3, pct(ns_w, nw, 100) / 1e3, pct(st_w, nw, 50),
               pct(st_w, nw, 99), pct(st_w, nw, 100));
    }
    printf("  ns per Euler step of one block (solves >= 2000 block steps, %d): p50 %.0f\n", nsp,
           pct(nsps, nsp, 50));
    free(ns_c);
    free(ns_w);
    free(st_c);
    free(st_w);
    free(nsps);
    return 0;
}

/* edge: fixed kappa = f * kappa_bound(gamma = 2, i.e. the bound 2/||I+M||^2 itself) */
static int run_edge(const opts_t *o) {
    static const double f[] = {0.25, 0.5, 0.75, 1.0, 1.2, 1.4, 1.5, 1.6, 1.65, 1.7, 1.8, 1.9, 2.0, 2.5, 3.0};
    const int nf = (int)(sizeof(f) / sizeof(f[0]));
    const int nqp = o->runs;
    printf(
        "pdnn edge: %d cold QPs, precond %d, tol %g, cap %d; kappa = f * 2/||I+M||^2 (upper-bounded norm)\n",
        nqp, o->precond, o->tol, o->max_steps);
    printf("  %5s %9s %9s %9s %9s %12s %12s\n", "f", "converged", "stays", "capped", "diverged", "steps p50",
           "steps max");
    double *st = calloc((size_t)nqp, sizeof(double));
    if (st == NULL) {
        return 2;
    }
    for (int a = 0; a < nf; a++) {
        qpgen_rng_t rng = {o->seed}, rng_tick = {o->seed + 1000};
        int conv = 0, cap = 0, div = 0, stays = 0;
        for (int k = 0; k < nqp; k++) {
            qpgen_scene_t sc;
            mca_qp_t qp;
            double phi[MCA_QP_MAX_VARS];
            qpgen_scene_random(&sc, &rng, o->tight);
            qpgen_build(&sc, &qp);
            mca_pdnn_params_t prm;
            params_of(o, &prm);
            mca_pdnn_result_t res;
            /* the bound for this QP: kappa_bound at gamma -> 2 */
            prm.step_rule = MCA_PDNN_STEP_BOUND;
            prm.gamma = 1.0;
            prm.no_rescue = 1; /* the network itself: last iterate, no cold restart */
            prm.max_steps = 0;
            mca_pdnn_init(&solver);
            mca_pdnn_solve(&solver, &qp, &prm, phi, &res);
            prm.kappa = f[a] * 2.0 * res.kappa_bound;
            prm.max_steps = o->max_steps;
            mca_pdnn_init(&solver);
            const int rc = mca_pdnn_solve(&solver, &qp, &prm, phi, &res);
            if (rc == MCA_OK) {
                st[conv++] = res.steps;
                /* Passing through the tolerance once is not stability: continue as a controller would, 5
                 * ticks of a slightly moved QP (--eps) warm-started from here, at the same kappa, no far-row
                 * rescaling (the same network). Stable iff all 5 converge. */
                prm.far_weight = 1.0;
                int ok = 1;
                for (int t = 0; t < 5; t++) {
                    qpgen_scene_perturb(&sc, &rng_tick, o->eps);
                    qpgen_build(&sc, &qp);
                    ok &= mca_pdnn_solve(&solver, &qp, &prm, phi, &res) == MCA_OK;
                }
                stays += ok;
            } else if (!isfinite(res.residual) || res.residual > 1e3) {
                div++;
            } else {
                cap++;
            }
        }
        printf("  %5.2f %9d %9d %9d %9d %12.0f %12.0f\n", f[a], conv, stays, cap, div, pct(st, conv, 50),
               pct(st, conv, 100));
    }
    free(st);
    return 0;
}

int main(int argc, char **argv) {
    opts_t o = {.runs = 100,
                .ticks = 10,
                .max_steps = 20000,
                .eps = 1e-3,
                .tol = 1e-9,
                .far = 0.3,
                .tight = 0.15,
                .gamma = 1.9,
                .precond = MCA_PDNN_PRECOND_ORTH,
                .rule = MCA_PDNN_STEP_ADAPTIVE,
                .seed = 1,
                .dir = NULL};
    if (argc < 2) {
        usage(argv[0]);
        return 2;
    }
    int first = 2;
    if (!strcmp(argv[1], "dump") || !strcmp(argv[1], "replay") || !strcmp(argv[1], "daqp")) {
        if (argc < 3) {
            usage(argv[0]);
            return 2;
        }
        o.dir = argv[2];
        first = 3;
    } else if (strcmp(argv[1], "time") && strcmp(argv[1], "edge")) {
        usage(argv[0]);
        return 2;
    }
    if (parse(argc, argv, first, &o) != 0) {
        usage(argv[0]);
        return 2;
    }
    int max_steps_given = 0;
    for (int i = first; i < argc; i++) {
        max_steps_given |= !strcmp(argv[i], "--max-steps");
    }
    if (!strcmp(argv[1], "replay") || !strcmp(argv[1], "daqp")) {
        if (!max_steps_given) {
            o.max_steps = 2000; /* the controller's cap */
        }
        int runs_given = 0;
        for (int i = first; i < argc; i++) {
            runs_given |= !strcmp(argv[i], "--runs");
        }
        return !strcmp(argv[1], "daqp") ? run_daqp(&o, runs_given ? o.runs : 3) : run_replay(&o);
    }
    return !strcmp(argv[1], "edge") ? run_edge(&o) : run_ticks(&o);
}
