// The scene side of collisions: the [collision] table, mesh colliders and repeated cloths: every key
// read, every bad value an error naming the file, line and key (or the override), and what reaches
// the world.
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "scene_test_util.h"
#include "weft/backend/model.h"
#include "weft/scene.h"

namespace weft {
namespace {

using test::data_file;
using test::expect_error;
using test::scene_file;

using test::kSheet;

SceneDesc parse(std::string_view text, std::vector<std::string> overrides = {}) {
    return parse_scene(text, "inline.toml", overrides);
}

std::string parse_error(std::string_view text, std::initializer_list<std::string_view> parts) {
    return expect_error([&] { (void)parse(text); }, parts);
}

// ---- [collision] --------------------------------------------------------------------------------

TEST(SceneCollision, DefaultsComeFromTheStruct) {
    const CollisionSettings d{};
    const CollisionSettings& c = parse(kSheet).world.collision;
    EXPECT_EQ(c.self_collision, d.self_collision);
    EXPECT_EQ(c.continuous, d.continuous);
    EXPECT_EQ(c.culling, d.culling);
    EXPECT_EQ(c.thickness, d.thickness);
    EXPECT_EQ(c.stiffness, d.stiffness);
    EXPECT_EQ(c.max_impact_iterations, d.max_impact_iterations);
    EXPECT_EQ(c.check, d.check);
    // An empty table is the defaults too.
    EXPECT_EQ(parse("[collision]\n" + kSheet).world.collision.max_impact_iterations, d.max_impact_iterations);
}

TEST(SceneCollision, EveryKeyIsRead) {
    // Every value differs from its default, so a key that is not read fails here.
    const CollisionSettings d{};
    const SceneDesc s = parse(R"(
[collision]
self = true
continuous = false
culling = "none"
thickness = 0.003
stiffness = 2.5e5
max_impact_iterations = 7
impact_tolerance = 0.2
cull_contacts = true
rest_exclusion = 2.5
count_culled = true
max_impact_sweeps = 64
check = true
)" + kSheet);
    const CollisionSettings& c = s.world.collision;
    EXPECT_NE(d.self_collision, true);
    EXPECT_TRUE(c.self_collision);
    EXPECT_NE(d.continuous, false);
    EXPECT_FALSE(c.continuous);
    EXPECT_NE(d.culling, CollisionCulling::None);
    EXPECT_EQ(c.culling, CollisionCulling::None);
    EXPECT_EQ(c.thickness, 0.003);
    EXPECT_EQ(c.stiffness, 2.5e5);
    EXPECT_EQ(c.max_impact_iterations, 7);
    EXPECT_EQ(d.impact_tolerance, 0.0);  // the backend's default
    EXPECT_EQ(c.impact_tolerance, 0.2);
    EXPECT_FALSE(d.cull_contacts);
    EXPECT_TRUE(c.cull_contacts);
    EXPECT_FALSE(d.count_culled);
    EXPECT_TRUE(c.count_culled);
    EXPECT_EQ(d.rest_exclusion, 1.0);
    EXPECT_EQ(c.rest_exclusion, 2.5);
    EXPECT_EQ(d.max_impact_sweeps, 0);
    EXPECT_EQ(c.max_impact_sweeps, 64);
    EXPECT_NE(d.check, true);
    EXPECT_TRUE(c.check);
    // The other choice of culling, and the range ends.
    const SceneDesc e = parse("[collision]\nculling = \"normal_cone\"\nthickness = 0.1\nstiffness = 1e9\n"
                              "max_impact_iterations = 1000\n" + kSheet);
    EXPECT_EQ(e.world.collision.culling, CollisionCulling::NormalCone);
    EXPECT_EQ(e.world.collision.thickness, 0.1);
    EXPECT_EQ(e.world.collision.stiffness, 1e9);
    EXPECT_EQ(e.world.collision.max_impact_iterations, 1000);
    EXPECT_EQ(parse("[collision]\nthickness = 0\nstiffness = 0\nmax_impact_iterations = 1\n" + kSheet)
                  .world.collision.max_impact_iterations,
              1);
}

TEST(SceneCollision, ReachesTheWorld) {
    const SceneDesc s = parse("[collision]\nself = true\nthickness = 0.004\n" + kSheet);
    const auto world = build_world(s);
    EXPECT_TRUE(world->settings().collision.self_collision);
    EXPECT_EQ(world->settings().collision.thickness, 0.004);
}

TEST(SceneCollisionErrors, InFiles) {
    expect_error([] { (void)load_scene(data_file("collision_bad.toml")); },
                 {"collision_bad.toml:4:", "key 'collision.self'", "wrong type", "the string \"yes\"", "true or false"});
    expect_error([] { (void)load_scene(data_file("collision_out_of_range.toml")); },
                 {"collision_out_of_range.toml:5:", "key 'collision.thickness'", "0.25", "out of range", "[0, 0.1]"});
}

TEST(SceneCollisionErrors, WrongTypes) {
    parse_error("[collision]\ncontinuous = 1\n" + kSheet,
                {"inline.toml:2:", "key 'collision.continuous'", "the integer 1", "true or false"});
    parse_error("[collision]\ncheck = \"true\"\n" + kSheet, {"key 'collision.check'", "true or false"});
    parse_error("[collision]\nmax_impact_iterations = 2.5\n" + kSheet,
                {"key 'collision.max_impact_iterations'", "expected an integer in [1, 1000]"});
    parse_error("[collision]\nthickness = \"thin\"\n" + kSheet, {"key 'collision.thickness'", "a number in [0, 0.1]"});
    parse_error("[collision]\nculling = true\n" + kSheet,
                {"key 'collision.culling'", "wrong type", "\"normal_cone\", \"none\""});
    parse_error("collision = true\n" + kSheet, {"inline.toml:1:", "key 'collision'", "expected a table"});
}

TEST(SceneCollisionErrors, OutOfRange) {
    parse_error("[collision]\nthickness = -0.001\n" + kSheet, {"key 'collision.thickness'", "out of range", "[0, 0.1]"});
    parse_error("[collision]\nstiffness = 2e9\n" + kSheet, {"key 'collision.stiffness'", "out of range", "[0, 1e9]"});
    parse_error("[collision]\nstiffness = -1\n" + kSheet, {"key 'collision.stiffness'", "out of range"});
    parse_error("[collision]\nmax_impact_iterations = 0\n" + kSheet,
                {"key 'collision.max_impact_iterations'", "value 0 is out of range", "[1, 1000]"});
    parse_error("[collision]\nmax_impact_iterations = 1001\n" + kSheet,
                {"key 'collision.max_impact_iterations'", "value 1001 is out of range"});
    parse_error("[collision]\nimpact_tolerance = 0.6\n" + kSheet,
                {"key 'collision.impact_tolerance'", "out of range", "[0, 0.5]"});
    parse_error("[collision]\nrest_exclusion = 11\n" + kSheet,
                {"key 'collision.rest_exclusion'", "out of range", "[0, 10]"});
    parse_error("[collision]\nmax_impact_sweeps = -1\n" + kSheet,
                {"key 'collision.max_impact_sweeps'", "value -1 is out of range"});
    parse_error("[collision]\nthickness = inf\n" + kSheet, {"key 'collision.thickness'", "not finite"});
}

TEST(SceneCollisionErrors, UnknownKeysAndValues) {
    parse_error("[collision]\ncontinous = true\n" + kSheet,
                {"inline.toml:2:", "key 'collision.continous'", "unknown key", "did you mean 'continuous'"});
    parse_error("[collision]\nself_collision = true\n" + kSheet,
                {"key 'collision.self_collision'", "unknown key", "expected one of", "'self'", "'max_impact_iterations'"});
    parse_error("[collision]\nculling = \"normal_cones\"\n" + kSheet,
                {"inline.toml:2:", "key 'collision.culling'", "unknown value \"normal_cones\"", "did you mean \"normal_cone\""});
}

TEST(SceneCollision, Overrides) {
    // hanging.toml has no [collision]: the override creates it.
    const SceneDesc h = load_scene(scene_file("hanging"));
    ASSERT_FALSE(h.world.collision.self_collision);
    const SceneDesc s = load_scene(scene_file("hanging"), std::vector<std::string>{
                                                              "collision.self=true", "collision.culling=none",
                                                              "collision.max_impact_iterations=5", "collision.check=true",
                                                              "collision.continuous=false", "collision.thickness=0.002",
                                                              "collision.stiffness=1e4"});
    EXPECT_TRUE(s.world.collision.self_collision);
    EXPECT_EQ(s.world.collision.culling, CollisionCulling::None);  // a bare word is a string
    EXPECT_EQ(s.world.collision.max_impact_iterations, 5);
    EXPECT_TRUE(s.world.collision.check);
    EXPECT_FALSE(s.world.collision.continuous);
    EXPECT_EQ(s.world.collision.thickness, 0.002);
    EXPECT_EQ(s.world.collision.stiffness, 1e4);
    // On a scene that has the table, the override wins over the file.
    const SceneDesc off = load_scene(scene_file("sphere"), std::vector<std::string>{"collision.self=false"});
    EXPECT_FALSE(off.world.collision.self_collision);
    EXPECT_TRUE(load_scene(scene_file("sphere")).world.collision.self_collision);
}

TEST(SceneCollisionErrors, OverridesNameTheOverride) {
    const auto hanging_with = [](std::string o) {
        return [o] { (void)load_scene(scene_file("hanging"), std::vector<std::string>{o}); };
    };
    const std::string m = expect_error(hanging_with("collision.thickness=0.5"),
                                       {"--set 'collision.thickness=0.5'", "key 'collision.thickness'", "out of range"});
    EXPECT_EQ(m.find("hanging.toml"), std::string::npos) << m;
    expect_error(hanging_with("collision.selff=true"),
                 {"--set 'collision.selff=true'", "key 'collision.selff'", "did you mean 'self'"});
    expect_error(hanging_with("collision.self=yes"), {"--set 'collision.self=yes'", "key 'collision.self'", "true or false"});
    expect_error(hanging_with("collision.culling=cones"),
                 {"--set 'collision.culling=cones'", "unknown value \"cones\"", "\"normal_cone\", \"none\""});
}

// ---- mesh colliders -----------------------------------------------------------------------------

TEST(SceneMeshCollider, Parses) {
    const SceneDesc s = load_scene(data_file("mesh_collider.toml"));
    ASSERT_EQ(s.colliders.size(), 4U);
    ASSERT_EQ(s.collider_meshes.size(), 4U);
    ASSERT_EQ(s.collider_motions.size(), 4U);
    const auto tetra = data_file("tetra.obj").lexically_normal();
    const ColliderDesc& rock = s.colliders[0];
    EXPECT_EQ(rock.shape, ColliderShape::Mesh);
    EXPECT_FALSE(rock.is_analytic());
    EXPECT_EQ(rock.mesh, nullptr);  // read by build_world()
    EXPECT_EQ(s.collider_meshes[0].file, tetra);
    EXPECT_EQ(s.collider_meshes[0].scale, 2.0);
    EXPECT_EQ(rock.friction, 0.7);
    // position/rotation go into the collider's frame exactly as for an analytic collider.
    EXPECT_EQ(rock.motion.origin, (Vec3d{1.0, 0.0, -1.0}));
    const Vec3d x = rock.motion.initial_rotation * Vec3d{1, 0, 0};  // [0, 90, 0] turns +x to −z
    EXPECT_NEAR(x.z, -1.0, 1e-12);
    EXPECT_TRUE(rock.motion.is_static());
    EXPECT_EQ(s.collider_motions[0], "");
    // Following a motion: its frame.
    EXPECT_EQ(s.colliders[1].shape, ColliderShape::Mesh);
    EXPECT_EQ(s.collider_motions[1], "turn");
    EXPECT_EQ(s.colliders[1].motion.angular_velocity, (Vec3d{0, 1, 0}));
    EXPECT_EQ(s.colliders[1].motion.origin, (Vec3d{0, 0.5, 0}));
    EXPECT_EQ(s.collider_meshes[1].scale, 1.0);
    EXPECT_EQ(s.collider_meshes[2].file, tetra);  // "./tetra.obj" resolves to the same file
    // Analytic colliders have no mesh source.
    EXPECT_EQ(s.colliders[3].shape, ColliderShape::Sphere);
    EXPECT_TRUE(s.collider_meshes[3].file.empty());
}

TEST(SceneMeshCollider, BuildLoadsTheMeshInTheLocalFrame) {
    if (!test::install_loader()) GTEST_SKIP() << "weft::assets not built";
    const SceneDesc s = load_scene(data_file("mesh_collider.toml"));
    const auto world = build_world(s);
    const auto& colliders = world->model().colliders;
    ASSERT_EQ(colliders.size(), 4U);
    const ColliderDesc& rock = colliders[0];
    ASSERT_NE(rock.mesh, nullptr);
    EXPECT_EQ(rock.mesh->positions.size(), 4U);
    EXPECT_EQ(rock.mesh->triangles.size(), 4U);
    // The local frame is the file's coordinates times scale, not moved by position or rotation.
    Vec3d lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
    for (const Vec3d& p : rock.mesh->positions)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], p[k]);
            hi[k] = std::max(hi[k], p[k]);
        }
    EXPECT_EQ(lo, (Vec3d{0, 0, 0}));
    EXPECT_EQ(hi, (Vec3d{2, 2, 2}));
    // The world position of the local (2, 0, 0) corner: turned to −z, then moved by position.
    const Vec3d w = rock.motion.at(0.0).apply(Vec3d{2, 0, 0});
    EXPECT_NEAR(w.x, 1.0, 1e-12);
    EXPECT_NEAR(w.y, 0.0, 1e-12);
    EXPECT_NEAR(w.z, -3.0, 1e-12);
    // Same file and scale: one shared mesh; another scale: its own.
    EXPECT_EQ(colliders[2].mesh, rock.mesh);
    ASSERT_NE(colliders[1].mesh, nullptr);
    EXPECT_NE(colliders[1].mesh, rock.mesh);
    Vec3d hi1{-1e9, -1e9, -1e9};
    for (const Vec3d& p : colliders[1].mesh->positions)
        for (int k = 0; k < 3; ++k) hi1[k] = std::max(hi1[k], p[k]);
    EXPECT_EQ(hi1, (Vec3d{1, 1, 1}));
    EXPECT_EQ(colliders[3].mesh, nullptr);
    // The world steps with mesh colliders in it (the backends skip them in their analytic loops).
    for (int i = 0; i < 3; ++i) (void)world->step();
    for (const Vec3d& p : world->positions(0)) ASSERT_TRUE(math::is_finite(p));
}

