// World::set_collider_shape: an analytic collider becomes another analytic shape between steps, the
// world is rebuilt with every cloth's state kept, and the cloth lies on the new shape; a mesh on
// either side is an error naming the collider.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

constexpr double kSize = 0.2;  // m: the sphere's radius, then the box's half extents

// A 0.6 m sheet of 12×12 cells, level, 5 cm above a ball of radius kSize at the origin.
std::unique_ptr<World> sheet_over_a_ball() {
    auto world = std::make_unique<World>(WorldDesc{}, "cpu");
    ClothDesc sheet{.name = "sheet", .fabric = Fabric::cook(make_grid(0.6, 0.6, 12, 12, GridPlane::XZ))};
    sheet.transform.translation = {0.0, kSize + 0.05, 0.0};  // the grid is centred on the origin
    world->add_cloth(sheet);
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.radius = kSize;
    world->add_collider(ball);
    return world;
}

// The lowest cloth vertex over the square |x|, |z| < 0.9·kSize: the ball's top cannot hold the
// vertices over its corners (the sphere is below y = kSize·√(1 − 2·0.9²) there: nowhere); a box's top can.
double lowest_over_the_top(const World& world) {
    double lowest = 1e9;
    for (const Vec3d& x : world.positions(0))
        if (std::abs(x.x) < 0.9 * kSize && std::abs(x.z) < 0.9 * kSize) lowest = std::min(lowest, x.y);
    return lowest;
}

TEST(ColliderShape, ABallTurnedIntoABoxHoldsTheClothOnItsTopWithTheStateKept) {
    const auto world = sheet_over_a_ball();
    for (int f = 0; f < 40; ++f) (void)world->step();
    const double on_the_ball = lowest_over_the_top(*world);
    const std::vector<Vec3d> before = world->positions(0), v_before = world->velocities(0);

    world->set_collider_shape(0, ColliderShape::Box);
    EXPECT_EQ(world->collider(0).shape, ColliderShape::Box);
    EXPECT_EQ(world->collider(0).half_extents.x, kSize) << "the box takes the ball's size";
    EXPECT_EQ(world->collider(0).half_extents.z, kSize);
    world->build();  // the rebuild the next step would do
    EXPECT_EQ(world->positions(0), before) << "the rebuild keeps the cloth's state";
    EXPECT_EQ(world->velocities(0), v_before);

    for (int f = 0; f < 40; ++f) {
        const StepStats& s = world->step();
        ASSERT_FALSE(s.non_finite) << "frame " << f;
    }
    const double on_the_box = lowest_over_the_top(*world);
    std::printf("[ shape    ] lowest vertex over the top's square: %.4f m on the ball, %.4f m on the box (top at %.2f m)\n",
                on_the_ball, on_the_box, kSize);
    EXPECT_LT(on_the_ball, kSize - 0.02) << "the ball does not hold the corners: the test would not tell the shapes apart";
    EXPECT_GT(on_the_box, kSize - 0.005) << "the cloth is held by the box's top";
    // Inside the box nowhere (a contact thickness's overlap at most).
    for (const Vec3d& x : world->positions(0)) {
        const bool inside = std::abs(x.x) < kSize - 0.01 && std::abs(x.z) < kSize - 0.01 && x.y < kSize - 0.01 && x.y > -kSize;
        EXPECT_FALSE(inside) << "a vertex at (" << x.x << ", " << x.y << ", " << x.z << ") is inside the box";
    }

    // A tall box becomes a capsule as wide as its larger side reaching as high, then a ball of its
    // height; the ball a cube again.
    world->collider(0).half_extents = {0.1, 0.5, 0.2};
    world->set_collider_shape(0, ColliderShape::Capsule);
    EXPECT_EQ(world->collider(0).radius, 0.2);
    EXPECT_DOUBLE_EQ(world->collider(0).half_height, 0.3);
    world->set_collider_shape(0, ColliderShape::Sphere);
    EXPECT_DOUBLE_EQ(world->collider(0).radius, 0.5);
    world->set_collider_shape(0, ColliderShape::Box);
    EXPECT_EQ(world->collider(0).half_extents, (Vec3d{0.5, 0.5, 0.5}));
    EXPECT_FALSE(world->step().non_finite);
}

TEST(ColliderShape, AMeshOnEitherSideOrAnUnknownColliderIsAnErrorNamingIt) {
    const auto world = sheet_over_a_ball();
    const auto message = [&](auto&& call) {
        try {
            call();
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    const std::string to_mesh = message([&] { world->set_collider_shape(0, ColliderShape::Mesh); });
    EXPECT_NE(to_mesh.find("collider 'ball'"), std::string::npos) << to_mesh;
    EXPECT_NE(to_mesh.find("a sphere cannot become a mesh"), std::string::npos) << to_mesh;
    EXPECT_EQ(world->collider(0).shape, ColliderShape::Sphere) << "nothing changed";

    ColliderDesc slab{.name = "slab", .shape = ColliderShape::Mesh};
    slab.mesh = std::make_shared<const MeshData>(make_grid(1.0, 1.0, 1, 1, GridPlane::XZ));
    world->add_collider(slab);
    const std::string from_mesh = message([&] { world->set_collider_shape(1, ColliderShape::Box); });
    EXPECT_NE(from_mesh.find("collider 'slab': a mesh cannot become a box"), std::string::npos) << from_mesh;
    const std::string missing = message([&] { world->set_collider_shape(2, ColliderShape::Box); });
    EXPECT_NE(missing.find("collider 2 of 2"), std::string::npos) << missing;
    world->set_collider_shape(0, ColliderShape::Sphere);  // the same shape: nothing to do
    EXPECT_EQ(world->collider(0).radius, kSize);
}

}  // namespace
}  // namespace weft
