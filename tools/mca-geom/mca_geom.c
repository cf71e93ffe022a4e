/* SPDX-License-Identifier: MIT */
/* mca-geom: command-line access to the geometry of mca_core and mca_body (segment distances, forward
 * kinematics, capsule-body distances). */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mca/armdist.h"
#include "mca/body.h"
#include "mca/chain.h"
#include "mca/err.h"
#include "mca/segdist.h"
#include "mca/urdf.h"

#define EXIT_BAD_INPUT 2

static void usage(FILE *f) {
    fputs("usage: mca-geom <command> [options]\n"
          "\n"
          "commands:\n"
          "  segdist [--method closed|lsdm|lsdm-cert] [--tol T] [--max-iter N]\n"
          "      Minimum distance between segments AB and CD. Reads stdin, one pair per line:\n"
          "        ax ay az bx by bz cx cy cz dx dy dz\n"
          "      and prints per line: d px py pz ex ey ez iterations   (%.17g; P on AB, E on CD).\n"
          "      Blank lines and lines whose first non-blank character is '#' are skipped.\n"
          "      closed (default): exact closed form, iterations = 0.\n"
          "      lsdm: the paper's LSDM, stops when the distance declines by less than T\n"
          "            (default 1e-12; the paper uses 1e-5), at most N projections (default 200).\n"
          "      lsdm-cert: LSDM that stops when a separating-plane certificate proves d within T.\n"
          "      A line with the wrong count of numbers, a non-number, NaN or inf is an error:\n"
          "      message with its line number on stderr, exit code 2 (lines before it are answered).\n"
          "      An LSDM that hits the cap is still printed, with a warning on stderr.\n"
          "\n"
          "  fk --robot FILE.urdf [--tip LINK] q1 ... qn\n"
          "      Forward kinematics at joint angles q [rad] (n = the chain's DOF). Prints\n"
          "        root x y z / joint i NAME x y z (each joint origin) / ee x y z   (world frame, m).\n"
          "      Bad URDF, unknown tip link, wrong number of q or non-numeric q: exit code 2.\n"
          "      LINK defaults to the URDF's single leaf link (tool_tip in config/robots/).\n"
          "\n"
          "  armdist --robot-a A.urdf [--base-a x,y,z,roll,pitch,yaw] --qa q1,...,qn\n"
          "          --robot-b B.urdf [--base-b x,y,z,roll,pitch,yaw] --qb q1,...,qm [--method closed|lsdm]\n"
          "      Arm-to-arm link distances (capsules: axis distance minus both radii). Prints\n"
          "        min LINK_A LINK_B d d_axis px py pz ex ey ez   (global minimum, P on A, E on B)\n"
          "        a_to_b I J ... (per link of A)  /  b_to_a J I ... (per link of B)  /  iterations N\n"
          "      Bad URDF, bad base or wrong number of q: exit code 2.\n"
          "\n"
          "  armgrid --robot-a A.urdf [--base-a ...] --robot-b B.urdf [--base-b ...] --out FILE\n"
          "          [--every N] [--cap C]\n"
          "      A coordination diagram's distances: stdin holds two recorded trajectories, one tick a line\n"
          "      (arm A's joint angles, then arm B's). Every N-th tick (default 10) is a sample; FILE gets\n"
          "      (native endian) int32 n, float64 travel_a[n], travel_b[n], float32 d[n][n]: d[i][j] the\n"
          "      arm-to-arm distance with A at sample i and B at sample j (at least C, default 0.5 m, is a\n"
          "      lower bound: the bounding spheres' gap), travel_x[i] an upper bound of how far any point\n"
          "      of arm X moves from sample i to i+1.\n"
          "\n"
          "  body\n"
          "      Link capsule against a fixed body (mca/body.h). Reads stdin, one pair per line:\n"
          "        KIND ax ay az bx by bz r  BODY...   (capsule A-B, radius r; then by KIND:)\n"
          "        plane    px py pz nx ny nz                (half-space n.(x - p) <= 0)\n"
          "        sphere   cx cy cz R\n"
          "        capsule  cx cy cz dx dy dz R\n"
          "        box      cx cy cz hx hy hz R00 R01 R02 R10 R11 R12 R20 R21 R22   (R row by row)\n"
          "        cylinder cx cy cz wx wy wz h R            (axis w, half length h, radius R)\n"
          "      and prints per line: d px py pz qx qy qz nx ny nz sx sy sz exact iterations   (%.17g; P on "
          "the\n"
          "      capsule's surface, Q on the body, N from the body to the capsule, S on the capsule's axis;\n"
          "      exact 0: the axis enters a cylinder and d is a lower bound; iterations: the cylinder's).\n"
          "      Bad kind, count or number, or a body the library refuses: exit code 2 (lines before it are\n"
          "      answered). Blank lines and '#' lines are skipped.\n"
          "\n"
          "  --help   this text\n",
          f);
}

