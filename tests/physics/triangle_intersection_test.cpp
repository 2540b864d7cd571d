// Exact triangle–triangle intersection: hand-made configurations (separated, crossing, an edge
// through a face, touching at a vertex or along an edge, coplanar overlap/containment/disjoint/
// touching, degenerate triangles), each checked in every vertex order, both argument orders and
// under exact symmetries of space; touching versus one-ulp misses; and random pairs against an
// independent floating-point separating-axis test wherever that one is decisive.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "weft/physics/triangle_intersection.h"

namespace weft::physics::test {
namespace {

using V3 = Vec3<double>;
using Tri = std::array<V3, 3>;

bool raw(const Tri& a, const Tri& b) { return triangles_intersect(a.data(), b.data()); }

// The answer must not depend on the vertex order of either triangle or on the argument order.
// Returns it (and fails the test if the 72 variants disagree).
bool intersect_all_orders(const Tri& a, const Tri& b) {
    static constexpr int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {1, 0, 2}, {2, 1, 0}};
    const bool first = raw(a, b);
    for (const auto& pa : kPerm)
        for (const auto& pb : kPerm) {
            const Tri a2{a[pa[0]], a[pa[1]], a[pa[2]]};
            const Tri b2{b[pb[0]], b[pb[1]], b[pb[2]]};
            EXPECT_EQ(raw(a2, b2), first);
            EXPECT_EQ(raw(b2, a2), first);
        }
    return first;
}

// Exact symmetries of space on coordinates that are small binary fractions: the 48 signed axis
// permutations, followed by a translation and a power-of-two scale (all exact here).
Tri transform(const Tri& t, int symmetry, V3 shift, int scale_exp) {
    static constexpr int kAxes[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {1, 0, 2}, {2, 1, 0}};
    const int* axes = kAxes[symmetry % 6];
    const int signs = symmetry / 6;  // 0..7
    Tri r;
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k) {
            const double v = t[i][axes[k]] * ((signs >> k) & 1 ? -1.0 : 1.0);
            r[i][k] = std::ldexp(v + shift[k], scale_exp);
        }
    return r;
}

// The expected answer in all orders and under all 48 symmetries with a few shifts and scales.
void expect_intersect(const Tri& a, const Tri& b, bool expected, const char* what) {
    SCOPED_TRACE(what);
    EXPECT_EQ(intersect_all_orders(a, b), expected);
    const V3 shifts[] = {{0, 0, 0}, {3, -5, 0.25}, {1024, 4096, -2048}};
    for (int s = 0; s < 48; ++s)
        for (const V3& shift : shifts)
            for (const int e : {0, -7, 30}) {
                const Tri ta = transform(a, s, shift, e), tb = transform(b, s, shift, e);
                ASSERT_EQ(raw(ta, tb), expected) << "symmetry " << s << ", scale 2^" << e;
                ASSERT_EQ(raw(tb, ta), expected) << "symmetry " << s << ", scale 2^" << e;
            }
}

const Tri kBase{V3{0, 0, 0}, V3{4, 0, 0}, V3{0, 4, 0}};  // in z = 0, legs along x and y

TEST(TriangleIntersection, SeparatedTriangles) {
    expect_intersect(kBase, Tri{V3{0, 0, 1}, V3{4, 0, 1}, V3{0, 4, 1}}, false, "parallel planes");
    expect_intersect(kBase, Tri{V3{5, 5, -1}, V3{6, 5, 1}, V3{5, 6, 1}}, false, "crosses the plane beside it");
    expect_intersect(kBase, Tri{V3{3, 3, -1}, V3{3, 3, 1}, V3{5, 1, 0}}, false, "beyond the hypotenuse");
    expect_intersect(kBase, Tri{V3{1, 1, 0.5}, V3{3, 0.5, 2}, V3{0.5, 3, 3}}, false, "hovering above the face");
}

