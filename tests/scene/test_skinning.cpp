// Skinned meshes (weft/skinning.h): linear blend skinning against hand-computed poses, clip sampling,
// the checks on bad skins, and (with weft::assets) the shipped character imported through assimp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "weft/backend/model.h"
#include "weft/collider.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/scene.h"
#include "weft/skinning.h"
#include "weft/world.h"
#if WEFT_TEST_HAVE_ASSETS
#include "weft/assets/assimp_loader.h"
#include "weft/assets/skinned_import.h"
#endif

namespace weft {
namespace {

constexpr double kPi = 3.14159265358979323846;

Quatd about_z(double radians) { return {std::cos(radians / 2), 0.0, 0.0, std::sin(radians / 2)}; }

/// A bar along +X from 0 to 2 m: joint 0 at the origin, joint 1 (its child) at x = 1. Vertices at
/// x = 0.5 (joint 0 only), 1 (half each) and 1.5, 2 (joint 1 only).
SkinnedMesh bar() {
    SkinnedMesh m;
    m.mesh.source = "bar";
    m.mesh.positions = {{0.5, 0, 0}, {1.0, 0, 0}, {1.5, 0, 0}, {2.0, 0, 0}};
    m.mesh.triangles = {{{0, 1, 2}}, {{1, 2, 3}}};
    m.vertex_joints = {{0, 0, 0, 0}, {0, 1, 0, 0}, {1, 0, 0, 0}, {1, 0, 0, 0}};
    m.vertex_weights = {{1, 0, 0, 0}, {0.5, 0.5, 0, 0}, {1, 0, 0, 0}, {1, 0, 0, 0}};
    Joint root{.name = "root"};
    Joint elbow{.name = "elbow", .parent = 0};
    elbow.rest.translation = {1, 0, 0};
    elbow.inverse_bind.translation = {-1, 0, 0};
    m.joints = {root, elbow};
    return m;
}

void expect_near(Vec3d a, Vec3d b, const std::string& what) {
    EXPECT_NEAR(a.x, b.x, 1e-12) << what;
    EXPECT_NEAR(a.y, b.y, 1e-12) << what;
    EXPECT_NEAR(a.z, b.z, 1e-12) << what;
}

TEST(Skinning, TheBindPoseGivesBackTheMeshAndABentElbowMovesTheForearm) {
    SkinnedMesh m = bar();
    validate(m);
    std::vector<Vec3d> x(4);
    skin(m, skinning_transforms(m, rest_poses(m)), x);
    for (std::size_t i = 0; i < 4; ++i) expect_near(x[i], m.mesh.positions[i], "bind pose, vertex " + std::to_string(i));

    // The elbow turned 90° about z: the forearm points up (+Y) from (1, 0, 0).
    std::vector<JointPose> poses = rest_poses(m);
    poses[1].rotation = about_z(kPi / 2);
    skin(m, skinning_transforms(m, poses), x);
    expect_near(x[0], {0.5, 0, 0}, "upper arm");
    expect_near(x[2], {1.0, 0.5, 0}, "forearm");
    expect_near(x[3], {1.0, 1.0, 0}, "hand");
    expect_near(x[1], {1.0, 0, 0}, "the elbow itself (half each, both at the joint)");

    // The root turned too: the whole chain follows its parent.
    poses[0].rotation = about_z(kPi / 2);
    skin(m, skinning_transforms(m, poses), x);
    expect_near(x[0], {0, 0.5, 0}, "upper arm, root turned");
    expect_near(x[3], {-1.0, 1.0, 0}, "hand, root and elbow turned");
}

/// bar() with the clip "wave": over 1 s the elbow turns 90° about z and rises 2 m.
SkinnedMesh waving_bar_skin() {
    SkinnedMesh m = bar();
    AnimationClip clip{.name = "wave", .duration = 1.0};
    JointTrack t{.joint = 1};
    t.rotation_times = {0.0, 1.0};
    t.rotations = {about_z(0.0), about_z(kPi / 2)};
    t.translation_times = {0.0, 1.0};
    t.translations = {{1, 0, 0}, {1, 2, 0}};
    clip.tracks.push_back(t);
    m.clips.push_back(clip);
    validate(m);
    return m;
}

TEST(Skinning, ClipsInterpolateBetweenKeysAndLoop) {
    const SkinnedMesh m = waving_bar_skin();
    const std::vector<JointPose> half = sample_clip(m, m.clip("wave"), 0.5, false);
    const Mat3d r = rotation_matrix(half[1].rotation), expected = rotation_matrix(about_z(kPi / 4));
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) EXPECT_NEAR(r.m[a][b], expected.m[a][b], 1e-12) << "slerp halfway is 45 degrees";
    expect_near(half[1].translation, {1, 1, 0}, "translation halfway");
    expect_near(sample_clip(m, m.clip("wave"), 1.25, true)[1].translation, {1, 0.5, 0}, "looped: 1.25 s is 0.25 s");
    expect_near(sample_clip(m, m.clip("wave"), 7.0, false)[1].translation, {1, 2, 0}, "held at the last key");
    expect_near(sample_clip(m, m.clip("wave"), 0.5, false)[0].translation, {0, 0, 0}, "no track: the rest pose");
    try {
        (void)m.clip("run");
        FAIL() << "an unknown clip was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("'wave'"), std::string::npos) << e.what();
    }
}

/// `edit` breaks `bar()`; validate must throw naming the mesh and `expected`.
template <typename Edit>
void expect_refused(Edit&& edit, const std::string& expected) {
    SkinnedMesh m = bar();
    edit(m);
    try {
        validate(m);
        FAIL() << "accepted: " << expected;
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.rfind("bar: ", 0), 0U) << what;
        EXPECT_NE(what.find(expected), std::string::npos) << what;
    }
}

