// build_world: every shipped scene becomes a world with the right cloths, pins and colliders, and
// pin selections resolve to the vertices they describe.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "scene_test_util.h"
#include "weft/backend/model.h"
#include "weft/scene.h"

namespace weft {
namespace {

using test::expect_error;
using test::scene_file;

struct Expected {
    const char* name;
    std::size_t cloths;
    std::size_t pins;       // pinned vertices of cloth 0
    std::size_t colliders;
    bool needs_loader;
};

// Every scene in assets/scenes/, with what it must build into.
constexpr Expected kShipped[] = {
    {"flag", 1, 25, 2, false},        // left edge of a 40×24 grid
    {"hanging", 1, 2, 0, false},      // two top corners
    {"drape", 1, 0, 2, false},
    {"cantilever", 1, 18, 0, false},  // two columns of a 48×8 strip: the clamp
    {"skirt", 1, 48, 1, true},        // the waist ring of a 48-segment skirt
    {"sphere", 1, 0, 2, false},
    {"twist", 1, 80, 0, false},       // left and right edges of 40×40 vertices
    {"falling", 4, 0, 2, false},      // one [[cloth]] repeated 4 times
    {"layers", 4, 0, 2, false},
    {"projectile", 1, 33, 1, false},  // top edge of a 32×32 grid
    {"garment", 1, 48, 2, true},      // the skirt's waist ring; a mesh body and a floor
    {"runner", 1, 13, 2, true},       // the cape's top edge, following the character's skin; it and a floor
};

TEST(SceneWorld, EveryShippedSceneIsListed) {
    std::set<std::string> listed;
    for (const Expected& e : kShipped) listed.insert(e.name);
    for (const auto& entry : std::filesystem::directory_iterator(test::source_dir() / "assets" / "scenes"))
        if (entry.path().extension() == ".toml") {
            EXPECT_TRUE(listed.contains(entry.path().stem().string()))
                << entry.path() << " is not in kShipped: add what it must build into";
        }
}

TEST(SceneWorld, ShippedScenesBuildAndStep) {
    const bool loader = test::install_loader();
    for (const Expected& e : kShipped) {
        SCOPED_TRACE(e.name);
        if (e.needs_loader && !loader) continue;
        const SceneDesc scene = load_scene(scene_file(e.name));
        const auto world = build_world(scene);
        ASSERT_NE(world, nullptr);
        const Model& model = world->model();
        ASSERT_EQ(model.cloths.size(), scene.cloths.size());
        EXPECT_EQ(model.cloths.size(), e.cloths);
        const ClothDesc& cloth = model.cloths[0];
        ASSERT_NE(cloth.fabric, nullptr);
        EXPECT_GT(cloth.fabric->vertex_count(), 0U);
        EXPECT_GT(cloth.fabric->triangle_count(), 0U);
        EXPECT_EQ(cloth.pins.size(), e.pins);
        EXPECT_EQ(model.colliders.size(), e.colliders);
        EXPECT_EQ(model.motions.size(), scene.motions.size());
        EXPECT_EQ(cloth.name, scene.cloths[0].desc.name);
        // Mesh colliders arrive with their mesh, analytic ones without.
        for (const ColliderDesc& c : model.colliders) {
            EXPECT_EQ(c.mesh != nullptr, c.shape == ColliderShape::Mesh) << c.name;
            if (c.mesh) {
                EXPECT_GT(c.mesh->triangles.size(), 0U) << c.name;
            }
        }
        // One frame runs and stays finite.
        (void)world->step();
        for (std::size_t c = 0; c < model.cloths.size(); ++c)
            for (const Vec3d& p : world->positions(c)) ASSERT_TRUE(math::is_finite(p));
    }
}

TEST(SceneWorld, GridEdgePinsFollowTheIndexLayout) {
    const SceneDesc scene = load_scene(scene_file("flag"));
    const auto world = build_world(scene);
    const ClothDesc& cloth = world->model().cloths[0];
    const auto rest = cloth.fabric->rest_positions();
    // The left edge: every pinned vertex at the grid's smallest x, and all of them.
    for (const PinDesc& p : cloth.pins) {
        EXPECT_NEAR(rest[p.vertex].x, -1.0, 1e-12);
        EXPECT_EQ(p.motion, -1);
    }
}

TEST(SceneWorld, CornerAndBoxPins) {
    const SceneDesc scene = parse_scene(R"(
[[motion]]
name = "m"
[[cloth]]
name = "sheet"
mesh = { grid = { width = 2.0, height = 1.0, cells = [4, 2], plane = "xz" } }
[[cloth.pin]]
corners = "top"
[[cloth.pin]]
box = { min = [-0.1, -0.1, -0.1], max = [0.1, 0.1, 0.1] }
motion = "m"
[[cloth.pin]]
corners = "all"
)",
                                        "pins.toml");
    const auto world = build_world(scene);
    const ClothDesc& cloth = world->model().cloths[0];
    // top = far edge (j = cells_y): vertices 10 and 14; the box holds the centre vertex 7; "all" adds
    // 0 and 4, and does not repeat 10 and 14.
    std::vector<std::pair<std::uint32_t, int>> got;
    for (const PinDesc& p : cloth.pins) got.emplace_back(p.vertex, p.motion);
    const std::vector<std::pair<std::uint32_t, int>> expected{{10, -1}, {14, -1}, {7, 0}, {0, -1}, {4, -1}};
    EXPECT_EQ(got, expected);
    const auto rest = cloth.fabric->rest_positions();
    EXPECT_NEAR(rest[10].z, -0.5, 1e-12);  // the far edge is at −z
}

TEST(SceneWorld, EmptySelectionNamesTheCloth) {
    const SceneDesc scene = parse_scene(R"(
[[cloth]]
name = "sheet"
mesh = { grid = { width = 1.0, height = 1.0, cells = [4, 4] } }
[[cloth.pin]]
box = { min = [5, 5, 5], max = [6, 6, 6] }
)",
                                        "empty_pins.toml");
    expect_error([&] { (void)build_world(scene); }, {"empty_pins.toml", "cloth[0] 'sheet'", "pin[0]", "pins no vertex"});
}

