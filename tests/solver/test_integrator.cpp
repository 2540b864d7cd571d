// The implicit integrator against exact solutions and physical laws.
#include <gtest/gtest.h>

#include <cmath>

#include "weft/backend/model.h"
#include "weft/mesh.h"
#include "weft/physics/bending.h"
#include "weft/physics/membrane.h"
#include "weft/world.h"

namespace weft {
namespace {

WorldDesc settings(double dt, Precision precision = Precision::Double) {
    WorldDesc w;
    w.solver.dt = dt;
    w.solver.precision = precision;
    w.solver.cg_tolerance = 1e-10;
    return w;
}

// Free fall: with no internal forces excited (a rigidly translating sheet), implicit Euler gives
// v_n = v0 + n·h·g and x_n = x0 + n·h·v0 + h²·g·n(n+1)/2 exactly.
void check_free_fall(Precision precision, double tolerance) {
    const double h = 1.0 / 100.0;
    WorldDesc desc = settings(h, precision);
    World world(desc);
    auto fabric = Fabric::cook(make_grid(0.5, 0.5, 6, 6));
    const Vec3d v0{0.3, 1.5, -0.2};
    world.add_cloth({.name = "sheet", .fabric = fabric, .initial_velocity = v0});
    const auto x0 = world.positions(0);
    const int steps = 50;
    for (int n = 1; n <= steps; ++n) {
        const StepStats& s = world.step();
        ASSERT_TRUE(s.ok());
        const auto x = world.positions(0);
        const double dn = n;
        const Vec3d expected_offset = (dn * h) * v0 + (h * h * dn * (dn + 1.0) / 2.0) * desc.gravity;
        for (std::size_t i = 0; i < x.size(); ++i) {
            const Vec3d e = x0[i] + expected_offset;
            ASSERT_NEAR(x[i].x, e.x, tolerance) << "step " << n;
            ASSERT_NEAR(x[i].y, e.y, tolerance) << "step " << n;
            ASSERT_NEAR(x[i].z, e.z, tolerance) << "step " << n;
        }
    }
}

TEST(Integrator, FreeFallMatchesTheExactDiscreteSolutionInDouble) { check_free_fall(Precision::Double, 1e-10); }
TEST(Integrator, FreeFallMatchesTheExactDiscreteSolutionInFloat) { check_free_fall(Precision::Float, 2e-4); }

// Forces on every vertex (internal + gravity) at a state, from the shared physics functions.
std::vector<Vec3d> net_forces(const World& world, std::size_t cloth, const std::vector<Vec3d>& x) {
    const ClothDesc& c = world.model().cloths[cloth];
    const Fabric& f = *c.fabric;
    std::vector<Vec3d> force(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) force[i] = f.masses()[i] * world.model().settings.gravity;
    const auto mat = physics::membrane_material(c.material.stretch_stiffness, c.material.poisson_ratio);
    for (std::size_t t = 0; t < f.triangle_count(); ++t) {
        const auto& v = f.triangles()[t].v;
        const Vec3d xs[3] = {x[v[0]], x[v[1]], x[v[2]]};
        Vec3d g[3];
        physics::membrane_evaluate<double>(f.triangle_rest()[t].dm_inv, f.triangle_rest()[t].area, mat, xs, g, nullptr,
                                           physics::HessianKind::None);
        for (int a = 0; a < 3; ++a) force[v[a]] -= g[a];
    }
    for (const Hinge& h : f.hinges()) {
        const Vec3d xs[4] = {x[h.v[0]], x[h.v[1]], x[h.v[2]], x[h.v[3]]};
        Vec3d g[4];
        physics::bending_evaluate<double>(c.material.bending_stiffness, h.weight, h.rest_angle, xs, g, nullptr,
                                          physics::HessianKind::None);
        for (int a = 0; a < 4; ++a) force[h.v[a]] -= g[a];
    }
    return force;
}

TEST(Integrator, HangingClothReachesAStaticEquilibriumWhoseForcesBalance) {
    WorldDesc desc = settings(1.0 / 30.0);
    desc.solver.newton_iterations = 2;
    World world(desc);
    const int n = 12;
    auto fabric = Fabric::cook(make_grid(1.0, 1.0, n, n));
    ClothDesc cloth{.name = "hanging", .fabric = fabric};
    cloth.material.stretch_stiffness = 2000.0;
    cloth.material.damping_mass = 2.0;
    const std::uint32_t top_left = std::uint32_t(n * (n + 1)), top_right = std::uint32_t((n + 1) * (n + 1) - 1);
    cloth.pins = {{top_left, -1}, {top_right, -1}};
    world.add_cloth(cloth);
    for (int i = 0; i < 600; ++i) ASSERT_TRUE(world.step().ok());
    const auto x = world.positions(0);
    const auto v = world.velocities(0);
    const auto force = net_forces(world, 0, x);
    double total_weight = 0.0, max_residual = 0.0, max_speed = 0.0, max_weight = 0.0;
    Vec3d reaction{};
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double w = fabric->masses()[i] * 9.81;
        total_weight += w;
        max_weight = std::max(max_weight, w);
        max_speed = std::max(max_speed, physics::length(v[i]));
        if (i == top_left || i == top_right)
            reaction -= force[i];  // what the pins must supply
        else
            max_residual = std::max(max_residual, physics::length(force[i]));
    }
    EXPECT_LT(max_speed, 1e-3);
    // Every free vertex is in balance to a small fraction of one vertex's weight ...
    EXPECT_LT(max_residual, 1e-2 * max_weight);
    // ... and the pins carry the whole weight of the cloth, straight up.
    EXPECT_NEAR(reaction.y, total_weight, 1e-3 * total_weight);
    EXPECT_NEAR(reaction.x, 0.0, 1e-3 * total_weight);
    EXPECT_NEAR(reaction.z, 0.0, 1e-3 * total_weight);
    // The sheet sags below its pins.
    EXPECT_LT(x[std::size_t(n / 2)].y, x[top_left].y - 0.5);
}

TEST(Integrator, EnergyDoesNotGrowInAnUndampedUnforcedRun) {
    WorldDesc desc = settings(1.0 / 60.0);
    desc.gravity = {0, 0, 0};
    World world(desc);
    auto fabric = Fabric::cook(make_grid(1.0, 1.0, 10, 10));
    ClothDesc cloth{.name = "free", .fabric = fabric};
    cloth.material.damping_mass = 0.0;
    cloth.material.damping_stiffness = 0.0;
    cloth.material.bending_stiffness = 1e-4;
    world.add_cloth(cloth);
    // Start stretched and crumpled so that every force is excited.
    auto x = world.positions(0);
    std::vector<Vec3d> v(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
        x[i] = Vec3d{1.2 * x[i].x, 0.9 * x[i].y, 0.05 * std::sin(7.0 * x[i].x + 3.0 * x[i].y)};
        v[i] = Vec3d{0.1 * std::cos(5.0 * x[i].y), 0.0, 0.2 * std::sin(4.0 * x[i].x)};
    }
    world.set_state(0, x, v);
    const double e0 = world.energy();
    ASSERT_GT(e0, 0.0);
    double previous = e0;
    for (int i = 0; i < 200; ++i) {
        ASSERT_TRUE(world.step().ok());
        const double e = world.energy();
        ASSERT_LE(e, previous * (1.0 + 1e-9) + 1e-12) << "step " << i;
        previous = e;
    }
    EXPECT_LT(previous, e0);  // implicit Euler dissipates
}

TEST(Integrator, AnimatedPinsLandExactlyOnTheirMotion) {
    WorldDesc desc = settings(1.0 / 60.0);
    World world(desc);
    Motion shoulder;
    shoulder.origin = {0.0, 0.5, 0.0};
    shoulder.linear_velocity = {0.4, 0.0, 0.0};
    shoulder.angular_velocity = {0.0, 1.0, 0.0};
    const int m = world.add_motion(shoulder);
    auto fabric = Fabric::cook(make_grid(0.6, 1.0, 6, 10));
    ClothDesc cape{.name = "cape", .fabric = fabric};
    for (std::uint32_t i = 0; i <= 6; ++i) cape.pins.push_back({std::uint32_t(10 * 7) + i, m});
    world.add_cloth(cape);
    const auto x0 = world.positions(0);
    for (int i = 0; i < 30; ++i) ASSERT_TRUE(world.step().ok());
    const auto x = world.positions(0);
    const Transform start = shoulder.at(0.0), now = shoulder.at(world.time());
    for (std::uint32_t i = 0; i <= 6; ++i) {
        const std::uint32_t v = 70 + i;
        const Vec3d local = physics::transpose(start.rotation) * (x0[v] - start.translation);
        const Vec3d expected = now.apply(local);
        EXPECT_NEAR(physics::length(x[v] - expected), 0.0, 1e-9);
    }
}

TEST(Integrator, ClothRestsOnAFloorAndASphereWithoutPassingThrough) {
    WorldDesc desc = settings(1.0 / 60.0);
    desc.solver.cg_tolerance = 1e-5;
    World world(desc);
    auto fabric = Fabric::cook(make_grid(1.2, 1.2, 16, 16, GridPlane::XZ));
    ClothDesc cloth{.name = "drape", .fabric = fabric};
    cloth.transform.translation = {0.0, 0.8, 0.0};
    world.add_cloth(cloth);
    ColliderDesc floor{.name = "floor", .shape = ColliderShape::Plane};
    world.add_collider(floor);
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.motion.origin = {0.0, 0.3, 0.0};
    ball.radius = 0.3;
    world.add_collider(ball);
    int contacts = 0;
    for (int i = 0; i < 150; ++i) {
        const StepStats& s = world.step();
        ASSERT_FALSE(s.non_finite);
        contacts = s.collider_contacts;
    }
    EXPECT_GT(contacts, 10);
    const double thickness = cloth.material.contact_thickness;
    for (const Vec3d& p : world.positions(0)) {
        EXPECT_GT(p.y, -0.5 * thickness);
        EXPECT_GT(physics::length(p - ball.motion.origin), ball.radius - 0.5 * thickness);
    }
    // The centre rests on the top of the ball.
    const auto x = world.positions(0);
    EXPECT_NEAR(x[std::size_t(8 * 17 + 8)].y, 0.6 + thickness, 2.0 * thickness);
}

TEST(Integrator, WindPushesAPinnedFlagDownwind) {
    WorldDesc desc = settings(1.0 / 60.0);
    desc.wind.velocity = {6.0, 0.0, 2.0};
    desc.solver.cg_tolerance = 1e-5;
    World world(desc);
    auto fabric = Fabric::cook(make_grid(1.0, 0.6, 10, 6));
    ClothDesc flag{.name = "flag", .fabric = fabric};
    for (std::uint32_t j = 0; j <= 6; ++j) flag.pins.push_back({j * 11, -1});
    world.add_cloth(flag);
    for (int i = 0; i < 120; ++i) ASSERT_TRUE(world.step().ok());
    const auto x = world.positions(0);
    double mean_z = 0.0;
    for (const Vec3d& p : x) mean_z += p.z;
    mean_z /= double(x.size());
    // The flag swings out of its plane in the wind's direction (+z), which it cannot do without wind.
    EXPECT_GT(mean_z, 0.05);
}

TEST(Integrator, MoreNewtonIterationsReduceTheErrorAgainstAFineReference) {
    // A stiff swinging sheet at a large step: compare 1 and 4 Newton iterations against a reference
    // with 16 substeps of the same frame. More iterations solve implicit Euler's non-linear system
    // more exactly, which must not move the result further from the reference.
    auto run = [](int newton, int substeps) {
        WorldDesc desc = settings(1.0 / 30.0);
        desc.solver.newton_iterations = newton;
        desc.solver.substeps = substeps;
        World world(desc);
        auto fabric = Fabric::cook(make_grid(0.6, 0.6, 8, 8));
        ClothDesc c{.name = "s", .fabric = fabric};
        c.material.stretch_stiffness = 1e4;
        c.pins = {{72, -1}};
        world.add_cloth(c);
        for (int i = 0; i < 10; ++i) world.step();
        return world.positions(0);
    };
    const auto reference = run(4, 16);
    const auto one = run(1, 1), four = run(4, 1);
    double e1 = 0, e4 = 0;
    for (std::size_t i = 0; i < reference.size(); ++i) {
        e1 += physics::length(one[i] - reference[i]);
        e4 += physics::length(four[i] - reference[i]);
    }
    EXPECT_LE(e4, e1 * 1.05);
}

}  // namespace
}  // namespace weft
