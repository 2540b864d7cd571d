#pragma once
// Random soups (random_geometry.h) that both broad-phase tests run, the CPU's (tests/solver/
// test_broad_phase.cpp, against brute force) and the GPU's (tests/gpu/test_collision_gpu.cpp,
// against the CPU), and the damage both do to them: non-finite positions, clusters far apart.
#include <cstddef>
#include <cstdint>
#include <limits>

#include "weft/types.h"

namespace weft::test {

/// The arguments of a random soup: seed, lattice size, triangle count, motion and outlier share.
struct SoupCase {
    unsigned seed;
    int lattice;
    std::size_t triangles;
    double motion, outliers;
};

/// From small and still to large, fast and with outliers (the oversized path).
inline constexpr SoupCase kSoupCases[] = {
    {1, 6, 200, 0.0, 0.0},    {2, 8, 800, 0.1, 0.0},     {3, 10, 1500, 0.3, 0.01},
    {4, 12, 3000, 0.05, 0.0}, {5, 12, 3000, 0.5, 0.005}, {6, 14, 2500, 0.2, 0.02},
};

/// The vertices `make_non_finite` spoils.
inline constexpr std::uint32_t kNonFiniteVertices[] = {3, 40, 41};

/// NaN in x1 of vertex 3, +∞ in x0 of vertex 40, −∞ in x1 of vertex 41: primitives a broad phase
/// must skip. `Soup` has x0 and x1 (std::vector<Vec3d>).
template <typename Soup>
void make_non_finite(Soup& s) {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    s.x1[3] = {nan, 0.0, 0.0};
    s.x0[40] = {0.0, inf, 0.0};
    s.x1[41] = {0.0, 0.0, -inf};
}

/// Every other vertex moved 10⁷ m away: with ~1 m cells, more than 2²¹ cells apart, so coordinates
/// are clamped at the border of the cell range.
template <typename Soup>
void split_far_apart(Soup& s) {
    for (std::size_t i = 0; i < s.x0.size(); i += 2) {
        s.x0[i] += Vec3d{1.0e7, -3.0e6, 0.0};
        s.x1[i] += Vec3d{1.0e7, -3.0e6, 0.0};
    }
}

}  // namespace weft::test
