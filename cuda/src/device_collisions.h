#pragma once
// The collision stages of a CUDA substep (docs/collisions.md; the CPU reference is
// runtime/src/cpu/cpu_collisions.{h,cpp}, which this mirrors step for step). Cloth vertices come
// first in the collision index space, then the vertices of the mesh colliders (kinematic: they
// follow their motion and are never moved).
//
// Before the solve (outside the solver's CUDA graph, on the same stream: the detection reads its
// overflow counters back to the host):
//   - kinematic vertices placed at t and t + h on the device (device_kinematics.h: the host sends
//     each mesh collider's map, or each joint's where a character plays a clip);
//   - the GPU broad phase over the predicted motion x0 → x0 + h·v0;
//   - the GPU proximity contacts, copied device to device into the solver's contact list (same
//     64-byte layout, asserted in device_collisions.cpp), with the kinematic poses at t + h and
//     velocities. With self-collision and `collision.culling = "normal_cone"`, the broad phase first
//     gets the normal-cone patch ids of the motion (collision/normal_cone_gpu.h), so that pairs inside
//     one self-collision-free patch are never generated (PSCC); the GPU does not count culled pairs.
// After the solve, when continuous collisions are on: the GPU impact zones
// (collision/impact_zones_gpu.h) over x0 → x1 — detection, projection rounds and fallbacks, all on
// the device; the first detection is the substep's gate (no hit: nothing else runs). Every detection
// recomputes the patch ids over the current motion first (the zones change x1 between detections).
// The cloth vertices the zones moved take x1 and the velocity (x1 − x0)/h.

#include <cuda_runtime_api.h>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "collision/broad_phase_gpu.h"
#include "collision/ccd_gpu.h"
#include "collision/displacement_bounds_gpu.h"
#include "weft/backend/collision_geometry.h"
#include "collision/impact_zones_gpu.h"
#include "collision/normal_cone_gpu.h"
#include "collision/proximity_gpu.h"
#include "device_array.h"
#include "device_contacts.h"
#include "device_kinematics.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/model.h"
#include "weft/stats.h"

namespace weft::cuda {

class DeviceCollisions {
public:
    DeviceCollisions();
    ~DeviceCollisions();
    DeviceCollisions(const DeviceCollisions&) = delete;
    DeviceCollisions& operator=(const DeviceCollisions&) = delete;

    /// Builds the collision geometry of `flat` and the mesh colliders of `model` on the current
    /// device (inactive, holding nothing, when the model needs no cloth collisions).
    void build(const FlatModel& flat, const Model& model);
    /// Frees everything (inactive).
    void release();
    [[nodiscard]] bool active() const { return active_; }
    /// True when `model`'s collision settings no longer match what was built (self-collision switched
    /// on or off live, or a scene that did not need the stages now does): call `build` again.
    [[nodiscard]] bool stale(const Model& model) const {
        return needs_cloth_collisions(model) != active_ ||
               (active_ && model.settings.collision.self_collision != geometry_.self);
    }
    [[nodiscard]] std::size_t kinematic_count() const { return kinematic_count_; }

    /// Before the solve: finds the substep's proximity contacts from the cloth state (`x`, `v`: the
    /// solver's SoA arrays of `n` cloth vertices, which the substep takes as x0, v0) and the colliders'
    /// poses at t and t + h. Synchronises `stream`. Returns the contact count: the solver's list must
    /// hold that many before `publish`.
    /// `dv_previous` (the last substep's velocity change) sharpens the offset mode's predicted moves.
    std::size_t detect(const Model& model, double t, double h, const float* x, const float* v, const float* dv_previous,
                       cudaStream_t stream, StepStats& stats);
    /// Across GPUs: this object's `detect` finds share `index` of `count` of the proximity pairs
    /// (GpuBroadPhaseInput::share_index), so that each GPU narrows down its own share. The impact
    /// zones always cover every pair. Default: one share (the whole list).
    void set_share(std::uint32_t index, std::uint32_t count) {
        share_index_ = index;
        share_count_ = count;
    }
    /// The contacts the last `detect` found (device, `detect`'s count of them), in the solver's layout.
    [[nodiscard]] const DeviceContact* contacts() const;

