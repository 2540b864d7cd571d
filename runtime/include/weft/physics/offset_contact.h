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
///   E(d) = k (r − d)³ / (3r)   for d < r,   0 beyond,
/// whose value, slope and curvature all vanish at d = r (C², so Newton sees no kink where a contact
/// starts), with force magnitude −E′ = k (r − d)²/r (k·r at touching) and curvature E″ = 2k (r − d)/r.
/// Its Hessian in g is E″·nnᵀ + (E′/d)(I − nnᵀ): the first part is PSD; the second is negative
/// semi-definite (E′ ≤ 0: the repulsion weakens as the pair turns) and is dropped, the PSD projection
/// that keeps the implicit system SPD. Friction acts on the relative velocity as for the pair springs.
/// Intersection-freedom does not rest on the penalty: it is the per-vertex displacement bound of §7b.

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

/// E(d) = k (r − d)³/(3r) inside the offset (d < r), zero outside. Defined for every finite d (a
/// crossed pair, d < 0, keeps being pushed out, harder).
template <typename T>
WEFT_HD inline OffsetPenalty<T> offset_penalty(T d, T k, T r) {
    if (!(d < r) || !(r > T(0))) return {T(0), T(0), T(0)};
    const T s = r - d;
    return {k * s * s * s / (T(3) * r), -k * s * s / r, T(2) * k * s / r};
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
