#pragma once
/// @file
/// The levels of the multilevel additive Schwarz preconditioner (Wu, Wang & Wang 2022,
/// docs/methods.md §2b), built once per topology and shared by the backends (backend kit): both
/// backends read the same tables, so their hierarchies are identical by construction.
///
/// Level 0's nodes are the vertices in Morton order of their rest positions (node p is the vertex
/// `order[p]`). At every level, a domain is a run of kDomainSize consecutive nodes. The nodes of
/// level l + 1 are the connected pieces of the domains of level l (pieces of a domain that the
/// matrix does not couple become separate coarse nodes: one coarse value for two unconnected
/// patches would tie them together and spoil the coarse correction), numbered domain by domain,
/// each domain's pieces in the order of their first node.
///
/// The preconditioner a backend builds on it is M⁻¹ = Σ_l R_lᵀ D_l⁻¹ R_l, with R_l the
/// piecewise-constant aggregation from vertices to the nodes of level l (a node's value is the sum
/// over its vertices; prolongation copies it back), A_l = R_l A R_lᵀ the aggregated 3×3 blocks and
/// D_l the block diagonal of A_l over the domains of level l (dense, 3·kDomainSize square). Each D_l
/// is SPD when A is, so M⁻¹ is SPD: a valid CG preconditioner.
///
/// Every step the backends compute A_l from the assembled matrix with fixed sums (no atomics,
/// the same bits on every run): the coupling blocks of level l ≥ 1 are sums of listed coupling blocks
/// of level l − 1, and those of level 1 are sums of listed blocks of A (its pattern slots).

#include <cstdint>
#include <span>
#include <vector>

#include "weft/fabric.h"
#include "weft/types.h"

namespace weft {

struct SchwarzLevel {
    std::uint32_t nodes = 0;
    /// node → its node of the next level (empty on the last level).
    std::vector<std::uint32_t> parent;
    /// Size domains + 1: the nodes of the next level made from domain d are
    /// [parent_start[d], parent_start[d + 1]) (empty on the last level).
    std::vector<std::uint32_t> parent_start;
    /// Level ≥ 1: the coupling blocks of A_l, one per coupled pair of nodes (row, column), and the
    /// blocks summed into each: entries [source_start[e], source_start[e + 1]) of `source`, which are
    /// pattern slots of A at level 1 and coupling entries of level l − 1 above. Empty at level 0,
    /// whose coupling blocks are A's own (its pattern slots).
    std::vector<std::uint32_t> entry_row, entry_column;
    std::vector<std::uint32_t> source_start, source;
    /// The coupling entries (pattern slots at level 0) whose two nodes share a domain, and where each
    /// lands: block (domain·kDomainSize + a)·kDomainSize + b of the domains' dense matrices (in
    /// increasing block order, so each domain's entries are one run).
    std::vector<std::uint32_t> dense_entry, dense_block;

    [[nodiscard]] std::uint32_t domains() const;
};

struct SchwarzHierarchy {
    static constexpr std::uint32_t kDomainBits = 4;
    /// Nodes per domain: 16 nodes make 48×48 dense blocks (9 KB in float): a warp's work, and a
    /// factorisation cheap enough to redo every Newton iteration (docs/methods.md §2b).
    static constexpr std::uint32_t kDomainSize = 1u << kDomainBits;
    static constexpr std::uint32_t kDomainDim = 3 * kDomainSize;  ///< rows of a dense domain matrix

    std::uint32_t vertex_count = 0;
    std::vector<std::uint32_t> order;  ///< order[p] = the vertex at level-0 node p
    std::vector<std::uint32_t> rank;   ///< rank[v] = the level-0 node of vertex v
    std::vector<SchwarzLevel> level;   ///< level 0 first; the last fits one domain or hit max_levels

    [[nodiscard]] int levels() const { return static_cast<int>(level.size()); }
    [[nodiscard]] std::uint32_t nodes(int l) const { return level[static_cast<std::size_t>(l)].nodes; }
    [[nodiscard]] std::uint32_t domains(int l) const { return level[static_cast<std::size_t>(l)].domains(); }
    /// Table entries, for memory accounting (4 bytes each).
    [[nodiscard]] std::size_t index_count() const;
};

/// The hierarchy for vertices at `rest` (m) coupled as `pattern` says (its rows are the vertices):
/// Morton order over their bounding box (ties by index: deterministic), then coarser levels until
/// one domain holds a whole level, at most `max_levels` (≥ 1). Throws weft::Error on a non-finite
/// position or a pattern that does not match the vertices.
[[nodiscard]] SchwarzHierarchy build_schwarz_hierarchy(std::span<const Vec3d> rest, const BlockPattern& pattern,
                                                       int max_levels = 8);

}  // namespace weft
