// Continuous collision detection and proximity (weft/physics/ccd.h, proximity.h):
//  - degenerate configurations (parallel, coplanar, zero-length and zero-area primitives, contacts
//    on edges and vertices, at t = 0 and t = 1, static pairs), in float and double;
//  - random queries with a contact built in by construction, exactly representable so that the
//    contact is real in exact arithmetic: every one must be reported with toi ≤ t* (no false
//    negatives, grazing contacts included);
//  - random near misses with a known minimum distance (exact by construction for translating
//    primitives, bounded by dense sampling for rotating ones) and pairs separated by a plane: false
//    positives are counted per margin and checked against the bound the header states;
//  - proximity against dense sampling.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "weft/physics/ccd.h"
#include "weft/physics/proximity.h"

namespace weft::physics::test {
namespace {

using Vd = Vec3<double>;
using LD = long double;

template <typename T>
Vec3<T> v3(double x, double y, double z) {
    return {T(x), T(y), T(z)};
}

template <typename T>
const char* scalar_name() {
    return sizeof(T) == sizeof(float) ? "float" : "double";
}

template <typename T>
double t_tol() {
    return double(CcdDefaults<T>::t_tolerance);
}

// ---- helpers shared by the deterministic cases ---------------------------------------------------

/// Vertex–face query from double coordinates.
template <typename T>
CcdResult<T> vf(Vd p0, Vd a0, Vd b0, Vd c0, Vd p1, Vd a1, Vd b1, Vd c1, double eta) {
    return vertex_face_ccd(p0.cast<T>(), a0.cast<T>(), b0.cast<T>(), c0.cast<T>(), p1.cast<T>(), a1.cast<T>(),
                           b1.cast<T>(), c1.cast<T>(), T(eta));
}
/// Edge–edge query from double coordinates.
template <typename T>
CcdResult<T> ee(Vd e00, Vd e10, Vd f00, Vd f10, Vd e01, Vd e11, Vd f01, Vd f11, double eta) {
    return edge_edge_ccd(e00.cast<T>(), e10.cast<T>(), f00.cast<T>(), f10.cast<T>(), e01.cast<T>(), e11.cast<T>(),
                         f01.cast<T>(), f11.cast<T>(), T(eta));
}

/// A hit at a known first contact time t*: toi ≤ t* (the guarantee) and not much earlier (the
/// tolerances; `slack` in units of t).
template <typename T>
void expect_hit_at(const CcdResult<T>& r, double t_star, const char* what, double slack = -1.0) {
    if (slack < 0.0) slack = 20.0 * t_tol<T>();
    EXPECT_TRUE(r.hit) << what << " (" << scalar_name<T>() << ")";
    EXPECT_EQ(r.diag.status, CcdStatus::Contact) << what;
    EXPECT_LE(double(r.toi), t_star) << what << " (" << scalar_name<T>() << ")";
    EXPECT_GE(double(r.toi), t_star - slack) << what << " (" << scalar_name<T>() << ")";
    EXPECT_GE(double(r.toi), 0.0) << what;
    EXPECT_TRUE(std::isfinite(double(r.diag.distance_bound))) << what;
}

template <typename T>
void expect_miss(const CcdResult<T>& r, const char* what) {
    EXPECT_FALSE(r.hit) << what << " (" << scalar_name<T>() << ")";
    EXPECT_EQ(r.diag.status, CcdStatus::Separated) << what;
    EXPECT_EQ(double(r.toi), 1.0) << what;
}

template <typename T>
class CcdDegenerate : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(CcdDegenerate, Scalars);

// Unit right triangle in z = 0 used by most vertex–face cases.
const Vd kA{0, 0, 0}, kB{1, 0, 0}, kC{0, 1, 0};

TYPED_TEST(CcdDegenerate, VertexFaceCrossingsOnFaceEdgeAndVertex) {
    using T = TypeParam;
    // Interior, through the midpoint of edge ab, through vertex a, through vertex c, through the
    // midpoint of the hypotenuse: z from +1 to −1, contact at t = 0.5 exactly.
    const Vd through[] = {{0.25, 0.25, 0}, {0.5, 0, 0}, {0, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0}};
    const char* what[] = {"interior", "edge ab", "vertex a", "vertex c", "hypotenuse"};
    for (int i = 0; i < 5; ++i) {
        const Vd q = through[i];
        expect_hit_at(vf<T>(q + Vd{0, 0, 1}, kA, kB, kC, q + Vd{0, 0, -1}, kA, kB, kC, 0.0), 0.5, what[i]);
        // Oblique approach in the plane of an edge (the vertex slides along the line of edge ab).
        expect_hit_at(vf<T>(q + Vd{-0.5, 0, 0.5}, kA, kB, kC, q + Vd{0.5, 0, -0.5}, kA, kB, kC, 0.0), 0.5, what[i]);
    }
    // Just outside vertex a and edge ab, with eta smaller than the gap: no contact.
    expect_miss(vf<T>(Vd{-0.1, -0.1, 1}, kA, kB, kC, Vd{-0.1, -0.1, -1}, kA, kB, kC, 0.05), "beside vertex a");
    expect_miss(vf<T>(Vd{0.5, -0.1, 1}, kA, kB, kC, Vd{0.5, -0.1, -1}, kA, kB, kC, 0.05), "beside edge ab");
    // … and with eta larger than the gap: contact when the height drops to √(eta² − gap²).
    const double h = std::sqrt(0.15 * 0.15 - 0.1 * 0.1);
    expect_hit_at(vf<T>(Vd{0.5, -0.1, 1}, kA, kB, kC, Vd{0.5, -0.1, -1}, kA, kB, kC, 0.15), 0.5 * (1.0 - h),
                  "beside edge ab within eta");
}

TYPED_TEST(CcdDegenerate, VertexFaceContactAtStartAndEnd) {
    using T = TypeParam;
    // Touching at t = 0 and moving away.
    expect_hit_at(vf<T>(Vd{0.2, 0.2, 0}, kA, kB, kC, Vd{0.2, 0.2, 1}, kA, kB, kC, 0.0), 0.0, "starts on the face");
    // Arriving exactly at t = 1.
    expect_hit_at(vf<T>(Vd{0.2, 0.2, 1}, kA, kB, kC, Vd{0.2, 0.2, 0}, kA, kB, kC, 0.0), 1.0, "ends on the face");
    // Arriving at t = 1 on the boundary (vertex b), moving triangle.
    expect_hit_at(vf<T>(Vd{1, 0, 1}, kA + Vd{0, 0, -1}, kB + Vd{0, 0, -1}, kC + Vd{0, 0, -1}, Vd{1, 0, 0.5},
                        kA + Vd{0, 0, 0.5}, kB + Vd{0, 0, 0.5}, kC + Vd{0, 0, 0.5}, 0.0),
                  1.0, "ends on vertex b, both moving");
    // Stopping short of the face by far more than the tolerances.
    expect_miss(vf<T>(Vd{0.2, 0.2, 1}, kA, kB, kC, Vd{0.2, 0.2, 0.01}, kA, kB, kC, 0.0), "stops short");
    // Stopping within eta at t = 1.
    expect_hit_at(vf<T>(Vd{0.2, 0.2, 1}, kA, kB, kC, Vd{0.2, 0.2, 0.01}, kA, kB, kC, 0.02), 0.98 / 0.99,
                  "ends within eta");
}

TYPED_TEST(CcdDegenerate, StaticPairs) {
    using T = TypeParam;
    const Vd p{0.2, 0.3, 0.05};
    expect_miss(vf<T>(p, kA, kB, kC, p, kA, kB, kC, 0.01), "static vertex-face, separated");
    expect_hit_at(vf<T>(p, kA, kB, kC, p, kA, kB, kC, 0.1), 0.0, "static vertex-face, within eta");
    const Vd on{0.2, 0.3, 0};
    expect_hit_at(vf<T>(on, kA, kB, kC, on, kA, kB, kC, 0.0), 0.0, "static vertex-face, touching, eta = 0");
    const Vd e0{0, 0, 0}, e1{1, 0, 0}, f0{0.5, -1, 0.05}, f1{0.5, 1, 0.05};
    expect_miss(ee<T>(e0, e1, f0, f1, e0, e1, f0, f1, 0.01), "static edge-edge, separated");
    expect_hit_at(ee<T>(e0, e1, f0, f1, e0, e1, f0, f1, 0.1), 0.0, "static edge-edge, within eta");
    const Vd g0{0.5, -1, 0}, g1{0.5, 1, 0};
    expect_hit_at(ee<T>(e0, e1, g0, g1, e0, e1, g0, g1, 0.0), 0.0, "static edge-edge, crossing, eta = 0");
}

TYPED_TEST(CcdDegenerate, VertexFaceDegenerateTriangles) {
    using T = TypeParam;
    // Collinear vertices (zero area): a segment from (0,0,0) to (2,0,0).
    const Vd a{0, 0, 0}, b{1, 0, 0}, c{2, 0, 0};
    expect_hit_at(vf<T>(Vd{1.5, 0, 1}, a, b, c, Vd{1.5, 0, -1}, a, b, c, 0.0), 0.5, "collinear triangle, through");
    expect_miss(vf<T>(Vd{1.5, 0.1, 1}, a, b, c, Vd{1.5, 0.1, -1}, a, b, c, 0.01), "collinear triangle, beside");
    // All three vertices coincide: the triangle is a point.
    const Vd o{0.3, -0.2, 0.1};
    expect_hit_at(vf<T>(o + Vd{-1, 0, 0}, o, o, o, o + Vd{1, 0, 0}, o, o, o, 0.0), 0.5, "point triangle, through");
    expect_miss(vf<T>(o + Vd{-1, 0.1, 0}, o, o, o, o + Vd{1, 0.1, 0}, o, o, o, 0.01), "point triangle, beside");
    // A triangle collapsing to a segment during the step while the vertex reaches the segment.
    expect_hit_at(vf<T>(Vd{0.5, 0.5, 1}, kA, kB, Vd{0, 1, 0}, Vd{0.5, 0, 0}, kA, kB, Vd{1, 0, 0}, 0.0), 1.0,
                  "triangle collapsing onto the vertex's end position");
}

TYPED_TEST(CcdDegenerate, VertexFaceCoplanar) {
    using T = TypeParam;
    // Vertex sliding in the triangle's plane, entering it through edge ab at t = 0.5.
    expect_hit_at(vf<T>(Vd{0.3, -0.5, 0}, kA, kB, kC, Vd{0.3, 0.5, 0}, kA, kB, kC, 0.0), 0.5, "in-plane entry");
    // Sliding in the plane parallel to edge ab, outside the triangle.
    expect_miss(vf<T>(Vd{-0.5, -0.2, 0}, kA, kB, kC, Vd{1.5, -0.2, 0}, kA, kB, kC, 0.01), "in-plane pass");
    // Triangle sliding in its own plane past a static coplanar vertex.
    expect_miss(vf<T>(Vd{0.5, -0.2, 0}, kA, kB, kC, Vd{0.5, -0.2, 0}, kA + Vd{2, 0, 0}, kB + Vd{2, 0, 0},
                      kC + Vd{2, 0, 0}, 0.01),
                "in-plane triangle passing");
}

TYPED_TEST(CcdDegenerate, EdgeEdgeCrossingsAndEndpoints) {
    using T = TypeParam;
    const Vd e0{0, 0, 0}, e1{1, 0, 0};
    // Perpendicular f (along y) dropping through e at t = 0.5, at e's interior, at endpoint e0, and
    // with f's endpoint on e (endpoint–interior) and endpoint–endpoint.
    expect_hit_at(ee<T>(e0, e1, Vd{0.5, -1, 1}, Vd{0.5, 1, 1}, e0, e1, Vd{0.5, -1, -1}, Vd{0.5, 1, -1}, 0.0), 0.5,
                  "interior crossing");
    expect_hit_at(ee<T>(e0, e1, Vd{0, -1, 1}, Vd{0, 1, 1}, e0, e1, Vd{0, -1, -1}, Vd{0, 1, -1}, 0.0), 0.5,
                  "through endpoint e0");
    expect_hit_at(ee<T>(e0, e1, Vd{0.5, 0, 1}, Vd{0.5, 1, 1}, e0, e1, Vd{0.5, 0, -1}, Vd{0.5, 1, -1}, 0.0), 0.5,
                  "f's endpoint on e");
    expect_hit_at(ee<T>(e0, e1, Vd{1, 0, 1}, Vd{1, 1, 1}, e0, e1, Vd{1, 0, -1}, Vd{1, 1, -1}, 0.0), 0.5,
                  "endpoint to endpoint");
    // Passing just beyond e's end.
    expect_miss(ee<T>(e0, e1, Vd{1.1, -1, 1}, Vd{1.1, 1, 1}, e0, e1, Vd{1.1, -1, -1}, Vd{1.1, 1, -1}, 0.05),
                "beyond the end");
    // Contact at t = 0 (moving apart) and exactly at t = 1.
    expect_hit_at(ee<T>(e0, e1, Vd{0.5, -1, 0}, Vd{0.5, 1, 0}, e0, e1, Vd{0.5, -1, 1}, Vd{0.5, 1, 1}, 0.0), 0.0,
                  "touching at t = 0");
    expect_hit_at(ee<T>(e0, e1, Vd{0.5, -1, 1}, Vd{0.5, 1, 1}, e0, e1, Vd{0.5, -1, 0}, Vd{0.5, 1, 0}, 0.0), 1.0,
                  "touching at t = 1");
    expect_miss(ee<T>(e0, e1, Vd{0.5, -1, 1}, Vd{0.5, 1, 1}, e0, e1, Vd{0.5, -1, 0.01}, Vd{0.5, 1, 0.01}, 0.0),
                "stops short");
}

TYPED_TEST(CcdDegenerate, EdgeEdgeParallelAndCoplanar) {
    using T = TypeParam;
    const Vd e0{0, 0, 0}, e1{1, 0, 0};
    // Parallel edges (both along x) approaching along z, overlapping in x: contact at t = 0.5.
    expect_hit_at(ee<T>(e0, e1, Vd{0.25, 0, 1}, Vd{0.75, 0, 1}, e0, e1, Vd{0.25, 0, -1}, Vd{0.75, 0, -1}, 0.0), 0.5,
                  "parallel, overlapping");
    // Anti-parallel (f reversed) and touching end to end.
    expect_hit_at(ee<T>(e0, e1, Vd{2, 0, 1}, Vd{1, 0, 1}, e0, e1, Vd{2, 0, -1}, Vd{1, 0, -1}, 0.0), 0.5,
                  "anti-parallel, end to end");
    // Parallel and collinear at t = 0.5 but with a gap of 0.5 along the line: no contact.
    expect_miss(ee<T>(e0, e1, Vd{1.5, 0, 1}, Vd{2.5, 0, 1}, e0, e1, Vd{1.5, 0, -1}, Vd{2.5, 0, -1}, 0.1),
                "parallel, collinear with a gap");
    // Coplanar (z = 0 throughout): f moves along −y and its endpoint meets e at t = 0.5.
    expect_hit_at(ee<T>(e0, e1, Vd{0.5, 1, 0}, Vd{0.5, 2, 0}, e0, e1, Vd{0.5, -1, 0}, Vd{0.5, 0, 0}, 0.0), 0.5,
                  "coplanar, endpoint onto e");
    // Coplanar, parallel, sliding along each other at a fixed distance 0.2.
    expect_miss(ee<T>(e0, e1, Vd{-1, 0.2, 0}, Vd{0, 0.2, 0}, e0, e1, Vd{2, 0.2, 0}, Vd{3, 0.2, 0}, 0.1),
                "coplanar, parallel sliding");
    // Collinear overlapping from the start.
    expect_hit_at(ee<T>(e0, e1, Vd{0.5, 0, 0}, Vd{1.5, 0, 0}, e0, e1, Vd{0.5, 0, 0}, Vd{1.5, 0, 0}, 0.0), 0.0,
                  "collinear, overlapping, static");
}

TYPED_TEST(CcdDegenerate, EdgeEdgeZeroLength) {
    using T = TypeParam;
    // e collapsed to the point (0.5, 0, 0); f crossing it, and passing beside it.
    const Vd pt{0.5, 0, 0};
    expect_hit_at(ee<T>(pt, pt, Vd{0.5, -1, 1}, Vd{0.5, 1, 1}, pt, pt, Vd{0.5, -1, -1}, Vd{0.5, 1, -1}, 0.0), 0.5,
                  "zero-length e, f through it");
    expect_miss(ee<T>(pt, pt, Vd{0.6, -1, 1}, Vd{0.6, 1, 1}, pt, pt, Vd{0.6, -1, -1}, Vd{0.6, 1, -1}, 0.05),
                "zero-length e, f beside it");
    // Both edges points: point–point.
    const Vd q0{-1, 0, 0}, q1{1, 0, 0};
    expect_hit_at(ee<T>(pt, pt, q0, q0, pt, pt, q1, q1, 0.0), 0.75, "two points meeting");
    expect_miss(
        ee<T>(pt, pt, q0 + Vd{0, 0.1, 0}, q0 + Vd{0, 0.1, 0}, pt, pt, q1 + Vd{0, 0.1, 0}, q1 + Vd{0, 0.1, 0}, 0.05),
        "two points passing");
    // An edge shrinking to zero length exactly at its contact.
    expect_hit_at(ee<T>(Vd{0, 0, 1}, Vd{1, 0, 1}, Vd{0.5, -1, 0}, Vd{0.5, 1, 0}, Vd{0.5, 0, 0}, Vd{0.5, 0, 0},
                        Vd{0.5, -1, 0}, Vd{0.5, 1, 0}, 0.0),
                  1.0, "edge shrinking onto f");
}

TYPED_TEST(CcdDegenerate, ConservativeAnswersWhenOutOfBudgetOrInvalid) {
    using T = TypeParam;
    CcdOptions<T> opt{};
    opt.max_iterations = 1;
    const CcdResult<T> r = vertex_face_ccd(v3<T>(0.25, 0.25, 1), kA.cast<T>(), kB.cast<T>(), kC.cast<T>(),
                                           v3<T>(0.25, 0.25, -1), kA.cast<T>(), kB.cast<T>(), kC.cast<T>(), T(0), opt);
    EXPECT_TRUE(r.hit);
    EXPECT_EQ(r.diag.status, CcdStatus::BudgetExhausted);
    EXPECT_LE(double(r.toi), 0.5);
    const T nan = T(std::nan(""));
    const CcdResult<T> s = edge_edge_ccd(v3<T>(0, 0, 0), v3<T>(1, 0, 0), v3<T>(0, 1, 0), Vec3<T>{nan, T(0), T(0)},
                                         v3<T>(0, 0, 0), v3<T>(1, 0, 0), v3<T>(0, 1, 0), v3<T>(0, 2, 0), T(0));
    EXPECT_TRUE(s.hit);
    EXPECT_EQ(s.diag.status, CcdStatus::NonFinite);
    EXPECT_EQ(double(s.toi), 0.0);
    // A negative eta is read as 0.
    expect_hit_at(vf<T>(Vd{0.2, 0.2, 1}, kA, kB, kC, Vd{0.2, 0.2, -1}, kA, kB, kC, -1.0), 0.5, "negative eta");
}

// ---- random queries with a contact by construction ----------------------------------------------

/// Exactly representable random values: multiples of 2^-bits in [−range, range].
struct Dyadic {
    std::mt19937_64 rng;
    explicit Dyadic(unsigned seed) : rng(seed) {}
    double operator()(int bits, double range) {
        const double scale = std::ldexp(1.0, bits);
        const auto n = static_cast<long long>(range * scale);
        std::uniform_int_distribution<long long> d(-n, n);
        return std::ldexp(double(d(rng)), -bits);
    }
    double unit(int bits) {  // [0, 1]
        std::uniform_int_distribution<long long> d(0, 1LL << bits);
        return std::ldexp(double(d(rng)), -bits);
    }
    Vd vec(int bits, double range) { return Vd{(*this)(bits, range), (*this)(bits, range), (*this)(bits, range)}; }
    int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); }
};

