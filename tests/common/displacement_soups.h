#pragma once
// Triangle soups for the displacement-bound tests (CPU reference and GPU twin): stacked sheets and
// random intersection-free soups, and random moves of their vertices.

#include <cstdint>
#include <random>
#include <vector>

#include "collision/intersection_check.h"
#include "weft/mesh.h"
#include "weft/types.h"

namespace weft::test {

struct Soup {
    std::vector<Vec3d> x;
    std::vector<Triangle> triangles;
};

/// `sheets` square sheets of `cells`² cells, 1 m wide, stacked `gap` m apart along z.
inline Soup stacked_sheets(int sheets, int cells, double gap) {
    Soup s;
    const MeshData grid = make_grid(1.0, 1.0, cells, cells);
    for (int k = 0; k < sheets; ++k) {
        const auto offset = static_cast<std::uint32_t>(s.x.size());
        for (Vec3d p : grid.positions) s.x.push_back(p + Vec3d{0.0, 0.0, gap * k});
        for (Triangle t : grid.triangles) {
            for (auto& v : t.v) v += offset;
            s.triangles.push_back(t);
        }
    }
    return s;
}

/// `count` triangles of edge ~`size` m at random in a cube of `extent` m, minus those that intersect.
inline Soup clean_soup(std::mt19937& rng, int count, double size, double extent) {
    std::uniform_real_distribution<double> u(0.0, extent), jitter(-size, size);
    Soup s;
    for (int k = 0; k < count; ++k) {
        const Vec3d c{u(rng), u(rng), u(rng)};
        const auto first = static_cast<std::uint32_t>(s.x.size());
        for (int a = 0; a < 3; ++a) s.x.push_back(c + Vec3d{jitter(rng), jitter(rng), jitter(rng)});
        s.triangles.push_back({{first, first + 1, first + 2}});
    }
    const collision::IntersectionReport report = collision::check_intersections(s.x, s.triangles, {.max_examples = 100000});
    std::vector<char> drop(s.triangles.size(), 0);
    for (const collision::IntersectingPair& p : report.examples) drop[p.a] = drop[p.b] = 1;
    Soup kept;
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
        if (drop[t]) continue;
        const auto first = static_cast<std::uint32_t>(kept.x.size());
        for (const std::uint32_t v : s.triangles[t].v) kept.x.push_back(s.x[v]);
        kept.triangles.push_back({{first, first + 1, first + 2}});
    }
    return kept;
}

/// Every vertex moves by a random vector of length up to `reach` m.
inline std::vector<Vec3d> random_moves(const std::vector<Vec3d>& x, std::mt19937& rng, double reach) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Vec3d> x1 = x;
    for (Vec3d& p : x1) {
        Vec3d d;
        do d = Vec3d{u(rng), u(rng), u(rng)};
        while (math::length(d) > 1.0);
        p += reach * d;
    }
    return x1;
}

}  // namespace weft::test
