#pragma once
/// @file
/// Smoothed Coulomb friction with a lagged normal force, shared by the analytic-collider contacts
/// (collider_contact.h) and the cloth–cloth proximity contacts (pair_contact.h).
///
/// The friction force derives from the dissipation potential Φ(u) = μ f_n √(|u_t|² + ε²) of the
/// tangential slip velocity u_t = (I − nnᵀ)u, with f_n held fixed over the step (lagged, as in IPC,
/// Li et al. 2020 §5): f_t = −∂Φ/∂u = −μ f_n u_t / s with s = √(|u_t|² + ε²). Below the slip
/// velocity ε it acts like viscous damping (static friction, regularised); above it, like Coulomb's
/// μ f_n. Its Jacobian ∂f_t/∂u = −μ f_n (P/s − u_t u_tᵀ/s³), P = I − nnᵀ, is symmetric and negative
/// semi-definite (|u_t|²/s² < 1), so it keeps the implicit system SPD.

#include <cmath>

#include "weft/math/host_device.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Adds the friction force (N) of slip velocity `u` (m/s) against the unit normal `n` to `force` and
/// its velocity Jacobian (N·s/m) to `*dfdu` (when not null). `normal_force` f_n ≥ 0 (N), `mu` the
/// Coulomb coefficient, `slip_velocity` ε > 0 (m/s). Nothing is added when μ f_n = 0.
template <typename T>
WEFT_HD inline void add_coulomb_friction(Vec3<T> n, Vec3<T> u, T normal_force, T mu, T slip_velocity, Vec3<T>& force,
                                         Mat3<T>* dfdu) {
    using std::sqrt;
    const T mf = mu * normal_force;
    if (!(mf > T(0))) return;
    const Vec3<T> ut = u - dot(u, n) * n;
    const T s = sqrt(length_squared(ut) + slip_velocity * slip_velocity);
    if (!(s > T(0))) return;
    force += (-mf / s) * ut;
    if (dfdu != nullptr) {
        const Mat3<T> P = Mat3<T>::identity() - Mat3<T>::outer(n, n);
        *dfdu += (-mf / s) * P + (mf / (s * s * s)) * Mat3<T>::outer(ut, ut);
    }
}

}  // namespace weft::physics
