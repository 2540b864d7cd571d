#pragma once
// A sheet whose pinned corner has been carried `pull` m away (as a character dragging a banner
// vertex along): the cloth next to it is stretched far past anything cloth does. The stretch report's
// tests on both backends (StretchReport, CudaBackend).
#include <string>
#include <vector>

#include "weft/mesh.h"
#include "weft/world.h"

namespace weft::test {

/// One 1/60 s step of a 1 m sheet (8 × 8 cells) pinned at vertex 0, that vertex moved `pull` m
/// along −x first, with the energy guard `guard` (the stretch is measured by its audit).
inline StepStats step_stretched_sheet(const std::string& backend, double pull, EnergyGuard guard) {
    WorldDesc desc;
    desc.solver.energy_guard = guard;
    World world(desc, backend);
    ClothDesc sheet{.name = "sheet", .fabric = Fabric::cook(make_grid(1.0, 1.0, 8, 8))};
    sheet.pins.push_back(PinDesc{.vertex = 0});
    world.add_cloth(sheet);
    std::vector<Vec3d> x = world.positions(0);
    x[0].x -= pull;
    world.set_state(0, x, std::vector<Vec3d>(x.size(), Vec3d{}));
    return world.step();
}

}  // namespace weft::test
