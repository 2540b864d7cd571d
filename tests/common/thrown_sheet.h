#pragma once
// A sheet thrown down at `thrown` m/s under the strongest gravity the parameters allow (1000 m/s²)
// and the longest step (0.1 s): one step adds 100 m/s, so a throw just under kRunawaySpeed passes
// it within the substep. The runaway guard's tests on both backends (RunawayGuard, CudaBackend).
#include <algorithm>
#include <string>
#include <vector>

#include "weft/mesh.h"
#include "weft/world.h"

namespace weft::test {

struct ThrownSheetStep {
    StepStats stats;
    std::vector<Vec3d> before, after;  // positions (m)
    double fastest = 0.0;              // the fastest vertex after the step, m/s
    double dt = 0.0;                   // s
};

inline ThrownSheetStep step_thrown_sheet(const std::string& backend, double thrown) {
    WorldDesc desc;
    desc.solver.dt = 0.1;
    desc.gravity = {0.0, -1000.0, 0.0};
    World world(desc, backend);
    world.add_cloth({.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 4, 4))});
    ThrownSheetStep out;
    out.dt = desc.solver.dt;
    out.before = world.positions(0);
    world.set_state(0, out.before, std::vector<Vec3d>(out.before.size(), Vec3d{0.0, -thrown, 0.0}));
    out.stats = world.step();
    out.after = world.positions(0);
    for (const Vec3d& v : world.velocities(0)) out.fastest = std::max(out.fastest, math::length(v));
    return out;
}

}  // namespace weft::test
