// Bending from a shape operator per triangle (weft/physics/shell_bending.h): the rest data, the
// gradient and the Gauss–Newton Hessian against finite differences, invariance under rigid motions,
// missing hinges, and the plate energy of a grid triangle bent into a cylinder about either axis; the
// mid-edge model's pieces (weft/physics/midedge_bending.h): a reading that changes nothing, the
// gradient with a reading, and a boundary edge's free normal condensed out.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fd_util.h"
#include "weft/physics/midedge_bending.h"
#include "weft/physics/shell_bending.h"

namespace weft::physics::test {
namespace {

/// A triangle p0 p1 p2 and the far corners s0 s1 s2 of its neighbours across edges k = (p_k, p_k+1):
/// stencil vertices 0–2 the corners, 3–5 the far corners. Hinge k in bending.h's order:
/// (p_k, p_k+1, p_k+2, s_k).
constexpr int kHinge[3][4] = {{0, 1, 2, 3}, {1, 2, 0, 4}, {2, 0, 1, 5}};

struct Stencil {
    V x[6];
};

/// A triangle of the checkerboard grid (cell size h, right angle at p2) and its neighbours in the
/// plane y = 0: p0 = (0,0), p1 = (h,h), p2 = (h,0) in (X, Z), far corners (0,h), (2h,0), (h,−h).
/// Its normal points up (+y), and every hinge (p_k, p_k+1, p_k+2, s_k) is consistently oriented.
Stencil grid_triangle(double h) {
    Stencil s;
    const double xz[6][2] = {{0, 0}, {h, h}, {h, 0}, {0, h}, {2 * h, 0}, {h, -h}};
    for (int a = 0; a < 6; ++a) s.x[a] = V{xz[a][0], 0.0, xz[a][1]};
    return s;
}

/// The triangle's terms with its hinges taken from the stencil `x`.
ShellBendingTerms<double> evaluate(double stiffness, const ShellBendingRest<double>& rest, const bool present[3], const V x[6],
                                   const double rest_angle[3]) {
    V p[3][4];
    for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 4; ++a) p[k][a] = x[kHinge[k][a]];
    return shell_bending_evaluate(stiffness, rest, present, p, rest_angle);
}

void gradient(const ShellBendingTerms<double>& t, V g[6]) {
    for (int a = 0; a < 6; ++a) g[a] = V{};
    for (int k = 0; k < 3; ++k)
        if (t.active[k])
            for (int a = 0; a < 4; ++a) g[kHinge[k][a]] += t.force_angle[k] * t.dtheta[k][a];
}

void gauss_newton(double stiffness, const ShellBendingRest<double>& rest, const ShellBendingTerms<double>& t, M H[6][6]) {
    for (int a = 0; a < 6; ++a)
        for (int b = 0; b < 6; ++b) H[a][b] = M{};
    for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) {
            if (!t.active[k] || !t.active[l]) continue;
            const double c = shell_bending_coupling(stiffness, rest, k, l);
            for (int a = 0; a < 4; ++a)
                for (int b = 0; b < 4; ++b) H[kHinge[k][a]][kHinge[l][b]] += c * M::outer(t.dtheta[k][a], t.dtheta[l][b]);
        }
}

Stencil random_stencil(std::mt19937& rng) {
    Stencil s = grid_triangle(0.1);
    std::uniform_real_distribution<double> jitter(-0.02, 0.02);
    for (V& p : s.x) p += V{jitter(rng), 0.5 * jitter(rng), jitter(rng)};
    return s;
}

