#pragma once
// An axis-aligned box as a closed triangle mesh, for tests that need a mesh collider with an inside.
#include <cstdint>

#include "weft/mesh.h"

namespace weft::test {

/// Appends the box [lo, hi] to `m`: 8 vertices and 12 triangles wound counter-clockwise seen from
/// outside (so that its inside has winding number +1).
inline void add_box(MeshData& m, Vec3d lo, Vec3d hi) {
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    for (int k = 0; k < 8; ++k) m.positions.push_back({(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z});
    const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        m.triangles.push_back({{base + q[0], base + q[1], base + q[2]}});
        m.triangles.push_back({{base + q[0], base + q[2], base + q[3]}});
    }
}

}  // namespace weft::test
