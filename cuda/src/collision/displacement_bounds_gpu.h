#pragma once
/// @file
/// Per-vertex conservative displacement bounds and the truncation on the GPU: the device twin of
/// runtime/src/collision/displacement_bounds.h (docs/methods.md §7b), in float.
///
/// Bounds. The broad phase (GpuBroadPhase, each primitive padded by the largest query radius r_v of
/// its vertices) gives the candidate pairs; one thread per candidate takes the closest points
/// (weft/physics/proximity.h, the CPU's functions), keeps the pair when its distance d is below the
/// largest r_v of its four vertices ("measured"), and lowers each vertex's nearest distance with an
/// integer atomicMin on the float's bits (non-negative floats order like their bits: exact and
/// order-independent, so the bounds are the same on every run). Then per vertex b_v = γ·min(r_v, d_v)
/// and reach_v = γ·r_v.
///
/// Truncation. The CPU keeps each vertex's partners in a CSR list; here the planar limits are applied
/// pair by pair instead: per vertex the share t = min(1, reach/|move|) (planar) or min(1, b_v/|move|)
/// (sphere), then one thread per measured pair lowers the share of each of its four vertices to
/// γ·d / (move·towards) where the vertex advances towards the partner (atomicMin on bits again), then
/// per vertex the move is scaled by t. The result is the CPU's kept_share up to float rounding.
///
/// Across GPUs (docs/multi-gpu.md, "Collisions"). Each GPU measures its share of the candidate pairs
/// (`share_index` of `share_count`, as the broad phase shares them), so its nearest distances and its
/// pair limits are partial: the per-vertex minimum over the GPUs' arrays (`reduce_across`, peer
/// reads; min is exact and order-free) is the one-GPU array, so every GPU ends with the same bounds
/// and the same truncation bits whatever the GPU count.
///
/// Float. Distances carry float rounding (about 1e-7 of the coordinates' magnitude); the bounds keep
/// (1 − 2γ) of every gap (10 % at γ = 0.45), far above it except for pairs closer than about 1e-6 m,
/// which the contact barrier keeps from forming.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "collision/broad_phase_gpu.h"
#include "collision/pair_keys.h"
#include "device_array.h"

namespace weft::cuda::collision {

/// What the bounds read (device pointers, valid until the work is done on the stream).
struct GpuBoundsInput {
    const float* x = nullptr;  ///< positions the bounds are taken at, m, structure of arrays
    std::uint32_t vertex_count = 0;
    std::uint32_t stride = 0;  ///< component stride; 0 means vertex_count
    const std::uint32_t* triangles = nullptr;
    std::uint32_t triangle_count = 0;
    const std::uint32_t* edges = nullptr;  ///< build_edges order
    std::uint32_t edge_count = 0;
    /// As GpuBroadPhaseInput: false measures only pairs across groups (self-collision off).
    bool self_pairs = true;
    const std::uint32_t* triangle_cloth = nullptr;
    const float* radius = nullptr;  ///< r_v per vertex, m (> 0)
    float relaxation = 0.45F;       ///< γ in (0, ½)
    /// Which share of the candidate pairs this GPU measures (GpuBroadPhaseInput::share_index).
    std::uint32_t share_index = 0;
    std::uint32_t share_count = 1;
};

/// The per-vertex arrays that a GPU's share leaves partial.
enum class BoundsArray {
    Nearest,  ///< nearest measured distance (float bits), after `compute`'s pair pass
    Shares,   ///< kept share of the move (float bits), after `limit_shares`
};

/// Across GPUs: given the array this GPU's share left partial, makes every GPU's array of that kind
/// available (waiting for the other shares as needed) and returns this GPU's device array holding
/// the per-vertex minimum over all of them (GpuDisplacementBounds::reduce_across).
using BoundsReduction = std::function<const std::uint32_t*(BoundsArray, cudaStream_t)>;

/// One truncation: local vertex i (bounds vertex first + i) proposes x0_i + h·v_i; its move from the
/// detection is that minus the frame shift minus x_detect (the bounds' positions). Truncated vertices
/// get v = (x_detect + t·move + shift − x0)/h (and v_copy the same); prescribed ones (pins) are never
/// changed but counted in `broken` when t < 1. Without `v` the positions x0 are the proposal and every
/// vertex is prescribed (a check of kinematic moves). h and the shift are read from device memory
/// when their pointers are given (a CUDA graph replays them per substep), else from the fields.
struct GpuTruncateInput {
    const float* x_detect = nullptr;  ///< the positions the bounds were taken at (GpuBoundsInput::x)
    const float* x0 = nullptr;        ///< start of the substep, m
    float* v = nullptr;               ///< in/out, m/s (null: check only)
    float* v_copy = nullptr;          ///< optional: receives the truncated velocities too
    float* remainder = nullptr;       ///< optional, per local vertex: (1 − t)·|move|, m
    std::uint32_t first = 0;          ///< bounds index of local vertex 0
    std::uint32_t vertex_count = 0;   ///< local vertices
    std::uint32_t stride = 0;         ///< component stride of x0 and v; 0 means vertex_count
    std::uint32_t detect_stride = 0;  ///< component stride of x_detect; 0 means the bounds' stride
    const std::uint8_t* prescribed = nullptr;  ///< per local vertex, 1: cannot be shortened (optional)
    float h = 1.0F;
    const float* h_device = nullptr;
    float shift[3] = {0.0F, 0.0F, 0.0F};
    const float* shift_device = nullptr;  ///< 3 floats
    bool planar = true;
};

/// Counters of the last `compute` and `truncate` (`read_back`).
struct GpuBoundsCounters {
    std::uint32_t measured_vf = 0;  ///< vertex–face pairs within the radius
    std::uint32_t measured_ee = 0;  ///< edge–edge pairs within the radius
    std::uint32_t limited = 0;      ///< vertices with a partner closer than their r_v
    std::uint32_t truncated = 0;    ///< free vertices the last truncation shortened
    std::uint32_t broken = 0;       ///< prescribed vertices whose move broke their bound
    std::uint32_t pad_ = 0;
};

class GpuDisplacementBounds {
public:
    /// The bounds at in.x: the broad phase with the radii as padding (grown and rerun until it fits:
    /// one host synchronisation), then the pair and vertex passes, enqueued on `stream`. With
    /// `reduce` (a share across GPUs), the vertex pass reads the nearest distances it returns.
    void compute(const GpuBoundsInput& in, GpuBroadPhase& hash, cudaStream_t stream, const BoundsReduction& reduce = {});
    /// Truncates the moves of the vertices in `t` to the bounds of the last `compute` (enqueued).
    /// `reset_counts` false adds to the last truncation's counts (a check after a truncation). With
    /// `reduce` (a share across GPUs), the moves are scaled by the shares it returns.
    void truncate(const GpuTruncateInput& t, cudaStream_t stream, bool reset_counts = true,
                  const BoundsReduction& reduce = {});
    /// The first half of `truncate`: the kept share of every vertex in `t` from its own bound and
    /// this share's measured pairs, into the Shares array (enqueued; resets the counts).
    void limit_shares(const GpuTruncateInput& t, cudaStream_t stream);
    /// The second half: each vertex of `t` moved by `share` (a Shares array, this GPU's or reduced),
    /// counted, its remainder written (enqueued).
    void apply_shares(const GpuTruncateInput& t, const std::uint32_t* share, cudaStream_t stream);
    /// This GPU's array of `which` (device; read by the other GPUs' reduce_across).
    [[nodiscard]] const std::uint32_t* array(BoundsArray which) const {
        return which == BoundsArray::Nearest ? nearest_bits_.get() : share_bits_.get();
    }
    /// The per-vertex minimum of `arrays` (device pointers, peers' included, each ≥ `count` long; at
    /// most kMaxReducedArrays) into this object's reduction array, which it returns (enqueued).
    const std::uint32_t* reduce_across(std::span<const std::uint32_t* const> arrays, std::uint32_t count, cudaStream_t stream);
    static constexpr std::size_t kMaxReducedArrays = 16;
    /// Copies the counters to the host and waits.
    const GpuBoundsCounters& read_back(cudaStream_t stream);
    [[nodiscard]] const GpuBoundsCounters& counters() const { return *counters_host_.get(); }