/// Bit budgets of the construction per scalar. Every constructed coordinate is a dyadic rational
/// whose significant bits fit the scalar (float: ≤ 23 bits, checked by round-tripping), so the
/// primitives really touch (within eta) at t* in exact arithmetic on the scalar's inputs.
template <typename T>
struct Bits;
template <>
struct Bits<float> {
    static constexpr int t = 6, uv = 6, pos = 6, tangent = 2;
};
template <>
struct Bits<double> {
    static constexpr int t = 12, uv = 12, pos = 14, tangent = 8;
};

/// t* with t = 0 and t = 1 over-represented (they are the boundary cases).
template <typename T>
double random_t(Dyadic& dy) {
    const int k = dy.pick(10);
    if (k == 0) return 0.0;
    if (k == 1) return 1.0;
    return dy.unit(Bits<T>::t);
}

/// Barycentric (u, v) on the triangle, with edges and vertices over-represented.
template <typename T>
void random_uv(Dyadic& dy, double& u, double& v) {
    u = dy.unit(Bits<T>::uv);
    v = dy.unit(Bits<T>::uv);
    if (u + v > 1.0) {
        u = 1.0 - u;
        v = 1.0 - v;
    }
    switch (dy.pick(8)) {
        case 0:
            u = 0.0;
            break;
        case 1:
            v = 0.0;
            break;
        case 2:
            v = 1.0 - u;
            break;
        case 3:
            u = dy.pick(2) == 0 ? 0.0 : 1.0;
            v = 0.0;
            break;
        case 4:
            u = 0.0;
            v = 1.0;
            break;
        default:
            break;
    }
}

