// Preconditioned CG with filtered constraints, on SPD block systems with known solutions.
#include <gtest/gtest.h>

#include <random>

#include "cpu/pcg.h"
#include "weft/fabric.h"
#include "weft/mesh.h"

namespace weft {
namespace {

using V3 = physics::Vec3<double>;
using M3 = physics::Mat3<double>;

// An SPD system on a fabric's pattern: A = M·I + Σ_triangles Bᵀ B (random 9×9 PSD per triangle),
// scattered with the fabric's slot map.
cpu::BsrMatrix<double> random_spd(const Fabric& fabric, std::mt19937& rng, double mass) {
    cpu::BsrMatrix<double> A;
    A.resize(fabric.pattern());
    std::normal_distribution<double> g(0.0, 1.0);
    for (std::size_t i = 0; i < fabric.vertex_count(); ++i) A.set_block(fabric.pattern().diagonal[i], M3::diagonal(mass));
    for (std::size_t t = 0; t < fabric.triangle_count(); ++t) {
        double B[9][9], K[9][9] = {};
        for (auto& row : B)
            for (double& v : row) v = g(rng);
        for (int r = 0; r < 9; ++r)
            for (int c = 0; c < 9; ++c)
                for (int k = 0; k < 9; ++k) K[r][c] += B[k][r] * B[k][c];
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                const std::size_t s = fabric.pattern().triangle_slots[t * 9 + std::size_t(a * 3 + b)];
                M3 blk = A.block(s);
                for (int r = 0; r < 3; ++r)
                    for (int c = 0; c < 3; ++c) blk.m[r][c] += K[3 * a + r][3 * b + c];
                A.set_block(s, blk);
            }
    }
    return A;
}

std::vector<V3> multiply(const cpu::BsrMatrix<double>& A, const std::vector<V3>& x) {
    std::vector<V3> y(x.size());
    A.multiply(x, y);
    return y;
}

TEST(Pcg, SolvesSpdSystemToTolerance) {
    std::mt19937 rng(7);
    auto fabric = Fabric::cook(make_grid(1, 1, 12, 9));
    const auto A = random_spd(*fabric, rng, 0.5);
    const std::size_t n = fabric->vertex_count();
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<V3> exact(n);
    for (V3& v : exact) v = {u(rng), u(rng), u(rng)};
    const auto b = multiply(A, exact);
    std::vector<V3> x(n);
    std::vector<std::uint8_t> fixed(n, 0);
    cpu::Pcg<double> pcg;
    pcg.resize(n);
    const auto r = pcg.solve(A, b, fixed, x, 1e-10, 2000);
    EXPECT_TRUE(r.converged);
    EXPECT_GT(r.iterations, 5);
    EXPECT_LE(r.relative_residual, 1e-10);
    double err = 0.0;
    for (std::size_t i = 0; i < n; ++i) err = std::max(err, physics::length(x[i] - exact[i]));
    EXPECT_LT(err, 1e-6);
}

TEST(Pcg, FilteredVerticesKeepTheirPrescribedValueAndTheRestSolvesTheReducedSystem) {
    std::mt19937 rng(11);
    auto fabric = Fabric::cook(make_grid(1, 1, 8, 8));
    const auto A = random_spd(*fabric, rng, 1.0);
    const std::size_t n = fabric->vertex_count();
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<V3> b(n), x(n);
    for (V3& v : b) v = {u(rng), u(rng), u(rng)};
    std::vector<std::uint8_t> fixed(n, 0);
    for (std::size_t i = 0; i < 9; ++i) {  // the first row of the grid is prescribed
        fixed[i] = 1;
        x[i] = {0.1 * double(i), -0.2, 0.3};
    }
    const std::vector<V3> z(x.begin(), x.begin() + 9);
    cpu::Pcg<double> pcg;
    pcg.resize(n);
    const auto r = pcg.solve(A, b, fixed, x, 1e-12, 5000);
    ASSERT_TRUE(r.converged);
    for (std::size_t i = 0; i < 9; ++i) EXPECT_EQ(x[i], z[i]);
    // Free rows satisfy (A x)_i = b_i.
    const auto ax = multiply(A, x);
    for (std::size_t i = 9; i < n; ++i) EXPECT_LT(physics::length(ax[i] - b[i]), 1e-7) << i;
}

TEST(Pcg, IterationCapIsReportedAsNotConverged) {
    std::mt19937 rng(3);
    auto fabric = Fabric::cook(make_grid(1, 1, 10, 10));
    const auto A = random_spd(*fabric, rng, 1e-3);
    const std::size_t n = fabric->vertex_count();
    std::vector<V3> b(n, V3{1, 2, 3}), x(n);
    std::vector<std::uint8_t> fixed(n, 0);
    cpu::Pcg<double> pcg;
    pcg.resize(n);
    const auto r = pcg.solve(A, b, fixed, x, 1e-12, 3);
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.iterations, 3);
    EXPECT_GT(r.relative_residual, 1e-12);
}

TEST(Pcg, ZeroRightHandSideConvergesImmediately) {
    auto fabric = Fabric::cook(make_grid(1, 1, 3, 3));
    std::mt19937 rng(5);
    const auto A = random_spd(*fabric, rng, 1.0);
    const std::size_t n = fabric->vertex_count();
    std::vector<V3> b(n), x(n);
    std::vector<std::uint8_t> fixed(n, 0);
    cpu::Pcg<double> pcg;
    pcg.resize(n);
    const auto r = pcg.solve(A, b, fixed, x, 1e-6, 100);
    EXPECT_TRUE(r.converged);
    EXPECT_EQ(r.iterations, 0);
}

}  // namespace
}  // namespace weft
