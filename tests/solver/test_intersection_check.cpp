// Whole-mesh exact intersection check: flat and folded grids are clean, a vertex pushed through the
// other layer of a fold is caught, the grid broad phase finds exactly what brute force over all pairs
// finds on random soups (with shared vertices, touching lattice triangles, huge and non-finite
// triangles), and a 200K-triangle sheet is timed (printed, not asserted).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "collision/intersection_check.h"
#include "collision/world_check.h"
#include "weft/fabric.h"
#include "weft/world.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/physics/triangle_intersection.h"

namespace weft::collision {
namespace {

// All intersecting pairs by brute force over every pair (same exclusion of shared vertices).
std::vector<IntersectingPair> brute_force(const std::vector<Vec3d>& x, const std::vector<Triangle>& tris) {
    std::vector<IntersectingPair> out;
    const auto finite = [&](const Triangle& t) {
        return physics::is_finite(x[t.v[0]]) && physics::is_finite(x[t.v[1]]) && physics::is_finite(x[t.v[2]]);
    };
    for (std::uint32_t i = 0; i < tris.size(); ++i) {
        if (!finite(tris[i])) continue;
        for (std::uint32_t j = i + 1; j < tris.size(); ++j) {
            if (!finite(tris[j])) continue;
            bool shared = false;
            for (const std::uint32_t u : tris[i].v)
                for (const std::uint32_t w : tris[j].v) shared = shared || u == w;
            if (shared) continue;
            const Vec3d a[3] = {x[tris[i].v[0]], x[tris[i].v[1]], x[tris[i].v[2]]};
            const Vec3d b[3] = {x[tris[j].v[0]], x[tris[j].v[1]], x[tris[j].v[2]]};
            if (physics::triangles_intersect(a, b)) out.push_back({i, j});
        }
    }
    return out;
}

IntersectionReport check_all(const std::vector<Vec3d>& x, const std::vector<Triangle>& tris) {
    return check_intersections(x, tris, {.max_examples = std::size_t(1) << 30});
}

TEST(IntersectionCheck, FlatGridsAreClean) {
    for (const GridPlane plane : {GridPlane::XY, GridPlane::XZ}) {
        const MeshData m = make_grid(1.0, 0.7, 30, 21, plane);
        const IntersectionReport r = check_intersections(m.positions, m.triangles);
        EXPECT_TRUE(r.clean());
        EXPECT_EQ(r.intersecting_pairs, 0u);
        EXPECT_TRUE(r.examples.empty());
        EXPECT_EQ(r.triangles_checked, m.triangles.size());
        EXPECT_GT(r.candidate_pairs, 0u);  // neighbours two cells apart are tested, and found apart
        EXPECT_EQ(r.nonfinite_triangles, 0u);
    }
}

// A 2 × 1 m sheet folded in half over the line x = 0: the half x > 0 is laid back over the other one,
// mirrored, at height `gap`. The crease column stays at z = 0, so the two layers meet only there, in
// shared vertices. Vertex (i, j) has index j·(nx+1) + i.
MeshData folded_sheet(int nx, int ny, double gap) {
    MeshData m = make_grid(2.0, 1.0, nx, ny, GridPlane::XY);
    for (Vec3d& p : m.positions)
        if (p.x > 0.0) p = Vec3d{-p.x, p.y, gap};
    return m;
}

TEST(IntersectionCheck, FoldedSheetIsCleanUntilAVertexIsPushedThroughTheOtherLayer) {
    const int nx = 40, ny = 20;
    MeshData m = folded_sheet(nx, ny, 0.05);
    EXPECT_TRUE(check_intersections(m.positions, m.triangles).clean());

    // Push an interior vertex of the upper layer down through the lower one.
    const int i = 3 * nx / 4, j = ny / 2;
    const auto v = static_cast<std::uint32_t>(j * (nx + 1) + i);
    ASSERT_GT(m.positions[v].z, 0.0);
    m.positions[v].z = -0.05;
    const IntersectionReport r = check_all(m.positions, m.triangles);
    EXPECT_GT(r.intersecting_pairs, 0u);
    ASSERT_EQ(r.examples.size(), r.intersecting_pairs);
    // Every intersecting pair involves one of the triangles around the pushed vertex (the rest of
    // the sheet did not move), and the other triangle is in the lower layer.
    const auto uses_v = [&](std::uint32_t t) {
        const Triangle& tri = m.triangles[t];
        return tri.v[0] == v || tri.v[1] == v || tri.v[2] == v;
    };
    for (const IntersectingPair& p : r.examples) {
        EXPECT_LT(p.a, p.b);
        EXPECT_TRUE(uses_v(p.a) != uses_v(p.b)) << p.a << " " << p.b;
    }
    EXPECT_EQ(r.examples, brute_force(m.positions, m.triangles));
    // The default report lists at most 16 pairs, the smallest ones, but counts them all.
    const IntersectionReport brief = check_intersections(m.positions, m.triangles, {.max_examples = 3});
    EXPECT_EQ(brief.intersecting_pairs, r.intersecting_pairs);
    ASSERT_EQ(brief.examples.size(), std::min<std::size_t>(3, r.intersecting_pairs));
    EXPECT_TRUE(std::equal(brief.examples.begin(), brief.examples.end(), r.examples.begin()));
}

// 2,000 random triangles in the unit cube, sized so that many pairs touch or cross.
struct Soup {
    std::vector<Vec3d> x;
    std::vector<Triangle> tris;
};

Soup random_soup(unsigned seed, bool lattice, bool shared_vertices, int huge) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0), d(-0.06, 0.06);
    std::uniform_int_distribution<int> cell(0, 24), step(-1, 1);
    Soup s;
    const int n = 2000;
    const auto snap = [](double v) { return std::round(v * 32.0) / 32.0; };
    if (shared_vertices) {
        // A pool of points; each triangle picks three distinct ones close together.
        for (int i = 0; i < 1500; ++i) {
            const Vec3d p =
                lattice ? Vec3d{cell(rng) / 24.0, cell(rng) / 24.0, cell(rng) / 24.0} : Vec3d{u(rng), u(rng), u(rng)};
            s.x.push_back(p);
        }
        // Sort the pool along x so that nearby indices are nearby points.
        std::sort(s.x.begin(), s.x.end(), [](const Vec3d& a, const Vec3d& b) { return a.x < b.x; });
        std::uniform_int_distribution<std::uint32_t> pick(0, 1499), near(1, 12);
        for (int t = 0; t < n; ++t) {
            const std::uint32_t a = pick(rng);
            const std::uint32_t b = std::min<std::uint32_t>(1499, a + near(rng));
            const std::uint32_t c = a >= 12 ? a - near(rng) : a + 13;
            s.tris.push_back({{a, b, c}});
        }
    } else {
        for (int t = 0; t < n; ++t) {
            const Vec3d c{u(rng), u(rng), u(rng)};
            const auto base = static_cast<std::uint32_t>(s.x.size());
            for (int k = 0; k < 3; ++k) {
                Vec3d p = c + Vec3d{d(rng), d(rng), d(rng)};
                if (lattice) p = Vec3d{snap(p.x), snap(p.y), snap(p.z)};
                s.x.push_back(p);
            }
            s.tris.push_back({{base, base + 1, base + 2}});
        }
    }
    for (int h = 0; h < huge; ++h) {  // triangles across the whole cube: tested without the grid
        const auto base = static_cast<std::uint32_t>(s.x.size());
        s.x.push_back({u(rng), -0.1, u(rng)});
        s.x.push_back({1.1, 1.1, u(rng)});
        s.x.push_back({-0.1, u(rng), u(rng)});
        s.tris.push_back({{base, base + 1, base + 2}});
    }
    return s;
}

