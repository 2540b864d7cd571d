#pragma once
// A strip meshed with its rows at 45° to its axis, for the bending convergence tests and benchmark
// (tests/solver/test_cantilever.cpp, bench/bending_models_bench.cpp): the lattice points
// (p·sx, 0, q·sz) with p + q even, each diamond around an odd point split into two triangles (along
// its x diagonal and its z diagonal in alternation), the diamonds cut by the strip's edges into half
// diamonds. `columns` (even) lattice columns along x, an even number of rows across z with sz ≈ sx,
// every triangle's normal up (+y). Vertices are numbered by column, then row, so the clamp (the first
// two lattice columns) is the first `clamp.size()` vertices; the tip is the last column.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "weft/fabric.h"
#include "weft/physics/vec.h"

namespace weft::test {

struct DiagonalStrip {
    MeshData mesh;
    std::vector<std::uint32_t> clamp, tip;
    double column_step = 0.0;  ///< sx, m
};

inline DiagonalStrip make_diagonal_strip(int columns, double length, double width) {
    DiagonalStrip d;
    d.mesh.source = "diagonal strip";
    const double sx = length / columns;
    int rows = std::max(2, static_cast<int>(std::lround(width / sx)));
    if (rows % 2 != 0) ++rows;
    const double sz = width / rows;
    std::vector<std::int64_t> index(static_cast<std::size_t>((columns + 1) * (rows + 1)), -1);
    const auto at = [&](int p, int q) -> std::int64_t& { return index[static_cast<std::size_t>(p * (rows + 1) + q)]; };
    for (int p = 0; p <= columns; ++p)
        for (int q = 0; q <= rows; ++q)
            if ((p + q) % 2 == 0) {
                at(p, q) = static_cast<std::int64_t>(d.mesh.positions.size());
                d.mesh.positions.push_back({p * sx, 0.0, q * sz});
                if (p <= 1) d.clamp.push_back(static_cast<std::uint32_t>(at(p, q)));
                if (p == columns) d.tip.push_back(static_cast<std::uint32_t>(at(p, q)));
            }
    const auto id = [&](int p, int q) { return static_cast<std::uint32_t>(at(p, q)); };
    const auto inside = [&](int p, int q) { return p >= 0 && p <= columns && q >= 0 && q <= rows; };
    const auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        const auto& x = d.mesh.positions;
        const Vec3d n = physics::cross(x[b] - x[a], x[c] - x[a]);
        d.mesh.triangles.push_back(n.y > 0.0 ? Triangle{{a, b, c}} : Triangle{{a, c, b}});
    };
    for (int p = 0; p <= columns; ++p)
        for (int q = 0; q <= rows; ++q) {
            if ((p + q) % 2 == 0) continue;  // diamonds sit around the odd points
            const bool left = inside(p - 1, q), right = inside(p + 1, q), down = inside(p, q - 1), up = inside(p, q + 1);
            if (left && right && down && up) {
                if (((p + q) / 2) % 2 == 0) {  // along the x diagonal
                    add(id(p - 1, q), id(p + 1, q), id(p, q + 1));
                    add(id(p + 1, q), id(p - 1, q), id(p, q - 1));
                } else {  // along the z diagonal
                    add(id(p, q - 1), id(p, q + 1), id(p - 1, q));
                    add(id(p, q + 1), id(p, q - 1), id(p + 1, q));
                }
            } else if (left && right) {
                add(id(p - 1, q), id(p + 1, q), id(p, down ? q - 1 : q + 1));  // cut by a long edge
            } else if (down && up) {
                add(id(p, q - 1), id(p, q + 1), id(p + (left ? -1 : 1), q));  // cut by the clamped or free end
            }
        }
    d.column_step = sx;
    return d;
}

}  // namespace weft::test
