#pragma once
// The stability matrix (issue 22): a sheet pinned at two corners in a gusty wind, with a ball that
// may fly through it, over the extremes of stretch stiffness, bending, density, time step, collider
// speed, mesh quality and resolution, one at a time from a nominal point and at the corners of the
// material and step ranges. Every cell must run stably or be refused up front with a message. The
// test (tests/solver/test_stability.cpp) runs the one-at-a-time extremes on the CPU; the benchmark
// (bench/stability_matrix_bench.cpp) runs them all on any backend and prints the table.
//
// A run's outcome, checked after every step:
//   refused     building or stepping threw weft::Error (the message names the limit);
//   non-finite  a NaN or an infinity in the state (the step reports it and rolls back);
//   energy      a substep gained energy beyond the external work, even after the energy guard's redo
//               (solver.energy_guard = "retry": more Newton iterations and a tighter CG);
//   unbounded   a vertex beyond the reach of the pins and the wind, or kinetic energy beyond what
//               gravity, the wind and the ball can have put in;
//   penetrated  a vertex deeper inside the ball than a tenth of its radius (it went through);
//   stable      none of these.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft::test {

struct StabilityCase {
    std::string name;
    double stretch = 5e3;         ///< N/m
    double bending = 1e-5;        ///< N·m
    double density = 0.2;         ///< kg/m²
    double dt = 1.0 / 60.0;       ///< s, one substep a frame
    double ball_speed = 0.0;      ///< m/s, straight through the sheet (0: the ball rests beside it)
    double size = 1.0;            ///< m, the square sheet's side (the width along x for `slivers`)
    int cells = 10;               ///< cells along each side
    bool slivers = false;         ///< cells 1 : 40 (cells × 1 cells)
};

enum class StabilityOutcome { Stable, Refused, NonFinite, EnergyGained, Unbounded, Penetrated };

inline const char* outcome_name(StabilityOutcome o) {
    switch (o) {
    case StabilityOutcome::Stable: return "stable";
    case StabilityOutcome::Refused: return "refused";
    case StabilityOutcome::NonFinite: return "non-finite";
    case StabilityOutcome::EnergyGained: return "energy";
    case StabilityOutcome::Unbounded: return "unbounded";
    case StabilityOutcome::Penetrated: return "penetrated";
    }
    return "?";
}

struct StabilityResult {
    StabilityOutcome outcome = StabilityOutcome::Stable;
    std::string detail;  ///< the refusal's message, or where it failed
    int steps = 0;
    int energy_gained = 0;    ///< substeps the energy guard flagged
    double energy_gain = 0.0; ///< J, what they gained beyond the external work, summed
    int cg_capped = 0;        ///< solves that stopped at the iteration cap
    double deepest = 0.0;     ///< the deepest a vertex got inside the ball, m (0: never inside)
    double seconds = 0.0;     ///< wall time
};

/// The one-at-a-time extremes (and, with `corners`, the 16 corners of stretch × bending × density ×
/// step at both ends of their ranges, and the mesh and resolution variants).
inline std::vector<StabilityCase> stability_cases(bool all) {
    std::vector<StabilityCase> out;
    const auto add = [&](std::string name, auto&& edit) {
        StabilityCase c;
        c.name = std::move(name);
        edit(c);
        out.push_back(c);
    };
    add("nominal", [](StabilityCase&) {});
    for (const double k : {1e1, 1e7}) add("stretch " + std::to_string(static_cast<long long>(k)), [&](StabilityCase& c) { c.stretch = k; });
    for (const double b : {1e-8, 1e-2}) add(b < 1e-5 ? "bending 1e-8" : "bending 1e-2", [&](StabilityCase& c) { c.bending = b; });
    for (const double d : {0.01, 2.0}) add(d < 0.1 ? "density 0.01" : "density 2", [&](StabilityCase& c) { c.density = d; });
    for (const double dt : {1.0 / 10000, 1.0 / 24}) add(dt < 1e-3 ? "dt 1/10000" : "dt 1/24", [&](StabilityCase& c) { c.dt = dt; });
    for (const double u : {5.0, 50.0}) add("ball " + std::to_string(static_cast<int>(u)) + " m/s", [&](StabilityCase& c) { c.ball_speed = u; });
    add("slivers 1:40", [](StabilityCase& c) { c.slivers = true; c.cells = 40; });
    add("cells 2.5 mm", [](StabilityCase& c) { c.size = 0.1; c.cells = 40; });
    add("cells 1 m", [](StabilityCase& c) { c.size = 10.0; c.cells = 10; });
    if (!all) return out;
    for (const double k : {1e2, 1e4, 1e6}) add("stretch " + std::to_string(static_cast<long long>(k)), [&](StabilityCase& c) { c.stretch = k; });
    for (const double b : {1e-6, 1e-4}) add(b < 1e-5 ? "bending 1e-6" : "bending 1e-4", [&](StabilityCase& c) { c.bending = b; });
    for (const double d : {0.05, 0.5}) add(d < 0.1 ? "density 0.05" : "density 0.5", [&](StabilityCase& c) { c.density = d; });
    for (const double dt : {1.0 / 1000, 1.0 / 240}) add(dt < 2e-3 ? "dt 1/1000" : "dt 1/240", [&](StabilityCase& c) { c.dt = dt; });
    for (const double u : {1.0, 20.0}) add("ball " + std::to_string(static_cast<int>(u)) + " m/s", [&](StabilityCase& c) { c.ball_speed = u; });
    for (const int n : {5, 20, 40}) add("resolution " + std::to_string(n) + "²", [&](StabilityCase& c) { c.cells = n; });
    for (int corner = 0; corner < 16; ++corner)
        add(std::string("corner ") + ((corner & 1) ? "stiff" : "soft") + ((corner & 2) ? " rigid-bending" : " no-bending") +
                ((corner & 4) ? " heavy" : " light") + ((corner & 8) ? " dt 1/24" : " dt 1/10000"),
            [&](StabilityCase& c) {
                c.stretch = (corner & 1) ? 1e7 : 1e1;
                c.bending = (corner & 2) ? 1e-2 : 1e-8;
                c.density = (corner & 4) ? 2.0 : 0.01;
                c.dt = (corner & 8) ? 1.0 / 24 : 1.0 / 10000;
            });
    return out;
}