TEST(SceneMeshColliderErrors, MissingFileNamesIt) {
    expect_error([] { (void)load_scene(data_file("missing_collider_mesh.toml")); },
                 {"missing_collider_mesh.toml:9:", "key 'collider[0].file'", "mesh file not found",
                  (data_file("no_such_body.obj").lexically_normal()).string(), "relative to the scene file"});
}

TEST(SceneMeshColliderErrors, FileOnAnAnalyticShape) {
    expect_error([] { (void)load_scene(data_file("collider_file_on_sphere.toml")); },
                 {"collider_file_on_sphere.toml:9:", "key 'collider[0].file'", "a sphere collider has no file",
                  "shape = \"mesh\""});
    parse_error(kSheet + "[[collider]]\nshape = \"plane\"\nfile = \"x.obj\"\n",
                {"inline.toml:7:", "key 'collider[0].file'", "a plane collider has no file"});
    parse_error(kSheet + "[[collider]]\nshape = \"box\"\nscale = 2\n",
                {"inline.toml:7:", "key 'collider[0].scale'", "a box collider has no scale"});
}

TEST(SceneMeshColliderErrors, KeysOfOtherShapes) {
    const std::string mesh = kSheet + "[[collider]]\nshape = \"mesh\"\nfile = \"" +
                             data_file("tetra.obj").generic_string() + "\"\n";
    parse_error(mesh + "radius = 0.3\n",
                {"inline.toml:8:", "key 'collider[0].radius'", "a mesh collider has no radius"});
    parse_error(mesh + "half_height = 0.3\n", {"key 'collider[0].half_height'", "a mesh collider has no half_height"});
    parse_error(mesh + "half_extents = [1, 1, 1]\n",
                {"key 'collider[0].half_extents'", "a mesh collider has no half_extents"});
    parse_error(mesh + "scale = 0\n", {"inline.toml:8:", "key 'collider[0].scale'", "out of range", "(0, 1e6]"});
    parse_error(mesh + "scale = \"big\"\n", {"key 'collider[0].scale'", "wrong type"});
    parse_error(mesh + "flie = \"x\"\n", {"key 'collider[0].flie'", "did you mean 'file'"});
    parse_error(kSheet + "[[motion]]\nname = \"m\"\n[[collider]]\nshape = \"mesh\"\nmotion = \"m\"\nfile = \"" +
                    data_file("tetra.obj").generic_string() + "\"\nrotation = [0, 1, 0]\n",
                {"key 'collider[0].rotation'", "either motion or position/rotation"});
}

