// One part's share of the multilevel Schwarz preconditioner (weft/backend/part_schwarz.h).
#include "weft/backend/part_schwarz.h"

#include <algorithm>
#include <limits>
#include <string>

#include "weft/error.h"

namespace weft {
namespace {

constexpr std::uint32_t kAbsent = std::numeric_limits<std::uint32_t>::max();
constexpr std::uint32_t kBits = SchwarzHierarchy::kDomainBits;

}  // namespace

PartSchwarz extract_part_schwarz(const SchwarzHierarchy& whole, const PartModel& part) {
    PartSchwarz out;
    const std::uint32_t owned = part.owned;
    const std::size_t local = part.global_vertex.size();
    if (whole.levels() == 0) throw Error("extract_part_schwarz: an empty hierarchy");
    if (owned == 0) throw Error("extract_part_schwarz: the part owns no vertices");
    std::uint32_t first = kAbsent, last = 0;  // the part's level-0 nodes in the whole order
    for (std::uint32_t i = 0; i < owned; ++i) {
        const std::uint32_t g = part.global_vertex[i];
        if (g >= whole.vertex_count) throw Error("extract_part_schwarz: vertex " + std::to_string(g) + " past the hierarchy");
        first = std::min(first, whole.rank[g]);
        last = std::max(last, whole.rank[g]);
    }
    SchwarzHierarchy& h = out.levels;
    h.vertex_count = owned;
    h.rank.assign(local, 0);
    const SchwarzLevel& w0 = whole.level[0];
    SchwarzLevel l0;
    {
        const std::uint32_t end = last + 1;
        if (end - first != owned || (first & ((1u << kBits) - 1)) != 0 ||
            ((end & ((1u << kBits) - 1)) != 0 && end != whole.vertex_count))
            throw Error("extract_part_schwarz: the part's " + std::to_string(owned) + " vertices are not whole level-0 domains "
                        "(nodes " + std::to_string(first) + " to " + std::to_string(end) + ")");
        out.first_domain = first >> kBits;
        std::vector<std::uint32_t> local_of(whole.vertex_count, kAbsent);
        for (std::uint32_t i = 0; i < owned; ++i) local_of[part.global_vertex[i]] = i;
        h.order.resize(owned);
        for (std::uint32_t p = 0; p < owned; ++p) {
            h.order[p] = local_of[whole.order[first + p]];
            h.rank[h.order[p]] = p;
        }
        l0.nodes = owned;
        const std::uint32_t domains = l0.domains();
        // Level 0's couplings are pattern slots: the whole's slot → the part's slot, for owned rows.
        std::vector<std::uint32_t> slot_of(part.global_slot.empty() ? 0 : *std::max_element(part.global_slot.begin(), part.global_slot.end()) + 1,
                                           kAbsent);
        const BlockPattern& lp = part.model.pattern;
        for (std::uint32_t s = 0; s < lp.row_start[owned]; ++s) slot_of[part.global_slot[s]] = s;
        const auto local_slot = [&](std::uint32_t global) {
            if (global >= slot_of.size() || slot_of[global] == kAbsent)
                throw Error("extract_part_schwarz: pattern slot " + std::to_string(global) + " is not in the part's owned rows");
            return slot_of[global];
        };
        // The dense entries of the part's domains: one run of the whole's (sorted by block).
        const std::uint32_t block_begin = out.first_domain << (2 * kBits), block_end = (out.first_domain + domains) << (2 * kBits);
        const auto lo = std::lower_bound(w0.dense_block.begin(), w0.dense_block.end(), block_begin);
        const auto hi = std::lower_bound(w0.dense_block.begin(), w0.dense_block.end(), block_end);
        for (auto it = lo; it != hi; ++it) {
            const auto k = static_cast<std::size_t>(it - w0.dense_block.begin());
            l0.dense_block.push_back(*it - block_begin);
            l0.dense_entry.push_back(local_slot(w0.dense_entry[k]));
        }
        if (whole.levels() > 1) {
            l0.parent.assign(w0.parent.begin() + first, w0.parent.begin() + end);
            l0.parent_start.assign(w0.parent_start.begin() + out.first_domain, w0.parent_start.begin() + out.first_domain + domains + 1);
            out.node_begin = l0.parent_start.front();
            out.node_end = l0.parent_start.back();
            // Level 1's entries of the part's row nodes (sorted by row), their sources in local slots.
            SchwarzLevel l1 = whole.level[1];
            const auto rows_lo = std::lower_bound(l1.entry_row.begin(), l1.entry_row.end(), out.node_begin);
            const auto rows_hi = std::lower_bound(l1.entry_row.begin(), l1.entry_row.end(), out.node_end);
            out.entry_begin = static_cast<std::uint32_t>(rows_lo - l1.entry_row.begin());
            out.entry_end = static_cast<std::uint32_t>(rows_hi - l1.entry_row.begin());
            const SchwarzLevel& w1 = whole.level[1];
            l1.source_start.clear();
            l1.source.clear();
            for (std::uint32_t e = out.entry_begin; e < out.entry_end; ++e) {
                l1.source_start.push_back(static_cast<std::uint32_t>(l1.source.size()));
                for (std::uint32_t k = w1.source_start[e]; k < w1.source_start[e + 1]; ++k) l1.source.push_back(local_slot(w1.source[k]));
            }
            l1.source_start.push_back(static_cast<std::uint32_t>(l1.source.size()));
            h.level.push_back(std::move(l0));
            h.level.push_back(std::move(l1));
            for (int l = 2; l < whole.levels(); ++l) h.level.push_back(whole.level[static_cast<std::size_t>(l)]);
            return out;
        }
    }
    h.level.push_back(std::move(l0));  // one level: nothing above level 0
    return out;
}

}  // namespace weft
