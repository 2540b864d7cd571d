// The multilevel additive Schwarz preconditioner (cpu/schwarz_preconditioner.h) and its levels
// (weft/backend/schwarz_hierarchy.h): a permutation with compact domains, an SPD operator, the same
// solution as block-Jacobi, and iteration counts that grow far less than Jacobi's under refinement.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <string>

#include "cpu/pcg.h"
#include "cpu/schwarz_preconditioner.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/error.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/physics/membrane.h"
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
                A.set_block(s, M3::diagonal(-k));
                degree += 1.0;
            }
        A.set_block(p.diagonal[i], M3::diagonal(mass + k * degree));
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

/// M⁻¹ restricted to the free vertices is symmetric and positive definite: (S M⁻¹ S) checked on
/// `trials` pairs of random filtered vectors.
void expect_spd_on_free_vertices(cpu::SchwarzPreconditioner<double>& M, const std::vector<std::uint8_t>& fixed,
                                 std::mt19937& rng, int trials, const std::string& what) {
    const std::size_t n = fixed.size();
    const auto filtered = [&](std::vector<V3> x) {
        for (std::size_t i = 0; i < n; ++i)
            if (fixed[i]) x[i] = V3{};
        return x;
    };
    for (int trial = 0; trial < trials; ++trial) {
        const auto x = filtered(random_vectors(n, rng)), y = filtered(random_vectors(n, rng));
        std::vector<V3> mx(n), my(n);
        M.apply(x, mx);
        M.apply(y, my);
        const double xmy = dot(filtered(my), x), ymx = dot(filtered(mx), y);
        EXPECT_NEAR(xmy, ymx, 1e-9 * std::abs(xmy)) << what;
        EXPECT_GT(dot(filtered(mx), x), 0.0) << what;
    }
}

TEST(SchwarzHierarchy, MortonOrderIsAPermutationWithCompactDomains) {
    const auto fabric = Fabric::cook(make_grid(1.0, 1.0, 63, 63));  // 64 × 64 vertices
    const SchwarzHierarchy h = build_schwarz_hierarchy(rest_positions(*fabric), fabric->pattern());
    const std::size_t n = fabric->vertex_count();
    ASSERT_EQ(h.order.size(), n);
    std::vector<std::uint32_t> sorted = h.order;
    std::sort(sorted.begin(), sorted.end());
    for (std::uint32_t v = 0; v < n; ++v) {
        ASSERT_EQ(sorted[v], v);
        ASSERT_EQ(h.order[h.rank[v]], v);
    }
    // 4096 vertices: on a 64 × 64 grid a Morton run of 16 vertices is a connected 4 × 4 patch, so
    // the levels have 4096, 256, 16 nodes.
    ASSERT_EQ(h.levels(), 3);
    EXPECT_EQ(h.nodes(1), 256u);
    EXPECT_EQ(h.nodes(2), 16u);
    const auto rest = rest_positions(*fabric);
    for (std::uint32_t d = 0; d < h.domains(0); ++d) {
        Vec3d lo = rest[h.order[16 * d]], hi = lo;
        for (std::uint32_t p = 16 * d; p < 16 * d + 16; ++p)
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min(lo[k], rest[h.order[p]][k]);
                hi[k] = std::max(hi[k], rest[h.order[p]][k]);
            }
        for (int k = 0; k < 3; ++k) EXPECT_LE(hi[k] - lo[k], 4.0 / 63.0 + 1e-12) << "domain " << d;
    }
}