TEST(SceneMeshColliderErrors, FileRequiredAndTyped) {
    parse_error(kSheet + "[[collider]]\nname = \"body\"\nshape = \"mesh\"\n",
                {"inline.toml:5:", "key 'collider[0].file'", "missing required key", "mesh file path"});
    parse_error(kSheet + "[[collider]]\nshape = \"mesh\"\nfile = 3\n",
                {"inline.toml:7:", "key 'collider[0].file'", "wrong type", "a string"});
    parse_error(kSheet + "[[collider]]\nshape = \"meshh\"\n", {"key 'collider[0].shape'", "did you mean \"mesh\""});
}

TEST(SceneMeshColliderErrors, ZeroAreaTrianglesAreRefused) {
    if (!test::install_loader()) GTEST_SKIP() << "weft::assets not built";
    const std::string text = kSheet + "[[collider]]\nname = \"bad\"\nshape = \"mesh\"\nfile = \"" +
                             data_file("collider_degenerate.obj").generic_string() + "\"\n";
    const SceneDesc s = parse_scene(text, "degenerate_collider.toml");  // loads: the file exists
    expect_error([&] { (void)build_world(s); },
                 {"degenerate_collider.toml", "collider[0] 'bad'", "collider_degenerate.obj",
                  "1 of 5 triangles have zero area", "the first is triangle 4"});
}