/// Runs `c` for half a second of simulated time (at most `max_steps` steps) on `backend` with the
/// bending model `bending`.
/// `guard` and `line_search`: the energy guard's mode and SolverSettings::line_search (the matrix
/// runs with the redo on, which turns the line search on for its redos).
inline StabilityResult run_stability_case(const StabilityCase& c, const std::string& backend, BendingModel bending,
                                          int max_steps = 300, EnergyGuard guard = EnergyGuard::Retry, bool line_search = false) {
    StabilityResult r;
    const auto start = std::chrono::steady_clock::now();
    const double ball_radius = 0.15 * c.size;
    try {
        WorldDesc desc;
        desc.solver.dt = c.dt;
        desc.solver.cg_tolerance = 1e-4;
        desc.solver.cg_max_iterations = 2000;
        desc.solver.bending = bending;
        desc.solver.energy_guard = guard;  // Retry: the engine's remedy on: a cell is judged by what it ends with
        desc.solver.line_search = line_search;
        desc.wind.velocity = {4.0, 0.0, 2.0};
        desc.wind.turbulence = 2.0;
        auto world = std::make_unique<World>(desc, backend);
        const int nx = c.cells, ny = c.slivers ? 1 : c.cells;
        auto fabric = Fabric::cook(make_grid(c.size, c.size, nx, ny), {.density = c.density});
        ClothDesc cloth{.name = c.name, .fabric = fabric};
        cloth.material.stretch_stiffness = c.stretch;
        cloth.material.bending_stiffness = c.bending;
        // The two top corners.
        cloth.pins = {{static_cast<std::uint32_t>(ny * (nx + 1)), -1}, {static_cast<std::uint32_t>(ny * (nx + 1) + nx), -1}};
        world->add_cloth(cloth);
        ColliderDesc ball{.name = "ball", .shape = ColliderShape::Sphere};
        ball.radius = ball_radius;
        if (c.ball_speed > 0.0) {
            ball.motion.origin = {0.0, -0.2 * c.size, 0.5 * c.size};  // in front of the sheet, flying through it
            ball.motion.linear_velocity = {0.0, 0.0, -c.ball_speed};
        } else {
            ball.motion.origin = {0.0, -0.9 * c.size, 0.2 * c.size};
        }
        world->add_collider(ball);
        const int steps = std::min(max_steps, static_cast<int>(std::ceil(0.5 / c.dt)));
        double mass = 0.0;
        for (const double m : fabric->masses()) mass += m;
        // What the outside can have put in over the run: a free fall of the sheet's size plus two
        // metres, the wind's 4.5 m/s (and its gusts), and the ball's speed (it may carry cloth along).
        const double reach_still = c.size + 0.5 * 9.81 * 0.25 + 2.0;
        const double speed_cap = 10.0 + 9.81 * 0.5 + 2.0 * c.ball_speed;
        for (int i = 0; i < steps; ++i) {
            const StepStats& s = world->step();
            ++r.steps;
            r.energy_gained += s.energy_gained;
            r.energy_gain += s.energy_gain;
            r.cg_capped += s.cg_not_converged;
            if (s.non_finite) {
                r.outcome = StabilityOutcome::NonFinite;
                r.detail = "step " + std::to_string(i);
                break;
            }
            const auto x = world->positions(0);
            const auto v = world->velocities(0);
            double kinetic = 0.0;
            const Vec3d centre = ball.motion.origin + world->time() * ball.motion.linear_velocity;
            for (std::size_t k = 0; k < x.size(); ++k) {
                kinetic += 0.5 * fabric->masses()[k] * math::dot(v[k], v[k]);
                r.deepest = std::max(r.deepest, ball_radius - math::length(x[k] - centre));
                const double reach = reach_still + c.ball_speed * world->time() + ball_radius;
                if (!(math::length(x[k]) < reach)) {
                    r.outcome = StabilityOutcome::Unbounded;
                    r.detail = "step " + std::to_string(i) + ": a vertex " + std::to_string(math::length(x[k])) + " m out";
                }
            }
            if (r.outcome == StabilityOutcome::Stable && !(kinetic < 0.5 * mass * speed_cap * speed_cap)) {
                r.outcome = StabilityOutcome::Unbounded;
                r.detail = "step " + std::to_string(i) + ": kinetic energy " + std::to_string(kinetic) + " J";
            }
            if (r.outcome != StabilityOutcome::Stable) break;
        }
        if (r.outcome == StabilityOutcome::Stable && r.deepest > 0.1 * ball_radius) {
            r.outcome = StabilityOutcome::Penetrated;
            r.detail = "a vertex " + std::to_string(r.deepest) + " m inside the ball";
        }
        if (r.outcome == StabilityOutcome::Stable && r.energy_gained > 0) {
            r.outcome = StabilityOutcome::EnergyGained;
            r.detail = std::to_string(r.energy_gained) + " of " + std::to_string(r.steps) + " substeps, " +
                       std::to_string(r.energy_gain) + " J; " + std::to_string(r.cg_capped) + " solves capped";
        }
    } catch (const Error& e) {
        r.outcome = StabilityOutcome::Refused;
        r.detail = e.what();
    }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
}

}  // namespace weft::test
