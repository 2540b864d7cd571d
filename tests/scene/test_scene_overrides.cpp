// `--set key=value` overrides: applied before validation, by index or by name, and errors that name
// the override.
#include <string>
#include <vector>

#include "scene_test_util.h"
#include "weft/scene.h"

namespace weft {
namespace {

using test::expect_error;
using test::scene_file;

SceneDesc flag_with(std::vector<std::string> overrides) { return load_scene(scene_file("flag"), overrides); }

std::string flag_error(std::string override_text, std::initializer_list<std::string_view> parts) {
    return expect_error([&] { (void)flag_with({override_text}); }, parts);
}

TEST(SceneOverrides, ScalarVectorAndIndexedKeys) {
    const SceneDesc s = flag_with({"solver.substeps=4", "wind.velocity=[5,0,0]", "cloth.0.material.stretch_stiffness=1e4"});
    EXPECT_EQ(s.world.solver.substeps, 4);
    EXPECT_EQ(s.world.wind.velocity, (Vec3d{5, 0, 0}));
    EXPECT_EQ(s.cloths[0].desc.material.stretch_stiffness, 1e4);
    // Everything else is as in the file.
    EXPECT_EQ(s.world.wind.turbulence, load_scene(scene_file("flag")).world.wind.turbulence);
}

// Positions beyond the scene's extent (weft/world_limits.h) are refused with the component named:
// 1e30 used to be accepted and threw the cloth 1e29 m in a frame.
TEST(SceneOverrides, PositionsBeyondTheWorldExtentAreRefused) {
    flag_error("cloth.0.position=[1e30,0,0]", {"cloth[0].position", "component 0 is 1e30", "[-100000, 100000]"});
    flag_error("collider.0.position=[0,-2e5,0]", {"position", "component 1"});
    EXPECT_EQ(flag_with({"cloth.0.position=[9e4,0,0]"}).cloth_placements[0].position.x, 9e4);
}

TEST(SceneOverrides, ByName) {
    const SceneDesc s = flag_with({"cloth.flag.material.bending_stiffness=1e-4", "collider.pole.radius=0.05",
                                   "cloth.flag.mesh.grid.cells=[80, 48]"});
    EXPECT_EQ(s.cloths[0].desc.material.bending_stiffness, 1e-4);
    EXPECT_EQ(s.colliders[0].radius, 0.05);
    EXPECT_EQ(s.cloths[0].source.cells_x, 80);
    EXPECT_EQ(s.cloths[0].source.cells_y, 48);
}

TEST(SceneOverrides, NestedArrayOfTables) {
    const SceneDesc s = flag_with({"cloth.flag.pin.0.edge=\"right\""});
    EXPECT_EQ(s.cloths[0].pins.at(0).edge, "right");
}

TEST(SceneOverrides, BareWordIsAString) {
    const SceneDesc s = flag_with({"solver.precision=float", "solver.hessian = projected"});
    EXPECT_EQ(s.world.solver.precision, Precision::Float);
    EXPECT_EQ(s.world.solver.hessian, HessianMode::Projected);
}

TEST(SceneOverrides, KeyTheFileOmits) {
    // hanging.toml has no [wind] and no damping_mass: both may still be set.
    const SceneDesc s = load_scene(scene_file("hanging"), std::vector<std::string>{"wind.velocity=[0, 0, 3]",
                                                                                   "cloth.sheet.material.damping_mass=0.2",
                                                                                   "scene.frames=10"});
    EXPECT_EQ(s.world.wind.velocity, (Vec3d{0, 0, 3}));
    EXPECT_EQ(s.cloths[0].desc.material.damping_mass, 0.2);
    EXPECT_EQ(s.frames, 10);
}

TEST(SceneOverrides, VectorElement) {
    const SceneDesc s = flag_with({"wind.velocity.1=2"});
    EXPECT_EQ(s.world.wind.velocity, (Vec3d{8, 2, 0}));
}

TEST(SceneOverrides, LaterOverrideWins) {
    EXPECT_EQ(flag_with({"solver.substeps=4", "solver.substeps=6"}).world.solver.substeps, 6);
}

TEST(SceneOverrides, ParseSceneTakesOverridesToo) {
    const std::vector<std::string> o{"cloth.0.density=0.5"};
    const SceneDesc s = parse_scene("[[cloth]]\nmesh = { grid = {} }\n", "mem.toml", o);
    EXPECT_EQ(s.cloths[0].fabric.density, 0.5);
}

TEST(SceneOverridesErrors, UnknownKey) {
    flag_error("solver.substepz=4", {"--set 'solver.substepz=4'", "key 'solver.substepz'", "did you mean 'substeps'"});
    flag_error("solvr.substeps=4", {"--set 'solvr.substeps=4'", "key 'solvr'", "did you mean 'solver'"});
    flag_error("cloth.0.material.stretch=1", {"--set 'cloth.0.material.stretch=1'", "cloth[0].material.stretch"});
}

TEST(SceneOverridesErrors, OutOfRangeAndWrongType) {
    const std::string m = flag_error("cloth.0.material.stretch_stiffness=1e9",
                                     {"--set 'cloth.0.material.stretch_stiffness=1e9'",
                                      "key 'cloth[0].material.stretch_stiffness'", "out of range", "[1, 1e8]"});
    EXPECT_EQ(m.find("flag.toml"), std::string::npos) << "an override error must not blame the file: " << m;
    flag_error("solver.substeps=2.5", {"--set 'solver.substeps=2.5'", "key 'solver.substeps'", "expected an integer"});
    flag_error("wind.velocity=[1,2]", {"--set 'wind.velocity=[1,2]'", "key 'wind.velocity'", "3 numbers"});
}

TEST(SceneOverridesErrors, Malformed) {
    flag_error("solver.substeps", {"--set 'solver.substeps'", "expected key=value"});
    flag_error("=4", {"--set '=4'", "key before '=' is empty"});
    flag_error("solver.substeps=", {"--set 'solver.substeps='", "value after '=' is empty"});
    flag_error("wind.velocity=[1,", {"--set 'wind.velocity=[1,'", "cannot parse"});
    flag_error("solver..dt=1", {"--set 'solver..dt=1'", "cannot parse"});
}

TEST(SceneOverridesErrors, BadSelectors) {
    flag_error("cloth.3.density=1", {"--set 'cloth.3.density=1'", "key 'cloth.3'", "out of range", "1 'cloth'"});
    flag_error("cloth.flga.density=1", {"--set 'cloth.flga.density=1'", "no 'cloth' entry is named 'flga'",
                                        "did you mean 'flag'"});
    flag_error("motion.0.frequency=1", {"--set 'motion.0.frequency=1'", "no 'motion' entries"});
    flag_error("cloth.0=1", {"--set 'cloth.0=1'", "cannot replace a whole entry"});
}

TEST(SceneOverridesErrors, ReferenceChecksApply) {
    flag_error("cloth.0.pin.0.motion=\"nowhere\"", {"--set 'cloth.0.pin.0.motion=\"nowhere\"'", "unknown motion 'nowhere'"});
}

}  // namespace
}  // namespace weft
