#pragma once
/// @file
/// Rayleigh damping (Baraff & Witkin 1998 §5; the classical C = αM + βK of structural dynamics):
/// a mass-proportional part that damps absolute motion and a stiffness-proportional part that
/// damps only deformation rates (it is zero for rigid motion because K annihilates translations
/// and, to first order, rotations). Both are linear in v, so their velocity Jacobian is exact.

#include "weft/math/host_device.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Mass-proportional damping force f = −α·m·v (N).
/// @param alpha mass damping coefficient α (1/s). @param mass vertex mass m (kg). @param v velocity (m/s).
template <typename T>
WEFT_HD constexpr Vec3<T> mass_damping_force(T alpha, T mass, Vec3<T> v) {
    return (-alpha * mass) * v;
}

/// Stiffness-proportional damping of one element with n vertices: f_a = −β Σ_b K_ab v_b (N).
/// @param beta stiffness damping coefficient β (s).
/// @param K    the element's PSD stiffness blocks (N/m), e.g. the Fast or Projected Hessian; an
///             indefinite K would inject energy, so never pass the Exact Hessian here.
/// @param v    vertex velocities (m/s). @param f receives the damping forces (added to nothing: overwritten).
template <int n, typename T>
WEFT_HD inline void stiffness_damping_force(T beta, const Mat3<T> K[n][n], const Vec3<T> v[n], Vec3<T> f[n]) {
    for (int a = 0; a < n; ++a) {
        Vec3<T> s{};
        for (int b = 0; b < n; ++b) s += K[a][b] * v[b];
        f[a] = (-beta) * s;
    }
}

/// Velocity Jacobian of the Rayleigh force between vertices a and b: ∂f_a/∂v_b = −(α m_a δ_ab I + β K_ab) (N·s/m).
/// @param alpha α (1/s); @param mass_a m_a (kg), used only when `same_vertex`;
/// @param beta β (s); @param K_ab the element stiffness block (N/m).
template <typename T>
WEFT_HD constexpr Mat3<T> rayleigh_velocity_jacobian(T alpha, T mass_a, bool same_vertex, T beta, const Mat3<T>& K_ab) {
    Mat3<T> j = (-beta) * K_ab;
    if (same_vertex)
        for (int r = 0; r < 3; ++r) j.m[r][r] -= alpha * mass_a;
    return j;
}

}  // namespace weft::physics