/// Start and end positions of a point at x* at time t* moving with velocity w: exact in double.
void trajectory(Vd x_star, Vd w, double t_star, Vd& x0, Vd& x1) {
    x0 = x_star - t_star * w;
    x1 = x_star + (1.0 - t_star) * w;
}

/// Whether every coordinate survives the cast to T unchanged.
template <typename T>
bool exact_in(const Vd* x, int n) {
    for (int k = 0; k < n; ++k)
        for (int i = 0; i < 3; ++i)
            if (double(T(x[k][i])) != x[k][i]) return false;
    return true;
}

/// |F(t, u, v)| in long double from T-valued inputs (x0, x1: 4 points each, ccd order); exact for the
/// dyadic constructions (64-bit significand).
template <typename T>
LD gap_ld(const Vec3<T> x0[4], const Vec3<T> x1[4], bool vertex_face, double t, double u, double v) {
    LD g[3];
    for (int i = 0; i < 3; ++i) {
        LD x[4];
        for (int k = 0; k < 4; ++k) x[k] = LD(x0[k][i]) + LD(t) * (LD(x1[k][i]) - LD(x0[k][i]));
        g[i] = vertex_face ? x[0] - ((1.0L - LD(u) - LD(v)) * x[1] + LD(u) * x[2] + LD(v) * x[3])
                           : (x[0] + LD(u) * (x[1] - x[0])) - (x[2] + LD(v) * (x[3] - x[2]));
    }
    return std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
}

