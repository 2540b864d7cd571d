// Exact orientation predicates: near-degenerate inputs on which plain double evaluation gets the sign
// wrong, checked against references computed independently (__int128 on integer inputs, long double
// where the exact answer is a short sum); coordinates outside the filter's window (the big-integer
// tier); and the three tiers against each other.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "weft/physics/predicates.h"

namespace weft::physics::test {
namespace {

using V3 = Vec3<double>;
using V2 = Vec2<double>;
__extension__ typedef __int128 i128;

int sign_of(i128 x) { return (x > 0) - (x < 0); }
int sign_of(long double x) { return (x > 0.0L) - (x < 0.0L); }
int sign_of(double x) { return (x > 0.0) - (x < 0.0); }

// Plain double evaluation of the same determinant, the way a naive implementation would do it.
int naive_orient3d(V3 a, V3 b, V3 c, V3 d) {
    const V3 u = b - a, v = c - a, w = d - a;
    return sign_of(u.x * (v.y * w.z - v.z * w.y) + v.x * (w.y * u.z - w.z * u.y) + w.x * (u.y * v.z - u.z * v.y));
}
int naive_orient2d(V2 a, V2 b, V2 c) { return sign_of((a.x - c.x) * (b.y - c.y) - (a.y - c.y) * (b.x - c.x)); }

// Exact reference for integer-valued inputs with |coordinate| ≤ 2^40: differences stay below 2^41,
// the six degree-3 terms below 2^123 each, their sum below 2^126.
int reference_orient3d(const std::int64_t a[3], const std::int64_t b[3], const std::int64_t c[3],
                       const std::int64_t d[3]) {
    i128 u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        w[k] = d[k] - a[k];
    }
    const i128 det =
        u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
    return sign_of(det);
}

V3 to_v3(const std::int64_t p[3]) {
    return {static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2])};
}

TEST(Predicates, Orient3dSignConventionAndSymmetries) {
    const V3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
    EXPECT_EQ(orient3d(a, b, c, V3{0, 0, 1}), 1);  // d on the side (b−a)×(c−a) points to
    EXPECT_EQ(orient3d(a, b, c, V3{0.3, 7, -1}), -1);
    EXPECT_EQ(orient3d(a, b, c, V3{5, -3, 0}), 0);
    EXPECT_EQ(orient3d(a, a, c, V3{5, -3, 2}), 0);  // repeated point
    // Odd permutations flip the sign, even ones keep it.
    const V3 d{0.1, 0.2, 0.3};
    EXPECT_EQ(orient3d(b, a, c, d), -1);
    EXPECT_EQ(orient3d(b, c, a, d), 1);
    EXPECT_EQ(orient3d(a, b, d, c), -1);
}

TEST(Predicates, Orient2dSignConvention) {
    EXPECT_EQ(orient2d(V2{0, 0}, V2{1, 0}, V2{0, 1}), 1);  // counter-clockwise
    EXPECT_EQ(orient2d(V2{0, 0}, V2{0, 1}, V2{1, 0}), -1);
    EXPECT_EQ(orient2d(V2{0, 0}, V2{1, 1}, V2{3, 3}), 0);
    EXPECT_EQ(orient2d(V2{2, 2}, V2{2, 2}, V2{2, 2}), 0);
}

