/* SPDX-License-Identifier: MIT */
/* The Euler integration of the LVI-PDNN (paper (32)) on Eigen maps and fixed-maximum vectors.
 * M = [I -N^T; N 0] with N = [G; -U] is never formed: each step applies N and N^T twice
 * (4 m*n multiply-adds) instead of an h*h product. Nothing here allocates: matrices are maps over the
 * caller's workspace, vectors have compile-time maximum sizes (storage on the stack), products are
 * evaluated with noalias() into them. */
/* Unoptimised Eigen is ~20x slower (every coefficient access a call): keep this file optimised in Debug
 * (and so ASan) builds too, or every test that runs the solver crawls there. Sanitizers still apply. */
#if !defined(__OPTIMIZE__) && defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("O2")
#endif
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <ctime>

#include "pdnn__eigen.h"

namespace {

constexpr int kMaxN = MCA_QP_MAX_VARS;
constexpr int kMaxM = MCA_QP_MAX_EQ + MCA_QP_MAX_INEQ;

using VecX = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxN, 1>;
using VecW = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxM, 1>;
using MatH = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxN, kMaxN>;
// The polish's C_A^T: free variables x guessed active rows. More active rows than variables are dependent
// anyway; a guess with more is not tried (kMaxN columns keep it on the stack: 18 KB).
using MatK = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxN, kMaxN>;
using VecK = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxN, 1>;
using MapN = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;
using MapV = Eigen::Map<const Eigen::VectorXd>;

// Polish constants (docs/pdnn.md, "Active-set polish"). Pivots below kRankTol of the largest count as zero
// (unit rows: rows within ~1e-9 rad of the span of the others are dependent).
constexpr double kRankTol = 1e-9;
constexpr int kPolishEvery = 24;    // steps after a failed try before the next one, doubled each time
constexpr double kPolishDrop = 0.1; // ... or when the residual has fallen by this factor
constexpr int kPolishNewton = 4;    // active-set corrections per try (each one exact solve)

// Guess the active set at (x, w) from the projection itself (a = N^T w, b = N x + q): a variable whose a_j
// the box clips, a row whose w_i - b_i > 0 (the projection is the identity there: multiplier or violation),
// every equality row. Solve min 1/2 |x|^2 with those rows as equalities and those variables at their bound:
// C x_F = d, x_F = C^T w_A (C = N[A, F], unit rows), through a column-pivoted QR of C^T: C^T P = Q R with
// rank r from the pivots, u = R11^-T (P^T d)_r, x_F = Q [u; 0], (P^T w_A)_r = R11^-1 u and 0 for the
// dependent rows (one multiplier per set of parallel rows). The dependent rows' own equations and every
// sign are not assumed: the caller checks the candidate with the network's residual. Returns 0 when no
// candidate could be formed (too many rows). No allocation: every Eigen object has fixed maximum sizes.
template <typename AV, typename BV, typename WV>
static int polish_candidate(const MapN &N, const MapV &q, const MapV &lox, const MapV &hix, const MapV &low,
                            const AV &a, const BV &b, const WV &w, VecX &xc, VecW &wc, unsigned char *set) {
    const int n = (int)N.cols(), m = (int)N.rows();
    int fr[kMaxN], ar[kMaxN], nf = 0, k = 0;
    for (int j = 0; j < n; j++) {
        set[j] = (unsigned char)(a(j) <= lox(j) ? 1 : a(j) >= hix(j) ? 2 : 0); // 0: free
        xc(j) = set[j] == 1 ? lox(j) : hix(j);
        if (set[j] == 0) {
            fr[nf++] = j;
        }
    }
    for (int i = 0; i < m; i++) {
        wc(i) = 0.0;
        set[n + i] = (unsigned char)(low(i) < 0.0 || w(i) - b(i) > 0.0);
        if (set[n + i]) {
            if (k == kMaxN) {
                return 0;
            }
            ar[k++] = i;
        }
    }
    MatK ct(nf, k);
    VecK d(k), sc(k);
    for (int c = 0; c < k; c++) {
        const int i = ar[c];
        double di = -q(i), nrm = 0.0; // d_i = -(q_i + N_iX x_X)
        for (int j = 0; j < n; j++) {
            if (set[j] != 0) {
                di -= N(i, j) * xc(j);
            }
        }
        for (int t = 0; t < nf; t++) {
            ct(t, c) = N(i, fr[t]);
            nrm += ct(t, c) * ct(t, c);
        }
        // a row on fixed variables only: its test d_i = 0 is left to the check
        sc(c) = nrm > 0.0 ? 1.0 / std::sqrt(nrm) : 0.0;
        ct.col(c) *= sc(c);
        d(c) = di * sc(c);
    }
    VecX xf = VecX::Zero(nf);
    if (nf > 0 && k > 0) {
        // Column-pivoted Householder QR of C^T in place, by hand: Eigen's ColPivHouseholderQR, triangular
        // solves and Householder products go through GEMV kernels that keep a heap fallback for large sizes
        // (never taken at these sizes, but it links malloc into the RT library: core.rt_symbols). Here only
        // dot products and axpys on the fixed-size storage.
        int perm[kMaxN];
        double tau[kMaxN];
        int r = 0;
        const int p = std::min(nf, k);
        for (int c = 0; c < k; c++) {
            perm[c] = c;
        }
        for (int h = 0; h < p; h++) {
            int best = h;
            double bn = -1.0;
            for (int c = h; c < k; c++) { // exact remaining norms (no downdating: sizes are small)
                const double cn = ct.col(c).tail(nf - h).squaredNorm();
                if (cn > bn) {
                    bn = cn;
                    best = c;
                }
            }
            if (!(std::sqrt(bn) > kRankTol * (h > 0 ? std::fabs(ct(0, 0)) : 1.0))) {
                break; // the rest lies in the span of the first h columns (unit columns: |R_00| = 1)
            }
            ct.col(h).swap(ct.col(best));
            std::swap(perm[h], perm[best]);
            // H_h = I - tau v v^T, v = [1; ess], maps the column's tail to [beta; 0]
            const double x0 = ct(h, h), nrm = std::sqrt(bn), beta = x0 >= 0.0 ? -nrm : nrm;
            tau[h] = (beta - x0) / beta;
            ct.col(h).tail(nf - h - 1) /= x0 - beta;
            ct(h, h) = beta;
            for (int c = h + 1; c < k; c++) {
                const double t =
                    tau[h] * (ct(h, c) + ct.col(h).tail(nf - h - 1).dot(ct.col(c).tail(nf - h - 1)));
                ct(h, c) -= t;
                ct.col(c).tail(nf - h - 1) -= t * ct.col(h).tail(nf - h - 1);
            }
            r = h + 1;
        }
        VecK u(r);
        for (int i = 0; i < r; i++) { // R11^T u = (P^T d)_r
            u(i) = (d(perm[i]) - ct.col(i).head(i).dot(u.head(i))) / ct(i, i);
        }
        xf.head(r) = u;
        for (int h = r - 1; h >= 0; h--) { // x_F = Q [u; 0] = H_0 ... H_{r-1} [u; 0]
            const int len = nf - h - 1;
            const double t = tau[h] * (xf(h) + ct.col(h).tail(len).dot(xf.tail(len)));
            xf(h) -= t;
            xf.tail(len) -= t * ct.col(h).tail(len);
        }
        for (int i = r - 1; i >= 0; i--) { // R11 z = u: the first r multipliers in pivot order
            u(i) = (u(i) - ct.row(i).segment(i + 1, r - i - 1).dot(u.segment(i + 1, r - i - 1))) / ct(i, i);
        }
        for (int c = 0; c < k; c++) {
            wc(ar[perm[c]]) = c < r ? u(c) * sc(perm[c]) : 0.0;
        }
    }
    for (int t = 0; t < nf; t++) {
        xc(fr[t]) = xf(t);
    }
    return 1;
}

} // namespace

