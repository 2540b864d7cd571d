// The shipped collision scenes mean what their header comments say: their Try lines load and reach
// the benchmark sizes, they start free of intersections, the twist turns its edges as specified,
// the projectile is fast and aimed, and the garment's skirt hangs clear of the body.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "collision/intersection_check.h"
#include "scene_test_util.h"
#include "weft/backend/model.h"
#include "weft/physics/proximity.h"
#include "weft/scene.h"

namespace weft {
namespace {

using test::scene_file;

// The `--set` arguments of a scene's "# Try:" header line.
std::vector<std::string> try_overrides(std::string_view name) {
    std::ifstream in(scene_file(name));
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("# Try:", 0) != 0) continue;
        std::istringstream words(line.substr(6));
        std::vector<std::string> out;
        std::string word;
        while (words >> word)
            if (word == "--set" && words >> word) out.push_back(word);
        return out;
    }
    return {};
}

std::size_t grid_triangles(const SceneDesc& s) {
    std::size_t n = 0;
    for (const SceneCloth& c : s.cloths) {
        EXPECT_EQ(c.source.kind, ClothSource::Kind::Grid) << c.desc.name;
        n += 2 * static_cast<std::size_t>(c.source.cells_x) * static_cast<std::size_t>(c.source.cells_y);
    }
    return n;
}

TEST(ShippedScenes, TryLinesReachTheBenchmarkSizes) {
    // Triangles at the size of the paper benchmark (or the stated stress size) each Try line names.
    const std::map<std::string, std::size_t> expected{
        {"twist", 2 * 316 * 316},        // 317 × 317 vertices: PSCC "Twisting", 200K
        {"sphere", 2 * 316 * 316},       // PSCC "Sphere", 200K
        {"falling", 4 * 2 * 147 * 147},  // PSCC "Falling", 172K
        {"layers", 50 * 2 * 69 * 69},    // 50 sheets, about 475K
        {"projectile", 2 * 256 * 256},
    };
    for (const auto& [name, triangles] : expected) {
        SCOPED_TRACE(name);
        const std::vector<std::string> overrides = try_overrides(name);
        ASSERT_FALSE(overrides.empty()) << "no '# Try:' line with --set in " << name << ".toml";
        const SceneDesc big = load_scene(scene_file(name), overrides);
        EXPECT_EQ(grid_triangles(big), triangles);
        // The defaults are small: 60 frames in well under a minute on two cores.
        EXPECT_LT(grid_triangles(load_scene(scene_file(name))), 6000U);
    }
    EXPECT_NEAR(static_cast<double>(50 * 2 * 69 * 69), 475e3, 0.01 * 475e3);
    // The twist's benchmark sheet keeps 1 cm between vertices.
    const SceneDesc twist = load_scene(scene_file("twist"), try_overrides("twist"));
    const ClothSource& g = twist.cloths.at(0).source;
    EXPECT_EQ(g.cells_x, 316);
    EXPECT_EQ(g.cells_y, 316);
    EXPECT_NEAR(g.width / g.cells_x, 0.01, 1e-12);
    EXPECT_NEAR(g.height / g.cells_y, 0.01, 1e-12);
}

TEST(ShippedScenes, CollisionScenesAskForSelfContact) {
    for (const char* name : {"sphere", "twist", "falling", "layers", "projectile", "garment"}) {
        SCOPED_TRACE(name);
        EXPECT_TRUE(load_scene(scene_file(name)).world.collision.self_collision);
    }
    EXPECT_FALSE(load_scene(scene_file("flag")).world.collision.self_collision);
}