TEST(IntersectionCheck, RandomSoupsMatchBruteForce) {
    struct Case {
        const char* name;
        unsigned seed;
        bool lattice, shared;
        int huge;
    };
    const Case cases[] = {{"continuous", 1, false, false, 0},
                          {"lattice (touching)", 2, true, false, 0},
                          {"shared vertices", 3, false, true, 0},
                          {"shared vertices, lattice", 4, true, true, 0},
                          {"with huge triangles", 5, false, false, 3}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        Soup s = random_soup(c.seed, c.lattice, c.shared, c.huge);
        if (c.huge > 0) {
            // One triangle with a NaN vertex and one with an infinite one: skipped and counted.
            s.x[s.tris[10].v[1]].y = std::nan("");
            s.x[s.tris[20].v[0]].z = std::numeric_limits<double>::infinity();
        }
        const std::vector<IntersectingPair> expected = brute_force(s.x, s.tris);
        const IntersectionReport r = check_all(s.x, s.tris);
        EXPECT_EQ(r.intersecting_pairs, expected.size());
        EXPECT_EQ(r.examples, expected);
        EXPECT_GT(expected.size(), 50u);
        if (c.huge > 0) {
            EXPECT_EQ(r.oversized_triangles, std::size_t(c.huge));
            EXPECT_EQ(r.nonfinite_triangles, 2u);
        }
        // Cell size does not change the answer.
        for (const double cell : {0.01, 0.3, 5.0}) {
            const IntersectionReport rc =
                check_intersections(s.x, s.tris, {.max_examples = std::size_t(1) << 30, .cell_size = cell});
            EXPECT_EQ(rc.examples, expected) << "cell " << cell;
        }
        std::printf("%s: %zu intersecting pairs of %zu triangles, %zu candidates tested\n", c.name, expected.size(),
                    s.tris.size(), r.candidate_pairs);
    }
}

