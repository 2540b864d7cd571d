#pragma once
/// @file
/// The contour half of the normal-cone test (Volino & Magnenat-Thalmann 1994; docs/methods.md §5):
/// does the contour of a patch, projected onto the plane orthogonal to its cone axis, stay a simple
/// polygon during the whole step? Vertices move linearly from x0 to x1 and the projection is linear,
/// so every projected contour vertex moves linearly in the plane too; the test is a continuous 2D
/// one: no two contour edges that share no vertex may touch at any t in [0, 1].
///
/// Method, conservative throughout (it may refuse a simple contour, never accept a non-simple one):
///  1. Project the end positions of the contour vertices; bound each edge's sweep by a 2D box.
///  2. Sort and sweep the boxes along x; only pairs of non-adjacent edges whose boxes overlap go on.
///  3. For such a pair, over a time interval [t0, t1], the difference between a point of one edge
///     and a point of the other, F(t, λ, μ) = e(t, λ) − f(t, μ), is multilinear in (t, λ, μ) and
///     so lies in the convex hull of its 8 corner values (the argument of physics/ccd.h, in 2D);
///     the edges touch only where F = 0. The origin is excluded when a direction (an inward normal
///     of the corners' hull, or their mean) has every corner on its positive side with margin.
///     Working with the difference makes a motion shared by both edges (a translating or turning
///     patch) cancel. Not excluded: bisect the interval, down to 2^−kContourMaxDepth; a pair still not
///     excluded there counts as touching.
/// Rounding: every projected, interpolated or subtracted coordinate is within τ = 128·ε·M of its
/// exact value (M the largest coordinate magnitude of the contour's positions; projection, lerp and
/// difference make fewer than 70εM), and an exclusion must exceed 4·τ·|d|₁ along the direction d.
///
/// CUDA: one thread block per contour: step 1 a thread per edge, step 2 a block-wide sort of the
/// box lower bounds, step 3 a thread per candidate pair with a fixed-size interval stack
/// (kContourMaxDepth + 2 entries), an any-pair-failed flag in shared memory for the early exit.

#include <cstddef>
#include <span>
#include <vector>

#include "weft/types.h"

#include "weft/backend/patch_hierarchy.h"

namespace weft::collision {

/// Work done by contour tests (summed over calls by the caller).
struct ContourTestCounters {
    std::size_t tests = 0;       ///< contours tested
    std::size_t edges = 0;       ///< contour edges projected
    std::size_t box_pairs = 0;   ///< non-adjacent edge pairs with overlapping swept boxes
    std::size_t hull_tests = 0;  ///< (pair, time interval) exclusion tests
    std::size_t failed = 0;      ///< contours refused
};

/// Reused buffers of one thread (nothing is allocated once they have grown).
struct ContourTestScratch {
    struct Swept {
        double p[4][2];  // ends a, b at t = 0 and t = 1: a0, a1, b0, b1
        double lo[2], hi[2];
    };
    std::vector<Swept> swept;
    std::vector<std::uint32_t> order;
};

/// Deepest time bisection of one edge pair (2^−12 of the step).
inline constexpr int kContourMaxDepth = 12;

/// True when `contour` (a closed polygon's edges, any order; two edges are adjacent when they share
/// a vertex id), projected along `axis` (unit), has no two non-adjacent edges that touch at any time
/// of the step. False for non-finite positions. `x0`, `x1` are indexed by global vertex id.
[[nodiscard]] bool contour_stays_simple(std::span<const ContourEdge> contour, const Vec3d& axis,
                                        std::span<const Vec3d> x0, std::span<const Vec3d> x1,
                                        ContourTestScratch& scratch, ContourTestCounters& counters);

}  // namespace weft::collision
