// Continuous contact with fast analytic colliders (weft/physics/swept_collider.h): a 50 m/s ball
// must not pass through a vertex in its path, a slow motion is checked at its end only (an
// overshoot goes back onto the surface), and the vertex is carried to the collider's end pose
// outside the solid.
#include <gtest/gtest.h>

#include <cmath>

#include "weft/physics/swept_collider.h"

namespace weft::physics {
namespace {

template <typename T>
Shape<T> ball(Vec3<T> centre, T radius, Vec3<T> velocity) {
    Shape<T> s{};
    s.kind = ShapeKind::Sphere;
    s.rotation = Mat3<T>::identity();
    s.origin = centre;
    s.radius = radius;
    s.linear_velocity = velocity;
    return s;
}

template <typename T>
class SweptCollider : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(SweptCollider, Scalars);

// A 5 cm ball at 50 m/s crosses a resting vertex in one 1/240 s substep (21 cm of travel): the
// end-only penalty would see the ball 16 cm past the vertex and do nothing.
TYPED_TEST(SweptCollider, FastBallCarriesTheVertexInItsPath) {
    using T = TypeParam;
    const T h = T(1) / T(240);
    const Vec3<T> v{T(0), T(0), T(-50)};
    const Shape<T> s0 = ball<T>({T(0), T(0), T(0.1)}, T(0.05), v);
    const Shape<T> s1 = ball<T>(s0.origin + h * v, T(0.05), v);
    const Vec3<T> x{T(0.01), T(0.0), T(0.0)};
    const T thickness = T(0.005);
    const SweptContact<T> c = swept_shape_contact(s0, s1, h, x, x, thickness);
    ASSERT_TRUE(c.hit);
    EXPECT_GT(c.samples, 1);
    // Carried: in front of the ball's end position (smaller z), outside it by the thickness.
    Vec3<T> n{};
    const T d = shape_distance(s1, c.position, n, static_cast<Mat3<T>*>(nullptr));
    EXPECT_NEAR(d, thickness, T(1e-4));
    EXPECT_LT(c.position.z, s1.origin.z);
}

TYPED_TEST(SweptCollider, SlowBallThatStopsShortIsLeftToThePenalty) {
    using T = TypeParam;
    const T h = T(1) / T(240);
    const Vec3<T> v{T(0), T(0), T(-1)};  // 4 mm per substep: less than a quarter of the 10 cm width
    const Shape<T> s0 = ball<T>({T(0), T(0), T(0.056)}, T(0.05), v);
    const Shape<T> s1 = ball<T>(s0.origin + h * v, T(0.05), v);
    const Vec3<T> x{T(0), T(0), T(0)};  // 2 mm from the surface at the end: inside the thickness only
    const SweptContact<T> c = swept_shape_contact(s0, s1, h, x, x, T(0.005));
    EXPECT_FALSE(c.hit);
    EXPECT_EQ(c.samples, 0);
    EXPECT_EQ(c.position.z, x.z);
}

// A contact that begins within a slow substep: the solve's penalty (at the substep's start) did not
// see it, and the vertex ends inside. It goes back along the normal onto the surface, not out to
// the contact thickness, so that (x − x0)/h has no outward part: no bounce.
TYPED_TEST(SweptCollider, SlowOvershootGoesBackOntoTheSurface) {
    using T = TypeParam;
    const T h = T(1) / T(24);
    const Shape<T> s = ball<T>({T(0), T(0), T(0)}, T(0.15), Vec3<T>{});
    const Vec3<T> x0{T(0.01), T(0), T(0.155)};  // 5 mm above the resting ball, falling 4 cm
    const Vec3<T> x1{T(0.01), T(0), T(0.115)};
    const SweptContact<T> c = swept_shape_contact(s, s, h, x0, x1, T(0.005));
    ASSERT_TRUE(c.hit);
    EXPECT_EQ(c.samples, 0);
    EXPECT_NEAR(length(c.position), T(0.15), T(1e-5));
    // Along the end point's normal: the same direction from the centre.
    EXPECT_NEAR(c.position.x / c.position.z, x1.x / x1.z, T(1e-5));
    // The velocity it implies moves towards the ball's centre or along its surface, never out.
    const Vec3<T> velocity = (c.position - x0) / h;
    EXPECT_LE(dot(velocity, x0 / length(x0)), T(0));
}

TYPED_TEST(SweptCollider, PathBesideTheBallIsNotTouched) {
    using T = TypeParam;
    const T h = T(1) / T(240);
    const Vec3<T> v{T(0), T(0), T(-50)};
    const Shape<T> s0 = ball<T>({T(0), T(0), T(0.1)}, T(0.05), v);
    const Shape<T> s1 = ball<T>(s0.origin + h * v, T(0.05), v);
    const Vec3<T> x{T(0.06), T(0), T(0)};  // 1 cm outside the ball's swept cylinder
    const SweptContact<T> c = swept_shape_contact(s0, s1, h, x, x, T(0.005));
    EXPECT_FALSE(c.hit);
    EXPECT_EQ(c.position.x, x.x);
}

TYPED_TEST(SweptCollider, VertexAlreadyInsideIsLeftToThePenalty) {
    using T = TypeParam;
    const T h = T(1) / T(240);
    const Vec3<T> v{T(0), T(0), T(-50)};
    const Shape<T> s0 = ball<T>({T(0), T(0), T(0)}, T(0.05), v);
    const Shape<T> s1 = ball<T>(s0.origin + h * v, T(0.05), v);
    const Vec3<T> x{T(0), T(0), T(0.01)};
    EXPECT_FALSE(swept_shape_contact(s0, s1, h, x, x, T(0.005)).hit);
}

// A thin box (a paddle, 1 cm thick) spinning at 60 rad/s sweeps a vertex between two poses.
TYPED_TEST(SweptCollider, SpinningPaddleHitsAVertexBetweenPoses) {
    using T = TypeParam;
    const T h = T(1) / T(120);
    Shape<T> s0{};
    s0.kind = ShapeKind::Box;
    s0.rotation = Mat3<T>::identity();
    s0.origin = Vec3<T>{};
    s0.half_extents = {T(0.3), T(0.005), T(0.05)};  // blade along x, thin along y
    s0.angular_velocity = {T(0), T(0), T(60)};       // turns about z: 0.5 rad per substep
    Shape<T> s1 = s0;
    s1.rotation = detail::rotation_of(h * s0.angular_velocity);
    // A vertex at 45° of the blade's start: (0.2·cos 0.25, 0.2·sin 0.25), swept over mid-substep.
    const Vec3<T> x{T(0.2) * std::cos(T(0.25)), T(0.2) * std::sin(T(0.25)), T(0)};
    Vec3<T> n{};
    ASSERT_GT(shape_distance(s0, x, n, static_cast<Mat3<T>*>(nullptr)), T(0));
    ASSERT_GT(shape_distance(s1, x, n, static_cast<Mat3<T>*>(nullptr)), T(0));  // outside at both ends
    const SweptContact<T> c = swept_shape_contact(s0, s1, h, x, x, T(0.002));
    ASSERT_TRUE(c.hit);
    EXPECT_GT(c.tau, T(0.3));
    EXPECT_LT(c.tau, T(0.7));
    // Carried ahead of the blade: at the end pose it sits in front of the blade (positive local y).
    const Vec3<T> local = transpose(s1.rotation) * (c.position - s1.origin);
    EXPECT_GT(local.y, T(0.004));
}

}  // namespace
}  // namespace weft::physics
