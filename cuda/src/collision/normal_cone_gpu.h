#pragma once
/// @file
/// Normal-cone self-collision culling on the GPU (PSCC: Tang, Liu, Tong & Manocha 2018; docs/methods.md
/// §5): every call recomputes, on the device, the patch ids that the CPU's NormalConeFront
/// (runtime/src/collision/normal_cone_front.h) keeps on the host, so that the GPU broad phase
/// (broad_phase_gpu.h: vertex_patch / edge_patch / triangle_patch) culls without a round trip.
///
/// What is computed: the top-most passing nodes of the CPU's PatchHierarchy, the same set semantics
/// as NormalConeFront::rebuild. A node passes when it is a single triangle, or a topological disk
/// whose continuous normal cone is narrower than a hemisphere and whose contour, projected along
/// the cone axis, stays simple during the whole step. Each primitive's patch is the id (hierarchy
/// node index) of the passing node above its reference triangle, as on the CPU; the broad phase
/// never pairs two primitives with one id.
///
/// Pipeline of one `enqueue` (one stream, no host synchronisation, fixed launch sizes: capturable in
/// a CUDA graph):
///   refit     bottom-up, one kernel per level (a thread per node): leaves take the continuous cone
///             of their triangle (Tang et al. 2009's Bernstein bound), inner nodes merge their
///             children's (runtime/src/collision/normal_cone.cpp)
///   classify  top-down, one kernel per level (a thread per node): a node under a passing ancestor
///             takes its patch; otherwise a leaf passes, a narrow disk is queued for a contour test,
///             anything else is opened (its children are examined at the next level). Queued nodes
///             are appended to a work list of (node, contour tile pair) items with one 64-bit integer
///             atomic (entry count and item count packed), so entries are ordered by item offset
///   contour   one kernel per level that has testable nodes: a warp per item, an item being a pair
///             of 32-edge tiles of one contour (every pair of tiles once, so that a long contour
///             spreads over many warps and a short one takes one); lanes hold the edges of one
///             tile and receive the other tile's by shuffles; a pair that may touch marks the node
///             failed (runtime/src/collision/contour_test.cpp, in float)
///   assign    a thread per vertex, edge and triangle: the patch of its reference triangle's leaf
/// The next level's classify resolves a queued parent from its failure flag, so no pass is needed
/// between the levels. No front is kept between calls: the cut is recomputed from the roots each
/// time, as NormalConeFront::rebuild does (PSCC maintains its front incrementally; here the refit
/// visits every node anyway, and a cut that depends on the current positions alone needs no state,
/// no host decision and no repair after a teleport).
///
/// Conservative. Every cone and contour decision uses float with rigorous outward allowances
/// (normal_cone_float.h says how each is derived), so a node passes here only if it provably has
/// no self-contact during the step, the same guarantee the CPU's double version gives. The two are
/// not bit-identical: near a threshold either may pass a node the other does not (float's margins
/// are wider, so it is mostly the GPU that refuses), and then the ids differ there. Atomics are on
/// integers only and order work, never results: every decision depends on the positions alone, so
/// the ids are the same bits on every run.
///
/// Mesh colliders and uncovered primitives get kNoPatch (never culled): primitives at or beyond the
/// layout's cloth counts, vertices no triangle uses, and everything beyond what the hierarchy
/// covers; hierarchy nodes made only of such triangles are never examined.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "device_array.h"

namespace weft::collision {
struct PatchHierarchy;
}

namespace weft::cuda::collision {

/// Sizes of the patch arrays and which primitives may be culled. With DeviceCollisions: the counts
/// of the collision index space (cloth first, then the kinematic mesh-collider primitives), and the
/// cloth's shares of them.
struct GpuNormalConeLayout {
    /// Patch array sizes: every collision vertex, edge and triangle, as given to GpuBroadPhaseInput.
    std::uint32_t vertex_count = 0, edge_count = 0, triangle_count = 0;
    /// Primitives with an index at or beyond these (the mesh colliders') get kNoPatch.
    std::uint32_t cloth_vertices = 0, cloth_edges = 0, cloth_triangles = 0;
};

/// Work of one call (`read_back`).
struct GpuNormalConeCounters {
    std::uint32_t front_size = 0;      ///< patches: passing nodes with no passing ancestor (leaves included)
    std::uint32_t contour_tests = 0;   ///< nodes whose contour was tested
    std::uint32_t contour_failed = 0;  ///< of those, refused
    std::uint32_t contour_items = 0;   ///< tile pairs (warp tasks) of those tests
};

/// A node's cone as the device holds it (`download_cones`): unit axis and half-angle, rad; +∞ when
/// it bounds nothing (a leaf or merge that failed, or a collider node).
struct GpuCone {
    float axis[3];
    float half_angle;
};

/// The culling on one device over one fixed topology. Keeps its buffers between calls; one object
/// per stream of work (`enqueue` is not reentrant). Must be used and destroyed with its device current.
class GpuNormalConeCulling {
public:
    GpuNormalConeCulling();
    ~GpuNormalConeCulling();
    GpuNormalConeCulling(const GpuNormalConeCulling&) = delete;
    GpuNormalConeCulling& operator=(const GpuNormalConeCulling&) = delete;