struct Counts {
    int cases = 0, misses = 0, late = 0, budget = 0, overflow = 0, not_exact = 0, max_iter = 0, max_queue = 0;
    long long iterations = 0;
};

/// One random contact built in: vertex–face (kind 0) or edge–edge (kind 1). Returns false when the
/// construction is not exact in T (not used then).
template <typename T>
bool make_contact(Dyadic& dy, bool vertex_face, Vec3<T> x0[4], Vec3<T> x1[4], double& t_star, double& u_star,
                  double& v_star, double& eta, int* tag = nullptr) {
    constexpr int P = Bits<T>::pos;
    t_star = random_t<T>(dy);
    const double scale = std::ldexp(1.0, dy.pick(5) - 2);  // 1/4 … 4, exact
    const Vd shift = Vd{double(dy.pick(9) - 4), double(dy.pick(9) - 4), double(dy.pick(9) - 4)};
    // eta: 0 (exact touching) in half the cases; otherwise a power of two, with the contact point
    // offset along one axis by a dyadic amount ≤ eta.
    eta = dy.pick(2) == 0 ? 0.0 : std::ldexp(1.0, -(4 + dy.pick(6)));
    Vd offset{};
    if (eta > 0.0) offset[dy.pick(3)] = eta * dy.unit(4) * (dy.pick(2) == 0 ? 1.0 : -1.0);
    const bool grazing = dy.pick(3) == 0;
    int shape_tag = 0;
    Vd s[4], w[4];  // positions at t* and velocities, before scaling and shifting
    if (vertex_face) {
        random_uv<T>(dy, u_star, v_star);
        for (int k = 1; k < 4; ++k) {
            s[k] = dy.vec(P, 1.0);
            w[k] = dy.vec(P, 1.0);
        }
        if (dy.pick(10) == 0) {  // zero-area triangle (two vertices coincide)
            s[3] = s[2];
            shape_tag = 1;
        }
        if (dy.pick(10) == 0) w[1] = w[2] = w[3] = Vd{};  // static triangle
        const Vd q = s[1] + u_star * (s[2] - s[1]) + v_star * (s[3] - s[1]);
        s[0] = q + offset;
        const Vd material = w[1] + u_star * (w[2] - w[1]) + v_star * (w[3] - w[1]);
        // Grazing: the relative velocity at t* lies in the triangle's plane (tangent), so the gap
        // has a double root at t*; otherwise a random crossing velocity.
        w[0] = grazing
                   ? material + dy(Bits<T>::tangent, 1.0) * (s[2] - s[1]) + dy(Bits<T>::tangent, 1.0) * (s[3] - s[1])
                   : dy.vec(P, 1.0);
        if (dy.pick(20) == 0) w[0] = Vd{};  // static vertex
    } else {
        u_star = dy.unit(Bits<T>::uv);
        v_star = dy.unit(Bits<T>::uv);
        if (dy.pick(4) == 0) u_star = double(dy.pick(2));  // endpoint contacts
        if (dy.pick(4) == 0) v_star = double(dy.pick(2));
        const Vd c = dy.vec(P, 1.0);
        Vd de = dy.vec(P, 1.0);
        Vd df = dy.vec(P, 1.0);
        const int shape = dy.pick(10);
        shape_tag = shape <= 1 ? shape + 1 : 0;
        if (shape == 0) df = dy(2, 2.0) * de;  // parallel (or collinear) edges
        if (shape == 1) de = Vd{};             // zero-length edge
        s[0] = c - u_star * de;
        s[1] = c + (1.0 - u_star) * de;
        s[2] = c + offset - v_star * df;
        s[3] = c + offset + (1.0 - v_star) * df;
        w[0] = dy.vec(P, 1.0);
        w[1] = dy.vec(P, 1.0);
        if (grazing) {  // f translates with e's contact point plus a velocity in the edges' plane
            const Vd we = w[0] + u_star * (w[1] - w[0]);
            w[2] = w[3] = we + dy(Bits<T>::tangent, 1.0) * de + dy(Bits<T>::tangent, 1.0) * df;
        } else {
            w[2] = dy.vec(P, 1.0);
            w[3] = dy.vec(P, 1.0);
        }
    }
    Vd a[4], b[4];
    for (int k = 0; k < 4; ++k) {
        trajectory(s[k], w[k], t_star, a[k], b[k]);
        a[k] = scale * a[k] + shift;
        b[k] = scale * b[k] + shift;
    }
    eta *= scale;
    if (tag != nullptr) *tag = (grazing ? 1 : 0) | (eta > 0.0 ? 2 : 0) | (shape_tag << 2);
    if (!exact_in<T>(a, 4) || !exact_in<T>(b, 4)) return false;
    for (int k = 0; k < 4; ++k) {
        x0[k] = a[k].cast<T>();
        x1[k] = b[k].cast<T>();
    }
    return true;
}

template <typename T, int Capacity = 128>
Counts run_known_contacts(bool vertex_face, int n, unsigned seed) {
    Dyadic dy(seed);
    Counts c;
    for (int i = 0; i < n; ++i) {
        Vec3<T> x0[4], x1[4];
        double t_star, u_star, v_star, eta;
        if (!make_contact(dy, vertex_face, x0, x1, t_star, u_star, v_star, eta)) {
            ++c.not_exact;
            continue;
        }
        // The construction must be a real contact in exact arithmetic on the T inputs.
        const LD g = gap_ld(x0, x1, vertex_face, t_star, u_star, v_star);
        EXPECT_LE(g, LD(eta)) << "construction not exact, case " << i;
        const CcdResult<T> r =
            vertex_face ? vertex_face_ccd<T, Capacity>(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], T(eta))
                        : edge_edge_ccd<T, Capacity>(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], T(eta));
        ++c.cases;
        if (!r.hit) ++c.misses;
        if (r.hit && double(r.toi) > t_star) ++c.late;
        if (!r.hit || double(r.toi) > t_star)
            ADD_FAILURE() << (vertex_face ? "vertex-face" : "edge-edge") << " false negative, case " << i
                          << ": t* = " << t_star << " u* = " << u_star << " v* = " << v_star << " eta = " << eta
                          << " hit = " << r.hit << " toi = " << double(r.toi);
        if (r.diag.status == CcdStatus::BudgetExhausted) ++c.budget;
        if (r.diag.status == CcdStatus::QueueOverflow) ++c.overflow;
        c.iterations += r.diag.iterations;
        c.max_iter = std::max(c.max_iter, r.diag.iterations);
        c.max_queue = std::max(c.max_queue, r.diag.max_queue);
    }
    return c;
}

