#pragma once
/// @file
/// Proximity contact between two cloth primitives (vertex–face or edge–edge), or between cloth and
/// a triangle-mesh collider, as a penalty spring with smoothed Coulomb friction in the implicit solve.
///
/// Both pair kinds reduce to one relative coordinate: with the four vertices x_0..x_3 and weights w
///   vertex–face  w = (1, −(1 − u − v), −u, −v)   (vertex minus its closest point on the face)
///   edge–edge    w = (1 − a, a, −(1 − b), −b)     (closest point on e minus closest point on f)
/// the gap vector is g = Σ_i w_i x_i and the gap along the contact normal n is d = n·g. The normal
/// and weights are taken from the closest points at the start of the substep and held fixed over it
/// (Bridson et al. 2002 §7.2 do the same for their repulsions), so the spring energy
///   E = ½ k (δ − n·g)²   (δ the contact thickness)
/// is quadratic in the positions: its force on the relative coordinate is F = k(δ − d)·n, vertex i
/// receives w_i·F, and its Hessian is k·w_i·w_j·nnᵀ — exact, PSD, one 3×3 block per pair that the
/// solver scales by the weights (the "dynamic matrix" of P-Cloth in factored form: 16 blocks per pair
/// never need to be stored). Friction acts on the relative velocity u = Σ_i w_i v_i (friction.h).
///
/// The spring is kept for the whole substep once the pair is found within δ at its start, or
/// predicted within δ at its end (a speculative contact): inside the substep it is two-sided, so a
/// pair separating past δ during one substep is held back at δ for that substep only. Continuous
/// collision detection and impact zones after the solve remain the guarantee against crossing; the
/// springs keep the solver's answer close to collision-free so that they rarely have work to do.

#include "weft/physics/friction.h"
#include "weft/math/host_device.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Parameters of one pair spring.
template <typename T>
struct PairContactParams {
    T stiffness;      ///< k, N/m
    T thickness;      ///< δ, the gap the spring holds, m
    T friction;       ///< Coulomb coefficient μ (dimensionless)
    T slip_velocity;  ///< friction regularisation ε, m/s (> 0)
};

/// The spring's force on the relative coordinate and its Jacobians; vertex i of the pair receives
/// w_i·force and the (i, j) block of the stiffness is w_i·w_j·dfdx (the same for dfdv).
template <typename T>
struct PairContactForce {
    T gap;           ///< d = n·g, m (negative when the primitives have crossed)
    T normal_force;  ///< k(δ − d), N; negative when the two-sided spring holds a separating pair back
    Vec3<T> force;   ///< normal force plus friction, N
    Mat3<T> dfdx;    ///< ∂force/∂g = −k·nnᵀ, N/m (symmetric negative semi-definite)
    Mat3<T> dfdv;    ///< ∂force/∂u from friction, N·s/m (symmetric negative semi-definite)
};

/// The pair spring at relative position `g` (m) and relative velocity `u` (m/s) with the fixed unit
/// normal `n`. Friction uses the compressive part of the normal force only (a spring holding a pair
/// back exerts no friction).
template <typename T>
WEFT_HD inline PairContactForce<T> pair_contact(Vec3<T> n, Vec3<T> g, Vec3<T> u, PairContactParams<T> p) {
    PairContactForce<T> r{};
    r.gap = dot(n, g);
    r.normal_force = p.stiffness * (p.thickness - r.gap);
    r.force = r.normal_force * n;
    r.dfdx = (-p.stiffness) * Mat3<T>::outer(n, n);
    r.dfdv = Mat3<T>{};
    if (r.normal_force > T(0))
        add_coulomb_friction(n, u, r.normal_force, p.friction, p.slip_velocity, r.force, &r.dfdv);
    return r;
}

}  // namespace weft::physics
