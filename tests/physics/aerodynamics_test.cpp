// Aerodynamic drag and lift (directions, two-sidedness, exact Jacobian against finite differences,
// the PSD damping block), the gust field (determinism, smoothness, divergence, RMS), and Rayleigh
// damping helpers.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fd_util.h"
#include "weft/physics/aerodynamics.h"
#include "weft/physics/damping.h"
#include "weft/physics/membrane.h"

namespace weft::physics::test {
namespace {

const AeroCoefficients<double> kAir{1.2, 1.5, 0.8};

TEST(Aerodynamics, DragOnlyBroadsideAndZeroEdgeOn) {
    // Unit right triangle in z = 0 (area 1/2, normal +z), moving up through still air.
    const V x[3] = {V{0, 0, 0}, V{1, 0, 0}, V{0, 1, 0}};
    const V v[3] = {V{0, 0, 2}, V{0, 0, 2}, V{0, 0, 2}};
    V f;
    aerodynamic_force(x, v, V{}, kAir, f, static_cast<M*>(nullptr));
    // Broadside: F = −½ρC_D A |u|² n, and no lift (n⊥ = 0).
    EXPECT_NEAR(3.0 * f.z, -0.5 * 1.2 * 1.5 * 0.5 * 4.0, 1e-12);
    EXPECT_NEAR(f.x, 0.0, 1e-15);
    EXPECT_NEAR(f.y, 0.0, 1e-15);
    // The same relative velocity from wind instead of motion: opposite sign of u, opposite force.
    const V still[3] = {};
    V g;
    aerodynamic_force(x, still, V{0, 0, 2}, kAir, g, static_cast<M*>(nullptr));
    EXPECT_NEAR(g.z, -f.z, 1e-12);
    // Edge-on (u in the plane): nothing.
    aerodynamic_force(x, still, V{3, 1, 0}, kAir, g, static_cast<M*>(nullptr));
    EXPECT_EQ(length(g), 0.0);
}

TEST(Aerodynamics, LiftIsPerpendicularToFlowAndTwoSided) {
    // A plate with its leading edge raised by α moving along +x through still air is lifted up (+y).
    const double alpha = 0.3;
    const V t{std::cos(alpha), std::sin(alpha), 0};
    const V x[3] = {V{0, 0, 0}, t, V{0, 0, 1}};
    const V xr[3] = {V{0, 0, 0}, V{0, 0, 1}, t};  // opposite winding, flipped normal
    const V v[3] = {V{5, 0, 0}, V{5, 0, 0}, V{5, 0, 0}};
    const AeroCoefficients<double> lift_only{1.2, 0.0, 1.0};
    V f, fr;
    aerodynamic_force(x, v, V{}, lift_only, f, static_cast<M*>(nullptr));
    aerodynamic_force(xr, v, V{}, lift_only, fr, static_cast<M*>(nullptr));
    EXPECT_GT(f.y, 0.0);
    EXPECT_NEAR(f.x, 0.0, 1e-12);  // perpendicular to u = +x
    const double area = 0.5;
    EXPECT_NEAR(3.0 * f.y, 0.5 * 1.2 * area * 25.0 * std::sin(alpha) * std::cos(alpha), 1e-12);
    EXPECT_LE(length(f - fr), 1e-13);
    V fd, fdr;
    aerodynamic_force(x, v, V{}, kAir, fd, static_cast<M*>(nullptr));
    aerodynamic_force(xr, v, V{}, kAir, fdr, static_cast<M*>(nullptr));
    EXPECT_LE(length(fd - fdr), 1e-13);
    EXPECT_LT(fd.x, 0.0);  // drag resists the motion
}

TEST(Aerodynamics, JacobianMatchesFiniteDifferencesAndDampingIsPsd) {
    std::mt19937 rng(41);
    for (int trial = 0; trial < 20; ++trial) {
        V x[3] = {random_vec(rng, -1, 1), random_vec(rng, -1, 1), random_vec(rng, -1, 1)};
        const V v[3] = {random_vec(rng, -3, 3), random_vec(rng, -3, 3), random_vec(rng, -3, 3)};
        const V wind = random_vec(rng, -5, 5);
        const M J = aerodynamic_force_jacobian(x, v, wind, kAir);
        // FD of the per-vertex force with respect to each vertex velocity: ∂f_a/∂v_b = J/9.
        M Jfd[3][3];
        fd_jacobian<3>(
            [&](const V* w, V* out) {
                V f;
                aerodynamic_force(x, w, wind, kAir, f, static_cast<M*>(nullptr));
                out[0] = out[1] = out[2] = f;
            },
            v, Jfd);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                EXPECT_LE(max_abs_diff((1.0 / 9.0) * J, Jfd[a][b]), 1e-7 * (max_abs(J) + 1e-12)) << trial;
        V f;
        M D;
        aerodynamic_force(x, v, wind, kAir, f, &D);
        double d[3][3];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) d[i][j] = D.m[i][j];
        EXPECT_TRUE(psd_by_cholesky<3>(d, 1e-12 * (max_abs(D) + 1e-300)));
        EXPECT_LE(max_abs_diff(D, transpose(D)), 1e-15 * max_abs(D));
        // D is the PSD part of −sym(J): uᵀDu ≥ −uᵀJu for all u (clamping only adds).
        const V u = random_vec(rng, -1, 1);
        EXPECT_GE(dot(u, D * u), -dot(u, J * u) - 1e-12 * max_abs(J));
    }
    // Pure drag along the normal: −J = q C_D (s n ûᵀ + r n nᵀ) = 2 q C_D |u| n nᵀ is already PSD, D equals it.
    const V x[3] = {V{0, 0, 0}, V{1, 0, 0}, V{0, 1, 0}};
    const V v[3] = {V{0, 0, 2}, V{0, 0, 2}, V{0, 0, 2}};
    V f;
    M D;
    aerodynamic_force(x, v, V{}, AeroCoefficients<double>{1.2, 1.5, 0.0}, f, &D);
    EXPECT_NEAR(D.m[2][2], 2.0 * 0.5 * 1.2 * 0.5 * 1.5 * 2.0, 1e-12);
    EXPECT_NEAR(D.m[0][0], 0.0, 1e-14);
}

TEST(Aerodynamics, DegenerateInputGivesZeros) {
    const V flat[3] = {V{0, 0, 0}, V{1, 0, 0}, V{2, 0, 0}};  // zero area
    const V same[3] = {V{1, 1, 1}, V{1, 1, 1}, V{1, 1, 1}};
    const V tri[3] = {V{0, 0, 0}, V{1, 0, 0}, V{0, 1, 0}};
    const V v[3] = {V{0, 0, 1}, V{0, 0, 1}, V{0, 0, 1}};
    const V zero[3] = {};
    for (const V* x : {flat, same, tri}) {
        for (const V* w : {v, zero}) {
            V f{9, 9, 9};
            M D;
            D.m[0][0] = 9;
            aerodynamic_force(x, w, x == tri ? V{0, 0, 0} : V{0, 3, 0}, kAir, f, &D);
            if (x == tri && w == v) continue;
            EXPECT_EQ(length(f), 0.0);
            EXPECT_EQ(max_abs(D), 0.0);
            EXPECT_EQ(max_abs(aerodynamic_force_jacobian(x, w, V{}, kAir)), 0.0);
        }
    }
}

TEST(WindGust, DeterministicSmoothDivergenceFreeAndCalibrated) {
    const V p{0.3, -1.7, 2.2};
    const V a = wind_gust(p, 0.4, 2.0, 1.5, 0.8);
    const V b = wind_gust(p, 0.4, 2.0, 1.5, 0.8);
    EXPECT_EQ(a, b);
    EXPECT_GT(length(a), 0.0);
    EXPECT_EQ(wind_gust(p, 0.4, 0.0, 1.5, 0.8), V{});
    // RMS speed ≈ amplitude over many samples.
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> U(-50, 50);
    double s2 = 0.0;
    const int n = 4000;
    for (int i = 0; i < n; ++i) s2 += length_squared(wind_gust(V{U(rng), U(rng), U(rng)}, U(rng), 3.0, 1.0, 2.0));
    EXPECT_NEAR(std::sqrt(s2 / n), 3.0, 0.3);
    // Divergence-free (central differences), and C¹: the Jacobian is continuous across lattice planes
    // (x/scale = 1 at x = 0.5, t·frequency = 1 at t = 0.5). A merely C⁰ field (linear interpolation)
    // would jump there by O(|J|); a C¹ one changes by O(|∂J|·δ).
    const double scale = 0.5, freq = 2.0;
    const auto jacobian = [&](V q, double t, double& div) {
        M j{};
        const double h = 1e-7;
        for (int i = 0; i < 3; ++i) {
            V e{};
            e[i] = 1.0;
            const V d = (wind_gust(q + h * e, t, 1.0, freq, scale) - wind_gust(q - h * e, t, 1.0, freq, scale)) / (2 * h);
            for (int r = 0; r < 3; ++r) j.m[r][i] = d[r];
        }
        div = j.m[0][0] + j.m[1][1] + j.m[2][2];
        return j;
    };
    for (const V q : {V{0.5, 0.21, -0.37}, V{1.3, 2.7, 0.11}}) {
        for (double t : {0.5, 0.77}) {
            double div = 0.0, div2 = 0.0;
            const double delta = 1e-5;
            const M jl = jacobian(q - V{delta, 0, 0}, t, div);
            const M jr = jacobian(q + V{delta, 0, 0}, t, div2);
            EXPECT_LE(std::fabs(div), 1e-6 * max_abs(jl));
            EXPECT_LE(max_abs_diff(jl, jr), 1e-2 * max_abs(jl));
            EXPECT_GT(max_abs(jl), 0.0);
            const M jt = jacobian(q, t + delta, div);
            const M jt0 = jacobian(q, t - delta, div2);
            EXPECT_LE(max_abs_diff(jt, jt0), 1e-2 * max_abs(jt));
        }
    }
    // Continuous in time across a lattice step.
    const V g0 = wind_gust(p, 0.5 - 1e-9, 1.0, 2.0, 1.0), g1 = wind_gust(p, 0.5 + 1e-9, 1.0, 2.0, 1.0);
    EXPECT_LE(length(g1 - g0), 1e-7);
}

/// The noise as its definition reads: every corner's lattice value hashed on its own.
template <typename T>
T value_noise4_by_corner(const T p[4], unsigned channel, T grad[3]) {
    int cell[4];
    T s[4], ds[4];
    for (int k = 0; k < 4; ++k) {
        const T fl = std::floor(p[k]);
        cell[k] = static_cast<int>(fl);
        const T f = p[k] - fl;
        s[k] = f * f * f * (f * (f * T(6) - T(15)) + T(10));
        ds[k] = T(30) * f * f * (f - T(1)) * (f - T(1));
    }
    T value = T(0);
    grad[0] = grad[1] = grad[2] = T(0);
    for (int corner = 0; corner < 16; ++corner) {
        T w[4], dw[4];
        int b[4];
        for (int k = 0; k < 4; ++k) {
            b[k] = (corner >> k) & 1;
            w[k] = b[k] != 0 ? s[k] : T(1) - s[k];
            dw[k] = b[k] != 0 ? ds[k] : -ds[k];
        }
        const T val = detail::lattice_value<T>(cell[0] + b[0], cell[1] + b[1], cell[2] + b[2], cell[3] + b[3], channel);
        value += val * (w[0] * w[1] * w[2] * w[3]);
        grad[0] += val * (dw[0] * w[1] * w[2] * w[3]);
        grad[1] += val * (w[0] * dw[1] * w[2] * w[3]);
        grad[2] += val * (w[0] * w[1] * dw[2] * w[3]);
    }
    return value;
}

// The noise shares its hash chain down the corners' tree (fewer mixes) and its weights across the
// three channels: each channel's gradient must have the bits of the corner-by-corner definition, in
// float and double, at points on both sides of zero.
template <typename T>
void expect_same_noise_bits() {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-40.0, 40.0);
    for (int n = 0; n < 2000; ++n) {
        const T p[4] = {static_cast<T>(u(rng)), static_cast<T>(u(rng)), static_cast<T>(u(rng)), static_cast<T>(u(rng))};
        T g[3][3];
        detail::value_noise4_gradients(p, g);
        for (unsigned channel = 0; channel < 3; ++channel) {
            T r[3];
            (void)value_noise4_by_corner(p, channel, r);
            for (int k = 0; k < 3; ++k)
                ASSERT_EQ(g[channel][k], r[k]) << "point " << n << ", channel " << channel << ", axis " << k;
        }
    }
}

