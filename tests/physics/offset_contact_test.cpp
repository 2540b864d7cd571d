// Offset geometric contact (weft/physics/offset_contact.h): the penalty is C² at the offset and at
// the barrier's joint, zero outside and unbounded as the primitives meet, the force is minus the energy gradient and the Jacobian its (PSD-projected) derivative,
// checked against finite differences in both scalars; friction opposes slip.
#include <gtest/gtest.h>

#include <cmath>
#include <type_traits>

#include "weft/physics/offset_contact.h"

namespace weft::physics {
namespace {

template <typename T>
class OffsetContact : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(OffsetContact, Scalars);

TYPED_TEST(OffsetContact, PenaltyIsSmoothAtTheOffsetAndZeroBeyond) {
    using T = TypeParam;
    const T k = T(500), r = T(0.01);
    // Value, slope and curvature all go to zero at d = r from inside, and are zero outside.
    for (const T d : {r, T(1.5) * r, T(10)}) {
        const auto e = offset_penalty(d, k, r);
        EXPECT_EQ(e.energy, T(0));
        EXPECT_EQ(e.slope, T(0));
        EXPECT_EQ(e.curvature, T(0));
    }
    const auto near = offset_penalty(r * T(0.999), k, r);
    EXPECT_LT(near.energy, T(1e-9) * k * r * r);
    EXPECT_LT(-near.slope, T(1e-5) * k * r);
    EXPECT_LT(near.curvature, T(1e-2) * k);
    // Inside half the radius the barrier: at τ = r/2 the cubic's force k·r/4 and curvature k; the
    // force grows without bound as d → 0 (1/d), and a crossed pair is pushed harder still.
    const T tau = T(0.5) * r;
    const auto at_tau = offset_penalty(tau, k, r);
    EXPECT_NEAR(-at_tau.slope, k * r / T(4), T(1e-4) * k * r);
    EXPECT_NEAR(at_tau.curvature, k, T(1e-4) * k);
    const auto close = offset_penalty(T(0.01) * tau, k, r);
    EXPECT_NEAR(-close.slope, T(100) * k * r / T(4), T(0.01) * k * r * T(25));
    const auto touch = offset_penalty(T(0), k, r);
    EXPECT_GT(-touch.slope, -close.slope);
    EXPECT_GT(-offset_penalty(-r, k, r).slope, -touch.slope);
    EXPECT_GT(touch.curvature, T(0));
    // Slope and curvature are the energy's derivatives, in both branches and across the joint at τ
    // and at the barrier's floor (10⁻³τ).
    for (const T d : {T(0.0004) * r, T(0.002) * r, T(0.1) * r, T(0.499) * r, T(0.5) * r, T(0.501) * r, T(0.9) * r}) {
        const T eps = (std::is_same_v<T, float> ? T(1e-3) : T(1e-6)) * d;
        const auto e = offset_penalty(d, k, r);
        const T slope = (offset_penalty(d + eps, k, r).energy - offset_penalty(d - eps, k, r).energy) / (T(2) * eps);
        const T curvature = (offset_penalty(d + eps, k, r).slope - offset_penalty(d - eps, k, r).slope) / (T(2) * eps);
        const T tolerance = std::is_same_v<T, float> ? T(2e-2) : T(1e-5);
        EXPECT_NEAR(e.slope, slope, tolerance * std::abs(e.slope) + T(1e-6) * k * r) << d;
        EXPECT_NEAR(e.curvature, curvature, tolerance * e.curvature + T(1e-4) * k) << d;
    }
    // Value, slope and curvature are continuous at τ (C²).
    const T below = tau * (T(1) - T(1e-4)), above = tau * (T(1) + T(1e-4));
    EXPECT_NEAR(offset_penalty(below, k, r).energy, offset_penalty(above, k, r).energy, T(1e-3) * at_tau.energy);
    EXPECT_NEAR(offset_penalty(below, k, r).slope, offset_penalty(above, k, r).slope, T(1e-3) * k * r);
    EXPECT_NEAR(offset_penalty(below, k, r).curvature, offset_penalty(above, k, r).curvature, T(1e-2) * k);
}

TYPED_TEST(OffsetContact, ForceIsMinusTheGradientAndTheJacobianIsItsProjectedDerivative) {
    using T = TypeParam;
    const OffsetContactParams<T> p{T(800), T(0.02), T(0), T(1e-3)};
    const Vec3<T> g{T(0.004), T(0.009), T(-0.003)};  // |g| ≈ 0.0103 < r
    const Vec3<T> up{T(0), T(1), T(0)};
    const auto c = offset_contact(g, Vec3<T>{}, up, p);
    EXPECT_NEAR(c.distance, length(g), T(1e-6));
    EXPECT_GT(c.normal_force, T(0));
    EXPECT_GT(dot(c.force, g), T(0)) << "pushes the primitives apart";
    const T eps = std::is_same_v<T, float> ? T(1e-4) : T(1e-7);
    const T tolerance = std::is_same_v<T, float> ? T(1e-2) : T(1e-6);
    const T scale = p.stiffness * p.radius;
    for (int a = 0; a < 3; ++a) {
        Vec3<T> e{};
        e[a] = eps;
        const auto cp = offset_contact(g + e, Vec3<T>{}, up, p), cm = offset_contact(g - e, Vec3<T>{}, up, p);
        EXPECT_NEAR(c.force[a], -(cp.energy - cm.energy) / (T(2) * eps), tolerance * scale) << a;
        // The exact derivative of the force is −(E″nnᵀ + (E′/d)(I − nnᵀ)); the Jacobian keeps the
        // first part. Along n they agree; across n the difference is the dropped −E′/d ≥ 0 term.
        for (int b = 0; b < 3; ++b) {
            const T exact = (cp.force[b] - cm.force[b]) / (T(2) * eps);
            const T dropped = (c.normal_force / c.distance) * ((a == b ? T(1) : T(0)) - c.normal[a] * c.normal[b]);
            EXPECT_NEAR(c.dfdx.m[b][a], exact - dropped, tolerance * p.stiffness) << a << b;
        }
    }
    // The kept Jacobian is symmetric negative semi-definite: the system stays SPD.
    for (int trial = 0; trial < 3; ++trial) {
        const Vec3<T> v{T(trial == 0), T(0.3) * T(trial), T(-1)};
        EXPECT_LE(dot(v, c.dfdx * v), T(1e-6) * p.stiffness);
    }
}

TYPED_TEST(OffsetContact, NothingOutsideTheOffsetAndAFallbackWhereThePointsMeet) {
    using T = TypeParam;
    const OffsetContactParams<T> p{T(800), T(0.02), T(0.5), T(1e-3)};
    const Vec3<T> up{T(0), T(0), T(1)};
    const auto far = offset_contact(Vec3<T>{T(0.03), T(0), T(0)}, Vec3<T>{T(1), T(0), T(0)}, up, p);
    EXPECT_EQ(far.normal_force, T(0));
    EXPECT_EQ(length(far.force), T(0)) << "no friction without a normal force";
    const auto met = offset_contact(Vec3<T>{}, Vec3<T>{}, up, p);
    EXPECT_NEAR(dot(met.normal, up), T(1), T(1e-6));
    EXPECT_GT(met.force.z, p.stiffness * p.radius) << "the barrier pushes along the fallback";
}

TYPED_TEST(OffsetContact, FrictionOpposesSlip) {
    using T = TypeParam;
    const OffsetContactParams<T> p{T(800), T(0.02), T(0.4), T(1e-3)};
    const Vec3<T> g{T(0), T(0.01), T(0)};
    const Vec3<T> slip{T(0.5), T(0), T(0.2)};  // tangential relative velocity
    const auto c = offset_contact(g, slip, Vec3<T>{T(0), T(1), T(0)}, p);
    const Vec3<T> tangential = c.force - dot(c.force, c.normal) * c.normal;
    EXPECT_LT(dot(tangential, slip), T(0));
    EXPECT_LE(length(tangential), p.friction * c.normal_force * T(1.0001));
}

}  // namespace
}  // namespace weft::physics
