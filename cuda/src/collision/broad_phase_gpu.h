#pragma once
/// @file
/// The broad phase on the GPU: the device twin of weft::collision::BroadPhase
/// (runtime/src/collision/broad_phase.h), a sorted spatial hash (Teschner, Heidelberger, Müller,
/// Pomeranets & Gross 2003, "Optimized spatial hashing for collision detection of deformable
/// objects"; docs/methods.md §4) over the swept, thickness-inflated bounds of vertices, edges and
/// triangles, with the same adjacency, cloth-group and normal-cone patch filters and the same
/// min-corner rule against duplicates. Output: the candidate vertex–face and edge–edge pairs as one
/// sorted key list (pair_keys.h), in the CPU's order.
///
/// Pipeline of one call (one stream, no host synchronisation inside; `docs` of each stage at its
/// kernel in broad_phase_gpu.cu):
///   bounds     swept inflated boxes in float, rounded outward; grid origin; edge extents
///   cell size  median edge extent (a radix sort of the extents and a one-thread pick), as the CPU
///   patches    with culling only: primitives ordered by (kind, patch, index)
///   count      cells per primitive (across GPUs, those of this share); oversized and non-finite
///              primitives set aside
///   scan       exclusive sum of the counts; (cell key, primitive) entries written and padded
///   sort       CUB radix sort of the entries by cell key (stable: primitive order within a cell)
///   ranges     cell starts (flags + inclusive sum) and each cell's extent
///   workload   per occupant ("row"), its number of partners in the cell; exclusive sum = the
///              workload table of Tang et al. (PSCC 2018) and Tang et al. (P-Cloth 2020), refined
///              from cells to rows
///   pairs      a fixed grid; each warp takes 32·K consecutive pair slots, finds their rows by
///              binary search in the table and tests them; found pairs appended with a warp-wide
///              atomic under a capacity; oversized primitives tested against every partner
///   canonical  the keys sorted (CUB), so the list is the same on every run
///
/// Robustness in float. The CPU reference computes bounds in double from the same (float)
/// positions. Here every bound is rounded outward (lo − thickness rounded down, hi + thickness
/// rounded up, thickness rounded up to float), so each GPU box contains the CPU's box and the GPU
/// pair set contains the CPU's. The extra pairs are those whose double boxes miss each other, on some
/// axis, by less than the outward rounding of the two bounds involved:
///     gap < 2⁻²³·(|lo| + |hi| + 4·thickness)  ≤  2⁻²²·(M + 2·thickness)
/// with M the largest coordinate magnitude of the two boxes (about 2.4e-7 of the scene's extent
/// from the origin, a quarter of a micrometre at 1 m). The hash itself is exact: cells come from a
/// monotone float map of the GPU bounds, so two overlapping GPU boxes always share a cell and the
/// pair is reported exactly once.
///
/// Sizes and growth. Entry and pair buffers have capacities (host-side numbers that every launch is
/// sized by); the device counts what it needs and writes only what fits. `read_back` reports the
/// counts, and `needs_rerun()` says whether a capacity (or the radix-sort key width) was too small;
/// `find()` grows and reruns by itself (collision/grow_and_rerun.h). Nothing is allocated once sizes
/// have settled.
///
/// CUDA graphs. `enqueue` launches a fixed sequence whose launch sizes depend only on host state
/// (capacities, key width, primitive counts), so it can be captured into a graph and replayed; the
/// one host synchronisation left is the read-back of the counters (overflow check), after the whole
/// sequence (or after the narrow phase, which can be enqueued behind it on the same stream).

#include <cuda_runtime_api.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string_view>
#include <vector>

#include "collision/grow_and_rerun.h"
#include "collision/pair_keys.h"
#include "device_array.h"
#include "weft/backend/buffer_trim.h"