// Nearly collinear points with 40-bit integer coordinates: a + k_i·w + e_i with |k_i·w| ~ 2^38 and
// tiny offsets e_i. The exact determinant is ~2^40 while the terms are ~2^115, so the rounding error
// of plain double evaluation (~2^62) swamps it. (For integer coordinates the determinant is only
// this small relative to its terms in such thin configurations.)
TEST(Predicates, Orient3dNearlyCollinearLargeIntegersMatchInt128) {
    std::mt19937_64 rng(12345);
    std::uniform_int_distribution<std::int64_t> base(-(std::int64_t{1} << 38), std::int64_t{1} << 38);
    std::uniform_int_distribution<std::int64_t> dir(-(std::int64_t{1} << 19), std::int64_t{1} << 19);
    std::uniform_int_distribution<std::int64_t> off(-2, 2);
    int naive_wrong = 0, zeros = 0;
    const int n = 20000;
    for (int it = 0; it < n; ++it) {
        std::int64_t w[3], p[4][3];
        for (std::int64_t& x : w) x = dir(rng);
        const std::int64_t a0[3] = {base(rng), base(rng), base(rng)};
        for (auto& pt : p) {
            const std::int64_t k = dir(rng);
            for (int j = 0; j < 3; ++j) pt[j] = a0[j] + k * w[j] + (it % 4 == 0 ? 0 : off(rng));
        }
        const int ref = reference_orient3d(p[0], p[1], p[2], p[3]);
        const V3 a = to_v3(p[0]), b = to_v3(p[1]), c = to_v3(p[2]), d = to_v3(p[3]);
        ASSERT_EQ(orient3d(a, b, c, d), ref) << "iteration " << it;
        // The sign is a property of the four points: permuted arguments must agree.
        ASSERT_EQ(orient3d(b, a, c, d), -ref);
        ASSERT_EQ(orient3d(d, b, c, a), -ref);
        ASSERT_EQ(orient3d(c, d, a, b), ref);
        naive_wrong += naive_orient3d(a, b, c, d) != ref;
        zeros += ref == 0;
    }
    // The cases are genuinely hard: plain doubles get a large share of them wrong.
    EXPECT_GT(naive_wrong, n / 10);
    EXPECT_GT(zeros, 100);
    std::printf("orient3d, nearly collinear 40-bit integers: naive double wrong in %d of %d (%d exact zeros)\n",
                naive_wrong, n, zeros);
}

// Points a, b, c exactly on the tilted plane z = x + y with moderate coordinates, and d within a few
// ulps of it: d = (x, y, fl(x + y) + j·ulp). Then orient3d = sign(n_z)·sign(d.z − d.x − d.y) with
// n = (b−a)×(c−a), and d.z − (d.x + d.y) is exact in long double (64-bit significand).
TEST(Predicates, Orient3dNearlyCoplanarTiltedPlaneMatchesLongDouble) {
    static_assert(std::numeric_limits<long double>::digits >= 64, "the reference needs an 80-bit long double");
    const V3 a{12, 13, 25}, b{-7, 30, 23}, c{24, -5, 19};
    const double nz = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);  // small integers: exact
    ASSERT_NE(nz, 0.0);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> coord(0.5, 1.0);
    std::uniform_int_distribution<int> ulps(-3, 3);
    int naive_wrong = 0, zeros = 0;
    const int n = 20000;
    for (int it = 0; it < n; ++it) {
        const double x = coord(rng), y = coord(rng);
        double z = x + y;
        for (int j = ulps(rng); j != 0; j += j > 0 ? -1 : 1) z = std::nextafter(z, j > 0 ? 4.0 : 0.0);
        const V3 d{x, y, z};
        const long double gap = static_cast<long double>(z) - (static_cast<long double>(x) + y);
        const int ref = sign_of(nz) * sign_of(gap);
        ASSERT_EQ(orient3d(a, b, c, d), ref) << "iteration " << it;
        ASSERT_EQ(orient3d(d, c, b, a), ref);  // an even permutation
        naive_wrong += naive_orient3d(a, b, c, d) != ref;
        zeros += ref == 0;
    }
    EXPECT_GT(naive_wrong, n / 20);
    EXPECT_GT(zeros, 100);
    std::printf("orient3d, within ulps of a tilted plane: naive double wrong in %d of %d (%d exact zeros)\n",
                naive_wrong, n, zeros);
}

