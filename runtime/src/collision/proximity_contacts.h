#pragma once
/// @file
/// Narrow phase for the solve: turns the broad phase's vertex–face and edge–edge candidates into the
/// proximity contacts (pair springs, weft/physics/pair_contact.h) of one substep. A candidate becomes
/// a contact when its primitives are within the contact thickness at the start of the substep, or
/// are predicted to be within it at the end (x0 + h·v0: a speculative contact that lets the implicit
/// solve stop an approach before it crosses). The normal and the weights come from the closest
/// points at the start and are held for the substep.
///
/// This is the reference the GPU narrow phase is checked against; the order of the output is the
/// order of the input pairs (vertex–face first), so the result does not depend on the thread count.

#include <cstdint>
#include <span>
#include <vector>

#include "collision/broad_phase.h"
#include "weft/backend/proximity_contact.h"
#include "weft/types.h"

namespace weft::collision {

/// Everything the narrow phase reads. Spans must stay valid for the call.
struct ProximityInput {
    std::span<const Vec3d> x0;              ///< positions at the start of the substep, m
    std::span<const Vec3d> x1;              ///< predicted positions at its end, m (kinematic: their pose at t + h)
    std::span<const double> inverse_mass;   ///< 1/kg; 0 for pinned and kinematic vertices
    std::span<const double> thickness;      ///< per vertex, m: its cloth's contact thickness (0 for kinematic)
    std::span<const double> friction;       ///< per vertex: Coulomb coefficient of its cloth or collider
    std::span<const Triangle> triangles;
    std::span<const Edge> edges;
    std::span<const VertexFacePair> vf;     ///< broad-phase candidates
    std::span<const EdgeEdgePair> ee;
    /// Rest exclusion (CollisionSettings::rest_exclusion): a pair whose four vertices are vertices of
    /// one cloth (ids below rest.size()) and lie closer than rest_exclusion × thickness in the rest
    /// positions is no contact. Empty `rest` or a factor of 0 excludes nothing.
    std::span<const Vec3d> rest;                 ///< rest positions of the cloth vertices, m
    std::span<const std::uint32_t> vertex_cloth;  ///< owning cloth of each cloth vertex
    double rest_exclusion = 0.0;
    /// Offset contact (CollisionSettings::mode): each vertex's displacement bound, m. Given, a pair is
    /// kept when it can come within the thickness under the bounds, d − (largest bound of the first
    /// primitive + largest of the second) < thickness, d its distance at x0 (x1 is not read).
    std::span<const double> offset_bound;
    double h = 0.0;                         ///< substep, s
    double thickness_override = 0.0;        ///< m; > 0 replaces the per-vertex thickness
    double stiffness_override = 0.0;        ///< N/m; > 0 replaces the 100·m/h² rule
};

/// Appends the contacts of `in` to `out` (cleared first). A pair whose four vertices all have
/// inverse mass 0 is skipped (nothing can move). Stiffness: `stiffness_override`, or 100·m/h² with
/// m = 1/Σ w_i²/m_i the pair's effective mass (the rule the analytic colliders use per vertex, so a
/// resting contact sinks g·h²/100 into the thickness). Thickness: the larger of the two sides'.
/// Friction: the mean of the two sides'. Pairs of rest neighbours are skipped (see `rest`). Throws `weft::Error` on mismatched sizes.
void find_proximity_contacts(const ProximityInput& in, std::vector<ProximityContact>& out);

}  // namespace weft::collision