TEST(Skinning, BadSkinsAreRefusedByName) {
    expect_refused([](SkinnedMesh& m) { m.vertex_weights[2] = {0.7, 0, 0, 0}; }, "vertex 2's skin weights sum to 0.7");
    expect_refused([](SkinnedMesh& m) { m.vertex_joints[3] = {5, 0, 0, 0}; }, "vertex 3 is bound to joint 5 of 2");
    expect_refused([](SkinnedMesh& m) { m.vertex_weights[0] = {-1, 2, 0, 0}; }, "vertex 0 has skin weight");
    expect_refused([](SkinnedMesh& m) { m.joints[0].parent = 1; }, "parents must come before their children");
    expect_refused([](SkinnedMesh& m) { m.vertex_weights.pop_back(); }, "4 vertices but 4 joint lists and 3 weight lists");
    expect_refused(
        [](SkinnedMesh& m) {
            AnimationClip c{.name = "bad"};
            JointTrack t{.joint = 1};
            t.rotation_times = {0.5, 0.25};
            t.rotations = {Quatd{}, Quatd{}};
            c.tracks.push_back(t);
            m.clips.push_back(c);
        },
        "clip 'bad', track of joint 1: key times are not increasing");
    SkinnedMesh unweighted = bar();
    unweighted.vertex_weights[1] = {0, 0, 0, 0};
    EXPECT_THROW(normalize_weights(unweighted), Error);
}

/// The waving bar as a mesh collider playing its clip once from t = 0.
ColliderDesc waving_bar() {
    const SkinnedMesh m = waving_bar_skin();
    ColliderDesc c{.name = "bar", .shape = ColliderShape::Mesh};
    c.skin = std::make_shared<const SkinnedMesh>(m);
    c.mesh = std::make_shared<const MeshData>(m.mesh);
    c.clip = "wave";
    c.clip_loop = false;
    return c;
}

Vec3d hand_at(const ColliderDesc& c, double t) {
    std::vector<Vec3d> x(4);
    collider_mesh_positions(c, t, x);
    return x[3];
}

