/* SPDX-License-Identifier: MIT */
/* The Euler integration of the LVI-PDNN (paper (32)) on Eigen maps and fixed-maximum vectors.
 * M = [I -N^T; N 0] with N = [G; -U] is never formed: each step applies N and N^T twice
 * (4 m*n multiply-adds) instead of an h*h product. Nothing here allocates: matrices are maps over the
 * caller's workspace, vectors have compile-time maximum sizes (storage on the stack), products are
 * evaluated with noalias() into them. The active-set polish (polish_try) solves small KKT systems with a
 * pivoted QR written out by hand on the same kind of storage (docs/pdnn.md, "Active-set polish"). */
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
// mca_pdnn__problem_t.side: 0 unknown, 1 at the lower bound, 2 at the upper, kSideFree known to be free
constexpr unsigned char kSideFree = 4;
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

// Solve min 1/2 |x|^2 with the rows in `set` (set[n + i] = 1) as equalities and the variables with
// set[j] = 1 / 2 at their lower / upper bound: C x_F = d, x_F = C^T w_A (C = N[A, F], unit rows), through a
// column-pivoted QR of C^T: C^T P = Q R with rank r from the pivots, u = R11^-T (P^T d)_r, x_F = Q [u; 0],
// (P^T w_A)_r = R11^-1 u and 0 for the dependent rows (one multiplier per set of parallel rows, equality
// rows pivoted first; the dependent rows' own equations are left to the caller). Returns 2 (full rank), 1
// (rank deficient: the rows' free parts are dependent) or 0 (more rows than kMaxN). With g: also the
// least-squares fit of g's free part by the rows' free parts, g_F ~ C^T mu (mu per row, 0 off the set), and
// the misfit |g_F - C^T mu| in *gres. No allocation: every Eigen object has fixed maximum sizes.
static int kkt_solve(const MapN &N, const MapV &q, const MapV &lox, const MapV &hix, const MapV &low,
                     const unsigned char *set, VecX &xc, VecW &wc, const VecX *g = nullptr,
                     VecW *mu = nullptr, double *gres = nullptr) {
    const int n = (int)N.cols(), m = (int)N.rows();
    int fr[kMaxN], ar[kMaxN], nf = 0, k = 0;
    for (int j = 0; j < n; j++) {
        xc(j) = set[j] == 1 ? lox(j) : hix(j);
        if (set[j] == 0) {
            fr[nf++] = j;
        }
    }
    for (int i = 0; i < m; i++) {
        wc(i) = 0.0;
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
    int rank = 0;
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
        const double lim = kRankTol * kRankTol;
        for (int h = 0; h < p; h++) {
            int best = h;
            double bn = -1.0;
            // equality rows first: a dependent row is left out, and an inequality row can leave the set
            for (int pass = 0; pass < 2 && !(bn > lim); pass++) {
                for (int c = h; c < k; c++) { // exact remaining norms (no downdating: sizes are small)
                    const double cn = ct.col(c).tail(nf - h).squaredNorm();
                    if ((pass == 1 || low(ar[perm[c]]) < 0.0) && cn > bn) {
                        bn = cn;
                        best = c;
                    }
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
        rank = r;
        if (g != nullptr) {
            VecX gq(nf);
            for (int t = 0; t < nf; t++) {
                gq(t) = (*g)(fr[t]);
            }
            for (int h = 0; h < r; h++) { // Q^T g_F = H_{r-1} ... H_0 g_F
                const int len = nf - h - 1;
                const double t = tau[h] * (gq(h) + ct.col(h).tail(len).dot(gq.tail(len)));
                gq(h) -= t;
                gq.tail(len) -= t * ct.col(h).tail(len);
            }
            *gres = gq.tail(nf - r).norm();
            for (int i = r - 1; i >= 0; i--) { // R11 mu' = (Q^T g_F)_r
                gq(i) = (gq(i) - ct.row(i).segment(i + 1, r - i - 1).dot(gq.segment(i + 1, r - i - 1))) /
                        ct(i, i);
            }
            mu->setZero();
            for (int c = 0; c < r; c++) {
                (*mu)(ar[perm[c]]) = gq(c) * sc(perm[c]);
            }
        }
    } else if (g != nullptr) {
        mu->setZero();
        *gres = 0.0;
        for (int t = 0; t < nf; t++) {
            *gres += (*g)(fr[t]) * (*g)(fr[t]);
        }
        *gres = std::sqrt(*gres);
    }
    for (int t = 0; t < nf; t++) {
        xc(fr[t]) = xf(t);
    }
    return rank == k ? 2 : 1;
}

// 1 once CLOCK_MONOTONIC has reached deadline_ns (0: no deadline).
static int past(int64_t deadline_ns) {
    if (deadline_ns == 0) {
        return 0;
    }
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec >= deadline_ns;
}

// One polish try from the network's iterate (a = N^T w, b = N x + q). Seed: the box side (or none) each
// variable had in the last polished answer (`side`, where known), else the active set the projection sees (a
// variable whose a_j the box clips), a row with w_i - b_i > 0, every equality row; cold: the equality rows
// alone. The box moves every tick (the acceleration box around the present velocity): a joint held at its
// bound by a small multiplier leaves the projection's guess although it stays at the bound, and each such
// miss costs an exact solve to put it back. Then a dual
// active-set method (Goldfarb-Idnani; with the objective 1/2 |x|^2 each subproblem is kkt_solve): first
// drop seed members with a negative multiplier, most negative first, until the set is dual feasible; then
// add the most violated constraint p and move along the segment to the solution with p in the set (the KKT
// solution is affine in p's right-hand side), dropping a member whose multiplier reaches 0 on the way; done
// when nothing is violated by more than eps. Each subproblem solve costs one unit of *budget. Returns 1 with
// the candidate in (xc, wc), 0 if the budget ran out or p depends on the set (degenerate, or infeasible).
// The caller still checks the candidate with the network's residual.
template <typename AV, typename BV, typename WV>
static int polish_try(const MapN &N, const MapV &q, const MapV &lox, const MapV &hix, const MapV &low,
                      const AV &a, const BV &b, const WV &w, const unsigned char *side, int cold, double eps,
                      int64_t deadline_ns, int *budget, VecX &xc, VecW &wc, unsigned char *side_out) {
    const int n = (int)N.cols(), m = (int)N.rows();
    unsigned char set[kMaxN + kMaxM];
    for (int j = 0; j < n; j++) {
        if (!cold && side && side[j] != 0) {
            set[j] = side[j] == kSideFree ? 0 : side[j];
        } else {
            set[j] = (unsigned char)(cold ? 0 : a(j) <= lox(j) ? 1 : a(j) >= hix(j) ? 2 : 0);
        }
    }
    for (int i = 0; i < m; i++) {
        set[n + i] = (unsigned char)(low(i) < 0.0 || (!cold && w(i) - b(i) > 0.0));
    }
    VecX x1(n), at(n), a1(n);
    VecW w1(m);
    const auto solve = [&](VecX &xo, VecW &wo) {
        if (*budget <= 0 || past(deadline_ns)) {
            return 0; // out of solves, or of time: the try fails and the network's answer stands
        }
        (*budget)--;
        return kkt_solve(N, q, lox, hix, low, set, xo, wo);
    };
    // Multiplier of member k (k < n: a bound, lam = lo - a_k or a_k - hi; else a row, w) given a = N^T w; the
    // members that may leave: bounds of a variable with lo < hi, inequality rows. Others: +inf.
    const auto mult = [&](int k, const VecX &ak, const VecW &wk) {
        if (k < n) {
            return set[k] == 0 || lox(k) == hix(k) ? INFINITY : set[k] == 1 ? lox(k) - ak(k) : ak(k) - hix(k);
        }
        return set[k] == 0 || low(k - n) < 0.0 ? INFINITY : wk(k - n);
    };
    if (!solve(xc, wc)) {
        return 0;
    }
    for (;;) { // dual feasibility of the seed
        at.noalias() = N.transpose().lazyProduct(wc);
        int worst = -1;
        double lw = 0.0;
        for (int k = 0; k < n + m; k++) {
            const double l = mult(k, at, wc);
            if (l < lw) {
                lw = l;
                worst = k;
            }
        }
        if (worst < 0) {
            break;
        }
        set[worst] = 0;
        if (!solve(xc, wc)) {
            return 0;
        }
    }
    // Rows the rank-deficient solve left out (multiplier 0, equation not met) leave the set: with a zero
    // multiplier the point stays a KKT point of the rest, and the loop below brings them back in properly.
    VecW bt(m);
    bt.noalias() = N.lazyProduct(xc);
    bt += q;
    for (int i = 0; i < m; i++) {
        if (set[n + i] && low(i) >= 0.0 && wc(i) == 0.0 && std::fabs(bt(i)) > eps) {
            set[n + i] = 0;
        }
    }
    for (;;) {
        // the most violated constraint outside the set
        int p = -1;
        double worst = eps;
        bt.noalias() = N.lazyProduct(xc);
        bt += q;
        for (int j = 0; j < n; j++) {
            const double v = std::max(lox(j) - xc(j), xc(j) - hix(j));
            if (set[j] == 0 && v > worst) {
                worst = v;
                p = j;
            }
        }
        for (int i = 0; i < m; i++) {
            if (set[n + i] == 0 && -bt(i) > worst) {
                worst = -bt(i);
                p = n + i;
            }
        }
        if (p < 0) {
            for (int j = 0; j < n; j++) {
                side_out[j] = set[j] != 0 ? set[j] : kSideFree;
            }
            return 1;
        }
        set[p] = p < n ? (unsigned char)(xc(p) < lox(p) ? 1 : 2) : 1;
        for (;;) {
            const int rc = solve(x1, w1);
            if (rc == 0) {
                return 0;
            }
            if (rc == 1 && *budget > 0) {
                // Rank deficient: if p's normal g (in the >= form) is a combination sum mu_k g_k of the
                // members', no step in x reaches p: a pure dual step. p's multiplier grows by s and the
                // members' fall by s mu_k until the first one reaches 0; it leaves (then p is independent).
                VecX g = VecX::Zero(n);
                VecW mu(m);
                double gres = 0.0;
                if (p < n) {
                    g(p) = set[p] == 1 ? 1.0 : -1.0;
                } else {
                    g = N.row(p - n).transpose();
                }
                const unsigned char sp = set[p];
                set[p] = 0;
                (*budget)--;
                kkt_solve(N, q, lox, hix, low, set, x1, w1, &g, &mu, &gres);
                set[p] = sp;
                if (gres <= kRankTol * g.norm()) {
                    at.noalias() = N.transpose().lazyProduct(wc);
                    a1.noalias() = N.transpose().lazyProduct(mu); // rows' part of the combination
                    double st = INFINITY;
                    int blk = -1;
                    for (int k = 0; k < n + m; k++) {
                        if (k == p || set[k] == 0) {
                            continue;
                        }
                        // bounds: the rest of g on the fixed variable, signed for its side
                        const double mk = k < n ? (set[k] == 1 ? 1.0 : -1.0) * (g(k) - a1(k)) : mu(k - n);
                        const double l = std::max(mult(k, at, wc), 0.0);
                        if (mk > kRankTol && l < INFINITY && l / mk < st) {
                            st = l / mk;
                            blk = k;
                        }
                    }
                    if (blk < 0) {
                        return 0; // nothing can give way: p cannot be met with the set (infeasible)
                    }
                    wc -= st * mu;
                    if (p >= n) {
                        wc(p - n) += st;
                    }
                    set[blk] = 0;
                    if (blk >= n) {
                        wc(blk - n) = 0.0;
                    }
                    continue;
                }
                if (!solve(x1, w1)) { // p is independent: the deficiency is among the others
                    return 0;
                }
            }
            at.noalias() = N.transpose().lazyProduct(wc);
            a1.noalias() = N.transpose().lazyProduct(w1);
            double t = 1.0;
            int blk = -1;
            for (int k = 0; k < n + m; k++) {
                const double l0 = k == p ? INFINITY : std::max(mult(k, at, wc), 0.0), l1 = mult(k, a1, w1);
                if (k != p && l1 < 0.0 && l0 < INFINITY) {
                    const double tk = l0 / (l0 - l1);
                    if (tk < t) {
                        t = tk;
                        blk = k;
                    }
                }
            }
            xc += t * (x1 - xc);
            wc += t * (w1 - wc);
            if (blk < 0) {
                break;
            }
            set[blk] = 0; // its multiplier reached 0: it leaves, p is still on its way in
            if (blk >= n) {
                wc(blk - n) = 0.0;
            }
        }
    }
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
    int tries = 0, next_k = 0, every = kPolishEvery;
    unsigned char sides[kMaxN];
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
        // every `every` steps (doubling) or once the residual fell by kPolishDrop; polish_max subproblem
        // solves in all (a try may use what is left). Accepted only if the candidate meets this loop's own
        // test; else the iteration goes on from (x, w), untouched.
        if (tries < polish_max && (steps >= next_k || r <= next_r)) {
            // the first time, a failed try from the iterate's set is followed by one from the equalities
            // alone (the textbook cold start of the dual method: finite for any feasible QP, budget
            // permitting)
            for (int cold = 0; cold < (steps == 0 ? 2 : 1) && !res->polished && tries < polish_max; cold++) {
                int budget = polish_max - tries; // a try may use what is left: it is one active-set run
                const int left = budget;
                const int got = polish_try(N, q, lox, hix, low, a, b, w, p->side, cold, 0.1 * tol,
                                           p->deadline_ns, &budget, xc, wc, sides);
                tries += left - budget;
                if (got) {
                    const double rc = residual_at();
                    if (rc <= tol && xc.allFinite() &&
                        wc.allFinite()) { // a NaN could slip through the max norms
                        x = xc;
                        w = wc;
                        r = rc;
                        res->polished = 1;
                        for (int j = 0; p->side && j < n; j++) {
                            p->side[j] = sides[j];
                        }
                    }
                }
            }
            if (res->polished) {
                break;
            }
            next_k = steps + every;
            every *= 2;
            next_r = r * kPolishDrop;
        }
        if (steps > 0 && (steps & 15) == 0 && past(p->deadline_ns)) {
            res->timed_out = 1;
            break;
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
