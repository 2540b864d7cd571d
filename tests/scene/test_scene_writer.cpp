// Saving scenes (scene_to_toml, save_scene, update_scene_from_world): load → save → load gives the
// same scene, for every shipped scene and for numbers that have no short decimal form; a world built
// from the saved scene steps bit for bit like the original; what is tuned live is what is saved.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

#include "weft/backend/model.h"
#include "weft/error.h"
#include "weft/parameters.h"
#include "weft/scene.h"

namespace weft {
namespace {

const std::filesystem::path kScenes = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes";

bool same(const Vec3d& a, const Vec3d& b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same(const Mat3d& a, const Mat3d& b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same(const Material& a, const Material& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Field by field, bit for bit, what the text comparison below could not see if both texts were
// wrong the same way: the derived transforms and motions the world is built from.
void expect_same_scene(const SceneDesc& a, const SceneDesc& b) {
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.frames, b.frames);
    ASSERT_EQ(a.cloths.size(), b.cloths.size());
    for (std::size_t i = 0; i < a.cloths.size(); ++i) {
        SCOPED_TRACE(a.cloths[i].desc.name);
        const SceneCloth& x = a.cloths[i];
        const SceneCloth& y = b.cloths[i];
        EXPECT_EQ(x.desc.name, y.desc.name);
        EXPECT_TRUE(same(x.desc.transform.translation, y.desc.transform.translation));
        EXPECT_TRUE(same(x.desc.transform.rotation, y.desc.transform.rotation));
        EXPECT_TRUE(same(x.desc.initial_velocity, y.desc.initial_velocity));
        EXPECT_TRUE(same(x.desc.material, y.desc.material));
        EXPECT_EQ(x.fabric.density, y.fabric.density);
        EXPECT_EQ(x.source.cells_x, y.source.cells_x);
        EXPECT_EQ(x.source.file, y.source.file);
        ASSERT_EQ(x.pins.size(), y.pins.size());
        for (std::size_t p = 0; p < x.pins.size(); ++p) {
            EXPECT_EQ(x.pins[p].motion, y.pins[p].motion);
            EXPECT_EQ(x.pins[p].follow, y.pins[p].follow);
        }
        EXPECT_EQ(x.entry, y.entry);
    }
    ASSERT_EQ(a.colliders.size(), b.colliders.size());
    for (std::size_t k = 0; k < a.colliders.size(); ++k) {
        SCOPED_TRACE(a.colliders[k].name);
        EXPECT_EQ(a.colliders[k].shape, b.colliders[k].shape);
        EXPECT_TRUE(same(a.colliders[k].motion.origin, b.colliders[k].motion.origin));
        EXPECT_TRUE(same(a.colliders[k].motion.initial_rotation, b.colliders[k].motion.initial_rotation));
        EXPECT_TRUE(same(a.colliders[k].motion.angular_velocity, b.colliders[k].motion.angular_velocity));
        EXPECT_EQ(a.colliders[k].radius, b.colliders[k].radius);
        EXPECT_EQ(a.colliders[k].friction, b.colliders[k].friction);
        EXPECT_EQ(a.collider_meshes[k].file, b.collider_meshes[k].file);
    }
    EXPECT_EQ(a.motions.size(), b.motions.size());
    EXPECT_EQ(a.world.solver.dt, b.world.solver.dt);
    EXPECT_EQ(a.world.solver.substeps, b.world.solver.substeps);
    EXPECT_EQ(a.world.solver.cg_tolerance, b.world.solver.cg_tolerance);
    EXPECT_TRUE(same(a.world.gravity, b.world.gravity));
    EXPECT_TRUE(same(a.world.wind.velocity, b.world.wind.velocity));
    EXPECT_EQ(a.world.collision.self_collision, b.world.collision.self_collision);
    EXPECT_EQ(a.world.collision.rest_exclusion, b.world.collision.rest_exclusion);
    EXPECT_TRUE(same(a.camera.position, b.camera.position));
    EXPECT_EQ(a.camera.fov_degrees, b.camera.fov_degrees);
}

TEST(SceneWriter, EveryShippedSceneRoundTripsExactly) {
    int scenes = 0;
    for (const auto& entry : std::filesystem::directory_iterator(kScenes)) {
        if (entry.path().extension() != ".toml") continue;
        SCOPED_TRACE(entry.path().filename().string());
        const SceneDesc original = load_scene(entry.path());
        // Saved next to the original, so mesh paths stay relative the way the loader resolves them.
        const std::string text = scene_to_toml(original, kScenes);
        const SceneDesc reloaded = parse_scene(text, kScenes / "saved.toml");
        expect_same_scene(original, reloaded);
        // A second save writes the same text: nothing drifts.
        EXPECT_EQ(scene_to_toml(reloaded, kScenes), text);
        ++scenes;
    }
    EXPECT_GE(scenes, 10);
}

TEST(SceneWriter, NumbersWithoutAShortDecimalFormComeBackBitForBit) {
    const std::string text = R"(
[solver]
dt = 0.0033333333333333335
cg_tolerance = 1.2345678901234567e-7
[wind]
velocity = [0.1, -0.30000000000000004, 123.45678901234567]
[[cloth]]
name = "a \"quoted\" name"
mesh = { grid = { width = 0.7071067811865476, height = 1.0, cells = [3, 5], plane = "xz" } }
rotation = [33.333333333333336, -90.0, 1e-300]
[cloth.material]
stretch_stiffness = 4999.999999999999
)";
    const SceneDesc a = parse_scene(text, "numbers.toml");
    const SceneDesc b = parse_scene(scene_to_toml(a, {}), "numbers.toml");
    expect_same_scene(a, b);
    EXPECT_EQ(b.world.solver.dt, 0.0033333333333333335);
    EXPECT_EQ(b.world.solver.cg_tolerance, 1.2345678901234567e-7);
    EXPECT_EQ(b.cloths[0].desc.name, "a \"quoted\" name");
    EXPECT_EQ(b.cloths[0].source.width, 0.7071067811865476);
    EXPECT_EQ(b.cloths[0].desc.material.stretch_stiffness, 4999.999999999999);
}

TEST(SceneWriter, AWorldBuiltFromTheSavedSceneStepsBitForBit) {
    const SceneDesc original = load_scene(kScenes / "flag.toml");
    const SceneDesc reloaded = parse_scene(scene_to_toml(original, kScenes), kScenes / "saved.toml");
    auto a = build_world(original);
    auto b = build_world(reloaded);
    for (int f = 0; f < 5; ++f) {
        (void)a->step();
        (void)b->step();
    }
    const auto xa = a->positions(0), xb = b->positions(0);
    ASSERT_EQ(xa.size(), xb.size());
    EXPECT_EQ(std::memcmp(xa.data(), xb.data(), xa.size() * sizeof(Vec3d)), 0);
}

TEST(SceneWriter, WhatIsTunedLiveIsWhatIsSaved) {
    SceneDesc scene = load_scene(kScenes / "layers.toml");
    auto world = build_world(scene);
    world->settings().solver.substeps = 7;
    world->settings().collision.rest_exclusion = 2.5;
    world->settings().gravity = {0.0, -3.7, 0.0};
    for (std::size_t i = 0; i < world->model().cloths.size(); ++i)
        world->material(i).stretch_stiffness = 1234.5;
    update_scene_from_world(scene, *world);
    const auto file = std::filesystem::temp_directory_path() / ("weft_saved_" + std::to_string(::getpid()) + ".toml");
    save_scene(scene, file);
    const SceneDesc saved = load_scene(file);
    std::filesystem::remove(file);
    EXPECT_EQ(saved.world.solver.substeps, 7);
    EXPECT_EQ(saved.world.collision.rest_exclusion, 2.5);
    EXPECT_EQ(saved.world.gravity.y, -3.7);
    for (const SceneCloth& c : saved.cloths) EXPECT_EQ(c.desc.material.stretch_stiffness, 1234.5);

    // Copies of one [[cloth]] table are saved as that table: they must agree.
    world->material(1).stretch_stiffness = 999.0;
    SceneDesc diverged = load_scene(kScenes / "layers.toml");
    update_scene_from_world(diverged, *world);
    try {
        (void)scene_to_toml(diverged, kScenes);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("different materials"), std::string::npos) << e.what();
    }
}

// Motions are tuned live too (the editor's Motions panel): what the world's motions hold is saved,
// and a world whose motions are not the scene's is refused.
TEST(SceneWriter, TunedMotionsAreSaved) {
    SceneDesc scene = load_scene(kScenes / "twist.toml");
    ASSERT_FALSE(scene.motions.empty());
    auto world = build_world(scene);
    world->motion(0).angular_velocity = {0.0, 2.5, 0.0};
    world->motion(0).frequency = 0.75;
    update_scene_from_world(scene, *world);
    const auto file = std::filesystem::temp_directory_path() / ("weft_motion_" + std::to_string(::getpid()) + ".toml");
    save_scene(scene, file);
    const SceneDesc saved = load_scene(file);
    std::filesystem::remove(file);
    ASSERT_EQ(saved.motions.size(), scene.motions.size());
    EXPECT_EQ(saved.motions[0].name, scene.motions[0].name);
    EXPECT_EQ(saved.motions[0].motion.angular_velocity.y, 2.5);
    EXPECT_EQ(saved.motions[0].motion.frequency, 0.75);

    SceneDesc other = load_scene(kScenes / "twist.toml");
    other.motions.push_back(other.motions[0]);
    other.motions.back().name = "extra";
    try {
        update_scene_from_world(other, *world);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("motions"), std::string::npos) << e.what();
    }
}

// The world's pins as (vertex, motion) pairs, sorted.
std::vector<std::pair<std::uint32_t, int>> pin_pairs(const World& world, std::size_t cloth) {
    std::vector<std::pair<std::uint32_t, int>> out;
    for (const PinDesc& p : world.model().cloths.at(cloth).pins) out.emplace_back(p.vertex, p.motion);
    std::sort(out.begin(), out.end());
    return out;
}

SceneDesc save_and_load(const SceneDesc& scene, const std::string& tag) {
    const auto file = std::filesystem::temp_directory_path() / ("weft_" + tag + "_" + std::to_string(::getpid()) + ".toml");
    save_scene(scene, file);
    SceneDesc saved = load_scene(file);
    std::filesystem::remove(file);
    return saved;
}

// Pins made and removed live (the editor's Shift+click) are saved: the rules become vertex lists that
// pin exactly what the world pins, each with its motion. Pins left as the file made them keep the
// file's rules.
TEST(SceneWriter, PinsChangedLiveAreSavedAsVertexLists) {
    SceneDesc scene = load_scene(kScenes / "twist.toml");
    auto world = build_world(scene);
    const auto before = pin_pairs(*world, 0);
    ASSERT_GE(before.size(), 4U);
    {
        SceneDesc untouched = scene;
        update_scene_from_world(untouched, *world);
        ASSERT_EQ(untouched.cloths[0].pins.size(), scene.cloths[0].pins.size());
        EXPECT_EQ(untouched.cloths[0].pins[0].kind, scene.cloths[0].pins[0].kind) << "unchanged pins keep their rules";
    }
    const std::uint32_t removed = before.front().first;
    ASSERT_TRUE(world->unpin(0, removed));
    auto added = static_cast<std::uint32_t>(world->model().cloths[0].fabric->vertex_count() / 2);
    while (world->is_pinned(0, added)) ++added;  // an inner vertex: the scene pins two edges
    ASSERT_TRUE(world->pin(0, added));
    update_scene_from_world(scene, *world);
    for (const PinSelection& rule : scene.cloths[0].pins) EXPECT_EQ(rule.kind, PinSelection::Kind::Vertices);
    const SceneDesc saved = save_and_load(scene, "pins");
    const auto rebuilt = build_world(saved);
    const auto want = pin_pairs(*world, 0);
    EXPECT_EQ(pin_pairs(*rebuilt, 0), want);
    EXPECT_EQ(std::count_if(want.begin(), want.end(), [&](const auto& p) { return p.first == removed; }), 0);
    EXPECT_EQ(std::count_if(want.begin(), want.end(), [&](const auto& p) { return p.first == added && p.second == -1; }), 1);
    // The edge pins still follow their motions after the round trip.
    EXPECT_GT(std::count_if(want.begin(), want.end(), [](const auto& p) { return p.second >= 0; }), 0);
}

// Copies of one [[cloth]] table share one pin set in the file: copies pinned differently are refused,
// naming them, instead of saving one copy's pins for all.
TEST(SceneWriter, CopiesOfOneTableWithDifferentPinsAreAnError) {
    SceneDesc scene = load_scene(kScenes / "layers.toml");
    auto world = build_world(scene);
    ASSERT_GE(world->model().cloths.size(), 2U);
    ASSERT_TRUE(world->pin(1, 0));
    try {
        update_scene_from_world(scene, *world);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("different pins"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(world->model().cloths[1].name), std::string::npos) << e.what();
    }
    ASSERT_TRUE(world->pin(0, 0));
    for (std::size_t i = 2; i < world->model().cloths.size(); ++i) ASSERT_TRUE(world->pin(i, 0));
    SceneDesc same_pins = load_scene(kScenes / "layers.toml");
    update_scene_from_world(same_pins, *world);
    const auto rebuilt = build_world(save_and_load(same_pins, "layers_pins"));
    for (std::size_t i = 0; i < world->model().cloths.size(); ++i) EXPECT_EQ(pin_pairs(*rebuilt, i), pin_pairs(*world, i));
}

// Colliders tuned live (World::collider: sizes, friction, position) are saved; one that follows a
// motion keeps following it.
TEST(SceneWriter, TunedCollidersAreSaved) {
    SceneDesc scene = load_scene(kScenes / "flag.toml");
    auto world = build_world(scene);
    ASSERT_EQ(world->model().colliders[0].shape, ColliderShape::Capsule);
    world->collider(0).radius = 0.045;
    world->collider(0).half_height = 1.25;
    world->collider(0).friction = 0.9;
    world->collider(0).motion.origin = {-0.05, 1.4, 0.1};
    world->collider(1).motion.origin.y = -0.25;
    update_scene_from_world(scene, *world);
    const SceneDesc saved = save_and_load(scene, "colliders");
    EXPECT_EQ(saved.colliders[0].radius, 0.045);
    EXPECT_EQ(saved.colliders[0].half_height, 1.25);
    EXPECT_EQ(saved.colliders[0].friction, 0.9);
    EXPECT_TRUE(same(saved.colliders[0].motion.origin, Vec3d{-0.05, 1.4, 0.1}));
    EXPECT_EQ(saved.colliders[1].motion.origin.y, -0.25);
    EXPECT_TRUE(same(saved.collider_rotation_degrees[0], scene.collider_rotation_degrees[0]))
        << "an untouched rotation keeps the file's angles";

    // The rotation is live too (the editor's row): set through the parameter, it turns the capsule
    // at the next step and is saved as Euler angles.
    const Parameter& rotation = parameter("collider", "rotation");
    ASSERT_EQ(rotation.effect, ParameterEffect::Live);
    set_parameter_vector(rotation, world->collider(0), Vec3d{0.0, 0.0, 90.0});
    const Vec3d axis = world->collider(0).motion.at(0.0).rotation * Vec3d{0.0, 1.0, 0.0};
    EXPECT_NEAR(axis.x, -1.0, 1e-12) << "the capsule's axis (local y) turned 90° about z";
    EXPECT_NEAR(parameter_vector(rotation, world->collider(0)).z, 90.0, 1e-9);
    update_scene_from_world(scene, *world);
    const SceneDesc turned = save_and_load(scene, "turned_collider");
    EXPECT_NEAR(turned.collider_rotation_degrees[0].z, 90.0, 1e-9);
    EXPECT_NEAR(turned.colliders[0].motion.initial_rotation.m[0][1], -1.0, 1e-12);
    // Euler angles back from a matrix, away from and at the gimbal lock.
    for (const Vec3d d : {Vec3d{30.0, -20.0, 110.0}, Vec3d{-170.0, 45.0, 5.0}, Vec3d{0.0, 90.0, 40.0}}) {
        const Vec3d back = euler_degrees_from_rotation(rotation_from_euler_degrees(d));
        const Mat3d a = rotation_from_euler_degrees(d), b = rotation_from_euler_degrees(back);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) EXPECT_NEAR(a.m[i][j], b.m[i][j], 1e-12) << d.x << " " << d.y << " " << d.z;
    }

    SceneDesc spinning = load_scene(kScenes / "sphere.toml");
    auto spin_world = build_world(spinning);
    spin_world->collider(0).radius = 0.4;
    update_scene_from_world(spinning, *spin_world);
    const SceneDesc spun = save_and_load(spinning, "sphere_collider");
    EXPECT_EQ(spun.colliders[0].radius, 0.4);
    EXPECT_EQ(spun.collider_motions[0], "spin");
}

TEST(SceneWriter, UnwritableFileIsAnErrorNamingIt) {
    const SceneDesc scene = load_scene(kScenes / "flag.toml");
    try {
        save_scene(scene, "/nonexistent-dir/scene.toml");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/scene.toml"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace weft
