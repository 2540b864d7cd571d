#pragma once
/// @file
/// In-plane (membrane) elasticity of cloth: constant-strain triangles with the St. Venant–Kirchhoff
/// material, isotropic, in plane stress. Energy, gradient and three Hessian flavours (see
/// `HessianKind`).
///
/// Notation (Sifakis & Barbič, "FEM simulation of 3D deformable solids", SIGGRAPH 2012 course,
/// §3–4; Volino et al. 2009 for the plane-stress StVK membrane):
///   Dm = [X1−X0, X2−X0] expressed in the rest triangle's own orthonormal 2D frame (2×2),
///   Ds = [x1−x0, x2−x0] (3×2), F = Ds·Dm⁻¹ (3×2 deformation gradient),
///   G = ½(FᵀF − I) (2×2 Green strain), ψ(G) = μ G:G + ½λ tr(G)² (J/m²),
///   S = ∂ψ/∂G = 2μG + λ tr(G) I (2nd Piola–Kirchhoff stress, N/m), E = A·ψ.
/// F is linear in the positions: F = Σ_a x_a g_aᵀ, where g_1, g_2 are the rows of Dm⁻¹ and
/// g_0 = −g_1 − g_2. Then ∂E/∂x_a = A·F·S·g_a and
///   ∂²E/∂x_a∂x_b = A·(g_aᵀ S g_b)·I₃  [geometric/stress term]  +  A·Jᵀ(∂²ψ/∂G²)J  [material term].

#include <cmath>

#include "weft/physics/eigen_sym.h"
#include "weft/physics/hessian.h"
#include "weft/math/host_device.h"
#include "weft/physics/scalar.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Lamé parameters of a plane-stress membrane, per unit rest area.
template <typename T>
struct MembraneMaterial {
    T lambda;  ///< first Lamé parameter λ (N/m)
    T mu;      ///< shear modulus μ (N/m)
};

/// Plane-stress Lamé parameters from the stretch stiffness and the Poisson ratio.
/// Plane stress (thin sheet, σ_zz = 0) gives μ = k/(2(1+ν)) and λ = kν/(1−ν²), with k = Young's
/// modulus × thickness (the 3D λ = Eν/((1+ν)(1−2ν)) would be wrong for a sheet: it assumes the
/// thickness cannot change).
/// @param stretch_stiffness k (N/m), > 0.
/// @param poisson ν, in (−1, 1) (ψ is then convex in G: its eigenvalues are 2μ and 2(μ+λ) = k/(1−ν)).
template <typename T>
WEFT_HD inline MembraneMaterial<T> membrane_material(T stretch_stiffness, T poisson) {
    MembraneMaterial<T> m{};
    m.mu = stretch_stiffness / (T(2) * (T(1) + poisson));
    m.lambda = stretch_stiffness * poisson / (T(1) - poisson * poisson);
    return m;
}

/// Relative size below which a triangle counts as degenerate: 2·area ≤ tol·(longest edge)².
/// 1e-8 in double (an aspect ratio of 10⁸), a few dozen ulps in float.
template <typename T>
WEFT_HD constexpr T degenerate_area_tolerance() {
    return max_(T(1e-8), T(64) * ScalarTraits<T>::epsilon);
}

/// Rest data of one triangle: Dm⁻¹ in the triangle's own 2D orthonormal frame
/// (e1 along X1−X0, e2 in the plane towards X2) and the rest area.
/// @param X0,X1,X2 rest positions (m).
/// @param dm_inv   receives Dm⁻¹ (1/m), row-major; all zeros when degenerate.
/// @param area     receives the rest area (m²); 0 when degenerate.
/// @return false when the triangle is degenerate (2·area ≤ `degenerate_area_tolerance`·longest
///         edge²); the element then contributes nothing.
template <typename T>
WEFT_HD inline bool membrane_rest(Vec3<T> X0, Vec3<T> X1, Vec3<T> X2, T dm_inv[2][2], T& area) {
    using std::sqrt;
    dm_inv[0][0] = dm_inv[0][1] = dm_inv[1][0] = dm_inv[1][1] = T(0);
    area = T(0);
    const Vec3<T> e01 = X1 - X0, e02 = X2 - X0, e12 = X2 - X1;
    const Vec3<T> n = cross(e01, e02);
    const T twice_area = length(n);
    const T longest_sq = max_(length_squared(e01), max_(length_squared(e02), length_squared(e12)));
    if (!(twice_area > degenerate_area_tolerance<T>() * longest_sq)) return false;  // also NaN
    const T l01 = length(e01);
    const Vec3<T> t1 = e01 / l01;
    const Vec3<T> t2 = normalized(cross(n, t1));  // in-plane, on the side of X2
    // Dm = [[l01, e02·t1], [0, e02·t2]] is upper triangular with det = 2·area > 0.
    const T a = l01, b = dot(e02, t1), c = dot(e02, t2);
    dm_inv[0][0] = T(1) / a;
    dm_inv[0][1] = -b / (a * c);
    dm_inv[1][1] = T(1) / c;
    area = T(0.5) * twice_area;
    return true;
}

