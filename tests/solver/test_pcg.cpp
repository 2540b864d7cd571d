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

// The energy test (weft/backend/cg_energy_stop.h): past a loose residual test the solve goes on
// while the incremental potential Φ still falls by more than the floor, and only then.
TEST(Pcg, TheEnergyTestGoesOnPastTheResidualTestWhilePhiStillFalls) {
    std::mt19937 rng(13);
    auto fabric = Fabric::cook(make_grid(1, 1, 12, 12));
    const auto A = random_spd(*fabric, rng, 1e-3);  // ill-conditioned: the residual test stops early
    const std::size_t n = fabric->vertex_count();
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<V3> exact(n);
    for (V3& v : exact) v = {u(rng), u(rng), u(rng)};
    const auto b = multiply(A, exact);
    const std::vector<std::uint8_t> fixed(n, 0);
    // ½‖x − x*‖²_A: how far Φ(x) is above its minimum, what the test estimates.
    const auto energy_error = [&](const std::vector<V3>& x) {
        std::vector<V3> e(n);
        for (std::size_t i = 0; i < n; ++i) e[i] = x[i] - exact[i];
        const auto ae = multiply(A, e);
        double sum = 0.0;
        for (std::size_t i = 0; i < n; ++i) sum += physics::dot(e[i], ae[i]);
        return 0.5 * sum;
    };
    cpu::Pcg<double> pcg;
    pcg.resize(n);
    const auto solve = [&](double floor, int cap, std::vector<V3>& x) {
        x.assign(n, V3{});
        pcg.set_energy_floor(floor);
        return pcg.solve(A, b, fixed, x, 1e-2, cap);
    };
    std::vector<V3> x_residual, x_high, x_energy, x_capped;
    const auto residual_only = solve(0.0, 5000, x_residual);
    ASSERT_TRUE(residual_only.converged);
    const double error_at_residual_test = energy_error(x_residual);
    ASSERT_GT(error_at_residual_test, 0.0);
    // A floor above every fall changes nothing: the same iterations, the same bits.
    const auto high = solve(1e30, 5000, x_high);
    EXPECT_EQ(high.iterations, residual_only.iterations);
    EXPECT_EQ(x_high, x_residual);
    // A floor below what Φ still had to fall: more iterations, and Φ ends much nearer its minimum.
    const auto energy = solve(1e-4 * error_at_residual_test, 5000, x_energy);
    EXPECT_TRUE(energy.converged);
    EXPECT_GT(energy.iterations, residual_only.iterations);
    EXPECT_LT(energy_error(x_energy), 1e-2 * error_at_residual_test)
        << "residual test alone: " << residual_only.iterations << " iterations, with the energy test "
        << energy.iterations;
    // The iteration cap still holds; the solve that met it past the residual test reports converged.
    const auto capped = solve(1e-300, residual_only.iterations + 2, x_capped);
    EXPECT_EQ(capped.iterations, residual_only.iterations + 2);
    EXPECT_TRUE(capped.converged);
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
