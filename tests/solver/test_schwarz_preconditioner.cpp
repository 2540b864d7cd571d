// The multilevel additive Schwarz preconditioner (cpu/schwarz_preconditioner.h) and its levels
// (weft/backend/schwarz_hierarchy.h): a permutation with compact domains, an SPD operator, the same
// solution as block-Jacobi, and iteration counts that grow far less than Jacobi's under refinement.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "cpu/pcg.h"
#include "cpu/schwarz_preconditioner.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/error.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

using V3 = physics::Vec3<double>;
using M3 = physics::Mat3<double>;

std::vector<Vec3d> rest_positions(const Fabric& fabric) {
    return {fabric.rest_positions().begin(), fabric.rest_positions().end()};
}

// A cloth-like SPD system on a fabric's pattern: A = m·I + k·L ⊗ I₃ with L the graph Laplacian of
// the pattern (every stored off-diagonal block −k·I). k/m plays k·h²/m: the stiffness that makes
// block-Jacobi slow on fine meshes.
cpu::BsrMatrix<double> stiff_laplacian(const Fabric& fabric, double mass, double k) {
    cpu::BsrMatrix<double> A;
    const BlockPattern& p = fabric.pattern();
    A.resize(p);
    for (std::size_t i = 0; i < fabric.vertex_count(); ++i) {
        double degree = 0.0;
        for (std::uint32_t s = p.row_start[i]; s < p.row_start[i + 1]; ++s)
            if (p.column[s] != i) {
                A.blocks[s] = M3::diagonal(-k);
                degree += 1.0;
            }
        A.blocks[p.diagonal[i]] = M3::diagonal(mass + k * degree);
    }
    return A;
}

std::vector<V3> random_vectors(std::size_t n, std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<V3> x(n);
    for (V3& v : x) v = {u(rng), u(rng), u(rng)};
    return x;
}

double dot(const std::vector<V3>& a, const std::vector<V3>& b) {
    double s = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) s += math::dot(a[i], b[i]);
    return s;
}

TEST(SchwarzHierarchy, MortonOrderIsAPermutationWithCompactDomains) {
    const auto fabric = Fabric::cook(make_grid(1.0, 1.0, 63, 63));  // 64 × 64 vertices
    const SchwarzHierarchy h = build_schwarz_hierarchy(rest_positions(*fabric));
    const std::size_t n = fabric->vertex_count();
    ASSERT_EQ(h.order.size(), n);
    std::vector<std::uint32_t> sorted = h.order;
    std::sort(sorted.begin(), sorted.end());
    for (std::uint32_t v = 0; v < n; ++v) {
        ASSERT_EQ(sorted[v], v);
        ASSERT_EQ(h.order[h.rank[v]], v);
    }
    // 4096 vertices: 4096, 128, 4 nodes.
    ASSERT_EQ(h.levels(), 3);
    EXPECT_EQ(h.level_nodes[1], 128u);
    EXPECT_EQ(h.level_nodes[2], 4u);
    // On a regular grid a Morton run of 32 vertices is a 4 × 8 patch: no domain spans more than
    // 8 cells of 1/63 m along an axis.
    const auto rest = rest_positions(*fabric);
    for (std::uint32_t d = 0; d < h.domains(0); ++d) {
        Vec3d lo = rest[h.order[32 * d]], hi = lo;
        for (std::uint32_t p = 32 * d; p < 32 * d + 32; ++p)
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min(lo[k], rest[h.order[p]][k]);
                hi[k] = std::max(hi[k], rest[h.order[p]][k]);
            }
        for (int k = 0; k < 3; ++k) EXPECT_LE(hi[k] - lo[k], 8.0 / 63.0 + 1e-12) << "domain " << d;
    }
}

TEST(SchwarzHierarchy, RejectsBadInput) {
    EXPECT_THROW((void)build_schwarz_hierarchy({}, 0), Error);
    const std::vector<Vec3d> nan{{0, 0, 0}, {std::nan(""), 0, 0}};
    EXPECT_THROW((void)build_schwarz_hierarchy(nan), Error);
}

TEST(SchwarzPreconditioner, IsSymmetricPositiveDefiniteWithAndWithoutPins) {
    const auto fabric = Fabric::cook(make_grid(1.0, 1.0, 39, 39));  // 1600 vertices: three levels
    const auto A = stiff_laplacian(*fabric, 1e-3, 10.0);
    const SchwarzHierarchy h = build_schwarz_hierarchy(rest_positions(*fabric));
    ASSERT_EQ(h.levels(), 3);
    const std::size_t n = fabric->vertex_count();
    std::mt19937 rng(3);
    for (const bool pins : {false, true}) {
        std::vector<std::uint8_t> fixed(n, 0);
        if (pins)
            for (std::size_t i = 0; i < 40; ++i) fixed[i] = 1;  // one edge of the sheet
        cpu::SchwarzPreconditioner<double> M;
        M.build(h);
        M.factor(A, fixed, [](std::size_t) { return M3{}; });
        EXPECT_EQ(M.pivot_failures(), 0);
        const auto filtered = [&](std::vector<V3> x) {
            for (std::size_t i = 0; i < n; ++i)
                if (fixed[i]) x[i] = V3{};
            return x;
        };
        for (int trial = 0; trial < 5; ++trial) {
            const auto x = filtered(random_vectors(n, rng)), y = filtered(random_vectors(n, rng));
            std::vector<V3> mx(n), my(n);
            M.apply(x, mx);
            M.apply(y, my);
            const double xmy = dot(filtered(my), x), ymx = dot(filtered(mx), y);
            EXPECT_NEAR(xmy, ymx, 1e-9 * std::abs(xmy)) << "pins " << pins;
            EXPECT_GT(dot(filtered(mx), x), 0.0) << "pins " << pins;
        }
    }
}