TEST(TriangleIntersection, CrossingTriangles) {
    expect_intersect(kBase, Tri{V3{1, 1, -1}, V3{2, 1, 1}, V3{0.5, 1, 1}}, true, "through the interior");
    expect_intersect(kBase, Tri{V3{1, 1, -1}, V3{1, 1, 1}, V3{6, 6, 6}}, true, "an edge through the face");
    expect_intersect(kBase, Tri{V3{-1, 1, -1}, V3{-1, 1, 1}, V3{3, 1, 0}}, true, "a vertex inside, edge outside");
    expect_intersect(kBase, Tri{V3{-1, 1, -1}, V3{5, 1, -1}, V3{2, 1, 3}}, true, "a face through an edge");
}

TEST(TriangleIntersection, TouchingCountsAsIntersecting) {
    expect_intersect(kBase, Tri{V3{1, 1, 0}, V3{0, 0, 1}, V3{2, 0, 1}}, true, "vertex on the face");
    expect_intersect(kBase, Tri{V3{2, 0, 0}, V3{0, -1, 1}, V3{3, -1, 2}}, true, "vertex on an edge");
    expect_intersect(kBase, Tri{V3{4, 0, 0}, V3{5, 1, 1}, V3{5, -1, 1}}, true, "vertex on a vertex");
    expect_intersect(kBase, Tri{V3{2, -1, 1}, V3{2, 1, -1}, V3{2, -3, -1}}, true, "edge crossing an edge");
    expect_intersect(kBase, Tri{V3{0, 0, 0}, V3{4, 0, 0}, V3{2, -1, 3}}, true, "sharing an edge");
    expect_intersect(kBase, Tri{V3{1, 0, 0}, V3{3, 0, 0}, V3{2, 0, 5}}, true, "an edge along an edge");
    expect_intersect(kBase, Tri{V3{1, 1, 0}, V3{2, 1, 0}, V3{1, 2, 3}}, true, "an edge lying in the face");
}

// Exactness: touching at a point versus missing or crossing by one ulp. Triangle a lies in the
// tilted plane z = x + y (its vertices exactly on it); b has its apex at or next to a point of a.
TEST(TriangleIntersection, TouchingVersusOneUlp) {
    const Tri a{V3{0.125, 0.25, 0.375}, V3{5, 0.5, 5.5}, V3{0.5, 6, 6.5}};
    // Apex exactly on the plane, inside a; the other two vertices of b above the plane.
    const Tri c{V3{0.75, 1.5, 2.25}, V3{-0.25, 1.5, 4.25}, V3{0.75, 0.5, 5.25}};
    EXPECT_TRUE(intersect_all_orders(a, c));
    Tri c_up = c, c_down = c;
    c_up[0].z = std::nextafter(2.25, 10.0);     // just above: b hovers over a
    c_down[0].z = std::nextafter(2.25, -10.0);  // just below: b pierces a
    EXPECT_FALSE(intersect_all_orders(a, c_up));
    EXPECT_TRUE(intersect_all_orders(a, c_down));

    // An apex (x, y, z) with x + y not representable: b meets a iff z ≤ x + y exactly (the sum is
    // exact in long double). fl(x + y) and its two neighbours cover above, below (and on, for the
    // representable case).
    for (const double x : {1.3, 0.7, 1.1})
        for (const double y : {2.1, 0.9, 1.7})
            for (const int step : {-1, 0, 1}) {
                double z = x + y;
                if (step != 0) z = std::nextafter(z, step * 100.0);
                const bool expected = static_cast<long double>(z) <= static_cast<long double>(x) + y;
                const Tri b{V3{x, y, z}, V3{x - 0.25, y, z + 2}, V3{x, y - 0.25, z + 3}};
                EXPECT_EQ(intersect_all_orders(a, b), expected) << x << " + " << y << ", step " << step;
            }

    // A vertex exactly on an edge of a (the hypotenuse x + y = 1 of e_a, in the plane z = x + y),
    // then one ulp off in x either way or one ulp down in z: each of those misses.
    const Tri e_a{V3{0, 0, 0}, V3{1, 0, 1}, V3{0, 1, 1}};
    const Tri e_on{V3{0.5, 0.5, 1}, V3{1, 1, 3}, V3{2, 1, 4}};
    EXPECT_TRUE(intersect_all_orders(e_a, e_on));
    Tri e_out = e_on, e_in = e_on, e_down = e_on;
    e_out[0].x = std::nextafter(0.5, 1.0);   // beyond the edge, so slightly below the plane: misses
    e_in[0].x = std::nextafter(0.5, 0.0);    // inside the edge's line but above the plane: misses
    e_down[0].z = std::nextafter(1.0, 0.0);  // below the plane; b crosses it outside the edge
    EXPECT_FALSE(intersect_all_orders(e_a, e_out));
    EXPECT_FALSE(intersect_all_orders(e_a, e_in));
    EXPECT_FALSE(intersect_all_orders(e_a, e_down));
}

