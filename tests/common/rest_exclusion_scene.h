#pragma once
// The scene of the rest-exclusion tests (CollisionSettings::rest_exclusion), shared by the CPU and
// CUDA tests: a flat sheet at rest, 5 mm edges under an 8 mm contact thickness, so that every vertex
// is within the thickness of faces and edges it shares no vertex with; optionally a second sheet
// 3 mm above it, whose pairs with the first are real contacts whatever the exclusion.
#include <string_view>

#include "weft/mesh.h"
#include "weft/world.h"

namespace weft::test {

/// Proximity contacts of the first step (one substep, no gravity) on `backend`.
inline int rest_exclusion_contacts(std::string_view backend, double rest_exclusion, bool second_sheet) {
    WorldDesc desc;
    desc.gravity = {0.0, 0.0, 0.0};
    desc.solver.dt = 1.0 / 240.0;
    desc.solver.substeps = 1;
    desc.collision.self_collision = true;
    desc.collision.rest_exclusion = rest_exclusion;
    World world(desc, backend);
    const auto fabric = Fabric::cook(make_grid(0.2, 0.2, 40, 40, GridPlane::XZ), {.density = 0.2});
    auto sheet = [&](const char* name, double y) {
        ClothDesc c{.name = name, .fabric = fabric};
        c.transform.translation = {0.0, y, 0.0};
        c.material.contact_thickness = 0.008;
        return c;
    };
    world.add_cloth(sheet("lower", 0.5));
    if (second_sheet) world.add_cloth(sheet("upper", 0.503));
    return world.step().collision.contacts;
}

}  // namespace weft::test