TEST(Skinning, ASwitchCrossFadesFromTheOldPoseAndASpeedChangeKeepsTheClipTime) {
    // Waving until 0.5 s, then back to the bind pose over a 0.2 s fade: at the switch the pose is
    // the wave's, halfway through the fade the joint's translation and rotation are half of each
    // (the wave at 0.6 s: up 1.2 m and turned 0.3·90°; the bind pose: 0 and 0), after it the bind pose.
    ColliderDesc c = waving_bar();
    const Vec3d waving = hand_at(c, 0.5);
    switch_clip(c, "", 0.5, 0.2);
    expect_near(hand_at(c, 0.5), waving, "the fade starts from the pose the switch left");
    const double half_turn = 0.5 * 0.6 * kPi / 2;
    expect_near(hand_at(c, 0.6), {1.0 + std::cos(half_turn), 0.6 + std::sin(half_turn), 0.0}, "halfway through the fade");
    expect_near(hand_at(c, 0.7), {2.0, 0.0, 0.0}, "the fade done: the bind pose");
    // The fade is continuous: no step of 1 ms moves the hand by more than the blend's rate allows,
    // where a cut moves it by the whole difference at once.
    double largest = 0.0;
    for (double t = 0.45; t < 0.75; t += 1e-3) largest = std::max(largest, math::length(hand_at(c, t + 1e-3) - hand_at(c, t)));
    EXPECT_LT(largest, 0.02);
    ColliderDesc cut = waving_bar();
    switch_clip(cut, "", 0.5, 0.0);
    EXPECT_GT(math::length(hand_at(cut, 0.5) - waving), 1.0) << "a cut jumps to the bind pose";

    // Halving the speed at 0.4 s keeps the clip at 0.4 s, and from there it runs at half the rate.
    ColliderDesc slow = waving_bar();
    set_clip_speed(slow, 0.4, 0.5);
    EXPECT_NEAR(clip_time(slow, 0.4), 0.4, 1e-12);
    EXPECT_NEAR(clip_time(slow, 0.6), 0.5, 1e-12);
    // Setting clip_speed alone would have jumped it to 0.2 s.
    // A clip entered part-way: the wave from 0.25 s at twice the rate, at t = 2 s.
    switch_clip(slow, "wave", 2.0, 0.1, false, 2.0, 0.25);
    EXPECT_NEAR(clip_time(slow, 2.0), 0.25, 1e-12);
    EXPECT_NEAR(clip_time(slow, 2.1), 0.45, 1e-12);
    EXPECT_THROW(switch_clip(slow, "run", 3.0, 0.1), Error);  // the bar has no run
    EXPECT_THROW(switch_clip(slow, "", 3.0, -1.0), Error);
    EXPECT_THROW(set_clip_speed(slow, 3.0, -1.0), Error);
    // The world refuses a fade that cannot be played.
    World world;
    ColliderDesc bad = waving_bar();
    bad.clip_fade = 0.2;
    bad.fade_from_clip = "run";
    EXPECT_THROW((void)world.add_collider(bad), Error);
    bad.fade_from_clip = "wave";
    EXPECT_NO_THROW((void)world.add_collider(bad));
}

// A switch while a fade is still running (the rigged runner stopping in the middle of the fade
// from its jump into the run): what shows is a blend of two poses, and the new fade must start
// from it. Fading from the newer clip alone jumped the runner's legs 0.27 m in one step.
TEST(Skinning, ASwitchDuringAFadeStartsFromTheBlendShown) {
    ColliderDesc c = waving_bar();
    switch_clip(c, "", 0.5, 0.4);                 // the wave fading into the bind pose until 0.9 s
    const Vec3d blended = hand_at(c, 0.7);        // halfway: the blend of the two
    switch_clip(c, "wave", 0.7, 0.2, false, 1.0, 0.7);  // back to the wave where it would be, mid-fade
    expect_near(hand_at(c, 0.7), blended, "the new fade starts where the old one was");
    ASSERT_EQ(c.fade_from_pose.size(), c.skin->joints.size());
    double largest = 0.0;
    for (double t = 0.6; t < 1.0; t += 1e-3) largest = std::max(largest, math::length(hand_at(c, t + 1e-3) - hand_at(c, t)));
    EXPECT_LT(largest, 0.02) << "continuous through both switches";
    expect_near(hand_at(c, 0.95), hand_at(waving_bar(), 0.95), "the fade done: the wave itself");
    // Without the held blend, fading from the bind pose alone would have jumped the hand.
    ColliderDesc from_bind = c;
    from_bind.fade_from_pose.clear();
    EXPECT_GT(math::length(hand_at(from_bind, 0.7) - blended), 0.3);
    // After a fade has ended a switch fades from the clip itself again (nothing held).
    switch_clip(c, "", 2.0, 0.2);
    EXPECT_TRUE(c.fade_from_pose.empty());
    // The world refuses a held pose that does not fit the skin.
    World world;
    ColliderDesc bad = waving_bar();
    bad.clip_fade = 0.2;
    bad.fade_from_pose.resize(bad.skin->joints.size() + 1);
    EXPECT_THROW((void)world.add_collider(bad), Error);
}

#if WEFT_TEST_HAVE_ASSETS
/// `skin`'s vertices at time `t` of clip `clip` (played once), in its own frame.
void skin_at(const SkinnedMesh& skin, const std::string& clip, double t, std::vector<Vec3d>& out) {
    weft::skin(skin, skinning_transforms(skin, sample_clip(skin, skin.clip(clip), t, false)), out);
}

