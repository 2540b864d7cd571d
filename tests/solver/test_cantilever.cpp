// Cantilever under its own weight against the heavy elastica (tests/common/heavy_elastica.h): a
// strip of length L, width b, areal density ρ and plate bending stiffness D clamped horizontally,
// w = ρ·b·g the weight per length and EI = D·b, so q = w/EI = ρ·g/D.
#include <gtest/gtest.h>

#include <cmath>

#include "heavy_elastica.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

struct ElasticaResult {
    double tip_deflection;
};

ElasticaResult heavy_elastica(double q, double L) { return {test::heavy_elastica_deflection(q, L)}; }

TEST(Elastica, ReducesToTheLinearBeamForSmallLoads) {
    // Sanity of the reference itself: δ → qL⁴/8 as the load vanishes.
    const double q = 1e-3, L = 1.0;
    EXPECT_NEAR(heavy_elastica(q, L).tip_deflection, q * L * L * L * L / 8.0, 1e-6);
}

struct Strip {
    double length = 0.3, width = 0.04, density = 0.2, bending = 2.0e-3;
};

// Simulates the strip to rest and returns the tip deflection and the clamp offset (the second
// column is the effective clamp: the first two columns are pinned to hold the slope).
std::pair<double, double> simulate(const Strip& s, int cells_along) {
    WorldDesc desc;
    desc.solver.dt = 1.0 / 24.0;
    desc.solver.newton_iterations = 3;
    desc.solver.cg_tolerance = 1e-8;
    desc.solver.cg_max_iterations = 5000;
    World world(desc);
    const int cells_across = std::max(2, cells_along / 8);
    auto fabric = Fabric::cook(make_grid(s.length, s.width, cells_along, cells_across, GridPlane::XZ),
                               {.density = s.density});
    ClothDesc c{.name = "strip", .fabric = fabric};
    c.material.stretch_stiffness = 1e6;  // effectively inextensible, as the elastica assumes
    c.material.poisson_ratio = 0.0;      // no anticlastic coupling in a narrow strip
    c.material.bending_stiffness = s.bending;
    c.material.damping_mass = 5.0;
    const int nx = cells_along + 1;
    for (int j = 0; j <= cells_across; ++j)
        for (int i = 0; i < 2; ++i) c.pins.push_back({std::uint32_t(j * nx + i), -1});
    world.add_cloth(c);
    for (int i = 0; i < 400; ++i) world.step();
    const auto x = world.positions(0);
    double tip = 0.0;
    for (int j = 0; j <= cells_across; ++j) tip += x[std::size_t(j * nx + cells_along)].y;
    tip /= cells_across + 1;
    return {-tip, s.length / cells_along};
}

TEST(Cantilever, TipDeflectionConvergesToTheHeavyElastica) {
    Strip s;
    const double q = s.density * 9.81 / s.bending;  // w / EI = ρ·b·g / (D·b)
    std::vector<double> errors;
    for (int cells : {12, 24, 48}) {
        const auto [deflection, dx] = simulate(s, cells);
        const double reference = heavy_elastica(q, s.length - dx).tip_deflection;
        const double rel = std::abs(deflection - reference) / reference;
        RecordProperty("cells_" + std::to_string(cells), std::to_string(deflection) + " vs " + std::to_string(reference));
        std::printf("cantilever %2d cells: tip deflection %.5f m, heavy elastica %.5f m, error %.2f%%\n", cells,
                    deflection, reference, 100.0 * rel);
        errors.push_back(rel);
    }
    // The load is deep in the non-linear regime (δ/L ≈ 0.84; the linear beam would predict
    // qL⁴/8 > L), so agreement with the elastica tests large rotations, not the linear beam.
    EXPECT_GT(heavy_elastica(q, s.length).tip_deflection / s.length, 0.6);
    EXPECT_LT(errors.back(), 0.05);
    EXPECT_LT(errors.back(), errors.front());
}

}  // namespace
}  // namespace weft
