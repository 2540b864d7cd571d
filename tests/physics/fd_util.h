#pragma once
// Shared helpers for the physics finite-difference tests: central differences of energies and
// gradients, block-matrix comparisons, and a positive semi-definiteness check by Cholesky that
// does not reuse the Jacobi eigensolver under test.
#include <cmath>
#include <random>

#include "weft/physics/vec.h"

namespace weft::physics::test {

using V = Vec3<double>;
using M = Mat3<double>;

/// Central-difference gradient of a scalar function of n points.
template <int n, typename F>
void fd_gradient(F&& f, const V x[n], V g[n], double h = 1e-6) {
    V y[n];
    for (int a = 0; a < n; ++a) y[a] = x[a];
    for (int a = 0; a < n; ++a)
        for (int i = 0; i < 3; ++i) {
            const double x0 = y[a][i];
            y[a][i] = x0 + h;
            const double ep = f(y);
            y[a][i] = x0 - h;
            const double em = f(y);
            y[a][i] = x0;
            g[a][i] = (ep - em) / (2.0 * h);
        }
}

/// Central-difference Jacobian of a vector function of n points (n outputs):
/// J[a][b].m[r][c] = ∂g_a[r]/∂x_b[c].
template <int n, typename G>
void fd_jacobian(G&& grad, const V x[n], M J[n][n], double h = 1e-6) {
    V y[n];
    for (int a = 0; a < n; ++a) y[a] = x[a];
    V gp[n], gm[n];
    for (int b = 0; b < n; ++b)
        for (int c = 0; c < 3; ++c) {
            const double x0 = y[b][c];
            y[b][c] = x0 + h;
            grad(y, gp);
            y[b][c] = x0 - h;
            grad(y, gm);
            y[b][c] = x0;
            for (int a = 0; a < n; ++a)
                for (int r = 0; r < 3; ++r) J[a][b].m[r][c] = (gp[a][r] - gm[a][r]) / (2.0 * h);
        }
}

template <int n>
double max_abs(const V g[n]) {
    double m = 0.0;
    for (int a = 0; a < n; ++a)
        for (int i = 0; i < 3; ++i) m = std::fmax(m, std::fabs(g[a][i]));
    return m;
}
template <int n>
double max_abs_diff(const V g[n], const V h[n]) {
    double m = 0.0;
    for (int a = 0; a < n; ++a)
        for (int i = 0; i < 3; ++i) m = std::fmax(m, std::fabs(g[a][i] - h[a][i]));
    return m;
}
template <int n>
double max_abs(const M H[n][n]) {
    double m = 0.0;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b)
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) m = std::fmax(m, std::fabs(H[a][b].m[r][c]));
    return m;
}
template <int n>
double max_abs_diff(const M H[n][n], const M K[n][n]) {
    double m = 0.0;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b)
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) m = std::fmax(m, std::fabs(H[a][b].m[r][c] - K[a][b].m[r][c]));
    return m;
}
inline double max_abs(const M& a) {
    double m = 0.0;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) m = std::fmax(m, std::fabs(a.m[r][c]));
    return m;
}
inline double max_abs_diff(const M& a, const M& b) { return max_abs(a - b); }

/// True when A + shift·I (A symmetric N×N) has a Cholesky factorisation, i.e. λ_min(A) > −shift.
/// Independent of eigen_sym, so PSD checks do not trust the code they test.
template <int N>
bool psd_by_cholesky(const double a[N][N], double shift) {
    double l[N][N] = {};
    for (int j = 0; j < N; ++j) {
        double d = a[j][j] + shift;
        for (int k = 0; k < j; ++k) d -= l[j][k] * l[j][k];
        if (!(d > 0.0)) return false;
        l[j][j] = std::sqrt(d);
        for (int i = j + 1; i < N; ++i) {
            double s = 0.5 * (a[i][j] + a[j][i]);
            for (int k = 0; k < j; ++k) s -= l[i][k] * l[j][k];
            l[i][j] = s / l[j][j];
        }
    }
    return true;
}
template <int n>
bool blocks_psd(const M H[n][n], double rel_tol = 1e-9) {
    double a[3 * n][3 * n];
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) a[3 * i + r][3 * j + c] = H[i][j].m[r][c];
    return psd_by_cholesky<3 * n>(a, rel_tol * (max_abs<n>(H) + 1e-300));
}
template <int n>
bool blocks_symmetric(const M H[n][n], double rel_tol = 1e-12) {
    const double s = max_abs<n>(H);
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b)
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c)
                    if (std::fabs(H[a][b].m[r][c] - H[b][a].m[c][r]) > rel_tol * s) return false;
    return true;
}

/// Random rotation (uniform enough for tests) from a seeded generator.
inline M random_rotation(std::mt19937& rng) {
    std::normal_distribution<double> N(0.0, 1.0);
    double q[4];
    double s = 0.0;
    for (double& qi : q) {
        qi = N(rng);
        s += qi * qi;
    }
    s = std::sqrt(s);
    const double w = q[0] / s, x = q[1] / s, y = q[2] / s, z = q[3] / s;
    M r{};
    r.m[0][0] = 1 - 2 * (y * y + z * z); r.m[0][1] = 2 * (x * y - w * z);     r.m[0][2] = 2 * (x * z + w * y);
    r.m[1][0] = 2 * (x * y + w * z);     r.m[1][1] = 1 - 2 * (x * x + z * z); r.m[1][2] = 2 * (y * z - w * x);
    r.m[2][0] = 2 * (x * z - w * y);     r.m[2][1] = 2 * (y * z + w * x);     r.m[2][2] = 1 - 2 * (x * x + y * y);
    return r;
}
inline V random_vec(std::mt19937& rng, double lo, double hi) {
    std::uniform_real_distribution<double> U(lo, hi);
    return V{U(rng), U(rng), U(rng)};
}

}  // namespace weft::physics::test