// Every coarse node is one connected piece of its domain, its parent lies in its domain's range,
// and each coarse coupling sums exactly the couplings between its two nodes' members.
TEST(SchwarzHierarchy, CoarseNodesAreConnectedPiecesAndCouplingsSumTheirMembers) {
    // Two sheets side by side, 1 cm apart: a domain straddling the gap holds two pieces.
    MeshData a = make_grid(1.0, 1.0, 20, 20), b = make_grid(1.0, 1.0, 20, 20);
    for (Vec3d& p : b.positions) p[0] += 1.01;
    MeshData both = a;
    const auto offset = static_cast<std::uint32_t>(a.positions.size());
    both.positions.insert(both.positions.end(), b.positions.begin(), b.positions.end());
    for (Triangle t : b.triangles) {
        for (auto& v : t.v) v += offset;
        both.triangles.push_back(t);
    }
    const auto fabric = Fabric::cook(both);
    const SchwarzHierarchy h = build_schwarz_hierarchy(rest_positions(*fabric), fabric->pattern());
    ASSERT_GE(h.levels(), 2);
    const BlockPattern& pattern = fabric->pattern();
    const auto sheet = [&](std::uint32_t v) { return v >= offset ? 1 : 0; };
    // Level-1 nodes never mix the sheets, and lie in their domain's range.
    const SchwarzLevel& l0 = h.level[0];
    for (std::uint32_t d = 0; d < l0.domains(); ++d)
        for (std::uint32_t p = 16 * d; p < std::min(h.vertex_count, 16 * d + 16); ++p) {
            EXPECT_GE(l0.parent[p], l0.parent_start[d]);
            EXPECT_LT(l0.parent[p], l0.parent_start[d + 1]);
            for (std::uint32_t q = 16 * d; q < p; ++q) {
                if (l0.parent[q] == l0.parent[p]) {
                    EXPECT_EQ(sheet(h.order[q]), sheet(h.order[p]));
                }
            }
        }
    EXPECT_GT(h.nodes(1), l0.domains());  // some domain was split
    // Level 1's coupling (a, b) sums the slots between members of a and b, each slot once.
    std::vector<int> used(pattern.column.size(), 0);
    const SchwarzLevel& l1 = h.level[1];
    for (std::size_t e = 0; e < l1.entry_row.size(); ++e)
        for (std::uint32_t k = l1.source_start[e]; k < l1.source_start[e + 1]; ++k) {
            const std::uint32_t s = l1.source[k];
            ++used[s];
            const auto row = static_cast<std::uint32_t>(
                std::upper_bound(pattern.row_start.begin(), pattern.row_start.end(), s) - pattern.row_start.begin() - 1);
            EXPECT_EQ(l0.parent[h.rank[row]], l1.entry_row[e]);
            EXPECT_EQ(l0.parent[h.rank[pattern.column[s]]], l1.entry_column[e]);
        }
    for (const int u : used) ASSERT_EQ(u, 1);
}

