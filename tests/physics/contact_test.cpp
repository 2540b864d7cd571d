// Analytic colliders: signed distance, normal and curvature against finite differences for every
// shape (outside, inside, box faces, edges and corners away from the medial axis), penalty force and
// its Jacobian flavours, smoothed Coulomb friction, moving colliders, degenerate points.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fd_util.h"
#include "weft/physics/collider_contact.h"

namespace weft::physics::test {
namespace {

Shape<double> make_shape(ShapeKind kind, const M& R, V origin) {
    Shape<double> s{};
    s.kind = kind;
    s.rotation = R;
    s.origin = origin;
    s.radius = 0.5;
    s.half_height = 0.7;
    s.half_extents = V{0.4, 0.6, 0.8};
    return s;
}

struct Probe {
    ShapeKind kind;
    V local;  // probe point in the shape's local frame
    const char* what;
};

const Probe kProbes[] = {
    {ShapeKind::Plane, {0.3, 0.02, -0.4}, "plane above"},
    {ShapeKind::Plane, {0.3, -0.03, -0.4}, "plane below"},
    {ShapeKind::Sphere, {0.3, 0.25, 0.33}, "sphere outside"},
    {ShapeKind::Sphere, {0.2, -0.1, 0.25}, "sphere inside"},
    {ShapeKind::Capsule, {0.4, 0.3, 0.32}, "capsule side outside"},
    {ShapeKind::Capsule, {0.2, -0.2, 0.1}, "capsule side inside"},
    {ShapeKind::Capsule, {0.1, 0.95, 0.2}, "capsule cap"},
    {ShapeKind::Capsule, {-0.1, -1.0, 0.3}, "capsule bottom cap"},
    {ShapeKind::Box, {0.1, 0.63, -0.2}, "box face outside"},
    {ShapeKind::Box, {0.42, 0.63, 0.1}, "box edge region"},
    {ShapeKind::Box, {-0.42, 0.62, -0.83}, "box corner region"},
    {ShapeKind::Box, {0.35, 0.1, 0.2}, "box inside near +x face"},
    {ShapeKind::Box, {0.05, -0.5, 0.1}, "box inside near -y face"},
};

TEST(Contact, DistanceNormalAndCurvatureMatchFiniteDifferences) {
    std::mt19937 rng(31);
    for (int trial = 0; trial < 3; ++trial) {
        const M R = random_rotation(rng);
        const V o = random_vec(rng, -2, 2);
        for (const Probe& pr : kProbes) {
            const Shape<double> s = make_shape(pr.kind, R, o);
            const V p = R * pr.local + o;
            V n;
            M J;
            const double d = shape_distance(s, p, n, &J);
            EXPECT_NEAR(length(n), 1.0, 1e-14) << pr.what;
            V grad[1];
            const V x[1] = {p};
            fd_gradient<1>([&](const V* y) { V nn; return shape_distance(s, y[0], nn, static_cast<M*>(nullptr)); }, x,
                           grad);
            EXPECT_LE(length(grad[0] - n), 1e-8) << pr.what;
            M Jfd[1][1];
            fd_jacobian<1>([&](const V* y, V* out) { out[0] = V{}; shape_distance(s, y[0], out[0], static_cast<M*>(nullptr)); },
                           x, Jfd);
            EXPECT_LE(max_abs_diff(J, Jfd[0][0]), 1e-7) << pr.what;
            (void)d;
        }
    }
}

TEST(Contact, KnownDistances) {
    const M I = M::identity();
    V n;
    const auto sphere = make_shape(ShapeKind::Sphere, I, V{1, 0, 0});
    EXPECT_NEAR(shape_distance(sphere, V{1, 2, 0}, n, static_cast<M*>(nullptr)), 1.5, 1e-15);
    EXPECT_NEAR(n.y, 1.0, 1e-15);
    const auto capsule = make_shape(ShapeKind::Capsule, I, V{});
    EXPECT_NEAR(shape_distance(capsule, V{0, 0.5, 2}, n, static_cast<M*>(nullptr)), 1.5, 1e-15);
    EXPECT_NEAR(shape_distance(capsule, V{0, 2.7, 0}, n, static_cast<M*>(nullptr)), 1.5, 1e-15);
    const auto box = make_shape(ShapeKind::Box, I, V{});
    EXPECT_NEAR(shape_distance(box, V{0, 0, 0}, n, static_cast<M*>(nullptr)), -0.4, 1e-15);  // nearest face ±x
    EXPECT_NEAR(std::fabs(n.x), 1.0, 1e-15);
    EXPECT_NEAR(shape_distance(box, V{1.4, 1.6, 0}, n, static_cast<M*>(nullptr)), std::sqrt(2.0), 1e-15);  // edge
    EXPECT_NEAR(shape_distance(box, V{0.4 + 3, 0.6 + 4, 0.8 + 12}, n, static_cast<M*>(nullptr)), 13.0, 1e-14);
    // A plane rotated so that its normal is +x.
    M Rz{};
    Rz.m[0][1] = 1; Rz.m[1][0] = -1; Rz.m[2][2] = 1;  // maps local +y to world +x
    const auto plane = make_shape(ShapeKind::Plane, Rz, V{1, 0, 0});
    EXPECT_NEAR(shape_distance(plane, V{3, 5, 7}, n, static_cast<M*>(nullptr)), 2.0, 1e-15);
    EXPECT_NEAR(n.x, 1.0, 1e-15);
}

ContactParams<double> params(double mu = 0.0) { return ContactParams<double>{1e4, 0.05, mu, 1e-2}; }

TEST(Contact, PenaltyForceAndJacobianMatchFiniteDifferences) {
    std::mt19937 rng(32);
    const M R = random_rotation(rng);
    const V o = random_vec(rng, -1, 1);
    for (const Probe& pr : kProbes) {
        const Shape<double> s = make_shape(pr.kind, R, o);
        const V x[1] = {R * pr.local + o};
        const auto c = params();
        const auto res = collider_contact(s, c, x[0], V{}, HessianKind::Exact);
        ASSERT_TRUE(res.active) << pr.what;
        V g[1];
        fd_gradient<1>([&](const V* y) { return collider_contact(s, c, y[0], V{}, HessianKind::None).energy; }, x, g);
        EXPECT_LE(length(g[0] + res.force), 1e-7 * length(res.force)) << pr.what;
        M J[1][1];
        fd_jacobian<1>([&](const V* y, V* out) { out[0] = collider_contact(s, c, y[0], V{}, HessianKind::None).force; },
                       x, J);
        EXPECT_LE(max_abs_diff(res.dfdx, J[0][0]), 1e-6 * max_abs(res.dfdx)) << pr.what;
        // Fast and Projected: −dfdx PSD, and equal to each other for these convex shapes.
        const auto fast = collider_contact(s, c, x[0], V{}, HessianKind::Fast);
        const auto proj = collider_contact(s, c, x[0], V{}, HessianKind::Projected);
        double nf[3][3], np[3][3];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                nf[i][j] = -fast.dfdx.m[i][j];
                np[i][j] = -proj.dfdx.m[i][j];
            }
        EXPECT_TRUE(psd_by_cholesky<3>(nf, 1e-9 * c.stiffness)) << pr.what;
        EXPECT_TRUE(psd_by_cholesky<3>(np, 1e-9 * c.stiffness)) << pr.what;
        EXPECT_LE(max_abs_diff(fast.dfdx, proj.dfdx), 1e-9 * c.stiffness) << pr.what;
        EXPECT_NEAR(fast.energy, res.energy, 1e-15 * res.energy);
        EXPECT_EQ(max_abs(collider_contact(s, c, x[0], V{}, HessianKind::None).dfdx), 0.0);
    }
    // On a sphere the exact −dfdx is indefinite (the curvature term), which is why Fast drops it.
    const auto sphere = make_shape(ShapeKind::Sphere, M::identity(), V{});
    const auto ex = collider_contact(sphere, params(), V{0, 0.49, 0}, V{}, HessianKind::Exact);
    double ne[3][3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) ne[i][j] = -ex.dfdx.m[i][j];
    EXPECT_FALSE(psd_by_cholesky<3>(ne, 1e-3));
}

TEST(Contact, InactiveBeyondThickness) {
    const auto sphere = make_shape(ShapeKind::Sphere, M::identity(), V{});
    const auto r = collider_contact(sphere, params(0.5), V{0, 0.56, 0}, V{1, 0, 0}, HessianKind::Exact);
    EXPECT_FALSE(r.active);
    EXPECT_NEAR(r.distance, 0.06, 1e-15);
    EXPECT_EQ(r.energy, 0.0);
    EXPECT_EQ(length(r.force), 0.0);
    EXPECT_EQ(max_abs(r.dfdx), 0.0);
    EXPECT_EQ(max_abs(r.dfdv), 0.0);
    const auto a = collider_contact(sphere, params(), V{0, 0.54, 0}, V{}, HessianKind::Exact);
    EXPECT_TRUE(a.active);
    EXPECT_NEAR(a.normal_force, 1e4 * 0.01, 1e-9);
    EXPECT_NEAR(a.force.y, 100.0, 1e-9);
    EXPECT_NEAR(a.energy, 0.5 * 1e4 * 1e-4, 1e-12);
}

TEST(Contact, FrictionIsTheGradientOfADissipationPotential) {
    std::mt19937 rng(33);
    for (const Probe& pr : kProbes) {
        Shape<double> s = make_shape(pr.kind, random_rotation(rng), random_vec(rng, -1, 1));
        s.linear_velocity = random_vec(rng, -1, 1);
        s.angular_velocity = random_vec(rng, -2, 2);
        const V x = s.rotation * pr.local + s.origin;
        const auto c = params(0.4);
        for (double speed : {0.0, 1e-3, 0.5}) {
            const V v[1] = {shape_point_velocity(s, x) + speed * random_vec(rng, -1, 1)};
            const auto res = collider_contact(s, c, x, v[0], HessianKind::Fast);
            ASSERT_TRUE(res.active);
            const V ft = res.force - res.normal_force * res.normal;
            EXPECT_LE(std::fabs(dot(ft, res.normal)), 1e-12 * (1.0 + length(ft)));
            EXPECT_LE(length(ft), c.friction * res.normal_force * (1.0 + 1e-12));  // Coulomb cone
            M J[1][1];
            fd_jacobian<1>([&](const V* y, V* out) { out[0] = collider_contact(s, c, x, y[0], HessianKind::None).force; },
                           v, J, 1e-7);
            EXPECT_LE(max_abs_diff(res.dfdv, J[0][0]), 1e-5 * max_abs(res.dfdv)) << pr.what << " speed " << speed;
            double nd[3][3];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) nd[i][j] = -res.dfdv.m[i][j];
            EXPECT_TRUE(psd_by_cholesky<3>(nd, 1e-12 * max_abs(res.dfdv)));
            EXPECT_LE(max_abs_diff(res.dfdv, transpose(res.dfdv)), 1e-15 * max_abs(res.dfdv));
            if (speed == 0.0) {  // sticking to a moving body
                EXPECT_LE(length(ft), 1e-12 * res.normal_force);
            }
        }
    }
    // Sliding fast: friction saturates at μ f_n opposite to the tangential slip.
    const auto plane = make_shape(ShapeKind::Plane, M::identity(), V{});
    const auto r = collider_contact(plane, params(0.4), V{0, 0.0, 0}, V{100, -3, 0}, HessianKind::Fast);
    EXPECT_NEAR(r.force.x, -0.4 * r.normal_force, 1e-6 * r.normal_force);
    EXPECT_NEAR(r.force.y, r.normal_force, 1e-12);
}

