#pragma once
/// @file
/// Bending from a shape operator per triangle: the candidate to replace the hinge model of
/// bending.h (issue 22; measured by bench/bending_models_bench.cpp, docs/results.md).
///
/// Each triangle f estimates its shape operator (the second fundamental form in its rest plane) from
/// the dihedral angles of its three edges:
///     S_f = Σ_k θ_k·|e_k|/(2·A_f) · t_k t_kᵀ,
/// with |e_k| the rest length of edge k, t_k its unit normal in the rest plane and A_f the rest area.
/// It is the in-plane gradient of the normal field that interpolates linearly between the edges'
/// midpoints, each edge's normal the mean of its two faces' (a "mid-edge" normal: rotated by θ_k/2
/// from the face's about the edge; to first order in θ). The energy is the plate's,
///     E = ½·D·Σ_f A_f·|S_f − S̄_f|²_F = ½·D·Σ_f A_f·Σ_kl M_kl (θ_k − θ̄_k)(θ_l − θ̄_l),
///     M_kl = c_k c_l (t_k·t_l)²,   c_k = |e_k|/(2·A_f),
/// with D the plate bending stiffness (N·m) and Poisson coupling 0. On Weft's grids the diagonal
/// terms M_kk summed over an edge's two faces are exactly the hinge model's weight |e|²/(A₀+A₁); the
/// cross terms (an edge's angle against the other edges' of the same triangle) are what the hinge
/// model lacks: they make a warped zig-zag of a quad's hinges cost what bending it does, which the
/// hinge model lets through as a soft mode (13–70% too soft a cantilever, depending on the cells'
/// aspect). Measured on the clamped strip: aspect-independent and within 0.5% of the heavy elastica
/// from 12 cells along, at every load.
///
/// A triangle's stencil is its three hinges, up to six vertices (its corners and the far corner of
/// each neighbour); a boundary edge has no hinge and adds nothing. Hinge k of the triangle is the
/// hinge of its edge k (corners k, k+1), in bending.h's hinge order (x0, x1 the edge, x2, x3 the
/// opposite corners).
///
/// Known limit: on grids of right triangles with alternating diagonals, a cylinder bent about the
/// grid's diagonal costs 1.49× the plate energy in this model as in the hinge model (1.0 about the
/// grid's axes): the angles of a linear interpolant are not a function of the curvature along the
/// edge alone on such meshes.

#include "weft/math/host_device.h"
#include "weft/physics/bending.h"
#include "weft/physics/membrane.h"
#include "weft/physics/scalar.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Rest data of one triangle's bending: its rest area (m²) and the coupling M (1/m², symmetric,
/// positive semi-definite: a Gram matrix of the scaled t_k t_kᵀ).
template <typename T>
struct ShellBendingRest {
    T area = T(0);
    T m[3][3]{};
};

/// The rest data of the triangle (X0, X1, X2) (m), edge k running from X_k to X_{k+1}. Returns false
/// (and zero data: the triangle adds nothing) for a degenerate triangle.
template <typename T>
WEFT_HD inline bool shell_bending_rest(Vec3<T> X0, Vec3<T> X1, Vec3<T> X2, ShellBendingRest<T>& out) {
    out = ShellBendingRest<T>{};
    const Vec3<T> p[3] = {X0, X1, X2};
    const Vec3<T> n = cross(X1 - X0, X2 - X0);
    const T twice_area = length(n);
    T longest_sq = T(0);
    for (int k = 0; k < 3; ++k) longest_sq = max_(longest_sq, length_squared(p[(k + 1) % 3] - p[k]));
    if (!(twice_area > degenerate_area_tolerance<T>() * longest_sq)) return false;
    const Vec3<T> unit_normal = (T(1) / twice_area) * n;
    Vec3<T> t[3];
    T c[3];
    for (int k = 0; k < 3; ++k) {
        const Vec3<T> e = p[(k + 1) % 3] - p[k];
        using std::sqrt;
        const T le = sqrt(length_squared(e));
        t[k] = (T(1) / le) * cross(e, unit_normal);
        c[k] = le / twice_area;  // |e_k| / (2·A)
    }
    out.area = T(0.5) * twice_area;
    for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) {
            const T d = dot(t[k], t[l]);
            out.m[k][l] = c[k] * c[l] * d * d;
        }
    return true;
}