TEST(TriangleIntersection, CoplanarTriangles) {
    expect_intersect(kBase, Tri{V3{1, 1, 0}, V3{5, 1, 0}, V3{1, 5, 0}}, true, "overlapping");
    expect_intersect(kBase, Tri{V3{0.5, 0.5, 0}, V3{1.5, 0.5, 0}, V3{0.5, 1.5, 0}}, true, "one inside the other");
    expect_intersect(kBase, Tri{V3{-1, -1, 0}, V3{8, -1, 0}, V3{-1, 8, 0}}, true, "one containing the other");
    expect_intersect(kBase, Tri{V3{3, 3, 0}, V3{5, 3, 0}, V3{3, 5, 0}}, false, "disjoint, boxes overlap");
    expect_intersect(kBase, Tri{V3{2, 2, 0}, V3{4, 4, 0}, V3{2, 6, 0}}, true, "vertex on the hypotenuse");
    expect_intersect(kBase, Tri{V3{4, 0, 0}, V3{0, 4, 0}, V3{4, 4, 0}}, true, "sharing the hypotenuse");
    expect_intersect(kBase, Tri{V3{4, 0, 0}, V3{6, 0, 0}, V3{5, 1, 0}}, true, "touching at a vertex");
    expect_intersect(kBase, Tri{V3{5, 0, 0}, V3{6, 0, 0}, V3{5, 1, 0}}, false, "collinear edges, apart");
    expect_intersect(kBase, Tri{V3{-1, 2, 0}, V3{5, 2, 0}, V3{2, 9, 0}}, true, "star of David-like crossing");
    // A tilted plane, z = x + 2y, with non-trivial coordinates (all sums exact).
    const Tri a{V3{0, 0, 0}, V3{4, 0, 4}, V3{0, 4, 8}};
    expect_intersect(a, Tri{V3{1, 1, 3}, V3{5, 1, 7}, V3{1, 5, 11}}, true, "tilted, overlapping");
    expect_intersect(a, Tri{V3{3, 3, 9}, V3{5, 3, 11}, V3{3, 5, 13}}, false, "tilted, disjoint");
    expect_intersect(a, Tri{V3{2, 2, 6}, V3{4, 4, 12}, V3{2, 6, 14}}, true, "tilted, touching");
    expect_intersect(a, Tri{V3{2.25, 1.875, 6}, V3{4, 4, 12}, V3{2, 6, 14}}, false, "tilted, just apart");
}