// The shipped character (tools/make_character.py) through assimp: its skeleton and clips arrive, the
// bind pose gives back its mesh, and the run clip moves its feet and not its head's height by much.
TEST(SkinnedImport, TheShippedRunnerHasItsSkeletonAndClips) {
    const std::filesystem::path file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets/characters/runner.gltf";
    const SkinnedMesh m = assets::import_skinned_mesh(file);
    EXPECT_EQ(m.mesh.positions.size(), 176U);
    EXPECT_EQ(m.mesh.triangles.size(), 304U);
    ASSERT_GE(m.joints.size(), 12U);
    EXPECT_NO_THROW((void)m.clip("run"));
    EXPECT_NEAR(m.clip("run").duration, 0.8, 1e-6);
    EXPECT_NEAR(m.clip("jump").duration, 1.0, 1e-6);
    std::vector<Vec3d> x(m.mesh.positions.size());
    skin(m, skinning_transforms(m, rest_poses(m)), x);
    double worst = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) worst = std::max(worst, length(x[i] - m.mesh.positions[i]));
    EXPECT_LT(worst, 1e-6) << "the bind pose moved the mesh";
    // A quarter of the run: the left thigh swings back, the right forward; the lowest point rises
    // off the ground and the forward-most vertex changes.
    double lowest_rest = 1e9, lowest_run = 1e9;
    for (const Vec3d& p : m.mesh.positions) lowest_rest = std::min(lowest_rest, p.y);
    skin(m, skinning_transforms(m, sample_clip(m, m.clip("run"), 0.0, true)), x);
    for (const Vec3d& p : x) lowest_run = std::min(lowest_run, p.y);
    EXPECT_GT(lowest_run, lowest_rest + 0.05) << "the run's first key should have both feet off the ground";
}

/// The shipped character (tools/make_character.py).
std::shared_ptr<const SkinnedMesh> runner_skin() {
    return std::make_shared<const SkinnedMesh>(
        assets::import_skinned_mesh(std::filesystem::path(WEFT_SOURCE_DIR) / "assets/characters/runner.gltf"));
}

/// A world with the exact check and self-contact, and a 40 cm kerchief just over the runner's head.
std::unique_ptr<World> kerchief_world() {
    WorldDesc desc;
    desc.collision.check = true;
    desc.collision.self_collision = true;  // the kerchief folds over the head
    auto world = std::make_unique<World>(desc);
    ClothDesc sheet{.name = "kerchief",
                    .fabric = Fabric::cook(make_grid(0.4, 0.4, 10, 10, GridPlane::XZ), {.density = 0.1})};
    sheet.transform.translation = {0.0, 1.92, 0.0};
    world->add_cloth(sheet);
    return world;
}

// The runner as a mesh collider playing its jump, a square of cloth dropped on its head: the
// collision pipeline places the skinned vertices each substep (and the exact check sees them), so the
// cloth rises with the head at the jump's top and nothing intersects; a clip that does not exist is
// refused at add_collider, naming the clips there are.
TEST(SkinnedImport, ACharacterPlayingAClipIsACollider) {
    const auto skin = runner_skin();
    const std::unique_ptr<World> kerchief = kerchief_world();
    World& world = *kerchief;
    ColliderDesc runner{.name = "runner", .shape = ColliderShape::Mesh};
    runner.skin = skin;
    runner.clip = "walk";
    EXPECT_THROW(world.add_collider(runner), Error);
    runner.clip = "jump";
    runner.clip_loop = false;
    world.add_collider(runner);

    // The clip's head height against the collider placement the pipeline uses.
    std::vector<Vec3d> placed(skin->mesh.positions.size()), skinned(placed.size());
    collider_mesh_positions(world.model().colliders[0], 0.7, placed);
    skin_at(*skin, "jump", 0.7, skinned);
    for (std::size_t i = 0; i < placed.size(); ++i) EXPECT_EQ(placed[i], skinned[i]) << "vertex " << i;

    long long intersecting = 0;
    double lowest_crouch = 0.0, lowest_top = 0.0;
    for (int frame = 1; frame <= 60; ++frame) {
        const StepStats& s = world.step();
        ASSERT_FALSE(s.non_finite) << "frame " << frame;
        intersecting += s.collision.remaining_intersections;
        double lowest = 1e9;
        for (const Vec3d& p : world.positions(0)) lowest = std::min(lowest, p.y);
        if (frame == 15) lowest_crouch = lowest;  // 0.25 s: the crouch
        if (frame == 42) lowest_top = lowest;     // 0.7 s: the top of the jump
    }
    std::printf("[ skinned  ] kerchief on the jumping runner: lowest point %.3f m in the crouch, %.3f m at the top\n",
                lowest_crouch, lowest_top);
    EXPECT_EQ(intersecting, 0);
    EXPECT_GT(lowest_top, lowest_crouch + 0.2) << "the head did not carry the cloth up";
}