TEST(Contact, PointVelocityOfRotatingShape) {
    Shape<double> s = make_shape(ShapeKind::Sphere, M::identity(), V{1, 0, 0});
    s.linear_velocity = V{0, 0, 2};
    s.angular_velocity = V{0, 3, 0};
    const V u = shape_point_velocity(s, V{2, 0, 0});  // ω × (1,0,0) = (0,0,−3)
    EXPECT_NEAR(u.x, 0.0, 1e-15);
    EXPECT_NEAR(u.z, -1.0, 1e-15);
}

TEST(Contact, DegeneratePointsGiveFiniteResults) {
    const Probe centre[] = {{ShapeKind::Sphere, {0, 0, 0}, "sphere centre"},
                            {ShapeKind::Capsule, {0, 0.3, 0}, "capsule axis"},
                            {ShapeKind::Capsule, {0, 0.7, 0}, "capsule segment end"},
                            {ShapeKind::Box, {0, 0, 0}, "box centre"}};
    for (const Probe& pr : centre) {
        const auto s = make_shape(pr.kind, M::identity(), V{});
        for (HessianKind k : {HessianKind::Exact, HessianKind::Fast, HessianKind::Projected}) {
            const auto r = collider_contact(s, params(0.3), pr.local, V{0, 0, 0}, k);
            EXPECT_TRUE(r.active);
            EXPECT_NEAR(length(r.normal), 1.0, 1e-15) << pr.what;
            EXPECT_TRUE(is_finite(r.force) && std::isfinite(max_abs(r.dfdx)) && std::isfinite(max_abs(r.dfdv)))
                << pr.what;
        }
    }
    // ε = 0 and zero slip: no division by zero.
    const auto plane = make_shape(ShapeKind::Plane, M::identity(), V{});
    const auto r = collider_contact(plane, ContactParams<double>{1e4, 0.05, 0.5, 0.0}, V{}, V{}, HessianKind::Exact);
    EXPECT_TRUE(is_finite(r.force) && std::isfinite(max_abs(r.dfdv)));
}

}  // namespace
}  // namespace weft::physics::test
