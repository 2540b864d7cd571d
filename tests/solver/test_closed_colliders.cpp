// Cloth inside a closed mesh collider (collision/closed_colliders.h, docs/collisions.md "Closed mesh
// colliders"): which pieces of a collider are closed, the winding number that says a point is
// inside, where an inside vertex goes, and through the public API a cloth that starts inside a
// closed box ends on top of it while an open box keeps it (the control).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "box_mesh.h"
#include "collision/closed_colliders.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

using collision::ClosedPiece;
using collision::CollisionGeometry;

/// An axis-aligned box [lo, hi] (tests/common/box_mesh.h).
MeshData box(Vec3d lo, Vec3d hi) {
    MeshData m;
    test::add_box(m, lo, hi);
    return m;
}

/// A sphere of radius r: an octahedron split by its edges' midpoints `levels` times (8·4^levels
/// triangles), every vertex pushed onto the sphere. Closed by construction, wound outward.
MeshData sphere(double r, int levels) {
    MeshData m;
    m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    m.triangles = {{{0, 2, 4}}, {{2, 1, 4}}, {{1, 3, 4}}, {{3, 0, 4}}, {{2, 0, 5}}, {{1, 2, 5}}, {{3, 1, 5}}, {{0, 3, 5}}};
    for (int level = 0; level < levels; ++level) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
        const auto mid = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            if (const auto it = middle.find(key); it != middle.end()) return it->second;
            m.positions.push_back(0.5 * (m.positions[a] + m.positions[b]));
            return middle[key] = static_cast<std::uint32_t>(m.positions.size() - 1);
        };
        std::vector<Triangle> finer;
        for (const Triangle& t : m.triangles) {
            const std::uint32_t a = t.v[0], b = t.v[1], c = t.v[2], ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
            finer.insert(finer.end(), {{{a, ab, ca}}, {{ab, b, bc}}, {{ca, bc, c}}, {{ab, bc, ca}}});
        }
        m.triangles = std::move(finer);
    }
    for (Vec3d& p : m.positions) p = (r / math::length(p)) * p;
    return m;
}

/// A collision geometry by hand: `cloth` free vertices (no triangles) and the meshes as kinematic
/// vertices and triangles; returns it with the collision positions (cloth, then the meshes').
struct Scene {
    CollisionGeometry g;
    std::vector<Vec3d> x;
};

Scene scene_of(const std::vector<Vec3d>& cloth, const std::vector<MeshData>& meshes) {
    Scene s;
    s.g.cloth_vertices = cloth.size();
    s.x = cloth;
    s.g.inverse_mass.assign(cloth.size(), 1.0);
    for (const MeshData& m : meshes) {
        const auto base = static_cast<std::uint32_t>(s.x.size());
        for (const Vec3d& p : m.positions) {
            s.g.kinematic_local.push_back(p);
            s.x.push_back(p);
            s.g.inverse_mass.push_back(0.0);
        }
        for (const Triangle& t : m.triangles) s.g.triangles.push_back({{base + t.v[0], base + t.v[1], base + t.v[2]}});
    }
    return s;
}

double winding(const Scene& s, const ClosedPiece& piece, Vec3d p) {
    return collision::winding_number(p, s.g.triangles, piece.triangles, s.x);
}

TEST(ClosedColliders, OnlyTheWatertightPiecesAreClosed) {
    MeshData open_box = box({2, 0, 0}, {3, 1, 1});
    open_box.triangles.pop_back();  // one face half gone: three edges used once
    const MeshData sheet = make_grid(1.0, 1.0, 2, 2, GridPlane::XZ);
    const Scene s = scene_of({{0, 5, 0}}, {sheet, box({0, 0, 0}, {1, 1, 1}), open_box, sphere(0.5, 1)});
    const std::vector<ClosedPiece> pieces = collision::find_closed_pieces(s.g);
    ASSERT_EQ(pieces.size(), 2u);
    EXPECT_EQ(pieces[0].triangles.size(), 12u);  // the box, not the sheet (8) nor the open box (11)
    EXPECT_EQ(pieces[1].triangles.size(), 32u);  // the sphere
    EXPECT_EQ(pieces[0].triangles.front(), 8u);  // after the sheet's triangles
}

TEST(ClosedColliders, TheWindingNumberIsOneInsideAndZeroOutside) {
    const Scene s = scene_of({}, {box({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5})});
    const ClosedPiece piece = collision::find_closed_pieces(s.g).at(0);
    for (const Vec3d p : {Vec3d{0, 0, 0}, Vec3d{0.49, 0.3, -0.2}, Vec3d{-0.45, -0.45, 0.45}})
        EXPECT_NEAR(winding(s, piece, p), 1.0, 1e-9) << p.x << " " << p.y << " " << p.z;
    for (const Vec3d p : {Vec3d{0.51, 0, 0}, Vec3d{3, 2, 1}, Vec3d{0, -0.6, 0.4}})
        EXPECT_NEAR(winding(s, piece, p), 0.0, 1e-9) << p.x << " " << p.y << " " << p.z;
    // Wound the other way round, the inside counts −1: still inside.
    MeshData inward = box({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5});
    for (Triangle& t : inward.triangles) std::swap(t.v[1], t.v[2]);
    const Scene r = scene_of({}, {inward});
    EXPECT_NEAR(winding(r, collision::find_closed_pieces(r.g).at(0), {0.1, 0.2, 0.3}), -1.0, 1e-9);
}