TEST(SchwarzHierarchy, RejectsBadInput) {
    BlockPattern two;
    two.row_start = {0, 1, 2};
    two.column = {0, 1};
    two.diagonal = {0, 1};
    EXPECT_THROW((void)build_schwarz_hierarchy({}, BlockPattern{}, 0), Error);
    const std::vector<Vec3d> nan{{0, 0, 0}, {std::nan(""), 0, 0}};
    EXPECT_THROW((void)build_schwarz_hierarchy(nan, two), Error);
    const std::vector<Vec3d> three{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    EXPECT_THROW((void)build_schwarz_hierarchy(three, two), Error);  // pattern of 2 rows
    BlockPattern wild = two;
    wild.column[1] = 7;
    EXPECT_THROW((void)build_schwarz_hierarchy({three.data(), 2}, wild), Error);
}

TEST(SchwarzPreconditioner, IsSymmetricPositiveDefiniteWithAndWithoutPins) {
    const auto fabric = Fabric::cook(make_grid(1.0, 1.0, 39, 39));  // 1600 vertices: three levels
    const auto A = stiff_laplacian(*fabric, 1e-3, 10.0);
    const SchwarzHierarchy h = build_schwarz_hierarchy(rest_positions(*fabric), fabric->pattern());
    ASSERT_GE(h.levels(), 3);
    const std::size_t n = fabric->vertex_count();
    std::mt19937 rng(3);
    for (const bool pins : {false, true}) {
        std::vector<std::uint8_t> fixed(n, 0);
        if (pins)
            for (std::size_t i = 0; i < 40; ++i) fixed[i] = 1;  // one edge of the sheet
        cpu::SchwarzPreconditioner<double> M;
        M.build(h, fabric->pattern());
        M.factor(A, fixed, [](std::size_t) { return M3{}; });
        EXPECT_EQ(M.pivot_failures(), 0);
        expect_spd_on_free_vertices(M, fixed, rng, 5, pins ? "with pins" : "without pins");
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
    const SchwarzHierarchy h = build_schwarz_hierarchy(rest_positions(*fabric), fabric->pattern());
    cpu::SchwarzPreconditioner<double> M;
    M.build(h, fabric->pattern());
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

// `auto` is block-Jacobi on the CPU backend below kAutoSchwarzMinVerticesCpu: the same bits as
// asking for jacobi (441 vertices here; the switch itself is the cuda test's AutoPicksMas...).
TEST(SchwarzPreconditioner, AutoIsJacobiOnSmallCpuCloth) {
    std::vector<Vec3d> final_state[2];
    for (const Preconditioner pre : {Preconditioner::Jacobi, Preconditioner::Auto}) {
        WorldDesc desc;
        desc.solver.preconditioner = pre;
        World world(desc, "cpu");
        ClothDesc cloth{.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 20, 20))};
        for (std::uint32_t i = 0; i <= 20; ++i) cloth.pins.push_back({.vertex = i});
        world.add_cloth(cloth);
        for (int frame = 0; frame < 10; ++frame) (void)world.step();
        final_state[pre == Preconditioner::Auto ? 1 : 0] = world.positions(0);
    }
    ASSERT_EQ(final_state[0].size(), final_state[1].size());
    EXPECT_EQ(std::memcmp(final_state[0].data(), final_state[1].data(), final_state[0].size() * sizeof(Vec3d)), 0);
}

// preconditioner_refresh = 4 reuses the factors for four substeps: every solve still converges, to
// the same state as refactoring every substep (both solves to 1e-9).
TEST(SchwarzPreconditioner, ReusedFactorsStillConvergeToTheSameState) {
    std::vector<Vec3d> final_state[2];
    long iterations[2] = {0, 0};
    for (const int refresh : {1, 4}) {
        WorldDesc desc;
        desc.solver.preconditioner = Preconditioner::Schwarz;
        desc.solver.preconditioner_refresh = refresh;
        desc.solver.cg_tolerance = 1e-9;
        desc.solver.cg_max_iterations = 5000;
        desc.solver.substeps = 4;
        World world(desc, "cpu");
        ClothDesc cloth{.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 30, 30))};
        for (std::uint32_t i = 0; i <= 30; ++i) cloth.pins.push_back({.vertex = i});
        world.add_cloth(cloth);
        for (int frame = 0; frame < 10; ++frame) {
            const StepStats& stats = world.step();
            ASSERT_EQ(stats.cg_not_converged, 0) << "refresh " << refresh << ", frame " << frame;
            iterations[refresh == 4 ? 1 : 0] += stats.cg_iterations;
        }
        final_state[refresh == 4 ? 1 : 0] = world.positions(0);
    }
    std::printf("refresh 1: %ld CG iterations, refresh 4: %ld\n", iterations[0], iterations[1]);
    double largest = 0.0;
    for (std::size_t i = 0; i < final_state[0].size(); ++i)
        largest = std::max(largest, math::length(final_state[1][i] - final_state[0][i]));
    EXPECT_LT(largest, 1e-5);
    EXPECT_GT(largest, 0.0);  // the iterates did differ: the factors really were reused
}

// The Schwarz solve splits its work by domain and vertex with no reduction across tasks: the same
// bits on one thread and on three.
TEST(SchwarzPreconditioner, SameBitsOnOneAndThreeThreads) {
    std::vector<Vec3d> final_state[2];
    for (const int threads : {1, 3}) {
        WorldDesc desc;
        desc.solver.preconditioner = Preconditioner::Schwarz;
        desc.solver.threads = threads;
        World world(desc, "cpu");
        ClothDesc cloth{.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 60, 60))};
        for (std::uint32_t i = 0; i <= 60; ++i) cloth.pins.push_back({.vertex = i});
        world.add_cloth(cloth);
        for (int frame = 0; frame < 5; ++frame) (void)world.step();
        final_state[threads == 3 ? 1 : 0] = world.positions(0);
    }
    EXPECT_EQ(std::memcmp(final_state[0].data(), final_state[1].data(), final_state[0].size() * sizeof(Vec3d)), 0);
}