template <typename T>
class CcdRandom : public ::testing::Test {};
TYPED_TEST_SUITE(CcdRandom, Scalars);

TYPED_TEST(CcdRandom, KnownContactsAreNeverMissed) {
    using T = TypeParam;
    constexpr int kCases = 20000;
    for (int kind = 0; kind < 2; ++kind) {
        const auto start = std::chrono::steady_clock::now();
        const Counts c = run_known_contacts<T>(kind == 0, kCases, 1000u + unsigned(kind));
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        std::printf(
            "[ccd %s %s known contacts] %d cases (%d skipped inexact): misses %d, late toi %d, budget "
            "exhausted %d, queue overflow %d, iterations mean %.1f max %d, queue max %d, %.2f us/query\n",
            scalar_name<T>(), kind == 0 ? "vertex-face" : "edge-edge", c.cases, c.not_exact, c.misses, c.late, c.budget,
            c.overflow, double(c.iterations) / c.cases, c.max_iter, c.max_queue, 1e3 * ms / c.cases);
        EXPECT_EQ(c.misses, 0);
        EXPECT_EQ(c.late, 0);
        EXPECT_EQ(c.not_exact, 0);
        EXPECT_GE(c.cases, kCases);
        EXPECT_LE(c.budget + c.overflow, c.cases / 1000);  // conservative answers stay rare
    }
}

TYPED_TEST(CcdRandom, TinyQueueStaysConservative) {
    // A 4-box queue overflows often; the answer must stay conservative (no false negatives, toi ≤ t*).
    using T = TypeParam;
    for (int kind = 0; kind < 2; ++kind) {
        const Counts c = run_known_contacts<T, 4>(kind == 0, 4000, 2000u + unsigned(kind));
        std::printf("[ccd %s %s, 4-box queue] %d cases: misses %d, late %d, queue overflow %d\n", scalar_name<T>(),
                    kind == 0 ? "vertex-face" : "edge-edge", c.cases, c.misses, c.late, c.overflow);
        EXPECT_EQ(c.misses, 0);
        EXPECT_EQ(c.late, 0);
        EXPECT_GT(c.overflow, 0);  // the path is exercised
    }
}

// ---- random near misses with a known minimum distance ------------------------------------------

/// Closest points of a segment [s0, s1] and a triangle (a, b, c), the reference for the near-miss
/// construction: the nearest of the endpoints against the triangle and the segment against the
/// triangle's edges, unless the segment crosses the triangle (`crossing`, distance 0).
struct SegmentTriangle {
    double distance = 1e300;
    Vd on_segment, on_triangle;
    bool crossing = false;
};
SegmentTriangle segment_triangle(Vd s0, Vd s1, Vd a, Vd b, Vd c) {
    SegmentTriangle r;
    auto consider = [&](double dist, Vd ps, Vd pt) {
        if (dist < r.distance) {
            r.distance = dist;
            r.on_segment = ps;
            r.on_triangle = pt;
        }
    };
    for (const Vd s : {s0, s1}) {
        const PointTriangleProximity<double> q = point_triangle_proximity(s, a, b, c);
        consider(q.distance, s, q.closest);
    }
    const Vd edges[3][2] = {{a, b}, {b, c}, {c, a}};
    for (const auto& e : edges) {
        const EdgeEdgeProximity<double> q = edge_edge_proximity(s0, s1, e[0], e[1]);
        consider(q.distance, q.closest_e, q.closest_f);
    }
    const Vd n = cross(b - a, c - a);
    const double h0 = dot(s0 - a, n), h1 = dot(s1 - a, n);
    if ((h0 < 0.0) != (h1 < 0.0)) {
        const Vd x = s0 + (h0 / (h0 - h1)) * (s1 - s0);
        if (point_triangle_proximity(x, a, b, c).distance < 1e-9) r.crossing = true;
    }
    return r;
}

/// A vertex–face (kind 0) or edge–edge (kind 1) pair whose minimum distance over the step is `gap`
/// by construction: in a frame translating with the triangle (or with f), the vertex sweeps a
/// segment (the edge e sweeps a parallelogram), both convex; shifting it along the line between the
/// closest points sets the distance between two convex sets exactly. A common random translation
/// is added to everything. Returns false when the sweep crosses the other primitive.
bool make_near_miss(std::mt19937_64& rng, bool vertex_face, double gap, Vd x0[4], Vd x1[4]) {
    std::uniform_real_distribution<double> U(-1.0, 1.0), U01(0.0, 1.0);
    auto rv = [&] { return Vd{U(rng), U(rng), U(rng)}; };
    const Vd V = rv();  // common translation over the step
    const int style = int(rng() % 3);
    if (vertex_face) {
        const Vd a = rv(), b = rv(), c = rv();
        // The vertex's relative path: sliding over the face at a small height (style 0, the cloth
        // case), passing an edge or a vertex (style 1), or any line (style 2).
        double u = U01(rng), v = U01(rng);
        if (u + v > 1.0) {
            u = 1.0 - u;
            v = 1.0 - v;
        }
        if (style == 1) {
            if (rng() % 2 == 0)
                v = 0.0;
            else
                u = v = 0.0;
        }
        const Vd q = a + u * (b - a) + v * (c - a);
        const Vd nrm = normalized(cross(b - a, c - a));
        Vd w = rv();
        if (style == 0) w = w - dot(w, nrm) * nrm;  // parallel to the face
        const Vd o = style == 0 ? nrm : normalized(rv());
        const double tc = U01(rng);
        Vd s0 = q + 0.1 * o - tc * w, s1 = q + 0.1 * o + (1.0 - tc) * w;
        const SegmentTriangle st = segment_triangle(s0, s1, a, b, c);
        if (st.crossing || !(st.distance > 1e-6)) return false;
        const Vd shift = ((gap - st.distance) / st.distance) * (st.on_segment - st.on_triangle);
        s0 = s0 + shift;
        s1 = s1 + shift;
        x0[0] = s0;
        x1[0] = s1 + V;
        const Vd tri[3] = {a, b, c};
        for (int k = 0; k < 3; ++k) {
            x0[k + 1] = tri[k];
            x1[k + 1] = tri[k] + V;
        }
    } else {
        const Vd e0 = rv(), e1 = rv();
        Vd f0 = rv(), f1 = rv();
        if (style == 0) f1 = f0 + (0.5 + U01(rng)) * (e1 - e0);  // parallel edges
        Vd w = rv();                                             // e's motion relative to f
        if (style == 0 && rng() % 2 == 0) w = w - dot(w, normalized(e1 - e0)) * normalized(e1 - e0);
        // e sweeps the parallelogram (e0, e1, e1 + w, e0 + w): two triangles.
        const SegmentTriangle s1 = segment_triangle(f0, f1, e0, e1, e1 + w);
        const SegmentTriangle s2 = segment_triangle(f0, f1, e0, e1 + w, e0 + w);
        if (s1.crossing || s2.crossing) return false;
        const SegmentTriangle& st = s1.distance <= s2.distance ? s1 : s2;
        if (!(st.distance > 1e-6)) return false;
        const Vd shift = ((gap - st.distance) / st.distance) * (st.on_segment - st.on_triangle);
        f0 = f0 + shift;
        f1 = f1 + shift;
        x0[0] = e0;
        x0[1] = e1;
        x1[0] = e0 + w + V;
        x1[1] = e1 + w + V;
        x0[2] = f0;
        x0[3] = f1;
        x1[2] = f0 + V;
        x1[3] = f1 + V;
    }
    return true;
}

