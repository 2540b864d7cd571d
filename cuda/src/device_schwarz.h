#pragma once
// The multilevel additive Schwarz preconditioner on the device (docs/methods.md §2b): the levels of
// weft/backend/schwarz_hierarchy.h (the same tables as the CPU backend's) uploaded once per build,
// and the per-step arrays: each level's coupling blocks, the dense domain inverses (float, 48×48 per
// domain of 16 nodes) and the restricted and solved vectors of the apply. schwarz_kernels.cu holds
// the kernels; DeviceSolver orders them.

#include <cstdint>

#include "device_array.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/part_schwarz.h"
#include "weft/backend/schwarz_hierarchy.h"

namespace weft::cuda {

inline constexpr int kSchwarzMaxLevels = 8;
inline constexpr std::uint32_t kSchwarzNodes = SchwarzHierarchy::kDomainSize;  // nodes per domain
inline constexpr std::uint32_t kSchwarzDim = SchwarzHierarchy::kDomainDim;     // rows of a domain matrix

struct SchwarzLevelView {
    std::uint32_t nodes = 0, domains = 0;
    /// Coupling entries this device computes, [entry_begin, entry_begin + entries) of `coupling`
    /// (all of them on one GPU; a part's own on several, docs/multi-gpu.md). source_start and source
    /// are indexed from entry_begin.
    std::uint32_t entries = 0, entry_begin = 0;
    const std::uint32_t* parent = nullptr;        ///< node → node of the next level (null on the last)
    const std::uint32_t* parent_start = nullptr;  ///< per domain, its first next-level node (domains + 1)
    const std::uint32_t* source_start = nullptr;  ///< level ≥ 1: entries + 1
    /// Level 1: indices into the level-0 slot arrays of SchwarzView; level ≥ 2: couplings below.
    const std::uint32_t* source = nullptr;
    const std::uint32_t* dense_start = nullptr;   ///< per domain, its first dense entry (domains + 1)
    const std::uint32_t* dense_entry = nullptr;   ///< level 0: slot; level ≥ 1: coupling entry
    const std::uint8_t* dense_cell = nullptr;     ///< a·16 + b: where the entry lands in its domain
    float* coupling = nullptr;  ///< level ≥ 1: 9 floats (row-major) per coupling entry
    float* inverse = nullptr;   ///< kSchwarzDim² floats per domain, column-major (symmetric anyway)
    float* values = nullptr;    ///< restricted residual, 3 per node (kSchwarzDim per domain, padded)
    float* solved = nullptr;    ///< D⁻¹·values, same layout
};

struct SchwarzView {
    int levels = 0;
    const std::uint32_t* order = nullptr;  ///< level-0 node → vertex
    const std::uint32_t* rank = nullptr;   ///< vertex → level-0 node
    // The pattern's slots (level 0's couplings): ELL position, row and column vertex.
    const std::uint32_t* slot_position = nullptr;
    const std::uint32_t* slot_row = nullptr;
    const std::uint32_t* slot_column = nullptr;
    SchwarzLevelView level[kSchwarzMaxLevels];
};

class DeviceSchwarz {
public:
    /// Builds the hierarchy for `flat` and uploads it with the per-step arrays, charged to `ledger`.
    /// `slot_position` maps the flat pattern's slots to the solver's ELL positions.
    void build(const FlatModel& flat, const std::vector<std::uint32_t>& slot_position, MemoryLedger& ledger);
    /// Part mode (the multi-GPU solver): uploads `part`'s share of the whole hierarchy for a part
    /// whose local pattern is `pattern`, its slots at `slot_position`.
    void build_part(PartSchwarz part, const BlockPattern& pattern, const std::vector<std::uint32_t>& slot_position,
                    MemoryLedger& ledger);
    /// Part mode: the floats of level 1's restricted residual and of its couplings that this part
    /// computes (what the all-gathers send), and the whole arrays' sizes.
    [[nodiscard]] const PartSchwarz& part() const { return part_; }
    void release();
    [[nodiscard]] bool built() const { return view_.levels > 0; }
    [[nodiscard]] const SchwarzView& view() const { return view_; }
    [[nodiscard]] const SchwarzHierarchy& hierarchy() const { return hierarchy_; }

private:
    void upload(const BlockPattern& pattern, const std::vector<std::uint32_t>& slot_position, std::uint32_t level1_entry_begin,
                MemoryLedger& ledger);

    SchwarzHierarchy hierarchy_;
    PartSchwarz part_;  // part mode only
    SchwarzView view_;
    DeviceArray<std::uint32_t> indices_;  // every table, one allocation
    DeviceArray<std::uint8_t> cells_;
    DeviceArray<float> floats_;           // couplings, inverses, values, solved
};

}  // namespace weft::cuda
