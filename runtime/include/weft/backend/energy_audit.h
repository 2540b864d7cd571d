#pragma once
/// @file
/// The energy guard's measurement (backend kit; docs/methods.md §1b): the mechanical energy of the
/// world's cloths at one instant and a bound on the power the outside world feeds them then, and the
/// criterion that turns two of them into "this substep gained energy". `Backend::energy_audit`
/// measures; its default reads the state back and calls `host_energy_audit`, and a device backend can
/// compute the same sums where its state lives and return only these few numbers.

#include <span>
#include <vector>

#include "weft/backend/model.h"
#include "weft/types.h"

namespace weft {

/// The world's cloths at time t, as the energy guard sees them. Every field is in J or W.
struct EnergyAudit {
    double kinetic = 0.0;  ///< ½ Σ m v², J
    double gravity = 0.0;  ///< −Σ m g·x, J (its zero is arbitrary: only differences mean anything)
    double elastic = 0.0;  ///< membrane + bending, J
    /// Penalty energy ½k(thickness − d)² of the vertices inside an analytic collider's contact
    /// thickness, J, with k the solver's (the scene's, or 100·m/h²).
    double contact = 0.0;
    /// Upper estimate of the power the outside world puts into the cloths at this instant, W (≥ 0):
    /// wind, pins that follow a motion, moving analytic colliders and the grab spring (see
    /// `host_energy_audit` for each term). Gravity is in `gravity`; damping and friction only take.
    double external_power = 0.0;
    /// Whether `external_power` includes the wind's (a gust evaluation per triangle; the guard asks
    /// for it whenever the world has wind).
    bool with_wind = false;
    /// False when the world holds a source of work the audit cannot bound (a mesh collider that
    /// moves); the guard then skips the substep and counts it in `StepStats::energy_unchecked`.
    bool bounded = true;
    /// The largest principal stretch of any triangle (physics::largest_stretch; 1 at rest): not an
    /// energy, but measured in the same pass over the triangles (StepStats::max_stretch).
    double max_stretch = 0.0;
    /// Kinetic + gravitational + elastic + contact energy, J.
    [[nodiscard]] double total() const { return kinetic + gravity + elastic + contact; }
};

/// The audit of cloths whose positions (m) and velocities (m/s) are `x[c]`, `v[c]` (one vector per
/// cloth of `model`), at time `t` (s) of a world stepped in substeps of `h` (s), evaluated in double
/// on the host; the wind's power only when `with_wind`. The external power is the sum of four upper
/// estimates, each ≥ 0:
///   wind:      Σ_tri max(0, F·w), F the triangle's drag + lift and w the air velocity at its
///              centroid. Exact power F·ū = F·w + F·(ū − w), and F·(ū − w) = −½ρ C_D A |u| (u·n)² ≤ 0;
///   pins:      max(0, Σ_i ∇_i U·v_i) over pinned vertices that follow a moving motion, U the elastic
///              energy: the pin holds the vertex against the elastic force f_i = −∇_i U;
///   colliders: Σ |f_i|·|v_col(x_i)| over vertices touching a moving analytic collider, f_i the
///              penalty + friction force (|F·v_col| ≤ |F| |v_col|);
///   grab:      max(0, f·v) with f = k(target − x) − c v.
[[nodiscard]] EnergyAudit host_energy_audit(const Model& model, std::span<const std::vector<Vec3d>> x,
                                            std::span<const std::vector<Vec3d>> v, double t, double h,
                                            bool with_wind);

/// Relative slack of the criterion: a substep may gain this fraction of the energy in motion and
/// deformation at its start (plus the gravitational energy it converted) without being flagged (see
/// `energy_excess`). Measured on the shipped scenes with converged solves: at most 0.40 (drape, the
/// substep in which the cloth meets the ball: a contact that activates inside the substep is not in
/// its one linearisation, so the penalty spring stores more than the cloth loses); the editor's
/// 'loose' preset on drape gains 43 times it in one substep.
inline constexpr double kEnergyGuardSlack = 0.5;
/// The external work estimate h·max(P₀, P₁) counts this many times: the power changes within the
/// substep (a pin starting to pull from rest has P₀ = 0).
inline constexpr double kEnergyGuardWorkFactor = 2.0;
/// Absolute slack of the criterion, J: below it a gain is rounding.
inline constexpr double kEnergyGuardFloor = 1e-9;

/// The energy a substep of length `h` (s) gained beyond what the outside world can have done,
/// J, from the audits at its start and end; 0 when it gained nothing unexplained:
///
///   excess = ΔE − 2·h·max(P₀, P₁) − ε·(K₀ + U₀ + |ΔG|) − E_floor,
///
/// E = kinetic + gravity + elastic + contact (the potentials of every conservative force), P the
/// external power bound (counted kEnergyGuardWorkFactor = 2 times), K the kinetic energy, U elastic +
/// contact, both at the substep's start, G gravity, ε = kEnergyGuardSlack.
/// Why this bound: implicit Euler solved exactly is dissipative — for a convex potential,
/// E₁ − E₀ = h v₁·f_ext − ½|v₁ − v₀|²_M − (damping) ≤ W_ext — so a converged step gains at most the
/// external work, and the slack covers what one linearisation, a non-convex membrane under
/// compression or bending, and the power's change within the step add. An inexact CG solve is not
/// bound by any of it: its velocity is not the minimiser, and what it gains is the excess.
[[nodiscard]] double energy_excess(const EnergyAudit& start, const EnergyAudit& end, double h);

}  // namespace weft