// Kettner et al., "Classroom examples of robustness problems in geometric computations" (2008):
// p = (0.5 + i·2^-53, 0.5 + j·2^-53) against the line through (12, 12) and (24, 24). Exactly,
// orient2d(p, q, r) = 12·(p.y − p.x), and p.y − p.x is computed exactly (Sterbenz).
TEST(Predicates, Orient2dKettnerClassroomExample) {
    const V2 q{12, 12}, r{24, 24};
    int naive_wrong = 0, total = 0;
    for (int i = 0; i < 256; ++i)
        for (int j = 0; j < 256; ++j) {
            const V2 p{0.5 + i * 0x1p-53, 0.5 + j * 0x1p-53};
            const int ref = sign_of(p.y - p.x);
            ASSERT_EQ(orient2d(p, q, r), ref) << i << ", " << j;
            ASSERT_EQ(orient2d(q, r, p), ref);
            ASSERT_EQ(orient2d(r, q, p), -ref);
            naive_wrong += naive_orient2d(p, q, r) != ref;
            ++total;
        }
    EXPECT_GT(naive_wrong, total / 10);
    std::printf("orient2d, Kettner's example: naive double wrong in %d of %d\n", naive_wrong, total);
}

// Outside the window of the filter and expansion tiers (|x| > 2^320 or 0 < |x| < 2^-267) the big-integer
// tier answers. Scaling every coordinate by 2^s multiplies the determinant by 2^3s; scaling the x, y
// and z columns by 2^s, 2^t and 2^-(s+t) leaves it unchanged: the sign is known in both cases.
TEST(Predicates, Orient3dExactFarOutsideTheFilterWindow) {
    std::mt19937_64 rng(99);
    std::uniform_int_distribution<std::int64_t> base(-(std::int64_t{1} << 38), std::int64_t{1} << 38);
    std::uniform_int_distribution<std::int64_t> dir(-(std::int64_t{1} << 19), std::int64_t{1} << 19);
    std::uniform_int_distribution<std::int64_t> off(-1, 1);
    const int scales[][3] = {{700, 700, 700},   {-1000, -1000, -1000}, {900, -900, 0},
                             {-1020, 500, 520}, {640, -600, -40},      {-300, -300, -300}};
    int naive_wrong = 0, total = 0;
    for (int it = 0; it < 500; ++it) {
        std::int64_t w[3], p[4][3];
        for (std::int64_t& x : w) x = dir(rng);
        const std::int64_t a0[3] = {base(rng), base(rng), base(rng)};
        for (auto& pt : p) {
            const std::int64_t k = dir(rng);
            for (int j = 0; j < 3; ++j) pt[j] = a0[j] + k * w[j] + off(rng);
        }
        const int ref = reference_orient3d(p[0], p[1], p[2], p[3]);
        for (const auto& s : scales) {
            V3 q[4];
            for (int i = 0; i < 4; ++i)
                for (int k = 0; k < 3; ++k) q[i][k] = std::ldexp(static_cast<double>(p[i][k]), s[k]);  // exact
            ASSERT_EQ(orient3d(q[0], q[1], q[2], q[3]), ref) << it << " scaled by 2^" << s[0];
            ASSERT_EQ(orient3d(q[1], q[0], q[2], q[3]), -ref);
            naive_wrong += naive_orient3d(q[0], q[1], q[2], q[3]) != ref;
            ++total;
        }
    }
    EXPECT_GT(naive_wrong, total / 2);  // overflow to inf/NaN, underflow to 0, or plain rounding
    // Hand-made: huge, tiny and subnormal coordinates side by side.
    const V3 o{0, 0, 0}, bx{1e300, 0, 0}, cy{0, 1e-300, 0};
    const double tiny = std::numeric_limits<double>::denorm_min();
    EXPECT_EQ(orient3d(o, bx, cy, V3{-1e300, 3e-300, tiny}), 1);
    EXPECT_EQ(orient3d(o, bx, cy, V3{1e-300, 1e300, -tiny}), -1);
    EXPECT_EQ(orient3d(o, bx, cy, V3{1e300, -1e-300, 0.0}), 0);
    EXPECT_EQ(orient3d(V3{tiny, 0, 0}, V3{0, tiny, 0}, V3{0, 0, tiny}, V3{0, 0, 0}), -1);
    EXPECT_EQ(orient3d(V3{tiny, 0, 0}, V3{0, tiny, 0}, V3{0, 0, tiny}, V3{tiny, tiny, -tiny}), 0);
    const double big = std::numeric_limits<double>::max();
    EXPECT_EQ(orient3d(V3{-big, -big, -big}, V3{big, -big, -big}, V3{-big, big, -big}, V3{big, big, big}), 1);
    EXPECT_EQ(orient3d(V3{-big, -big, 0}, V3{big, -big, 0}, V3{-big, big, 0}, V3{big, big, -tiny}), -1);
}