TEST(SceneMeshColliderErrors, UnreadableMeshNamesTheCollider) {
    if (!test::install_loader()) GTEST_SKIP() << "weft::assets not built";
    // A file that exists but is no mesh: the importer's error, prefixed with the collider.
    const std::string text = kSheet + "[[collider]]\nname = \"junk\"\nshape = \"mesh\"\nfile = \"" +
                             data_file("bad_syntax.toml").generic_string() + "\"\n";
    const SceneDesc s = parse_scene(text, "junk.toml");
    expect_error([&] { (void)build_world(s); }, {"junk.toml", "collider[0] 'junk'", "bad_syntax.toml"});
}

// ---- repeat ---------------------------------------------------------------------------------------

const std::string kStack = R"(
[[motion]]
name = "m"
[[cloth]]
name = "sheets"
mesh = { grid = { width = 1.0, height = 1.0, cells = [4, 4], plane = "xz" } }
position = [1.0, 2.0, 3.0]
rotation = [0.0, 10.0, 0.0]
repeat = { count = 3, offset = [0.0, 0.1, -0.2], rotation_step = [0.0, 80.0, 0.0] }
density = 0.3
[cloth.material]
friction = 0.6
[[cloth.pin]]
corners = "top"
motion = "m"
[[cloth]]
name = "other"
mesh = { grid = { cells = [2, 2] } }
)";