TYPED_TEST(CcdRandom, NearMissFalsePositives) {
    using T = TypeParam;
    constexpr int kCases = 20000;
    constexpr double eps = double(ScalarTraits<T>::epsilon);
    std::mt19937_64 rng(77);
    std::uniform_real_distribution<double> U01(0.0, 1.0);
    for (int kind = 0; kind < 2; ++kind) {
        const bool vertex_face = kind == 0;
        // Per decade of the margin (minimum distance − eta): cases and false positives.
        constexpr int kDecades = 7;  // margin in [1e-7, 1e0)
        int cases[kDecades] = {}, fp[kDecades] = {}, fp_conservative = 0, beyond_bound = 0, not_separated = 0;
        long long iterations = 0;
        int max_iter = 0;
        double ms = 0.0;
        for (int i = 0; i < kCases; ++i) {
            const double eta = rng() % 2 == 0 ? 0.0 : 1e-3;
            const double margin = std::pow(10.0, -7.0 + 6.0 * U01(rng));  // log-uniform in [1e-7, 1e-1]
            Vd a[4], b[4];
            if (!make_near_miss(rng, vertex_face, eta + margin, a, b)) {
                --i;
                continue;
            }
            Vec3<T> x0[4], x1[4];
            double M = 0.0, extent = 0.0, maxd = 0.0;
            for (int k = 0; k < 4; ++k) {
                x0[k] = a[k].cast<T>();
                x1[k] = b[k].cast<T>();
                for (int ax = 0; ax < 3; ++ax) {
                    M = std::max({M, std::fabs(a[k][ax]), std::fabs(b[k][ax])});
                    maxd = std::max(maxd, std::fabs(double(x1[k][ax]) - double(x0[k][ax])));
                }
            }
            for (int ax = 0; ax < 3; ++ax) {
                double mn = 1e300, mx = -1e300;
                for (int k = 0; k < 4; ++k) {
                    mn = std::min({mn, double(x0[k][ax]), double(x1[k][ax])});
                    mx = std::max({mx, double(x0[k][ax]), double(x1[k][ax])});
                }
                extent = std::max(extent, mx - mn);
            }
            // Lower bound on the minimum distance of the inputs as rounded to T: rounding moves each
            // input coordinate by ≤ ε/2·M, so any point of F by ≤ 4 such moves per coordinate.
            const double lower = eta + margin - 4.0 * std::sqrt(3.0) * eps * M - 1e-13;
            if (!(lower > eta)) {
                ++not_separated;
                continue;
            }
            const int decade = std::min(kDecades - 1, std::max(0, int(std::floor(std::log10(lower - eta))) + 7));
            ++cases[decade];
            const auto start = std::chrono::steady_clock::now();
            const CcdResult<T> r = vertex_face
                                       ? vertex_face_ccd(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], T(eta))
                                       : edge_edge_ccd(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], T(eta));
            ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
            iterations += r.diag.iterations;
            max_iter = std::max(max_iter, r.diag.iterations);
            if (!r.hit) continue;
            ++fp[decade];
            // distance_bound is a rigorous bound on the distance at contact_time, which is ≥ lower.
            EXPECT_LE(lower, double(r.diag.distance_bound)) << "case " << i;
            if (r.diag.status != CcdStatus::Contact) {
                ++fp_conservative;
                continue;
            }
            // The header's bound on distance_bound for status Contact.
            const double tt = t_tol<T>();
            const double delta = double(r.diag.error_bound);
            const double bound = (eta + std::sqrt(3.0) * (2.0 * tt * extent + 8.0 * delta + tt * 4.0 * maxd)) * 1.001;
            if (double(r.diag.distance_bound) > bound) ++beyond_bound;
        }
        int total = 0, total_fp = 0;
        std::printf("[ccd %s %s near misses] false positives by margin (min distance − eta):", scalar_name<T>(),
                    vertex_face ? "vertex-face" : "edge-edge");
        for (int d = 0; d < kDecades; ++d) {
            std::printf(" [1e%d,1e%d): %d/%d", d - 7, d - 6, fp[d], cases[d]);
            total += cases[d];
            total_fp += fp[d];
        }
        std::printf(
            "\n[ccd %s %s near misses] %d cases (%d closed by rounding), %d false positives (%.2f%%), %d of "
            "them conservative (budget/overflow), iterations mean %.1f max %d, %.2f us/query\n",
            scalar_name<T>(), vertex_face ? "vertex-face" : "edge-edge", total, not_separated, total_fp,
            100.0 * total_fp / total, fp_conservative, double(iterations) / total, max_iter, 1e3 * ms / total);
        EXPECT_EQ(beyond_bound, 0);
        // No false positive beyond the header's bound, eta + √3·(2·t_tolerance·extent + 8δ +
        // t_tolerance·D) with extent ≈ 3 and D ≤ 4·1.5 here: ≈ 2.3e-3 in float, 2e-5 in double. So
        // none from margin 1e-2 on in float and from 1e-4 on in double.
        const int clean_from = sizeof(T) == sizeof(float) ? 5 : 3;
        for (int dec = clean_from; dec < kDecades; ++dec) EXPECT_EQ(fp[dec], 0) << "margin decade 1e" << dec - 7;
        // Budget or queue exhaustion: rare.
        EXPECT_LE(fp_conservative, total / 500);
    }
}

