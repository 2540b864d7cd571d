#pragma once
// Total energy of a cloth (diagnostics, tests of energy behaviour), evaluated in double.

#include <span>

#include "weft/cloth.h"
#include "weft/settings.h"

namespace weft::cpu {

struct EnergyBreakdown {
    double kinetic = 0.0;    ///< ½ Σ m v², J
    double gravity = 0.0;    ///< −Σ m g·x, J
    double membrane = 0.0;   ///< J
    double bending = 0.0;    ///< J
    [[nodiscard]] double total() const { return kinetic + gravity + membrane + bending; }
};

[[nodiscard]] EnergyBreakdown cloth_energy(const ClothDesc& cloth, const WorldDesc& world, std::span<const Vec3d> x,
                                           std::span<const Vec3d> v);

}  // namespace weft::cpu
