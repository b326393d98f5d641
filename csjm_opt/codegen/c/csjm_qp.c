/* csjm_qp.c: the bounded tension QP, exact and with a bound on the work fixed by the code.
 *
 *     minimise 1/2 |t - t_ref|^2   subject to   J^T t = b,   lo <= t <= hi     (m = CSJM_N_CABLES variables)
 *
 * The objective is strictly convex, so the solution is unique when the load is feasible; any
 * exact method gives the answer of csjm_opt's planner to round-off. Three stages:
 *
 * 1. Primal-dual active set, warm-started (csjm_qp_pdas): guess the active bounds, solve the
 *    3x3 equality-constrained KKT system by Cramer's rule, update the guess, stop when it is
 *    stable. At most max_iter iterations (the same method and tolerances as csjm_opt's
 *    compiled planner kernel). It usually settles in 1-3 iterations; it can cycle.
 * 2. If it does not settle: the support function of the zonotope {J^T t} over its m (m - 1)
 *    facet normals tells whether the load can be held. If it can, every active set with at
 *    least three free cables is checked for the KKT conditions (of the 3^m = CSJM_N_PATTERNS
 *    bound patterns; 233 sets for m = 6, csjm_qp_exhaustive).
 * 3. If it cannot: the distance min |J^T t - b| over the box is found exactly from the
 *    faces of dimension <= 2 (m (m - 1) / 2 pairs of free cables x 2^(m - 2) assignments of the
 *    others to their bounds, each a 2-variable box least squares solved in closed form).
 *
 * No loop runs longer than these fixed counts: the worst case is max_iter PDAS iterations +
 * m (m - 1) support evaluations + m (m - 1) / 2 * 2^(m - 2) two-variable problems + 3^m pattern
 * tests with at most one 3x3 KKT solve each (m = 6: 30, 240 and 233 solves; m = 12: 132,
 * 67584 and 531441 patterns).
 */
#include <math.h>

#include "csjm_qp.h"

static double det3(const double M[9])
{
    return M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6])
         + M[2] * (M[3] * M[7] - M[4] * M[6]);
}

/* Multipliers lam of the KKT system for the active set: M lam = rhs with M = J_F^T J_F.
 * Returns 0 when M is singular (fewer than three independent free rows). */
static int kkt_multipliers(const double J[3 * CSJM_N_CABLES], const double b[3], const double t_ref[CSJM_N_CABLES], double lo, double hi,
                           const unsigned char lower[CSJM_N_CABLES], const unsigned char upper[CSJM_N_CABLES], double lam[3])
{
    double M[9] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    double rhs[3], C[9], tr, det;
    int i, p, q;
    rhs[0] = b[0];
    rhs[1] = b[1];
    rhs[2] = b[2];
    for (i = 0; i < CSJM_N_CABLES; ++i) {
        const double *Ji = J + 3 * i;
        if (lower[i] || upper[i]) {
            double bound = lower[i] ? lo : hi;
            for (p = 0; p < 3; ++p) rhs[p] -= Ji[p] * bound;
        } else {
            for (p = 0; p < 3; ++p) {
                rhs[p] -= Ji[p] * t_ref[i];
                for (q = 0; q < 3; ++q) M[3 * p + q] += Ji[p] * Ji[q];
            }
        }
    }
    tr = (M[0] + M[4] + M[8]) / 3.0;
    det = det3(M);
    if (!(tr > 0.0) || !(fabs(det) >= 1e-12 * tr * tr * tr)) return 0;
    for (p = 0; p < 3; ++p) {     /* Cramer's rule: column p replaced by rhs */
        for (q = 0; q < 9; ++q) C[q] = M[q];
        for (q = 0; q < 3; ++q) C[3 * q + p] = rhs[q];
        lam[p] = det3(C) / det;
    }
    return 1;
}