// Near misses under general motion (rotating, deforming primitives): no exact reference, so the
// minimum distance is bounded from below by sampling t densely, d(t) being Lipschitz in t with
// constant L = Σ|x1 − x0| over the 4 points (so min d ≥ min over samples − L/(2N)). Configurations
// are random, then shifted so that the sampled minimum becomes eta plus a margin ≥ 1e-3.
TYPED_TEST(CcdRandom, RotatingNearMissFalsePositives) {
    using T = TypeParam;
    constexpr int kCases = 2000, kSamples = 4000;
    std::mt19937_64 rng(79);
    std::uniform_real_distribution<double> U(-1.0, 1.0), U01(0.0, 1.0);
    auto sampled = [&](bool vf, const Vd a[4], const Vd b[4], double& best_t, Vd& best_gap) {
        double best = 1e300;
        for (int s = 0; s <= kSamples; ++s) {
            const double t = double(s) / kSamples;
            Vd x[4];
            for (int k = 0; k < 4; ++k) x[k] = a[k] + t * (b[k] - a[k]);
            Vd gap;
            if (vf) {
                const PointTriangleProximity<double> q = point_triangle_proximity(x[0], x[1], x[2], x[3]);
                gap = x[0] - q.closest;
            } else {
                const EdgeEdgeProximity<double> q = edge_edge_proximity(x[0], x[1], x[2], x[3]);
                gap = q.closest_e - q.closest_f;
            }
            if (length(gap) < best) {
                best = length(gap);
                best_t = t;
                best_gap = gap;
            }
        }
        return best;
    };
    for (int kind = 0; kind < 2; ++kind) {
        const bool vertex_face = kind == 0;
        int cases = 0, fp = 0, fp_conservative = 0;
        long long iterations = 0;
        for (int i = 0; i < kCases; ++i) {
            const double eta = i % 2 == 0 ? 0.0 : 1e-3;
            const double margin = std::pow(10.0, -3.0 + 2.0 * U01(rng));  // log-uniform in [1e-3, 1e-1]
            Vd a[4], b[4];
            for (int k = 0; k < 4; ++k) {
                a[k] = Vd{U(rng), U(rng), U(rng)};
                b[k] = a[k] + 0.5 * Vd{U(rng), U(rng), U(rng)};
            }
            double t_min;
            Vd gap;
            const double d = sampled(vertex_face, a, b, t_min, gap);
            if (!(d > 1e-9)) continue;
            // Move the vertex (or edge e) along the gap so that the sampled minimum is eta + margin.
            const Vd shift = ((eta + margin - d) / d) * gap;
            const int moved = vertex_face ? 1 : 2;
            for (int k = 0; k < moved; ++k) {
                a[k] = a[k] + shift;
                b[k] = b[k] + shift;
            }
            Vec3<T> x0[4], x1[4];
            double L = 0.0, M = 0.0;
            for (int k = 0; k < 4; ++k) {
                x0[k] = a[k].cast<T>();
                x1[k] = b[k].cast<T>();
                L += length(b[k] - a[k]);
                for (int ax = 0; ax < 3; ++ax) M = std::max({M, std::fabs(a[k][ax]), std::fabs(b[k][ax])});
            }
            const double lower = sampled(vertex_face, a, b, t_min, gap) - L / (2.0 * kSamples) -
                                 4.0 * std::sqrt(3.0) * double(ScalarTraits<T>::epsilon) * M;
            if (!(lower > eta)) continue;
            ++cases;
            const CcdResult<T> r = vertex_face
                                       ? vertex_face_ccd(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], T(eta))
                                       : edge_edge_ccd(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], T(eta));
            iterations += r.diag.iterations;
            if (!r.hit) continue;
            ++fp;
            if (r.diag.status != CcdStatus::Contact) ++fp_conservative;
            EXPECT_LE(lower, double(r.diag.distance_bound)) << "case " << i;
        }
        std::printf(
            "[ccd %s %s rotating near misses, margin 1e-3..1e-1] %d cases, %d false positives (%d "
            "conservative), iterations mean %.1f\n",
            scalar_name<T>(), vertex_face ? "vertex-face" : "edge-edge", cases, fp, fp_conservative,
            double(iterations) / cases);
        EXPECT_GE(cases, kCases / 2);
        // Float resolves ~3e-4 (t_tolerance·extent), double far below the smallest margin here.
        EXPECT_LE(fp, sizeof(T) == sizeof(float) ? cases / 100 : 0);
    }
}

// Separated by a fixed plane with a margin (the simple construction): all excluded, quickly.
TYPED_TEST(CcdRandom, PlaneSeparatedNeverHit) {
    using T = TypeParam;
    std::mt19937_64 rng(78);
    std::uniform_real_distribution<double> U(-1.0, 1.0), U01(0.0, 1.0);
    for (int kind = 0; kind < 2; ++kind) {
        const bool vertex_face = kind == 0;
        int hits = 0, total = 0;
        for (int i = 0; i < 5000; ++i) {
            const Vd n = normalized(Vd{U(rng), U(rng), U(rng)});
            const double eta = i % 2 == 0 ? 0.0 : 1e-3;
            const double half = 0.5 * (eta + (sizeof(T) == sizeof(float) ? 1e-2 : 1e-4));
            Vec3<T> x0[4], x1[4];
            for (int k = 0; k < 8; ++k) {
                const int point = k % 4;
                const double side = vertex_face ? (point == 0 ? 1.0 : -1.0) : (point < 2 ? 1.0 : -1.0);
                Vd x{U(rng), U(rng), U(rng)};
                x = x - dot(x, n) * n + (side * (half + (i % 3 == 0 ? 0.0 : 0.3 * U01(rng)))) * n;
                (k < 4 ? x0[point] : x1[point]) = x.cast<T>();
            }
            const CcdResult<T> r = vertex_face
                                       ? vertex_face_ccd(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], T(eta))
                                       : edge_edge_ccd(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], T(eta));
            ++total;
            hits += r.hit ? 1 : 0;
        }
        std::printf("[ccd %s %s plane-separated] %d cases, %d hits\n", scalar_name<T>(),
                    vertex_face ? "vertex-face" : "edge-edge", total, hits);
        EXPECT_EQ(hits, 0);
    }
}

// ---- proximity ---------------------------------------------------------------------------------------

/// Random triangle, often degenerate (sliver, collinear, coincident vertices).
Vd random_point(std::mt19937_64& rng) {
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    return Vd{U(rng), U(rng), U(rng)};
}

TEST(Proximity, PointTriangleMatchesDenseSampling) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> U01(0.0, 1.0);
    constexpr int N = 160;  // samples per edge
    for (int trial = 0; trial < 1500; ++trial) {
        Vd a = random_point(rng), b = random_point(rng), c = random_point(rng);
        switch (trial % 6) {
            case 1:
                c = a + U01(rng) * (b - a);
                break;  // collinear
            case 2:
                c = b;
                break;  // two vertices coincide
            case 3:
                b = c = a;
                break;  // a point
            case 4:
                c = a + 0.5 * (b - a) + 1e-9 * random_point(rng);
                break;  // sliver
            default:
                break;
        }
        Vd p = random_point(rng);
        if (trial % 5 == 0) p = a + 0.3 * (b - a) + 0.2 * (c - a);  // on the triangle
        const PointTriangleProximity<double> r = point_triangle_proximity(p, a, b, c);
        ASSERT_TRUE(std::isfinite(r.distance) && std::isfinite(r.u) && std::isfinite(r.v) && is_finite(r.normal));
        EXPECT_GE(r.u, 0.0);
        EXPECT_GE(r.v, 0.0);
        EXPECT_LE(r.u + r.v, 1.0 + 1e-15);
        EXPECT_LE(length(r.closest - ((1.0 - r.u - r.v) * a + r.u * b + r.v * c)), 1e-14);
        EXPECT_NEAR(r.distance, length(p - r.closest), 1e-15);
        EXPECT_NEAR(length(r.normal), 1.0, 1e-14);
        if (r.distance > 1e-12) {
            EXPECT_NEAR(dot(r.normal, p - r.closest), r.distance, 1e-14);
        }
        double best = 1e300;
        for (int i = 0; i <= N; ++i)
            for (int j = 0; i + j <= N; ++j) {
                const double u = double(i) / N, v = double(j) / N;
                best = std::min(best, length(p - ((1.0 - u - v) * a + u * b + v * c)));
            }
        const double diam = std::max({length(b - a), length(c - a), length(c - b)});
        // Never worse than any sample, except on slivers, where the interior solve is ill-conditioned
        // and the answer may come from an edge: off by at most the smallest altitude.
        const double altitude = diam > 0.0 ? length(cross(b - a, c - a)) / diam : 0.0;
        EXPECT_LE(r.distance, best + altitude + 1e-14) << "trial " << trial;
        EXPECT_GE(r.distance, best - diam / N - 1e-14) << "trial " << trial;  // samples are diam/N apart
        // The interior optimum is a projection: the gap is normal to the triangle.
        if (trial % 6 == 0 && r.u > 1e-9 && r.v > 1e-9 && r.u + r.v < 1.0 - 1e-9) {
            EXPECT_NEAR(dot(p - r.closest, b - a), 0.0, 1e-12);
            EXPECT_NEAR(dot(p - r.closest, c - a), 0.0, 1e-12);
        }
    }
}