    /// Enqueues the copy of the contacts, their count and the kinematic arrays into `list` (capacity
    /// ≥ the count `detect` returned, kinematic capacity ≥ kinematic_count()).
    void publish(const ContactInputs& list, cudaStream_t stream, StepStats& stats);
    /// After the solve (`x`, `v` the solved cloth state; the substep's start is what `detect` read):
    /// the GPU impact zones. The vertices they move get v = (x1 − x0)/h and, as on the CPU, the warm
    /// start of the next substep's solve dv_previous = v − v0. Returns true when they changed anything.
    /// In offset mode (CollisionSettings::mode) it runs only as the fallback: when a prescribed move
    /// broke a bound or `moved_after_solve` (a fast analytic collider carried cloth along).
    bool resolve(const Model& model, double h, float* x, float* v, const float* v0, float* dv_previous,
                 bool moved_after_solve, cudaStream_t stream, StepStats& stats);

    // ---- offset contact (docs/methods.md §7b; the CPU's CpuCollisions::truncate and redetect) ----
    /// True when the last `detect` ran in offset mode: the contacts are offset contacts, every Newton
    /// update goes through `enqueue_truncation`, and `resolve` is only the fallback.
    [[nodiscard]] bool offset() const { return offset_; }
    /// What a CUDA graph that captured `enqueue_truncation` depends on besides its arguments: the
    /// bounds' buffers (their generation), the bound shape and γ. Equal values: the capture is valid.
    [[nodiscard]] std::uint64_t truncation_key(const Model& model) const {
        const CollisionSettings& c = model.settings.collision;
        return (bounds_.generation() << 33) ^ (std::uint64_t{c.bound_shape == BoundShape::Planar} << 32) ^
               std::bit_cast<std::uint32_t>(static_cast<float>(c.relaxation));
    }
    /// After a Newton update (enqueued; no synchronisation): truncates the free cloth vertices' v_k
    /// (and w_k) to the bounds of the last detection; pinned ones (`fixed`) are counted, not moved.
    /// h is read from device memory (the solver's step parameters).
    void enqueue_truncation(const Model& model, const float* x0, float* vk, float* wk, const std::uint8_t* fixed,
                            const float* h_device, cudaStream_t stream);
    /// After the substep's Newton iterations (synchronises): the last truncation's counts into
    /// `stats`; true when more than CollisionSettings::redetect_share of the free vertices were
    /// truncated and a rerun is still allowed.
    bool finish_truncation(const Model& model, cudaStream_t stream, StepStats& stats);
    /// A rerun of the detection at the truncated state x0 + h·v_k (colliders at t + h). Returns the
    /// contact count, as `detect`; `publish` follows.
    std::size_t redetect(const Model& model, double h, const float* x0, const float* vk, const float* h_device,
                         cudaStream_t stream, StepStats& stats);

    // ---- offset contact across GPUs (docs/multi-gpu.md, "Collisions") ----
    /// Across GPUs: `detect` and `redetect` call `reduce` where this share's nearest distances or
    /// pair limits are partial (collision::BoundsReduction; the multi-GPU solver waits there for the
    /// other shares and takes the minimum over the GPUs). Empty: one GPU.
    void set_bounds_reduction(collision::BoundsReduction reduce) { reduce_ = std::move(reduce); }
    /// This GPU's per-vertex array of `which` (device), for the other GPUs' reductions.
    [[nodiscard]] const std::uint32_t* bounds_array(collision::BoundsArray which) const { return bounds_.array(which); }
    /// The minimum of `arrays` (every GPU's array of one kind) over the bounds' vertices, on this
    /// GPU (enqueued); returns the device array.
    const std::uint32_t* reduce_bounds(std::span<const std::uint32_t* const> arrays, cudaStream_t stream) {
        return bounds_.reduce_across(arrays, vertices_, stream);
    }
    /// Across GPUs, after a Newton update: the first half of `enqueue_truncation` over the whole
    /// model's arrays on this GPU (x0, v_k: stride n), the kept shares from this GPU's share of the
    /// pairs (enqueued).
    void enqueue_share_limits(const Model& model, const float* x0, const float* vk, const float* h_device, cudaStream_t stream);
    /// The second half, once every GPU's limits are done: v_k (whole, on this GPU) truncated by the
    /// minimum of `shares` (every GPU's Shares array); pins (`fixed`, whole) counted, not moved; the
    /// remainders for a rerun kept (enqueued). `finish_truncation` reads the counts.
    void enqueue_reduced_truncation(const Model& model, std::span<const std::uint32_t* const> shares, const float* x0,
                                    float* vk, const std::uint8_t* fixed, const float* h_device, cudaStream_t stream);