/* Parse a whole token as a finite double. */
static int parse_finite(const char *tok, double *out) {
    char *end;
    errno = 0;
    *out = strtod(tok, &end);
    if (end == tok || *end != '\0' || !isfinite(*out)) {
        return -1;
    }
    return 0;
}

static int cmd_segdist(int argc, char **argv) {
    enum { M_CLOSED, M_LSDM, M_CERT } method = M_CLOSED;
    mca_lsdm_params_t params = {MCA_LSDM_DEFAULT_TOL, MCA_LSDM_DEFAULT_MAX_ITER};
    char *line = NULL;
    size_t cap = 0;
    long lineno = 0;
    int status = 0;

    for (int i = 0; i < argc; i++) {
        if (strcmp(argv[i], "--method") == 0 && i + 1 < argc) {
            const char *m = argv[++i];
            if (strcmp(m, "closed") == 0) {
                method = M_CLOSED;
            } else if (strcmp(m, "lsdm") == 0) {
                method = M_LSDM;
            } else if (strcmp(m, "lsdm-cert") == 0) {
                method = M_CERT;
            } else {
                fprintf(stderr, "mca-geom segdist: unknown --method '%s' (closed, lsdm or lsdm-cert)\n", m);
                return EXIT_BAD_INPUT;
            }
        } else if (strcmp(argv[i], "--tol") == 0 && i + 1 < argc) {
            if (parse_finite(argv[++i], &params.tol) != 0 || params.tol < 0.0) {
                fprintf(stderr, "mca-geom segdist: --tol '%s' is not a finite number >= 0\n", argv[i]);
                return EXIT_BAD_INPUT;
            }
        } else if (strcmp(argv[i], "--max-iter") == 0 && i + 1 < argc) {
            char *end;
            long v = strtol(argv[++i], &end, 10);
            if (*argv[i] == '\0' || *end != '\0' || v < 2 || v > 100000000L) {
                fprintf(stderr, "mca-geom segdist: --max-iter '%s' is not an integer in [2, 1e8]\n", argv[i]);
                return EXIT_BAD_INPUT;
            }
            params.max_iter = (int)v;
        } else {
            fprintf(stderr, "mca-geom segdist: unknown or incomplete option '%s' (see --help)\n", argv[i]);
            return EXIT_BAD_INPUT;
        }
    }

    while (getline(&line, &cap, stdin) != -1) {
        double v[12];
        int n = 0, rc;
        char *p = line, *tok, *save = NULL;
        mca_segdist_t r;

        lineno++;
        while (*p == ' ' || *p == '\t') {
            p++;
        }
        if (*p == '#' || *p == '\n' || *p == '\r' || *p == '\0') {
            continue;
        }
        for (tok = strtok_r(p, " \t\r\n,", &save); tok != NULL; tok = strtok_r(NULL, " \t\r\n,", &save)) {
            double x;
            if (n == 12) {
                n++; /* too many: counted below */
                break;
            }
            if (parse_finite(tok, &x) != 0) {
                fflush(stdout);
                fprintf(stderr, "mca-geom segdist: stdin line %ld: field %d '%s' is not a finite number\n",
                        lineno, n + 1, tok);
                status = EXIT_BAD_INPUT;
                goto out;
            }
            v[n++] = x;
        }
        if (n != 12) {
            fflush(stdout);
            fprintf(stderr,
                    "mca-geom segdist: stdin line %ld: expected 12 numbers (A B C D, x y z each), got %s%d\n",
                    lineno, n > 12 ? "more than " : "", n > 12 ? 12 : n);
            status = EXIT_BAD_INPUT;
            goto out;
        }
        if (method == M_CLOSED) {
            rc = mca_segdist_closed(&v[0], &v[3], &v[6], &v[9], &r);
        } else if (method == M_LSDM) {
            rc = mca_segdist_lsdm(&v[0], &v[3], &v[6], &v[9], &params, &r);
        } else {
            rc = mca_segdist_lsdm_certified(&v[0], &v[3], &v[6], &v[9], &params, &r);
        }
        if (rc != MCA_OK && rc != MCA_ENOTCONV) {
            fflush(stdout);
            fprintf(stderr, "mca-geom segdist: stdin line %ld: %s (coordinates must be within +-%g m)\n",
                    lineno, mca_strerror(rc), MCA_SEGDIST_MAX_COORD);
            status = EXIT_BAD_INPUT;
            goto out;
        }
        printf("%.17g %.17g %.17g %.17g %.17g %.17g %.17g %d\n", r.d, r.p[0], r.p[1], r.p[2], r.e[0], r.e[1],
               r.e[2], r.iterations);
        if (rc == MCA_ENOTCONV) {
            fflush(stdout);
            fprintf(stderr, "mca-geom segdist: stdin line %ld: warning: LSDM hit the cap of %d projections\n",
                    lineno, params.max_iter);
        }
    }
out:
    free(line);
    fflush(stdout);
    return status;
}