TEST(ShellBending, RestDataIsSymmetricPositiveAndZeroForADegenerateTriangle) {
    const Stencil s = grid_triangle(0.1);
    ShellBendingRest<double> r;
    ASSERT_TRUE(shell_bending_rest(s.x[0], s.x[1], s.x[2], r));
    EXPECT_NEAR(r.area, 0.005, 1e-15);
    for (int k = 0; k < 3; ++k) {
        EXPECT_GT(r.m[k][k], 0.0);
        for (int l = 0; l < 3; ++l) EXPECT_DOUBLE_EQ(r.m[k][l], r.m[l][k]);
    }
    // The legs are perpendicular: no coupling between their angles; each leg with the hypotenuse
    // (t·t)² = ½.
    EXPECT_NEAR(r.m[1][2], 0.0, 1e-12);
    EXPECT_NEAR(r.m[0][1], 0.5 * std::sqrt(r.m[0][0] * r.m[1][1]), 1e-9);
    // Positive semi-definite: all leading minors ≥ 0 (a Gram matrix).
    const double det2 = r.m[0][0] * r.m[1][1] - r.m[0][1] * r.m[1][0];
    EXPECT_GE(det2, -1e-9 * r.m[0][0] * r.m[1][1]);
    ShellBendingRest<double> degenerate;
    EXPECT_FALSE(shell_bending_rest(V{0, 0, 0}, V{1, 0, 0}, V{2, 0, 0}, degenerate));
    EXPECT_EQ(degenerate.area, 0.0);
    EXPECT_EQ(degenerate.m[0][0], 0.0);
}

TEST(ShellBending, GradientAndGaussNewtonHessianMatchFiniteDifferences) {
    std::mt19937 rng(7);
    const bool all[3] = {true, true, true};
    for (int trial = 0; trial < 20; ++trial) {
        const Stencil rest_shape = grid_triangle(0.1);
        ShellBendingRest<double> rest;
        ASSERT_TRUE(shell_bending_rest(rest_shape.x[0], rest_shape.x[1], rest_shape.x[2], rest));
        const Stencil s = random_stencil(rng);
        const double stiffness = 1e-3;
        const double rest_angle[3] = {0.05, -0.1, 0.02};
        const auto energy = [&](const V y[6]) { return evaluate(stiffness, rest, all, y, rest_angle).energy; };
        V g[6], fd[6];
        gradient(evaluate(stiffness, rest, all, s.x, rest_angle), g);
        fd_gradient<6>(energy, s.x, fd);
        EXPECT_LT(max_abs_diff<6>(g, fd), 1e-6 * max_abs<6>(fd) + 1e-12) << "trial " << trial;
        // At the rest angles the angles' second derivatives drop out: Gauss–Newton is the Hessian.
        double at_rest[3];
        {
            const auto t = evaluate(stiffness, rest, all, s.x, rest_angle);
            for (int k = 0; k < 3; ++k) at_rest[k] = rest_angle[k] + t.angle[k];
        }
        M H[6][6], J[6][6];
        gauss_newton(stiffness, rest, evaluate(stiffness, rest, all, s.x, at_rest), H);
        fd_jacobian<6>([&](const V y[6], V out[6]) { gradient(evaluate(stiffness, rest, all, y, at_rest), out); }, s.x, J);
        EXPECT_LT(max_abs_diff<6>(H, J), 1e-5 * max_abs<6>(J)) << "trial " << trial;
    }
}

TEST(ShellBending, RigidMotionsChangeNothingAndTheForcesBalance) {
    std::mt19937 rng(11);
    const bool all[3] = {true, true, true};
    const Stencil rest_shape = grid_triangle(0.1);
    ShellBendingRest<double> rest;
    ASSERT_TRUE(shell_bending_rest(rest_shape.x[0], rest_shape.x[1], rest_shape.x[2], rest));
    const Stencil s = random_stencil(rng);
    const double rest_angle[3] = {0.0, 0.0, 0.0};
    const auto t = evaluate(1.0, rest, all, s.x, rest_angle);
    ASSERT_GT(t.energy, 0.0);
    const double c = std::cos(0.7), sn = std::sin(0.7);
    M R{};
    R.m[0][0] = c;
    R.m[0][1] = -sn;
    R.m[1][0] = sn;
    R.m[1][1] = c;
    R.m[2][2] = 1.0;
    V moved[6];
    for (int a = 0; a < 6; ++a) moved[a] = R * s.x[a] + V{0.3, -2.0, 5.0};
    EXPECT_NEAR(evaluate(1.0, rest, all, moved, rest_angle).energy, t.energy, 1e-12 * t.energy);
    V g[6];
    gradient(t, g);
    V sum{};
    for (const V& f : g) sum += f;
    EXPECT_LT(length(sum), 1e-10 * max_abs<6>(g));
}

