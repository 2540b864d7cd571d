#pragma once
// The collision stages of a CUDA substep (docs/collisions.md; the CPU reference is
// runtime/src/cpu/cpu_collisions.{h,cpp}, which this mirrors step for step). Cloth vertices come
// first in the collision index space, then the vertices of the mesh colliders (kinematic: they
// follow their motion and are never moved).
//
// Before the solve (outside the solver's CUDA graph, on the same stream: the detection reads its
// overflow counters back to the host):
//   - kinematic vertices placed at t and t + h on the host, in double, and uploaded;
//   - the GPU broad phase over the predicted motion x0 → x0 + h·v0;
//   - the GPU proximity contacts, copied device to device into the solver's contact list (same
//     64-byte layout, asserted in device_collisions.cpp), with the kinematic poses at t + h and
//     velocities. Normal-cone culling is not done on the GPU yet: every overlapping pair is tested
//     (as `collision.culling = "none"`; same contacts, more work, culled pairs reported as 0).
// After the solve, when continuous collisions are on:
//   - the GPU CCD over x0 → x1 on a fresh broad phase. No hit: done, nothing leaves the device.
//   - INTERIM (hybrid): on a hit, x0 and x1 of every collision vertex are downloaded and the CPU
//     impact zones (collision::ImpactZoneSolver, the reference, with the inputs CpuCollisions gives
//     it) correct x1 on the host; the moved cloth vertices are uploaded with v = (x1 − x0)/h.
//     GPU impact zones replace this next.
//
// Not done here yet: the swept test of fast analytic colliders (CpuSolver::sweep_fast_colliders).

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "collision/broad_phase_gpu.h"
#include "collision/ccd_gpu.h"
#include "collision/proximity_gpu.h"
#include "device_array.h"
#include "device_contacts.h"
#include "weft/flat_model.h"
#include "weft/model.h"
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
        return needs_cloth_collisions(model) != active_ || (active_ && model.settings.collision.self_collision != self_);
    }
    [[nodiscard]] std::size_t kinematic_count() const { return kinematic_count_; }

    /// Before the solve: finds the substep's proximity contacts from the cloth state (`x`, `v`: the
    /// solver's SoA arrays of `n` cloth vertices, which the substep takes as x0, v0) and the colliders'
    /// poses at t and t + h. Synchronises `stream`. Returns the contact count: the solver's list must
    /// hold that many before `publish`.
    std::size_t detect(const Model& model, double t, double h, const float* x, const float* v, cudaStream_t stream,
                       StepStats& stats);
    /// Enqueues the copy of the contacts, their count and the kinematic arrays into `list` (capacity
    /// ≥ the count `detect` returned, kinematic capacity ≥ kinematic_count()).
    void publish(const ContactInputs& list, cudaStream_t stream, StepStats& stats);
    /// After the solve (`x`, `v` the solved cloth state; the substep's start is what `detect` read):
    /// CCD, and the interim CPU impact zones on a hit. Returns true when it changed x and v.
    bool resolve(const Model& model, double h, float* x, float* v, cudaStream_t stream, StepStats& stats);

    /// Device memory held, bytes.
    [[nodiscard]] std::size_t memory_bytes() const;
    /// Substeps whose CCD reported a hit and that went to the CPU impact zones (since the build).
    [[nodiscard]] int host_resolves() const { return host_resolves_; }

private:
    struct Host;  // the CPU-side geometry and the reference impact-zone solver (runtime/src types)
    std::unique_ptr<Host> host_;
    bool active_ = false;
    bool self_ = false;
    std::uint32_t n_ = 0;               // cloth vertices
    std::size_t kinematic_count_ = 0;   // mesh collider vertices
    std::uint32_t vertices_ = 0;        // n + kinematic: the component stride of the position arrays
    std::uint32_t triangle_count_ = 0, edge_count_ = 0;
    float max_thickness_ = 0.0F;
    int host_resolves_ = 0;

    MemoryLedger ledger_;
    DeviceArray<float> positions_;  // x0 then x1, SoA with stride vertices_
    DeviceArray<std::uint32_t> triangles_, edges_, triangle_group_;
    DeviceArray<float> inverse_mass_, thickness_, friction_;
    PinnedArray<float> kinematic_host_;  // x(t), x(t + h), x(t + h) again for the solve, v: 3·nk each
    collision::GpuBroadPhase broad_;      // over the predicted motion (proximity)
    collision::GpuBroadPhase ccd_broad_;  // over the solved motion (CCD)
    collision::GpuProximityContacts proximity_;
    collision::GpuCcd ccd_;
    std::vector<float> download_;  // interim host path: x0, x1 of every collision vertex, v of the cloth
};

}  // namespace weft::cuda