static int cmd_fk(int argc, char **argv) {
    const char *robot = NULL, *tip = NULL;
    double q[MCA_MAX_DOF];
    int nq = 0, rc;
    char err[512] = "";
    mca_chain_t chain;
    mca_kin_t kin;
    int i;

    for (i = 0; i < argc; i++) {
        if (strcmp(argv[i], "--robot") == 0 && i + 1 < argc) {
            robot = argv[++i];
        } else if (strcmp(argv[i], "--tip") == 0 && i + 1 < argc) {
            tip = argv[++i];
        } else if (strcmp(argv[i], "--") == 0) {
            i++;
            break;
        } else if (argv[i][0] == '-' && argv[i][1] == '-') {
            fprintf(stderr, "mca-geom fk: unknown or incomplete option '%s' (see --help)\n", argv[i]);
            return EXIT_BAD_INPUT;
        } else {
            break;
        }
    }
    if (robot == NULL) {
        fprintf(stderr, "mca-geom fk: --robot FILE.urdf is required\n");
        return EXIT_BAD_INPUT;
    }
    rc = mca_chain_load_urdf(&chain, robot, tip, err, sizeof err);
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-geom fk: %s: %s\n", mca_strerror(rc), err[0] ? err : robot);
        return EXIT_BAD_INPUT;
    }
    for (; i < argc; i++) {
        if (nq >= MCA_MAX_DOF || nq >= chain.dof) {
            nq++;
            continue; /* counted for the message */
        }
        if (parse_finite(argv[i], &q[nq]) != 0) {
            fprintf(stderr, "mca-geom fk: q%d '%s' is not a finite number\n", nq + 1, argv[i]);
            return EXIT_BAD_INPUT;
        }
        nq++;
    }
    if (nq != chain.dof) {
        fprintf(stderr, "mca-geom fk: %s has %d joints but %d joint angle(s) were given\n", robot, chain.dof,
                nq);
        return EXIT_BAD_INPUT;
    }
    rc = mca_fk(&chain, q, &kin);
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-geom fk: forward kinematics failed: %s\n", mca_strerror(rc));
        return EXIT_BAD_INPUT;
    }
    printf("root %.17g %.17g %.17g\n", kin.point[0][0], kin.point[0][1], kin.point[0][2]);
    for (i = 0; i < chain.dof; i++) {
        printf("joint %d %s %.17g %.17g %.17g\n", i + 1, chain.joint[i].name, kin.point[i + 1][0],
               kin.point[i + 1][1], kin.point[i + 1][2]);
    }
    printf("ee %.17g %.17g %.17g\n", kin.ee[0], kin.ee[1], kin.ee[2]);
    return 0;
}