TEST(SceneRepeat, NamesPlacesAndCopies) {
    const SceneDesc s = parse(kStack);
    ASSERT_EQ(s.cloths.size(), 4U);
    for (int k = 0; k < 3; ++k) {
        SCOPED_TRACE(k);
        const SceneCloth& c = s.cloths[static_cast<std::size_t>(k)];
        EXPECT_EQ(c.desc.name, "sheets" + std::to_string(k));
        EXPECT_EQ(c.entry, 0U);
        // Copy k at position + k·offset.
        EXPECT_NEAR(c.desc.transform.translation.x, 1.0, 1e-15);
        EXPECT_NEAR(c.desc.transform.translation.y, 2.0 + 0.1 * k, 1e-15);
        EXPECT_NEAR(c.desc.transform.translation.z, 3.0 - 0.2 * k, 1e-15);
        // Turned by rotation + k·rotation_step about y: +x goes to (cos a, 0, −sin a).
        const double a = (10.0 + 80.0 * k) * std::numbers::pi / 180.0;
        const Vec3d x = c.desc.transform.rotation * Vec3d{1, 0, 0};
        EXPECT_NEAR(x.x, std::cos(a), 1e-12);
        EXPECT_NEAR(x.z, -std::sin(a), 1e-12);
        // Everything else is the table's.
        EXPECT_EQ(c.source.cells_x, 4);
        EXPECT_EQ(c.fabric.density, 0.3);
        EXPECT_EQ(c.desc.material.friction, 0.6);
        ASSERT_EQ(c.pins.size(), 1U);
        EXPECT_EQ(c.pins[0].motion, "m");
    }
    EXPECT_EQ(s.cloths[3].desc.name, "other");
    EXPECT_EQ(s.cloths[3].entry, 1U);
}

