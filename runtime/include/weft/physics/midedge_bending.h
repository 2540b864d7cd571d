#pragma once
/// @file
/// Bending with mid-edge normals (SolverSettings::bending = MidEdge): the shape operator per triangle
/// of shell_bending.h, with each edge's normal free to turn about the edge instead of sitting at the
/// mean of its two faces' normals (the mid-edge shape operator of Grinspun, Gingold, Reisman & Zorin
/// 2006, "Computing discrete shape operators on general meshes", with the edge normals' turns as
/// unknowns that minimise the energy, as in Weischedel's and Chen et al.'s mid-edge shells).
///
/// Triangle f reads its edge k's angle as
///     ψ_k = a_k·(θ_k − θ̄_k) + 2·s_k·ξ_e,
/// with ξ_e (rad) the turn of edge e's normal away from the mean of its faces' normals, s_k = +1 on
/// the side of the hinge's first triangle (v0, v1, v2) and −1 on the other, so that the two faces'
/// readings still add up to twice the fold; a_k = 1 (below: the clamp). The energy is the shell
/// model's with ψ for θ:
///     E(x, ξ) = ½·D·Σ_f A_f·ψ_fᵀ M'_f ψ_f,          E(x) = min_ξ E(x, ξ).
/// With ξ = 0 it is the shell model. With the ξ that minimise it, a cylinder costs the plate energy
/// bent about any direction of a grid (shell_bending.h's model charges 1.49× about the diagonal),
/// and a clamped strip meshed with its rows at 45° converges to the heavy elastica like one meshed
/// along its axis (docs/results.md, "Bending convergence").
///
/// Edges without ξ:
/// - a boundary edge's normal is free and touches one triangle: it is condensed out of that
///   triangle's coupling once, at rest (M' = M_PP − M_PB·M_BB⁻¹·M_BP over the present edges P and
///   the boundary ones B): no moment across a free edge;
/// - a clamp: an edge of a triangle whose three corners are pinned keeps that triangle's normal, so
///   the pinned triangle reads ψ = 0 and the free one the whole fold, ψ = 2·(θ − θ̄) (a = 0 and 2).
///   Without it the pinned cells' normals would turn and the clamp would hold no slope.
///
/// ξ enters E quadratically with constant coefficients, K_ξξ = Σ_f 4·D·A_f·s s ᵀ∘M'_f, a mass-like
/// matrix over the edges (no differences across neighbours), so Jacobi-preconditioned CG solves it
/// in a few tens of iterations at any resolution. The solver's forces are ∂E/∂x at the minimising ξ
/// (exact: ∂E/∂ξ = 0 there), its matrix the ξ-fixed Gauss–Newton Hessian of shell_bending_slots.h
/// with the scales a_k, which is stiffer than the condensed Hessian: the step stays stable (a stiffer
/// matrix damps more).

#include <cstdint>

#include "weft/math/host_device.h"
#include "weft/physics/shell_bending.h"

namespace weft::physics {

/// Relative residual |K_ξξ·ξ + b| / |b| at which the normals count as relaxed: far below what moves
/// a force's digits that the solver resolves (float CG stops at 1e-3–1e-4 of its residual).
inline constexpr double kMidEdgeTolerance = 1e-8;
/// The most CG iterations of the normals' solve: K_ξξ is mass-like (no differences across
/// neighbours), so its condition number does not grow with resolution; 20–60 iterations on Weft's
/// meshes.
inline constexpr int kMidEdgeMaxIterations = 500;

/// The rest data of a triangle of the mid-edge model: the shell model's (shell_bending_rest) with the
/// normals of the edges that have no hinge (`present[k]` false) condensed out of the coupling.
template <typename T>
WEFT_HD inline ShellBendingRest<T> midedge_condensed_rest(const ShellBendingRest<T>& rest, const bool present[3]) {
    ShellBendingRest<T> out = rest;
    int free_edges[3], n_free = 0;
    for (int k = 0; k < 3; ++k)
        if (!present[k]) free_edges[n_free++] = k;
    if (n_free == 0) return out;
    for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) out.m[k][l] = T(0);
    if (n_free == 3) return out;  // a lone triangle bends freely
    // The inverse of M_BB (1×1 or 2×2; M is positive definite for a triangle that is not degenerate).
    T inv[2][2]{};
    if (n_free == 1) {
        const T d = rest.m[free_edges[0]][free_edges[0]];
        if (!(d > T(0))) return out;
        inv[0][0] = T(1) / d;
    } else {
        const int b0 = free_edges[0], b1 = free_edges[1];
        const T det = rest.m[b0][b0] * rest.m[b1][b1] - rest.m[b0][b1] * rest.m[b1][b0];
        if (!(det > T(0))) return out;
        inv[0][0] = rest.m[b1][b1] / det;
        inv[1][1] = rest.m[b0][b0] / det;
        inv[0][1] = -rest.m[b0][b1] / det;
        inv[1][0] = -rest.m[b1][b0] / det;
    }
    for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) {
            if (!present[k] || !present[l]) continue;
            T schur = rest.m[k][l];
            for (int i = 0; i < n_free; ++i)
                for (int j = 0; j < n_free; ++j) schur -= rest.m[k][free_edges[i]] * inv[i][j] * rest.m[free_edges[j]][l];
            out.m[k][l] = schur;
        }
    return out;
}

/// Which side of hinge (v0, v1, v2, v3) a triangle sees it from: +1 where the triangle's edge k runs
/// from v0 to v1 (the hinge's first triangle), −1 where it runs from v1 to v0.
WEFT_HD inline int midedge_side(std::uint32_t edge_start, std::uint32_t hinge_v0) { return edge_start == hinge_v0 ? 1 : -1; }

/// One triangle of the mid-edge model for the normals' solve: its hinges' angles (θ − θ̄, rad), the
/// clamp's scales a_k, the sides s_k and which edges have a ξ.
template <typename T>
struct MidEdgeFace {
    std::int32_t hinge[3]{-1, -1, -1};  ///< hinge of edge k (−1: boundary)
    T angle[3]{};                       ///< θ_k − θ̄_k, rad
    T scale[3]{T(1), T(1), T(1)};       ///< a_k
    T side[3]{};                        ///< s_k (0 where edge k has no ξ)
};

/// The triangle's reading for shell_bending_evaluate at the normals' turns `xi[k]` (rad) of its edges.
template <typename T>
WEFT_HD inline ShellReading<T> midedge_reading(const MidEdgeFace<T>& f, const T xi[3]) {
    ShellReading<T> r;
    for (int k = 0; k < 3; ++k) {
        r.scale[k] = f.scale[k];
        r.offset[k] = T(2) * f.side[k] * xi[k];
    }
    return r;
}

/// The triangle's part of ∂E/∂ξ for its edge k, per unit D·A (1/m²·rad): 2·s_k·(M'ψ)_k, with ψ from
/// the angles and `xi` (set `with_angles` false for the product K_ξξ·ξ alone).
template <typename T>
WEFT_HD inline T midedge_xi_gradient(const MidEdgeFace<T>& f, const ShellBendingRest<T>& rest, const T xi[3], int k,
                                     bool with_angles) {
    T sum = T(0);
    for (int l = 0; l < 3; ++l) {
        const T psi = (with_angles ? f.scale[l] * f.angle[l] : T(0)) + T(2) * f.side[l] * xi[l];
        sum += rest.m[k][l] * psi;
    }
    return T(2) * f.side[k] * sum;
}

}  // namespace weft::physics