// The cloth matrix the implicit step solves, A = M + h²·K with K the membrane Hessian blocks
// (HessianKind::Fast, as the backends assemble) of a stiff sheet stretched and crumpled at random.
cpu::BsrMatrix<double> cloth_matrix(const Fabric& fabric, std::mt19937& rng) {
    cpu::BsrMatrix<double> A;
    const BlockPattern& p = fabric.pattern();
    A.resize(p);
    const double h = 1.0 / 60.0;
    std::normal_distribution<double> noise(0.0, 0.004);
    std::vector<Vec3d> x(fabric.rest_positions().begin(), fabric.rest_positions().end());
    for (Vec3d& q : x) q = 1.05 * q + Vec3d{noise(rng), noise(rng), noise(rng)};  // stretched 5 %, rumpled
    for (std::size_t i = 0; i < fabric.vertex_count(); ++i) A.set_block(p.diagonal[i], M3::diagonal(fabric.masses()[i]));
    const auto material = physics::membrane_material(2.0e4, 0.3);
    for (std::size_t t = 0; t < fabric.triangle_count(); ++t) {
        const auto& v = fabric.triangles()[t].v;
        const Vec3d xs[3] = {x[v[0]], x[v[1]], x[v[2]]};
        const TriangleRest& r = fabric.triangle_rest()[t];
        M3 H[3][3];
        (void)physics::membrane_evaluate<double>(r.dm_inv, r.area, material, xs, nullptr, H, physics::HessianKind::Fast);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                const std::size_t s = p.triangle_slots[9 * t + 3 * a + b];
                A.set_block(s, A.block(s) + (h * h) * H[a][b]);
            }
    }
    return A;
}

// The SPD checks on the matrix the backends assemble, with a pinned edge: symmetric, positive,
// and its PCG reaches block-Jacobi's solution in fewer iterations.
TEST(SchwarzPreconditioner, OnAnAssembledClothMatrix) {
    const auto fabric = Fabric::cook(make_grid(1.0, 1.0, 59, 59), {.density = 0.1});
    std::mt19937 rng(23);
    const auto A = cloth_matrix(*fabric, rng);
    const std::size_t n = fabric->vertex_count();
    std::vector<std::uint8_t> fixed(n, 0);
    for (std::size_t i = 0; i < 60; ++i) fixed[i] = 1;
    const SchwarzHierarchy h = build_schwarz_hierarchy(rest_positions(*fabric), fabric->pattern());
    cpu::SchwarzPreconditioner<double> M;
    M.build(h, fabric->pattern());
    M.factor(A, fixed, [](std::size_t) { return M3{}; });
    EXPECT_EQ(M.pivot_failures(), 0);
    expect_spd_on_free_vertices(M, fixed, rng, 4, "cloth matrix");
    const auto b = random_vectors(n, rng);
    std::vector<V3> xj(n), xs(n);
    cpu::Pcg<double> pcg;
    pcg.resize(n);
    const auto rj = pcg.solve(A, b, fixed, xj, 1e-9, 20000);
    const auto rs = pcg.solve(A, b, fixed, xs, 1e-9, 20000, &M);
    ASSERT_TRUE(rj.converged);
    ASSERT_TRUE(rs.converged);
    double difference = 0.0, scale = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        difference = std::max(difference, math::length(xs[i] - xj[i]));
        scale = std::max(scale, math::length(xj[i]));
    }
    std::printf("cloth matrix, 3,600 vertices: jacobi %d, schwarz %d iterations, relative difference %.2e\n",
                rj.iterations, rs.iterations, difference / scale);
    EXPECT_LT(difference, 1e-6 * scale);
    EXPECT_LT(rs.iterations, rj.iterations);
}