// A cape pinned to the running character's skin: its pinned vertices stay on their skin vertices
// (plus the offset they started with) frame after frame; a pin to an analytic collider, to a vertex
// the mesh lacks, or to a collider and a motion at once is refused naming the cloth and the pin.
TEST(SkinnedImport, ACapePinnedToTheSkinFollowsTheRunCycle) {
    const auto skin = std::make_shared<const SkinnedMesh>(
        assets::import_skinned_mesh(std::filesystem::path(WEFT_SOURCE_DIR) / "assets/characters/runner.gltf"));
    // Two skin vertices at the back of the chest's top ring: the highest, most backward ones.
    std::vector<std::uint32_t> shoulders;
    for (std::uint32_t i = 0; i < skin->mesh.positions.size(); ++i) {
        const Vec3d p = skin->mesh.positions[i];
        if (std::abs(p.y - 1.59) < 1e-3 && p.z < -0.1 && std::abs(p.x) > 0.15) shoulders.push_back(i);  // not the head's
    }
    ASSERT_EQ(shoulders.size(), 2U) << "the chest's top back corners";
    const Vec3d left = skin->mesh.positions[shoulders[0]], right = skin->mesh.positions[shoulders[1]];
    const double width = std::abs(left.x - right.x);

    WorldDesc desc;
    World world(desc);
    ColliderDesc runner{.name = "runner", .shape = ColliderShape::Mesh};
    runner.skin = skin;
    runner.clip = "run";
    const std::size_t collider = world.add_collider(runner);
    ClothDesc cape{.name = "cape", .fabric = Fabric::cook(make_grid(width, 0.6, 4, 8, GridPlane::XY), {.density = 0.2})};
    cape.transform.translation = {std::min(left.x, right.x), 1.59 - 0.6, -0.13};  // hanging from the corners, behind
    // The grid's top corners (row 8 of 9, columns 0 and 4) follow the two skin vertices.
    const std::uint32_t top_left = 8 * 5, top_right = 8 * 5 + 4;
    const bool left_first = left.x < right.x;
    cape.pins.push_back({.vertex = top_left, .collider = static_cast<int>(collider),
                         .collider_vertex = left_first ? shoulders[0] : shoulders[1]});
    cape.pins.push_back({.vertex = top_right, .collider = static_cast<int>(collider),
                         .collider_vertex = left_first ? shoulders[1] : shoulders[0]});
    world.add_cloth(cape);
    const std::vector<Vec3d> start = world.positions(0);
    const Vec3d offset_l = start[top_left] - skin->mesh.positions[cape.pins[0].collider_vertex];
    std::vector<Vec3d> skinned(skin->mesh.positions.size());
    double worst = 0.0, travel = 0.0;
    for (int frame = 1; frame <= 30; ++frame) {
        ASSERT_FALSE(world.step().non_finite) << "frame " << frame;
        collider_mesh_positions(world.model().colliders[0], world.time(), skinned);
        const Vec3d target = skinned[cape.pins[0].collider_vertex] + offset_l;
        worst = std::max(worst, length(world.positions(0)[top_left] - target));
        travel = std::max(travel, length(world.positions(0)[top_left] - start[top_left]));
    }
    std::printf("[ skinned  ] cape pinned to the running chest: pin %.2e m off its skin vertex at worst, moved up to %.3f m\n",
                worst, travel);
    EXPECT_LT(worst, 1e-6);  // to rounding: the pin velocity (target − x)/h lands it there
    EXPECT_GT(travel, 0.01) << "the chest did not move the pin: the test proves nothing";

    const auto refused = [&](PinDesc pin, const std::string& expected) {
        World w(desc);
        ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
        w.add_collider(runner);
        w.add_collider(ball);
        ClothDesc c{.name = "bad", .fabric = cape.fabric};
        c.pins.push_back(pin);
        w.add_cloth(c);
        try {
            (void)w.step();
            FAIL() << "accepted: " << expected;
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("cloth 'bad': pin of vertex 0"), std::string::npos) << what;
            EXPECT_NE(what.find(expected), std::string::npos) << what;
        }
    };
    refused({.vertex = 0, .collider = 1}, "collider 'ball', which is not a mesh");
    refused({.vertex = 0, .collider = 0, .collider_vertex = 9999}, "has 176 vertices");
    refused({.vertex = 0, .collider = 5}, "follows collider 5 of 2");
}

