#pragma once
/// @file
/// Wind on cloth: per-triangle aerodynamic drag and lift against the air's velocity (the thin-plate
/// model of Keckeisen et al. 2004 / Wilson et al. 2014 "Simulating wind effects on cloth and hair"),
/// and a deterministic turbulent gust field (curl noise, Bridson, Houriham & Nordenstam 2007).
///
/// For a triangle of area A, unit normal n and velocity relative to the air u = mean(v) − w:
///   drag  F_D = −½ρ C_D A |u| (u·n) n                       (pressure normal to the plate),
///   lift  F_L = −½ρ C_L A |u| (u·n) n⊥,  n⊥ = n − (n·û)û    (perpendicular to u).
/// |F_L| = ½ρ C_L A |u|² |cos φ| sin φ with φ the angle between u and n. Both are two-sided: flipping
/// n leaves them unchanged. The lift lies in the plane of u and n, perpendicular to u, on the side the
/// drag pushes (F_L·n has the sign of −u·n): a plate moving through still air with its leading edge
/// raised is lifted up, like a kite or a wing at small angle of attack.

#include <cmath>

#include "weft/physics/eigen_sym.h"
#include "weft/math/host_device.h"
#include "weft/physics/scalar.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Aerodynamic coefficients of the cloth.
template <typename T>
struct AeroCoefficients {
    T air_density;  ///< ρ (kg/m³), 1.2 for air at 20 °C
    T drag;         ///< C_D, dimensionless (≈ 1–2 for a flat plate broadside to the flow)
    T lift;         ///< C_L, dimensionless (≈ 0–1)
};

/// Total aerodynamic force (N) on a plate of area `area` (m²) with unit normal `n`, moving with
/// velocity `u` (m/s) relative to the air (see the file comment). Returns zero for u = 0 or A = 0.
/// @param dfdu if non-null, receives the exact ∂F/∂u (N·s/m, not symmetric in general).
template <typename T>
WEFT_HD inline Vec3<T> aerodynamic_plate_force(Vec3<T> u, Vec3<T> n, T area, AeroCoefficients<T> c, Mat3<T>* dfdu) {
    using std::sqrt;
    const T r = length(u);
    if (dfdu != nullptr) *dfdu = Mat3<T>{};
    if (!(r > T(0)) || !(area > T(0))) return Vec3<T>{};
    const T q = T(0.5) * c.air_density * area;
    const T s = dot(u, n);
    // F = −q(C_D + C_L)·r·s·n + q·C_L·(s²/r)·u   (n⊥ expanded so that F is a polynomial in r, s, u).
    const T kn = q * (c.drag + c.lift);
    const T kl = q * c.lift;
    const Vec3<T> F = (-kn * r * s) * n + (kl * s * s / r) * u;
    if (dfdu != nullptr) {
        // ∂r/∂u = û, ∂s/∂u = n:
        // ∂F/∂u = −kn·n⊗(s û + r n) + kl·((s²/r) I + 2s û⊗n − (s²/r) û⊗û).
        const Vec3<T> uh = u / r;
        Mat3<T> J = (-kn) * (Mat3<T>::outer(n, s * uh + r * n));
        J += kl * (Mat3<T>::diagonal(s * s / r) + Mat3<T>::outer(T(2) * s * uh, n) -
                   Mat3<T>::outer((s * s / r) * uh, uh));
        *dfdu = J;
    }
    return F;
}

/// Exact Jacobian ∂F_total/∂u of the triangle's total aerodynamic force with respect to its relative
/// velocity u = mean(v) − wind (N·s/m). Per vertex, ∂f_a/∂v_b = (1/9)·this (f_a = F/3, u = Σv/3).
template <typename T>
WEFT_HD inline Mat3<T> aerodynamic_force_jacobian(const Vec3<T> x[3], const Vec3<T> v[3], Vec3<T> wind_velocity,
                                                  AeroCoefficients<T> c) {
    const Vec3<T> N = cross(x[1] - x[0], x[2] - x[0]);
    const Vec3<T> u = (v[0] + v[1] + v[2]) / T(3) - wind_velocity;
    Mat3<T> J{};
    aerodynamic_plate_force(u, normalized(N), T(0.5) * length(N), c, &J);
    return J;
}

