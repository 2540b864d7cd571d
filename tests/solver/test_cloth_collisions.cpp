// Cloth collisions end to end through the public API on the CPU backend (docs/collisions.md):
// proximity contacts in the solve, CCD and impact zones after it, the exact check after every step.
// Each case must end every step with zero intersecting triangles; the control case (collisions off)
// proves the check sees the failure it guards against.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "collider_jump.h"
#include "rest_exclusion_scene.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

WorldDesc collision_world(bool self) {
    WorldDesc desc;
    desc.solver.dt = 1.0 / 60.0;
    desc.solver.substeps = 2;
    desc.solver.cg_tolerance = 1e-4;
    desc.solver.cg_max_iterations = 500;
    desc.collision.self_collision = self;
    desc.collision.check = true;
    return desc;
}

ClothDesc sheet(const char* name, const std::shared_ptr<const Fabric>& fabric, Vec3d position) {
    ClothDesc c{.name = name, .fabric = fabric};
    c.transform.translation = position;
    c.material.stretch_stiffness = 2e3;
    c.material.bending_stiffness = 1e-6;
    c.material.contact_thickness = 0.004;
    c.material.friction = 0.3;
    return c;
}

ColliderDesc floor_plane() { return ColliderDesc{.name = "floor", .shape = ColliderShape::Plane}; }

// A thin horizontal bar across z, 25 cm up, and the floor: a sheet dropped across it folds onto itself.
void add_bar_and_floor(World& world) {
    ColliderDesc bar{.name = "bar", .shape = ColliderShape::Capsule};
    bar.radius = 0.02;
    bar.half_height = 0.4;
    bar.motion.origin = {0.0, 0.25, 0.0};
    bar.motion.initial_rotation = rotation_from_vector({1.5707963267948966, 0.0, 0.0});
    world.add_collider(bar);
    world.add_collider(floor_plane());
}

// Two sheets dropped one above the other onto a ball and the floor.
void add_stacked_sheets_on_a_ball(World& world) {
    const auto fabric = Fabric::cook(make_grid(0.6, 0.6, 12, 12, GridPlane::XZ), {.density = 0.2});
    world.add_cloth(sheet("low", fabric, {0.0, 0.35, 0.0}));
    world.add_cloth(sheet("high", fabric, {0.03, 0.40, 0.02}));
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.radius = 0.15;
    ball.motion.origin = {0.0, 0.15, 0.0};
    world.add_collider(ball);
    world.add_collider(floor_plane());
}

// The two sheets drape over each other.
TEST(ClothCollisions, StackedSheetsOnABallStayApart) {
    World world(collision_world(true));
    add_stacked_sheets_on_a_ball(world);
    int contacts = 0;
    for (int frame = 0; frame < 45; ++frame) {
        const StepStats& s = world.step();
        ASSERT_FALSE(s.non_finite) << "frame " << frame;
        ASSERT_EQ(s.collision.remaining_intersections, 0) << "frame " << frame;
        ASSERT_EQ(s.collision.unresolved_substeps, 0) << "frame " << frame;
        contacts = std::max(contacts, s.collision.contacts);
    }
    EXPECT_GT(contacts, 0) << "the sheets never came close: the test does not test anything";
    // The upper sheet still lies on top: its highest point (on the ball's top) is above the lower
    // sheet's highest point.
    auto top = [](const std::vector<Vec3d>& x) {
        return std::max_element(x.begin(), x.end(), [](Vec3d a, Vec3d b) { return a.y < b.y; })->y;
    };
    EXPECT_GT(top(world.positions(1)), top(world.positions(0)));

    // Where the memory goes: the parts sum to the total, and the contacts' buffers are a part.
    std::size_t sum = 0, collisions = 0;
    for (const auto& [what, bytes] : world.memory_breakdown()) {
        sum += bytes;
        if (what == "collisions") collisions = bytes;
    }
    EXPECT_EQ(sum, world.memory_bytes());
    EXPECT_GT(collisions, 0U);
}

// Four sheets 2 cm apart dropped onto a ball, in both contact modes: every frame intersection-free,
// and at the end the layers still in their order over the ball's top (no sheet on the wrong side of
// another). The offset mode must also have truncated moves and found contacts, or it tested nothing.
class StackedLayers : public ::testing::TestWithParam<CollisionMode> {};