/// One triangle's bending at the current positions: the angles of its hinges, their gradients and
/// ∂E/∂θ_k. Hessian blocks (Gauss–Newton, positive semi-definite for the triangle as a whole):
/// ∂²E/∂x_{k,a}∂x_{l,b} ≈ shell_bending_coupling(k, l)·∇_aθ_k ∇_bθ_lᵀ.
template <typename T>
struct ShellBendingTerms {
    T energy = T(0);          ///< J
    T angle[3]{};             ///< θ_k − θ̄_k (wrapped), rad; 0 where the edge has no hinge
    T force_angle[3]{};       ///< ∂E/∂θ_k, J/rad
    Vec3<T> dtheta[3][4]{};   ///< ∇θ_k with respect to hinge k's vertices, 1/m
    bool active[3]{};         ///< hinge k present and not degenerate
};

/// How a triangle reads its hinges' angles: ψ_k = scale_k·(θ_k − θ̄_k) + offset_k (rad). The mid-edge
/// model's (weft/physics/midedge_bending.h: its clamp's scales and its edge normals' turns); the
/// identity reading (scale 1, offset 0) is this file's model.
template <typename T>
struct ShellReading {
    T scale[3]{T(1), T(1), T(1)};
    T offset[3]{};
};

/// Evaluates one triangle. `stiffness` D (N·m); `rest` from shell_bending_rest; `present[k]`: the
/// edge has a hinge; `x[k]` its four positions (m) in hinge order; `rest_angle[k]` its rest angle.
/// The gradient with respect to hinge k's vertex a is force_angle[k]·dtheta[k][a]; vertices that
/// appear in several hinges sum their parts. `reading` (null: the identity): the triangle reads its
/// hinges as ψ, so that E = ½·D·A·ψᵀMψ and ∂E/∂θ_k = scale_k·D·A·(Mψ)_k.
template <typename T>
WEFT_HD inline ShellBendingTerms<T> shell_bending_evaluate(T stiffness, const ShellBendingRest<T>& rest, const bool present[3],
                                                           const Vec3<T> x[3][4], const T rest_angle[3],
                                                           const ShellReading<T>* reading = nullptr) {
    ShellBendingTerms<T> out;
    for (int k = 0; k < 3; ++k) {
        if (!present[k]) continue;
        out.active[k] = dihedral_angle_derivatives(x[k], out.dtheta[k], static_cast<Mat3<T>(*)[4]>(nullptr));
        if (out.active[k]) out.angle[k] = detail::wrap_angle(dihedral_angle(x[k]) - rest_angle[k]);
    }
    const T scale = stiffness * rest.area;
    if (reading != nullptr) {
        T psi[3];
        for (int k = 0; k < 3; ++k) psi[k] = reading->scale[k] * out.angle[k] + reading->offset[k];
        for (int k = 0; k < 3; ++k) {
            T sum = T(0);
            for (int l = 0; l < 3; ++l) sum += rest.m[k][l] * psi[l];
            out.force_angle[k] = reading->scale[k] * scale * sum;
            out.energy += T(0.5) * psi[k] * scale * sum;
        }
        return out;
    }
    for (int k = 0; k < 3; ++k) {
        T sum = T(0);
        for (int l = 0; l < 3; ++l) sum += rest.m[k][l] * out.angle[l];
        out.force_angle[k] = scale * sum;
        out.energy += T(0.5) * out.angle[k] * out.force_angle[k];
    }
    return out;
}

/// The Gauss–Newton coupling D·A·M_kl of hinges k and l of a triangle (N·m/rad², per 1/m² of ∇θ).
template <typename T>
WEFT_HD inline T shell_bending_coupling(T stiffness, const ShellBendingRest<T>& rest, int k, int l) {
    return stiffness * rest.area * rest.m[k][l];
}

}  // namespace weft::physics
