// Pulling and pinning cloth while it runs (World::set_grab, World::pin/unpin): what the editor's
// mouse does. The grab spring is implicit (weft/grab.h), so it holds a whole cloth near its target
// and stays finite at any stiffness; a pin holds a vertex where it was when pinned, and the rebuild
// it needs does not send the cloth back to its start.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "weft/backend/model.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

constexpr int kCells = 10;  // (kCells+1)² vertices; the top row is y = 1 m

// A free 1 m sheet (it falls).
std::unique_ptr<World> free_sheet(WorldDesc desc = {}) {
    auto world = std::make_unique<World>(desc);
    world->add_cloth({.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, kCells, kCells))});
    return world;
}

double cloth_mass(const World& w) {
    double m = 0.0;
    for (double x : w.model().cloths[0].fabric->masses()) m += x;
    return m;
}

// The vertex nearest `p` at the cloth's start.
std::uint32_t vertex_near(World& w, const Vec3d& p) {
    const std::vector<Vec3d> x = w.positions(0);
    std::uint32_t best = 0;
    for (std::uint32_t i = 0; i < x.size(); ++i)
        if (math::length(x[i] - p) < math::length(x[best] - p)) best = i;
    return best;
}

TEST(Grab, PullsAFallingSheetToTheTargetAndLetsGo) {
    auto owner = free_sheet();
    World& world = *owner;
    const std::vector<Vec3d> start = world.positions(0);
    // The corner the sheet would fall from: grab it and hold it where it is, a little forward.
    const std::uint32_t corner = vertex_near(world, start[0]);
    const Vec3d target = start[corner] + Vec3d{0.0, 0.0, 0.3};
    VertexGrab g{.cloth = 0, .vertex = corner, .target = target, .stiffness = grab_stiffness_for(cloth_mass(world))};
    world.set_grab(g);
    for (int k = 0; k < 90; ++k) ASSERT_FALSE(world.step().non_finite);
    // The spring carries the whole falling sheet: within twice its design sag of the target.
    const double held = math::length(world.positions(0)[corner] - target);
    EXPECT_LT(held, 0.04) << "the grabbed vertex hangs " << held << " m from the target";
    const double other = math::length(world.positions(0)[vertex_near(world, start[kCells])] - target);
    EXPECT_GT(other, 0.5) << "the rest of the sheet hangs below";

    // Moving the grab moves the vertex.
    g.target = target + Vec3d{0.4, 0.0, 0.0};
    world.set_grab(g);
    for (int k = 0; k < 60; ++k) (void)world.step();
    EXPECT_LT(math::length(world.positions(0)[corner] - g.target), 0.04);

    // Released, it falls.
    world.release_grab();
    EXPECT_FALSE(world.grab());
    for (int k = 0; k < 30; ++k) (void)world.step();
    EXPECT_LT(world.positions(0)[corner].y, g.target.y - 0.3);
}

// A spring far stiffer than the cloth on a light vertex, at a large step: implicit, so finite.
TEST(Grab, StaysFiniteAtTheStiffestSettingAndALargeStep) {
    WorldDesc desc;
    desc.solver.dt = 0.05;
    desc.solver.substeps = 1;
    desc.solver.cg_max_iterations = 2000;
    auto owner = free_sheet(desc);
    World& world = *owner;
    world.add_cloth({.name = "dummy", .fabric = Fabric::cook(make_grid(0.1, 0.1, 1, 1))});
    world.set_grab({.cloth = 0, .vertex = 0, .target = {3.0, 2.0, 1.0}, .stiffness = 1e9, .damping = 1e6});
    for (int k = 0; k < 40; ++k) ASSERT_FALSE(world.step().non_finite) << "step " << k;
    for (const Vec3d& p : world.positions(0)) ASSERT_TRUE(math::is_finite(p));
    EXPECT_LT(math::length(world.positions(0)[0] - Vec3d{3.0, 2.0, 1.0}), 0.01);
}