TEST(Proximity, EdgeEdgeMatchesDenseSampling) {
    std::mt19937_64 rng(6);
    std::uniform_real_distribution<double> U01(0.0, 1.0);
    constexpr int N = 256;
    for (int trial = 0; trial < 600; ++trial) {
        Vd e0 = random_point(rng), e1 = random_point(rng), f0 = random_point(rng), f1 = random_point(rng);
        switch (trial % 7) {
            case 1:
                f1 = f0 + (2.0 * U01(rng) - 1.0) * (e1 - e0);
                break;  // parallel
            case 2:
                f0 = e0 + 0.3 * (e1 - e0);
                f1 = e0 + 1.4 * (e1 - e0);
                break;  // collinear, overlapping
            case 3:
                e1 = e0;
                break;  // zero-length e
            case 4:
                e1 = e0;
                f1 = f0;
                break;  // both points
            case 5:
                f1 = f0 + (e1 - e0) + 1e-10 * random_point(rng);
                break;  // nearly parallel
            case 6: {   // crossing
                const Vd m = e0 + 0.4 * (e1 - e0);
                f0 = m - 0.6 * (f1 - f0);
                f1 = f0 + (m - f0) / 0.6;
            } break;
            default:
                break;
        }
        const EdgeEdgeProximity<double> r = edge_edge_proximity(e0, e1, f0, f1);
        ASSERT_TRUE(std::isfinite(r.distance) && std::isfinite(r.u) && std::isfinite(r.v) && is_finite(r.normal));
        EXPECT_TRUE(r.u >= 0.0 && r.u <= 1.0 && r.v >= 0.0 && r.v <= 1.0);
        EXPECT_LE(length(r.closest_e - (e0 + r.u * (e1 - e0))), 1e-15);
        EXPECT_LE(length(r.closest_f - (f0 + r.v * (f1 - f0))), 1e-15);
        EXPECT_NEAR(r.distance, length(r.closest_e - r.closest_f), 1e-15);
        EXPECT_NEAR(length(r.normal), 1.0, 1e-14);
        if (r.distance > 1e-12) {
            EXPECT_NEAR(dot(r.normal, r.closest_e - r.closest_f), r.distance, 1e-14);
        }
        double best = 1e300;
        for (int i = 0; i <= N; ++i)
            for (int j = 0; j <= N; ++j) {
                const double u = double(i) / N, v = double(j) / N;
                best = std::min(best, length((e0 + u * (e1 - e0)) - (f0 + v * (f1 - f0))));
            }
        const double spacing = (length(e1 - e0) + length(f1 - f0)) / N;
        EXPECT_LE(r.distance, best + 1e-14) << "trial " << trial;
        EXPECT_GE(r.distance, best - spacing - 1e-14) << "trial " << trial;
    }
}

TEST(Proximity, DegenerateQueriesAreFinite) {
    const Vd o{0.1, 0.2, 0.3};
    // Point on a point-triangle, on a collinear triangle, at a zero-length segment; touching and
    // parallel edges: distance 0 or constant, fallback normals unit length.
    const PointTriangleProximity<double> a = point_triangle_proximity(o, o, o, o);
    EXPECT_EQ(a.distance, 0.0);
    EXPECT_NEAR(length(a.normal), 1.0, 1e-15);
    const PointTriangleProximity<double> b =
        point_triangle_proximity(Vd{0.5, 0, 0}, Vd{0, 0, 0}, Vd{1, 0, 0}, Vd{2, 0, 0});
    EXPECT_EQ(b.distance, 0.0);
    EXPECT_NEAR(length(b.normal), 1.0, 1e-15);
    EXPECT_NEAR(dot(b.normal, Vd{1, 0, 0}), 0.0, 1e-15);
    const PointSegmentProximity<double> c = point_segment_proximity(Vd{1, 1, 1}, o, o);
    EXPECT_EQ(c.s, 0.0);
    EXPECT_NEAR(c.distance, length(Vd{1, 1, 1} - o), 1e-15);
    const EdgeEdgeProximity<double> d = edge_edge_proximity(Vd{0, 0, 0}, Vd{1, 0, 0}, Vd{0.5, 0, 0}, Vd{2, 0, 0});
    EXPECT_EQ(d.distance, 0.0);
    EXPECT_NEAR(length(d.normal), 1.0, 1e-15);
    const EdgeEdgeProximity<double> e = edge_edge_proximity(Vd{0, 0, 0}, Vd{1, 0, 0}, Vd{0.2, 0.5, 0}, Vd{0.7, 0.5, 0});
    EXPECT_NEAR(e.distance, 0.5, 1e-15);
    EXPECT_NEAR(dot(e.normal, Vd{0, -1, 0}), 1.0, 1e-15);
    const EdgeEdgeProximity<double> f = edge_edge_proximity(o, o, o, o);
    EXPECT_EQ(f.distance, 0.0);
    EXPECT_NEAR(length(f.normal), 1.0, 1e-15);
    // Perpendicular crossing: the closest points are the crossing.
    const EdgeEdgeProximity<double> g = edge_edge_proximity(Vd{-1, 0, 0}, Vd{1, 0, 0}, Vd{0.5, -1, 1}, Vd{0.5, 1, 1});
    EXPECT_NEAR(g.distance, 1.0, 1e-15);
    EXPECT_NEAR(g.u, 0.75, 1e-15);
    EXPECT_NEAR(g.v, 0.5, 1e-15);
    EXPECT_NEAR(g.normal.z, -1.0, 1e-15);
}

TEST(Proximity, FloatAgreesWithDouble) {
    std::mt19937_64 rng(8);
    double worst_pt = 0.0, worst_ee = 0.0;
    for (int trial = 0; trial < 2000; ++trial) {
        const Vd p = random_point(rng), a = random_point(rng), b = random_point(rng), c = random_point(rng);
        const double dd = point_triangle_proximity(p, a, b, c).distance;
        const float df =
            point_triangle_proximity(p.cast<float>(), a.cast<float>(), b.cast<float>(), c.cast<float>()).distance;
        worst_pt = std::max(worst_pt, std::fabs(double(df) - dd));
        const double ed = edge_edge_proximity(p, a, b, c).distance;
        const float ef =
            edge_edge_proximity(p.cast<float>(), a.cast<float>(), b.cast<float>(), c.cast<float>()).distance;
        worst_ee = std::max(worst_ee, std::fabs(double(ef) - ed));
    }
    std::printf("[proximity float vs double] worst |Δd|: point-triangle %.3g, edge-edge %.3g\n", worst_pt, worst_ee);
    EXPECT_LE(worst_pt, 1e-5);
    EXPECT_LE(worst_ee, 1e-5);
}

}  // namespace
}  // namespace weft::physics::test
