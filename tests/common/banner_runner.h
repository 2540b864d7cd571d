#pragma once
// A body running through a banner at 5 m/s, one step a 60 Hz frame (the game preset): a head box over
// a torso box, a mesh collider bobbing on a straight run, and a banner pinned along its top, hanging
// to head height across the way (the cape_runner's banner at its coarsest). Over one long step the
// solve moves the banner's light vertices through the head and the collision stages put them back in
// front, so the head drags the banner along and tears it open (docs/results.md, "Splitting the
// substeps that tear"); SolverSettings::split_stretch is what keeps it whole.
#include <algorithm>
#include <memory>

#include "box_mesh.h"
#include "weft/mesh.h"
#include "weft/presets.h"
#include "weft/world.h"

namespace weft::test {

/// The world, `split_stretch` set over the game preset (0: no splitting).
inline std::unique_ptr<World> banner_runner(double split_stretch, const char* backend = "cpu") {
    WorldDesc desc;
    apply_solver_preset(desc, "game");
    desc.solver.split_stretch = split_stretch;
    desc.collision.self_collision = true;
    desc.collision.check = true;
    auto world = std::make_unique<World>(desc, backend);

    Motion run;
    run.origin = {0.0, 0.0, 8.0};
    run.linear_velocity = {0.0, 0.0, 5.0};  // m/s: reaches the banner after 0.2 s
    run.amplitude = {0.0, 0.05, 0.0};       // a runner's bob
    run.frequency = 2.5;
    auto body = std::make_shared<MeshData>();
    body->source = "banner_runner body";
    add_box(*body, {-0.1, 1.595, -0.11}, {0.1, 1.845, 0.11});  // the head
    add_box(*body, {-0.2, 0.95, -0.125}, {0.2, 1.55, 0.125});  // the torso
    ColliderDesc runner{.name = "runner", .shape = ColliderShape::Mesh};
    runner.mesh = body;
    runner.motion = run;
    runner.friction = 0.1;
    world->add_collider(runner);

    constexpr int kCellsX = 18, kCellsY = 9;
    ClothDesc banner{.name = "banner", .fabric = Fabric::cook(make_grid(1.9, 0.9, kCellsX, kCellsY), {.density = 0.15})};
    banner.material.stretch_stiffness = 2e4;  // N/m
    banner.transform.translation = {0.0, 1.8, 9.0};  // hangs from 2.25 m to 1.35 m
    for (int i = 0; i <= kCellsX; ++i) banner.pins.push_back({.vertex = static_cast<std::uint32_t>(kCellsY * (kCellsX + 1) + i)});
    world->add_cloth(banner);
    return world;
}

/// What a run of `frames` steps did: the largest stretch of any frame, the substeps redone as halves
/// and the pieces taken, the frames the exact check found intersecting, and the failed steps (a NaN,
/// a dropped solve or a substep the collision stages left unresolved).
struct BannerRun {
    double max_stretch = 0.0;
    int split_substeps = 0, substeps = 0, intersecting_frames = 0, failed = 0;
};

inline BannerRun run_frames(World& world, int frames) {
    BannerRun r;
    for (int f = 0; f < frames; ++f) {
        const StepStats& s = world.step();
        r.max_stretch = std::max(r.max_stretch, s.max_stretch);
        r.split_substeps += s.split_substeps;
        r.substeps += s.substeps;
        if (s.collision.remaining_intersections > 0) ++r.intersecting_frames;
        if (s.non_finite || s.runaway_solves > 0 || s.collision.unresolved_substeps > 0) ++r.failed;
    }
    return r;
}

/// Frames of the run through the banner and 1.5 m past it.
inline constexpr int kBannerFrames = 60;

}  // namespace weft::test