TEST_P(StackedLayers, StayInOrderOverABall) {
    WorldDesc desc = collision_world(true);
    desc.collision.mode = GetParam();
    World world(desc);
    const auto fabric = Fabric::cook(make_grid(0.6, 0.6, 12, 12, GridPlane::XZ), {.density = 0.2});
    constexpr int kSheets = 4;
    for (int k = 0; k < kSheets; ++k) {
        const std::string name = "sheet" + std::to_string(k);
        world.add_cloth(sheet(name.c_str(), fabric, {0.0, 0.33 + 0.02 * k, 0.0}));
    }
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.radius = 0.15;
    ball.motion.origin = {0.0, 0.15, 0.0};
    world.add_collider(ball);
    world.add_collider(floor_plane());
    std::int64_t truncated = 0;
    int contacts = 0, overshoots = 0, fallbacks = 0;
    for (int frame = 0; frame < 60; ++frame) {
        const StepStats& s = world.step();
        ASSERT_FALSE(s.non_finite) << "frame " << frame;
        ASSERT_EQ(s.collision.remaining_intersections, 0) << "frame " << frame;
        ASSERT_EQ(s.collision.unresolved_substeps, 0) << "frame " << frame;
        ASSERT_EQ(s.collision.frozen_vertices, 0) << "frame " << frame;
        truncated += s.collision.truncated_vertices;
        contacts = std::max(contacts, s.collision.contacts);
        overshoots += s.collision.collider_overshoots;
        fallbacks += s.collision.bound_fallbacks;
    }
    std::printf("[ layers   ] %s: %lld truncated moves, %d ball overshoots put back, %d CCD fallbacks\n",
                GetParam() == CollisionMode::Offset ? "offset" : "ccd_zones", static_cast<long long>(truncated), overshoots,
                fallbacks);
    EXPECT_GT(contacts, 0);
    if (GetParam() == CollisionMode::Offset) {
        EXPECT_GT(truncated, 0) << "the bounds never acted: the test does not test them";
        // The bounded moves are not overridden after the truncation: a slow overshoot into the ball is
        // left to the penalty, so nothing sends a substep to the CCD fallback.
        EXPECT_EQ(overshoots, 0);
        EXPECT_EQ(fallbacks, 0);
    } else {
        EXPECT_EQ(truncated, 0);
    }
    // The centre vertex of each sheet (on the ball's top): heights strictly increase with the layer.
    const std::size_t centre = 6 * 13 + 6;
    double below = -1.0;
    for (int k = 0; k < kSheets; ++k) {
        const double y = world.positions(static_cast<std::size_t>(k))[centre].y;
        EXPECT_GT(y, below) << "sheet " << k << " is not above sheet " << k - 1;
        EXPECT_GT(y, 0.29) << "sheet " << k << " fell off the ball";
        below = y;
    }
}

/// The world's collision memory (bytes), from its breakdown.
std::size_t collision_bytes(const World& world) {
    for (const auto& [what, bytes] : world.memory_breakdown())
        if (what == "collisions") return bytes;
    return 0;
}

// A flood of candidate pairs (the sheet crushed into a 2 cm cube for one step) grows the narrow
// phase's lists; once the sheet lies flat again, a trim window later (collision/buffer_trim.h) the
// collision memory is given back.
TEST(ClothCollisions, AFloodOfContactCandidatesIsGivenBack) {
    WorldDesc desc = collision_world(true);
    desc.collision.check = false;
    World world(desc);
    const auto fabric = Fabric::cook(make_grid(0.6, 0.6, 14, 14, GridPlane::XZ), {.density = 0.2});
    world.add_cloth(sheet("sheet", fabric, {0.0, 1.0, 0.0}));
    (void)world.step();
    const std::size_t calm = collision_bytes(world);
    const std::vector<Vec3d> flat = world.positions(0);
    std::vector<Vec3d> crushed(flat.size()), still(flat.size());
    std::uint32_t seed = 12345;
    const auto next = [&seed] {
        seed = seed * 1664525u + 1013904223u;
        return static_cast<double>(seed >> 8) / static_cast<double>(1u << 24);
    };
    for (Vec3d& p : crushed) p = Vec3d{next(), next(), next()} * 0.02 + Vec3d{0.0, 1.0, 0.0};
    world.set_state(0, crushed, still);
    (void)world.step();
    const std::size_t flood = collision_bytes(world);
    world.set_state(0, flat, still);
    for (std::size_t k = 0; k < 2 * 240 / static_cast<std::size_t>(desc.solver.substeps) + 2; ++k) (void)world.step();
    const std::size_t after = collision_bytes(world);
    std::printf("[ memory   ] collision stages: %zu bytes calm, %zu after the flood, %zu a trim window later\n", calm, flood,
                after);
    EXPECT_GT(flood, calm + (std::size_t{4} << 20)) << "the flood did not grow the lists: the test proves nothing";
    EXPECT_LT(after, flood / 4);
}

