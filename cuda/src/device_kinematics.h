#pragma once
// The mesh colliders' vertices placed on the device each substep (docs/collisions.md, "Mesh
// colliders and characters"). A mesh collider's vertex i at time t is
//     x_i(t) = Σ_k w_ik · A_{j_ik}(t) · X_i,
// with X_i its rest (or bind-pose) position and A_j the maps of weft::collider_mesh_transforms: one
// per joint for a character playing a clip (linear blend skinning), one for a rigid mesh (weight 1).
// So the host sends 36 floats a map a substep instead of 12 floats a vertex: the rest positions,
// joint ids and weights stay on the device from the build on.
//
// The velocity of the substep's motion, (x(t + h) − x(t))/h, is formed from the maps' difference
// (A_j(t + h) − A_j(t))/h taken in double on the host: a static mesh gets exactly zero, and a moving
// one does not lose the digits that the difference of two float positions would.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "device_array.h"
#include "weft/backend/collision_geometry.h"
#include "weft/backend/model.h"

namespace weft::cuda {

class DeviceKinematics {
public:
    /// Uploads the rest positions, joint ids and weights of the mesh colliders of `g` (those of
    /// `model`); holds nothing when there are none.
    void build(const Model& model, const weft::collision::CollisionGeometry& g, MemoryLedger& ledger);
    void release();
    [[nodiscard]] std::size_t count() const { return count_; }
    /// The maps a substep sends (joints of the characters, one a rigid mesh).
    [[nodiscard]] std::size_t map_count() const { return map_count_; }

    /// Places every mesh-collider vertex at t and t + h (s): x0c and x1c are collision-space SoA
    /// arrays (component stride `stride`) whose kinematic part starts at `first`; the end positions
    /// and velocities (m, m/s; SoA, stride count()) also go to end_positions() and velocities() for
    /// the solve. Enqueued on `stream`, which must have finished reading the staging buffer (the
    /// previous substep's synchronisation).
    void place(const Model& model, double t, double h, float* x0c, float* x1c, std::uint32_t stride, std::uint32_t first,
               cudaStream_t stream);
    [[nodiscard]] const float* end_positions() const { return x1_.get(); }
    [[nodiscard]] const float* velocities() const { return v_.get(); }
    /// The largest move of a mesh-collider vertex between where the last `place` left it (its end,
    /// at t + h then) and where this one starts it, m: 0 unless this substep starts at the time the
    /// last one ended. A game that rewrites a motion or pose for the time already reached makes it
    /// non-zero (the CPU backend's `collider_jumps` check, the same number: computed on the host in
    /// double from the maps, as the CPU places the vertices).
    [[nodiscard]] double jump() const { return jump_; }

private:
    std::vector<std::size_t> colliders_;   // model collider index of each mesh collider
    std::vector<std::uint32_t> first_map_;  // its first map in the table
    std::size_t count_ = 0, map_count_ = 0;
    std::vector<Affine> maps0_, maps1_;     // scratch: one collider's maps at t and t + h
    // The jump check (jump()): the rest positions, map ids and weights again on the host, every map
    // at the start of this substep and at the end of the last one, and that end's time.
    std::vector<Vec3d> rest_host_;
    std::vector<std::uint32_t> joints_host_;
    std::vector<double> weights_host_;
    std::vector<Affine> start_maps_, end_maps_, last_end_maps_;
    double last_end_time_ = 0.0, jump_ = 0.0;
    bool have_last_end_ = false;
    DeviceArray<float> rest_;               // X_i, SoA stride count_
    DeviceArray<std::uint32_t> joints_;     // 4 map ids a vertex (into the whole table)
    DeviceArray<float> weights_;            // 4 weights a vertex
    DeviceArray<float> maps_;               // kMapFloats a map: A(t), A(t + h), (A(t + h) − A(t))/h, row-major 3×4
    DeviceArray<float> x1_, v_;             // SoA stride count_
    PinnedArray<float> maps_host_;
};

}  // namespace weft::cuda
