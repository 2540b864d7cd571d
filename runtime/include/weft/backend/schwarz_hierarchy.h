#pragma once
/// @file
/// The levels of the multilevel additive Schwarz preconditioner (Wu, Wang & Wang 2022,
/// docs/methods.md §2b), built once per topology and shared by the backends (backend kit).
///
/// Vertices are put in Morton order of their rest positions, so that runs of consecutive vertices
/// are spatially compact. Level 0's nodes are the vertices; the nodes of level l + 1 are the domains
/// of level l: runs of kDomainSize consecutive nodes (in that order). A vertex at rank p (its place
/// in the order) is therefore node p >> (kDomainBits·l) of level l, in domain p >> (kDomainBits·(l+1)).
/// No tables: the ranks say everything, which is what a GPU kernel (one warp a domain) wants.
///
/// The preconditioner a backend builds on it is M⁻¹ = Σ_l R_lᵀ D_l⁻¹ R_l, with R_l the
/// piecewise-constant aggregation from vertices to the nodes of level l (a node's value is the sum
/// over its vertices; prolongation copies it back), A_l = R_l A R_lᵀ the aggregated 3×3 blocks, and
/// D_l the block diagonal of A_l over the domains of level l (dense, 3·kDomainSize square). Each D_l
/// is SPD when A is, so M⁻¹ is SPD: a valid CG preconditioner.

#include <cstdint>
#include <span>
#include <vector>

#include "weft/types.h"

namespace weft {

struct SchwarzHierarchy {
    static constexpr std::uint32_t kDomainBits = 5;
    static constexpr std::uint32_t kDomainSize = 1u << kDomainBits;  ///< nodes per domain (a warp)

    std::uint32_t vertex_count = 0;
    std::vector<std::uint32_t> order;  ///< order[p] = the vertex at rank p
    std::vector<std::uint32_t> rank;   ///< rank[v] = the place of vertex v in the order
    /// Nodes of each level (level 0: the vertices); the last level fits in one domain.
    std::vector<std::uint32_t> level_nodes;

    [[nodiscard]] int levels() const { return static_cast<int>(level_nodes.size()); }
    /// Domains of level l (the nodes of level l + 1).
    [[nodiscard]] std::uint32_t domains(int level) const {
        return (level_nodes[static_cast<std::size_t>(level)] + kDomainSize - 1) >> kDomainBits;
    }
    /// The node of level `level` that holds the vertex at rank `p`.
    [[nodiscard]] static std::uint32_t node_of(std::uint32_t p, int level) {
        return p >> (kDomainBits * static_cast<std::uint32_t>(level));
    }
};

/// The hierarchy for vertices at `rest` (m): Morton order over their bounding box (ties by index:
/// deterministic), then levels until one domain holds a whole level, at most `max_levels` (≥ 1).
[[nodiscard]] SchwarzHierarchy build_schwarz_hierarchy(std::span<const Vec3d> rest, int max_levels = 6);

}  // namespace weft
