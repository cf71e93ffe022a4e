/* SPDX-License-Identifier: MIT */
/* The JSON dump of a QP for the independent OSQP check (tools/qp-check); see mca/qp_dump.h. */
#include "mca/qp_dump.h"

#include <math.h>
#include <stdio.h>

#include "mca/err.h"

/* A JSON number; infinities (and NaN, which JSON cannot hold either) become null. */
static void put_num(FILE *f, double x) {
    if (isfinite(x)) {
        fprintf(f, "%.17g", x);
    } else {
        fputs("null", f);
    }
}

static void put_vec(FILE *f, const double *v, int len) {
    fputc('[', f);
    for (int i = 0; i < len; i++) {
        if (i > 0) {
            fputc(',', f);
        }
        put_num(f, v[i]);
    }
    fputc(']', f);
}

static void put_str(FILE *f, const char *s) {
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p != '\0'; p++) {
        if (*p == '"' || *p == '\\') {
            fputc('\\', f);
            fputc(*p, f);
        } else if (*p < 0x20) {
            fprintf(f, "\\u%04x", *p);
        } else {
            fputc(*p, f);
        }
    }
    fputc('"', f);
}

int mca_qp_dump_json(const mca_qp_t *qp, const double *phi, int steps, double residual, const char *tag,
                     const char *path) {
    if (qp == NULL || path == NULL || qp->n < 0 || qp->n > MCA_QP_MAX_VARS || qp->n_eq < 0 ||
        qp->n_eq > MCA_QP_MAX_EQ || qp->n_ineq < 0 || qp->n_ineq > MCA_QP_MAX_INEQ) {
        return MCA_EINVAL;
    }
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        return MCA_EIO;
    }
    fprintf(f, "{\"n\":%d,\"n_eq\":%d,\"n_ineq\":%d,\n\"G\":[", qp->n, qp->n_eq, qp->n_ineq);
    for (int i = 0; i < qp->n_eq; i++) {
        fputs(i > 0 ? ",\n" : "", f);
        put_vec(f, qp->G[i], qp->n);
    }
    fputs("],\n\"alpha\":", f);
    put_vec(f, qp->alpha, qp->n_eq);
    fputs(",\n\"U\":[", f);
    for (int i = 0; i < qp->n_ineq; i++) {
        fputs(i > 0 ? ",\n" : "", f);
        put_vec(f, qp->U[i], qp->n);
    }
    fputs("],\n\"beta\":", f);
    put_vec(f, qp->beta, qp->n_ineq);
    fputs(",\n\"lb\":", f);
    put_vec(f, qp->lb, qp->n);
    fputs(",\n\"ub\":", f);
    put_vec(f, qp->ub, qp->n);
    if (phi != NULL) {
        fputs(",\n\"phi\":", f);
        put_vec(f, phi, qp->n);
        fprintf(f, ",\n\"steps\":%d,\"residual\":", steps);
        put_num(f, residual);
    }
    if (tag != NULL) {
        fputs(",\n\"tag\":", f);
        put_str(f, tag);
    }
    fputs("}\n", f);
    int bad = ferror(f);
    if (fclose(f) != 0 || bad) {
        return MCA_EIO;
    }
    return MCA_OK;
}
