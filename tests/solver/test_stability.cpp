// Stability at the extremes the issue names: stiffness, bending, density and time step at both ends
// of their ranges (and the nastiest corners together). No NaN, no runaway energy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "stability_matrix.h"
#include "stretched_sheet.h"
#include "thrown_sheet.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

struct Case {
    const char* name;
    double stretch, bending, density, dt;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

class Extremes : public ::testing::TestWithParam<Case> {};

TEST_P(Extremes, StaysFiniteAndBounded) {
    const Case& c = GetParam();
    WorldDesc desc;
    desc.solver.dt = c.dt;
    desc.solver.cg_tolerance = 1e-4;
    desc.solver.cg_max_iterations = 2000;
    desc.wind.velocity = {4.0, 0.0, 2.0};
    World world(desc);
    auto fabric = Fabric::cook(make_grid(1.0, 1.0, 10, 10), {.density = c.density});
    ClothDesc cloth{.name = c.name, .fabric = fabric};
    cloth.material.stretch_stiffness = c.stretch;
    cloth.material.bending_stiffness = c.bending;
    cloth.pins = {{110, -1}, {120, -1}};
    world.add_cloth(cloth);
    ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
    ball.motion.origin = {0.0, -0.9, 0.2};
    ball.radius = 0.3;
    world.add_collider(ball);
    // Simulate a fixed half second (at most 300 steps so the smallest dt stays cheap).
    const int steps = std::min(300, int(std::ceil(0.5 / c.dt)));
    double mass = 0.0;
    for (double m : fabric->masses()) mass += m;
    for (int i = 0; i < steps; ++i) {
        const StepStats& s = world.step();
        ASSERT_FALSE(s.non_finite) << "step " << i;
    }
    for (const Vec3d& p : world.positions(0)) ASSERT_TRUE(math::is_finite(p));
    // Bounded: no vertex further than the sheet's size plus a free fall from its pins, and the
    // kinetic energy no more than the work gravity and a 4.5 m/s wind can do in half a second.
    const double fall = 0.5 * 9.81 * 0.25 + 2.0;
    for (const Vec3d& p : world.positions(0)) ASSERT_LT(math::length(p), fall);
    double kinetic = 0.0;
    const auto v = world.velocities(0);
    for (std::size_t i = 0; i < v.size(); ++i) kinetic += 0.5 * fabric->masses()[i] * math::dot(v[i], v[i]);
    EXPECT_LT(kinetic, mass * (0.5 * 25.0 + 9.81 * 2.0) + 10.0 * mass);
}

INSTANTIATE_TEST_SUITE_P(
    Weft, Extremes,
    ::testing::Values(Case{"soft", 1e1, 1e-5, 0.2, 1.0 / 60}, Case{"stiff", 1e7, 1e-5, 0.2, 1.0 / 60},
                      Case{"no_bending", 5e3, 1e-8, 0.2, 1.0 / 60}, Case{"rigid_bending", 5e3, 1e-2, 0.2, 1.0 / 60},
                      Case{"light", 5e3, 1e-5, 0.01, 1.0 / 60}, Case{"heavy", 5e3, 1e-5, 2.0, 1.0 / 60},
                      Case{"tiny_step", 5e3, 1e-5, 0.2, 1.0 / 10000}, Case{"huge_step", 5e3, 1e-5, 0.2, 1.0 / 24},
                      Case{"stiff_light_huge_step", 1e7, 1e-2, 0.01, 1.0 / 24},
                      Case{"soft_heavy_huge_step", 1e1, 1e-8, 2.0, 1.0 / 24},
                      Case{"stiff_heavy_tiny_step", 1e7, 1e-8, 2.0, 1.0 / 10000},
                      Case{"soft_light_tiny_step", 1e1, 1e-2, 0.01, 1.0 / 10000}),
    [](const ::testing::TestParamInfo<Case>& param_info) { return std::string(param_info.param.name); });

// The small stability matrix (tests/common/stability_matrix.h; the full one is
// bench/stability_matrix_bench.cpp): the one-at-a-time extremes of every dimension, with the three
// bending models, on the CPU backend, with the energy guard's redo on. Every cell must be stable or
// refused with a message, except the known failures listed here (none today: the moving ball and the
// 2.5 mm cells gained energy until the guard's redo took more Newton iterations), which are reported
// when they run, and when they start to pass.
TEST(StabilityMatrix, EveryExtremeIsStableOrRefused) {
    const std::vector<std::string> known_failures{};
    int checked = 0;
    for (const test::StabilityCase& c : test::stability_cases(false))
        for (const BendingModel m : {BendingModel::Hinge, BendingModel::Shell, BendingModel::MidEdge}) {
            const test::StabilityResult r = test::run_stability_case(c, "cpu", m);
            const bool ok = r.outcome == test::StabilityOutcome::Stable || r.outcome == test::StabilityOutcome::Refused;
            const bool known = std::find(known_failures.begin(), known_failures.end(), c.name) != known_failures.end();
            const char* model = m == BendingModel::Hinge ? "hinge" : m == BendingModel::Shell ? "shell" : "midedge";
            if (r.outcome == test::StabilityOutcome::Refused) {
                EXPECT_FALSE(r.detail.empty()) << c.name << ": refused without a message";
            }
            if (known) {
                std::printf("[ known    ] %s, %s bending: %s%s%s\n", c.name.c_str(), model, test::outcome_name(r.outcome),
                            r.detail.empty() ? "" : ": ", ok ? " (passes now: take it off the known failures)" : r.detail.c_str());
                continue;
            }
            ++checked;
            EXPECT_TRUE(ok) << c.name << ", " << model << " bending: " << test::outcome_name(r.outcome) << ": " << r.detail;
        }
    EXPECT_GE(checked, 20);
}

// The stiff (1e7 N/m), light (0.01 kg/m²) sheet at 1/24 s: one Baraff–Witkin step there is so poor a
// model of the energy that plain Newton gains kJ in a substep, even redone with 4× the iterations
// or as quarter substeps. With the line search (SolverSettings::line_search) it gains nothing, and
// the matrix's redo (which turns it on) leaves the corner stable for both bending models.
const test::StabilityCase& stiff_light_long_step() {
    static const test::StabilityCase c = [] {
        for (const test::StabilityCase& k : test::stability_cases(true))
            if (k.name == "corner stiff no-bending light dt 1/24") return k;
        throw Error("the stability matrix lost its stiff light corner");
    }();
    return c;
}

TEST(LineSearch, KeepsPlainNewtonFromGainingEnergyOnAStiffLightSheet) {
    const test::StabilityCase& c = stiff_light_long_step();
    const test::StabilityResult plain = test::run_stability_case(c, "cpu", BendingModel::Hinge, 300, EnergyGuard::Report, false);
    const test::StabilityResult searched = test::run_stability_case(c, "cpu", BendingModel::Hinge, 300, EnergyGuard::Report, true);
    EXPECT_GT(plain.energy_gained, 0) << "plain Newton no longer gains energy here: the test lost its point";
    EXPECT_EQ(searched.energy_gained, 0) << searched.energy_gain << " J gained with the line search";
    EXPECT_EQ(searched.outcome, test::StabilityOutcome::Stable) << searched.detail;
}

TEST(StabilityMatrix, TheStiffLightCornersAtALongStepAreStable) {
    for (const test::StabilityCase& c : test::stability_cases(true)) {
        if (c.name.find("stiff") == std::string::npos || c.name.find("light dt 1/24") == std::string::npos) continue;
        for (const BendingModel m : {BendingModel::Hinge, BendingModel::Shell, BendingModel::MidEdge}) {
            const test::StabilityResult r = test::run_stability_case(c, "cpu", m);
            const char* model = m == BendingModel::Hinge ? ", hinge: " : m == BendingModel::Shell ? ", shell: " : ", midedge: ";
            EXPECT_EQ(r.outcome, test::StabilityOutcome::Stable) << c.name << model << test::outcome_name(r.outcome) << ": " << r.detail;
        }
    }
}

// The soft (10 N/m) heavy (2 kg/m²) sheet at 1/24 s falls onto the resting ball several centimetres a
// step: its contacts begin within a step, where the solve's penalty (at the step's start) does not
// see them, and it used to end 15–57 mm inside. A slow end inside a collider now goes back onto the
// surface (swept_collider.h): no vertex ends a step inside the ball at all.
TEST(StabilityMatrix, TheSoftHeavyCornersAtALongStepStayOutOfTheBall) {
    int cases = 0;
    for (const test::StabilityCase& c : test::stability_cases(true)) {
        if (c.name.find("soft") == std::string::npos || c.name.find("heavy dt 1/24") == std::string::npos) continue;
        for (const BendingModel m : {BendingModel::Hinge, BendingModel::Shell, BendingModel::MidEdge}) {
            const test::StabilityResult r = test::run_stability_case(c, "cpu", m);
            ++cases;
            const char* model = m == BendingModel::Hinge ? ", hinge: " : m == BendingModel::Shell ? ", shell: " : ", midedge: ";
            EXPECT_EQ(r.outcome, test::StabilityOutcome::Stable) << c.name << model << test::outcome_name(r.outcome) << ": " << r.detail;
            EXPECT_LT(r.deepest, 1e-4) << c.name << model << r.deepest << " m inside the ball";
        }
    }
    EXPECT_EQ(cases, 6) << "the soft heavy corners at 1/24 s (two, with three bending models) were not found in the matrix";
}

// A solve that gives cloth a speed no cloth reaches (cpu::kRunawaySpeed, 10 km/s: what a system
// singular in float does, |Δv| ~10¹⁵ m/s) is dropped and reported, never committed: the cloth
// drifts on at its start velocity through the substep. Driven here by the state itself: a sheet thrown down at just under the limit, under the
// strongest gravity the parameters allow and the longest step, passes it within one substep.
TEST(RunawayGuard, ASolveFasterThanAnyClothIsDroppedAndReported) {
    for (const double thrown : {9'000.0, 9'990.0}) {
        SCOPED_TRACE("thrown at " + std::to_string(thrown) + " m/s");
        const test::ThrownSheetStep r = test::step_thrown_sheet("cpu", thrown);
        if (thrown < 9'500.0) {  // 9,000 + 100 m/s: under the limit, an ordinary step
            EXPECT_EQ(r.stats.runaway_solves, 0);
            EXPECT_GT(r.fastest, thrown);
            EXPECT_TRUE(r.stats.ok());
        } else {  // 9,990 + 100 m/s: over it
            EXPECT_GT(r.stats.runaway_solves, 0);
            EXPECT_FALSE(r.stats.ok());
            EXPECT_FALSE(r.stats.non_finite);  // a runaway, not a NaN
            EXPECT_LE(r.fastest, thrown * (1.0 + 1e-6));  // the solve's speed never committed
            for (std::size_t i = 0; i < r.before.size(); ++i)  // drifted one step at the start velocity
                EXPECT_NEAR(r.after[i].y, r.before[i].y - thrown * r.dt, 1e-6 * thrown) << "vertex " << i;
        }
    }
}

// A cloth torn open or dragged along by something it should slide off (the cape_runner's banner
// held to the runner) breaks no other check: the stats report its largest principal stretch,
// measured by the energy guard's audit at the end of the step.
TEST(StretchReport, ADraggedCornerIsReportedAndARestingSheetIsNot) {
    const StepStats resting = test::step_stretched_sheet("cpu", 0.0, EnergyGuard::Report);
    EXPECT_GT(resting.max_stretch, 0.99);
    EXPECT_LT(resting.max_stretch, 1.05);
    const StepStats dragged = test::step_stretched_sheet("cpu", 5.0, EnergyGuard::Report);
    EXPECT_GE(dragged.max_stretch, kOverstretch) << "a corner 5 m from a 12.5 cm cell";
    // Without the guard nothing is audited: 0, "not measured".
    EXPECT_EQ(test::step_stretched_sheet("cpu", 5.0, EnergyGuard::Off).max_stretch, 0.0);
}

}  // namespace
}  // namespace weft