/* Comma-separated finite numbers into v[0..max-1]; returns the count or -1 (bad field, too many). */
static int parse_list(const char *text, double *v, int max) {
    char buf[1024], *tok, *save = NULL;
    int n = 0;
    if (strlen(text) >= sizeof buf) {
        return -1;
    }
    strcpy(buf, text);
    for (tok = strtok_r(buf, ", \t", &save); tok != NULL; tok = strtok_r(NULL, ", \t", &save)) {
        if (n >= max || parse_finite(tok, &v[n]) != 0) {
            return -1;
        }
        n++;
    }
    return n;
}

typedef struct arm_arg {
    const char *robot, *base, *q;
} arm_arg_t;

/* The chain of --robot-X placed at --base-X. */
static int load_chain(const char *cmd, const char *label, const arm_arg_t *arg, mca_chain_t *chain) {
    char err[512] = "";
    double base[6] = {0, 0, 0, 0, 0, 0};
    int rc;
    if (arg->robot == NULL) {
        fprintf(stderr, "mca-geom %s: --robot-%s is required\n", cmd, label);
        return EXIT_BAD_INPUT;
    }
    rc = mca_chain_load_urdf(chain, arg->robot, NULL, err, sizeof err);
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-geom %s: arm %s: %s: %s\n", cmd, label, mca_strerror(rc),
                err[0] ? err : arg->robot);
        return EXIT_BAD_INPUT;
    }
    if (arg->base != NULL && parse_list(arg->base, base, 6) != 6) {
        fprintf(stderr, "mca-geom %s: --base-%s '%s': expected 6 numbers x,y,z,roll,pitch,yaw\n", cmd, label,
                arg->base);
        return EXIT_BAD_INPUT;
    }
    mca_chain_set_base(chain, &base[0], &base[3]);
    return 0;
}

static int load_arm(const char *label, const arm_arg_t *arg, mca_chain_t *chain, mca_kin_t *kin) {
    double q[MCA_MAX_DOF];
    int rc, n;
    if (arg->q == NULL) {
        fprintf(stderr, "mca-geom armdist: --q%s is required\n", label);
        return EXIT_BAD_INPUT;
    }
    if ((rc = load_chain("armdist", label, arg, chain)) != 0) {
        return rc;
    }
    n = parse_list(arg->q, q, MCA_MAX_DOF);
    if (n != chain->dof) {
        fprintf(stderr, "mca-geom armdist: --q%s '%s': %s has %d joints (numbers, comma-separated)\n", label,
                arg->q, arg->robot, chain->dof);
        return EXIT_BAD_INPUT;
    }
    if (mca_fk(chain, q, kin) != MCA_OK) {
        fprintf(stderr, "mca-geom armdist: arm %s: forward kinematics failed\n", label);
        return EXIT_BAD_INPUT;
    }
    return 0;
}

static void print_pair(const char *tag, const mca_link_pair_t *lp) {
    printf("%s %d %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", tag, lp->link, lp->other_link, lp->d,
           lp->d_axis, lp->p[0], lp->p[1], lp->p[2], lp->e[0], lp->e[1], lp->e[2]);
}

static int cmd_armdist(int argc, char **argv) {
    arm_arg_t arm[2] = {{NULL, NULL, NULL}, {NULL, NULL, NULL}};
    mca_dist_method_t method = MCA_DIST_CLOSED;
    static mca_chain_t chain[2];
    static mca_kin_t kin[2];
    mca_arm_distances_t out;
    int rc;

    for (int i = 0; i < argc; i++) {
        const char *o = argv[i];
        if (i + 1 >= argc) {
            fprintf(stderr, "mca-geom armdist: option '%s' needs a value (see --help)\n", o);
            return EXIT_BAD_INPUT;
        }
        const char *v = argv[++i];
        if (strcmp(o, "--robot-a") == 0) {
            arm[0].robot = v;
        } else if (strcmp(o, "--robot-b") == 0) {
            arm[1].robot = v;
        } else if (strcmp(o, "--base-a") == 0) {
            arm[0].base = v;
        } else if (strcmp(o, "--base-b") == 0) {
            arm[1].base = v;
        } else if (strcmp(o, "--qa") == 0) {
            arm[0].q = v;
        } else if (strcmp(o, "--qb") == 0) {
            arm[1].q = v;
        } else if (strcmp(o, "--method") == 0 && (strcmp(v, "closed") == 0 || strcmp(v, "lsdm") == 0)) {
            method = strcmp(v, "closed") == 0 ? MCA_DIST_CLOSED : MCA_DIST_LSDM;
        } else {
            fprintf(stderr, "mca-geom armdist: unknown option or value '%s %s' (see --help)\n", o, v);
            return EXIT_BAD_INPUT;
        }
    }
    if ((rc = load_arm("a", &arm[0], &chain[0], &kin[0])) != 0 ||
        (rc = load_arm("b", &arm[1], &chain[1], &kin[1])) != 0) {
        return rc;
    }
    rc = mca_arm_distances(&chain[0], &kin[0], &chain[1], &kin[1], method, &out);
    if (rc != MCA_OK) {
        fprintf(stderr, "mca-geom armdist: %s\n", mca_strerror(rc));
        return EXIT_BAD_INPUT;
    }
    print_pair("min", &out.min);
    for (int i = 0; i < out.n_links_a; i++) {
        print_pair("a_to_b", &out.a_to_b[i]);
    }
    for (int j = 0; j < out.n_links_b; j++) {
        print_pair("b_to_a", &out.b_to_a[j]);
    }
    printf("iterations %d\n", out.iterations);
    return 0;
}

