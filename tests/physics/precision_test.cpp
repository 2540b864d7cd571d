// Every physics function instantiated for float: compiles warning-free and agrees with double to
// ~1e-4 relative on well-conditioned inputs (the CPU backend runs in either precision).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fd_util.h"
#include "weft/physics/aerodynamics.h"
#include "weft/physics/bending.h"
#include "weft/physics/collider_contact.h"
#include "weft/physics/damping.h"
#include "weft/physics/membrane.h"

namespace weft::physics::test {
namespace {

using Vf = Vec3<float>;
using Mf = Mat3<float>;

Vf to_f(V v) { return v.cast<float>(); }
V to_d(Vf v) { return v.cast<double>(); }

double rel(double a, double b, double scale) { return std::fabs(a - b) / scale; }

template <int n>
double rel_blocks(const Mf Hf[n][n], const M Hd[n][n]) {
    double d = 0.0;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b)
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) d = std::fmax(d, std::fabs(double(Hf[a][b].m[r][c]) - Hd[a][b].m[r][c]));
    return d / max_abs<n>(Hd);
}

TEST(Precision, MembraneFloatAgreesWithDouble) {
    const V X[3] = {V{0.1, 0.0, 0.2}, V{0.9, 0.1, 0.0}, V{0.3, 0.8, 0.1}};
    const V x[3] = {V{0.1, 0.05, 0.2}, V{1.05, 0.1, -0.05}, V{0.25, 0.85, 0.2}};
    double dd[2][2], ad;
    float df[2][2], af;
    ASSERT_TRUE(membrane_rest(X[0], X[1], X[2], dd, ad));
    ASSERT_TRUE(membrane_rest(to_f(X[0]), to_f(X[1]), to_f(X[2]), df, af));
    const Vf xf[3] = {to_f(x[0]), to_f(x[1]), to_f(x[2])};
    for (HessianKind k : {HessianKind::Exact, HessianKind::Fast, HessianKind::Projected}) {
        V gd[3];
        M Hd[3][3];
        Vf gf[3];
        Mf Hf[3][3];
        const double ed = membrane_evaluate(dd, ad, membrane_material(1000.0, 0.3), x, gd, Hd, k);
        const float ef = membrane_evaluate(df, af, membrane_material(1000.0F, 0.3F), xf, gf, Hf, k);
        EXPECT_LE(rel(double(ef), ed, ed), 1e-4);
        V gfd[3] = {to_d(gf[0]), to_d(gf[1]), to_d(gf[2])};
        EXPECT_LE(max_abs_diff<3>(gfd, gd) / max_abs<3>(gd), 1e-4);
        EXPECT_LE(rel_blocks<3>(Hf, Hd), 1e-4);
    }
}

TEST(Precision, BendingFloatAgreesWithDouble) {
    const V X[4] = {V{0, 0, 0}, V{1, 0, 0}, V{0.3, 0.9, 0}, V{0.6, -0.8, 0}};
    const V x[4] = {V{0, 0, 0}, V{1, 0.05, 0}, V{0.3, 0.85, 0.3}, V{0.6, -0.75, 0.2}};
    const Vf Xf[4] = {to_f(X[0]), to_f(X[1]), to_f(X[2]), to_f(X[3])};
    const Vf xf[4] = {to_f(x[0]), to_f(x[1]), to_f(x[2]), to_f(x[3])};
    EXPECT_LE(rel(double(hinge_weight(Xf)), hinge_weight(X), hinge_weight(X)), 1e-6);
    EXPECT_LE(std::fabs(double(dihedral_angle(xf)) - dihedral_angle(x)), 1e-6);
    for (HessianKind k : {HessianKind::Exact, HessianKind::Fast, HessianKind::Projected}) {
        V gd[4];
        M Hd[4][4];
        Vf gf[4];
        Mf Hf[4][4];
        const double ed = bending_evaluate(1e-3, 1.0, 0.1, x, gd, Hd, k);
        const float ef = bending_evaluate(1e-3F, 1.0F, 0.1F, xf, gf, Hf, k);
        EXPECT_LE(rel(double(ef), ed, ed), 1e-4);
        V gfd[4] = {to_d(gf[0]), to_d(gf[1]), to_d(gf[2]), to_d(gf[3])};
        EXPECT_LE(max_abs_diff<4>(gfd, gd) / max_abs<4>(gd), 1e-4);
        EXPECT_LE(rel_blocks<4>(Hf, Hd), 1e-4);
    }
}