TEST(SceneRepeat, DefaultNameAndSingleCopy) {
    const SceneDesc s = parse("[[cloth]]\nmesh = { grid = {} }\nrepeat = { count = 2, offset = [0, 1, 0] }\n"
                              "[[cloth]]\nmesh = { grid = {} }\nrepeat = { count = 1 }\n"
                              "[[cloth]]\nmesh = { grid = {} }\n");
    ASSERT_EQ(s.cloths.size(), 4U);
    EXPECT_EQ(s.cloths[0].desc.name, "cloth00");
    EXPECT_EQ(s.cloths[1].desc.name, "cloth01");
    EXPECT_EQ(s.cloths[2].desc.name, "cloth10");  // count = 1: one copy, still numbered; no offset needed
    EXPECT_EQ(s.cloths[2].desc.transform.translation, (Vec3d{}));
    EXPECT_EQ(s.cloths[3].desc.name, "cloth2");
    EXPECT_EQ(s.cloths[3].entry, 2U);
}

TEST(SceneRepeat, CopiesShareOneFabricAndEachGetsItsPins) {
    const SceneDesc s = parse(kStack);
    const auto world = build_world(s);
    const Model& m = world->model();
    ASSERT_EQ(m.cloths.size(), 4U);
    ASSERT_NE(m.cloths[0].fabric, nullptr);
    EXPECT_EQ(m.cloths[1].fabric, m.cloths[0].fabric);
    EXPECT_EQ(m.cloths[2].fabric, m.cloths[0].fabric);
    EXPECT_NE(m.cloths[3].fabric, m.cloths[0].fabric);
    for (std::size_t k = 0; k < 3; ++k) {
        ASSERT_EQ(m.cloths[k].pins.size(), 2U);  // the two far corners of a 4×4 grid: 20 and 24
        EXPECT_EQ(m.cloths[k].pins[0].vertex, 20U);
        EXPECT_EQ(m.cloths[k].pins[1].vertex, 24U);
        EXPECT_EQ(m.cloths[k].pins[0].motion, 0);
    }
    // Placement reaches the state: copy 2's vertex 0 is its rest position moved by its transform.
    const Vec3d rest = m.cloths[2].fabric->rest_positions()[0];
    const Vec3d expected = m.cloths[2].transform.apply(rest);
    const Vec3d got = world->positions(2)[0];
    EXPECT_NEAR(got.y, expected.y, 1e-12);
    EXPECT_NEAR(got.y, 2.2, 1e-12);  // an xz grid lies at the copy's height
    (void)world->step();
    for (std::size_t c = 0; c < m.cloths.size(); ++c)
        for (const Vec3d& p : world->positions(c)) ASSERT_TRUE(math::is_finite(p));
}

