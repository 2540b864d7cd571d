#pragma once
/// @file
/// Cloth-vertex contact with analytic colliders (plane, sphere, capsule, box; moving and rotating):
/// signed distance with its normal and curvature, a penalty normal force and smoothed Coulomb
/// friction, each with the Jacobians the implicit solver assembles.
///
/// Normal force: penalty energy E = ½k(h − d)² for d < h (h = contact thickness, d = signed
/// distance), f = −∇E = k(h − d)·n (Baraff & Witkin 1998 §6 use the same spring; Bridson et al. 2002
/// the repulsion). Friction: a regularised Coulomb law derived from the dissipation potential
/// Φ(v) = μ f_n √(|u_t|² + ε²), f_t = −∂Φ/∂v, with f_n lagged (held fixed over the step) as in
/// IPC (Li et al. 2020 §5) — so ∂f_t/∂v is symmetric negative semi-definite and the implicit system
/// stays SPD.

#include <cmath>

#include "weft/physics/eigen_sym.h"
#include "weft/physics/friction.h"
#include "weft/physics/hessian.h"
#include "weft/math/host_device.h"
#include "weft/physics/scalar.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Kind of analytic collider.
enum class ShapeKind : unsigned char {
    Plane,    ///< infinite plane through `origin`, normal rotation·(0, 1, 0); the half-space behind is solid
    Sphere,   ///< ball of `radius` about `origin`
    Capsule,  ///< points within `radius` of the segment origin ± half_height·rotation·(0, 1, 0)
    Box,      ///< oriented box: |local coordinate i| ≤ half_extents[i]
};

/// An analytic collider at one instant, in world coordinates (m, m/s, rad/s).
template <typename T>
struct Shape {
    ShapeKind kind;
    Mat3<T> rotation;          ///< local → world rotation (orthonormal)
    Vec3<T> origin;            ///< centre (or a point of the plane), m
    T radius;                  ///< sphere and capsule radius, m
    T half_height;             ///< capsule half-length of the axis segment (local Y), m
    Vec3<T> half_extents;      ///< box half-sizes along the local axes, m
    Vec3<T> linear_velocity;   ///< velocity of `origin`, m/s
    Vec3<T> angular_velocity;  ///< world-frame angular velocity about `origin`, rad/s
};

namespace detail {
/// Distance from p to a convex core (point, segment or box) inflated by `radius`, given r = p − c with
/// c the closest core point: d = |r| − radius, n = r/|r|, and ∂n/∂p = (I − nnᵀ)·proj/|r| where
/// proj = ∂r/∂p (I for a point core; I − aaᵀ along a segment; the outside axes of a box).
template <typename T>
WEFT_HD inline T round_distance(Vec3<T> r, T radius, const Mat3<T>& proj, Vec3<T> fallback, Vec3<T>& normal,
                                Mat3<T>* normal_jacobian) {
    const T l = length(r);
    if (!(l > T(0))) {  // exactly on the core: any direction is a normal; pick a fixed one, no NaN
        normal = fallback;
        if (normal_jacobian != nullptr) *normal_jacobian = Mat3<T>{};
        return -radius;
    }
    normal = r / l;
    if (normal_jacobian != nullptr)
        *normal_jacobian = (T(1) / l) * ((Mat3<T>::identity() - Mat3<T>::outer(normal, normal)) * proj);
    return l - radius;
}
}  // namespace detail

/// Signed distance from `p` to the surface of `s` (m; negative inside), with the outward unit
/// normal (the gradient of the distance) and optionally its Jacobian ∂n/∂p (1/m).
/// The distance is C¹ except on the medial axis (the centre of a sphere, the axis of a capsule,
/// the interior diagonals of a box) where the normal jumps; ∂n/∂p is zero on flat parts (plane,
/// box faces and the whole box interior) and is the curvature (I − nnᵀ)/ρ on round parts (ρ the
/// distance to the core: sphere centre, capsule axis, box edge or corner).
template <typename T>
WEFT_HD inline T shape_distance(const Shape<T>& s, Vec3<T> p, Vec3<T>& normal, Mat3<T>* normal_jacobian) {
    const Vec3<T> up = s.rotation.col(1);
    switch (s.kind) {
        case ShapeKind::Plane: {
            normal = up;
            if (normal_jacobian != nullptr) *normal_jacobian = Mat3<T>{};
            return dot(p - s.origin, up);
        }
        case ShapeKind::Sphere:
            return detail::round_distance(p - s.origin, s.radius, Mat3<T>::identity(), up, normal, normal_jacobian);
        case ShapeKind::Capsule: {
            const T t = dot(p - s.origin, up);
            const T tc = clamp_(t, -s.half_height, s.half_height);
            // Along the cylindrical part the core point slides with p: ∂(p − c)/∂p = I − a aᵀ.
            const Mat3<T> proj = (t > -s.half_height && t < s.half_height)
                                     ? Mat3<T>::identity() - Mat3<T>::outer(up, up)
                                     : Mat3<T>::identity();
            // Fallback normal on the axis: perpendicular to it (local X), as good as any.
            return detail::round_distance(p - (s.origin + tc * up), s.radius, proj, s.rotation.col(0), normal,
                                          normal_jacobian);
        }
        case ShapeKind::Box:
        default: {
            const Mat3<T> rt = transpose(s.rotation);
            const Vec3<T> q = rt * (p - s.origin);  // local coordinates
            Vec3<T> r{};
            Mat3<T> proj{};
            bool outside = false;
            for (int i = 0; i < 3; ++i) {
                const T h = s.half_extents[i];
                const T c = clamp_(q[i], -h, h);
                r[i] = q[i] - c;
                if (q[i] > h || q[i] < -h) {
                    outside = true;
                    proj.m[i][i] = T(1);  // the closest point stops following p along this axis
                }
            }
            if (outside) {
                Vec3<T> nl{};
                Mat3<T> jl{};
                const T d = detail::round_distance(r, T(0), proj, Vec3<T>{T(0), T(1), T(0)}, nl,
                                                   normal_jacobian != nullptr ? &jl : nullptr);
                normal = s.rotation * nl;
                if (normal_jacobian != nullptr) *normal_jacobian = s.rotation * jl * rt;
                return d;
            }
            // Inside: the nearest face decides (ties go to the lowest axis); the distance is the
            // largest of q_i − h_i over faces, and the normal is constant, so ∂n/∂p = 0.
            int best = 0;
            T best_d = T(0);
            for (int i = 0; i < 3; ++i) {
                const T di = (q[i] < T(0) ? -q[i] : q[i]) - s.half_extents[i];
                if (i == 0 || di > best_d) {
                    best_d = di;
                    best = i;
                }
            }
            Vec3<T> nl{};
            nl[best] = sign_(q[best]);
            normal = s.rotation * nl;
            if (normal_jacobian != nullptr) *normal_jacobian = Mat3<T>{};
            return best_d;
        }
    }
}

