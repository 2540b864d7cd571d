// Pair springs of the cloth–cloth contacts (weft/physics/pair_contact.h): force from the energy,
// Jacobians against finite differences, friction opposing slip, both scalars.
#include <gtest/gtest.h>

#include <cmath>

#include "weft/physics/pair_contact.h"

namespace weft::physics {
namespace {

template <typename T>
class PairContact : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(PairContact, Scalars);

TYPED_TEST(PairContact, NormalForceIsMinusTheEnergyGradient) {
    using T = TypeParam;
    const Vec3<T> n = normalized(Vec3<T>{T(0.2), T(1), T(-0.1)});
    const PairContactParams<T> p{T(1000), T(0.01), T(0), T(1e-3)};
    const Vec3<T> g{T(0.001), T(0.004), T(0.002)};
    const auto r = pair_contact(n, g, Vec3<T>{}, p);
    auto energy = [&](Vec3<T> x) {
        const T d = p.thickness - dot(n, x);
        return T(0.5) * p.stiffness * d * d;
    };
    const T eps = std::is_same_v<T, float> ? T(1e-3) : T(1e-6);
    for (int a = 0; a < 3; ++a) {
        Vec3<T> e{};
        e[a] = eps;
        const T fd = -(energy(g + e) - energy(g - e)) / (T(2) * eps);
        const T tolerance = std::is_same_v<T, float> ? T(2e-3) : T(1e-8);
        EXPECT_NEAR(r.force[a], fd, tolerance) << a;
        // dfdx column a against the force difference.
        const auto rp = pair_contact(n, g + e, Vec3<T>{}, p);
        const auto rm = pair_contact(n, g - e, Vec3<T>{}, p);
        for (int b = 0; b < 3; ++b)
            EXPECT_NEAR(r.dfdx.m[b][a], (rp.force[b] - rm.force[b]) / (T(2) * eps), T(1e-2)) << a << b;
    }
    EXPECT_GT(r.normal_force, T(0));
    EXPECT_NEAR(r.gap, dot(n, g), T(1e-7));
}

TYPED_TEST(PairContact, FrictionOpposesSlipAndItsJacobianMatches) {
    using T = TypeParam;
    const Vec3<T> n{T(0), T(1), T(0)};
    const PairContactParams<T> p{T(1000), T(0.01), T(0.5), T(1e-3)};
    const Vec3<T> g{T(0), T(0.005), T(0)};  // compressed by 5 mm: f_n = 5 N
    const Vec3<T> u{T(0.3), T(-0.2), T(0.1)};
    const auto r = pair_contact(n, g, u, p);
    const Vec3<T> tangential = r.force - r.normal_force * n;
    EXPECT_LT(dot(tangential, Vec3<T>{u.x, T(0), u.z}), T(0));
    EXPECT_NEAR(length(tangential), T(0.5) * r.normal_force, T(1e-3));  // sliding fast: Coulomb
    const T eps = std::is_same_v<T, float> ? T(1e-3) : T(1e-7);
    for (int a = 0; a < 3; ++a) {
        Vec3<T> e{};
        e[a] = eps;
        const auto rp = pair_contact(n, g, u + e, p);
        const auto rm = pair_contact(n, g, u - e, p);
        for (int b = 0; b < 3; ++b)
            EXPECT_NEAR(r.dfdv.m[b][a], (rp.force[b] - rm.force[b]) / (T(2) * eps), T(2e-2)) << a << b;
    }
}

TYPED_TEST(PairContact, HoldingBackASeparatingPairExertsNoFriction) {
    using T = TypeParam;
    const Vec3<T> n{T(0), T(0), T(1)};
    const PairContactParams<T> p{T(1000), T(0.01), T(0.5), T(1e-3)};
    const auto r = pair_contact(n, Vec3<T>{T(0), T(0), T(0.02)}, Vec3<T>{T(1), T(0), T(0)}, p);
    EXPECT_LT(r.normal_force, T(0));  // two-sided within the substep
    EXPECT_EQ(r.force.x, T(0));
    EXPECT_EQ(r.dfdv.m[0][0], T(0));
}

}  // namespace
}  // namespace weft::physics
