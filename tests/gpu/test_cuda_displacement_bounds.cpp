// The displacement bounds and the truncation on the GPU (cuda/src/collision/displacement_bounds_gpu.h)
// against the CPU reference (runtime/src/collision/displacement_bounds.h) on the same
// float-representable positions and per-vertex radii: the same pairs measured (up to pairs whose
// distance lies within float rounding of a radius), every bound and reach within float rounding of
// the CPU's, truncated moves within rounding of the CPU's kept share (planar and sphere), and the
// GPU-truncated state free of intersections under the exact check while the untruncated one is not.
// Prescribed vertices are never moved, only counted. Every test skips without a GPU.
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "collision/broad_phase_gpu.h"
#include "collision/displacement_bounds.h"
#include "collision/displacement_bounds_gpu.h"
#include "collision/intersection_check.h"
#include "device_array.h"
#include "displacement_soups.h"
#include "float_positions.h"
#include "gpu_test_util.h"
#include "weft/backend/collision_primitives.h"

namespace weft {
namespace {

namespace gpu = cuda::collision;
using cuda::DeviceArray;
using cuda::MemoryLedger;

struct Case {
    test::Soup soup;
    std::vector<Vec3d> x1;        // proposed positions
    std::vector<double> radius;   // r_v
};

/// Positions rounded to float (the device's input), a random radius per vertex in [reach, 2·reach]
/// and random moves of up to `reach`.
Case make_case(test::Soup soup, std::mt19937& rng, double reach) {
    for (Vec3d& p : soup.x)
        for (int k = 0; k < 3; ++k) p[k] = static_cast<double>(static_cast<float>(p[k]));
    Case c{std::move(soup), {}, {}};
    c.x1 = test::random_moves(c.soup.x, rng, reach);
    for (Vec3d& p : c.x1)
        for (int k = 0; k < 3; ++k) p[k] = static_cast<double>(static_cast<float>(p[k]));
    std::uniform_real_distribution<double> u(reach, 2.0 * reach);
    for (std::size_t v = 0; v < c.soup.x.size(); ++v) c.radius.push_back(static_cast<double>(static_cast<float>(u(rng))));
    return c;
}

std::vector<std::uint32_t> flat_triangles(const std::vector<Triangle>& t) {
    std::vector<std::uint32_t> out;
    for (const Triangle& tri : t) out.insert(out.end(), tri.v, tri.v + 3);
    return out;
}
std::vector<std::uint32_t> flat_edges(const std::vector<collision::Edge>& e) {
    std::vector<std::uint32_t> out;
    for (const collision::Edge& edge : e) out.insert(out.end(), edge.v, edge.v + 2);
    return out;
}

struct GpuRun {
    std::vector<float> bound, reach;
    std::vector<Vec3d> truncated;
    gpu::GpuBoundsCounters counters;
};

/// Bounds at c.soup.x and the truncation of c.x1 on the device; `prescribed` marks vertices that may
/// not be shortened.
GpuRun run_gpu(const Case& c, double relaxation, bool planar, const std::vector<std::uint8_t>& prescribed = {}) {
    test::Stream stream;
    MemoryLedger ledger;
    const std::size_t n = c.soup.x.size();
    const std::vector<collision::Edge> edges = collision::build_edges(c.soup.triangles);
    DeviceArray<float> x, x0, v, radius;
    DeviceArray<std::uint32_t> tri, edge;
    DeviceArray<std::uint8_t> fixed;
    x.upload(test::soa_floats(c.soup.x), ledger, "x");
    x0.upload(test::soa_floats(c.soup.x), ledger, "x0");
    // With x0 = x_detect and h = 1 the velocity is the move itself.
    std::vector<Vec3d> moves(n);
    for (std::size_t i = 0; i < n; ++i) moves[i] = c.x1[i] - c.soup.x[i];
    v.upload(test::soa_floats(moves), ledger, "v");
    std::vector<float> r(c.radius.begin(), c.radius.end());
    radius.upload(r, ledger, "radius");
    tri.upload(flat_triangles(c.soup.triangles), ledger, "tri");
    edge.upload(flat_edges(edges), ledger, "edges");
    if (!prescribed.empty()) fixed.upload(prescribed, ledger, "prescribed");

    gpu::GpuBroadPhase hash;
    gpu::GpuDisplacementBounds bounds;
    gpu::GpuBoundsInput in;
    in.x = x.get();
    in.vertex_count = static_cast<std::uint32_t>(n);
    in.triangles = tri.get();
    in.triangle_count = static_cast<std::uint32_t>(c.soup.triangles.size());
    in.edges = edge.get();
    in.edge_count = static_cast<std::uint32_t>(edges.size());
    in.radius = radius.get();
    in.relaxation = static_cast<float>(relaxation);
    bounds.compute(in, hash, stream.s);
    gpu::GpuTruncateInput t;
    t.x_detect = x.get();
    t.x0 = x0.get();
    t.v = v.get();
    t.vertex_count = static_cast<std::uint32_t>(n);
    t.prescribed = prescribed.empty() ? nullptr : fixed.get();
    t.planar = planar;
    bounds.truncate(t, stream.s);
    GpuRun out;
    out.counters = bounds.read_back(stream.s);
    bounds.download(out.bound, out.reach, stream.s);
    std::vector<float> moved(3 * n);
    WEFT_CUDA_CHECK(cudaMemcpy(moved.data(), v.get(), moved.size() * sizeof(float), cudaMemcpyDeviceToHost));
    out.truncated.resize(n);
    for (std::size_t i = 0; i < n; ++i)
        out.truncated[i] = c.soup.x[i] + Vec3d{moved[i], moved[n + i], moved[2 * n + i]};
    return out;
}

collision::DisplacementBounds run_cpu(const Case& c, double relaxation) {
    const std::vector<collision::Edge> edges = collision::build_edges(c.soup.triangles);
    collision::BroadPhase hash;
    collision::DisplacementBounds b;
    collision::compute_displacement_bounds(
        {.x = c.soup.x, .triangles = c.soup.triangles, .edges = edges, .radius = c.radius, .relaxation = relaxation}, hash, b);
    return b;
}

// Bounds, reach and pair counts agree; both truncations keep the CPU's share of every move up to
// float rounding; the GPU-truncated states are intersection-free.
TEST(CudaDisplacementBounds, AgreeWithTheCpuAndNeverIntersect) {
    WEFT_REQUIRE_GPU();
    std::mt19937 rng(23);
    const double gamma = 0.45;
    int untruncated_intersecting = 0;
    for (int trial = 0; trial < 4; ++trial) {
        const bool sheets = trial % 2 == 0;
        const double reach = sheets ? 0.05 : 0.1;
        const Case c = make_case(sheets ? test::stacked_sheets(4, 16, 0.01) : test::clean_soup(rng, 250, 0.04, 0.4), rng, reach);
        ASSERT_TRUE(collision::check_intersections(c.soup.x, c.soup.triangles).clean()) << "trial " << trial;
        untruncated_intersecting += collision::check_intersections(c.x1, c.soup.triangles).clean() ? 0 : 1;
        const collision::DisplacementBounds cpu = run_cpu(c, gamma);
        for (const bool planar : {true, false}) {
            const GpuRun g = run_gpu(c, gamma, planar);
            const std::size_t measured = g.counters.measured_vf + g.counters.measured_ee;
            const std::size_t expected = cpu.vf_pairs + cpu.ee_pairs;
            EXPECT_NEAR(static_cast<double>(measured), static_cast<double>(expected), 0.002 * static_cast<double>(expected) + 2.0)
                << "trial " << trial;
            std::size_t truncated_cpu = 0;
            for (std::size_t v = 0; v < c.soup.x.size(); ++v) {
                const double tolerance = 1e-5 * cpu.reach[v] + 1e-7;
                ASSERT_NEAR(g.bound[v], cpu.bound[v], tolerance) << "trial " << trial << " vertex " << v;
                ASSERT_NEAR(g.reach[v], cpu.reach[v], tolerance) << "trial " << trial << " vertex " << v;
                const Vec3d move = c.x1[v] - c.soup.x[v];
                const double share = collision::kept_share(cpu, v, move, planar);
                truncated_cpu += share < 1.0 ? 1 : 0;
                const double kept = math::length(g.truncated[v] - c.soup.x[v]);
                ASSERT_NEAR(kept, share * math::length(move), 1e-4 * math::length(move) + 1e-6)
                    << "trial " << trial << (planar ? " planar" : " sphere") << " vertex " << v;
            }
            EXPECT_NEAR(static_cast<double>(g.counters.truncated), static_cast<double>(truncated_cpu),
                        0.002 * static_cast<double>(truncated_cpu) + 2.0);
            EXPECT_GT(g.counters.truncated, 0u);
            const collision::IntersectionReport after = collision::check_intersections(g.truncated, c.soup.triangles);
            EXPECT_TRUE(after.clean()) << "trial " << trial << (planar ? " planar: " : " sphere: ")
                                       << after.intersecting_pairs << " pairs intersect";
            std::printf("trial %d %s: %zu pairs measured (cpu %zu), %u of %zu vertices truncated (cpu %zu)\n", trial,
                        planar ? "planar" : "sphere", measured, expected, g.counters.truncated, c.soup.x.size(),
                        truncated_cpu);
        }
    }
    EXPECT_GE(untruncated_intersecting, 2) << "the untruncated moves must intersect for the test to mean anything";
}

// A prescribed vertex keeps its move even beyond its bound; the breach is counted.
TEST(CudaDisplacementBounds, PrescribedVerticesAreCountedNotMoved) {
    WEFT_REQUIRE_GPU();
    std::mt19937 rng(4);
    const Case c = make_case(test::stacked_sheets(2, 8, 0.01), rng, 0.05);
    const collision::DisplacementBounds cpu = run_cpu(c, 0.45);
    std::vector<std::uint8_t> prescribed(c.soup.x.size(), 0);
    std::size_t breaking = 0;
    for (std::size_t v = 0; v < prescribed.size(); v += 3) {
        prescribed[v] = 1;
        breaking += collision::kept_share(cpu, v, c.x1[v] - c.soup.x[v], true) < 1.0 ? 1 : 0;
    }
    ASSERT_GT(breaking, 0u);
    const GpuRun g = run_gpu(c, 0.45, true, prescribed);
    EXPECT_NEAR(static_cast<double>(g.counters.broken), static_cast<double>(breaking), 2.0);
    for (std::size_t v = 0; v < prescribed.size(); v += 3)
        EXPECT_NEAR(math::length(g.truncated[v] - c.x1[v]), 0.0, 1e-6) << "prescribed vertex " << v << " moved";
}

}  // namespace
}  // namespace weft