TEST(ShippedScenes, TwistTurnsItsEdgesAboutTheCentreLine) {
    const SceneDesc s = load_scene(scene_file("twist"));
    EXPECT_EQ(s.world.gravity, (Vec3d{0, 0, 0}));
    EXPECT_NEAR(s.world.solver.dt, 1.0 / 600.0, 1e-9);
    EXPECT_EQ(s.world.solver.substeps, 1);
    const SceneCloth& sheet = s.cloths.at(0);
    EXPECT_EQ(sheet.source.cells_x, 39);  // 40 × 40 vertices
    EXPECT_EQ(sheet.source.cells_y, 39);
    EXPECT_NEAR(sheet.source.width, 0.39, 1e-15);
    EXPECT_NEAR(sheet.source.height, 0.39, 1e-15);
    ASSERT_EQ(s.motions.size(), 2U);
    const Vec3d centre = sheet.desc.transform.translation;
    const double half = 0.5 * sheet.source.width;
    const double rate = std::numbers::pi / 3.0;
    for (const SceneMotion& m : s.motions) {
        SCOPED_TRACE(m.name);
        const double sign = m.name == "left" ? -1.0 : 1.0;  // the left edge is at −x
        // Origin at the edge's midpoint, on the centre line; turning about x at ∓π/3 rad/s.
        EXPECT_NEAR(m.motion.origin.x, centre.x + sign * half, 1e-12);
        EXPECT_NEAR(m.motion.origin.y, centre.y, 1e-12);
        EXPECT_NEAR(m.motion.origin.z, centre.z, 1e-12);
        EXPECT_NEAR(m.motion.angular_velocity.x, -sign * rate, 1e-9);
        EXPECT_EQ(m.motion.angular_velocity.y, 0.0);
        EXPECT_EQ(m.motion.angular_velocity.z, 0.0);
    }
    // The pinned edges follow: after 60 frames (0.1 s) each edge has turned by ±π/30 about x.
    const auto world = build_world(s);
    const ClothDesc& cloth = world->model().cloths.at(0);
    const std::vector<Vec3d> start = world->positions(0);
    for (int f = 0; f < 60; ++f) (void)world->step();
    const std::vector<Vec3d> now = world->positions(0);
    const double t = 60 * s.world.solver.dt;
    std::size_t left = 0, right = 0;
    for (const PinDesc& p : cloth.pins) {
        const Vec3d x0 = start[p.vertex];
        const bool is_left = x0.x < centre.x;
        (is_left ? left : right) += 1;
        ASSERT_GE(p.motion, 0);
        EXPECT_EQ(s.motions.at(static_cast<std::size_t>(p.motion)).name, is_left ? "left" : "right");
        const double angle = (is_left ? rate : -rate) * t;
        const double dy = x0.y - centre.y, dz = x0.z - centre.z;
        const Vec3d expected{x0.x, centre.y + std::cos(angle) * dy - std::sin(angle) * dz,
                             centre.z + std::sin(angle) * dy + std::cos(angle) * dz};
        ASSERT_NEAR(now[p.vertex].x, expected.x, 1e-7);
        ASSERT_NEAR(now[p.vertex].y, expected.y, 1e-7);
        ASSERT_NEAR(now[p.vertex].z, expected.z, 1e-7);
    }
    EXPECT_EQ(left, 40U);
    EXPECT_EQ(right, 40U);
    // Something actually turned: a corner moved by about r·angle = 0.195·π/30 ≈ 2 cm.
    EXPECT_GT(physics::length(now[cloth.pins[0].vertex] - start[cloth.pins[0].vertex]), 0.015);
}

TEST(ShippedScenes, ProjectileIsFastSmallAndAimedThroughTheSheet) {
    const SceneDesc s = load_scene(scene_file("projectile"));
    ASSERT_EQ(s.colliders.size(), 1U);
    const ColliderDesc& ball = s.colliders[0];
    EXPECT_EQ(ball.shape, ColliderShape::Sphere);
    EXPECT_LE(ball.radius, 0.1);
    EXPECT_EQ(ball.motion.linear_velocity, (Vec3d{0, 0, -50}));
    const SceneCloth& sheet = s.cloths.at(0);
    EXPECT_EQ(sheet.source.plane, GridPlane::XY);  // hanging in the plane z = position.z
    EXPECT_NEAR(ball.motion.origin.z - sheet.desc.transform.translation.z, 1.0, 1e-12);  // 1 m in front
    EXPECT_NEAR(ball.motion.origin.x, sheet.desc.transform.translation.x, 1e-12);        // at the centre
    EXPECT_NEAR(ball.motion.origin.y, sheet.desc.transform.translation.y, 1e-12);
    // It crosses the sheet (at t = 0.02 s) well within the scene's frames.
    EXPECT_GT(s.frames * s.world.solver.dt, 0.1);
    ASSERT_EQ(s.cloths[0].pins.size(), 1U);
    EXPECT_EQ(s.cloths[0].pins[0].edge, "top");
}

