#pragma once
/// @file
/// One proximity contact of the solve (a pair spring, weft/physics/pair_contact.h), the layout the
/// CPU narrow phase writes and both backends' solves read (backend kit).

#include <cstdint>

#include "weft/types.h"

namespace weft::collision {

/// A candidate is no contact when the vertices that can move carry less than this of its weights
/// (Σ |w_i| over vertices of inverse mass > 0): its gap lies on pinned or kinematic vertices. The
/// stiffness rule 100·m/h² takes m = 1/Σ w_i²/m_i, so that each movable vertex sees 100·m_i/h², and
/// a gap of d then asks the movable vertices to move d/Σ|w|: with a weight of rounding size (a body
/// vertex against the cloth edge between two pinned corners, the free corner at 5.6e-17) the solve
/// sent that vertex at 1e15 m/s (the cape_runner at detail 2, frame 390: the "runaway solve" of
/// docs/results.md). At 1e-3 no move beyond a thousand times the gap is asked.
inline constexpr double kMinMovableContactWeight = 1e-3;

/// One proximity contact: the gap vector g = Σ_i weight[i]·x[vertex[i]] held along `normal`.
struct ProximityContact {
    std::uint32_t vertex[4]{};  ///< collision vertex ids (cloth vertices first, then kinematic ones)
    double weight[4]{};         ///< vertex–face (1, −(1−u−v), −u, −v); edge–edge (1−a, a, −(1−b), −b)
    Vec3d normal{};             ///< unit, from the second primitive towards the first, at the start
    double gap = 0.0;           ///< n·g at the start, m
    double thickness = 0.0;     ///< gap the spring holds, m
    double stiffness = 0.0;     ///< N/m
    double friction = 0.0;      ///< Coulomb coefficient
    /// Edge–edge (vertex 0–1 one edge, 2–3 the other) rather than vertex–face (vertex 0 against the
    /// triangle 1–2–3): the offset contact recomputes its closest points from this.
    bool edge_edge = false;
};

}  // namespace weft::collision