TEST(SceneWorld, PinVertexOutOfRangeOnMeshFile) {
    if (!test::install_loader()) GTEST_SKIP() << "weft::assets not built";
    const std::string text = "[[cloth]]\nname = \"q\"\nmesh = { file = \"" + test::data_file("quad.ply").generic_string() +
                             "\" }\n[[cloth.pin]]\nvertices = [9]\n";
    const SceneDesc scene = parse_scene(text, "range.toml");
    expect_error([&] { (void)build_world(scene); }, {"range.toml", "cloth[0] 'q'", "pin[0]", "vertex 9 is out of range"});
}

TEST(SceneWorld, ClothTransformAndMaterialReachTheWorld) {
    const SceneDesc scene = load_scene(scene_file("hanging"), std::vector<std::string>{"cloth.0.material.friction=0.9"});
    const auto world = build_world(scene);
    const ClothDesc& c = world->model().cloths[0];
    EXPECT_EQ(c.material.friction, 0.9);
    EXPECT_EQ(c.transform.translation, (Vec3d{0.0, 1.5, 0.0}));
    EXPECT_EQ(world->settings().solver.substeps, scene.world.solver.substeps);
}

TEST(SceneWorld, SkirtPinsTheWholeWaist) {
    if (!test::install_loader()) GTEST_SKIP() << "weft::assets not built";
    const SceneDesc scene = load_scene(scene_file("skirt"));
    const auto world = build_world(scene);
    const ClothDesc& c = world->model().cloths[0];
    const auto rest = c.fabric->rest_positions();
    for (const PinDesc& p : c.pins) {
        EXPECT_NEAR(rest[p.vertex].y, 0.0, 1e-9);
        EXPECT_EQ(p.motion, 0);
    }
    EXPECT_EQ(world->model().colliders.at(0).shape, ColliderShape::Capsule);
}

}  // namespace
}  // namespace weft

namespace weft {
namespace {

// The complete example in docs/scene-format.md parses and builds, so the documentation cannot drift
// from the format.
TEST(SceneWorld, DocumentationExampleBuilds) {
    const auto doc = test::source_dir() / "docs" / "scene-format.md";
    std::ifstream in(doc);
    ASSERT_TRUE(in) << doc;
    std::ostringstream all;
    all << in.rdbuf();
    const std::string text = all.str();
    const auto heading = text.find("## Complete example");
    ASSERT_NE(heading, std::string::npos);
    const auto begin = text.find("```toml\n", heading);
    ASSERT_NE(begin, std::string::npos);
    const auto end = text.find("```", begin + 8);
    ASSERT_NE(end, std::string::npos);
    const std::string example = text.substr(begin + 8, end - begin - 8);
    const SceneDesc scene = parse_scene(example, doc);
    EXPECT_EQ(scene.name, "cape");
    EXPECT_EQ(scene.colliders.size(), 4U);
    EXPECT_TRUE(scene.world.collision.self_collision);
    EXPECT_EQ(scene.world.collision.culling, CollisionCulling::NormalCone);
    const auto world = build_world(scene);
    EXPECT_EQ(world->model().cloths[0].pins.size(), 33U);  // the top edge of a 32-cell-wide grid
    for (const PinDesc& p : world->model().cloths[0].pins) EXPECT_EQ(p.motion, 0);
}

}  // namespace
}  // namespace weft
