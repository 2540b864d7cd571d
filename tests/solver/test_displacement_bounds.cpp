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