TEST(ShellBending, AMissingHingeAddsNothing) {
    std::mt19937 rng(3);
    const Stencil rest_shape = grid_triangle(0.1);
    ShellBendingRest<double> rest;
    ASSERT_TRUE(shell_bending_rest(rest_shape.x[0], rest_shape.x[1], rest_shape.x[2], rest));
    const Stencil s = random_stencil(rng);
    const bool two[3] = {true, false, true};
    const bool all[3] = {true, true, true};
    const double rest_angle[3] = {0.0, 0.0, 0.0};
    const auto without = evaluate(1.0, rest, two, s.x, rest_angle);
    // The same as a hinge whose angle sits at its rest angle.
    double flat_middle[3] = {0.0, 0.0, 0.0};
    flat_middle[1] = evaluate(1.0, rest, all, s.x, rest_angle).angle[1];
    const auto at_rest = evaluate(1.0, rest, all, s.x, flat_middle);
    EXPECT_FALSE(without.active[1]);
    EXPECT_NEAR(without.energy, at_rest.energy, 1e-14);
    EXPECT_NEAR(without.force_angle[0], at_rest.force_angle[0], 1e-14);
    EXPECT_NEAR(without.force_angle[2], at_rest.force_angle[2], 1e-14);
}

// The calibration: a grid triangle and its neighbours on a cylinder of curvature κ about either grid
// axis give the plate energy ½·D·κ²·A, to rounding (the hinge across the bend folds by exactly κh).
TEST(ShellBending, AGridTriangleOnACylinderHasThePlateEnergy) {
    const double h = 0.02, kappa = 3.0, stiffness = 2e-4;
    const Stencil flat = grid_triangle(h);
    ShellBendingRest<double> rest;
    ASSERT_TRUE(shell_bending_rest(flat.x[0], flat.x[1], flat.x[2], rest));
    const bool all[3] = {true, true, true};
    const double rest_angle[3] = {0.0, 0.0, 0.0};
    for (const bool about_z : {true, false}) {
        V x[6];
        for (int a = 0; a < 6; ++a) {
            const double u = about_z ? flat.x[a].x : flat.x[a].z;  // the coordinate the bend runs along
            const double along = std::sin(kappa * u) / kappa, up = (1.0 - std::cos(kappa * u)) / kappa;
            x[a] = about_z ? V{along, up, flat.x[a].z} : V{flat.x[a].x, up, along};
        }
        const double energy = evaluate(stiffness, rest, all, x, rest_angle).energy;
        const double plate = 0.5 * stiffness * kappa * kappa * rest.area;
        EXPECT_NEAR(energy / plate, 1.0, 1e-9) << (about_z ? "about z" : "about x");
    }
}

// The mid-edge model's reading at scale 1 and offset 0 is the shell model, to the bit.
TEST(MidEdgeBending, ANeutralReadingIsTheShellModel) {
    std::mt19937 rng(7);
    const Stencil flat = grid_triangle(0.1);
    ShellBendingRest<double> rest;
    ASSERT_TRUE(shell_bending_rest(flat.x[0], flat.x[1], flat.x[2], rest));
    const bool all[3] = {true, true, true};
    const double rest_angle[3] = {0.0, 0.05, 0.0};
    const Stencil s = random_stencil(rng);
    V p[3][4];
    for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 4; ++a) p[k][a] = s.x[kHinge[k][a]];
    const ShellReading<double> neutral;
    const auto plain = shell_bending_evaluate(1e-3, rest, all, p, rest_angle);
    const auto read = shell_bending_evaluate(1e-3, rest, all, p, rest_angle, &neutral);
    EXPECT_EQ(plain.energy, read.energy);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(plain.force_angle[k], read.force_angle[k]);
}

