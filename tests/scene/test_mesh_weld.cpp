// weld_by_position: merges within the tolerance into the lowest index, remaps triangles, drops
// unreferenced vertices, and agrees with a brute-force reference.
#include <random>

#include "scene_test_util.h"

namespace weft {
namespace {

using test::expect_error;

// Two triangles of a unit square, cut apart along the diagonal like an importer's UV seam.
MeshData split_square() {
    MeshData m;
    m.source = "split square";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    m.triangles = {{{0, 1, 2}}, {{3, 4, 5}}};
    return m;
}

TEST(MeshWeld, MergesSeamIntoLowestIndex) {
    MeshData m = split_square();
    EXPECT_EQ(weld_by_position(m, 1e-9), 2U);
    EXPECT_EQ(m.welded_vertices, 2U);
    ASSERT_EQ(m.positions.size(), 4U);
    EXPECT_EQ(m.positions[3], (Vec3d{0, 1, 0}));
    EXPECT_EQ(m.triangles[0].v[0], 0U);
    EXPECT_EQ(m.triangles[1].v[0], 0U);  // vertex 3 became 0
    EXPECT_EQ(m.triangles[1].v[1], 2U);  // vertex 4 became 2
    EXPECT_EQ(m.triangles[1].v[2], 3U);  // vertex 5 moved down after compaction
}

TEST(MeshWeld, RespectsTolerance) {
    MeshData m = split_square();
    m.positions[3] = {1e-3, 0, 0};
    EXPECT_EQ(weld_by_position(m, 1e-4), 1U);  // only 4 ↔ 2 merges
    EXPECT_EQ(m.positions.size(), 5U);
    MeshData n = split_square();
    n.positions[3] = {1e-3, 0, 0};
    EXPECT_EQ(weld_by_position(n, 2e-3), 2U);  // now both
}

TEST(MeshWeld, ZeroToleranceMergesExactDuplicatesOnly) {
    MeshData m = split_square();
    m.positions[4] = {1, 1, 1e-12};
    EXPECT_EQ(weld_by_position(m, 0.0), 1U);
    EXPECT_EQ(m.positions.size(), 5U);
}

TEST(MeshWeld, DropsUnreferencedVertices) {
    MeshData m = split_square();
    m.positions.push_back({7, 7, 7});
    EXPECT_EQ(weld_by_position(m, 1e-9), 3U);
    EXPECT_EQ(m.welded_vertices, 2U);  // the dropped vertex was not welded
    EXPECT_EQ(m.positions.size(), 4U);
}

TEST(MeshWeld, Errors) {
    MeshData m = split_square();
    m.triangles[1].v[2] = 6;
    expect_error([&] { (void)weld_by_position(m, 1e-6); }, {"split square", "triangle 1", "vertex 6"});
    MeshData n = split_square();
    expect_error([&] { (void)weld_by_position(n, -1.0); }, {"split square", "tolerance"});
}

TEST(MeshWeld, MatchesBruteForceAndIsDeterministic) {
    // Random points on a coarse lattice with jitter, so that many pairs sit near the tolerance.
    std::mt19937 rng(1234);
    std::uniform_int_distribution<int> cell(0, 30);
    std::uniform_real_distribution<double> jitter(-0.6, 0.6);
    const double tol = 0.01;
    MeshData m;
    m.source = "random";
    for (int i = 0; i < 3000; ++i)
        m.positions.push_back({cell(rng) * 0.02 + jitter(rng) * tol, cell(rng) * 0.02 + jitter(rng) * tol,
                               cell(rng) * 0.02 + jitter(rng) * tol});
    for (std::uint32_t i = 0; i + 2 < m.positions.size(); i += 3) m.triangles.push_back({{i, i + 1, i + 2}});

    // Reference: visit in order; merge into the lowest earlier representative within tol.
    std::vector<std::uint32_t> reps, target(m.positions.size());
    for (std::uint32_t i = 0; i < m.positions.size(); ++i) {
        target[i] = i;
        for (std::uint32_t r : reps)
            if (math::length_squared(m.positions[r] - m.positions[i]) <= tol * tol) {
                target[i] = r;
                break;
            }
        if (target[i] == i) reps.push_back(i);
    }
    std::vector<Vec3d> expected_corners;
    for (const Triangle& t : m.triangles)
        for (std::uint32_t v : t.v) expected_corners.push_back(m.positions[target[v]]);

    MeshData a = m, b = m;
    const std::size_t removed = weld_by_position(a, tol);
    EXPECT_EQ(a.positions.size(), reps.size());
    EXPECT_EQ(removed, m.positions.size() - reps.size());
    EXPECT_GT(removed, 0U);
    std::size_t k = 0;
    for (const Triangle& t : a.triangles)
        for (std::uint32_t v : t.v) EXPECT_EQ(a.positions[v], expected_corners[k++]);
    (void)weld_by_position(b, tol);
    EXPECT_EQ(a.positions, b.positions);
}

}  // namespace
}  // namespace weft
