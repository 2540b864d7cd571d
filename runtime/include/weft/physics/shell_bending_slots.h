#pragma once
/// @file
/// The bending model per triangle (SolverSettings::bending = Shell; weft/physics/shell_bending.h) in
/// a solver's hinge slots, one copy for the CPU and CUDA backends. A triangle couples up to six
/// vertices (its corners and its neighbours' far corners), the solvers' bending elements four: each
/// triangle's implicit terms are split over the slots of its hinges, so that every hinge's terms are
/// a fixed sum (deterministic on any thread count and on the device).
///
///   pass 1, per triangle (shell_face_terms): the angles' gradients ∇θ_k of its hinges, the scalars
///     g_k = h·∂E/∂θ_k + Σ_l C_kl·q_l   (q_l = Σ_b ∇_bθ_l·(h·β·v_k,b + h²·d_b), C = D·A·M)
///   so that its right-hand side at vertex a is −Σ_k g_k·∇_aθ_k: the elastic terms' −h·∇E −
///   H·(hβv + h²d) with the Gauss–Newton Hessian H = Σ_kl C_kl ∇θ_k ∇θ_lᵀ, exactly (the forces are
///   the model's);
///   pass 2, per hinge (shell_hinge_slots): the hinge's four right-hand sides, each triangle's term at
///     a vertex going to the triangle's first hinge (in edge order) that holds it, and its sixteen
///     blocks.
/// The matrix. H couples the far corners of a triangle's different hinges, for which the pattern has
/// no slot, and dropping those blocks leaves it indefinite (measured: the strip blows up). It is
/// replaced by H' = Σ_k (C_kk + Σ_{l≠k} |C_kl|)·∇θ_k ∇θ_kᵀ, one rank-one term per hinge, which fits
/// the hinge's slots: H' − H = Σ_{k<l} |C_kl|·(∇θ_k ∓ ∇θ_l)(∇θ_k ∓ ∇θ_l)ᵀ ⪰ 0, so the implicit step is
/// at least as stable as with H (a stiffer matrix damps more), at the price of some Newton
/// convergence: on Weft's grids H' is at most 1.7× H along a hinge. (Spreading the dropped blocks'
/// norms onto the vertices' diagonal blocks instead, also PSD, over-damped the cantilever so much that
/// 400 steps were far from rest.)

#include <cstdint>

#include "weft/math/host_device.h"
#include "weft/physics/shell_bending.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Pass 1's output for one triangle.
template <typename T>
struct ShellFaceTerms {
    std::int32_t hinge[3]{-1, -1, -1};  ///< active hinges (−1: none, or degenerate)
    Vec3<T> dtheta[3][4]{};              ///< ∇θ_k over hinge k's vertices, in the hinge's order (1/m)
    T g[3]{};                            ///< see the file comment
    T weight[3]{};                       ///< (h·β + h²)·(C_kk + Σ_{l≠k} |C_kl|): hinge k's rank-one block
};

/// Pass 1 for one triangle: `hinge[k]` its hinge across edge k (−1: none); `x`, `vk`, `d` hinge k's
/// four vertices' linearisation point (m), iterate (m/s) and v_k − w_k (m/s), in the hinge's order
/// (read only where hinge[k] ≥ 0); `rest_angle[k]` its rest angle (rad); `stiffness` D (N·m),
/// `beta` the stiffness damping (s), `h` the substep (s).
/// `reading`: the mid-edge model's (shell_bending_evaluate); its scales enter the couplings too.
template <typename T>
WEFT_HD inline ShellFaceTerms<T> shell_face_terms(T h, T stiffness, T beta, const ShellBendingRest<T>& rest,
                                                  const std::int32_t hinge[3], const Vec3<T> x[3][4], const Vec3<T> vk[3][4],
                                                  const Vec3<T> d[3][4], const T rest_angle[3],
                                                  const ShellReading<T>* reading = nullptr) {
    ShellFaceTerms<T> out;
    bool present[3];
    for (int k = 0; k < 3; ++k) present[k] = hinge[k] >= 0;
    const ShellBendingTerms<T> t = shell_bending_evaluate(stiffness, rest, present, x, rest_angle, reading);
    T q[3]{};
    for (int k = 0; k < 3; ++k) {
        if (!t.active[k]) continue;
        out.hinge[k] = hinge[k];
        for (int a = 0; a < 4; ++a) {
            out.dtheta[k][a] = t.dtheta[k][a];
            q[k] += dot(t.dtheta[k][a], (h * beta) * vk[k][a] + (h * h) * d[k][a]);
        }
    }
    const T coef = h * beta + h * h;
    for (int k = 0; k < 3; ++k) {
        if (!t.active[k]) continue;
        T sum = h * t.force_angle[k], weight = T(0);
        for (int l = 0; l < 3; ++l)
            if (t.active[l]) {
                const T c = reading != nullptr ? reading->scale[k] * reading->scale[l] * shell_bending_coupling(stiffness, rest, k, l)
                                               : shell_bending_coupling(stiffness, rest, k, l);
                sum += c * q[l];
                weight += l == k ? c : (c < T(0) ? -c : c);
            }
        out.g[k] = sum;
        out.weight[k] = coef * weight;
    }
    return out;
}

/// Pass 2 for hinge `self` (its vertices `mine`): adds into rhs[4] and block[16] (row-major, the
/// hinge's vertex order) the terms of triangle `face` (pass 1's output) that fall to it.
/// `face_vertices[k]` are the vertices of the face's hinge k (read where face.hinge[k] ≥ 0).
template <typename T>
WEFT_HD inline void shell_hinge_slots(std::int32_t self, const std::uint32_t mine[4], const ShellFaceTerms<T>& face,
                                      const std::uint32_t face_vertices[3][4], Vec3<T> rhs[4], Mat3<T>* block) {
    int self_k = -1;
    for (int k = 0; k < 3; ++k)
        if (face.hinge[k] == self) self_k = k;
    if (self_k < 0) return;  // not an active hinge of this triangle
    for (int a = 0; a < 4; ++a) {
        // Vertex a's places in the triangle's hinges; its right-hand side falls to the first.
        int where[3];
        int first = -1;
        for (int k = 0; k < 3; ++k) {
            where[k] = -1;
            if (face.hinge[k] >= 0)
                for (int b = 0; b < 4; ++b)
                    if (where[k] < 0 && face_vertices[k][b] == mine[a]) where[k] = b;
            if (first < 0 && where[k] >= 0) first = k;
        }
        if (first == self_k) {
            Vec3<T> f{};
            for (int k = 0; k < 3; ++k)
                if (where[k] >= 0) f -= face.g[k] * face.dtheta[k][where[k]];
            rhs[a] += f;
        }
        for (int b = 0; b < 4; ++b)
            block[4 * a + b] += face.weight[self_k] * Mat3<T>::outer(face.dtheta[self_k][a], face.dtheta[self_k][b]);
    }
}

}  // namespace weft::physics
