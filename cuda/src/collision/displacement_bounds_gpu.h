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
/// Float. Distances carry float rounding (about 1e-7 of the coordinates' magnitude); the bounds keep
/// (1 − 2γ) of every gap (10 % at γ = 0.45), far above it except for pairs closer than about 1e-6 m,
/// which the contact barrier keeps from forming.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
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
};

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
    /// one host synchronisation), then the pair and vertex passes, enqueued on `stream`.
    void compute(const GpuBoundsInput& in, GpuBroadPhase& hash, cudaStream_t stream);
    /// Truncates the moves of the vertices in `t` to the bounds of the last `compute` (enqueued).
    /// `reset_counts` false adds to the last truncation's counts (a check after a truncation).
    void truncate(const GpuTruncateInput& t, cudaStream_t stream, bool reset_counts = true);
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
    DeviceArray<float> bound_, reach_;
    DeviceArray<float4> pair_geometry_;
    DeviceArray<GpuBoundsCounters> counters_;
    PinnedArray<GpuBoundsCounters> counters_host_;
};

}  // namespace weft::cuda::collision