    /// Device arrays of the last `compute`: b_v and reach_v per vertex (m), and per candidate of the
    /// broad phase's list its distance (+∞ when not measured) and unit normal (from the second
    /// primitive towards the first), 4 floats each.
    [[nodiscard]] const float* bound() const { return bound_.get(); }
    [[nodiscard]] const float* reach() const { return reach_.get(); }
    [[nodiscard]] const float4* pair_geometry() const { return pair_geometry_.get(); }
    [[nodiscard]] const GpuPairList& pairs() const { return pairs_; }

    /// Bumped whenever an array the truncation reads is reallocated: a CUDA graph that captured
    /// `truncate` must be captured again.
    [[nodiscard]] std::uint64_t generation() const { return generation_; }

    /// Downloads b_v and reach_v (tests). Synchronises.
    void download(std::vector<float>& bound, std::vector<float>& reach, cudaStream_t stream) const;
    [[nodiscard]] std::size_t memory_bytes() const;

private:
    void enqueue_limits(const GpuTruncateInput& t, cudaStream_t stream, bool reset_counts);
    [[nodiscard]] std::uint32_t detect_stride_of(const GpuTruncateInput& t) const;

    GpuBoundsInput in_{};
    GpuPairList pairs_{};
    // The truncation's own copy of each candidate (its four vertices, the edge–edge flag in bit 31 of
    // the last), sized by capacity_ ≥ the broad phase's capacity, so that it reads no buffer of the
    // broad phase but its count (whose pointer is fixed): a captured truncation stays valid while the
    // broad phase alternates or grows its pair buffers, until capacity_ itself grows.
    std::uint32_t capacity_ = 0;
    std::uint64_t generation_ = 0;
    DeviceArray<uint4> pair_ids_;
    MemoryLedger ledger_;
    DeviceArray<std::uint32_t> nearest_bits_, share_bits_;
    DeviceArray<std::uint32_t> reduced_bits_;  // reduce_across's result (allocated on first use)
    DeviceArray<float> bound_, reach_;
    DeviceArray<float4> pair_geometry_;
    DeviceArray<GpuBoundsCounters> counters_;
    PinnedArray<GpuBoundsCounters> counters_host_;
};

}  // namespace weft::cuda::collision
