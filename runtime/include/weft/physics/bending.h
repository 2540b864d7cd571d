#pragma once
/// @file
/// Discrete hinge bending of cloth (Grinspun, Hirani, Desbrun & Schröder 2003, "Discrete shells";
/// derivatives after Tamstorf & Grinspun 2013, "Discrete bending forces and their Jacobians").
///
/// A hinge is the pair of triangles that share an interior edge. Vertex order everywhere:
///   x0, x1  the shared edge,
///   x2      the vertex opposite the edge in triangle (x0, x1, x2),
///   x3      the vertex opposite the edge in triangle (x1, x0, x3).
/// Both triangles are then consistently oriented, with (unnormalised) normals
///   N1 = (x1−x0)×(x2−x0),  N2 = (x0−x1)×(x3−x1),
/// which agree when the hinge is flat.
///
/// Sign convention of the dihedral angle θ: 0 when flat, and θ > 0 when the hinge folds towards its
/// normals (the wings x2 and x3 rise to the side that N1 and N2 point to: the surface is concave
/// seen from +N). θ ∈ (−π, π].

#include <cmath>

#include "weft/physics/eigen_sym.h"
#include "weft/physics/hessian.h"
#include "weft/math/host_device.h"
#include "weft/physics/membrane.h"
#include "weft/physics/scalar.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Signed dihedral angle of a hinge (radians, in (−π, π], 0 when flat; sign convention in the
/// file comment). Returns 0 when the edge has zero length or a triangle is degenerate (atan2(0,0)).
/// @param x hinge positions (m), in the order x0, x1 (edge), x2, x3 (opposite vertices).
template <typename T>
WEFT_HD inline T dihedral_angle(const Vec3<T> x[4]) {
    using std::atan2;
    const Vec3<T> e = x[1] - x[0];
    const Vec3<T> n1 = cross(e, x[2] - x[0]);
    const Vec3<T> n2 = cross(x[0] - x[1], x[3] - x[1]);
    const T le = length(e);
    if (!(le > T(0))) return T(0);
    // atan2(|N1||N2| sin θ, |N1||N2| cos θ): robust at every angle, unlike acos of the dot product.
    const T s = dot(cross(n2, n1), e) / le;
    const T c = dot(n1, n2);
    return atan2(s, c);
}

/// Calibrated hinge weight from rest positions: w = |e|²/(A0 + A1) (dimensionless), with |e| the
/// rest length of the shared edge and A0, A1 the rest areas of the two triangles.
///
/// Why not Grinspun's 3|e|²/(A0+A1)? The discrete-shells weight |e|/h̄ (h̄ = a third of the mean
/// height of the two triangles) makes Σ w θ² approximate ∫(2H)² only up to a mesh-dependent
/// constant. On Weft's grids (square cells split along alternating diagonals, `make_grid`) bent into
/// a cylinder of curvature κ about either grid axis, the edges along the axis carry θ = κ·a (a =
/// cell size) and every other hinge stays flat, so Σ 3|e|²/(A0+A1)·θ² = 3·κ²·Area: three times the
/// plate energy ½Dκ²·Area. Dropping the factor 3 makes D the physical plate bending stiffness (N·m)
/// on these meshes. Measured (tests/physics/bending_test.cpp, 40×40 cells): Σ E / (½Dκ²·Area) =
/// 0.975 bending about either grid axis (the missing 1/n is the boundary row of cells, which has no
/// outer hinge), and 1.49 about the 45° diagonal (the hinge energy is anisotropic on this mesh).
/// @param X rest positions (m) in hinge order. @return w, or 0 for a degenerate hinge.
template <typename T>
WEFT_HD inline T hinge_weight(const Vec3<T> X[4]) {
    const Vec3<T> e = X[1] - X[0];
    const T a0 = T(0.5) * length(cross(e, X[2] - X[0]));
    const T a1 = T(0.5) * length(cross(X[0] - X[1], X[3] - X[1]));
    const T le2 = length_squared(e);
    const T longest_sq = max_(max_(le2, max_(length_squared(X[2] - X[0]), length_squared(X[2] - X[1]))),
                              max_(length_squared(X[3] - X[0]), length_squared(X[3] - X[1])));
    const T tol = T(0.5) * degenerate_area_tolerance<T>() * longest_sq;
    if (!(a0 > tol) || !(a1 > tol)) return T(0);
    return le2 / (a0 + a1);
}

