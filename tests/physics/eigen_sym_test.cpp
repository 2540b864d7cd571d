// Cyclic Jacobi eigensolver and PSD projection against matrices with known spectra.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "fd_util.h"
#include "weft/physics/eigen_sym.h"

namespace weft::physics::test {
namespace {

// Builds A = Q diag(lambda) Qᵀ with a random orthogonal Q (Gram–Schmidt of a Gaussian matrix).
template <int N>
void random_spectrum_matrix(std::mt19937& rng, const double lambda[N], double a[N][N], double q[N][N]) {
    std::normal_distribution<double> G(0.0, 1.0);
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) q[i][j] = G(rng);
    for (int k = 0; k < N; ++k) {  // orthonormalise column k
        for (int p = 0; p < k; ++p) {
            double d = 0.0;
            for (int i = 0; i < N; ++i) d += q[i][k] * q[i][p];
            for (int i = 0; i < N; ++i) q[i][k] -= d * q[i][p];
        }
        double nrm = 0.0;
        for (int i = 0; i < N; ++i) nrm += q[i][k] * q[i][k];
        nrm = std::sqrt(nrm);
        for (int i = 0; i < N; ++i) q[i][k] /= nrm;
    }
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) {
            double s = 0.0;
            for (int k = 0; k < N; ++k) s += q[i][k] * lambda[k] * q[j][k];
            a[i][j] = s;
        }
}

template <int N>
void check_known_spectrum(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(-10.0, 10.0);
    double lambda[N];
    for (double& l : lambda) l = U(rng);
    lambda[0] = lambda[N - 1];  // a repeated eigenvalue, the classic trap
    double a[N][N], q[N][N], a0[N][N];
    random_spectrum_matrix<N>(rng, lambda, a, q);
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) a0[i][j] = a[i][j];
    double ev[N], V[N][N];
    const int sweeps = eigen_sym<N>(a, ev, V);
    EXPECT_LT(sweeps, 30);
    double want[N], got[N];
    for (int i = 0; i < N; ++i) {
        want[i] = lambda[i];
        got[i] = ev[i];
    }
    std::sort(want, want + N);
    std::sort(got, got + N);
    for (int i = 0; i < N; ++i) EXPECT_NEAR(got[i], want[i], 1e-12) << "N=" << N << " i=" << i;
    // A·v_k = λ_k v_k and VᵀV = I.
    for (int k = 0; k < N; ++k) {
        for (int i = 0; i < N; ++i) {
            double av = 0.0;
            for (int j = 0; j < N; ++j) av += a0[i][j] * V[j][k];
            EXPECT_NEAR(av, ev[k] * V[i][k], 1e-12);
        }
        for (int l = 0; l < N; ++l) {
            double d = 0.0;
            for (int i = 0; i < N; ++i) d += V[i][k] * V[i][l];
            EXPECT_NEAR(d, k == l ? 1.0 : 0.0, 1e-13);
        }
    }
}

TEST(EigenSym, KnownSpectra) {
    check_known_spectrum<2>(1);
    check_known_spectrum<3>(2);
    check_known_spectrum<6>(3);
    check_known_spectrum<9>(4);
    check_known_spectrum<12>(5);
}

TEST(EigenSym, DiagonalAndExplicit2x2) {
    double a[2][2] = {{2.0, 1.0}, {1.0, 2.0}};  // eigenvalues 1 and 3
    double ev[2], v[2][2];
    eigen_sym<2>(a, ev, v);
    EXPECT_NEAR(std::fmin(ev[0], ev[1]), 1.0, 1e-15);
    EXPECT_NEAR(std::fmax(ev[0], ev[1]), 3.0, 1e-15);
    double d[3][3] = {{5.0, 0.0, 0.0}, {0.0, -1.0, 0.0}, {0.0, 0.0, 2.0}};
    double e3[3], v3[3][3];
    EXPECT_EQ(eigen_sym<3>(d, e3, v3), 0);  // already diagonal: no sweep
    EXPECT_EQ(e3[0], 5.0);
    EXPECT_EQ(e3[1], -1.0);
    EXPECT_EQ(e3[2], 2.0);
}

TEST(EigenSym, ProjectPsdClampsOnlyNegativeEigenvalues) {
    std::mt19937 rng(7);
    constexpr int N = 9;
    const double lambda[N] = {-3.0, -1e-3, 0.0, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0};
    double a[N][N], q[N][N];
    random_spectrum_matrix<N>(rng, lambda, a, q);
    EXPECT_TRUE(project_psd<N>(a));
    // Expected: Q diag(max(λ,0)) Qᵀ.
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) {
            double s = 0.0;
            for (int k = 0; k < N; ++k) s += q[i][k] * std::fmax(lambda[k], 0.0) * q[j][k];
            EXPECT_NEAR(a[i][j], s, 1e-12);
        }
    EXPECT_TRUE(psd_by_cholesky<N>(a, 1e-12));
    // An SPD matrix passes through unchanged.
    const double pos[N] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    double b[N][N], b0[N][N];
    random_spectrum_matrix<N>(rng, pos, b, q);
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) b0[i][j] = b[i][j];
    EXPECT_FALSE(project_psd<N>(b));
    for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) EXPECT_NEAR(b[i][j], b0[i][j], 1e-15);
}

TEST(EigenSym, PackUnpackRoundTrip) {
    M blocks[2][2];
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) blocks[a][b].m[r][c] = 100.0 * a + 10.0 * b + 3.0 * r + c;
    double dense[6][6];
    pack_blocks<2>(blocks, dense);
    EXPECT_EQ(dense[4][2], blocks[1][0].m[1][2]);
    EXPECT_EQ(dense[2][5], blocks[0][1].m[2][2]);
    M back[2][2];
    unpack_blocks<2>(dense, back);
    EXPECT_EQ(max_abs_diff<2>(blocks, back), 0.0);
}

TEST(EigenSym, NaNInputTerminates) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    double a[3][3] = {{1.0, nan, 0.0}, {nan, 1.0, 0.0}, {0.0, 0.0, 1.0}};
    double ev[3], v[3][3];
    EXPECT_LE(eigen_sym<3>(a, ev, v), 30);
}

}  // namespace
}  // namespace weft::physics::test