/* The two arms' sampled states read by cmd_armgrid: kinematics per sample, each sample's bounding sphere and
 * how far any point of the arm travels until the next sample. */
typedef struct grid_arm {
    mca_chain_t chain;
    mca_kin_t *kin; /* [n] */
    double *centre, *radius, *travel;
} grid_arm_t;

/* Largest displacement of any capsule axis point between two states: the motion from one tick to the next is
 * a rigid transform per link, whose displacement is affine along the link, so the axis ends bound it. */
static double max_point_move(const mca_kin_t *a, const mca_kin_t *b) {
    double m = 0.0;
    for (int k = 0; k < a->n_points; k++) {
        double dx = b->point[k][0] - a->point[k][0], dy = b->point[k][1] - a->point[k][1],
               dz = b->point[k][2] - a->point[k][2];
        m = fmax(m, sqrt(dx * dx + dy * dy + dz * dz));
    }
    return m;
}

static void bounding_sphere(const mca_chain_t *chain, const mca_kin_t *kin, double c[3], double *r) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, rmax = 0.0,
           m = 0.0;
    for (int k = 0; k < kin->n_points; k++) {
        for (int i = 0; i < 3; i++) {
            lo[i] = fmin(lo[i], kin->point[k][i]);
            hi[i] = fmax(hi[i], kin->point[k][i]);
        }
    }
    for (int i = 0; i < 3; i++) {
        c[i] = 0.5 * (lo[i] + hi[i]);
    }
    for (int k = 0; k < kin->n_points; k++) {
        double dx = kin->point[k][0] - c[0], dy = kin->point[k][1] - c[1], dz = kin->point[k][2] - c[2];
        m = fmax(m, sqrt(dx * dx + dy * dy + dz * dz));
    }
    for (int k = 0; k <= chain->dof; k++) {
        rmax = fmax(rmax, chain->link_radius[k]);
    }
    *r = m + rmax;
}

/* Arm-to-arm distance over every pair of sampled states of two recorded trajectories (a coordination diagram:
 * tools/mca-sweep/coord_diagram.py). */