TEST(Predicates, Orient2dExactFarOutsideTheFilterWindow) {
    const V2 q{12, 12}, r{24, 24};
    for (const int s : {600, -1000, 1000, -1020})
        for (int i = 0; i < 32; ++i)
            for (int j = 0; j < 32; ++j) {
                const V2 p{0.5 + i * 0x1p-53, 0.5 + j * 0x1p-53};
                const int ref = sign_of(p.y - p.x);
                const auto sc = [s](V2 v) { return V2{std::ldexp(v.x, s), std::ldexp(v.y, s)}; };
                ASSERT_EQ(orient2d(sc(p), sc(q), sc(r)), ref) << s << " " << i << " " << j;
            }
    const double tiny = std::numeric_limits<double>::denorm_min();
    EXPECT_EQ(orient2d(V2{0, 0}, V2{1e300, 0}, V2{-1e300, tiny}), 1);
    EXPECT_EQ(orient2d(V2{0, 0}, V2{1e300, 1e-300}, V2{1e300, 1e-300}), 0);
    EXPECT_EQ(orient2d(V2{tiny, tiny}, V2{2 * tiny, 2 * tiny}, V2{1e300, 1e300}), 0);
    EXPECT_EQ(orient2d(V2{tiny, tiny}, V2{2 * tiny, 2 * tiny}, V2{1e300, 1e300 * (1 + 0x1p-52)}), 1);
}

// The three tiers are independent exact methods (filter, expansions, big integers): they must agree
// wherever each applies. Random points within a few ulps of a random plane with non-integer
// coordinates exercise all of them.
TEST(Predicates, TiersAgreeOnRandomNearDegenerateInputs) {
    std::mt19937_64 rng(2024);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::uniform_int_distribution<int> ulps(-2, 2);
    int filtered_out = 0;
    for (int it = 0; it < 20000; ++it) {
        const double scale = std::ldexp(1.0, static_cast<int>(it % 41) - 20);
        V3 p[4];
        for (int i = 0; i < 3; ++i) p[i] = V3{u(rng), u(rng), u(rng)} * scale;
        const double s = u(rng), t = u(rng);
        p[3] = p[0] + s * (p[1] - p[0]) + t * (p[2] - p[0]);  // on the plane up to rounding
        for (int k = 0; k < 3; ++k)
            for (int j = ulps(rng); j != 0; j += j > 0 ? -1 : 1)
                p[3][k] = std::nextafter(p[3][k], j > 0 ? 10.0 : -10.0);
        if (it % 3 == 0) p[3].z = p[0].z;  // some exactly degenerate structure too
        const int e = predicates_detail::orient3d_expansion(p[0], p[1], p[2], p[3]);
        const int b = predicates_detail::orient3d_bigint(p[0], p[1], p[2], p[3]);
        ASSERT_EQ(e, b) << "iteration " << it;
        ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), b) << "iteration " << it;
        filtered_out += naive_orient3d(p[0], p[1], p[2], p[3]) != b;

        const V2 a2{p[0].x, p[0].y}, b2{p[1].x, p[1].y};
        V2 c2 = a2 + s * (b2 - a2);
        c2.y = std::nextafter(c2.y, ulps(rng) > 0 ? 10.0 : -10.0);
        ASSERT_EQ(predicates_detail::orient2d_expansion(a2, b2, c2), predicates_detail::orient2d_bigint(a2, b2, c2));
        ASSERT_EQ(orient2d(a2, b2, c2), predicates_detail::orient2d_bigint(a2, b2, c2));
    }
    EXPECT_GT(filtered_out, 0);
}

}  // namespace
}  // namespace weft::physics::test