// Iterations of PCG (to 1e-8) for the stiff Laplacian on an n × n-vertex grid, from a random b.
struct Iterations {
    int jacobi = 0, schwarz = 0;
    double difference = 0.0;  // largest |x_schwarz − x_jacobi|
};
Iterations solve_both(int cells, double k) {
    const auto fabric = Fabric::cook(make_grid(1.0, 1.0, cells, cells));
    const auto A = stiff_laplacian(*fabric, 1e-3, k);
    const std::size_t n = fabric->vertex_count();
    std::mt19937 rng(11);
    const auto b = random_vectors(n, rng);
    std::vector<std::uint8_t> fixed(n, 0);
    for (int i = 0; i <= cells; ++i) fixed[static_cast<std::size_t>(i)] = 1;  // a pinned edge
    std::vector<V3> xj(n), xs(n);
    cpu::Pcg<double> pcg;
    pcg.resize(n);
    Iterations it;
    const auto rj = pcg.solve(A, b, fixed, xj, 1e-8, 20000);
    EXPECT_TRUE(rj.converged);
    const SchwarzHierarchy h = build_schwarz_hierarchy(rest_positions(*fabric));
    cpu::SchwarzPreconditioner<double> M;
    M.build(h);
    M.factor(A, fixed, [](std::size_t) { return M3{}; });
    const auto rs = pcg.solve(A, b, fixed, xs, 1e-8, 20000, &M);
    EXPECT_TRUE(rs.converged);
    it.jacobi = rj.iterations;
    it.schwarz = rs.iterations;
    double scale = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        it.difference = std::max(it.difference, math::length(xs[i] - xj[i]));
        scale = std::max(scale, math::length(xj[i]));
    }
    it.difference /= scale;
    return it;
}

TEST(SchwarzPreconditioner, ReachesJacobisSolutionInFarFewerIterations) {
    const Iterations it = solve_both(47, 10.0);
    std::printf("48 x 48, k/m = 1e4: jacobi %d, schwarz %d iterations, relative difference %.2e\n", it.jacobi,
                it.schwarz, it.difference);
    EXPECT_LT(it.difference, 1e-5);
    EXPECT_LT(it.schwarz, it.jacobi);
}

TEST(SchwarzPreconditioner, IterationsGrowLessThanJacobisUnderRefinement) {
    const Iterations coarse = solve_both(23, 10.0), fine = solve_both(95, 10.0);  // 4× finer
    const double jacobi_growth = double(fine.jacobi) / coarse.jacobi;
    const double schwarz_growth = double(fine.schwarz) / coarse.schwarz;
    std::printf("24² -> 96²: jacobi %d -> %d (%.2fx), schwarz %d -> %d (%.2fx)\n", coarse.jacobi, fine.jacobi,
                jacobi_growth, coarse.schwarz, fine.schwarz, schwarz_growth);
    EXPECT_LT(schwarz_growth, jacobi_growth);
}

// The whole step with `solver.preconditioner = "mas"`: a sheet pinned along one edge, falling and
// swinging for 30 frames, ends where the Jacobi run ends (both solves to
// 1e-9), and every solve converges.
TEST(SchwarzPreconditioner, StepsACpuWorldToJacobisState) {
    std::vector<Vec3d> final_state[2];
    for (const Preconditioner pre : {Preconditioner::Jacobi, Preconditioner::Schwarz}) {
        WorldDesc desc;
        desc.solver.preconditioner = pre;
        desc.solver.cg_tolerance = 1e-9;
        desc.solver.cg_max_iterations = 5000;
        World world(desc, "cpu");
        ClothDesc cloth{.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 40, 40))};
        for (std::uint32_t i = 0; i <= 40; ++i) cloth.pins.push_back({.vertex = i});
        world.add_cloth(cloth);
        for (int frame = 0; frame < 30; ++frame) {
            const StepStats& stats = world.step();
            ASSERT_EQ(stats.cg_not_converged, 0) << "frame " << frame;
            ASSERT_FALSE(stats.non_finite);
        }
        final_state[pre == Preconditioner::Schwarz ? 1 : 0] = world.positions(0);
    }
    double largest = 0.0;
    for (std::size_t i = 0; i < final_state[0].size(); ++i)
        largest = std::max(largest, math::length(final_state[1][i] - final_state[0][i]));
    EXPECT_LT(largest, 1e-5);  // m, after 30 frames of a 1 m sheet
}

}  // namespace
}  // namespace weft
