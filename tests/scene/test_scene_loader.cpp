// Scene files: the shipped scenes parse, defaults hold, and every kind of bad input is an error that
// names the file, the line and the key.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>

#include "scene_test_util.h"
#include "weft/scene.h"

namespace weft {
namespace {

using test::data_file;
using test::expect_error;
using test::scene_file;

using test::kSheet;

SceneDesc parse(std::string_view text) { return parse_scene(text, "inline.toml"); }

std::string parse_error(std::string_view text, std::initializer_list<std::string_view> parts) {
    return expect_error([&] { (void)parse(text); }, parts);
}

TEST(SceneLoader, ShippedScenesParse) {
    // Every file in assets/scenes/, not a list that could miss a new one.
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(test::source_dir() / "assets" / "scenes"))
        if (entry.path().extension() == ".toml") names.push_back(entry.path().stem().string());
    std::sort(names.begin(), names.end());
    EXPECT_GE(names.size(), 11U);
    const std::set<std::string> unpinned{"drape", "sphere", "falling", "layers"};
    for (const std::string& name : names) {
        SCOPED_TRACE(name);
        const SceneDesc scene = load_scene(scene_file(name));
        EXPECT_EQ(scene.name, name);
        EXPECT_EQ(scene.path, scene_file(name));
        ASSERT_FALSE(scene.cloths.empty());
        EXPECT_GT(scene.frames, 0);
        EXPECT_EQ(scene.collider_motions.size(), scene.colliders.size());
        EXPECT_EQ(scene.collider_meshes.size(), scene.colliders.size());
        EXPECT_EQ(scene.cloths[0].pins.empty(), unpinned.contains(name));
    }
}

TEST(SceneLoader, FlagValues) {
    const SceneDesc s = load_scene(scene_file("flag"));
    EXPECT_DOUBLE_EQ(s.world.wind.velocity.x, 8.0);
    EXPECT_GT(s.world.wind.turbulence, 0.0);
    ASSERT_EQ(s.cloths.size(), 1U);
    const SceneCloth& c = s.cloths[0];
    EXPECT_EQ(c.desc.name, "flag");
    EXPECT_EQ(c.source.kind, ClothSource::Kind::Grid);
    EXPECT_EQ(c.source.plane, GridPlane::XY);
    EXPECT_EQ(c.source.cells_x, 40);
    EXPECT_EQ(c.source.cells_y, 24);
    EXPECT_DOUBLE_EQ(c.source.width, 2.0);
    EXPECT_DOUBLE_EQ(c.desc.transform.translation.x, 1.0);
    ASSERT_EQ(c.pins.size(), 1U);
    EXPECT_EQ(c.pins[0].kind, PinSelection::Kind::Edge);
    EXPECT_EQ(c.pins[0].edge, "left");
    ASSERT_EQ(s.colliders.size(), 2U);
    EXPECT_EQ(s.colliders[0].shape, ColliderShape::Capsule);
    EXPECT_EQ(s.colliders[1].shape, ColliderShape::Plane);
    EXPECT_EQ(s.world.solver.precision, Precision::Double);
    EXPECT_EQ(s.world.solver.substeps, 2);
}

TEST(SceneLoader, SkirtResolvesMeshAndMotion) {
    const SceneDesc s = load_scene(scene_file("skirt"));
    ASSERT_EQ(s.cloths.size(), 1U);
    EXPECT_EQ(s.cloths[0].source.kind, ClothSource::Kind::File);
    EXPECT_EQ(s.cloths[0].source.file, (test::source_dir() / "assets" / "meshes" / "skirt.obj").lexically_normal());
    ASSERT_EQ(s.motions.size(), 1U);
    EXPECT_EQ(s.cloths[0].pins.at(0).motion, "hips");
    ASSERT_EQ(s.collider_motions.size(), 1U);
    EXPECT_EQ(s.collider_motions[0], "hips");
    // The collider carries the motion itself.
    EXPECT_DOUBLE_EQ(s.colliders[0].motion.origin.y, 0.85);
    EXPECT_DOUBLE_EQ(s.colliders[0].motion.frequency, 0.5);
}

TEST(SceneLoader, DefaultsComeFromTheStructs) {
    const SceneDesc s = parse(kSheet);
    EXPECT_EQ(s.name, "inline");
    const SolverSettings d{};
    EXPECT_EQ(s.world.solver.dt, d.dt);
    EXPECT_EQ(s.world.solver.substeps, d.substeps);
    EXPECT_EQ(s.world.solver.cg_tolerance, d.cg_tolerance);
    EXPECT_EQ(s.world.gravity, (WorldDesc{}.gravity));
    EXPECT_FALSE(s.world.wind.active());
    const Material m{};
    const Material& got = s.cloths[0].desc.material;
    EXPECT_EQ(got.stretch_stiffness, m.stretch_stiffness);
    EXPECT_EQ(got.bending_stiffness, m.bending_stiffness);
    EXPECT_EQ(got.friction, m.friction);
    EXPECT_EQ(s.cloths[0].fabric.density, FabricDesc{}.density);
    EXPECT_TRUE(s.colliders.empty());
    EXPECT_EQ(s.frames, SceneDesc{}.frames);
}

TEST(SceneLoader, EveryKeyIsRead) {
    const SceneDesc s = parse(R"(
[scene]
name = "all"
frames = 12
[solver]
dt = 0.01
substeps = 3
newton_iterations = 2
cg_tolerance = 1e-6
cg_max_iterations = 77
precision = "float"
hessian = "projected"
contact_stiffness = 1e4
threads = 2
[world]
gravity = [0, -3, 0]
[wind]
velocity = [1, 2, 3]
air_density = 1.1
turbulence = 0.5
turbulence_frequency = 2
turbulence_scale = 0.25
[[motion]]
name = "m"
origin = [1, 2, 3]
rotation = [0, 0, 90]
linear_velocity = [0.1, 0, 0]
angular_velocity = [0, 1, 0]
amplitude = [0, 0.2, 0]
frequency = 0.5
phase = 1.5
[[cloth]]
name = "c"
mesh = { grid = { width = 2, height = 3, cells = [5, 6], plane = "xz" } }
position = [0, 1, 0]
rotation = [90, 0, 0]
initial_velocity = [0, 0, -1]
density = 0.3
flat_rest_bending = true
[cloth.material]
stretch_stiffness = 1e4
poisson_ratio = 0.2
bending_stiffness = 1e-4
damping_mass = 0.1
damping_stiffness = 0.01
drag_coefficient = 1.5
lift_coefficient = 0.5
contact_thickness = 0.002
friction = 0.7
[[cloth.pin]]
vertices = [0, 1, 2]
motion = "m"
[[cloth.pin]]
box = { min = [-1, -1, -1], max = [1, 1, 1] }
[[cloth.pin]]
corners = "all"
[[collider]]
name = "b"
shape = "box"
half_extents = [0.1, 0.2, 0.3]
friction = 0.9
rotation = [0, 45, 0]
position = [1, 0, 0]
[[collider]]
name = "k"
shape = "capsule"
radius = 0.2
half_height = 0.4
motion = "m"
[camera]
position = [0, 2, 5]
target = [0, 1, 0]
fov = 60
)");
    EXPECT_EQ(s.name, "all");
    EXPECT_EQ(s.frames, 12);
    const SolverSettings& v = s.world.solver;
    EXPECT_EQ(v.dt, 0.01);
    EXPECT_EQ(v.substeps, 3);
    EXPECT_EQ(v.newton_iterations, 2);
    EXPECT_EQ(v.cg_tolerance, 1e-6);
    EXPECT_EQ(v.cg_max_iterations, 77);
    EXPECT_EQ(v.precision, Precision::Float);
    EXPECT_EQ(v.hessian, HessianMode::Projected);
    EXPECT_EQ(v.contact_stiffness, 1e4);
    EXPECT_EQ(v.threads, 2);
    EXPECT_EQ(s.world.gravity, (Vec3d{0, -3, 0}));
    EXPECT_EQ(s.world.wind.velocity, (Vec3d{1, 2, 3}));
    EXPECT_EQ(s.world.wind.air_density, 1.1);
    EXPECT_EQ(s.world.wind.turbulence, 0.5);
    EXPECT_EQ(s.world.wind.turbulence_frequency, 2.0);
    EXPECT_EQ(s.world.wind.turbulence_scale, 0.25);
    ASSERT_EQ(s.motions.size(), 1U);
    const Motion& m = s.motions[0].motion;
    EXPECT_EQ(m.origin, (Vec3d{1, 2, 3}));
    EXPECT_EQ(m.linear_velocity, (Vec3d{0.1, 0, 0}));
    EXPECT_EQ(m.angular_velocity, (Vec3d{0, 1, 0}));
    EXPECT_EQ(m.amplitude, (Vec3d{0, 0.2, 0}));
    EXPECT_EQ(m.frequency, 0.5);
    EXPECT_EQ(m.phase, 1.5);
    // rotation = [0, 0, 90]: +x turns to +y.
    const Vec3d x = m.initial_rotation * Vec3d{1, 0, 0};
    EXPECT_NEAR(x.x, 0.0, 1e-12);
    EXPECT_NEAR(x.y, 1.0, 1e-12);
    const SceneCloth& c = s.cloths.at(0);
    EXPECT_EQ(c.source.width, 2.0);
    EXPECT_EQ(c.source.height, 3.0);
    EXPECT_EQ(c.source.cells_x, 5);
    EXPECT_EQ(c.source.cells_y, 6);
    EXPECT_EQ(c.source.plane, GridPlane::XZ);
    EXPECT_EQ(c.desc.transform.translation, (Vec3d{0, 1, 0}));
    // rotation = [90, 0, 0]: +y turns to +z.
    const Vec3d y = c.desc.transform.rotation * Vec3d{0, 1, 0};
    EXPECT_NEAR(y.z, 1.0, 1e-12);
    EXPECT_EQ(c.desc.initial_velocity, (Vec3d{0, 0, -1}));
    EXPECT_EQ(c.fabric.density, 0.3);
    EXPECT_TRUE(c.fabric.flat_rest_bending);
    const Material& mat = c.desc.material;
    EXPECT_EQ(mat.stretch_stiffness, 1e4);
    EXPECT_EQ(mat.poisson_ratio, 0.2);
    EXPECT_EQ(mat.bending_stiffness, 1e-4);
    EXPECT_EQ(mat.damping_mass, 0.1);
    EXPECT_EQ(mat.damping_stiffness, 0.01);
    EXPECT_EQ(mat.drag_coefficient, 1.5);
    EXPECT_EQ(mat.lift_coefficient, 0.5);
    EXPECT_EQ(mat.contact_thickness, 0.002);
    EXPECT_EQ(mat.friction, 0.7);
    ASSERT_EQ(c.pins.size(), 3U);
    EXPECT_EQ(c.pins[0].kind, PinSelection::Kind::Vertices);
    EXPECT_EQ(c.pins[0].vertices, (std::vector<std::uint32_t>{0, 1, 2}));
    EXPECT_EQ(c.pins[0].motion, "m");
    EXPECT_EQ(c.pins[1].kind, PinSelection::Kind::Box);
    EXPECT_EQ(c.pins[1].box_min, (Vec3d{-1, -1, -1}));
    EXPECT_EQ(c.pins[2].kind, PinSelection::Kind::Corners);
    EXPECT_EQ(c.pins[2].edge, "all");
    ASSERT_EQ(s.colliders.size(), 2U);
    EXPECT_EQ(s.colliders[0].shape, ColliderShape::Box);
    EXPECT_EQ(s.colliders[0].half_extents, (Vec3d{0.1, 0.2, 0.3}));
    EXPECT_EQ(s.colliders[0].friction, 0.9);
    EXPECT_EQ(s.colliders[0].motion.origin, (Vec3d{1, 0, 0}));
    EXPECT_EQ(s.collider_motions[0], "");
    EXPECT_EQ(s.colliders[1].radius, 0.2);
    EXPECT_EQ(s.colliders[1].half_height, 0.4);
    EXPECT_EQ(s.colliders[1].friction, -1.0);
    EXPECT_EQ(s.collider_motions[1], "m");
    EXPECT_EQ(s.colliders[1].motion.frequency, 0.5);
    EXPECT_EQ(s.camera.position, (Vec3d{0, 2, 5}));
    EXPECT_EQ(s.camera.fov_degrees, 60.0);
}

// ---- bad input files: file name, line and key in every message -----------------------------------

// `preset = "NAME"` in [solver] sets the preset's values first; the table's own keys and the
// [collision] table win over it; an unknown name is an error naming the line and the presets.
TEST(SceneLoader, ASolverPresetIsABaseTheTablesKeysOverride) {
    const SceneDesc plain = parse(kSheet);
    const SceneDesc game = parse("[solver]\npreset = \"game\"\n" + kSheet);
    EXPECT_EQ(game.world.solver.substeps, 1);
    EXPECT_EQ(game.world.solver.newton_iterations, 1);
    EXPECT_DOUBLE_EQ(game.world.solver.cg_tolerance, 1e-3);
    EXPECT_EQ(game.world.solver.cg_max_iterations, 300);
    EXPECT_EQ(game.world.solver.precision, Precision::Float);
    EXPECT_EQ(game.world.solver.preconditioner, Preconditioner::Schwarz);
    EXPECT_NE(plain.world.solver.cg_max_iterations, 300) << "the default would not show the preset";
    const SceneDesc mixed = parse("[solver]\npreset = \"game\"\ncg_tolerance = 1e-5\n[collision]\nmode = \"offset\"\n" + kSheet);
    EXPECT_DOUBLE_EQ(mixed.world.solver.cg_tolerance, 1e-5);
    EXPECT_EQ(mixed.world.solver.cg_max_iterations, 300);
    EXPECT_EQ(mixed.world.collision.mode, CollisionMode::Offset);
    parse_error("[solver]\npreset = \"gme\"\n" + kSheet,
                {"inline.toml:2:", "unknown solver preset 'gme'", "did you mean 'game'", "interactive, game"});
}

TEST(SceneLoaderErrors, SyntaxError) {
    expect_error([] { (void)load_scene(data_file("bad_syntax.toml")); }, {"bad_syntax.toml:6:", "syntax error"});
}

TEST(SceneLoaderErrors, UnknownKeyWithSuggestion) {
    expect_error([] { (void)load_scene(data_file("unknown_key.toml")); },
                 {"unknown_key.toml:9:1: ", "key 'cloth[0].material.stretch_stifness'", "unknown key",
                  "did you mean 'stretch_stiffness'"});
}

TEST(SceneLoaderErrors, WrongType) {
    expect_error([] { (void)load_scene(data_file("wrong_type.toml")); },
                 {"wrong_type.toml:4:", "key 'solver.substeps'", "the string \"four\"", "expected an integer in [1, 1000]"});
}

TEST(SceneLoaderErrors, OutOfRange) {
    expect_error([] { (void)load_scene(data_file("out_of_range.toml")); },
                 {"out_of_range.toml:8:", "key 'cloth[0].material.poisson_ratio'", "0.7", "out of range",
                  "[0, 0.49]"});
}

TEST(SceneLoaderErrors, UnknownMotion) {
    expect_error([] { (void)load_scene(data_file("bad_motion.toml")); },
                 {"bad_motion.toml:13:", "key 'cloth[0].pin[0].motion'", "unknown motion 'shoulderr'",
                  "did you mean 'shoulder'"});
}

TEST(SceneLoaderErrors, MissingMeshFile) {
    expect_error([] { (void)load_scene(data_file("missing_mesh.toml")); },
                 {"missing_mesh.toml:5:", "key 'cloth[0].mesh.file'", "no_such_mesh.obj", "not found"});
}

TEST(SceneLoaderErrors, MissingRequiredKey) {
    expect_error([] { (void)load_scene(data_file("missing_key.toml")); },
                 {"missing_key.toml:7:", "key 'collider[0].shape'", "missing required key"});
}

TEST(SceneLoaderErrors, MissingSceneFile) {
    expect_error([] { (void)load_scene(data_file("does_not_exist.toml")); }, {"does_not_exist.toml", "cannot open"});
}

// ---- bad input text: one case per validation rule ------------------------------------------------

TEST(SceneLoaderErrors, UnknownTopLevelTable) {
    parse_error(std::string(kSheet) + "[solvr]\ndt = 0.01\n",
                {"inline.toml:5:", "key 'solvr'", "did you mean 'solver'"});
}

TEST(SceneLoaderErrors, UnknownKeyWithoutSuggestionListsKeys) {
    parse_error(std::string(kSheet) + "[camera]\nzoom = 2\n", {"key 'camera.zoom'", "expected one of", "'fov'"});
}

TEST(SceneLoaderErrors, UnknownEnumValue) {
    parse_error(std::string(kSheet) + "[solver]\nprecision = \"doble\"\n",
                {"inline.toml:6:", "key 'solver.precision'", "did you mean \"double\"", "\"float\", \"double\""});
}

TEST(SceneLoaderErrors, VectorOfWrongLength) {
    parse_error(std::string(kSheet) + "[world]\ngravity = [0, -9.81]\n",
                {"inline.toml:6:", "key 'world.gravity'", "2 elements", "3 numbers"});
}

TEST(SceneLoaderErrors, VectorWithAString) {
    parse_error(std::string(kSheet) + "[wind]\nvelocity = [1, \"x\", 0]\n", {"key 'wind.velocity'", "element 1"});
}

TEST(SceneLoaderErrors, NonFiniteNumber) {
    parse_error(std::string(kSheet) + "[solver]\ndt = nan\n", {"key 'solver.dt'", "not finite"});
}

TEST(SceneLoaderErrors, FloatForInteger) {
    parse_error(std::string(kSheet) + "[solver]\nsubsteps = 2.5\n", {"key 'solver.substeps'", "expected an integer"});
}

TEST(SceneLoaderErrors, NoCloth) {
    parse_error("[solver]\ndt = 0.01\n", {"inline.toml", "key 'cloth'", "no cloth"});
}

TEST(SceneLoaderErrors, ClothAsTableInsteadOfArray) {
    parse_error("[cloth]\nname = \"x\"\n", {"inline.toml:1:", "key 'cloth'", "array of tables"});
}

TEST(SceneLoaderErrors, MeshMissing) {
    parse_error("[[cloth]]\nname = \"a\"\n", {"inline.toml:1:", "key 'cloth[0].mesh'", "missing required key"});
}

TEST(SceneLoaderErrors, MeshBothGridAndFile) {
    parse_error("[[cloth]]\nmesh = { grid = {}, file = \"x.obj\" }\n", {"key 'cloth[0].mesh.file'", "both grid and file"});
}

TEST(SceneLoaderErrors, GridCells) {
    parse_error("[[cloth]]\nmesh = { grid = { cells = [0, 4] } }\n",
                {"inline.toml:2:", "key 'cloth[0].mesh.grid.cells'", "element 0"});
    parse_error("[[cloth]]\nmesh = { grid = { cells = 4 } }\n", {"key 'cloth[0].mesh.grid.cells'", "[nx, ny]"});
}

TEST(SceneLoaderErrors, GridSizeMustBePositive) {
    parse_error("[[cloth]]\nmesh = { grid = { width = 0 } }\n", {"key 'cloth[0].mesh.grid.width'", "(0, 1000]"});
}

TEST(SceneLoaderErrors, UnknownGridPlane) {
    parse_error("[[cloth]]\nmesh = { grid = { plane = \"yz\" } }\n", {"key 'cloth[0].mesh.grid.plane'", "\"xy\", \"xz\""});
}

TEST(SceneLoaderErrors, PinNeedsExactlyOneSelection) {
    parse_error(std::string(kSheet) + "[[cloth.pin]]\nmotion = \"m\"\n",
                {"inline.toml:5:", "key 'cloth[0].pin[0]", "no selection given"});
    parse_error(std::string(kSheet) + "[[cloth.pin]]\nedge = \"top\"\ncorners = \"top\"\n",
                {"key 'cloth[0].pin[0]", "more than one selection"});
}

TEST(SceneLoaderErrors, PinVertexOutOfGrid) {
    parse_error(std::string(kSheet) + "[[cloth.pin]]\nvertices = [0, 25]\n",
                {"inline.toml:6:", "key 'cloth[0].pin[0].vertices'", "vertex 25 is out of range", "25"});
}

TEST(SceneLoaderErrors, PinBoxInverted) {
    parse_error(std::string(kSheet) + "[[cloth.pin]]\nbox = { min = [0, 1, 0], max = [1, 0, 1] }\n",
                {"key 'cloth[0].pin[0].box.max'", "axis y"});
}

TEST(SceneLoaderErrors, EdgePinOnMeshFile) {
    const std::string text = "[[cloth]]\nmesh = { file = \"" + test::data_file("quad.ply").generic_string() +
                             "\" }\n[[cloth.pin]]\nedge = \"top\"\n";
    parse_error(text, {"inline.toml:4:", "key 'cloth[0].pin[0].edge'", "need a grid mesh"});
}

TEST(SceneLoaderErrors, UnknownEdge) {
    parse_error(std::string(kSheet) + "[[cloth.pin]]\nedge = \"middle\"\n", {"key 'cloth[0].pin[0].edge'", "\"top\""});
}

TEST(SceneLoaderErrors, DuplicateNames) {
    parse_error(std::string(kSheet) + kSheet, {"inline.toml:7:", "key 'cloth[1].name'", "duplicate name 'sheet'"});
    parse_error(std::string(kSheet) + "[[motion]]\nname = \"a\"\n[[motion]]\nname = \"a\"\n",
                {"key 'motion[1].name'", "duplicate"});
}

TEST(SceneLoaderErrors, MotionWithoutName) {
    parse_error(std::string(kSheet) + "[[motion]]\nfrequency = 1\n", {"inline.toml:5:", "key 'motion[0].name'", "missing"});
}

TEST(SceneLoaderErrors, MotionReferenceWithNoMotions) {
    parse_error(std::string(kSheet) + "[[cloth.pin]]\nedge = \"top\"\nmotion = \"arm\"\n",
                {"key 'cloth[0].pin[0].motion'", "defines none"});
}

TEST(SceneLoaderErrors, ColliderKeysMustFitTheShape) {
    parse_error(std::string(kSheet) + "[[collider]]\nshape = \"box\"\nradius = 0.3\n",
                {"inline.toml:7:", "key 'collider[0].radius'", "no radius"});
    parse_error(std::string(kSheet) + "[[collider]]\nshape = \"sphere\"\nhalf_extents = [1, 1, 1]\n",
                {"key 'collider[0].half_extents'"});
    parse_error(std::string(kSheet) + "[[collider]]\nshape = \"sphere\"\nhalf_height = 1\n",
                {"key 'collider[0].half_height'"});
    parse_error(std::string(kSheet) + "[[collider]]\nshape = \"box\"\nhalf_extents = [1, 0, 1]\n",
                {"key 'collider[0].half_extents'", "component 1"});
    parse_error(std::string(kSheet) + "[[collider]]\nshape = \"cone\"\n",
                {"key 'collider[0].shape'", "\"plane\", \"sphere\", \"capsule\", \"box\""});
}

TEST(SceneLoaderErrors, ColliderMotionExcludesPosition) {
    parse_error(std::string(kSheet) + "[[motion]]\nname = \"m\"\n[[collider]]\nshape = \"sphere\"\nmotion = \"m\"\nposition = [0, 1, 0]\n",
                {"key 'collider[0].position'", "either motion or position"});
}

TEST(SceneLoaderErrors, CameraFov) {
    parse_error(std::string(kSheet) + "[camera]\nfov = 180\n", {"key 'camera.fov'", "(0, 180)"});
}

TEST(SceneLoaderErrors, SectionOfWrongType) {
    parse_error("solver = 3\n" + std::string(kSheet), {"inline.toml:1:", "key 'solver'", "expected a table"});
}

TEST(SceneLoaderErrors, EmptyString) {
    parse_error("[[cloth]]\nname = \"\"\nmesh = { grid = {} }\n", {"key 'cloth[0].name'", "empty"});
}

}  // namespace
}  // namespace weft