TEST(Grab, BadValuesAreErrorsNamingThem) {
    auto owner = free_sheet();
    World& world = *owner;
    const auto message = [&](const VertexGrab& g) {
        try {
            world.set_grab(g);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message({.cloth = 1, .stiffness = 10}).find("cloth 1 of 1"), std::string::npos);
    EXPECT_NE(message({.vertex = 121, .stiffness = 10}).find("vertex 121"), std::string::npos);
    EXPECT_NE(message({.stiffness = -1}).find("stiffness"), std::string::npos);
    EXPECT_NE(message({.stiffness = 10, .damping = 2e6}).find("damping"), std::string::npos);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    EXPECT_NE(message({.target = {nan, 0, 0}, .stiffness = 10}).find("not finite"), std::string::npos);
    EXPECT_FALSE(world.grab()) << "a refused grab is not kept";
}

TEST(Pins, PinningHoldsAVertexWhereItIsAndKeepsTheState) {
    auto owner = free_sheet();
    World& world = *owner;
    for (int k = 0; k < 20; ++k) (void)world.step();  // falling
    const std::vector<Vec3d> before = world.positions(0);
    const std::vector<Vec3d> velocities = world.velocities(0);
    const std::uint32_t v = (kCells + 1) * kCells;  // the top-left corner: the sheet swings from it
    ASSERT_FALSE(world.is_pinned(0, v));
    EXPECT_TRUE(world.pin(0, v));
    EXPECT_FALSE(world.pin(0, v)) << "pinned already";
    EXPECT_TRUE(world.is_pinned(0, v));
    // The rebuild the pin needs keeps every vertex's state (not the sheet's start).
    const std::vector<Vec3d> after = world.positions(0);
    const std::vector<Vec3d> velocities_after = world.velocities(0);
    for (std::size_t i = 0; i < before.size(); ++i) {
        ASSERT_EQ(after[i], before[i]) << "vertex " << i;
        ASSERT_EQ(velocities_after[i], velocities[i]) << "vertex " << i;
    }
    for (int k = 0; k < 40; ++k) (void)world.step();
    EXPECT_LT(math::length(world.positions(0)[v] - before[v]), 1e-9) << "held where it was pinned";
    EXPECT_GT(math::length(world.positions(0)[kCells] - before[kCells]), 0.05) << "the far corner swings";

    // A grab on a pinned vertex does nothing.
    world.set_grab({.cloth = 0, .vertex = v, .target = before[v] + Vec3d{1, 0, 0}, .stiffness = 1e4});
    (void)world.step();
    EXPECT_LT(math::length(world.positions(0)[v] - before[v]), 1e-9);
    world.release_grab();

    EXPECT_TRUE(world.unpin(0, v));
    EXPECT_FALSE(world.unpin(0, v)) << "no pin left";
    for (int k = 0; k < 20; ++k) (void)world.step();
    EXPECT_GT(math::length(world.positions(0)[v] - before[v]), 0.05) << "unpinned, it falls";
    EXPECT_THROW(world.pin(1, 0), Error);
    EXPECT_THROW(world.pin(0, 999), Error);
}

// The scene's own pins (no position) still hold their vertex where it starts.
TEST(Pins, ScenePinsHoldTheStartPosition) {
    auto owner = free_sheet();
    World& world = *owner;
    const Vec3d start = world.positions(0)[3];
    ClothDesc pinned{.name = "pinned", .fabric = Fabric::cook(make_grid(1.0, 1.0, kCells, kCells))};
    pinned.pins = {{.vertex = 3}};
    world.add_cloth(pinned);
    for (int k = 0; k < 30; ++k) (void)world.step();
    EXPECT_LT(math::length(world.positions(1)[3] - start), 1e-9);
    EXPECT_GT(math::length(world.positions(0)[3] - start), 0.05) << "cloth 0 has no pin";
}

}  // namespace
}  // namespace weft
