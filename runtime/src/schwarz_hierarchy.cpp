// Morton ordering and the connected coarse levels of the additive Schwarz hierarchy
// (weft/backend/schwarz_hierarchy.h).
#include "weft/backend/schwarz_hierarchy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <utility>

#include "weft/error.h"

namespace weft {
namespace {

constexpr std::uint32_t kBits = SchwarzHierarchy::kDomainBits;
constexpr std::uint32_t kMask = SchwarzHierarchy::kDomainSize - 1;

/// The bits of a 21-bit integer spread to every third bit of a 63-bit code.
std::uint64_t spread_bits(std::uint64_t v) {
    v &= 0x1FFFFFu;
    v = (v | v << 32) & 0x1F00000000FFFFull;
    v = (v | v << 16) & 0x1F0000FF0000FFull;
    v = (v | v << 8) & 0x100F00F00F00F00Full;
    v = (v | v << 4) & 0x10C30C30C30C30C3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
}

std::vector<std::uint32_t> morton_order(std::span<const Vec3d> rest) {
    const std::size_t n = rest.size();
    Vec3d lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
    Vec3d hi = -1.0 * lo;
    for (const Vec3d& p : rest) {
        if (!math::is_finite(p)) throw Error("Schwarz hierarchy: a rest position is not finite");
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], p[k]);
            hi[k] = std::max(hi[k], p[k]);
        }
    }
    // One scale for all axes keeps cells cubic, so a run of codes is a compact patch of a sheet.
    double extent = 0.0;
    for (int k = 0; k < 3; ++k) extent = std::max(extent, hi[k] - lo[k]);
    const double scale = extent > 0.0 ? double((1u << 21) - 1) / extent : 0.0;
    std::vector<std::uint64_t> code(n);
    for (std::size_t v = 0; v < n; ++v) {
        std::uint64_t c = 0;
        for (int k = 0; k < 3; ++k) c |= spread_bits(static_cast<std::uint64_t>(std::floor((rest[v][k] - lo[k]) * scale))) << k;
        code[v] = c;
    }
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return code[a] < code[b]; });
    return order;
}

std::uint32_t find_root(std::vector<std::uint32_t>& up, std::uint32_t a) {
    while (up[a] != a) a = up[a] = up[up[a]];
    return a;
}

/// Fills `level`'s dense placement for the couplings (row[e], column[e]) between its nodes and,
/// unless `last`, its parents (the connected pieces of each domain) and the couplings of the next
/// level with their sources. Returns the next level (nodes 0 when `last`).
SchwarzLevel coarsen(SchwarzLevel& level, std::span<const std::uint32_t> row, std::span<const std::uint32_t> column,
                     bool last) {
    const std::size_t entries = row.size();
    std::vector<std::pair<std::uint32_t, std::uint32_t>> dense;  // (block, entry)
    for (std::uint32_t e = 0; e < entries; ++e) {
        const std::uint32_t r = row[e], c = column[e];
        if ((r >> kBits) != (c >> kBits)) continue;
        dense.emplace_back((((r >> kBits) << kBits | (r & kMask)) << kBits) | (c & kMask), e);
    }
    // By block, so each domain's entries are one run (one GPU block fills a domain's matrix).
    std::sort(dense.begin(), dense.end());
    for (const auto& [block, e] : dense) {
        level.dense_block.push_back(block);
        level.dense_entry.push_back(e);
    }
    SchwarzLevel next;
    if (last) return next;
    // Pieces: union of the nodes a coupling inside a domain joins.
    std::vector<std::uint32_t> up(level.nodes);
    std::iota(up.begin(), up.end(), 0u);
    for (std::uint32_t e = 0; e < entries; ++e) {
        const std::uint32_t r = row[e], c = column[e];
        if (r == c || (r >> kBits) != (c >> kBits)) continue;
        const std::uint32_t a = find_root(up, r), b = find_root(up, c);
        if (a != b) up[std::max(a, b)] = std::min(a, b);  // the root is the piece's first node
    }
    level.parent.assign(level.nodes, 0);
    const std::uint32_t domains = level.domains();
    level.parent_start.assign(domains + 1, 0);
    std::uint32_t pieces = 0;
    for (std::uint32_t d = 0; d < domains; ++d) {
        level.parent_start[d] = pieces;
        const std::uint32_t first = d << kBits, end = std::min(level.nodes, first + SchwarzHierarchy::kDomainSize);
        for (std::uint32_t k = first; k < end; ++k) {
            const std::uint32_t root = find_root(up, k);
            // A root comes first in its piece, so it is numbered before its other members look it up.
            level.parent[k] = root == k ? pieces++ : level.parent[root];
        }
    }
    level.parent_start[domains] = pieces;
    next.nodes = pieces;
    // The next level's couplings: one per distinct pair of parents, summing its couplings in order.
    std::vector<std::uint64_t> key(entries);
    for (std::uint32_t e = 0; e < entries; ++e)
        key[e] = std::uint64_t(level.parent[row[e]]) << 32 | level.parent[column[e]];
    std::vector<std::uint32_t> sorted(entries);
    std::iota(sorted.begin(), sorted.end(), 0u);
    std::stable_sort(sorted.begin(), sorted.end(), [&](std::uint32_t a, std::uint32_t b) { return key[a] < key[b]; });
    next.source = sorted;
    for (std::uint32_t k = 0; k < entries; ++k) {
        if (k > 0 && key[sorted[k]] == key[sorted[k - 1]]) continue;
        next.source_start.push_back(k);
        next.entry_row.push_back(static_cast<std::uint32_t>(key[sorted[k]] >> 32));
        next.entry_column.push_back(static_cast<std::uint32_t>(key[sorted[k]] & 0xFFFFFFFFu));
    }
    next.source_start.push_back(static_cast<std::uint32_t>(entries));
    return next;
}

}  // namespace

