#pragma once
// A mesh collider that a game moves with no motion between two steps (its motion rewritten so that
// it is elsewhere at the time already reached) is reported: the collisions sweep each substep's
// motion only, so cloth can end up through a collider that jumps. A motion rewritten the way a game
// should (from where the collider is now) reports nothing. The same expectations on every backend.
#include <gtest/gtest.h>

#include <memory>

#include "weft/mesh.h"
#include "weft/world.h"

namespace weft::test {

inline void expect_collider_jumps_reported(const char* backend) {
    WorldDesc desc;
    desc.solver.dt = 1.0 / 60.0;
    desc.solver.substeps = 2;
    World world(desc, backend);
    ClothDesc cloth{.name = "patch", .fabric = Fabric::cook(make_grid(0.4, 0.4, 4, 4, GridPlane::XZ))};
    cloth.transform.translation = {0.0, 1.0, 0.0};
    world.add_cloth(cloth);
    ColliderDesc slab{.name = "slab", .shape = ColliderShape::Mesh};
    slab.mesh = std::make_shared<const MeshData>(make_grid(2.0, 2.0, 2, 2, GridPlane::XZ));
    slab.motion.linear_velocity = {0.1, 0.0, 0.0};
    const std::size_t k = world.add_collider(slab);
    for (int step = 0; step < 3; ++step) EXPECT_EQ(world.step().collision.collider_jumps, 0) << "step " << step;
    // Continued from where it is: velocity changed, no jump.
    Motion& m = world.collider(k).motion;
    const Vec3d here = m.at(world.time()).translation;
    m.linear_velocity = {0.0, 0.0, 0.3};
    m.origin = here - world.time() * m.linear_velocity;
    EXPECT_EQ(world.step().collision.collider_jumps, 0);
    // Moved 5 cm at the time already reached: the next substep starts it away from where it ended.
    m.origin.x += 0.05;
    const StepStats& s = world.step();
    EXPECT_EQ(s.collision.collider_jumps, 1);
    EXPECT_NEAR(s.collision.collider_jump_max, 0.05, 1e-9);
    EXPECT_EQ(world.step().collision.collider_jumps, 0) << "once there, it moves on smoothly";
}

}  // namespace weft::test