    /// Device memory held, bytes.
    [[nodiscard]] std::size_t memory_bytes() const;
    /// `memory_bytes` by purpose, each name prefixed "collisions: ".
    [[nodiscard]] std::vector<std::pair<std::string, std::size_t>> memory_breakdown() const;

    /// Adds to `stats` the buffer growths (grow-and-rerun passes) since the last call (`publish`
    /// calls it; a share that is not published calls it itself).
    void count_buffer_growths(StepStats& stats);

private:
    /// The truncation of the cloth vertices' v_k (whole model, stride n_) to the last detection's bounds.
    [[nodiscard]] collision::GpuTruncateInput cloth_truncation(const Model& model, const float* x0, float* vk, float* wk,
                                                               const std::uint8_t* fixed, const float* h_device) const;

    /// The broad-phase input over `x0c` → `x1c` with bounds grown by `thickness` (m).
    [[nodiscard]] collision::GpuBroadPhaseInput broad_phase_input(double thickness) const;
    /// The proximity contacts' input between `x0` and `x1` (collision-space SoA, stride vertices_).
    [[nodiscard]] collision::GpuProximityInput proximity_input(const CollisionSettings& settings, const float* x0,
                                                               const float* x1, double h) const;
    /// With culling on: computes the patch ids over in.x0 → in.x1 and attaches them to `in`.
    void cull(const Model& model, collision::GpuBroadPhaseInput& in, cudaStream_t stream);

    weft::collision::CollisionGeometry geometry_;  // the index space, as the CPU backend builds it
    bool active_ = false;
    std::uint32_t n_ = 0;               // cloth vertices
    std::size_t kinematic_count_ = 0;   // mesh collider vertices
    std::uint32_t vertices_ = 0;        // n + kinematic: the component stride of the position arrays
    std::uint32_t triangle_count_ = 0, edge_count_ = 0;
    bool trace_zones_ = false;
    bool colored_zones_ = false;        // WEFT_CUDA_ZONE_PROJECTION=colored
    long colored_above_ = -1;           // WEFT_CUDA_ZONE_COLORED_ABOVE (-1: the default)
    std::uint32_t share_index_ = 0, share_count_ = 1;  // set_share

    MemoryLedger ledger_;
    DeviceArray<float> positions_;  // x0 then x1, SoA with stride vertices_
    DeviceArray<std::uint32_t> triangles_, edges_, triangle_group_;
    DeviceArray<float> inverse_mass_, thickness_, friction_;
    DeviceArray<float> rest_;                 // with self-collision: cloth rest positions, SoA stride n_
    DeviceArray<std::uint32_t> vertex_cloth_;  // with self-collision: owning cloth of each cloth vertex
    DeviceKinematics kinematics_;  // the mesh colliders' vertices, skinned and placed on the device
    collision::GpuNormalConeCulling cones_;  // built with self-collision
    collision::GpuBroadPhase broad_;  // over the predicted motion (proximity)
    collision::GpuProximityContacts proximity_;
    collision::GpuImpactZones zones_;  // over the solved motion (its own broad phase and CCD)

    // Offset mode: the bounds (taken at detect_positions_, with radii radius_), the frame shift, the
    // largest radius (float bits) and the momentum sums the shift comes from.
    /// The bounds and offset contacts at detect_positions_ (radii in radius_ and shift already set).
    std::size_t detect_offset(const Model& model, double h, cudaStream_t stream, StepStats& stats);
    bool offset_ = false;
    bool fallback_ = false;
    collision::BoundsReduction reduce_;  // set_bounds_reduction
    int redetections_ = 0;
    int growths_counted_ = 0;  // count_buffer_growths: the passes' rerun total seen so far
    std::size_t free_vertices_ = 0;
    collision::GpuDisplacementBounds bounds_;
    DeviceArray<float> detect_positions_, radius_, remainder_;
    DeviceArray<double> offset_sums_;      // Σ m·v (3), Σ m
    DeviceArray<double> offset_partials_;  // their per-block sums (launch_offset_momentum)
    DeviceArray<float> offset_shift_;  // 3
    DeviceArray<std::uint32_t> offset_largest_;
    PinnedArray<double> offset_host_;  // the momentum sums
};

}  // namespace weft::cuda