INSTANTIATE_TEST_SUITE_P(BothModes, StackedLayers, ::testing::Values(CollisionMode::CcdZones, CollisionMode::Offset),
                         [](const auto& mode) { return mode.param == CollisionMode::Offset ? "offset" : "ccd_zones"; });

// One long sheet folded onto itself by dropping it across a thin bar.
TEST(ClothCollisions, SheetFoldingOverABarDoesNotPassThroughItself) {
    World world(collision_world(true));
    const auto fabric = Fabric::cook(make_grid(0.8, 0.3, 20, 8, GridPlane::XZ), {.density = 0.2});
    world.add_cloth(sheet("strip", fabric, {0.1, 0.3, 0.0}));
    add_bar_and_floor(world);
    int substeps = 0, reused = 0;
    for (int frame = 0; frame < 60; ++frame) {
        const StepStats& s = world.step();
        ASSERT_FALSE(s.non_finite) << "frame " << frame;
        ASSERT_EQ(s.collision.remaining_intersections, 0) << "frame " << frame;
        ASSERT_EQ(s.collision.unresolved_substeps, 0) << "frame " << frame;
        substeps += s.substeps;
        reused += s.collision.reused_detections;
    }
    // The impact zones' first detection reuses the proximity detection's pairs in most substeps
    // (BroadPhase::find_reusing); never in more than there were.
    std::printf("first detection from the proximity's pairs in %d of %d substeps\n", reused, substeps);
    EXPECT_GT(reused, substeps / 2);
    EXPECT_LE(reused, substeps);
}

// Offset contact with the bound query culled by the normal cones (collision.cull_contacts): a sheet
// of 1 cm cells, finer than the query radius reaches, folding over a bar. Every frame ends
// intersection-free, culling ran, and each update whose culled patches stopped holding was measured
// again in full (counted).
TEST(ClothCollisions, OffsetContactWithACulledBoundQueryStaysIntersectionFree) {
    WorldDesc desc = collision_world(true);
    desc.collision.mode = CollisionMode::Offset;
    desc.collision.cull_contacts = true;
    World world(desc);
    const auto fabric = Fabric::cook(make_grid(0.6, 0.2, 60, 20, GridPlane::XZ), {.density = 0.2});
    world.add_cloth(sheet("strip", fabric, {0.1, 0.3, 0.0}));
    add_bar_and_floor(world);
    double culling_ms = 0.0;
    int uncullings = 0;
    for (int frame = 0; frame < 45; ++frame) {
        const StepStats& s = world.step();
        ASSERT_FALSE(s.non_finite) << "frame " << frame;
        ASSERT_EQ(s.collision.remaining_intersections, 0) << "frame " << frame;
        ASSERT_EQ(s.collision.unresolved_substeps, 0) << "frame " << frame;
        culling_ms += s.ms(Stage::Culling);
        uncullings += s.collision.uncullings;
    }
    EXPECT_GT(culling_ms, 0.0) << "the bound query was never culled";
    std::printf("culled bound query: %d of the updates measured again in full\n", uncullings);
}

// A sheet whose edges are shorter than its contact thickness: its rest neighbours are within the
// thickness but are no contacts (CollisionSettings::rest_exclusion); the exclusion off gives them
// springs, and two sheets 3 mm apart keep theirs with it on.
TEST(ClothCollisions, RestNeighboursGetNoSpringsButOtherClothsDo) {
    const int excluded = test::rest_exclusion_contacts("cpu", 1.0, false);
    const int kept = test::rest_exclusion_contacts("cpu", 0.0, false);
    const int two_sheets = test::rest_exclusion_contacts("cpu", 1.0, true);
    EXPECT_EQ(excluded, 0);
    EXPECT_GT(kept, 1000) << "the scene must have in-plane neighbours within the thickness";
    EXPECT_GE(two_sheets, 41 * 41) << "every vertex of each sheet is over a face of the other";
}