TEST(WindGust, TheSharedHashTreeGivesTheBitsOfTheDefinition) {
    expect_same_noise_bits<float>();
    expect_same_noise_bits<double>();
}

TEST(RayleighDamping, ForcesAndJacobian) {
    const V v{1, -2, 3};
    const V fm = mass_damping_force(0.5, 2.0, v);
    EXPECT_EQ(fm, (V{-1, 2, -3}));
    // Stiffness damping with a membrane's PSD Hessian: zero for rigid translation, resists stretching.
    double dm_inv[2][2], area;
    ASSERT_TRUE(membrane_rest(V{0, 0, 0}, V{1, 0, 0}, V{0, 1, 0}, dm_inv, area));
    const V x[3] = {V{0, 0, 0}, V{1.1, 0, 0}, V{0, 1, 0}};
    M K[3][3];
    membrane_evaluate(dm_inv, area, membrane_material(100.0, 0.3), x, static_cast<V*>(nullptr), K, HessianKind::Fast);
    const V vt[3] = {v, v, v};
    V f[3];
    stiffness_damping_force<3>(0.1, K, vt, f);
    EXPECT_LE(max_abs<3>(f), 1e-12);
    const V vs[3] = {V{0, 0, 0}, V{1, 0, 0}, V{0, 0, 0}};  // vertex 1 moving away: stretching rate
    stiffness_damping_force<3>(0.1, K, vs, f);
    EXPECT_LT(f[1].x, 0.0);
    EXPECT_LT(dot(f[1], vs[1]), 0.0);  // dissipative
    // Jacobian: the force is linear in v, so f_a = Σ_b J_ab v_b exactly.
    for (int a = 0; a < 3; ++a) {
        V s{};
        for (int b = 0; b < 3; ++b) s += rayleigh_velocity_jacobian(0.0, 0.0, a == b, 0.1, K[a][b]) * vs[b];
        EXPECT_LE(length(s - f[a]), 1e-12);
    }
    const M jd = rayleigh_velocity_jacobian(0.5, 2.0, true, 0.0, M::identity());
    EXPECT_EQ(jd.m[1][1], -1.0);
    EXPECT_EQ(jd.m[0][1], 0.0);
}

}  // namespace
}  // namespace weft::physics::test
