// Per-vertex conservative displacement bounds (collision/displacement_bounds.h; docs/methods.md §7b):
// the bounds equal a brute-force search's, and no update truncated to them makes an intersection
// (stacked sheets and random triangle soups, checked by the exact triangle test), while the same
// updates untruncated do.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <random>
#include <span>
#include <vector>

#include "collision/displacement_bounds.h"
#include "displacement_soups.h"
#include "collision/intersection_check.h"
#include "collision/normal_cone_front.h"
#include "sheet_deformations.h"
#include "weft/backend/patch_hierarchy.h"
#include "weft/error.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/physics/proximity.h"

namespace weft::collision {
namespace {

using test::random_moves;
using test::Soup;
using test::stacked_sheets;

Soup random_soup(std::mt19937& rng, int count, double size, double extent) {
    return test::clean_soup(rng, count, size, extent);
}

DisplacementBounds bounds_of(const Soup& s, double radius, double relaxation = 0.45,
                             std::span<const double> radii = {}) {
    const std::vector<Edge> edges = build_edges(s.triangles);
    BroadPhase hash;
    DisplacementBounds b;
    compute_displacement_bounds({.x = s.x, .triangles = s.triangles, .edges = edges, .query_radius = radius,
                                 .radius = radii, .relaxation = relaxation},
                                hash, b);
    return b;
}

/// Each vertex's bound by brute force: γ·min(r_v, distance to the nearest pair it belongs to that is
/// within the largest radius of the pair's four vertices).
std::vector<double> brute_force_bounds(const Soup& s, std::span<const double> radius, double gamma) {
    std::vector<double> nearest(radius.begin(), radius.end());
    const auto limit = [&](double d, std::initializer_list<std::uint32_t> vertices) {
        double largest = 0.0;
        for (const std::uint32_t c : vertices) largest = std::max(largest, radius[c]);
        if (!(d < largest)) return;
        for (const std::uint32_t c : vertices) nearest[c] = std::min(nearest[c], d);
    };
    const auto shares = [](const Triangle& t, std::uint32_t v) { return t.v[0] == v || t.v[1] == v || t.v[2] == v; };
    for (std::uint32_t v = 0; v < s.x.size(); ++v)
        for (const Triangle& t : s.triangles) {
            if (shares(t, v)) continue;
            const double d = physics::point_triangle_proximity(s.x[v], s.x[t.v[0]], s.x[t.v[1]], s.x[t.v[2]]).distance;
            limit(d, {v, t.v[0], t.v[1], t.v[2]});
        }
    const std::vector<Edge> edges = build_edges(s.triangles);
    for (std::size_t i = 0; i < edges.size(); ++i)
        for (std::size_t j = i + 1; j < edges.size(); ++j) {
            const Edge &e = edges[i], &f = edges[j];
            if (e.v[0] == f.v[0] || e.v[0] == f.v[1] || e.v[1] == f.v[0] || e.v[1] == f.v[1]) continue;
            const double d = physics::edge_edge_proximity(s.x[e.v[0]], s.x[e.v[1]], s.x[f.v[0]], s.x[f.v[1]]).distance;
            limit(d, {e.v[0], e.v[1], f.v[0], f.v[1]});
        }
    for (double& b : nearest) b *= gamma;
    return nearest;
}

TEST(DisplacementBounds, EqualABruteForceSearch) {
    std::mt19937 rng(5);
    const Soup s = random_soup(rng, 120, 0.05, 0.4);
    const double r = 0.05, gamma = 0.45;
    const DisplacementBounds b = bounds_of(s, r, gamma);
    const std::vector<double> radius(s.x.size(), r);
    const std::vector<double> brute = brute_force_bounds(s, radius, gamma);
    std::size_t limited = 0;
    for (std::size_t v = 0; v < s.x.size(); ++v) {
        ASSERT_DOUBLE_EQ(b.bound[v], brute[v]) << "vertex " << v;
        ASSERT_DOUBLE_EQ(b.reach[v], gamma * r);
        limited += brute[v] < gamma * r ? 1 : 0;
    }
    EXPECT_EQ(b.limited_vertices, limited);
    EXPECT_GT(limited, s.x.size() / 4) << "the soup is dense enough to test something";
}

// Per-vertex radii (the padded broad phase): every pair within the largest radius of its vertices is
// found, and limits all four.
TEST(DisplacementBounds, PerVertexRadiiEqualABruteForceSearch) {
    std::mt19937 rng(8);
    const Soup s = random_soup(rng, 120, 0.05, 0.4);
    std::uniform_real_distribution<double> u(0.005, 0.08);
    std::vector<double> radius(s.x.size());
    for (double& r : radius) r = u(rng);
    const double gamma = 0.4;
    const DisplacementBounds b = bounds_of(s, 0.0, gamma, radius);
    const std::vector<double> brute = brute_force_bounds(s, radius, gamma);
    std::size_t limited = 0;
    for (std::size_t v = 0; v < s.x.size(); ++v) {
        ASSERT_DOUBLE_EQ(b.bound[v], brute[v]) << "vertex " << v;
        ASSERT_DOUBLE_EQ(b.reach[v], gamma * radius[v]);
        limited += brute[v] < gamma * radius[v] ? 1 : 0;
    }
    EXPECT_EQ(b.limited_vertices, limited);
    EXPECT_GT(limited, s.x.size() / 5);
}

// Both truncations, on the same moves: neither lets anything intersect, the planar one never keeps
// less of a move than the sphere one, and the test prints how much of the moves each keeps.
TEST(DisplacementBounds, TruncatedMovesNeverIntersect) {
    std::mt19937 rng(17);
    int untruncated_intersecting = 0;
    double kept[2] = {0.0, 0.0}, wanted = 0.0;
    for (int trial = 0; trial < 6; ++trial) {
        const bool sheets = trial % 2 == 0;
        const Soup s = sheets ? stacked_sheets(4, 16, 0.01) : random_soup(rng, 250, 0.04, 0.4);
        ASSERT_TRUE(check_intersections(s.x, s.triangles).clean()) << "trial " << trial << " starts clean";
        const double reach = sheets ? 0.05 : 0.1;
        const std::vector<Vec3d> x1 = random_moves(s.x, rng, reach);
        untruncated_intersecting += check_intersections(x1, s.triangles).clean() ? 0 : 1;
        // Trials 1 and 4: a radius per vertex, between the move and twice it.
        std::vector<double> radii;
        if (trial % 3 == 1) {
            std::uniform_real_distribution<double> u(reach, 2.0 * reach);
            for (std::size_t v = 0; v < s.x.size(); ++v) radii.push_back(u(rng));
        }
        const DisplacementBounds b = bounds_of(s, 2.0 * reach, 0.45, radii);
        std::vector<Vec3d> sphere = x1, planar = x1;
        EXPECT_GT(truncate_displacements(s.x, sphere, b.bound), 0u) << "trial " << trial;
        EXPECT_GT(truncate_displacements_planar(s.x, planar, b), 0u) << "trial " << trial;
        for (const auto* result : {&sphere, &planar}) {
            const IntersectionReport after = check_intersections(*result, s.triangles);
            EXPECT_TRUE(after.clean()) << "trial " << trial << (result == &sphere ? " sphere: " : " planar: ")
                                       << after.intersecting_pairs << " pairs intersect";
        }
        for (std::size_t v = 0; v < s.x.size(); ++v) {
            const double a = math::length(sphere[v] - s.x[v]), p = math::length(planar[v] - s.x[v]);
            ASSERT_LE(a, b.bound[v] * (1 + 1e-9) + 1e-15);  // rounding of x0 + move
            ASSERT_GE(p, a * (1 - 1e-9));
            kept[0] += a;
            kept[1] += p;
            wanted += math::length(x1[v] - s.x[v]);
        }
    }
    std::printf("share of the random moves kept: sphere bounds %.1f %%, planar bounds %.1f %%\n", 100.0 * kept[0] / wanted,
                100.0 * kept[1] / wanted);
    EXPECT_GE(untruncated_intersecting, 4) << "the untruncated moves must intersect for the test to mean anything";
}

// The certificate of the culled bound query: every culled patch must map into one certified patch.
TEST(DisplacementBounds, CulledPatchesHoldOnlyInsideOneCertifiedPatch) {
    const std::uint32_t none = kNoPatch;
    // Patches 7 and 9 become one certified patch 3: holds.
    EXPECT_TRUE(patches_hold(std::vector<std::uint32_t>{7, 7, 9, none}, std::vector<std::uint32_t>{3, 3, 3, 5}));
    // A culled primitive that lost its patch: a pair inside patch 7 is no longer certified.
    EXPECT_FALSE(patches_hold(std::vector<std::uint32_t>{7, 7, 9}, std::vector<std::uint32_t>{3, none, 4}));
    // Patch 7 split in two: a pair across the halves was culled but is not certified.
    EXPECT_FALSE(patches_hold(std::vector<std::uint32_t>{7, 7, 7}, std::vector<std::uint32_t>{3, 3, 4}));
    // Nothing was culled: nothing to certify.
    EXPECT_TRUE(patches_hold(std::vector<std::uint32_t>{none, none}, std::vector<std::uint32_t>{none, 1}));
    EXPECT_THROW((void)patches_hold(std::vector<std::uint32_t>{1}, std::vector<std::uint32_t>{}), Error);
}

// Culling the bound query by a front over one motion, then certifying it over the motion actually
// taken, against brute force: on folded and rolled sheets moved at random (small moves in the first
// three trials, where the patches hold; large ones after, where they fail and the solver would measure
// every pair), the pairs the culled query skipped are exactly the pairs inside one detection patch;
// whenever the patches hold over the truncated update, the truncated state is intersection-free.
TEST(DisplacementBounds, CulledQueryIsSafeWhereThePatchesHold) {
    std::mt19937 rng(31);
    int held = 0, failed = 0, culled_total = 0;
    for (int trial = 0; trial < 6; ++trial) {
        // A 24² sheet, folded (trials 0, 2, 4) or rolled, 1 m wide: 4 cm cells, radius 6 cm.
        const MeshData grid = make_grid(1.0, 1.0, 24, 24);
        Soup s{grid.positions, grid.triangles};
        for (Vec3d& p : s.x) {
            const Vec3d q{p.x + 0.5, p.y + 0.5, 0.0};
            p = trial % 2 == 0 ? test::fold(q, 0.3, 0.5, 2.6 + 0.1 * trial) : test::roll(q, 0.4, 0.08, 0.03);
        }
        const std::vector<Edge> edges = build_edges(s.triangles);
        PatchHierarchy hierarchy = build_patch_hierarchy(s.x, s.triangles, edges, {});
        NormalConeFront front(hierarchy);
        const std::vector<Vec3d> predicted = test::random_moves(s.x, rng, 0.002);
        front.update(s.x, predicted);
        std::vector<std::uint32_t> before;
        for (const auto span : {front.vertex_patch(), front.edge_patch(), front.triangle_patch()})
            before.insert(before.end(), span.begin(), span.end());
        const std::size_t nv = s.x.size(), ne = edges.size();
        const std::span<const std::uint32_t> ids(before);
        BroadPhase hash;
        DisplacementBounds culled, full;
        DisplacementBoundsInput in{.x = s.x, .triangles = s.triangles, .edges = edges, .query_radius = 0.06};
        compute_displacement_bounds(in, hash, full);
        in.vertex_patch = ids.subspan(0, nv);
        in.edge_patch = ids.subspan(nv, ne);
        in.triangle_patch = ids.subspan(nv + ne);
        compute_displacement_bounds(in, hash, culled);
        // Brute force: the measured pairs the culled query lacks are all inside one patch.
        std::size_t same_patch = 0;
        for (std::size_t k = 0; k < full.pairs.vf.size(); ++k) {
            if (!(full.vf_distance[k] < 0.06)) continue;
            const auto& p = full.pairs.vf[k];
            const bool inside = before[p.vertex] != kNoPatch && before[p.vertex] == before[nv + ne + p.triangle];
            same_patch += inside ? 1 : 0;
        }
        EXPECT_EQ(culled.vf_pairs + same_patch, full.vf_pairs) << "trial " << trial;
        culled_total += static_cast<int>(same_patch);
        // The actual update: a random move, truncated to the culled bounds, then certified.
        std::vector<Vec3d> x1 = test::random_moves(s.x, rng, trial < 3 ? 0.003 : 0.03);
        (void)truncate_displacements_planar(s.x, x1, culled);
        front.update(s.x, x1);
        std::vector<std::uint32_t> after;
        for (const auto span : {front.vertex_patch(), front.edge_patch(), front.triangle_patch()})
            after.insert(after.end(), span.begin(), span.end());
        if (!patches_hold(before, after)) {
            ++failed;
            continue;
        }
        ++held;
        const IntersectionReport report = check_intersections(x1, s.triangles);
        EXPECT_TRUE(report.clean()) << "trial " << trial << ": " << report.intersecting_pairs << " pairs intersect";
    }
    std::printf("culled bound query: %d vertex-face pairs culled, patches held in %d of %d updates\n", culled_total, held,
                held + failed);
    EXPECT_GT(culled_total, 0) << "the culling must skip something for the test to mean anything";
    EXPECT_GT(held, 0);
}

TEST(DisplacementBounds, RejectBadInput) {
    const Soup s = stacked_sheets(1, 2, 0.01);
    EXPECT_THROW((void)bounds_of(s, 0.0), Error);
    EXPECT_THROW((void)bounds_of(s, 0.01, 0.5), Error);
    EXPECT_THROW((void)bounds_of(s, 0.01, 0.0), Error);
    const std::vector<double> short_radii(s.x.size() - 1, 0.1), zero_radii(s.x.size(), 0.0);
    EXPECT_THROW((void)bounds_of(s, 0.01, 0.45, short_radii), Error);
    EXPECT_THROW((void)bounds_of(s, 0.01, 0.45, zero_radii), Error);
    std::vector<Vec3d> x1 = s.x;
    const std::vector<double> short_bounds(s.x.size() - 1, 0.1);
    EXPECT_THROW((void)truncate_displacements(s.x, x1, short_bounds), Error);
    EXPECT_THROW((void)truncate_displacements_planar(s.x, x1, DisplacementBounds{}), Error);
}

}  // namespace
}  // namespace weft::collision