static int cmd_armgrid(int argc, char **argv) {
    arm_arg_t arg[2] = {{NULL, NULL, NULL}, {NULL, NULL, NULL}};
    static grid_arm_t arm[2];
    const char *out_path = NULL;
    long every = 10, ticks = 0, n = 0, cap_ticks = 0;
    double cap = 0.5, *q = NULL;
    char *line = NULL;
    size_t lcap = 0;
    int rc = EXIT_BAD_INPUT;
    FILE *out = NULL;
    float *row = NULL;

    for (int i = 0; i < argc; i++) {
        const char *o = argv[i];
        if (i + 1 >= argc) {
            fprintf(stderr, "mca-geom armgrid: option '%s' needs a value (see --help)\n", o);
            return EXIT_BAD_INPUT;
        }
        const char *v = argv[++i];
        double x;
        if (strcmp(o, "--robot-a") == 0 || strcmp(o, "--robot-b") == 0) {
            arg[o[8] - 'a'].robot = v;
        } else if (strcmp(o, "--base-a") == 0 || strcmp(o, "--base-b") == 0) {
            arg[o[7] - 'a'].base = v;
        } else if (strcmp(o, "--every") == 0 && parse_finite(v, &x) == 0 && x >= 1 && x == floor(x)) {
            every = (long)x;
        } else if (strcmp(o, "--cap") == 0 && parse_finite(v, &x) == 0 && x > 0) {
            cap = x;
        } else if (strcmp(o, "--out") == 0) {
            out_path = v;
        } else {
            fprintf(stderr, "mca-geom armgrid: unknown option or value '%s %s' (see --help)\n", o, v);
            return EXIT_BAD_INPUT;
        }
    }
    if (out_path == NULL) {
        fprintf(stderr, "mca-geom armgrid: --out FILE is required\n");
        return EXIT_BAD_INPUT;
    }
    for (int a = 0; a < 2; a++) {
        if ((rc = load_chain("armgrid", a ? "b" : "a", &arg[a], &arm[a].chain)) != 0) {
            return rc;
        }
    }
    rc = EXIT_BAD_INPUT;
    const int dof[2] = {arm[0].chain.dof, arm[1].chain.dof};
    q = malloc(sizeof(double) * (size_t)(dof[0] + dof[1]));
    cap_ticks = 1024;
    for (int a = 0; a < 2; a++) {
        arm[a].kin = malloc(sizeof(mca_kin_t) * (size_t)cap_ticks);
        arm[a].travel = calloc((size_t)cap_ticks, sizeof(double));
        if (!q || !arm[a].kin || !arm[a].travel) {
            goto nomem;
        }
    }
    mca_kin_t prev[2], cur[2];
    while (getline(&line, &lcap, stdin) != -1) {
        char *p = line, *end;
        int k = 0;
        for (; k < dof[0] + dof[1]; k++) {
            q[k] = strtod(p, &end);
            if (end == p || !isfinite(q[k])) {
                break;
            }
            p = end;
        }
        while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') {
            p++;
        }
        if (k != dof[0] + dof[1] || *p != '\0') {
            fprintf(stderr,
                    "mca-geom armgrid: stdin:%ld: expected %d joint angles (arm a's %d, then arm b's %d)\n",
                    ticks + 1, dof[0] + dof[1], dof[0], dof[1]);
            goto done;
        }
        for (int a = 0; a < 2; a++) {
            if (mca_fk(&arm[a].chain, q + (a ? dof[0] : 0), &cur[a]) != MCA_OK) {
                fprintf(stderr, "mca-geom armgrid: stdin:%ld: forward kinematics failed\n", ticks + 1);
                goto done;
            }
            if (ticks > 0) {
                arm[a].travel[n - 1] += max_point_move(&prev[a], &cur[a]);
            }
            prev[a] = cur[a];
        }
        if (ticks % every == 0) {
            if (n == cap_ticks) {
                cap_ticks *= 2;
                for (int a = 0; a < 2; a++) {
                    mca_kin_t *kin = realloc(arm[a].kin, sizeof(mca_kin_t) * (size_t)cap_ticks);
                    if (kin) {
                        arm[a].kin = kin;
                    }
                    double *travel = realloc(arm[a].travel, sizeof(double) * (size_t)cap_ticks);
                    if (travel) {
                        arm[a].travel = travel;
                    }
                    if (!kin || !travel) {
                        goto nomem;
                    }
                    memset(arm[a].travel + n, 0, sizeof(double) * (size_t)(cap_ticks - n));
                }
            }
            for (int a = 0; a < 2; a++) {
                arm[a].kin[n] = cur[a];
            }
            n++;
        }
        ticks++;
    }
    if (n == 0) {
        fprintf(stderr, "mca-geom armgrid: stdin: no states\n");
        goto done;
    }
    for (int a = 0; a < 2; a++) {
        arm[a].travel[n - 1] = 0.0;
        arm[a].centre = malloc(sizeof(double) * 3 * (size_t)n);
        arm[a].radius = malloc(sizeof(double) * (size_t)n);
        if (!arm[a].centre || !arm[a].radius) {
            goto nomem;
        }
        for (long i = 0; i < n; i++) {
            bounding_sphere(&arm[a].chain, &arm[a].kin[i], &arm[a].centre[3 * i], &arm[a].radius[i]);
        }
    }
    if ((out = fopen(out_path, "wb")) == NULL) {
        fprintf(stderr, "mca-geom armgrid: %s: %s\n", out_path, strerror(errno));
        goto done;
    }
    int32_t n32 = (int32_t)n;
    fwrite(&n32, sizeof n32, 1, out);
    fwrite(arm[0].travel, sizeof(double), (size_t)n, out);
    fwrite(arm[1].travel, sizeof(double), (size_t)n, out);
    if ((row = malloc(sizeof(float) * (size_t)n)) == NULL) {
        goto nomem;
    }
    for (long i = 0; i < n; i++) {
        for (long j = 0; j < n; j++) {
            const double *ca = &arm[0].centre[3 * i], *cb = &arm[1].centre[3 * j];
            double lb = sqrt((ca[0] - cb[0]) * (ca[0] - cb[0]) + (ca[1] - cb[1]) * (ca[1] - cb[1]) +
                             (ca[2] - cb[2]) * (ca[2] - cb[2])) -
                        arm[0].radius[i] - arm[1].radius[j];
            /* at least cap: a lower bound, far enough not to matter */
            row[j] = (float)(lb >= cap ? lb
                                       : mca_arm_least_distance(
                                             &arm[0].chain, (const double(*)[3])arm[0].kin[i].point,
                                             &arm[1].chain, (const double(*)[3])arm[1].kin[j].point, cap));
        }
        fwrite(row, sizeof(float), (size_t)n, out);
    }
    if (fclose(out) != 0) {
        out = NULL;
        fprintf(stderr, "mca-geom armgrid: %s: %s\n", out_path, strerror(errno));
        goto done;
    }
    out = NULL;
    printf("armgrid %ld ticks, %ld samples every %ld ticks\n", ticks, n, every);
    rc = 0;
    goto done;