// A 3D block Laplacian (a 16³ lattice, 6 neighbours): Morton order in 3D, the same guarantees.
TEST(SchwarzPreconditioner, OnA3dLaplacian) {
    constexpr int kSide = 16;
    const auto id = [](int i, int j, int k) { return static_cast<std::uint32_t>((k * kSide + j) * kSide + i); };
    const std::size_t n = kSide * kSide * kSide;
    std::vector<Vec3d> x(n);
    BlockPattern p;
    p.row_start.push_back(0);
    for (int k = 0; k < kSide; ++k)
        for (int j = 0; j < kSide; ++j)
            for (int i = 0; i < kSide; ++i) {
                x[id(i, j, k)] = Vec3d{double(i), double(j), double(k)};
                std::vector<std::uint32_t> cols{id(i, j, k)};
                if (i > 0) cols.push_back(id(i - 1, j, k));
                if (i + 1 < kSide) cols.push_back(id(i + 1, j, k));
                if (j > 0) cols.push_back(id(i, j - 1, k));
                if (j + 1 < kSide) cols.push_back(id(i, j + 1, k));
                if (k > 0) cols.push_back(id(i, j, k - 1));
                if (k + 1 < kSide) cols.push_back(id(i, j, k + 1));
                std::sort(cols.begin(), cols.end());
                for (const std::uint32_t c : cols) {
                    if (c == id(i, j, k)) p.diagonal.push_back(static_cast<std::uint32_t>(p.column.size()));
                    p.column.push_back(c);
                }
                p.row_start.push_back(static_cast<std::uint32_t>(p.column.size()));
            }
    cpu::BsrMatrix<double> A;
    A.resize(p);
    for (std::size_t r = 0; r < n; ++r) {
        double degree = 0.0;
        for (std::uint32_t s = p.row_start[r]; s < p.row_start[r + 1]; ++s)
            if (p.column[s] != r) {
                A.set_block(s, M3::diagonal(-10.0));
                degree += 1.0;
            }
        A.set_block(p.diagonal[r], M3::diagonal(1e-3 + 10.0 * degree));
    }
    const SchwarzHierarchy h = build_schwarz_hierarchy(x, p);
    EXPECT_GE(h.levels(), 3);
    cpu::SchwarzPreconditioner<double> M;
    M.build(h, p);
    const std::vector<std::uint8_t> fixed(n, 0);
    M.factor(A, fixed, [](std::size_t) { return M3{}; });
    EXPECT_EQ(M.pivot_failures(), 0);
    std::mt19937 rng(31);
    expect_spd_on_free_vertices(M, fixed, rng, 3, "3D Laplacian");
    const auto b = random_vectors(n, rng);
    std::vector<V3> xj(n), xs(n);
    cpu::Pcg<double> pcg;
    pcg.resize(n);
    const auto rj = pcg.solve(A, b, fixed, xj, 1e-8, 20000);
    const auto rs = pcg.solve(A, b, fixed, xs, 1e-8, 20000, &M);
    ASSERT_TRUE(rj.converged);
    ASSERT_TRUE(rs.converged);
    std::printf("3D Laplacian 16^3: jacobi %d, schwarz %d iterations\n", rj.iterations, rs.iterations);
    EXPECT_LT(rs.iterations, rj.iterations);
}

// A preconditioner that is not SPD (factored from an indefinite matrix: the Laplacian shifted down
// by its stiffness, or by three times it) makes rᵀM⁻¹r useless as the stopping norm: the solve must
// say so (PcgResult::preconditioner_failed) instead of reporting convergence, so that the solver
// can solve again with block-Jacobi. One factored from the system itself is not flagged.
TEST(SchwarzPreconditioner, APreconditionerThatIsNotSpdIsReportedNotTakenForConvergence) {
    const auto fabric = Fabric::cook(make_grid(1.0, 1.0, 39, 39));
    const auto A = stiff_laplacian(*fabric, 1e-3, 10.0);
    const std::size_t n = fabric->vertex_count();
    std::mt19937 rng(5);
    const auto b = random_vectors(n, rng);
    const std::vector<std::uint8_t> fixed(n, 0);
    const SchwarzHierarchy h = build_schwarz_hierarchy(rest_positions(*fabric), fabric->pattern());
    cpu::Pcg<double> pcg;
    pcg.resize(n);
    for (const double shift : {0.0, 1.0, 3.0}) {
        SCOPED_TRACE("shift " + std::to_string(shift));
        const auto factored_from = shift == 0.0 ? A : stiff_laplacian(*fabric, -shift * 10.0, 10.0);
        cpu::SchwarzPreconditioner<double> M;
        M.build(h, fabric->pattern());
        M.factor(factored_from, fixed, [](std::size_t) { return M3{}; });
        std::vector<V3> x(n);
        const cpu::PcgResult r = pcg.solve(A, b, fixed, x, 1e-4, 500, &M);
        if (shift == 0.0) {
            EXPECT_TRUE(r.converged);
            EXPECT_FALSE(r.preconditioner_failed);
        } else {
            EXPECT_GT(M.pivot_failures(), 0);
            EXPECT_TRUE(r.preconditioner_failed);
            EXPECT_FALSE(r.converged);
        }
    }
}

}  // namespace
}  // namespace weft