/// Velocity of the collider's material point at `p` (m/s): linear_velocity + ω × (p − origin).
template <typename T>
WEFT_HD constexpr Vec3<T> shape_point_velocity(const Shape<T>& s, Vec3<T> p) {
    return s.linear_velocity + cross(s.angular_velocity, p - s.origin);
}

/// Contact parameters.
template <typename T>
struct ContactParams {
    T stiffness;      ///< penalty stiffness k (N/m)
    T thickness;      ///< contact thickness h: the force starts when the distance drops below it (m)
    T friction;       ///< Coulomb coefficient μ (dimensionless)
    T slip_velocity;  ///< friction regularisation ε (m/s), > 0: below it friction acts like viscous damping
};

/// Result of one vertex–collider contact evaluation.
template <typename T>
struct ContactResult {
    bool active;      ///< distance < thickness; every other field but distance and normal is zero if not
    T distance;       ///< signed distance d (m)
    Vec3<T> normal;   ///< outward unit normal n at the vertex
    T energy;         ///< penalty energy ½k(h − d)² (J); friction is dissipative and has none
    Vec3<T> force;    ///< normal force k(h − d)·n plus friction force (N)
    Mat3<T> dfdx;     ///< ∂force/∂x (N/m); see `collider_contact` for what each HessianKind keeps
    Mat3<T> dfdv;     ///< ∂force/∂v (N·s/m), symmetric negative semi-definite
    T normal_force;   ///< f_n = k(h − d) (N), the lagged normal force magnitude used by friction
};

/// Penalty contact and smoothed Coulomb friction of one cloth vertex against a collider.
/// @param s the collider. @param c contact parameters. @param x vertex position (m). @param v vertex velocity (m/s).
/// @param kind which position Jacobian to return in `dfdx`:
///   None: dfdx and dfdv are zero;
///   Exact: k(h − d)·∂n/∂x − k·nnᵀ (the curvature term makes −dfdx indefinite on round shapes);
///   Fast: −k·nnᵀ only (−dfdx PSD, the curvature term dropped);
///   Projected: the exact −dfdx eigen-clamped to PSD (for the convex shapes here, ∂n/∂x is orthogonal
///              to n, so this equals Fast up to rounding).
/// Friction (lagged f_n, so it contributes nothing to dfdx): u = v − shape_point_velocity,
/// u_t = (I − nnᵀ)u, f_t = −μ f_n u_t/√(|u_t|² + ε²), and
/// dfdv = −μ f_n (P/s − u_t u_tᵀ/s³) with P = I − nnᵀ, s = √(|u_t|² + ε²) (exact, NSD).
template <typename T>
WEFT_HD inline ContactResult<T> collider_contact(const Shape<T>& s, ContactParams<T> c, Vec3<T> x, Vec3<T> v,
                                                 HessianKind kind) {
    using std::sqrt;
    ContactResult<T> res{};
    Mat3<T> dn{};
    const bool want_jac = kind != HessianKind::None;
    res.distance = shape_distance(s, x, res.normal, kind == HessianKind::None || kind == HessianKind::Fast ? nullptr : &dn);
    res.active = res.distance < c.thickness;
    if (!res.active) return res;
    const Vec3<T> n = res.normal;
    const T pen = c.thickness - res.distance;
    const T fn = c.stiffness * pen;
    res.normal_force = fn;
    res.energy = T(0.5) * c.stiffness * pen * pen;
    res.force = fn * n;
    const Mat3<T> nn = Mat3<T>::outer(n, n);
    if (want_jac) {
        res.dfdx = (-c.stiffness) * nn;
        if (kind == HessianKind::Exact) {
            res.dfdx += fn * dn;
        } else if (kind == HessianKind::Projected) {
            T a[3][3];
            const Mat3<T> neg = c.stiffness * nn - fn * dn;  // −dfdx, exact
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) a[i][j] = neg.m[i][j];
            project_psd<3>(a);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) res.dfdx.m[i][j] = -a[i][j];
        }
    }
    if (c.friction > T(0))
        add_coulomb_friction(n, v - shape_point_velocity(s, x), fn, c.friction, c.slip_velocity, res.force,
                             want_jac ? &res.dfdv : nullptr);
    return res;
}

}  // namespace weft::physics
