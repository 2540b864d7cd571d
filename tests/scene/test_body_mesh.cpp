// assets/meshes/body.obj (tools/make_body.py), the mesh collider of the garment scene: a closed,
// consistently outward-wound 2-manifold of genus 0, free of zero-area triangles and of
// self-intersections, of human size. Read with a small OBJ reader of its own so that it is checked
// exactly as written, with or without the assimp importer.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "collision/intersection_check.h"
#include "scene_test_util.h"
#include "weft/physics/vec.h"

namespace weft {
namespace {

struct Obj {
    std::vector<Vec3d> positions;
    std::vector<Triangle> triangles;
};

// "v x y z" and "f a b c" lines (a face corner may carry /vt/vn, which is ignored).
Obj read_obj(const std::filesystem::path& path) {
    Obj obj;
    std::ifstream in(path);
    EXPECT_TRUE(in) << path;
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream words(line);
        std::string tag;
        words >> tag;
        if (tag == "v") {
            Vec3d p{};
            words >> p.x >> p.y >> p.z;
            obj.positions.push_back(p);
        } else if (tag == "f") {
            std::vector<std::uint32_t> corners;
            std::string corner;
            while (words >> corner) corners.push_back(static_cast<std::uint32_t>(std::stoul(corner)) - 1);
            EXPECT_EQ(corners.size(), 3U) << line;
            if (corners.size() == 3) obj.triangles.push_back({{corners[0], corners[1], corners[2]}});
        }
    }
    return obj;
}

const Obj& body() {
    static const Obj obj = read_obj(test::source_dir() / "assets" / "meshes" / "body.obj");
    return obj;
}

TEST(BodyMesh, IsAClosedConsistentlyWoundManifoldOfGenusZero) {
    const Obj& b = body();
    ASSERT_GT(b.triangles.size(), 1000U);
    EXPECT_LT(b.triangles.size(), 10000U);  // low-poly: a few thousand
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
    std::vector<int> used(b.positions.size(), 0);
    for (const Triangle& t : b.triangles)
        for (int k = 0; k < 3; ++k) {
            ASSERT_LT(t.v[k], b.positions.size());
            ++directed[{t.v[k], t.v[(k + 1) % 3]}];
            ++used[t.v[k]];
        }
    // Each directed edge once and its reverse once: closed, manifold along edges, wound one way.
    for (const auto& [edge, count] : directed) {
        ASSERT_EQ(count, 1) << "edge " << edge.first << "-" << edge.second << " used twice the same way";
        ASSERT_TRUE(directed.contains({edge.second, edge.first})) << "edge " << edge.first << "-" << edge.second
                                                                   << " is on a hole";
    }
    EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0) << "unreferenced vertices";
    // One fan per vertex: walking the faces around a vertex visits all of them.
    std::vector<std::map<std::uint32_t, std::uint32_t>> next(b.positions.size());
    for (const Triangle& t : b.triangles)
        for (int k = 0; k < 3; ++k) next[t.v[k]][t.v[(k + 1) % 3]] = t.v[(k + 2) % 3];
    for (std::size_t v = 0; v < next.size(); ++v) {
        const auto start = next[v].begin()->first;
        std::uint32_t p = start;
        std::size_t steps = 0;
        do {
            p = next[v].at(p);
            ++steps;
        } while (p != start && steps <= next[v].size());
        ASSERT_EQ(steps, next[v].size()) << "vertex " << v << " is not manifold";
    }
    const long long euler = static_cast<long long>(b.positions.size()) - static_cast<long long>(directed.size() / 2) +
                            static_cast<long long>(b.triangles.size());
    EXPECT_EQ(euler, 2);
    // Outward normals: the divergence theorem gives a positive volume, about a person's (60 L).
    double volume = 0.0;
    for (const Triangle& t : b.triangles)
        volume += physics::dot(b.positions[t.v[0]], physics::cross(b.positions[t.v[1]], b.positions[t.v[2]])) / 6.0;
    EXPECT_GT(volume, 0.04);
    EXPECT_LT(volume, 0.09);
}

TEST(BodyMesh, HasNoZeroAreaTrianglesAndDoesNotIntersectItself) {
    const Obj& b = body();
    double worst = 1.0;
    for (const Triangle& t : b.triangles) {
        const Vec3d a = b.positions[t.v[0]], c = b.positions[t.v[1]], d = b.positions[t.v[2]];
        const double longest = std::max({physics::length_squared(c - a), physics::length_squared(d - c),
                                         physics::length_squared(a - d)});
        worst = std::min(worst, physics::length(physics::cross(c - a, d - a)) / longest);
    }
    EXPECT_GT(worst, 0.05);  // 2·area / longest edge²: no slivers, let alone zero-area triangles
    const collision::IntersectionReport r = collision::check_intersections(b.positions, b.triangles);
    EXPECT_EQ(r.triangles_checked, b.triangles.size());
    EXPECT_EQ(r.intersecting_pairs, 0U);
}

TEST(BodyMesh, IsHumanSizedAndStandsOnTheFloorFacingZ) {
    const Obj& b = body();
    Vec3d lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
    for (const Vec3d& p : b.positions)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], p[k]);
            hi[k] = std::max(hi[k], p[k]);
        }
    EXPECT_NEAR(lo.y, 0.0, 1e-9);       // feet on y = 0
    EXPECT_NEAR(hi.y, 1.76, 0.01);      // 1.76 m tall
    EXPECT_NEAR(hi.x, -lo.x, 1e-4);     // symmetric left to right
    EXPECT_GT(hi.x - lo.x, 0.3);        // hips/shoulders about 35 cm wide
    EXPECT_LT(hi.x - lo.x, 0.45);
    EXPECT_LT(hi.z - lo.z, hi.x - lo.x);  // wider than deep
    // Two legs: at knee height the body is two separate rings, left and right of x = 0.
    bool left = false, right = false, middle = false;
    for (const Vec3d& p : b.positions)
        if (std::abs(p.y - 0.48) < 0.03) {
            left |= p.x < -0.02;
            right |= p.x > 0.02;
            middle |= std::abs(p.x) < 0.01;
        }
    EXPECT_TRUE(left);
    EXPECT_TRUE(right);
    EXPECT_FALSE(middle);
}

}  // namespace
}  // namespace weft