int csjm_qp_pdas(const double J[3 * CSJM_N_CABLES], const double b[3], const double t_ref[CSJM_N_CABLES], double lo, double hi,
                 unsigned char lower[CSJM_N_CABLES], unsigned char upper[CSJM_N_CABLES], int max_iter, double t[CSJM_N_CABLES], int *iterations)
{
    double eps = 1e-10 * (fabs(hi) > 1.0 ? fabs(hi) : 1.0);
    double lam[3];
    int it, i;
    *iterations = 0;
    for (it = 0; it < max_iter; ++it) {
        int stable = 1;
        *iterations = it + 1;
        if (!kkt_multipliers(J, b, t_ref, lo, hi, lower, upper, lam)) return CSJM_QP_NOT_SETTLED;
        for (i = 0; i < CSJM_N_CABLES; ++i) {
            const double *Ji = J + 3 * i;
            double jl = Ji[0] * lam[0] + Ji[1] * lam[1] + Ji[2] * lam[2];
            if (lower[i]) {
                t[i] = lo;
                if (t[i] - t_ref[i] - jl < -eps) { lower[i] = 0; stable = 0; }  /* multiplier < 0: release */
            } else if (upper[i]) {
                t[i] = hi;
                if (t[i] - t_ref[i] - jl > eps) { upper[i] = 0; stable = 0; }
            } else {
                t[i] = t_ref[i] + jl;
                if (t[i] < lo - eps) { lower[i] = 1; stable = 0; }
                else if (t[i] > hi + eps) { upper[i] = 1; stable = 0; }
            }
        }
        if (stable) return CSJM_QP_OK;
    }
    return CSJM_QP_NOT_SETTLED;
}

int csjm_qp_exhaustive(const double J[3 * CSJM_N_CABLES], const double b[3], const double t_ref[CSJM_N_CABLES], double lo, double hi,
                       unsigned char lower[CSJM_N_CABLES], unsigned char upper[CSJM_N_CABLES], double t[CSJM_N_CABLES])
{
    double eps = 1e-10 * (fabs(hi) > 1.0 ? fabs(hi) : 1.0);
    unsigned char lo_set[CSJM_N_CABLES], up_set[CSJM_N_CABLES];
    double lam[3], cand[CSJM_N_CABLES];
    long code;
    int i;
    for (code = 0; code < CSJM_N_PATTERNS; ++code) {     /* 3^m patterns: digit 0 free, 1 lower, 2 upper */
        long c = code;
        int n_free = 0, ok = 1;
        for (i = 0; i < CSJM_N_CABLES; ++i) {
            int d = (int)(c % 3);
            c /= 3;
            lo_set[i] = (unsigned char)(d == 1);
            up_set[i] = (unsigned char)(d == 2);
            n_free += d == 0;
        }
        if (n_free < 3) continue;            /* 233 patterns pass this test for m = 6 */
        if (!kkt_multipliers(J, b, t_ref, lo, hi, lo_set, up_set, lam)) continue;
        for (i = 0; i < CSJM_N_CABLES && ok; ++i) {
            const double *Ji = J + 3 * i;
            double v = t_ref[i] + Ji[0] * lam[0] + Ji[1] * lam[1] + Ji[2] * lam[2];
            if (lo_set[i]) { cand[i] = lo; ok = v - lo <= eps; }         /* multiplier lo - v >= 0 */
            else if (up_set[i]) { cand[i] = hi; ok = v - hi >= -eps; }
            else { cand[i] = v; ok = v >= lo - eps && v <= hi + eps; }
        }
        if (ok) {
            for (i = 0; i < CSJM_N_CABLES; ++i) { t[i] = cand[i]; lower[i] = lo_set[i]; upper[i] = up_set[i]; }
            return CSJM_QP_OK;
        }
    }
    return CSJM_QP_NOT_SETTLED;
}

double csjm_qp_outside_margin(const double J[3 * CSJM_N_CABLES], const double b[3], double lo, double hi)
{
    double worst = -HUGE_VAL;
    int i, j, k, s;
    for (i = 0; i < CSJM_N_CABLES; ++i) {
        for (j = i + 1; j < CSJM_N_CABLES; ++j) {
            const double *gi = J + 3 * i, *gj = J + 3 * j;
            double n[3], nn;
            n[0] = gi[1] * gj[2] - gi[2] * gj[1];
            n[1] = gi[2] * gj[0] - gi[0] * gj[2];
            n[2] = gi[0] * gj[1] - gi[1] * gj[0];
            nn = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (!(nn > 1e-12 * sqrt((gi[0] * gi[0] + gi[1] * gi[1] + gi[2] * gi[2])
                                    * (gj[0] * gj[0] + gj[1] * gj[1] + gj[2] * gj[2])))) continue;
            for (s = -1; s <= 1; s += 2) {
                double h = 0.0, ub = 0.0, m;
                for (k = 0; k < CSJM_N_CABLES; ++k) {     /* support function h(u) = sum_k max(lo u.g_k, hi u.g_k) */
                    double d = s * (n[0] * J[3 * k] + n[1] * J[3 * k + 1] + n[2] * J[3 * k + 2]);
                    h += d > 0.0 ? hi * d : lo * d;
                }
                ub = s * (n[0] * b[0] + n[1] * b[1] + n[2] * b[2]);
                m = (ub - h) / nn;
                if (m > worst) worst = m;
            }
        }
    }
    return worst;
}