TEST(SceneRepeat, Overrides) {
    const SceneDesc base = load_scene(scene_file("layers"));
    const SceneDesc s = load_scene(scene_file("layers"), std::vector<std::string>{"cloth.sheets.repeat.count=50"});
    ASSERT_EQ(s.cloths.size(), 50U);
    EXPECT_EQ(s.cloths.front().desc.name, "sheets0");
    EXPECT_EQ(s.cloths.back().desc.name, "sheets49");
    const Vec3d first = s.cloths.front().desc.transform.translation;
    const Vec3d last = s.cloths.back().desc.transform.translation;
    EXPECT_NEAR(last.y - first.y, 49 * 0.02, 1e-12);
    EXPECT_EQ(first, base.cloths.front().desc.transform.translation);
    // The table's name selects every copy for other keys too.
    const SceneDesc f = load_scene(scene_file("layers"), std::vector<std::string>{
                                                             "cloth.sheets.repeat.offset=[0, 0.05, 0]",
                                                             "cloth.sheets.material.friction=0.9"});
    ASSERT_EQ(f.cloths.size(), base.cloths.size());
    EXPECT_NEAR(f.cloths[1].desc.transform.translation.y - f.cloths[0].desc.transform.translation.y, 0.05, 1e-12);
    for (const SceneCloth& c : f.cloths) EXPECT_EQ(c.desc.material.friction, 0.9);
    // repeat added to a scene whose cloth has none.
    const SceneDesc h = load_scene(scene_file("hanging"), std::vector<std::string>{"cloth.sheet.repeat.count=3",
                                                                                   "cloth.sheet.repeat.offset=[0,0,0.1]"});
    ASSERT_EQ(h.cloths.size(), 3U);
    EXPECT_EQ(h.cloths[2].desc.name, "sheet2");
}

TEST(SceneRepeatErrors, Count) {
    expect_error([] { (void)load_scene(data_file("repeat_bad.toml")); },
                 {"repeat_bad.toml:6:", "key 'cloth[0].repeat.count'", "value 0 is out of range", "[1, 10000]"});
    const std::string head = "[[cloth]]\nname = \"s\"\nmesh = { grid = {} }\n";
    parse_error(head + "repeat = { count = 10001, offset = [0, 1, 0] }\n",
                {"inline.toml:4:", "key 'cloth[0].repeat.count'", "value 10001 is out of range"});
    parse_error(head + "repeat = { count = \"3\", offset = [0, 1, 0] }\n",
                {"key 'cloth[0].repeat.count'", "wrong type", "an integer in [1, 10000]"});
    parse_error(head + "repeat = { count = 2.0, offset = [0, 1, 0] }\n", {"key 'cloth[0].repeat.count'", "wrong type"});
    parse_error(head + "repeat = { offset = [0, 1, 0] }\n",
                {"inline.toml:4:", "key 'cloth[0].repeat.count'", "missing required key"});
    const std::string m = expect_error(
        [] { (void)load_scene(scene_file("layers"), std::vector<std::string>{"cloth.sheets.repeat.count=0"}); },
        {"--set 'cloth.sheets.repeat.count=0'", "key 'cloth[0].repeat.count'", "out of range"});
    EXPECT_EQ(m.find("layers.toml"), std::string::npos) << m;
}

TEST(SceneRepeatErrors, PlacementAndKeys) {
    const std::string head = "[[cloth]]\nname = \"s\"\nmesh = { grid = {} }\n";
    parse_error(head + "repeat = { count = 3 }\n", {"key 'cloth[0].repeat.offset'", "would all lie on the first"});
    parse_error(head + "repeat = { count = 3, offset = [0, 0, 0] }\n",
                {"inline.toml:4:", "key 'cloth[0].repeat.offset'", "would all lie on the first"});
    parse_error(head + "repeat = { count = 3, offset = [0, 1] }\n", {"key 'cloth[0].repeat.offset'", "3 numbers"});
    parse_error(head + "repeat = { count = 3, offset = [1e308, 0, 0] }\n", {"key 'cloth[0].repeat.offset'", "not finite"});
    parse_error(head + "repeat = { count = 3, offest = [0, 1, 0] }\n",
                {"key 'cloth[0].repeat.offest'", "did you mean 'offset'"});
    parse_error(head + "repeat = { count = 3, rotation_step = [0, 1, \"x\"] }\n",
                {"key 'cloth[0].repeat.rotation_step'", "element 2"});
    parse_error(head + "repeat = 3\n", {"inline.toml:4:", "key 'cloth[0].repeat'", "expected a table"});
    // rotation_step alone separates the copies.
    EXPECT_EQ(parse(head + "repeat = { count = 3, rotation_step = [0, 0, 30] }\n").cloths.size(), 3U);
}

