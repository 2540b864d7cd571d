#pragma once
/// @file
/// A spring from one cloth vertex to a point that moves: what an editor's mouse drag (or a game's
/// hand) pulls the cloth with. A parameter of the model, read at every substep like wind: setting,
/// moving or releasing it rebuilds nothing.
#include <cstddef>
#include <cstdint>

#include "weft/types.h"

namespace weft {

/// f = k·(target − x) − c·v on vertex `vertex` of cloth `cloth`, taken implicitly in the solve
/// (Baraff & Witkin 1998 §5 eq. 15, with ∂f/∂x = −k·I and ∂f/∂v = −c·I on the vertex's diagonal
/// block), so a stiff spring on a light vertex stays stable at any time step. A pinned vertex
/// ignores it.
struct VertexGrab {
    std::size_t cloth = 0;
    std::uint32_t vertex = 0;
    Vec3d target{};          ///< m, world
    double stiffness = 0.0;  ///< k, N/m, in [0, 1e9]
    double damping = 0.0;    ///< c, N·s/m, in [0, 1e6]
};

/// A stiffness that holds the whole cloth of mass `cloth_mass` (kg) against gravity within
/// `sag` (m) of the target: k = M·g / sag. What the editor's drag uses (sag 2 cm).
[[nodiscard]] inline double grab_stiffness_for(double cloth_mass, double sag = 0.02) {
    return cloth_mass * 9.81 / (sag > 0.0 ? sag : 0.02);
}

}  // namespace weft