nomem:
    fprintf(stderr, "mca-geom armgrid: out of memory (%ld samples)\n", n);
    rc = 1;
done:
    if (out != NULL) {
        fclose(out);
    }
    for (int a = 0; a < 2; a++) {
        free(arm[a].kin);
        free(arm[a].travel);
        free(arm[a].centre);
        free(arm[a].radius);
    }
    free(row);
    free(q);
    free(line);
    return rc;
}

/* One capsule-body pair per stdin line (mca/body.h). */
static int cmd_body(int argc, char **argv) {
    static const struct {
        const char *name;
        mca_body_kind_t kind;
        int n;
    } kinds[] = {{"plane", MCA_BODY_PLANE, 6},
                 {"sphere", MCA_BODY_SPHERE, 4},
                 {"capsule", MCA_BODY_CAPSULE, 7},
                 {"box", MCA_BODY_BOX, 15},
                 {"cylinder", MCA_BODY_CYLINDER, 8}};
    char *line = NULL;
    size_t cap = 0;
    long lineno = 0;
    int status = 0;

    if (argc > 0) {
        fprintf(stderr, "mca-geom body: unknown option '%s' (see --help)\n", argv[0]);
        return EXIT_BAD_INPUT;
    }
    while (getline(&line, &cap, stdin) != -1) {
        double v[22];
        int n = 0, k = -1, want;
        char *p = line, *tok, *save = NULL;
        mca_capsule_t c;
        mca_body_t b;
        mca_body_dist_t r;

        lineno++;
        while (*p == ' ' || *p == '\t') {
            p++;
        }
        if (*p == '#' || *p == '\n' || *p == '\r' || *p == '\0') {
            continue;
        }
        tok = strtok_r(p, " \t\r\n,", &save);
        for (int i = 0; i < (int)(sizeof kinds / sizeof kinds[0]); i++) {
            if (strcmp(tok, kinds[i].name) == 0) {
                k = i;
            }
        }
        if (k < 0) {
            fflush(stdout);
            fprintf(
                stderr,
                "mca-geom body: stdin line %ld: unknown kind '%s' (plane, sphere, capsule, box, cylinder)\n",
                lineno, tok);
            status = EXIT_BAD_INPUT;
            goto out;
        }
        want = 7 + kinds[k].n;
        for (tok = strtok_r(NULL, " \t\r\n,", &save); tok != NULL; tok = strtok_r(NULL, " \t\r\n,", &save)) {
            double x;
            if (n == want) {
                n++;
                break;
            }
            if (parse_finite(tok, &x) != 0) {
                fflush(stdout);
                fprintf(stderr, "mca-geom body: stdin line %ld: field %d '%s' is not a finite number\n",
                        lineno, n + 2, tok);
                status = EXIT_BAD_INPUT;
                goto out;
            }
            v[n++] = x;
        }
        if (n != want) {
            fflush(stdout);
            fprintf(stderr, "mca-geom body: stdin line %ld: %s expects %d numbers after the kind, got %s%d\n",
                    lineno, kinds[k].name, want, n > want ? "more than " : "", n > want ? want : n);
            status = EXIT_BAD_INPUT;
            goto out;
        }
        memcpy(c.a, &v[0], sizeof c.a);
        memcpy(c.b, &v[3], sizeof c.b);
        c.radius = v[6];
        memset(&b, 0, sizeof b);
        b.kind = kinds[k].kind;
        switch (b.kind) {
        case MCA_BODY_PLANE:
            memcpy(b.u.plane.point, &v[7], sizeof b.u.plane.point);
            memcpy(b.u.plane.normal, &v[10], sizeof b.u.plane.normal);
            break;
        case MCA_BODY_SPHERE:
            memcpy(b.u.sphere.centre, &v[7], sizeof b.u.sphere.centre);
            b.u.sphere.radius = v[10];
            break;
        case MCA_BODY_CAPSULE:
            memcpy(b.u.capsule.a, &v[7], sizeof b.u.capsule.a);
            memcpy(b.u.capsule.b, &v[10], sizeof b.u.capsule.b);
            b.u.capsule.radius = v[13];
            break;
        case MCA_BODY_BOX:
            memcpy(b.u.box.centre, &v[7], sizeof b.u.box.centre);
            memcpy(b.u.box.half, &v[10], sizeof b.u.box.half);
            memcpy(b.u.box.R, &v[13], sizeof b.u.box.R);
            break;
        default:
            memcpy(b.u.cylinder.centre, &v[7], sizeof b.u.cylinder.centre);
            memcpy(b.u.cylinder.axis, &v[10], sizeof b.u.cylinder.axis);
            b.u.cylinder.half_len = v[13];
            b.u.cylinder.radius = v[14];
            break;
        }
        if (mca_capsule_body_distance(&c, &b, &r) != MCA_OK) {
            fflush(stdout);
            fprintf(stderr,
                    "mca-geom body: stdin line %ld: invalid input (negative size, zero normal or axis, "
                    "rotation not "
                    "orthonormal, or coordinates beyond +-%g m)\n",
                    lineno, MCA_SEGDIST_MAX_COORD);
            status = EXIT_BAD_INPUT;
            goto out;
        }
        printf("%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %d %d\n", r.d,
               r.p[0], r.p[1], r.p[2], r.q[0], r.q[1], r.q[2], r.n[0], r.n[1], r.n[2], r.p_axis[0],
               r.p_axis[1], r.p_axis[2], r.exact, r.iterations);
    }
out:
    free(line);
    fflush(stdout);
    return status;
}

int main(int argc, char **argv) {
    if (argc < 2) {
        usage(stderr);
        return EXIT_BAD_INPUT;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "help") == 0) {
        usage(stdout);
        return 0;
    }
    if (strcmp(argv[1], "segdist") == 0) {
        return cmd_segdist(argc - 2, argv + 2);
    }
    if (strcmp(argv[1], "fk") == 0) {
        return cmd_fk(argc - 2, argv + 2);
    }
    if (strcmp(argv[1], "armdist") == 0) {
        return cmd_armdist(argc - 2, argv + 2);
    }
    if (strcmp(argv[1], "armgrid") == 0) {
        return cmd_armgrid(argc - 2, argv + 2);
    }
    if (strcmp(argv[1], "body") == 0) {
        return cmd_body(argc - 2, argv + 2);
    }
    fprintf(stderr, "mca-geom: unknown command '%s' (see mca-geom --help)\n", argv[1]);
    return EXIT_BAD_INPUT;
}