/// Aerodynamic force on each vertex of a triangle (N): the total drag + lift divided by 3.
/// @param x vertex positions (m). @param v vertex velocities (m/s). @param wind_velocity air velocity (m/s).
/// @param force_per_vertex receives F_total/3 (N).
/// @param damping if non-null, receives D (N·s/m): the symmetric positive semi-definite part of
///        −∂F_total/∂u (symmetrised, negative eigenvalues clamped to 0). The solver adds, for every
///        pair (a, b) of the triangle's vertices, −D/9 to ∂f_a/∂v_b (i.e. +h·D/9 to the system
///        matrix block (a, b)): the dissipative part of the linearised wind force, which makes the
///        implicit step stable without adding energy. Zero when u = 0 or the triangle has no area.
template <typename T>
WEFT_HD inline void aerodynamic_force(const Vec3<T> x[3], const Vec3<T> v[3], Vec3<T> wind_velocity, AeroCoefficients<T> c,
                                      Vec3<T>& force_per_vertex, Mat3<T>* damping) {
    const Vec3<T> N = cross(x[1] - x[0], x[2] - x[0]);
    const Vec3<T> u = (v[0] + v[1] + v[2]) / T(3) - wind_velocity;
    Mat3<T> J{};
    const Vec3<T> F = aerodynamic_plate_force(u, normalized(N), T(0.5) * length(N), c, damping != nullptr ? &J : nullptr);
    force_per_vertex = F / T(3);
    if (damping != nullptr) {
        T d[3][3];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) d[i][j] = T(-0.5) * (J.m[i][j] + J.m[j][i]);
        project_psd<3>(d);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) damping->m[i][j] = d[i][j];
    }
}