TEST(SkinnedImport, FilesThatHoldNoCharacterAreRefusedByName) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "weft_skinned_import_test";
    std::filesystem::create_directories(dir);
    const auto expect_error = [](const std::filesystem::path& p, const std::string& expected) {
        try {
            (void)assets::import_skinned_mesh(p);
            FAIL() << p << " accepted";
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(p.string()), std::string::npos) << what;
            EXPECT_NE(what.find(expected), std::string::npos) << what;
        }
    };
    expect_error(dir / "missing.gltf", "not found");
    expect_error(std::filesystem::path(WEFT_SOURCE_DIR) / "assets/meshes/body.obj", "glTF 2.0 (.gltf, .glb) or FBX");
    const std::filesystem::path text = dir / "text.gltf";
    {
        std::FILE* f = std::fopen(text.string().c_str(), "w");
        ASSERT_NE(f, nullptr);
        std::fputs("not json at all\n", f);
        std::fclose(f);
    }
    expect_error(text, "not a glTF file");
}
// The shipped runner scene: `[[cloth.pin]] follow = "runner"` pins the cape's top edge to the skin
// vertices nearest to it at the start, and they stay on them (plus their starting offsets) while the
// character runs; saved and loaded again, the scene pins the same vertices to the same skin vertices.
TEST(SkinnedImport, TheRunnerScenesCapeFollowsTheSkin) {
    assets::install_mesh_loader();
    const std::filesystem::path file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets/scenes/runner.toml";
    const SceneDesc scene = load_scene(file);
    const auto world = build_world(scene);
    const Model& model = world->model();
    ASSERT_EQ(model.colliders[0].name, "runner");
    const ColliderDesc& runner = model.colliders[0];
    ASSERT_TRUE(plays_clip(runner));
    std::vector<Vec3d> skin(runner.mesh->positions.size());
    collider_mesh_positions(runner, 0.0, skin);
    const std::vector<Vec3d> start = world->positions(0);
    const std::vector<PinDesc>& pins = model.cloths[0].pins;
    ASSERT_EQ(pins.size(), 13U) << "the top edge of a 12-cell-wide grid";
    std::vector<Vec3d> offsets;
    for (const PinDesc& p : pins) {
        EXPECT_EQ(p.collider, 0);
        EXPECT_EQ(p.motion, -1);
        // The nearest skin vertex, found here by brute force.
        double best = 1e9;
        for (const Vec3d& x : skin) best = std::min(best, length(x - start[p.vertex]));
        EXPECT_DOUBLE_EQ(length(skin[p.collider_vertex] - start[p.vertex]), best) << "pin of vertex " << p.vertex;
        EXPECT_LT(best, 0.2) << "the cape starts on the shoulders";
        offsets.push_back(start[p.vertex] - skin[p.collider_vertex]);
    }
    double worst = 0.0, travel = 0.0;
    for (int frame = 1; frame <= 20; ++frame) {
        ASSERT_FALSE(world->step().non_finite) << "frame " << frame;
        collider_mesh_positions(runner, world->time(), skin);
        const std::vector<Vec3d> x = world->positions(0);
        for (std::size_t k = 0; k < pins.size(); ++k) {
            worst = std::max(worst, length(x[pins[k].vertex] - (skin[pins[k].collider_vertex] + offsets[k])));
            travel = std::max(travel, length(x[pins[k].vertex] - start[pins[k].vertex]));
        }
    }
    std::printf("[ skinned  ] runner scene: cape pins %.2e m off their skin vertices at worst, moved up to %.3f m\n", worst,
                travel);
    EXPECT_LT(worst, 1e-6);
    EXPECT_GT(travel, 0.01) << "the run did not move the shoulders: the test proves nothing";

    const SceneDesc again = parse_scene(scene_to_toml(scene, file.parent_path()), file.parent_path() / "saved.toml");
    const auto rebuilt = build_world(again);
    const std::vector<PinDesc>& pins_again = rebuilt->model().cloths[0].pins;
    ASSERT_EQ(pins_again.size(), pins.size());
    for (std::size_t k = 0; k < pins.size(); ++k) {
        EXPECT_EQ(pins_again[k].vertex, pins[k].vertex);
        EXPECT_EQ(pins_again[k].collider, pins[k].collider);
        EXPECT_EQ(pins_again[k].collider_vertex, pins[k].collider_vertex);
    }
}