namespace detail {
/// Positive part of a symmetric 2×2 matrix [[a, b], [b, c]] (negative eigenvalue clamped to 0),
/// in closed form: with λ± = m ± r, the projector on the λ+ eigenvector is (S − λ−I)/(2r).
template <typename T>
WEFT_HD inline void clamp_sym2(const T s[2][2], T out[2][2]) {
    using std::sqrt;
    const T m = T(0.5) * (s[0][0] + s[1][1]);
    const T h = T(0.5) * (s[0][0] - s[1][1]);
    const T r = sqrt(h * h + s[0][1] * s[0][1]);
    const T lo = m - r, hi = m + r;
    if (lo >= T(0)) {
        out[0][0] = s[0][0]; out[0][1] = s[0][1]; out[1][0] = s[1][0]; out[1][1] = s[1][1];
    } else if (hi <= T(0)) {
        out[0][0] = out[0][1] = out[1][0] = out[1][1] = T(0);
    } else {  // r > 0 here
        const T k = hi / (T(2) * r);
        out[0][0] = k * (s[0][0] - lo);
        out[0][1] = k * s[0][1];
        out[1][0] = k * s[1][0];
        out[1][1] = k * (s[1][1] - lo);
    }
}
}  // namespace detail

/// Energy, gradient and Hessian of one StVK membrane triangle.
/// @param dm_inv Dm⁻¹ from `membrane_rest` (1/m).
/// @param area   rest area from `membrane_rest` (m²).
/// @param m      Lamé parameters (N/m).
/// @param x      current positions of the three vertices (m).
/// @param grad   if non-null, receives ∂E/∂x_a (N); the elastic force on vertex a is −grad[a].
/// @param hess   if non-null and kind ≠ None, receives hess[a][b] = ∂²E/∂x_a∂x_b (N/m):
///               Exact: the true Hessian (indefinite under compression);
///               Fast: material term + geometric term built from S with its negative principal
///                     stresses clamped to 0 — PSD always, equal to Exact whenever both principal
///                     stresses are ≥ 0 (a taut cloth), cheap (no 9×9 eigensolve);
///               Projected: the exact 9×9 Hessian eigen-clamped to PSD.
/// @return the elastic energy E = A·(μ G:G + ½λ tr(G)²) (J).
template <typename T>
WEFT_HD inline T membrane_evaluate(const T dm_inv[2][2], T area, MembraneMaterial<T> m, const Vec3<T> x[3],
                                   Vec3<T> grad[3], Mat3<T> hess[3][3], HessianKind kind) {
    // g_a = ∂F/∂x_a as a 2-vector (rows of Dm⁻¹, and minus their sum for vertex 0).
    T g[3][2];
    g[1][0] = dm_inv[0][0];
    g[1][1] = dm_inv[0][1];
    g[2][0] = dm_inv[1][0];
    g[2][1] = dm_inv[1][1];
    g[0][0] = -g[1][0] - g[2][0];
    g[0][1] = -g[1][1] - g[2][1];
    // Columns of F from edge vectors (translation invariant to the last bit).
    const Vec3<T> d1 = x[1] - x[0], d2 = x[2] - x[0];
    Vec3<T> f[2];
    for (int j = 0; j < 2; ++j) f[j] = dm_inv[0][j] * d1 + dm_inv[1][j] * d2;
    T G[2][2];
    for (int k = 0; k < 2; ++k)
        for (int l = 0; l < 2; ++l) G[k][l] = T(0.5) * (dot(f[k], f[l]) - (k == l ? T(1) : T(0)));
    const T trG = G[0][0] + G[1][1];
    T S[2][2];
    for (int k = 0; k < 2; ++k)
        for (int l = 0; l < 2; ++l) S[k][l] = T(2) * m.mu * G[k][l] + (k == l ? m.lambda * trG : T(0));
    const T psi = m.mu * (G[0][0] * G[0][0] + T(2) * G[0][1] * G[0][1] + G[1][1] * G[1][1]) +
                  T(0.5) * m.lambda * trG * trG;

    if (grad != nullptr) {
        for (int a = 0; a < 3; ++a) {
            const T sg0 = S[0][0] * g[a][0] + S[0][1] * g[a][1];
            const T sg1 = S[1][0] * g[a][0] + S[1][1] * g[a][1];
            grad[a] = area * (sg0 * f[0] + sg1 * f[1]);  // A·F·S·g_a
        }
    }
    if (hess == nullptr || kind == HessianKind::None) return area * psi;

    // Material term A·Jᵀψ''J, column by column: perturb x_b along axis i, so dF = e_i g_bᵀ and
    // dG = sym(g_b w_iᵀ) with w_i = Fᵀe_i (row i of F); dS = 2μ dG + λ tr(dG) I; the change of
    // ∂E/∂x_a is A·F·dS·g_a. (ψ'' is PSD for ν ∈ (−1, 1), so this term is PSD.)
    for (int b = 0; b < 3; ++b) {
        for (int i = 0; i < 3; ++i) {
            const T w[2] = {f[0][i], f[1][i]};
            T dG[2][2];
            for (int k = 0; k < 2; ++k)
                for (int l = 0; l < 2; ++l) dG[k][l] = T(0.5) * (g[b][k] * w[l] + w[k] * g[b][l]);
            const T trdG = dG[0][0] + dG[1][1];
            T dS[2][2];
            for (int k = 0; k < 2; ++k)
                for (int l = 0; l < 2; ++l) dS[k][l] = T(2) * m.mu * dG[k][l] + (k == l ? m.lambda * trdG : T(0));
            for (int a = 0; a < 3; ++a) {
                const T v0 = dS[0][0] * g[a][0] + dS[0][1] * g[a][1];
                const T v1 = dS[1][0] * g[a][0] + dS[1][1] * g[a][1];
                const Vec3<T> col = area * (v0 * f[0] + v1 * f[1]);
                for (int r = 0; r < 3; ++r) hess[a][b].m[r][i] = col[r];
            }
        }
    }
    // Geometric (initial-stress) term A·(g_aᵀ S g_b)·I₃, i.e. (D S Dᵀ) ⊗ I₃. Under compression S has
    // a negative principal stress and this term makes the Hessian indefinite (buckling); Fast keeps
    // only the tensile part S⁺, which is PSD, so the whole Fast Hessian is PSD.
    T Su[2][2];
    if (kind == HessianKind::Fast) {
        detail::clamp_sym2(S, Su);
    } else {
        for (int k = 0; k < 2; ++k)
            for (int l = 0; l < 2; ++l) Su[k][l] = S[k][l];
    }
    for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
            const T kab = area * (g[a][0] * (Su[0][0] * g[b][0] + Su[0][1] * g[b][1]) +
                                  g[a][1] * (Su[1][0] * g[b][0] + Su[1][1] * g[b][1]));
            for (int r = 0; r < 3; ++r) hess[a][b].m[r][r] += kab;
        }
    }
    if (kind == HessianKind::Projected) project_psd_blocks<3>(hess);
    return area * psi;
}

