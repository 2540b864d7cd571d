#pragma once
/// @file
/// The primitives and pair lists of cloth collision detection, shared by the CPU reference
/// (runtime/src/collision/) and the GPU stages (backend kit): edges, vertex–face and edge–edge pairs,
/// and the "no patch" id of normal-cone culling (docs/collisions.md).

#include <compare>
#include <cstdint>
#include <span>
#include <vector>

#include "weft/types.h"

namespace weft::collision {

/// An undirected mesh edge; `v[0] < v[1]` (global vertex ids).
struct Edge {
    std::uint32_t v[2]{};
};

/// The unique edges of `triangles`, each with v[0] < v[1], sorted by (v[0], v[1]). Deterministic.
/// Throws `weft::Error` for a triangle with a repeated vertex.
[[nodiscard]] std::vector<Edge> build_edges(std::span<const Triangle> triangles);

/// A vertex whose bound overlaps a triangle's bound (indices into the positions and triangles).
struct VertexFacePair {
    std::uint32_t vertex = 0;
    std::uint32_t triangle = 0;
    friend auto operator<=>(const VertexFacePair&, const VertexFacePair&) = default;
};

/// Two edges whose bounds overlap; `a < b` (indices into the edge list).
struct EdgeEdgePair {
    std::uint32_t a = 0;
    std::uint32_t b = 0;
    friend auto operator<=>(const EdgeEdgePair&, const EdgeEdgePair&) = default;
};

/// "No patch": a primitive with this patch id is never culled.
inline constexpr std::uint32_t kNoPatch = 0xFFFFFFFFU;

}  // namespace weft::collision