// `follow` names a mesh collider of the scene and excludes `motion`; each mistake is an error that
// names the file, the line and what was expected.
TEST(SkinnedImport, FollowPinsThatCannotBeResolvedAreRefusedByName) {
    const std::filesystem::path file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets/scenes/bad_follow.toml";
    const auto text = [](const std::string& pin) {
        return "[[motion]]\nname = \"sway\"\n"
               "[[collider]]\nname = \"runner\"\nshape = \"mesh\"\nfile = \"../characters/runner.gltf\"\nclip = \"run\"\n"
               "[[collider]]\nname = \"floor\"\nshape = \"plane\"\n"
               "[[cloth]]\nname = \"cape\"\nmesh = { grid = { width = 0.3, height = 0.7, cells = [4, 4] } }\n"
               "[[cloth.pin]]\nedge = \"top\"\n" + pin;
    };
    const auto refused = [&](const std::string& pin, const std::vector<std::string>& parts) {
        try {
            (void)parse_scene(text(pin), file);
            FAIL() << "accepted: " << pin;
        } catch (const Error& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("bad_follow.toml:"), std::string::npos) << what;
            for (const std::string& p : parts) EXPECT_NE(what.find(p), std::string::npos) << what;
        }
    };
    refused("follow = \"runer\"\n", {"unknown collider 'runer'", "did you mean 'runner'"});
    refused("follow = \"floor\"\n", {"collider 'floor' is not a mesh"});
    refused("follow = \"runner\"\nmotion = \"sway\"\n", {"follow and motion together"});
    refused("follow = 3\n", {"follow"});
    EXPECT_NO_THROW((void)parse_scene(text("follow = \"runner\"\n"), file));
}
// A cape pinned to the runner's chest bone (PinDesc::collider_joint) while the runner turns on the
// spot: the pins keep their place in the bone's frame, so they swing round the body with it (a
// vertex pin keeps a fixed world offset and would not turn); a joint the skin lacks is refused.
TEST(SkinnedImport, PinsOnABoneTurnWithIt) {
    const auto skin = std::make_shared<const SkinnedMesh>(
        assets::import_skinned_mesh(std::filesystem::path(WEFT_SOURCE_DIR) / "assets/characters/runner.gltf"));
    std::uint32_t chest = 0;
    while (chest < skin->joints.size() && skin->joints[chest].name != "chest") ++chest;
    ASSERT_LT(chest, skin->joints.size());
    World world{WorldDesc{}};
    ColliderDesc runner{.name = "runner", .shape = ColliderShape::Mesh};
    runner.skin = skin;
    runner.mesh = std::make_shared<const MeshData>(skin->mesh);
    runner.clip = "run";
    runner.motion.angular_velocity = {0.0, 1.0, 0.0};  // turning on the spot: 1 rad/s about +y
    const std::size_t collider = world.add_collider(runner);
    ClothDesc cape{.name = "cape", .fabric = Fabric::cook(make_grid(0.3, 0.6, 4, 8, GridPlane::XY), {.density = 0.2})};
    cape.transform.translation = {0.0, 1.28, -0.15};  // behind the back, its top edge at 1.58 m
    for (std::uint32_t i = 0; i <= 4; ++i)
        cape.pins.push_back({.vertex = 8 * 5 + i, .collider = static_cast<int>(collider), .collider_joint = static_cast<int>(chest)});
    world.add_cloth(cape);
    const std::vector<Vec3d> start = world.positions(0);
    const auto radius = [](Vec3d p) { return std::sqrt(p.x * p.x + p.z * p.z); };
    double worst = 0.0, turned = 0.0;
    std::vector<Affine> maps0, maps;
    collider_mesh_transforms(world.model().colliders[0], 0.0, maps0);
    for (int frame = 1; frame <= 60; ++frame) {
        ASSERT_FALSE(world.step().non_finite) << "frame " << frame;
        collider_mesh_transforms(world.model().colliders[0], world.time(), maps);
        const std::vector<Vec3d> x = world.positions(0);
        for (std::uint32_t i = 0; i <= 4; ++i) {
            const std::uint32_t v = 8 * 5 + i;
            const Vec3d target = maps[chest].apply(inverse(maps0[chest]).apply(start[v]));
            worst = std::max(worst, length(x[v] - target));
        }
        const Vec3d a = start[8 * 5 + 2], b = x[8 * 5 + 2];  // the top edge's middle, round the axis
        turned = std::atan2(a.x * b.z - a.z * b.x, a.x * b.x + a.z * b.z);
        EXPECT_NEAR(radius(b), radius(a), 0.05) << "frame " << frame << ": the pin left the body's circle";
    }
    std::printf("[ skinned  ] cape on the chest bone: pins %.2e m off the bone's frame at worst, turned %.2f rad in 1 s\n",
                worst, -turned);
    EXPECT_LT(worst, 1e-6);
    EXPECT_NEAR(-turned, 1.0, 0.05) << "the pins did not turn with the body";

    World bad{WorldDesc{}};
    bad.add_collider(runner);
    ClothDesc c{.name = "bad", .fabric = cape.fabric};
    c.pins.push_back({.vertex = 0, .collider = 0, .collider_joint = 99});
    bad.add_cloth(c);
    try {
        (void)bad.step();
        FAIL() << "a pin on joint 99 was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("follows joint 99 of collider 'runner', which has"), std::string::npos) << e.what();
    }
}

