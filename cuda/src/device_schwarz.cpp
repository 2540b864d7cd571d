// Uploads the additive Schwarz levels (device_schwarz.h): the shared hierarchy's tables in one
// index allocation, the per-step floats in another.
#include "device_schwarz.h"

#include <string>

#include "weft/error.h"

namespace weft::cuda {

void DeviceSchwarz::release() {
    indices_ = {};
    cells_ = {};
    floats_ = {};
    view_ = SchwarzView{};
    hierarchy_ = SchwarzHierarchy{};
    part_ = PartSchwarz{};
}

void DeviceSchwarz::build(const FlatModel& flat, const std::vector<std::uint32_t>& slot_position, MemoryLedger& ledger) {
    release();
    hierarchy_ = build_schwarz_hierarchy(flat.initial_positions, flat.pattern, kSchwarzMaxLevels);
    upload(flat.pattern, slot_position, 0, ledger);
}

void DeviceSchwarz::build_part(PartSchwarz part, const BlockPattern& pattern, const std::vector<std::uint32_t>& slot_position,
                               MemoryLedger& ledger) {
    release();
    part_ = std::move(part);
    hierarchy_ = std::move(part_.levels);
    part_.levels = SchwarzHierarchy{};
    upload(pattern, slot_position, part_.entry_begin, ledger);
}

void DeviceSchwarz::upload(const BlockPattern& pattern, const std::vector<std::uint32_t>& slot_position,
                           std::uint32_t level1_entry_begin, MemoryLedger& ledger) {
    const SchwarzHierarchy& h = hierarchy_;

    // Tables: appended to one host vector; offsets become pointers after the upload.
    std::vector<std::uint32_t> table;
    std::vector<std::uint8_t> cells;
    const auto append = [&](const std::vector<std::uint32_t>& v) {
        const std::size_t at = table.size();
        table.insert(table.end(), v.begin(), v.end());
        return at;
    };
    std::vector<std::uint32_t> slot_row(pattern.column.size());
    for (std::uint32_t i = 0; i + 1 < pattern.row_start.size(); ++i)
        for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s) slot_row[s] = i;
    const std::size_t order_at = append(h.order), rank_at = append(h.rank), position_at = append(slot_position),
                      row_at = append(slot_row), column_at = append(pattern.column);

    struct Offsets {
        std::size_t parent, parent_start, source_start, source, dense_start, dense_entry, cells;
        std::size_t coupling, inverse, values, solved;
    };
    std::vector<Offsets> at(static_cast<std::size_t>(h.levels()));
    std::size_t floats = 0;
    for (int l = 0; l < h.levels(); ++l) {
        const SchwarzLevel& level = h.level[static_cast<std::size_t>(l)];
        Offsets& o = at[static_cast<std::size_t>(l)];
        o.parent = append(level.parent);
        o.parent_start = append(level.parent_start);
        o.source_start = append(level.source_start);
        o.source = append(level.source);
        std::vector<std::uint32_t> dense_start(level.domains() + 1, 0);
        for (const std::uint32_t block : level.dense_block) ++dense_start[(block >> (2 * SchwarzHierarchy::kDomainBits)) + 1];
        for (std::size_t d = 0; d < level.domains(); ++d) dense_start[d + 1] += dense_start[d];
        o.dense_start = append(dense_start);
        o.dense_entry = append(level.dense_entry);
        o.cells = cells.size();
        for (const std::uint32_t block : level.dense_block) cells.push_back(static_cast<std::uint8_t>(block & 0xFFu));
        o.coupling = floats;
        floats += 9 * std::size_t(level.entry_row.size());
        o.inverse = floats;
        floats += std::size_t(level.domains()) * kSchwarzDim * kSchwarzDim;
        o.values = floats;
        floats += std::size_t(level.domains()) * kSchwarzDim;
        o.solved = floats;
        floats += std::size_t(level.domains()) * kSchwarzDim;
    }
    indices_.upload(table, ledger, "MAS levels");
    cells_.upload(cells, ledger, "MAS levels");
    floats_.allocate(floats, ledger, "MAS domain inverses and vectors");
    // Padding nodes of the last domain of each level are never written: their values stay 0.
    WEFT_CUDA_CHECK(cudaMemset(floats_.get(), 0, floats_.bytes()));
    wait_for_default_stream();

    const std::uint32_t* base = indices_.get();
    view_.levels = h.levels();
    view_.order = base + order_at;
    view_.rank = base + rank_at;
    view_.slot_position = base + position_at;
    view_.slot_row = base + row_at;
    view_.slot_column = base + column_at;
    for (int l = 0; l < h.levels(); ++l) {
        const SchwarzLevel& level = h.level[static_cast<std::size_t>(l)];
        const Offsets& o = at[static_cast<std::size_t>(l)];
        SchwarzLevelView& v = view_.level[l];
        v.nodes = level.nodes;
        v.domains = level.domains();
        // Computed here: every entry on one GPU, the part's own in part mode (source_start's runs).
        v.entries = level.source_start.empty() ? 0 : static_cast<std::uint32_t>(level.source_start.size() - 1);
        v.entry_begin = l == 1 ? level1_entry_begin : 0;
        v.parent = level.parent.empty() ? nullptr : base + o.parent;
        v.parent_start = level.parent_start.empty() ? nullptr : base + o.parent_start;
        v.source_start = base + o.source_start;
        v.source = base + o.source;
        v.dense_start = base + o.dense_start;
        v.dense_entry = base + o.dense_entry;
        v.dense_cell = cells_.get() + o.cells;
        v.coupling = floats_.get() + o.coupling;
        v.inverse = floats_.get() + o.inverse;
        v.values = floats_.get() + o.values;
        v.solved = floats_.get() + o.solved;
    }
}

}  // namespace weft::cuda
