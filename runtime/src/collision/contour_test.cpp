// Continuous 2D simplicity test of a projected contour (contour_test.h).
#include "collision/contour_test.h"
#include "weft/physics/vec.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace weft::collision {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

struct P2 {
    double x, y;
};

P2 lerp(const double p0[2], const double p1[2], double t) {
    return {p0[0] + t * (p1[0] - p0[0]), p0[1] + t * (p1[1] - p0[1])};
}

double cross2(const P2& o, const P2& a, const P2& b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

/// True when the 8 points provably stay away from the origin: some direction d has d·p > 4τ|d|₁
/// for every point (each point may sit τ off per coordinate, so |d·δp| ≤ τ|d|₁, and the dot
/// products round by far less; NaN compares false). The candidate directions are the inward
/// normals of the points' convex hull (Andrew's monotone chain) and the direction of their mean;
/// how they were found does not matter to soundness, since each is checked on all 8 points.
bool origin_excluded(P2 (&p)[8], double tau) {
    const auto separates = [&](double dx, double dy) {
        const double need = 4.0 * tau * (std::abs(dx) + std::abs(dy));
        for (const P2& q : p)
            if (!(dx * q.x + dy * q.y > need)) return false;
        return true;
    };
    P2 mean{0.0, 0.0};
    for (const P2& q : p) mean = {mean.x + q.x, mean.y + q.y};
    if (separates(mean.x, mean.y)) return true;
    std::sort(std::begin(p), std::end(p), [](const P2& a, const P2& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
    P2 hull[16];
    int k = 0;
    for (int i = 0; i < 8; ++i) {  // lower chain
        while (k >= 2 && cross2(hull[k - 2], hull[k - 1], p[i]) <= 0.0) --k;
        hull[k++] = p[i];
    }
    for (int i = 6, lower = k + 1; i >= 0; --i) {  // upper chain
        while (k >= lower && cross2(hull[k - 2], hull[k - 1], p[i]) <= 0.0) --k;
        hull[k++] = p[i];
    }
    // hull[0..k) runs counter-clockwise and repeats its first point; (−dy, dx) points inwards.
    for (int i = 0; i + 1 < k; ++i) {
        const double dx = hull[i + 1].x - hull[i].x, dy = hull[i + 1].y - hull[i].y;
        if (separates(-dy, dx)) return true;
    }
    return false;
}

/// Continuous test of one edge pair: false when they may touch at some t in [0, 1].
bool pair_separated(const ContourTestScratch::Swept& e, const ContourTestScratch::Swept& f, double tau,
                    ContourTestCounters& counters) {
    struct Interval {
        double t0, t1;
        int depth;
    };
    Interval stack[kContourMaxDepth + 2];
    int top = 0;
    stack[top++] = {0.0, 1.0, 0};
    while (top > 0) {
        const Interval iv = stack[--top];
        ++counters.hull_tests;
        // The gap F(t, λ, μ) = e(t, λ) − f(t, μ) between a point of each edge is multilinear in
        // (t, λ, μ), so over the interval it lies in the hull of its 8 corner values; the edges
        // touch only where F = 0. Working with the difference makes a shared motion cancel.
        P2 corners[8];
        int c = 0;
        for (const double t : {iv.t0, iv.t1}) {
            const P2 a = lerp(e.p[0], e.p[1], t), b = lerp(e.p[2], e.p[3], t);
            const P2 g = lerp(f.p[0], f.p[1], t), h = lerp(f.p[2], f.p[3], t);
            for (const P2& x : {a, b})
                for (const P2& y : {g, h}) corners[c++] = {x.x - y.x, x.y - y.y};
        }
        if (origin_excluded(corners, tau)) continue;
        if (iv.depth == kContourMaxDepth) return false;
        // Dyadic midpoints are exact; the earlier half is examined first.
        const double mid = 0.5 * (iv.t0 + iv.t1);
        stack[top++] = {mid, iv.t1, iv.depth + 1};
        stack[top++] = {iv.t0, mid, iv.depth + 1};
    }
    return true;
}

}  // namespace

bool contour_stays_simple(std::span<const ContourEdge> contour, const Vec3d& axis, std::span<const Vec3d> x0,
                          std::span<const Vec3d> x1, ContourTestScratch& scratch, ContourTestCounters& counters) {
    ++counters.tests;
    const std::size_t m = contour.size();
    counters.edges += m;
    // Basis of the projection plane: u ⟂ axis through the coordinate axis least aligned with it,
    // v = axis × u. The kernel of (u, v) is u × v, within a few ε of the axis (normal_cone.h's
    // margin covers it), so every triangle of a passing patch projects with positive orientation.
    const Vec3d abs_axis{std::abs(axis.x), std::abs(axis.y), std::abs(axis.z)};
    const Vec3d pick = abs_axis.x <= abs_axis.y && abs_axis.x <= abs_axis.z ? Vec3d{1, 0, 0}
                       : abs_axis.y <= abs_axis.z                           ? Vec3d{0, 1, 0}
                                                                            : Vec3d{0, 0, 1};
    const Vec3d u = physics::normalized(physics::cross(axis, pick));
    const Vec3d v = physics::cross(axis, u);
    scratch.swept.resize(m);
    double big = 0.0;
    bool finite = true;
    for (std::size_t i = 0; i < m; ++i) {
        ContourTestScratch::Swept& s = scratch.swept[i];
        const Vec3d* ends[4] = {&x0[contour[i].a], &x1[contour[i].a], &x0[contour[i].b], &x1[contour[i].b]};
        for (int k = 0; k < 4; ++k) {
            const Vec3d& x = *ends[k];
            finite = finite && physics::is_finite(x);
            big = std::max(big, std::max(std::abs(x.x), std::max(std::abs(x.y), std::abs(x.z))));
            s.p[k][0] = physics::dot(u, x);
            s.p[k][1] = physics::dot(v, x);
        }
    }
    if (!finite || !std::isfinite(big) || big > 1e300) {
        ++counters.failed;
        return false;
    }
    const double tau = 128.0 * kEps * big + 1e-300;
    for (std::size_t i = 0; i < m; ++i) {
        ContourTestScratch::Swept& s = scratch.swept[i];
        for (int c = 0; c < 2; ++c) {
            s.lo[c] = std::min(std::min(s.p[0][c], s.p[1][c]), std::min(s.p[2][c], s.p[3][c])) - 2.0 * tau;
            s.hi[c] = std::max(std::max(s.p[0][c], s.p[1][c]), std::max(s.p[2][c], s.p[3][c])) + 2.0 * tau;
        }
    }
    // Sweep along x: (lo.x, index) is a total order, so the pairs examined do not depend on the sort.
    scratch.order.resize(m);
    for (std::size_t i = 0; i < m; ++i) scratch.order[i] = static_cast<std::uint32_t>(i);
    std::sort(scratch.order.begin(), scratch.order.end(), [&](std::uint32_t p, std::uint32_t q) {
        const double a = scratch.swept[p].lo[0], b = scratch.swept[q].lo[0];
        return a != b ? a < b : p < q;
    });
    for (std::size_t k = 0; k < m; ++k) {
        const std::uint32_t i = scratch.order[k];
        const ContourTestScratch::Swept& si = scratch.swept[i];
        const ContourEdge& ei = contour[i];
        for (std::size_t k2 = k + 1; k2 < m; ++k2) {
            const std::uint32_t j = scratch.order[k2];
            const ContourTestScratch::Swept& sj = scratch.swept[j];
            if (sj.lo[0] > si.hi[0]) break;
            if (sj.lo[1] > si.hi[1] || si.lo[1] > sj.hi[1]) continue;
            const ContourEdge& ej = contour[j];
            if (ei.a == ej.a || ei.a == ej.b || ei.b == ej.a || ei.b == ej.b) continue;  // adjacent
            ++counters.box_pairs;
            if (!pair_separated(si, sj, tau, counters)) {
                ++counters.failed;
                return false;
            }
        }
    }
    return true;
}

}  // namespace weft::collision