TEST(TriangleIntersection, DegenerateTriangles) {
    // Segments (three collinear vertices, the middle one listed anywhere).
    expect_intersect(kBase, Tri{V3{1, 1, -1}, V3{1, 1, 1}, V3{1, 1, 0.5}}, true, "segment through the face");
    expect_intersect(kBase, Tri{V3{1, 1, 1}, V3{1, 1, 3}, V3{1, 1, 2}}, false, "segment above the face");
    expect_intersect(kBase, Tri{V3{1, 1, 0}, V3{1, 1, 3}, V3{1, 1, 2}}, true, "segment ending on the face");
    expect_intersect(kBase, Tri{V3{-1, 1, 0}, V3{1, 1, 0}, V3{0, 1, 0}}, true, "segment in the plane across an edge");
    expect_intersect(kBase, Tri{V3{-3, 1, 0}, V3{-1, 1, 0}, V3{-2, 1, 0}}, false, "segment in the plane, outside");
    expect_intersect(kBase, Tri{V3{5, -1, 0}, V3{-1, 5, 0}, V3{2, 2, 0}}, true, "segment along the hypotenuse");
    // Points (three equal vertices).
    expect_intersect(kBase, Tri{V3{1, 1, 0}, V3{1, 1, 0}, V3{1, 1, 0}}, true, "point in the face");
    expect_intersect(kBase, Tri{V3{2, 2, 0}, V3{2, 2, 0}, V3{2, 2, 0}}, true, "point on an edge");
    expect_intersect(kBase, Tri{V3{1, 1, 0.5}, V3{1, 1, 0.5}, V3{1, 1, 0.5}}, false, "point above");
    expect_intersect(kBase, Tri{V3{3, 3, 0}, V3{3, 3, 0}, V3{3, 3, 0}}, false, "point beside, in the plane");
    // Two degenerate triangles.
    const Tri s{V3{0, 0, 0}, V3{4, 4, 4}, V3{2, 2, 2}};
    expect_intersect(s, Tri{V3{0, 4, 0}, V3{4, 0, 4}, V3{2, 2, 2}}, true, "segments crossing");
    expect_intersect(s, Tri{V3{0, 4, 0}, V3{4, 0, 4}, V3{1, 3, 1}}, true, "segments crossing (middle listed)");
    expect_intersect(s, Tri{V3{0, 4, 1}, V3{4, 0, 5}, V3{2, 2, 3}}, false, "skew segments");
    expect_intersect(s, Tri{V3{1, 0, 0}, V3{5, 4, 4}, V3{3, 2, 2}}, false, "parallel segments");
    expect_intersect(s, Tri{V3{3, 3, 3}, V3{6, 6, 6}, V3{5, 5, 5}}, true, "collinear, overlapping");
    expect_intersect(s, Tri{V3{4, 4, 4}, V3{6, 6, 6}, V3{5, 5, 5}}, true, "collinear, touching");
    expect_intersect(s, Tri{V3{5, 5, 5}, V3{6, 6, 6}, V3{5.5, 5.5, 5.5}}, false, "collinear, apart");
    expect_intersect(s, Tri{V3{1, 1, 1}, V3{1, 1, 1}, V3{1, 1, 1}}, true, "point on the segment");
    expect_intersect(s, Tri{V3{1, 1, 2}, V3{1, 1, 2}, V3{1, 1, 2}}, false, "point off the segment");
    const Tri p{V3{1, 2, 3}, V3{1, 2, 3}, V3{1, 2, 3}};
    expect_intersect(p, p, true, "same point");
    expect_intersect(p, Tri{V3{1, 2, 4}, V3{1, 2, 4}, V3{1, 2, 4}}, false, "different points");
    // Two vertices equal: a segment again.
    expect_intersect(kBase, Tri{V3{1, 1, -1}, V3{1, 1, -1}, V3{1, 1, 1}}, true, "repeated vertex, through");
}

