#pragma once
/// @file
/// Offset geometric contact between two cloth primitives (docs/methods.md §7b; Chen, Hsu, Liu,
/// Macklin, Yang & Yuksel 2025): every primitive is thickened by the contact radius r, and a smooth
/// penalty acts on the distance d between the two primitives while d < r, pushing along the direction
/// of the closest points, which is normal to the offset surfaces.
///
/// As for the pair springs (pair_contact.h), a pair is one relative coordinate g = Σ_i w_i x_i over
/// its four vertices with the closest-point weights w (vertex–face: (1, −(1 − u − v), −u, −v);
/// edge–edge: (1 − a, a, −(1 − b), −b)), so vertex i receives w_i·F and the (i, j) Hessian block is
/// w_i·w_j·H. Unlike the pair spring, the distance is |g| itself, not its component along a normal
/// frozen at the start of the substep: the energy follows the primitives as they slide and turn.
/// With w held at the closest points, ∂d/∂g = n = g/|g| (the envelope theorem: moving the closest
/// points along their primitives does not change d to first order).
///
/// The penalty is the cubic
///   E(d) = k (r − d)³ / (3r)   for r/2 ≤ d < r,   0 beyond,
/// whose value, slope and curvature all vanish at d = r (C², so Newton sees no kink where a contact
/// starts), and inside half the radius a logarithmic barrier joined to it with the same value, slope
/// and curvature at τ = r/2:
///   E(d) = E(τ) + E′(τ)·τ·ln(d/τ) + (k/4)(d − τ)²   for d < τ,
/// whose force E′(τ)·τ/d grows without bound as the primitives meet (OGC's split between a quadratic
/// and a log barrier, here joined C²). A bounded force would not do: the displacement bounds keep
/// (1 − 2γ) of a gap per update, so a pair squeezed harder than the penalty can push back closes
/// geometrically, to 10⁻¹⁵ m within a few dozen substeps of the twisted sheet, where the exact check
/// then finds crossings made by rounding. Below d = 10⁻³τ the barrier continues as its own quadratic
/// Taylor expansion, so a crossed pair (d ≤ 0, which the bounds exclude) still gets a finite push.
/// Its Hessian in g is E″·nnᵀ + (E′/d)(I − nnᵀ): the first part is PSD (E″ > 0 everywhere inside);
/// the second is negative semi-definite (E′ ≤ 0: the repulsion weakens as the pair turns) and is
/// dropped, the PSD projection that keeps the implicit system SPD. Friction acts on the relative
/// velocity as for the pair springs.
/// Intersection-freedom does not rest on the penalty: it is the per-vertex displacement bound of §7b.

#include <cmath>

#include "weft/math/host_device.h"
#include "weft/physics/friction.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Parameters of one offset contact.
template <typename T>
struct OffsetContactParams {
    T stiffness;      ///< k, N/m: the penalty's curvature at touching is 2k
    T radius;         ///< r, m: the contact radius (offset of each primitive's pair, summed)
    T friction;       ///< Coulomb coefficient μ (dimensionless)
    T slip_velocity;  ///< friction regularisation ε, m/s (> 0)
};

/// The penalty E(d) and its first two derivatives in d.
template <typename T>
struct OffsetPenalty {
    T energy;     ///< J
    T slope;      ///< E′(d), N (≤ 0)
    T curvature;  ///< E″(d), N/m (≥ 0)
};

/// The barrier starts at this share of the radius (τ = r/2 in the comment above).
inline constexpr double kOffsetBarrierShare = 0.5;
/// Below this share of τ the barrier continues as its quadratic Taylor expansion.
inline constexpr double kOffsetBarrierFloor = 1e-3;

/// E(d) inside the offset (d < r): the cubic down to τ = r/2, the log barrier below; zero outside.
/// Defined for every finite d (a crossed pair, d ≤ 0, keeps being pushed out, harder).
template <typename T>
WEFT_HD inline OffsetPenalty<T> offset_penalty(T d, T k, T r) {
    if (!(d < r) || !(r > T(0))) return {T(0), T(0), T(0)};
    const T tau = T(kOffsetBarrierShare) * r;
    if (d >= tau) {
        const T s = r - d;
        return {k * s * s * s / (T(3) * r), -k * s * s / r, T(2) * k * s / r};
    }
    // The cubic's value, slope and curvature at τ; the barrier −E′(τ)·τ·ln(τ/d) plus c/2·(d − τ)²,
    // c = E″(τ) + E′(τ)/τ (= k/2 for τ = r/2), matches all three there.
    const T s = r - tau;
    const T e_tau = k * s * s * s / (T(3) * r), slope_tau = -k * s * s / r, curvature_tau = T(2) * k * s / r;
    const T c = curvature_tau + slope_tau / tau;
    using std::log;
    const auto barrier = [&](T x) -> OffsetPenalty<T> {
        return {e_tau + slope_tau * tau * log(x / tau) + T(0.5) * c * (x - tau) * (x - tau),
                slope_tau * tau / x + c * (x - tau), -slope_tau * tau / (x * x) + c};
    };
    const T floor = T(kOffsetBarrierFloor) * tau;
    if (d >= floor) return barrier(d);
    const OffsetPenalty<T> b = barrier(floor);
    const T e = d - floor;
    return {b.energy + b.slope * e + T(0.5) * b.curvature * e * e, b.slope + b.curvature * e, b.curvature};
}

/// The contact's force on the relative coordinate and its Jacobians; vertex i of the pair receives
/// w_i·force and the (i, j) block of the stiffness is w_i·w_j·dfdx (the same for dfdv).
template <typename T>
struct OffsetContactForce {
    T distance;      ///< d = |g|, m
    T energy;        ///< E(d), J
    T normal_force;  ///< −E′(d) ≥ 0, N
    Vec3<T> normal;  ///< n = g/|g|: from the second primitive's closest point to the first's
    Vec3<T> force;   ///< normal force plus friction, N
    Mat3<T> dfdx;    ///< −E″·nnᵀ: the PSD-projected Hessian, negated (N/m)
    Mat3<T> dfdv;    ///< ∂force/∂u from friction, N·s/m (symmetric negative semi-definite)
};

/// The offset contact at relative position `g` (m) and relative velocity `u` (m/s). `fallback` is
/// the direction to push along when the closest points coincide (|g| = 0: the caller's separating
/// normal, e.g. the face normal), a unit vector.
template <typename T>
WEFT_HD inline OffsetContactForce<T> offset_contact(Vec3<T> g, Vec3<T> u, Vec3<T> fallback, OffsetContactParams<T> p) {
    OffsetContactForce<T> r{};
    r.distance = length(g);
    r.normal = r.distance > T(0) ? g / r.distance : fallback;
    const OffsetPenalty<T> e = offset_penalty(r.distance, p.stiffness, p.radius);
    r.energy = e.energy;
    r.normal_force = -e.slope;
    r.force = r.normal_force * r.normal;
    r.dfdx = (-e.curvature) * Mat3<T>::outer(r.normal, r.normal);
    r.dfdv = Mat3<T>{};
    if (r.normal_force > T(0))
        add_coulomb_friction(r.normal, u, r.normal_force, p.friction, p.slip_velocity, r.force, &r.dfdv);
    return r;
}

}  // namespace weft::physics