// All triangles of the world at t = 0: every cloth and every mesh collider.
struct Soup {
    std::vector<Vec3d> positions;
    std::vector<Triangle> triangles;
    void add(std::span<const Vec3d> p, std::span<const Triangle> t) {
        const auto base = static_cast<std::uint32_t>(positions.size());
        positions.insert(positions.end(), p.begin(), p.end());
        for (Triangle tri : t) {
            for (auto& v : tri.v) v += base;
            triangles.push_back(tri);
        }
    }
};

/// The pairs a mesh collider makes with itself at t = 0 (a character built of overlapping boxes
/// intersects itself; the cloth pipeline never tests kinematic triangles against each other).
std::size_t collider_self_pairs(const World& world) {
    std::size_t pairs = 0;
    for (const ColliderDesc& c : world.model().colliders) {
        if (!c.mesh) continue;
        std::vector<Vec3d> p(c.mesh->positions.size());
        collider_mesh_positions(c, 0.0, p);
        pairs += collision::check_intersections(p, c.mesh->triangles).intersecting_pairs;
    }
    return pairs;
}

Soup world_at_start(const World& world) {
    Soup soup;
    const Model& m = world.model();
    for (std::size_t c = 0; c < m.cloths.size(); ++c) soup.add(world.positions(c), m.cloths[c].fabric->triangles());
    for (const ColliderDesc& c : m.colliders) {
        if (!c.mesh) continue;
        std::vector<Vec3d> p(c.mesh->positions.size());
        collider_mesh_positions(c, 0.0, p);  // a character in its clip's first pose
        soup.add(p, c.mesh->triangles);
    }
    return soup;
}

TEST(ShippedScenes, StartFreeOfIntersections) {
    // The collision pipeline keeps a state free of intersections; it cannot repair one it starts
    // from, so every scene must start clean (copies made by repeat, skirt against body included).
    const bool loader = test::install_loader();
    for (const char* name : {"sphere", "twist", "falling", "layers", "projectile", "garment", "skirt", "drape", "runner"}) {
        SCOPED_TRACE(name);
        const SceneDesc s = load_scene(scene_file(name));
        bool needs_loader = false;
        for (const SceneCloth& c : s.cloths) needs_loader |= c.source.kind == ClothSource::Kind::File;
        for (const ColliderDesc& c : s.colliders) needs_loader |= c.shape == ColliderShape::Mesh;
        if (needs_loader && !loader) continue;
        const auto world = build_world(s);
        const Soup soup = world_at_start(*world);
        const collision::IntersectionReport r = collision::check_intersections(soup.positions, soup.triangles);
        EXPECT_EQ(r.intersecting_pairs, collider_self_pairs(*world)) << "pairs with a cloth in them";
        EXPECT_EQ(r.triangles_checked, soup.triangles.size());
    }
    // The check can fail: two copies placed on top of each other, turned, do intersect.
    const SceneDesc crossed = load_scene(scene_file("falling"), std::vector<std::string>{
                                                                    "cloth.sheet.repeat.offset=[0,0,0]"});
    const auto world = build_world(crossed);
    const Soup soup = world_at_start(*world);
    EXPECT_GT(collision::check_intersections(soup.positions, soup.triangles).intersecting_pairs, 0U);
}