// The world's check says which kind each intersection is: a flat sheet crossed by a second cloth
// (cloth through cloth) and by a mesh collider (cloth through the body). Each count must be what
// the plain check finds on that pair of meshes alone, and a pair of two collider triangles (the
// collider's own mesh crossing itself) is no one's.
TEST(IntersectionCheck, AWorldsIntersectionsAreSplitIntoClothAndColliderPairs) {
    World world;
    world.add_cloth({.name = "floor sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 8, 8, GridPlane::XZ))});
    ClothDesc wall{.name = "wall sheet", .fabric = Fabric::cook(make_grid(0.5, 0.5, 4, 4, GridPlane::XY))};
    wall.transform.translation = {0.0, 0.0, 0.21};  // stands across the floor sheet
    world.add_cloth(wall);
    MeshData fence = make_grid(0.8, 0.6, 4, 4, GridPlane::XY);  // a mesh collider across the floor sheet at z = -0.2
    const MeshData crossing = make_grid(0.3, 0.3, 2, 2, GridPlane::XY);  // turned into x = 0: through the fence
    const auto offset = static_cast<std::uint32_t>(fence.positions.size());
    for (Vec3d p : crossing.positions) fence.positions.push_back({p.z, p.y, p.x});
    for (Triangle t : crossing.triangles) fence.triangles.push_back({{t.v[0] + offset, t.v[1] + offset, t.v[2] + offset}});
    for (Vec3d& p : fence.positions) p.z -= 0.2;
    ColliderDesc body{.name = "fence", .shape = ColliderShape::Mesh};
    body.mesh = std::make_shared<const MeshData>(fence);
    world.add_collider(body);

    const std::vector<std::vector<Vec3d>> x{world.positions(0), world.positions(1)};
    const WorldIntersections found = check_world_intersections(world.model(), x, 0.0);

    // The same pairs by the plain check on two meshes at a time.
    const auto pairs_of = [](const std::vector<Vec3d>& a, const std::vector<Triangle>& ta, const std::vector<Vec3d>& b,
                             const std::vector<Triangle>& tb) {
        std::vector<Vec3d> xs = a;
        std::vector<Triangle> ts = ta;
        const auto base = static_cast<std::uint32_t>(xs.size());
        xs.insert(xs.end(), b.begin(), b.end());
        for (Triangle t : tb) ts.push_back({{t.v[0] + base, t.v[1] + base, t.v[2] + base}});
        return check_all(xs, ts).intersecting_pairs - check_all(a, ta).intersecting_pairs - check_all(b, tb).intersecting_pairs;
    };
    const std::span<const Triangle> floor_span = world.model().cloths[0].fabric->triangles();
    const std::span<const Triangle> wall_span = world.model().cloths[1].fabric->triangles();
    const std::vector<Triangle> floor_tris(floor_span.begin(), floor_span.end()), wall_tris(wall_span.begin(), wall_span.end());
    const std::size_t cloth_pairs = pairs_of(x[0], floor_tris, x[1], wall_tris);
    const std::size_t body_pairs = pairs_of(x[0], floor_tris, fence.positions, fence.triangles) +
                                   pairs_of(x[1], wall_tris, fence.positions, fence.triangles);
    EXPECT_GT(cloth_pairs, 0U);
    EXPECT_GT(body_pairs, 0U);
    EXPECT_GT(check_all(fence.positions, fence.triangles).intersecting_pairs, 0U) << "the fence must cross itself";
    EXPECT_EQ(found.cloth_with_cloth, cloth_pairs);
    EXPECT_EQ(found.cloth_with_collider, body_pairs);
    EXPECT_EQ(found.total(), cloth_pairs + body_pairs);

    // World::intersections names the same pairs: each one's two triangles do intersect, there are as
    // many of each kind, and a cap keeps the first ones.
    const std::vector<IntersectingTriangles> named = world.intersections();
    std::size_t named_cloth = 0, named_body = 0;
    for (const IntersectingTriangles& p : named) {
        ASSERT_LT(p.cloth, 2U);
        const std::vector<Vec3d>& xa = x[p.cloth];
        const Triangle ta = world.model().cloths[p.cloth].fabric->triangles()[p.triangle];
        const std::vector<Vec3d>& xb = p.with_collider ? fence.positions : x[p.other];
        const Triangle tb = p.with_collider ? fence.triangles[p.other_triangle] : world.model().cloths[p.other].fabric->triangles()[p.other_triangle];
        const Vec3d a[3] = {xa[ta.v[0]], xa[ta.v[1]], xa[ta.v[2]]};
        const Vec3d b[3] = {xb[tb.v[0]], xb[tb.v[1]], xb[tb.v[2]]};
        EXPECT_TRUE(physics::triangles_intersect(a, b)) << "cloth " << p.cloth << " triangle " << p.triangle;
        EXPECT_EQ(p.other, p.with_collider ? 0U : 1U);  // the fence is collider 0; the wall sheet cloth 1
        (p.with_collider ? named_body : named_cloth) += 1;
    }
    EXPECT_EQ(named_cloth, cloth_pairs);
    EXPECT_EQ(named_body, body_pairs);
    const std::vector<IntersectingTriangles> first = world.intersections(3);
    ASSERT_EQ(first.size(), 3U);
    for (std::size_t k = 0; k < first.size(); ++k) EXPECT_EQ(first[k].triangle, named[k].triangle);
}

TEST(IntersectionCheck, RejectsBadIndices) {
    const std::vector<Vec3d> x{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const std::vector<Triangle> tris{{{0, 1, 3}}};
    EXPECT_THROW((void)check_intersections(x, tris), Error);
    const std::vector<Triangle> ok{{{0, 1, 2}}};
    EXPECT_TRUE(check_intersections(x, ok).clean());
    EXPECT_TRUE(check_intersections(x, {}).clean());
}

// A ~200K-triangle sheet: flat in z = 0; tilted about the x axis (vertices with equal y still share
// their rounded y and z, so boxes of non-adjacent neighbours still touch and are tested, and the sheet
// is flat only up to rounding: the orientation filter often has to fall back to exact arithmetic);
// and rotated about two axes. The times are printed for the record, not asserted.
TEST(IntersectionCheck, LargeGridTiming) {
    const MeshData m = make_grid(3.0, 3.0, 316, 316, GridPlane::XY);  // 199,712 triangles
    std::vector<Vec3d> tilted(m.positions.size()), rotated(m.positions.size());
    const double c1 = std::cos(0.4), s1 = std::sin(0.4), c2 = std::cos(1.1), s2 = std::sin(1.1);
    for (std::size_t i = 0; i < m.positions.size(); ++i) {
        const Vec3d p = m.positions[i];
        tilted[i] = Vec3d{p.x, c2 * p.y, s2 * p.y};
        const Vec3d q{c1 * p.x - s1 * p.z, p.y, s1 * p.x + c1 * p.z};       // about y
        rotated[i] = Vec3d{q.x, c2 * q.y - s2 * q.z, s2 * q.y + c2 * q.z};  // then about x
    }
    const struct {
        const char* name;
        const std::vector<Vec3d>* positions;
    } sheets[] = {{"flat", &m.positions}, {"tilted", &tilted}, {"rotated", &rotated}};
    for (const auto& sheet : sheets) {
        const auto t0 = std::chrono::steady_clock::now();
        const IntersectionReport r = check_intersections(*sheet.positions, m.triangles);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        EXPECT_TRUE(r.clean()) << sheet.name;
        std::printf("%s grid, %zu triangles: %.3f s (%zu candidate pairs, cell %.4g m)\n", sheet.name,
                    m.triangles.size(), seconds, r.candidate_pairs, r.cell_size);
    }
}

}  // namespace
}  // namespace weft::collision