namespace detail {
/// [v]ₓ: the matrix of w ↦ v × w.
template <typename T>
WEFT_HD constexpr Mat3<T> cross_matrix(Vec3<T> v) {
    Mat3<T> r{};
    r.m[0][1] = -v.z; r.m[0][2] = v.y;
    r.m[1][0] = v.z;  r.m[1][2] = -v.x;
    r.m[2][0] = -v.y; r.m[2][1] = v.x;
    return r;
}
/// Wraps an angle difference into (−π, π], so that a rest angle near ±π and a current angle just
/// across the branch cut are close (the energy is then continuous except at θ − θ̄ = ±π).
template <typename T>
WEFT_HD inline T wrap_angle(T d) {
    const T pi = ScalarTraits<T>::pi;
    if (d > pi) d -= T(2) * pi;
    if (d <= -pi) d += T(2) * pi;
    return d;
}
}  // namespace detail

/// Gradient (and optionally Hessian) of the dihedral angle θ of a hinge.
/// ∇θ (Bridson et al. 2003; Tamstorf & Grinspun 2013, eq. 3–4): the opposite vertices move θ by
/// their height above the edge, ∂θ/∂x2 = |e|·N1/|N1|² and ∂θ/∂x3 = |e|·N2/|N2|²; the edge vertices
/// take the rest so that ∇θ is invariant under translation and rotation: with t_i the parameter of
/// the projection of x2 (i = 1) or x3 (i = 2) onto the edge line,
///   ∂θ/∂x0 = −(1−t1) ∂θ/∂x2 − (1−t2) ∂θ/∂x3,   ∂θ/∂x1 = −t1 ∂θ/∂x2 − t2 ∂θ/∂x3.
/// ∇²θ is this expression differentiated once more in closed form (product rule through |e|, N_i
/// and t_i; the same quantities as Tamstorf & Grinspun's Hessian, grouped per factor), then
/// symmetrised to remove rounding asymmetry.
/// @return false (outputs zeroed) for a degenerate hinge: zero-length edge or a triangle with
///         2·area ≤ `degenerate_area_tolerance`·longest edge².
template <typename T>
WEFT_HD inline bool dihedral_angle_derivatives(const Vec3<T> x[4], Vec3<T> dtheta[4], Mat3<T> (*d2theta)[4]) {
    for (int a = 0; a < 4; ++a) dtheta[a] = Vec3<T>{};
    if (d2theta != nullptr)
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) d2theta[a][b] = Mat3<T>{};
    const Vec3<T> e = x[1] - x[0];
    const Vec3<T> n1 = cross(e, x[2] - x[0]);
    const Vec3<T> n2 = cross(x[0] - x[1], x[3] - x[1]);
    const T le2 = length_squared(e);
    const T n1sq = length_squared(n1), n2sq = length_squared(n2);
    const T longest_sq = max_(max_(le2, max_(length_squared(x[2] - x[0]), length_squared(x[2] - x[1]))),
                              max_(length_squared(x[3] - x[0]), length_squared(x[3] - x[1])));
    const T tol = sqr_(degenerate_area_tolerance<T>() * longest_sq);
    if (!(le2 > T(0)) || !(n1sq > tol) || !(n2sq > tol)) return false;
    using std::sqrt;
    const T le = sqrt(le2);
    const Vec3<T> g2 = (le / n1sq) * n1;
    const Vec3<T> g3 = (le / n2sq) * n2;
    const T t1 = dot(x[2] - x[0], e) / le2;
    const T t2 = dot(x[3] - x[0], e) / le2;
    dtheta[0] = -(T(1) - t1) * g2 - (T(1) - t2) * g3;
    dtheta[1] = -t1 * g2 - t2 * g3;
    dtheta[2] = g2;
    dtheta[3] = g3;
    if (d2theta == nullptr) return true;

    // ∂|e|/∂x_b, ∂N_i/∂x_b (cross-product matrices) and ∂t_i/∂x_b.
    const Vec3<T> eh = e / le;
    const Vec3<T> dle[4] = {-eh, eh, Vec3<T>{}, Vec3<T>{}};
    const Mat3<T> dn1[4] = {detail::cross_matrix(x[2] - x[1]), T(-1) * detail::cross_matrix(x[2] - x[0]),
                            detail::cross_matrix(e), Mat3<T>{}};
    const Mat3<T> dn2[4] = {T(-1) * detail::cross_matrix(x[3] - x[1]), detail::cross_matrix(x[3] - x[0]),
                            Mat3<T>{}, T(-1) * detail::cross_matrix(e)};
    const Vec3<T> dt1_1 = (x[2] - x[0] - T(2) * t1 * e) / le2;
    const Vec3<T> dt1_2 = e / le2;
    const Vec3<T> dt1[4] = {-(dt1_1 + dt1_2), dt1_1, dt1_2, Vec3<T>{}};
    const Vec3<T> dt2_1 = (x[3] - x[0] - T(2) * t2 * e) / le2;
    const Vec3<T> dt2_3 = e / le2;
    const Vec3<T> dt2[4] = {-(dt2_1 + dt2_3), dt2_1, Vec3<T>{}, dt2_3};
    // ∂(|e| N/|N|²)/∂x_b = (N ⊗ ∂|e|/∂x_b + |e| (I − 2 N̂N̂ᵀ) ∂N/∂x_b) / |N|².
    const Mat3<T> p1 = Mat3<T>::identity() - (T(2) / n1sq) * Mat3<T>::outer(n1, n1);
    const Mat3<T> p2 = Mat3<T>::identity() - (T(2) / n2sq) * Mat3<T>::outer(n2, n2);
    Mat3<T> h[4][4];
    for (int b = 0; b < 4; ++b) {
        const Mat3<T> dg2 = (T(1) / n1sq) * (Mat3<T>::outer(n1, dle[b]) + le * (p1 * dn1[b]));
        const Mat3<T> dg3 = (T(1) / n2sq) * (Mat3<T>::outer(n2, dle[b]) + le * (p2 * dn2[b]));
        const Mat3<T> o2 = Mat3<T>::outer(g2, dt1[b]);
        const Mat3<T> o3 = Mat3<T>::outer(g3, dt2[b]);
        h[0][b] = (t1 - T(1)) * dg2 + o2 + (t2 - T(1)) * dg3 + o3;
        h[1][b] = T(-1) * (t1 * dg2 + o2 + t2 * dg3 + o3);
        h[2][b] = dg2;
        h[3][b] = dg3;
    }
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) d2theta[a][b] = T(0.5) * (h[a][b] + transpose(h[b][a]));
    return true;
}