TEST(SceneRepeatErrors, NamesStayUnique) {
    // "a" repeated makes a0 and a1; a cloth called "a1" clashes with the second copy.
    parse_error("[[cloth]]\nname = \"a\"\nmesh = { grid = {} }\nrepeat = { count = 2, offset = [0, 1, 0] }\n"
                "[[cloth]]\nname = \"a1\"\nmesh = { grid = {} }\n",
                {"inline.toml:6:", "key 'cloth[1].name'", "duplicate name 'a1'"});
    parse_error("[[cloth]]\nname = \"a1\"\nmesh = { grid = {} }\n"
                "[[cloth]]\nname = \"a\"\nmesh = { grid = {} }\nrepeat = { count = 2, offset = [0, 1, 0] }\n",
                {"inline.toml:5:", "key 'cloth[1].name'", "duplicate name 'a1'"});
    // Two tables may not share the name that --set selects them by, repeated or not.
    parse_error("[[cloth]]\nname = \"a\"\nmesh = { grid = {} }\nrepeat = { count = 2, offset = [0, 1, 0] }\n"
                "[[cloth]]\nname = \"a\"\nmesh = { grid = {} }\n",
                {"key 'cloth[1].name'", "duplicate name 'a'"});
}

// A mesh collider with a `clip` is an animated character: the file is read as a skinned mesh, the
// collider plays the clip (speed and loop from the scene), the scene writes it back; a clip the file
// does not hold and a scale with a clip are refused naming the scene, the collider and the clips.
TEST(SceneSkinnedCollider, AClipMakesTheMeshACharacter) {
    if (!test::install_loader()) GTEST_SKIP() << "weft::assets not built";
    const std::string runner = (test::source_dir() / "assets/characters/runner.gltf").generic_string();
    const std::string text = kSheet + "[[collider]]\nname = \"runner\"\nshape = \"mesh\"\nfile = \"" + runner +
                             "\"\nclip = \"run\"\nclip_speed = 1.5\nclip_loop = false\n";
    const SceneDesc s = parse_scene(text, "runner.toml");
    ASSERT_EQ(s.collider_meshes.size(), 1U);
    EXPECT_EQ(s.collider_meshes[0].clip, "run");
    const auto world = build_world(s);
    const ColliderDesc& c = world->model().colliders.at(0);
    ASSERT_NE(c.skin, nullptr);
    EXPECT_EQ(c.clip, "run");
    EXPECT_EQ(c.clip_speed, 1.5);
    EXPECT_FALSE(c.clip_loop);
    EXPECT_EQ(c.mesh->positions.size(), c.skin->mesh.positions.size());
    EXPECT_TRUE(c.moves());
    const SceneDesc again = parse_scene(scene_to_toml(s, test::source_dir()), test::source_dir() / "again.toml");
    EXPECT_EQ(again.collider_meshes.at(0).clip, "run");
    EXPECT_EQ(again.colliders.at(0).clip_speed, 1.5);
    EXPECT_FALSE(again.colliders.at(0).clip_loop);

    std::string wrong = text;
    wrong.replace(wrong.find("\"run\""), 5, "\"walk\"");
    expect_error([&] { (void)build_world(parse_scene(wrong, "walk.toml")); },
                 {"walk.toml", "collider[0] 'runner'", "no animation clip 'walk'", "'run', 'jump'"});
    expect_error([&] { (void)build_world(parse_scene(text + "scale = 2.0\n", "scaled.toml")); },
                 {"scaled.toml", "collider[0] 'runner'", "scale 2", "with a clip"});
}

}  // namespace
}  // namespace weft