TEST(ClosedColliders, AVertexInsideGoesOutThroughTheNearestFaceWithTheSurfacesVelocity) {
    const double gap = 0.01;
    Scene s = scene_of({{0.4, 0.1, 0.0}, {0.7, 0.0, 0.0}, {-0.3, 0.0, 0.0}}, {box({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5})});
    s.g.inverse_mass[2] = 0.0;  // pinned inside: its motion is prescribed, left alone
    const std::vector<ClosedPiece> pieces = collision::find_closed_pieces(s.g);
    const std::vector<Vec3d> velocity(8, Vec3d{1.0, 0.0, 2.0});  // the box moves
    const std::vector<collision::Ejection> out = collision::find_ejections(s.g, pieces, s.x, velocity, gap);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].vertex, 0u);
    EXPECT_NEAR(out[0].position.x, 0.5 + gap, 1e-12);
    EXPECT_NEAR(out[0].position.y, 0.1, 1e-12);
    EXPECT_NEAR(out[0].position.z, 0.0, 1e-12);
    EXPECT_NEAR(out[0].normal.x, 1.0, 1e-12);
    EXPECT_NEAR(out[0].surface_velocity.x, 1.0, 1e-12);
    EXPECT_NEAR(out[0].surface_velocity.z, 2.0, 1e-12);
}

TEST(ClosedColliders, WhereTwoPiecesOverlapTheVertexEndsOutsideBoth) {
    const double gap = 0.01;
    // x ∈ [0.3, 0.5] is inside both boxes: each box's nearest face leads into the other.
    const Scene s = scene_of({{0.45, 0.05, 0.0}}, {box({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}), box({0.3, -0.5, -0.5}, {1.3, 0.5, 0.5})});
    const std::vector<ClosedPiece> pieces = collision::find_closed_pieces(s.g);
    ASSERT_EQ(pieces.size(), 2u);
    const std::vector<collision::Ejection> out = collision::find_ejections(s.g, pieces, s.x, std::vector<Vec3d>(16), gap);
    ASSERT_EQ(out.size(), 1u);
    for (const ClosedPiece& piece : pieces) EXPECT_NEAR(winding(s, piece, out[0].position), 0.0, 1e-9);
    // Out through the nearest face that leads outside: the top (y = 0.5), 0.45 away.
    EXPECT_NEAR(out[0].position.y, 0.5 + gap, 1e-12);
    EXPECT_NEAR(out[0].position.x, 0.45, 1e-12);
}

TEST(ClosedColliders, TheFarFieldKeepsTheInsideTestOnAFineSphere) {
    // 2,048 triangles: the clusters far from a point enter by their dipole, the near ones exactly.
    std::vector<Vec3d> cloth;
    std::vector<bool> expect_inside;
    for (const double r : {0.0, 0.3, 0.6, 0.95, 1.05, 1.5, 4.0})
        for (const Vec3d d : {Vec3d{1, 0, 0}, normalized(Vec3d{1, 2, 3}), normalized(Vec3d{-2, -1, 0.5})}) {
            cloth.push_back(r * d);
            expect_inside.push_back(r < 1.0);
        }
    const Scene s = scene_of(cloth, {sphere(1.0, 4)});
    const std::vector<ClosedPiece> pieces = collision::find_closed_pieces(s.g);
    ASSERT_EQ(pieces.size(), 1u);
    ASSERT_EQ(pieces[0].triangles.size(), 2048u);
    const std::vector<collision::Ejection> out =
        collision::find_ejections(s.g, pieces, s.x, std::vector<Vec3d>(s.g.kinematic_vertices()), 0.01);
    std::vector<bool> ejected(cloth.size(), false);
    for (const collision::Ejection& e : out) {
        ejected[e.vertex] = true;
        EXPECT_NEAR(math::length(e.position), 1.01, 0.01) << e.vertex;  // just outside the surface
    }
    for (std::size_t i = 0; i < cloth.size(); ++i) EXPECT_EQ(ejected[i], expect_inside[i]) << "point " << i;
}

// Through the public API on the CPU backend: a 0.4 m square of cloth starts inside a closed 1 m box,
// 5 cm under its top. The first substep moves it onto the top, and it stays outside with nothing
// intersecting. With the top missing (an open box: no inside) nothing moves it: the control.
TEST(ClosedColliders, ClothStartingInsideAClosedBoxEndsOnTopOfIt) {
    for (const bool closed : {true, false}) {
        WorldDesc desc;
        desc.solver.dt = 1.0 / 60.0;
        desc.solver.substeps = 2;
        desc.collision.check = true;
        World world(desc);
        ClothDesc cloth{.name = "patch", .fabric = Fabric::cook(make_grid(0.4, 0.4, 4, 4, GridPlane::XZ))};
        cloth.transform.translation = {0.0, 0.45, 0.0};
        world.add_cloth(cloth);
        MeshData body = box({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5});
        if (!closed) body.triangles.erase(body.triangles.begin() + 6, body.triangles.begin() + 8);  // the top (y = 0.5)
        ColliderDesc collider{.name = "box", .shape = ColliderShape::Mesh};
        collider.mesh = std::make_shared<const MeshData>(body);
        world.add_collider(collider);
        int ejected = 0;
        for (int step = 0; step < 30; ++step) {
            const StepStats& s = world.step();
            ejected += s.collision.ejected_vertices;
            if (step == 0) {
                EXPECT_EQ(s.collision.ejected_vertices, closed ? 25 : 0);
            }
            EXPECT_EQ(s.collision.remaining_intersections, 0) << "step " << step << (closed ? " closed" : " open");
        }
        EXPECT_EQ(ejected, closed ? 25 : 0) << "once out, nothing gets back in";
        for (const Vec3d& p : world.positions(0)) {
            if (closed) {
                EXPECT_GT(p.y, 0.5) << "on top of the box";
            } else {
                EXPECT_LT(p.y, 0.5) << "the open box keeps it inside";
            }
        }
    }
}

}  // namespace
}  // namespace weft