TEST(ShippedScenes, GarmentSkirtHangsClearOfTheBody) {
    if (!test::install_loader()) GTEST_SKIP() << "weft::assets not built";
    const SceneDesc s = load_scene(scene_file("garment"));
    const auto world = build_world(s);
    const Model& m = world->model();
    ASSERT_EQ(m.cloths.size(), 1U);
    std::size_t body_index = m.colliders.size();
    for (std::size_t k = 0; k < m.colliders.size(); ++k)
        if (m.colliders[k].shape == ColliderShape::Mesh) body_index = k;
    ASSERT_LT(body_index, m.colliders.size());
    const ColliderDesc* body = &m.colliders[body_index];
    ASSERT_NE(body->mesh, nullptr);
    // The body follows a gentle motion that turns it, and the skirt's waist follows the same one.
    const Motion& motion = body->motion;
    EXPECT_GT(physics::length(motion.angular_velocity), 0.0);
    EXPECT_LE(physics::length(motion.angular_velocity), 1.0);
    int body_motion = -1;
    for (std::size_t k = 0; k < s.motions.size(); ++k)
        if (s.motions[k].name == s.collider_motions[body_index]) body_motion = static_cast<int>(k);
    ASSERT_GE(body_motion, 0);
    ASSERT_FALSE(m.cloths[0].pins.empty());
    for (const PinDesc& p : m.cloths[0].pins) EXPECT_EQ(p.motion, body_motion);
    // The body stands on the floor.
    double feet = 1e9;
    for (const Vec3d& x : body->mesh->positions) feet = std::min(feet, x.y);
    EXPECT_NEAR(feet, 0.0, 1e-9);

    const Transform frame = motion.at(0.0);
    std::vector<Vec3d> body_x;
    for (const Vec3d& x : body->mesh->positions) body_x.push_back(frame.apply(x));
    const std::vector<Vec3d> skirt_x = world->positions(0);
    const auto body_t = body->mesh->triangles;
    const auto skirt_t = m.cloths[0].fabric->triangles();

    // The skirt spans the hips: the widest part of the body between waist and knees.
    double skirt_top = -1e9, skirt_bottom = 1e9;
    for (const Vec3d& x : skirt_x) {
        skirt_top = std::max(skirt_top, x.y);
        skirt_bottom = std::min(skirt_bottom, x.y);
    }
    double hip_y = 0.0, hip_width = 0.0;
    for (const Vec3d& x : body_x)
        if (x.y > 0.6 && x.y < 1.2 && std::abs(x.x) > hip_width) {
            hip_width = std::abs(x.x);
            hip_y = x.y;
        }
    EXPECT_LT(skirt_bottom, hip_y - 0.1);
    EXPECT_GT(skirt_top, hip_y + 0.05);
    EXPECT_GT(hip_width, 0.15);

    // Clearance of at least 1 cm between the two surfaces (vertex–face in both directions).
    double clearance = 1e9;
    for (const Vec3d& p : skirt_x)
        for (const Triangle& t : body_t)
            clearance = std::min(clearance, physics::point_triangle_proximity(p, body_x[t.v[0]], body_x[t.v[1]],
                                                                              body_x[t.v[2]])
                                                .distance);
    for (const Vec3d& p : body_x) {
        if (p.y < skirt_bottom - 0.02 || p.y > skirt_top + 0.02) continue;
        for (const Triangle& t : skirt_t)
            clearance = std::min(clearance, physics::point_triangle_proximity(p, skirt_x[t.v[0]], skirt_x[t.v[1]],
                                                                              skirt_x[t.v[2]])
                                                .distance);
    }
    EXPECT_GE(clearance, 0.01);
    EXPECT_LE(clearance, 0.06);  // and it does sit on the body, not float around it
    std::printf("garment: skirt-body clearance %.4f m, hips %.3f m wide at y = %.3f\n", clearance, 2 * hip_width, hip_y);
}

}  // namespace
}  // namespace weft
