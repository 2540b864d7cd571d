// Cooking: hinges, masses, block pattern and the handling of bad meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "weft/error.h"
#include "weft/fabric.h"
#include "weft/mesh.h"

namespace weft {
namespace {

TEST(Fabric, GridHasExpectedTopologyAndMass) {
    const int nx = 6, ny = 4;
    auto fabric = Fabric::cook(make_grid(1.2, 0.8, nx, ny), {.density = 0.25});
    EXPECT_EQ(fabric->vertex_count(), std::size_t((nx + 1) * (ny + 1)));
    EXPECT_EQ(fabric->triangle_count(), std::size_t(2 * nx * ny));
    // Interior edges of a triangulated grid: horizontal + vertical interior + one diagonal per cell.
    const std::size_t interior = std::size_t(nx * (ny - 1) + ny * (nx - 1) + nx * ny);
    EXPECT_EQ(fabric->hinges().size(), interior);
    double mass = 0.0;
    for (double m : fabric->masses()) mass += m;
    EXPECT_NEAR(mass, 0.25 * 1.2 * 0.8, 1e-12);
    EXPECT_NEAR(fabric->total_area(), 1.2 * 0.8, 1e-12);
    for (const Hinge& h : fabric->hinges()) EXPECT_NEAR(h.rest_angle, 0.0, 1e-12);
    EXPECT_TRUE(fabric->report().warnings.empty());
}

TEST(Fabric, PatternIsSymmetricSortedAndSlotsPointAtTheRightBlocks) {
    auto fabric = Fabric::cook(make_grid(1.0, 1.0, 5, 7, GridPlane::XZ));
    const BlockPattern& p = fabric->pattern();
    std::set<std::pair<std::uint32_t, std::uint32_t>> entries;
    for (std::uint32_t i = 0; i + 1 < p.row_start.size(); ++i) {
        EXPECT_TRUE(std::is_sorted(p.column.begin() + p.row_start[i], p.column.begin() + p.row_start[i + 1]));
        EXPECT_EQ(p.column[p.diagonal[i]], i);
        for (std::uint32_t s = p.row_start[i]; s < p.row_start[i + 1]; ++s) entries.insert({i, p.column[s]});
    }
    for (auto [i, j] : entries) EXPECT_TRUE(entries.count({j, i})) << i << "," << j;
    const auto row_of = [&](std::uint32_t slot) {
        return std::uint32_t(std::upper_bound(p.row_start.begin(), p.row_start.end(), slot) - p.row_start.begin() - 1);
    };
    for (std::size_t t = 0; t < fabric->triangle_count(); ++t)
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                const std::uint32_t s = p.triangle_slots[t * 9 + std::size_t(a * 3 + b)];
                EXPECT_EQ(row_of(s), fabric->triangles()[t].v[a]);
                EXPECT_EQ(p.column[s], fabric->triangles()[t].v[b]);
            }
    for (std::size_t k = 0; k < fabric->hinges().size(); ++k)
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
                const std::uint32_t s = p.hinge_slots[k * 16 + std::size_t(a * 4 + b)];
                EXPECT_EQ(row_of(s), fabric->hinges()[k].v[a]);
                EXPECT_EQ(p.column[s], fabric->hinges()[k].v[b]);
            }
}

TEST(Fabric, FoldedRestShapeKeepsItsRestAngles) {
    // Two triangles folded by 90° about the x axis: the hinge's rest angle must be ±π/2, and with
    // flat_rest_bending it must be 0.
    MeshData m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0, 1}};
    m.triangles = {{{0, 1, 2}}, {{1, 0, 3}}};
    auto folded = Fabric::cook(m);
    ASSERT_EQ(folded->hinges().size(), 1u);
    EXPECT_NEAR(std::abs(folded->hinges()[0].rest_angle), 3.14159265358979 / 2, 1e-9);
    auto flat = Fabric::cook(m, {.density = 0.2, .flat_rest_bending = true});
    EXPECT_EQ(flat->hinges()[0].rest_angle, 0.0);
}

TEST(Fabric, DegenerateDuplicateAndUnreferencedAreDroppedAndReported) {
    MeshData m = make_grid(1.0, 1.0, 2, 2);
    m.source = "test-mesh";
    m.triangles.push_back({{0, 1, 2}});      // collinear: zero area
    m.triangles.push_back({{4, 4, 5}});      // repeated index
    m.triangles.push_back(m.triangles[0]);   // duplicate
    m.positions.push_back({9, 9, 9});        // unreferenced
    auto fabric = Fabric::cook(m);
    EXPECT_EQ(fabric->triangle_count(), 8u);
    EXPECT_EQ(fabric->vertex_count(), 9u);
    EXPECT_EQ(fabric->report().degenerate_triangles, 2u);
    EXPECT_EQ(fabric->report().duplicate_triangles, 1u);
    EXPECT_EQ(fabric->report().unreferenced_vertices, 1u);
    EXPECT_EQ(fabric->report().warnings.size(), 3u);
}

TEST(Fabric, NonManifoldEdgeGetsNoHingeAndIsReported) {
    MeshData m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}, {0.5, 0, 1}};
    m.triangles = {{{0, 1, 2}}, {{1, 0, 3}}, {{0, 1, 4}}};
    auto fabric = Fabric::cook(m);
    EXPECT_EQ(fabric->report().non_manifold_edges, 1u);
    EXPECT_TRUE(fabric->hinges().empty());
}

TEST(Fabric, UnusableMeshesThrowNamingTheSource) {
    MeshData empty;
    empty.source = "empty.obj";
    try {
        (void)Fabric::cook(empty);
        FAIL() << "expected an error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("empty.obj"), std::string::npos);
    }
    MeshData bad = make_grid(1, 1, 1, 1);
    bad.source = "bad.ply";
    bad.triangles[0].v[2] = 99;
    EXPECT_THROW((void)Fabric::cook(bad), Error);
    MeshData nan = make_grid(1, 1, 1, 1);
    nan.positions[1].x = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW((void)Fabric::cook(nan), Error);
    MeshData flat;
    flat.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    flat.triangles = {{{0, 1, 2}}};
    EXPECT_THROW((void)Fabric::cook(flat), Error);
    EXPECT_THROW((void)Fabric::cook(make_grid(1, 1, 2, 2), {.density = -1.0}), Error);
    EXPECT_THROW((void)make_grid(0.0, 1.0, 2, 2), Error);
    EXPECT_THROW((void)make_grid(1.0, 1.0, 0, 2), Error);
}

}  // namespace
}  // namespace weft