std::uint32_t SchwarzLevel::domains() const { return (nodes + SchwarzHierarchy::kDomainSize - 1) >> kBits; }

std::size_t SchwarzHierarchy::index_count() const {
    std::size_t count = order.size() + rank.size();
    for (const SchwarzLevel& l : level)
        count += l.parent.size() + l.parent_start.size() + l.entry_row.size() + l.entry_column.size() +
                 l.source_start.size() + l.source.size() + l.dense_entry.size() + l.dense_block.size();
    return count;
}

SchwarzHierarchy build_schwarz_hierarchy(std::span<const Vec3d> rest, const BlockPattern& pattern, int max_levels) {
    if (max_levels < 1) throw Error("Schwarz hierarchy: max_levels = " + std::to_string(max_levels) + " (at least 1)");
    const std::size_t n = rest.size();
    if (n >= std::numeric_limits<std::uint32_t>::max())
        throw Error("Schwarz hierarchy: " + std::to_string(n) + " vertices do not fit 32-bit indices");
    if (pattern.row_start.size() != n + 1 || pattern.row_start.back() != pattern.column.size())
        throw Error("Schwarz hierarchy: the block pattern has " + std::to_string(pattern.row_start.size()) +
                    " row offsets for " + std::to_string(n) + " vertices");
    for (const std::uint32_t j : pattern.column)
        if (j >= n) throw Error("Schwarz hierarchy: the block pattern names column " + std::to_string(j) + " of " + std::to_string(n));
    SchwarzHierarchy h;
    h.vertex_count = static_cast<std::uint32_t>(n);
    h.order = morton_order(rest);
    h.rank.resize(n);
    for (std::uint32_t p = 0; p < n; ++p) h.rank[h.order[p]] = p;

    // Level 0's couplings are A's blocks, between the ranks of their row and column.
    std::vector<std::uint32_t> row(pattern.column.size()), column(pattern.column.size());
    for (std::uint32_t i = 0; i < n; ++i)
        for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s) {
            row[s] = h.rank[i];
            column[s] = h.rank[pattern.column[s]];
        }
    SchwarzLevel current;
    current.nodes = h.vertex_count;
    for (;;) {
        const bool last = current.nodes <= SchwarzHierarchy::kDomainSize || h.levels() + 1 >= max_levels;
        SchwarzLevel next = coarsen(current, row, column, last);
        // A level that barely coarsens (domains of mostly unconnected nodes: many tiny pieces of
        // cloth) would only cost time: stop there instead.
        const bool useless = !last && next.nodes * 4 > current.nodes * 3;
        if (useless) {
            current.parent.clear();
            current.parent_start.clear();
        }
        h.level.push_back(std::move(current));
        if (last || useless) break;
        row = next.entry_row;
        column = next.entry_column;
        current = std::move(next);
    }
    return h;
}

}  // namespace weft