// A coarse CCD time tolerance (collision.ccd_time_tolerance) keeps CCD's guarantee: the stacked
// sheets end every frame intersection-free. It reaches the CCD: the run differs from the default's.
// Out of its range it is refused.
TEST(ClothCollisions, ACoarseCcdTimeToleranceStaysIntersectionFree) {
    auto run = [](double tolerance) {
        WorldDesc desc = collision_world(true);
        desc.collision.ccd_time_tolerance = tolerance;
        World world(desc);
        add_stacked_sheets_on_a_ball(world);
        std::int64_t hits = 0;
        for (int frame = 0; frame < 45; ++frame) {
            const StepStats& s = world.step();
            EXPECT_FALSE(s.non_finite) << "frame " << frame;
            EXPECT_EQ(s.collision.remaining_intersections, 0) << "tolerance " << tolerance << ", frame " << frame;
            EXPECT_EQ(s.collision.unresolved_substeps, 0) << "tolerance " << tolerance << ", frame " << frame;
            hits += s.collision.ccd_hits;
        }
        return std::make_pair(hits, world.positions(1));
    };
    const auto [default_hits, default_x] = run(0.0);
    const auto [coarse_hits, coarse_x] = run(1e-2);
    EXPECT_GT(default_hits, 0) << "no CCD hit: the scene does not test the tolerance";
    EXPECT_NE(coarse_x, default_x) << "the tolerance did not reach the CCD";
    for (double bad : {-1e-3, 0.5}) {
        WorldDesc desc;
        desc.collision.ccd_time_tolerance = bad;
        EXPECT_THROW(World world(desc), Error) << bad;
    }
}

TEST(ClothCollisions, RestExclusionOutOfRangeIsRejected) {
    WorldDesc desc;
    desc.collision.rest_exclusion = -1.0;
    EXPECT_THROW(World world(desc), Error);
}

// Control: without cloth collisions the same two sheets end up through each other on the floor, and
// the check says so. (Without this, a check that always answered 0 would pass the tests above.)
TEST(ClothCollisions, WithoutCollisionsTheCheckFindsIntersections) {
    World world(collision_world(false));
    add_stacked_sheets_on_a_ball(world);
    std::int64_t worst = 0;
    for (int frame = 0; frame < 45; ++frame) worst = std::max(worst, world.step().collision.remaining_intersections);
    EXPECT_GT(worst, 0);
}

// A 10 cm ball at 50 m/s through a hanging sheet (the `projectile` scene): at 4 substeps of 1/60 s
// it moves 21 cm per substep, twice its width, so the end-of-substep penalty alone lets it through.
// The swept test must catch the sheet: no vertex ever inside the ball, and the sheet dragged along.
TEST(ClothCollisions, FastBallDoesNotTunnelThroughASheet) {
    WorldDesc desc = collision_world(false);
    desc.solver.substeps = 4;
    desc.solver.cg_max_iterations = 2000;
    World world(desc);
    const auto fabric = Fabric::cook(make_grid(0.5, 0.5, 16, 16), {.density = 0.2});
    ClothDesc cloth = sheet("sheet", fabric, {0.0, 1.0, 0.0});
    cloth.pins = {{16 * 17, -1}, {16 * 17 + 16, -1}};  // top corners
    world.add_cloth(cloth);
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.radius = 0.05;
    ball.motion.origin = {0.0, 1.0, 0.5};
    ball.motion.linear_velocity = {0.0, 0.0, -50.0};
    world.add_collider(ball);
    int hits = 0;
    double furthest = 0.0;
    for (int frame = 0; frame < 3; ++frame) {
        const StepStats& s = world.step();
        ASSERT_FALSE(s.non_finite);
        hits += s.collision.swept_collider_hits;
        const Vec3d centre = ball.motion.origin + world.time() * ball.motion.linear_velocity;
        for (const Vec3d& p : world.positions(0)) {
            ASSERT_GE(math::length(p - centre), ball.radius - 1e-9) << "frame " << frame;
            furthest = std::min(furthest, p.z);
        }
    }
    EXPECT_GT(hits, 0);
    EXPECT_LT(furthest, -0.5) << "the ball should have dragged the sheet along";
}

}  // namespace
}  // namespace weft

namespace weft {
namespace {

// A mesh collider that jumps between substeps is reported (tests/common/collider_jump.h).
TEST(ClothCollisions, AMeshColliderThatJumpsBetweenSubstepsIsReported) { test::expect_collider_jumps_reported("cpu"); }

}  // namespace
}  // namespace weft