/// The largest principal stretch of triangle x[0..2] against its rest shape (`dm_inv`, as in
/// membrane_evaluate): the square root of the larger eigenvalue of FᵀF, F = [x1 − x0, x2 − x0]·Dm⁻¹
/// (1 at rest, 1.1 for 10% stretch along some direction). What the stats report as a torn cloth
/// when it reaches tens (StepStats::max_stretch).
/// Its square, the larger eigenvalue of FᵀF (≥ 0): what a maximum over many triangles compares, the
/// square root taken once for the largest (√ is monotone and correctly rounded: the same result).
template <typename T>
WEFT_HD inline T largest_stretch_squared(const T dm_inv[2][2], const Vec3<T> x[3]) {
    const Vec3<T> d1 = x[1] - x[0], d2 = x[2] - x[0];
    const Vec3<T> f0 = dm_inv[0][0] * d1 + dm_inv[1][0] * d2;
    const Vec3<T> f1 = dm_inv[0][1] * d1 + dm_inv[1][1] * d2;
    const T a = dot(f0, f0), b = dot(f0, f1), c = dot(f1, f1);
    const T half_trace = T(0.5) * (a + c), half_difference = T(0.5) * (a - c);
    using std::sqrt;
    const T largest = half_trace + sqrt(half_difference * half_difference + b * b);
    return largest > T(0) ? largest : T(0);
}

template <typename T>
WEFT_HD inline T largest_stretch(const T dm_inv[2][2], const Vec3<T> x[3]) {
    using std::sqrt;
    return sqrt(largest_stretch_squared(dm_inv, x));
}

}  // namespace weft::physics
