#pragma once
/// @file
/// Continuous contact of a cloth vertex with a fast analytic collider (issue 4, item 5: no
/// tunnelling at 50 m/s). The penalty contact of the solve (collider_contact.h) sees the collider at
/// the end of the substep only; a ball that moves further than its own width in one substep would
/// jump over the vertices in its path. This test follows the vertex's straight path and the
/// collider's motion together, and when the vertex enters the solid part on the way, it is carried
/// with the collider from that moment: its end position becomes the collider-frame point where it
/// was hit, pushed out to the contact thickness, placed at the collider's end pose.
///
/// Method: sampling the relative motion at spacing ≤ a quarter of the shape's smallest width w
/// (sphere and capsule 2r, box twice its smallest half extent). A straight path cannot cross a
/// convex solid between two samples unless its chord is shorter than the spacing, so what sampling
/// misses is a graze of depth ≤ r − √(r² − (w/8)²) ≈ w²/(128·r) — under 1/64 of the radius for a
/// sphere — which the penalty handles at the end of the substep anyway. Only motions that cover
/// more than that spacing in one substep are sampled (slower ones cannot tunnel); a plane is a
/// half-space and cannot be tunnelled through.
///
/// A slow motion is checked at its end only: the solve's penalty acts where the vertex is at the
/// start of the substep, so a contact that begins within the substep is not seen by it, and a heavy
/// vertex at a long step can end deep inside (a soft 2 kg/m² sheet at 1/24 s: 15–57 mm into a
/// resting ball). Such an end goes back along the normal onto the surface (distance 0, not the
/// contact thickness: the velocity (x − x0)/h then points no further out than the surface moved,
/// so the correction adds no bounce); from there the penalty sees the contact at the next
/// substep's start. Under offset contact the solvers skip this correction: it would move the vertex
/// past the displacement bound that keeps the cloth free of intersections (and send the substep to
/// the CCD fallback), so there the penalty alone pushes the vertex out at the next substep.

#include <cmath>

#include "weft/physics/collider_contact.h"
#include "weft/math/host_device.h"
#include "weft/physics/vec.h"

namespace weft::physics {

/// Outcome of `swept_shape_contact`.
template <typename T>
struct SweptContact {
    bool hit;          ///< the vertex entered the solid on its way
    T tau;             ///< fraction of the substep at the first sample found inside, in (0, 1]
    Vec3<T> position;  ///< corrected end position (m); the input end position when no hit
    int samples;       ///< samples taken (0: the motion was too slow to need any)
};

/// Smallest width of a bounded shape (m): what a point has to cross to pass through it. A plane
/// has none: returns 0, meaning "cannot be tunnelled through".
template <typename T>
WEFT_HD inline T shape_min_width(const Shape<T>& s) {
    switch (s.kind) {
        case ShapeKind::Sphere:
        case ShapeKind::Capsule: return T(2) * s.radius;
        case ShapeKind::Box: {
            T m = s.half_extents.x < s.half_extents.y ? s.half_extents.x : s.half_extents.y;
            m = m < s.half_extents.z ? m : s.half_extents.z;
            return T(2) * m;
        }
        case ShapeKind::Plane:
        default: return T(0);
    }
}

/// Radius of a ball about the shape's origin that holds the whole shape (m).
template <typename T>
WEFT_HD inline T shape_bounding_radius(const Shape<T>& s) {
    switch (s.kind) {
        case ShapeKind::Sphere: return s.radius;
        case ShapeKind::Capsule: return s.half_height + s.radius;
        case ShapeKind::Box: return length(s.half_extents);
        case ShapeKind::Plane:
        default: return T(0);
    }
}

namespace detail {
/// Rotation by the rotation vector w (axis × angle, rad): Rodrigues' formula.
template <typename T>
WEFT_HD inline Mat3<T> rotation_of(Vec3<T> w) {
    using std::cos;
    using std::sin;
    const T angle = length(w);
    if (!(angle > T(0))) return Mat3<T>::identity();
    const Vec3<T> k = w / angle;
    Mat3<T> K{};
    K.m[0][1] = -k.z;
    K.m[0][2] = k.y;
    K.m[1][0] = k.z;
    K.m[1][2] = -k.x;
    K.m[2][0] = -k.y;
    K.m[2][1] = k.x;
    return Mat3<T>::identity() + sin(angle) * K + (T(1) - cos(angle)) * (K * K);
}
}  // namespace detail

/// The vertex moving from x0 to x1 (m) over a substep of `h` s, against the collider at its start
/// pose `s0` and end pose `s1` (same shape; the pose in between: origin interpolated linearly,
/// rotation turned at s0's angular velocity). A vertex already inside at the start is left to the
/// penalty contact (returns no hit); a slow one that ends inside goes back onto the surface (hit,
/// no samples). `max_samples` caps the work per vertex (the spacing then grows).
template <typename T>
WEFT_HD inline SweptContact<T> swept_shape_contact(const Shape<T>& s0, const Shape<T>& s1, T h, Vec3<T> x0, Vec3<T> x1,
                                                   T thickness, int max_samples = 256) {
    using std::ceil;
    SweptContact<T> r{false, T(1), x1, 0};
    const T width = shape_min_width(s0);
    if (!(width > T(0))) return r;
    // Largest displacement of the vertex relative to any point of the collider over the substep.
    const T relative = length(x1 - x0) + length(s1.origin - s0.origin) +
                       length(s0.angular_velocity) * h * shape_bounding_radius(s0);
    const T spacing = T(0.25) * width;
    Vec3<T> n{};
    if (!(relative > spacing)) {
        // Slow: the path cannot cross the solid between its ends; an end inside it that started
        // outside overshot a contact that began within the substep.
        if (shape_distance(s0, x0, n, static_cast<Mat3<T>*>(nullptr)) < T(0)) return r;
        const T d = shape_distance(s1, x1, n, static_cast<Mat3<T>*>(nullptr));
        if (!(d < T(0))) return r;
        r.hit = true;
        r.position = x1 - d * n;
        return r;
    }
    const T wanted = ceil(relative / spacing);
    const int samples = wanted < T(max_samples) ? static_cast<int>(wanted) : max_samples;
    r.samples = samples;
    if (shape_distance(s0, x0, n, static_cast<Mat3<T>*>(nullptr)) < T(0)) return r;
    for (int k = 1; k <= samples; ++k) {
        const T tau = T(k) / T(samples);
        Shape<T> s = s0;
        s.origin = s0.origin + tau * (s1.origin - s0.origin);
        s.rotation = k == samples ? s1.rotation : detail::rotation_of((tau * h) * s0.angular_velocity) * s0.rotation;
        const Vec3<T> p = x0 + tau * (x1 - x0);
        const T d = shape_distance(s, p, n, static_cast<Mat3<T>*>(nullptr));
        if (!(d < T(0))) continue;
        // Entered: the surface point outside it at the contact thickness, in the collider's frame,
        // carried to the end pose.
        const Vec3<T> surface = p + (thickness - d) * n;
        const Vec3<T> local = transpose(s.rotation) * (surface - s.origin);
        r.hit = true;
        r.tau = tau;
        r.position = s1.rotation * local + s1.origin;
        return r;
    }
    return r;
}

}  // namespace weft::physics