// With a reading (scales and offsets), the gradient is the energy's: finite differences.
TEST(MidEdgeBending, GradientWithAReadingMatchesFiniteDifferences) {
    std::mt19937 rng(11);
    const Stencil flat = grid_triangle(0.1);
    ShellBendingRest<double> rest;
    ASSERT_TRUE(shell_bending_rest(flat.x[0], flat.x[1], flat.x[2], rest));
    const bool all[3] = {true, true, true};
    const double rest_angle[3] = {0.0, 0.0, 0.0};
    ShellReading<double> reading;
    reading.scale[1] = 2.0;
    reading.scale[2] = 0.0;
    reading.offset[0] = 0.03;
    reading.offset[1] = -0.02;
    const Stencil s = random_stencil(rng);
    const auto energy = [&](const V x[6]) {
        V p[3][4];
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 4; ++a) p[k][a] = x[kHinge[k][a]];
        return shell_bending_evaluate(1e-3, rest, all, p, rest_angle, &reading);
    };
    const auto t = energy(s.x);
    V g[6];
    gradient(t, g);
    const double eps = 1e-7;
    for (int a = 0; a < 6; ++a)
        for (int c = 0; c < 3; ++c) {
            V plus[6], minus[6];
            for (int b = 0; b < 6; ++b) plus[b] = minus[b] = s.x[b];
            plus[a][c] += eps;
            minus[a][c] -= eps;
            const double fd = (energy(plus).energy - energy(minus).energy) / (2.0 * eps);
            EXPECT_NEAR(g[a][c], fd, 1e-6 * (1.0 + std::abs(fd))) << "vertex " << a << " axis " << c;
        }
}

// A boundary edge's normal is free: the condensed coupling gives, for any readings of the other
// edges, the energy minimised over the boundary edge's reading (and never more than with it at 0,
// the shell model's boundary).
TEST(MidEdgeBending, ABoundaryEdgesFreeNormalIsCondensedOut) {
    const Stencil flat = grid_triangle(0.1);
    ShellBendingRest<double> rest;
    ASSERT_TRUE(shell_bending_rest(flat.x[0], flat.x[1], flat.x[2], rest));
    const auto quad = [&](const ShellBendingRest<double>& r, const double psi[3]) {
        double e = 0.0;
        for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l) e += 0.5 * psi[k] * r.m[k][l] * psi[l];
        return e;
    };
    for (int boundary = 0; boundary < 3; ++boundary) {
        bool present[3] = {true, true, true};
        present[boundary] = false;
        const ShellBendingRest<double> condensed = midedge_condensed_rest(rest, present);
        for (int k = 0; k < 3; ++k) EXPECT_EQ(condensed.m[boundary][k], 0.0);
        double psi[3] = {0.3, -0.2, 0.1};
        psi[boundary] = 0.0;
        // The minimum over the free reading, by its stationarity condition.
        double coupling = 0.0;
        for (int l = 0; l < 3; ++l) coupling += rest.m[boundary][l] * psi[l];
        double best[3] = {psi[0], psi[1], psi[2]};
        best[boundary] = -coupling / rest.m[boundary][boundary];
        EXPECT_NEAR(quad(condensed, psi), quad(rest, best), 1e-12 * quad(rest, psi)) << "boundary edge " << boundary;
        EXPECT_LT(quad(condensed, psi), quad(rest, psi));
    }
    const bool none[3] = {false, false, false};
    const ShellBendingRest<double> lone = midedge_condensed_rest(rest, none);
    for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) EXPECT_EQ(lone.m[k][l], 0.0);
}

}  // namespace
}  // namespace weft::physics::test