    /// Uploads the hierarchy (built once per topology by weft::collision::build_patch_hierarchy over
    /// the collision index space or a prefix of it: its vertex, edge and triangle ids must be those
    /// of the broad phase) and everything derived from it: nodes, levels, contours, each
    /// primitive's reference leaf. Synchronous; allocates everything `enqueue` needs. Throws
    /// weft::Error when the hierarchy covers more vertices, edges or triangles than `layout`, when a
    /// cloth count exceeds its total, or when a level's contour work exceeds 2³² tile pairs.
    void build(const weft::collision::PatchHierarchy& hierarchy, const GpuNormalConeLayout& layout);
    /// Frees everything (`built()` false).
    void release();
    [[nodiscard]] bool built() const { return built_; }

    /// Enqueues on `stream` the refit, the pass tests and the patch ids for the step x0 → x1 (every
    /// vertex moving linearly). `x0`, `x1`: device positions, m, structure of arrays as in
    /// GpuBroadPhaseInput: x at [0, n), y at [stride, stride + n), z at [2·stride, 2·stride + n);
    /// `stride` 0 means layout.vertex_count. Only the vertices of cloth triangles are read. No host
    /// synchronisation, no allocation. Throws weft::Error before `build`, or for a null position
    /// pointer or a stride below the hierarchy's vertex count.
    void enqueue(const float* x0, const float* x1, std::uint32_t stride, cudaStream_t stream);
    /// Copies the last call's counters to the host and waits for them (diagnostics, benchmarks).
    const GpuNormalConeCounters& read_back(cudaStream_t stream);
    [[nodiscard]] const GpuNormalConeCounters& counters() const { return *counters_host_.get(); }

    /// Patch ids of the last call (device, sized as the layout; kNoPatch = 0xFFFFFFFF for none), for
    /// GpuBroadPhaseInput::vertex_patch, edge_patch and triangle_patch. Null for a size of 0.
    [[nodiscard]] const std::uint32_t* vertex_patch() const { return vertex_patch_.get(); }
    [[nodiscard]] const std::uint32_t* edge_patch() const { return edge_patch_.get(); }
    [[nodiscard]] const std::uint32_t* triangle_patch() const { return triangle_patch_.get(); }
    /// Downloads the three patch arrays (tests, tools). Synchronises `stream`.
    void download(std::vector<std::uint32_t>& vertex, std::vector<std::uint32_t>& edge,
                  std::vector<std::uint32_t>& triangle, cudaStream_t stream) const;
    /// Downloads every node's cone of the last call (tests). Synchronises `stream`.
    void download_cones(std::vector<GpuCone>& cones, cudaStream_t stream) const;

    [[nodiscard]] std::size_t node_count() const { return nodes_; }
    [[nodiscard]] std::size_t levels() const { return level_first_.empty() ? 0 : level_first_.size() - 1; }
    /// Device memory held, bytes.
    [[nodiscard]] std::size_t memory_bytes() const { return ledger_.total(); }

private:
    bool built_ = false;
    int multiprocessors_ = 0;
    GpuNormalConeLayout layout_{};
    std::uint32_t hierarchy_vertices_ = 0;
    std::uint32_t nodes_ = 0;
    std::vector<std::uint32_t> level_first_;        ///< host copy: launch sizes
    std::vector<std::uint32_t> level_items_;        ///< per level: contour tile pairs if every disk is tested
    std::vector<std::uint8_t> level_has_contours_;  ///< per level: any testable node

    MemoryLedger ledger_;
    // Per node.
    DeviceArray<std::uint32_t> parent_, link_;  // link: left child, or the triangle of a leaf
    DeviceArray<std::uint8_t> flags_;
    DeviceArray<std::uint32_t> contour_first_;  // nodes + 1
    DeviceArray<uint2> contour_edges_;
    DeviceArray<float4> cones_;
    DeviceArray<std::uint32_t> top_, failed_;
    // Per triangle (the hierarchy's): vertex ids.
    DeviceArray<std::uint32_t> triangles_;
    // Per primitive of the layout: the leaf whose patch it takes (kNone: never culled), and the ids.
    DeviceArray<std::uint32_t> vertex_leaf_, edge_leaf_, triangle_leaf_;
    DeviceArray<std::uint32_t> vertex_patch_, edge_patch_, triangle_patch_;
    // Work list of the contour tests (reused level after level) and the counters.
    DeviceArray<uint2> entries_;                // (node, first item)
    DeviceArray<unsigned long long> counters_;  // GpuNormalConeCounters (2 words), then one per level
    PinnedArray<GpuNormalConeCounters> counters_host_;
};

}  // namespace weft::cuda::collision