TEST(Precision, ContactFloatAgreesWithDouble) {
    for (ShapeKind kind : {ShapeKind::Plane, ShapeKind::Sphere, ShapeKind::Capsule, ShapeKind::Box}) {
        Shape<double> s{};
        s.kind = kind;
        std::mt19937 rng(51);
        s.rotation = random_rotation(rng);
        s.origin = V{0.1, 0.2, 0.3};
        s.radius = 0.5;
        s.half_height = 0.4;
        s.half_extents = V{0.5, 0.5, 0.5};
        s.linear_velocity = V{0.1, 0, 0};
        s.angular_velocity = V{0, 1, 0};
        Shape<float> sf{kind, s.rotation.cast<float>(), to_f(s.origin), 0.5F, 0.4F, to_f(s.half_extents),
                        to_f(s.linear_velocity), to_f(s.angular_velocity)};
        const V x = s.origin + s.rotation * V{0.3, kind == ShapeKind::Plane ? 0.05 : 0.42, 0.1};
        const V v{0.5, -0.2, 0.1};
        const auto rd = collider_contact(s, ContactParams<double>{1e3, 0.1, 0.3, 0.01}, x, v, HessianKind::Exact);
        const auto rf = collider_contact(sf, ContactParams<float>{1e3F, 0.1F, 0.3F, 0.01F}, to_f(x), to_f(v),
                                         HessianKind::Exact);
        ASSERT_TRUE(rd.active && rf.active);
        EXPECT_LE(rel(double(rf.distance), rd.distance, 1.0), 1e-6);
        EXPECT_LE(length(to_d(rf.force) - rd.force) / length(rd.force), 1e-4);
        EXPECT_LE(max_abs(rf.dfdx.cast<double>() - rd.dfdx) / max_abs(rd.dfdx), 1e-4);
        EXPECT_LE(max_abs(rf.dfdv.cast<double>() - rd.dfdv) / max_abs(rd.dfdv), 1e-4);
    }
}

TEST(Precision, AerodynamicsAndGustFloatAgreeWithDouble) {
    const V x[3] = {V{0, 0, 0}, V{1, 0.2, 0}, V{0.1, 1, 0.3}};
    const V v[3] = {V{1, 2, 3}, V{1.5, 2, 2}, V{0, 1, 3}};
    const Vf xf[3] = {to_f(x[0]), to_f(x[1]), to_f(x[2])};
    const Vf vf[3] = {to_f(v[0]), to_f(v[1]), to_f(v[2])};
    V fd;
    M Dd;
    Vf ff;
    Mf Df;
    aerodynamic_force(x, v, V{3, 0, 0}, AeroCoefficients<double>{1.2, 1.5, 0.8}, fd, &Dd);
    aerodynamic_force(xf, vf, Vf{3, 0, 0}, AeroCoefficients<float>{1.2F, 1.5F, 0.8F}, ff, &Df);
    EXPECT_LE(length(to_d(ff) - fd) / length(fd), 1e-4);
    EXPECT_LE(max_abs(Df.cast<double>() - Dd) / max_abs(Dd), 1e-4);
    const Mf Jf = aerodynamic_force_jacobian(xf, vf, Vf{3, 0, 0}, AeroCoefficients<float>{1.2F, 1.5F, 0.8F});
    const M Jd = aerodynamic_force_jacobian(x, v, V{3, 0, 0}, AeroCoefficients<double>{1.2, 1.5, 0.8});
    EXPECT_LE(max_abs(Jf.cast<double>() - Jd) / max_abs(Jd), 1e-4);
    const V gd = wind_gust(V{1.3, -0.4, 2.2}, 0.7, 2.0, 1.0, 3.0);
    const Vf gf = wind_gust(Vf{1.3F, -0.4F, 2.2F}, 0.7F, 2.0F, 1.0F, 3.0F);
    EXPECT_LE(length(to_d(gf) - gd), 1e-4 * 2.0);
    // Damping helpers in float.
    const Vf fm = mass_damping_force(0.5F, 2.0F, Vf{1, 2, 3});
    EXPECT_EQ(fm.z, -3.0F);
    Mf K[1][1] = {{Mf::identity()}};
    const Vf vv[1] = {Vf{1, 0, 0}};
    Vf fo[1];
    stiffness_damping_force<1>(0.25F, K, vv, fo);
    EXPECT_EQ(fo[0].x, -0.25F);
    EXPECT_EQ(rayleigh_velocity_jacobian(1.0F, 2.0F, true, 0.5F, Mf::identity()).m[2][2], -2.5F);
}

}  // namespace
}  // namespace weft::physics::test