static double clamp(double x, double lo, double hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

/* |r0 + x gi + y gj|^2 for (x, y) */
static double residual2(const double r0[3], const double gi[3], const double gj[3], double x, double y)
{
    double e0 = r0[0] + x * gi[0] + y * gj[0], e1 = r0[1] + x * gi[1] + y * gj[1];
    double e2 = r0[2] + x * gi[2] + y * gj[2];
    return e0 * e0 + e1 * e1 + e2 * e2;
}

double csjm_qp_distance(const double J[3 * CSJM_N_CABLES], const double b[3], double lo, double hi, double t[CSJM_N_CABLES])
{
    double best = HUGE_VAL;
    int i, j, k;
    long mask;
    for (i = 0; i < CSJM_N_CABLES; ++i) t[i] = lo;
    for (i = 0; i < CSJM_N_CABLES; ++i) {
        for (j = i + 1; j < CSJM_N_CABLES; ++j) {
            const double *gi = J + 3 * i, *gj = J + 3 * j;
            double a = gi[0] * gi[0] + gi[1] * gi[1] + gi[2] * gi[2];
            double c = gj[0] * gj[0] + gj[1] * gj[1] + gj[2] * gj[2];
            double bb = gi[0] * gj[0] + gi[1] * gj[1] + gi[2] * gj[2];
            double det = a * c - bb * bb;
            double inv_a = a > 0.0 ? 1.0 / a : 0.0, inv_c = c > 0.0 ? 1.0 / c : 0.0;
            double inv_det = det > 1e-12 * a * c ? 1.0 / det : 0.0;
            for (mask = 0; mask < (1L << (CSJM_N_CABLES - 2)); ++mask) {   /* the others at lo (bit 0) or hi (bit 1) */
                double r0[3] = {-b[0], -b[1], -b[2]}, p, q, xs[4], ys[4], d;
                int bit = 0, e, n_cand;
                for (k = 0; k < CSJM_N_CABLES; ++k) {
                    double tk;
                    if (k == i || k == j) continue;
                    tk = (mask >> bit) & 1 ? hi : lo;
                    ++bit;
                    r0[0] += tk * J[3 * k];
                    r0[1] += tk * J[3 * k + 1];
                    r0[2] += tk * J[3 * k + 2];
                }
                p = gi[0] * r0[0] + gi[1] * r0[1] + gi[2] * r0[2];
                q = gj[0] * r0[0] + gj[1] * r0[1] + gj[2] * r0[2];
                /* the interior minimiser if it lies in the box (then it is the face's minimum),
                 * else the four edges' clamped 1-D minimisers */
                n_cand = 4;
                xs[0] = lo; ys[0] = clamp(-(q + bb * lo) * inv_c, lo, hi);
                xs[1] = hi; ys[1] = clamp(-(q + bb * hi) * inv_c, lo, hi);
                ys[2] = lo; xs[2] = clamp(-(p + bb * lo) * inv_a, lo, hi);
                ys[3] = hi; xs[3] = clamp(-(p + bb * hi) * inv_a, lo, hi);
                if (inv_det > 0.0) {
                    double x = (-p * c + q * bb) * inv_det, y = (-q * a + p * bb) * inv_det;
                    if (x >= lo && x <= hi && y >= lo && y <= hi) { xs[0] = x; ys[0] = y; n_cand = 1; }
                }
                for (e = 0; e < n_cand; ++e) {
                    d = residual2(r0, gi, gj, xs[e], ys[e]);
                    if (d < best) {
                        best = d;
                        bit = 0;
                        for (k = 0; k < CSJM_N_CABLES; ++k) {
                            if (k == i) t[k] = xs[e];
                            else if (k == j) t[k] = ys[e];
                            else { t[k] = (mask >> bit) & 1 ? hi : lo; ++bit; }
                        }
                    }
                }
            }
        }
    }
    return sqrt(best);
}