namespace detail {
/// 32-bit integer mixer (xor-shift-multiply; constants from Wellons' "hash prospector" search),
/// the same on host and device, with no tables.
WEFT_HD constexpr unsigned mix_u32(unsigned h) {
    h ^= h >> 16;
    h *= 0x7feb352dU;
    h ^= h >> 15;
    h *= 0x846ca68bU;
    h ^= h >> 16;
    return h;
}
/// Pseudo-random value in [−1, 1) at a 4D lattice point, for one channel.
template <typename T>
WEFT_HD constexpr T lattice_value(int i, int j, int k, int l, unsigned channel) {
    unsigned h = mix_u32(static_cast<unsigned>(l) + 0x9e3779b9U * (channel + 1U));
    h = mix_u32(h ^ static_cast<unsigned>(k));
    h = mix_u32(h ^ static_cast<unsigned>(j));
    h = mix_u32(h ^ static_cast<unsigned>(i));
    // Top 24 bits: exact in float and double, so host and device agree bit for bit.
    return static_cast<T>(h >> 8) * T(1.0 / 8388608.0) - T(1);
}
/// The gradients in the first three coordinates of three channels of 4D value noise at p:
/// grad[c][k] = ∂noise_c/∂p_k for channels c = 0, 1, 2. Quintic fade 6f⁵ − 15f⁴ + 10f³ (Perlin
/// 2002) has zero first and second derivatives at the lattice, so each noise is C² in every
/// coordinate, its gradient C¹ and the curl below C¹.
///
/// The channels share their lattice cell, fade weights and the corners' weight products (formed
/// once for the three: they are the same numbers); each channel's corner values come from its own
/// hash chain, shared down the 16 corners' tree (l, then k, j, i): 30 mixes a channel instead of
/// 64. Every channel gets the bits of the corner-by-corner definition, lattice_value in order i
/// fastest, l slowest (WindGust.TheSharedHashTreeGivesTheBitsOfTheDefinition).
template <typename T>
WEFT_HD inline void value_noise4_gradients(const T p[4], T grad[3][3]) {
    using std::floor;
    constexpr int kChannels = 3;
    int cell[4];
    T s[4], ds[4];
    for (int k = 0; k < 4; ++k) {
        const T fl = floor(p[k]);
        cell[k] = static_cast<int>(fl);
        const T f = p[k] - fl;
        s[k] = f * f * f * (f * (f * T(6) - T(15)) + T(10));
        ds[k] = T(30) * f * f * (f - T(1)) * (f - T(1));
    }
    for (int c = 0; c < kChannels; ++c) grad[c][0] = grad[c][1] = grad[c][2] = T(0);
    for (int bl = 0; bl < 2; ++bl) {
        unsigned hl[kChannels];
        for (int c = 0; c < kChannels; ++c)
            hl[c] = mix_u32(static_cast<unsigned>(cell[3] + bl) + 0x9e3779b9U * (static_cast<unsigned>(c) + 1U));
        const T wl = bl != 0 ? s[3] : T(1) - s[3];
        for (int bk = 0; bk < 2; ++bk) {
            unsigned hk[kChannels];
            for (int c = 0; c < kChannels; ++c) hk[c] = mix_u32(hl[c] ^ static_cast<unsigned>(cell[2] + bk));
            const T wk = bk != 0 ? s[2] : T(1) - s[2], dwk = bk != 0 ? ds[2] : -ds[2];
            for (int bj = 0; bj < 2; ++bj) {
                unsigned hj[kChannels];
                for (int c = 0; c < kChannels; ++c) hj[c] = mix_u32(hk[c] ^ static_cast<unsigned>(cell[1] + bj));
                const T wj = bj != 0 ? s[1] : T(1) - s[1], dwj = bj != 0 ? ds[1] : -ds[1];
                for (int bi = 0; bi < 2; ++bi) {
                    const T wi = bi != 0 ? s[0] : T(1) - s[0], dwi = bi != 0 ? ds[0] : -ds[0];
                    const T weight[3] = {dwi * wj * wk * wl, wi * dwj * wk * wl, wi * wj * dwk * wl};
                    for (int c = 0; c < kChannels; ++c) {
                        const unsigned h = mix_u32(hj[c] ^ static_cast<unsigned>(cell[0] + bi));
                        const T val = static_cast<T>(h >> 8) * T(1.0 / 8388608.0) - T(1);  // as lattice_value
                        for (int k = 0; k < 3; ++k) grad[c][k] += val * weight[k];
                    }
                }
            }
        }
    }
}
}  // namespace detail

/// Turbulent gust velocity (m/s) to add to the mean wind: the curl of a 3-channel 4D value-noise
/// potential ψ(p/scale, t·frequency), so the field is divergence-free in space (it looks like
/// incompressible eddies, not sources and sinks), C¹ in space and time, deterministic and identical
/// on host and device (integer hash, no tables). The typical (RMS) speed is about `amplitude`.
/// @param p position (m). @param t time (s). @param amplitude typical gust speed (m/s).
/// @param frequency how fast the pattern changes (1/s). @param scale eddy size (m); ≤ 0 gives no gust.
/// Valid while |p|/scale and |t|·frequency stay below 2³¹ (lattice indices are int).
template <typename T>
WEFT_HD inline Vec3<T> wind_gust(Vec3<T> p, T t, T amplitude, T frequency, T scale) {
    if (!(scale > T(0))) return Vec3<T>{};  // no eddy size: no turbulence (and no division by zero)
    const T q[4] = {p.x / scale, p.y / scale, p.z / scale, t * frequency};
    T d[3][3];
    detail::value_noise4_gradients(q, d);
    // curl ψ in noise coordinates. Its RMS over space–time is 1.66 (10⁵ random samples; peaks
    // reach ≈ 5.4), so 0.6 makes the RMS gust speed ≈ amplitude (checked in aerodynamics_test.cpp).
    const Vec3<T> curl{d[2][1] - d[1][2], d[0][2] - d[2][0], d[1][0] - d[0][1]};
    return (amplitude * T(0.6)) * curl;
}

}  // namespace weft::physics