// `[[cloth.pin]] follow = "runner"` with `joint = "chest"` pins to the bone; a joint without follow
// and a joint the skeleton lacks are errors naming the file, cloth and pin (and the joints there are).
TEST(SkinnedImport, SceneJointPinsAreResolvedAgainstTheSkeleton) {
    assets::install_mesh_loader();
    const std::filesystem::path file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets/scenes/joint_pins.toml";
    const auto text = [](const std::string& pin) {
        return "[[collider]]\nname = \"runner\"\nshape = \"mesh\"\nfile = \"../characters/runner.gltf\"\nclip = \"run\"\n"
               "[[cloth]]\nname = \"cape\"\nmesh = { grid = { width = 0.3, height = 0.6, cells = [4, 8] } }\n"
               "position = [0.0, 1.28, -0.15]\n"
               "[[cloth.pin]]\nedge = \"top\"\n" + pin;
    };
    const SceneDesc scene = parse_scene(text("follow = \"runner\"\njoint = \"chest\"\n"), file);
    const auto world = build_world(scene);
    const std::vector<PinDesc>& pins = world->model().cloths[0].pins;
    ASSERT_EQ(pins.size(), 5U);
    const SkinnedMesh& skin = *world->model().colliders[0].skin;
    for (const PinDesc& p : pins) {
        EXPECT_EQ(p.collider, 0);
        ASSERT_GE(p.collider_joint, 0);
        EXPECT_EQ(skin.joints[static_cast<std::size_t>(p.collider_joint)].name, "chest");
    }
    const std::string saved = scene_to_toml(scene, file.parent_path());
    EXPECT_NE(saved.find("joint = \"chest\""), std::string::npos) << saved;

    try {
        (void)parse_scene(text("joint = \"chest\"\n"), file);
        FAIL() << "a joint without follow was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("joint without follow"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("joint_pins.toml:"), std::string::npos) << e.what();
    }
    try {
        (void)build_world(parse_scene(text("follow = \"runner\"\njoint = \"chst\"\n"), file));
        FAIL() << "an unknown joint was accepted";
    } catch (const Error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("cloth[0] 'cape' pin[0]: unknown joint 'chst'"), std::string::npos) << what;
        EXPECT_NE(what.find("'chest'"), std::string::npos) << what;
    }
}

// A game switches a character's clip between steps: standing in its bind pose (no clip), then a
// jump that starts now (clip_start). The collision pipeline places the jump's poses from its start,
// and the kerchief on the head rises with it, with no intersection.
TEST(SkinnedImport, ACharacterSwitchesClipsBetweenSteps) {
    const auto skin = runner_skin();
    const std::unique_ptr<World> kerchief = kerchief_world();
    World& world = *kerchief;
    ColliderDesc runner{.name = "runner", .shape = ColliderShape::Mesh};
    runner.skin = skin;
    const std::size_t k = world.add_collider(runner);
    long long intersecting = 0;
    for (int frame = 1; frame <= 12; ++frame) intersecting += world.step().collision.remaining_intersections;
    const double start = world.time();
    world.collider(k).clip = "jump";
    world.collider(k).clip_loop = false;
    world.collider(k).clip_start = start;
    std::vector<Vec3d> placed(skin->mesh.positions.size()), expected(placed.size());
    double lowest_top = 0.0, worst = 0.0;
    for (int frame = 1; frame <= 45; ++frame) {
        const StepStats& s = world.step();
        ASSERT_FALSE(s.non_finite) << "frame " << frame;
        intersecting += s.collision.remaining_intersections;
        collider_mesh_positions(world.model().colliders[k], world.time(), placed);
        skin_at(*skin, "jump", world.time() - start, expected);
        for (std::size_t i = 0; i < placed.size(); ++i) worst = std::max(worst, length(placed[i] - expected[i]));
        if (frame == 42) {  // 0.7 s into the jump: its top
            lowest_top = 1e9;
            for (const Vec3d& p : world.positions(0)) lowest_top = std::min(lowest_top, p.y);
        }
    }
    EXPECT_LT(worst, 1e-9) << "the jump was not placed from its start";
    EXPECT_EQ(intersecting, 0);
    EXPECT_GT(lowest_top, 1.8) << "the head did not carry the kerchief up";
}
#endif

}  // namespace
}  // namespace weft
