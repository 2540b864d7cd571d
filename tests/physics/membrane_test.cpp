// StVK membrane triangle: finite-difference checks of the gradient and Hessian, the PSD flavours,
// invariances, the plane-stress calibration, and degenerate input.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fd_util.h"
#include "weft/physics/membrane.h"

namespace weft::physics::test {
namespace {

constexpr double kStretch = 1000.0;  // N/m
constexpr double kPoisson = 0.3;

struct Tri {
    V X[3];
    double dm_inv[2][2];
    double area;
    // Orthonormal rest frame (t1, t2) and normal, to build deformations from 2×2 in-plane maps.
    V t1, t2, n;
};

Tri make_rest(std::mt19937& rng) {
    Tri t{};
    for (;;) {
        t.X[0] = random_vec(rng, -0.5, 0.5);
        t.X[1] = random_vec(rng, -0.5, 0.5);
        t.X[2] = random_vec(rng, -0.5, 0.5);
        if (membrane_rest(t.X[0], t.X[1], t.X[2], t.dm_inv, t.area) && t.area > 0.02) break;
    }
    t.t1 = normalized(t.X[1] - t.X[0]);
    t.n = normalized(cross(t.X[1] - t.X[0], t.X[2] - t.X[0]));
    t.t2 = cross(t.n, t.t1);
    return t;
}

// x_a = R·(A applied in the rest plane)(X_a − X_0) + c, with A a 2×2 map (plus `out` times the normal
// component in the second row for an out-of-plane shear).
void deform(const Tri& t, const double A[2][2], double out_of_plane, const M& R, V c, V x[3]) {
    for (int a = 0; a < 3; ++a) {
        const V d = t.X[a] - t.X[0];
        const double u = dot(d, t.t1), w = dot(d, t.t2);
        const double u2 = A[0][0] * u + A[0][1] * w, w2 = A[1][0] * u + A[1][1] * w;
        x[a] = R * (u2 * t.t1 + w2 * t.t2 + (out_of_plane * w) * t.n) + c;
    }
}

struct Config {
    const char* name;
    double A[2][2];
    double out;
};
const Config kConfigs[] = {
    {"stretched", {{1.20, 0.0}, {0.0, 1.10}}, 0.0},
    {"compressed", {{0.80, 0.0}, {0.0, 0.90}}, 0.0},
    {"mixed", {{1.15, 0.0}, {0.0, 0.85}}, 0.0},
    {"sheared", {{1.0, 0.35}, {0.0, 1.0}}, 0.0},
    {"out_of_plane", {{1.05, 0.1}, {-0.05, 0.95}}, 0.3},
    {"strongly_compressed", {{0.3, 0.1}, {0.05, 0.5}}, 0.1},
};

double energy(const Tri& t, MembraneMaterial<double> m, const V x[3]) {
    return membrane_evaluate(t.dm_inv, t.area, m, x, static_cast<V*>(nullptr), static_cast<M(*)[3]>(nullptr),
                             HessianKind::None);
}

TEST(Membrane, MaterialIsPlaneStressLame) {
    const auto m = membrane_material(kStretch, kPoisson);
    EXPECT_NEAR(m.mu, kStretch / (2.0 * 1.3), 1e-12);
    EXPECT_NEAR(m.lambda, kStretch * 0.3 / (1.0 - 0.09), 1e-12);
}

TEST(Membrane, GradientAndHessianMatchFiniteDifferences) {
    std::mt19937 rng(11);
    const auto m = membrane_material(kStretch, kPoisson);
    for (int trial = 0; trial < 4; ++trial) {
        const Tri t = make_rest(rng);
        const M R = random_rotation(rng);
        const V c = random_vec(rng, -2.0, 2.0);
        for (const Config& cfg : kConfigs) {
            V x[3];
            deform(t, cfg.A, cfg.out, R, c, x);
            V g[3];
            M H[3][3];
            membrane_evaluate(t.dm_inv, t.area, m, x, g, H, HessianKind::Exact);
            V gfd[3];
            fd_gradient<3>([&](const V* y) { return energy(t, m, y); }, x, gfd);
            EXPECT_LE(max_abs_diff<3>(g, gfd), 1e-6 * (max_abs<3>(g) + 1.0)) << cfg.name;
            M Hfd[3][3];
            fd_jacobian<3>(
                [&](const V* y, V* out) {
                    membrane_evaluate(t.dm_inv, t.area, m, y, out, static_cast<M(*)[3]>(nullptr), HessianKind::None);
                },
                x, Hfd);
            EXPECT_LE(max_abs_diff<3>(H, Hfd), 1e-6 * max_abs<3>(H)) << cfg.name;
            EXPECT_TRUE(blocks_symmetric<3>(H)) << cfg.name;
        }
    }
}

TEST(Membrane, FastAndProjectedArePsdAndFastIsExactUnderTension) {
    std::mt19937 rng(12);
    const auto m = membrane_material(kStretch, kPoisson);
    int indefinite_exact = 0;
    for (int trial = 0; trial < 20; ++trial) {
        const Tri t = make_rest(rng);
        const M R = random_rotation(rng);
        std::uniform_real_distribution<double> U(0.3, 1.5), S(-0.4, 0.4);
        const double A[2][2] = {{U(rng), S(rng)}, {S(rng), U(rng)}};
        V x[3];
        deform(t, A, S(rng), R, V{}, x);
        M He[3][3], Hf[3][3], Hp[3][3];
        membrane_evaluate(t.dm_inv, t.area, m, x, static_cast<V*>(nullptr), He, HessianKind::Exact);
        membrane_evaluate(t.dm_inv, t.area, m, x, static_cast<V*>(nullptr), Hf, HessianKind::Fast);
        membrane_evaluate(t.dm_inv, t.area, m, x, static_cast<V*>(nullptr), Hp, HessianKind::Projected);
        EXPECT_TRUE(blocks_psd<3>(Hf)) << trial;
        EXPECT_TRUE(blocks_psd<3>(Hp)) << trial;
        if (!blocks_psd<3>(He)) ++indefinite_exact;
        else EXPECT_LE(max_abs_diff<3>(Hp, He), 1e-10 * max_abs<3>(He));  // nothing to clamp
    }
    EXPECT_GT(indefinite_exact, 0) << "the random set should include compressed, indefinite cases";

    // Under biaxial tension both principal stresses are positive: Fast is the exact Hessian.
    const Tri t = make_rest(rng);
    V x[3];
    deform(t, kConfigs[0].A, 0.0, random_rotation(rng), V{1, 2, 3}, x);
    M He[3][3], Hf[3][3];
    membrane_evaluate(t.dm_inv, t.area, m, x, static_cast<V*>(nullptr), He, HessianKind::Exact);
    membrane_evaluate(t.dm_inv, t.area, m, x, static_cast<V*>(nullptr), Hf, HessianKind::Fast);
    EXPECT_LE(max_abs_diff<3>(Hf, He), 1e-12 * max_abs<3>(He));
    // Under compression it is not (the geometric term is clamped), and Exact is indefinite.
    deform(t, kConfigs[1].A, 0.0, M::identity(), V{}, x);
    membrane_evaluate(t.dm_inv, t.area, m, x, static_cast<V*>(nullptr), He, HessianKind::Exact);
    membrane_evaluate(t.dm_inv, t.area, m, x, static_cast<V*>(nullptr), Hf, HessianKind::Fast);
    EXPECT_GT(max_abs_diff<3>(Hf, He), 1e-3 * max_abs<3>(He));
    EXPECT_FALSE(blocks_psd<3>(He));
}

TEST(Membrane, ZeroAtRestAndInvariantUnderRigidMotion) {
    std::mt19937 rng(13);
    const auto m = membrane_material(kStretch, kPoisson);
    const Tri t = make_rest(rng);
    const double I2[2][2] = {{1.0, 0.0}, {0.0, 1.0}};
    for (int k = 0; k < 3; ++k) {
        V x[3];
        deform(t, I2, 0.0, random_rotation(rng), random_vec(rng, -5, 5), x);
        V g[3];
        const double e = membrane_evaluate(t.dm_inv, t.area, m, x, g, static_cast<M(*)[3]>(nullptr), HessianKind::None);
        EXPECT_LE(std::fabs(e), 1e-20);
        EXPECT_LE(max_abs<3>(g), 1e-10);
    }
    for (const Config& cfg : kConfigs) {
        V x[3], y[3];
        deform(t, cfg.A, cfg.out, M::identity(), V{}, x);
        deform(t, cfg.A, cfg.out, random_rotation(rng), random_vec(rng, -5, 5), y);
        const double ex = energy(t, m, x), ey = energy(t, m, y);
        EXPECT_GT(ex, 0.0);
        EXPECT_NEAR(ey, ex, 1e-12 * ex) << cfg.name;
    }
}

TEST(Membrane, UniaxialStressEnergyIsHalfKStrainSquared) {
    // Plane stress, uniaxial: stretch ε along t1, free lateral contraction −νε ⇒ ψ = ½kε² (to O(ε³)).
    // This pins down the plane-stress Lamé parameters (the 3D λ would give a different value).
    std::mt19937 rng(14);
    const auto m = membrane_material(kStretch, kPoisson);
    const Tri t = make_rest(rng);
    const double eps = 1e-4;
    const double A[2][2] = {{1.0 + eps, 0.0}, {0.0, 1.0 - kPoisson * eps}};
    V x[3];
    deform(t, A, 0.0, M::identity(), V{}, x);
    const double e = energy(t, m, x);
    EXPECT_NEAR(e / t.area, 0.5 * kStretch * eps * eps, 1e-3 * 0.5 * kStretch * eps * eps);
}

TEST(Membrane, LargestStretchIsTheInPlaneMapsLargestSingularValue) {
    // x = R·A·X + c in the rest plane: the principal stretches are A's singular values, whatever the
    // rotation and the translation; 1 at rest.
    std::mt19937 rng(16);
    const Tri t = make_rest(rng);
    const double I2[2][2] = {{1.0, 0.0}, {0.0, 1.0}};
    const double A[2][2] = {{3.0, 0.5}, {0.2, 0.7}};
    // σ_max² = the larger eigenvalue of AᵀA.
    const double a = A[0][0] * A[0][0] + A[1][0] * A[1][0], b = A[0][0] * A[0][1] + A[1][0] * A[1][1];
    const double c = A[0][1] * A[0][1] + A[1][1] * A[1][1];
    const double sigma = std::sqrt(0.5 * (a + c) + std::sqrt(0.25 * (a - c) * (a - c) + b * b));
    for (int k = 0; k < 3; ++k) {
        const M R = random_rotation(rng);
        const V shift = random_vec(rng, -5, 5);
        V x[3];
        deform(t, I2, 0.0, R, shift, x);
        EXPECT_NEAR(largest_stretch(t.dm_inv, x), 1.0, 1e-12);
        deform(t, A, 0.0, R, shift, x);
        EXPECT_NEAR(largest_stretch(t.dm_inv, x), sigma, 1e-12 * sigma);
    }
    // A triangle squashed to a point stretches nothing.
    const V point[3] = {V{1, 1, 1}, V{1, 1, 1}, V{1, 1, 1}};
    EXPECT_EQ(largest_stretch(t.dm_inv, point), 0.0);
}

TEST(Membrane, DegenerateInputGivesZerosNotNaN) {
    double dm_inv[2][2] = {{7, 7}, {7, 7}};
    double area = 7;
    EXPECT_FALSE(membrane_rest(V{0, 0, 0}, V{1, 0, 0}, V{2, 0, 0}, dm_inv, area));  // collinear
    EXPECT_EQ(area, 0.0);
    EXPECT_EQ(dm_inv[0][0], 0.0);
    EXPECT_EQ(dm_inv[0][1], 0.0);
    EXPECT_EQ(dm_inv[1][1], 0.0);
    EXPECT_FALSE(membrane_rest(V{1, 1, 1}, V{1, 1, 1}, V{1, 1, 1}, dm_inv, area));  // coincident
    EXPECT_FALSE(membrane_rest(V{0, 0, 0}, V{1, 0, 0}, V{0.5, 1e-9, 0}, dm_inv, area));  // sliver
    EXPECT_TRUE(membrane_rest(V{0, 0, 0}, V{1, 0, 0}, V{0.5, 1e-3, 0}, dm_inv, area));
    // A valid element whose vertices all collapse onto one point: finite energy, gradient, Hessian.
    std::mt19937 rng(15);
    const Tri t = make_rest(rng);
    const auto m = membrane_material(kStretch, kPoisson);
    const V x[3] = {V{1, 1, 1}, V{1, 1, 1}, V{1, 1, 1}};
    V g[3];
    M H[3][3];
    for (HessianKind k : {HessianKind::Exact, HessianKind::Fast, HessianKind::Projected}) {
        const double e = membrane_evaluate(t.dm_inv, t.area, m, x, g, H, k);
        EXPECT_TRUE(std::isfinite(e));
        EXPECT_NEAR(e, t.area * (m.mu * 0.5 + 0.5 * m.lambda), 1e-12);  // G = −I/2
        EXPECT_TRUE(std::isfinite(max_abs<3>(g)));
        EXPECT_TRUE(std::isfinite(max_abs<3>(H)));
        EXPECT_TRUE(blocks_psd<3>(H) || k == HessianKind::Exact);
    }
}

}  // namespace
}  // namespace weft::physics::test