namespace weft::cuda::collision {

/// A primitive whose bound covers more cells than this is not hashed but tested against every
/// partner (as weft::collision::BroadPhase::kMaxCellsPerPrimitive).
inline constexpr std::uint64_t kMaxCellsPerPrimitive = 512;

/// What the GPU broad phase reads: device pointers, valid until the work is done on the stream.
/// Same meaning as weft::collision::BroadPhaseInput, in the CUDA backend's layout.
struct GpuBroadPhaseInput {
    /// Positions at the start and end of the step, m, structure of arrays as in the CUDA backend:
    /// x components at [0, n), y at [stride, stride + n), z at [2·stride, 2·stride + n).
    const float* x0 = nullptr;
    const float* x1 = nullptr;
    std::uint32_t vertex_count = 0;
    std::uint32_t stride = 0;  ///< component stride; 0 means vertex_count
    const std::uint32_t* triangles = nullptr;  ///< 3 vertex ids per triangle
    std::uint32_t triangle_count = 0;
    const std::uint32_t* edges = nullptr;  ///< 2 vertex ids per edge, v0 < v1 (build_edges order)
    std::uint32_t edge_count = 0;
    /// Cloth of each triangle (optional); read only when `self_pairs` is false. A vertex takes the
    /// cloth of the lowest-numbered triangle using it, an edge that of its first vertex.
    const std::uint32_t* triangle_cloth = nullptr;
    bool self_pairs = true;
    /// Normal-cone patch ids (optional: all three or none). Pairs of equal ids (other than kNoPatch)
    /// are never generated, nor enumerated (PSCC's cone ids).
    const std::uint32_t* vertex_patch = nullptr;
    const std::uint32_t* edge_patch = nullptr;
    const std::uint32_t* triangle_patch = nullptr;
    double thickness = 0.0;  ///< m, ≥ 0: every bound grows by this on each side
    /// Extra growth per vertex, m (optional, device, vertex_count finite values ≥ 0): as
    /// weft::collision::BroadPhaseInput::vertex_padding, a primitive grows by thickness + the largest
    /// padding of its vertices (rounded up), so two primitives within max(p_a, p_b) always pair.
    const float* vertex_padding = nullptr;
    /// Hash cell edge, m; 0 picks the median extent (longest axis) of the edges' bounds, computed on
    /// the device (as the CPU does, but from the float bounds: any size gives the same pairs).
    double cell_size = 0.0;
    /// Which share of the pairs to enumerate (multi-GPU detection, docs/multi-gpu.md): the hash
    /// cells are dealt to `share_count` shares by a mix of their key, and this call hashes only the
    /// cells of share `share_index` (entries, sort, cell ranges, workload table and pair tests), and
    /// tests the oversized primitives whose id is share_index modulo share_count. A pair is reported
    /// by one cell only (the min-corner rule), so every pair is in exactly one share and the shares'
    /// lists together are the whole list. The bounds, the cell size and the per-primitive cell
    /// counts are computed whole by every share. Default: one share, the whole list.
    std::uint32_t share_index = 0;
    std::uint32_t share_count = 1;
};

/// Counters of one call, as the device leaves them (`read_back`).
struct GpuBroadPhaseCounters {
    std::uint32_t pairs = 0;     ///< pairs found (vertex–face + edge–edge); more than capacity on overflow
    std::uint32_t vf_pairs = 0;  ///< of those, vertex–face
    std::uint32_t ee_pairs = 0;  ///< of those, edge–edge
    std::uint32_t nonfinite = 0;         ///< primitives skipped for a non-finite position
    std::uint32_t oversized = 0;         ///< primitives tested against all partners instead of hashed
    std::uint32_t cells_occupied = 0;    ///< distinct cells holding an entry
    std::uint32_t max_cell_entries = 0;  ///< occupants of the fullest cell
    std::uint32_t key_bits = 0;          ///< bits of the packed cell keys this grid needs
    std::uint32_t overflow = 0;          ///< kOverflow* bits: what did not fit (rerun after growing)
    float cell_size = 0.0F;              ///< cell edge used, m
    unsigned long long entries = 0;          ///< (cell, primitive) entries the grid needs
    unsigned long long tested_pairs = 0;     ///< pair slots enumerated in cells (the workload)
    unsigned long long candidate_pairs = 0;  ///< of those plus the oversized tests: overlapping, not
                                             ///< adjacent, not filtered, before the min-corner rule
    std::uint32_t finite_edges = 0;          ///< edges whose bounds entered the median
    std::uint32_t pad_ = 0;
};
inline constexpr std::uint32_t kOverflowEntries = 1;  ///< entry buffer too small
inline constexpr std::uint32_t kOverflowPairs = 2;    ///< pair buffer too small
inline constexpr std::uint32_t kOverflowKeyBits = 4;  ///< cell keys wider than the sort looked at

/// The thickness as the device uses it: the smallest float ≥ `thickness` (bounds must not shrink).
[[nodiscard]] inline float float_at_least(double value) {
    auto f = static_cast<float>(value);
    if (static_cast<double>(f) < value) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

/// Bits the entry sort runs over for keys of `needed` bits: rounded up to whole radix-sort digits (8
/// bits, CUB's one-sweep digit on Hopper) so that the grid can grow a little without a rerun.
[[nodiscard]] constexpr int entry_sort_bits(std::uint32_t needed) {
    const int bits = static_cast<int>((needed + 7) / 8 * 8);
    return bits < 8 ? 8 : (bits > 64 ? 64 : bits);
}

/// The spatial hash on one device. Keeps every buffer between calls; one object per stream of
/// work (`enqueue` is not reentrant). Must be used and destroyed with its device current.
class GpuBroadPhase {
public:
    /// Timed stages (`set_stage_timing`), in order.
    enum Stage : int { Bounds, CellSize, PatchOrder, Count, Scan, Sort, Ranges, Workload, Pairs, Canonical, kStageCount };
    static constexpr std::array<std::string_view, kStageCount> kStageNames = {
        "bounds", "cell_size", "patch_order", "count", "scan", "sort", "ranges", "workload", "pairs", "canonical"};

    /// Initial capacities; 0 estimates from the mesh on first use (8 entries and 4 pairs per primitive).
    struct Capacities {
        std::size_t entries = 0;
        std::size_t pairs = 0;
    };

    GpuBroadPhase() : GpuBroadPhase(Capacities{}) {}
    explicit GpuBroadPhase(Capacities initial);
    GpuBroadPhase(const GpuBroadPhase&) = delete;
    GpuBroadPhase& operator=(const GpuBroadPhase&) = delete;
    ~GpuBroadPhase();

    /// Enqueues the whole broad phase on `stream`. No host synchronisation; allocates only on first use
    /// or after a growth. Throws weft::Error for inconsistent input (checked on the host: counts,
    /// pointers, thickness, patch lists given partly).
    void enqueue(const GpuBroadPhaseInput& in, cudaStream_t stream);
    /// Enqueues the copy of the counters to host memory and waits for it: the one synchronisation.
    const GpuBroadPhaseCounters& read_back(cudaStream_t stream);
    /// After `read_back`: whether a buffer or the sort width was too small, in which case the sizes
    /// have been grown and the caller must `enqueue` again (the pair list is incomplete).
    [[nodiscard]] bool needs_rerun();
    /// enqueue + read_back, repeated after growing until everything fits. Returns the counters.
    const GpuBroadPhaseCounters& find(const GpuBroadPhaseInput& in, cudaStream_t stream);

    /// The sorted pairs of the last call (device).
    [[nodiscard]] GpuPairList pairs() const;
    /// Downloads the sorted keys [0, counters().pairs) (tests, tools). Synchronises.
    void download(std::vector<std::uint64_t>& keys, cudaStream_t stream) const;

    [[nodiscard]] const GpuBroadPhaseCounters& counters() const { return *counters_host_.get(); }
    [[nodiscard]] std::size_t entry_capacity() const { return entry_capacity_; }
    [[nodiscard]] std::size_t pair_capacity() const { return pair_capacity_; }
    [[nodiscard]] int sort_bits() const { return key_sort_bits_; }
    /// Times `enqueue` grew a buffer or a sort width and had to be rerun.
    [[nodiscard]] int reruns() const { return reruns_; }
    /// Times the entry or pair buffers were cut back after a window of calls that needed far less
    /// than they held (weft/backend/buffer_trim.h): a flood's memory is given back.
    [[nodiscard]] int trims() const { return trims_; }
    /// Device memory held, bytes.
    [[nodiscard]] std::size_t memory_bytes() const;
    /// The share of `memory_bytes` held by the candidate-pair lists (both of the alternating pair).
    [[nodiscard]] std::size_t pair_memory_bytes() const;

    /// Records CUDA events between the stages of each `enqueue` (benchmarks); `stage_ms` reads them
    /// once the stream has reached the end of the call.
    void set_stage_timing(bool enabled);
    [[nodiscard]] std::array<float, kStageCount> stage_ms() const;

private:
    void reserve(const GpuBroadPhaseInput& in, std::uint32_t primitives);
    void mark(Stage stage, cudaStream_t stream);

    std::size_t entry_capacity_ = 0, pair_capacity_ = 0;
    int key_sort_bits_ = 64;  ///< bits of the cell keys the entry sort looks at; 64 until measured
    bool key_bits_known_ = false;
    int reruns_ = 0;
    // The trim windows of the entry and pair capacities (needs_rerun records; the next reserve
    // reallocates what was cut, once the last call's pairs are no longer read).
    CapacityTrim entry_trim_, pair_trim_;
    std::size_t trimmed_entries_ = 0, trimmed_pairs_ = 0;  // the cut capacities, 0 = none pending
    int trims_ = 0;
    int multiprocessors_ = 0;
    PairEncoding encoding_{};
    unsigned long long* sorted_pairs_ = nullptr;  ///< which pair buffer holds the sorted keys
    bool timing_ = false;
    std::array<cudaEvent_t, kStageCount + 1> events_{};

    MemoryLedger ledger_;
    // Per primitive.
    DeviceArray<float4> box_lo_, box_hi_;
    DeviceArray<unsigned long long> cell_lo_, cell_hi_;
    DeviceArray<unsigned long long> counts_;  // P + 1: cells per primitive, then their exclusive sum
    DeviceArray<std::uint8_t> state_;
    DeviceArray<std::uint32_t> oversized_, vertex_cloth_;
    DeviceArray<std::uint32_t> extent_keys_[2];
    DeviceArray<unsigned long long> order_keys_[2];
    DeviceArray<std::uint32_t> order_[2];
    // Per entry.
    DeviceArray<unsigned long long> entry_keys_[2];
    DeviceArray<std::uint32_t> entry_prims_[2];
    DeviceArray<std::uint32_t> cell_id_, cell_begin_;
    DeviceArray<unsigned long long> row_offset_;  // entry capacity + 1
    DeviceArray<uint4> row_info_;
    // Per pair.
    DeviceArray<unsigned long long> pair_keys_[2];
    // Small state: counters, grid, scratch for CUB.
    DeviceArray<unsigned char> block_;
    DeviceArray<unsigned char> temp_;
    PinnedArray<GpuBroadPhaseCounters> counters_host_;
};

}  // namespace weft::cuda::collision