extern "C" double mca_pdnn__norm_sq_bound(const mca_pdnn__problem_t *p) {
    const MapN N(p->N, p->m, p->n);
    MatH H(p->n, p->n);
    // lazyProduct: coefficient-wise evaluation, no GEMM blocking buffers (which would be heap-allocated).
    H.noalias() = N.transpose().lazyProduct(N);
    return H.cwiseAbs().rowwise().sum().maxCoeff();
}

extern "C" void mca_pdnn__iterate(const mca_pdnn__problem_t *p, double *y, double kappa_fixed, double gamma,
                                  double tol, int max_steps, int keep_best, int polish_max,
                                  mca_pdnn_result_t *res) {
    const int n = p->n, m = p->m;
    const MapN N(p->N, m, n);
    const MapV q(p->q, m), lox(p->lo, n), hix(p->hi, n), low(p->lo + n, m), hiw(p->hi + n, m);
    Eigen::Map<Eigen::VectorXd> x(y, n), w(y + n, m);

    VecX a(n), ex(n), u(n), dx(n), best_x(n);
    VecW b(m), ew(m), v(m), dw(m), best_w(m), vt(m), et(m);
    const MapV f(p->f != nullptr ? p->f : p->q, m), finv(p->finv != nullptr ? p->finv : p->q, m);
    int steps = 0;
    double kappa = kappa_fixed, r = 0.0, best_r = INFINITY;

    // The residual below, at a polish candidate (its own vectors: ex, ew are still needed for the step).
    VecX xc(n), ac(n), exc(n);
    VecW wc(m), bc(m), ewc(m);
    const auto residual_at = [&]() {
        ac.noalias() = N.transpose().lazyProduct(wc);
        bc.noalias() = N.lazyProduct(xc);
        bc += q;
        exc = ac.cwiseMax(lox).cwiseMin(hix) - xc;
        if (p->f == nullptr) {
            ewc = (wc - bc).cwiseMax(low).cwiseMin(hiw) - wc;
        } else {
            ewc =
                (f.cwiseProduct(wc) - bc.cwiseProduct(finv)).cwiseMax(low).cwiseMin(hiw) - f.cwiseProduct(wc);
        }
        return std::max(exc.lpNorm<Eigen::Infinity>(), ewc.lpNorm<Eigen::Infinity>());
    };
    VecX ag(n);
    VecW bg(m), wg(m);
    unsigned char set[2][kMaxN + kMaxM];
    int tries = 0, next_k = 0, every = kPolishEvery;
    double next_r = INFINITY;
    res->polished = 0;
    for (;;) {
        // e(y) = P_Omega(y - (M y + q)) - y, with y - (M y + q) = [N^T w; w - (N x + q)].
        // The blocks are small (an arm: ~10 columns, a few rows): lazyProduct's plain dot products cost
        // 13-15 % fewer instructions than the blocked GEMV kernel's set-up (callgrind, task 1).
        a.noalias() = N.transpose().lazyProduct(w);
        b.noalias() = N.lazyProduct(x);
        b += q;
        ex = a.cwiseMax(lox).cwiseMin(hix) - x;
        ew = (w - b).cwiseMax(low).cwiseMin(hiw) - w;

        // Stop test in the units of the QP as given: with scaled rows (docs/pdnn.md) the iterated residual
        // can be orders of magnitude off (a row of norm 1e-4 scaled to 1 has its multiplier divided by 1e4).
        r = ex.lpNorm<Eigen::Infinity>();
        if (p->f == nullptr) {
            r = std::max(r, ew.lpNorm<Eigen::Infinity>());
        } else {
            vt = f.cwiseProduct(w);
            et = (vt - b.cwiseProduct(finv)).cwiseMax(low).cwiseMin(hiw) - vt;
            r = std::max(r, et.lpNorm<Eigen::Infinity>());
        }
        if (!std::isfinite(r)) {
            break; // diverged (kappa above the stability edge): report, do not spin on NaN
        }
        if (r <= tol || steps >= max_steps) {
            break;
        }
        // Active-set polish: at the first step (a warm start's active set is usually still right), then
        // every `every` steps (doubling) or once the residual fell by kPolishDrop. Accepted only if the
        // candidate meets this loop's own test; else the iteration goes on from (x, w), untouched.
        if (tries < polish_max && (steps >= next_k || r <= next_r)) {
            // Guess from the iterate, then from each candidate in turn: the guess rule applied to a candidate
            // drops rows with a negative multiplier and adds violated ones (a primal-dual active-set, i.e.
            // semismooth Newton, step on e(y) = 0); stops when the set repeats.
            ag = a;
            bg = b;
            wg = w;
            for (int nt = 0; nt < kPolishNewton && tries < polish_max; nt++) {
                tries++;
                if (!polish_candidate(N, q, lox, hix, low, ag, bg, wg, xc, wc, set[nt & 1]) ||
                    (nt > 0 && std::equal(set[0], set[0] + n + m, set[1]))) {
                    break;
                }
                const double rc = residual_at();
                if (rc <= tol && xc.allFinite() && wc.allFinite()) { // a NaN could slip through the max norms
                    x = xc;
                    w = wc;
                    r = rc;
                    res->polished = 1;
                    break;
                }
                ag = ac;
                bg = bc;
                wg = wc;
            }
            if (res->polished) {
                break;
            }
            next_k = steps + every;
            every *= 2;
            next_r = r * kPolishDrop;
        }
        if (p->deadline_ns != 0 && steps > 0 && (steps & 15) == 0) {
            struct timespec ts;
            clock_gettime(CLOCK_MONOTONIC, &ts);
            if ((int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec >= p->deadline_ns) {
                res->timed_out = 1;
                break;
            }
        }
        // The projection-contraction argument makes the distance to the solution fall, not the residual:
        // keep the best point seen, to hand back if the cap comes first.
        if (keep_best && r < best_r) {
            best_r = r;
            best_x = x;
            best_w = w;
        }
        // Direction (I + M^T) e = [2 e_x + N^T e_w; e_w - N e_x].
        u.noalias() = N.transpose().lazyProduct(ew);
        v.noalias() = N.lazyProduct(ex);
        dx = 2.0 * ex + u;
        dw = ew - v;
        if (kappa_fixed <= 0.0) {
            // He's projection-contraction step: ||y+ - y*||^2 <= ||y - y*||^2 - gamma (2 - gamma) rho
            // ||e||^2.
            const double dd = dx.squaredNorm() + dw.squaredNorm();
            kappa = gamma * (ex.squaredNorm() + ew.squaredNorm()) / dd;
        }
        x += kappa * dx;
        w += kappa * dw;
        steps++;
    }
    if (std::isfinite(r) && r > tol && best_r < r) {
        x = best_x;
        w = best_w;
        r = best_r;
    }
    res->steps = steps;
    res->polish_tries = tries;
    res->residual = r;
    res->converged = r <= tol;
    res->kappa = kappa;
}