// Random pairs against a separating-axis test in plain doubles with the 17 candidate axes (both
// normals, the nine edge×edge cross products, the six in-plane edge normals). Where that test is
// decisive by a clear margin (separated by more than 1e-9, or overlapping by more than 1e-9 along
// every axis), the exact test must agree.
int sat_reference(const Tri& a, const Tri& b) {
    const auto sub = [](V3 p, V3 q) { return p - q; };
    V3 ea[3], eb[3];
    for (int i = 0; i < 3; ++i) {
        ea[i] = sub(a[(i + 1) % 3], a[i]);
        eb[i] = sub(b[(i + 1) % 3], b[i]);
    }
    const V3 na = cross(ea[0], ea[1]), nb = cross(eb[0], eb[1]);
    V3 axes[17];
    int n = 0;
    axes[n++] = na;
    axes[n++] = nb;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) axes[n++] = cross(ea[i], eb[j]);
    for (int i = 0; i < 3; ++i) {
        axes[n++] = cross(na, ea[i]);
        axes[n++] = cross(nb, eb[i]);
    }
    double worst = -1e300;  // largest normalised gap over the axes
    for (const V3& axis : axes) {
        const double len = length(axis);
        if (len < 1e-6) continue;  // nearly parallel edges: not a reliable axis
        double alo = 1e300, ahi = -1e300, blo = 1e300, bhi = -1e300;
        for (int i = 0; i < 3; ++i) {
            const double pa = dot(axis, a[i]) / len, pb = dot(axis, b[i]) / len;
            alo = std::min(alo, pa);
            ahi = std::max(ahi, pa);
            blo = std::min(blo, pb);
            bhi = std::max(bhi, pb);
        }
        worst = std::max(worst, std::max(blo - ahi, alo - bhi));
    }
    if (worst > 1e-9) return 0;   // separated
    if (worst < -1e-9) return 1;  // overlapping along every axis (the set is complete): intersecting
    return -1;                    // too close to call in floating point
}

TEST(TriangleIntersection, RandomPairsAgreeWithFloatingPointSeparatingAxes) {
    std::mt19937_64 rng(31337);
    std::uniform_real_distribution<double> centre(-1.0, 1.0), offset(-0.8, 0.8);
    int decided = 0, hits = 0;
    for (int it = 0; it < 40000; ++it) {
        Tri t[2];
        for (Tri& tri : t) {
            const V3 c{centre(rng) * 0.5, centre(rng) * 0.5, centre(rng) * 0.5};
            for (V3& v : tri) v = c + V3{offset(rng), offset(rng), offset(rng)};
        }
        const int ref = sat_reference(t[0], t[1]);
        if (ref < 0) continue;
        ++decided;
        hits += ref;
        ASSERT_EQ(raw(t[0], t[1]), ref == 1) << "iteration " << it;
        ASSERT_EQ(raw(t[1], t[0]), ref == 1) << "iteration " << it;
    }
    EXPECT_GT(decided, 39000);
    EXPECT_GT(hits, 5000);
    EXPECT_LT(hits, decided - 5000);
}

// Lattice triangles (coordinates in {0, 1, 2}) are full of degeneracies: shared vertices, edges and
// faces, coplanar pairs, collinear and repeated vertices. The answer must not change under the
// exact symmetries and with the vertices reordered.
TEST(TriangleIntersection, LatticeTrianglesAreConsistent) {
    std::mt19937_64 rng(5);
    std::uniform_int_distribution<int> coord(0, 2);
    int hits = 0;
    for (int it = 0; it < 3000; ++it) {
        Tri t[2];
        for (Tri& tri : t)
            for (V3& v : tri) v = V3{double(coord(rng)), double(coord(rng)), double(coord(rng))};
        const bool r = intersect_all_orders(t[0], t[1]);
        hits += r;
        const int s = it % 48;
        ASSERT_EQ(raw(transform(t[0], s, V3{0.5, -3, 7}, -3), transform(t[1], s, V3{0.5, -3, 7}, -3)), r);
    }
    EXPECT_GT(hits, 300);
    EXPECT_LT(hits, 2700);
}

}  // namespace
}  // namespace weft::physics::test