/// Energy, gradient and Hessian of one bending hinge: E = ½·D·w·(θ − θ̄)² (J), with θ − θ̄ wrapped
/// into (−π, π].
/// @param stiffness  bending stiffness D (N·m).
/// @param weight     `hinge_weight` of the rest hinge (dimensionless).
/// @param rest_angle θ̄ (radians, `dihedral_angle` of the rest shape; 0 for flat cloth).
/// @param x          current hinge positions (m) in hinge order.
/// @param grad       if non-null, receives ∂E/∂x_a (N); force = −grad.
/// @param hess       if non-null and kind ≠ None, receives ∂²E/∂x_a∂x_b (N/m):
///                   Exact: D·w·(∇θ∇θᵀ + (θ−θ̄)∇²θ) (indefinite away from the rest angle);
///                   Fast: Gauss–Newton D·w·∇θ∇θᵀ (PSD, rank 1, exact at θ = θ̄);
///                   Projected: the exact 12×12 Hessian eigen-clamped to PSD.
/// Degenerate hinges (zero-length edge, zero-area triangle) return 0 with zero gradient and Hessian.
/// Limits: E jumps where θ − θ̄ crosses ±π (the hinge folded flat onto itself) and ∇θ grows like
/// 1/height as a triangle flattens into a sliver.
template <typename T>
WEFT_HD inline T bending_evaluate(T stiffness, T weight, T rest_angle, const Vec3<T> x[4], Vec3<T> grad[4],
                                  Mat3<T> hess[4][4], HessianKind kind) {
    const bool want_hess = hess != nullptr && kind != HessianKind::None;
    const bool need_d2 = want_hess && kind != HessianKind::Fast;
    Vec3<T> dth[4];
    Mat3<T> d2th[4][4];
    const bool ok = dihedral_angle_derivatives(x, dth, need_d2 ? d2th : nullptr);
    if (!ok) {
        if (grad != nullptr)
            for (int a = 0; a < 4; ++a) grad[a] = Vec3<T>{};
        if (want_hess)
            for (int a = 0; a < 4; ++a)
                for (int b = 0; b < 4; ++b) hess[a][b] = Mat3<T>{};
        return T(0);
    }
    const T d = detail::wrap_angle(dihedral_angle(x) - rest_angle);
    const T kw = stiffness * weight;
    if (grad != nullptr)
        for (int a = 0; a < 4; ++a) grad[a] = (kw * d) * dth[a];
    if (want_hess) {
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
                hess[a][b] = kw * Mat3<T>::outer(dth[a], dth[b]);
                if (need_d2) hess[a][b] += (kw * d) * d2th[a][b];
            }
        if (kind == HessianKind::Projected) project_psd_blocks<4>(hess);
    }
    return T(0.5) * kw * d * d;
}

}  // namespace weft::physics
