// Mesh colliders placed on the device (device_kinematics.h).
#include "device_kinematics.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "kernels.h"
#include "weft/collider.h"
#include "weft/error.h"

namespace weft::cuda {
namespace {

/// Writes `a` row-major as 3 rows of (linear row, translation).
void write_map(const Mat3d& linear, const Vec3d& translation, float* out) {
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) out[4 * r + c] = static_cast<float>(linear(r, c));
        out[4 * r + 3] = static_cast<float>(translation[r]);
    }
}

}  // namespace

void DeviceKinematics::release() {
    colliders_.clear();
    first_map_.clear();
    count_ = map_count_ = 0;
    rest_ = {};
    joints_ = {};
    weights_ = {};
    maps_ = {};
    x1_ = {};
    v_ = {};
    maps_host_.allocate(0);
    rest_host_.clear();
    joints_host_.clear();
    weights_host_.clear();
    start_maps_.clear();
    last_end_maps_.clear();
    have_last_end_ = false;
    jump_ = 0.0;
}

void DeviceKinematics::build(const Model& model, const weft::collision::CollisionGeometry& g, MemoryLedger& ledger) {
    release();
    count_ = g.kinematic_local.size();
    if (count_ == 0) return;
    std::vector<float> rest(3 * count_);
    for (std::size_t j = 0; j < count_; ++j)
        for (int c = 0; c < 3; ++c) rest[static_cast<std::size_t>(c) * count_ + j] = static_cast<float>(g.kinematic_local[j][c]);
    std::vector<std::uint32_t> joints(4 * count_, 0);
    std::vector<double> weights(4 * count_, 0.0);  // in double for the host's jump check; floats to the device
    for (std::size_t m = 0; m < g.meshes.size(); ++m) {
        const ColliderDesc& c = model.colliders[g.meshes[m].collider];
        const std::size_t first = g.meshes[m].first_vertex;
        const std::size_t last = m + 1 < g.meshes.size() ? g.meshes[m + 1].first_vertex : count_;
        const auto base = static_cast<std::uint32_t>(map_count_);
        colliders_.push_back(g.meshes[m].collider);
        first_map_.push_back(base);
        if (c.skin == nullptr) {  // rigid: one map (a character has its joints' even in its bind pose)
            for (std::size_t j = first; j < last; ++j) {
                joints[4 * j] = base;
                weights[4 * j] = 1.0;
            }
            map_count_ += 1;
            continue;
        }
        const SkinnedMesh& skin = *c.skin;
        if (skin.vertex_joints.size() != last - first)
            throw Error("collider '" + c.name + "': its skin has " + std::to_string(skin.vertex_joints.size()) +
                        " vertices, its mesh " + std::to_string(last - first));
        for (std::size_t j = first; j < last; ++j)
            for (std::size_t k = 0; k < 4; ++k) {
                joints[4 * j + k] = base + skin.vertex_joints[j - first][k];
                weights[4 * j + k] = skin.vertex_weights[j - first][k];
            }
        map_count_ += skin.joints.size();
    }
    rest_.upload(rest, ledger, "mesh colliders: rest shape and skin");
    joints_.upload(joints, ledger, "mesh colliders: rest shape and skin");
    std::vector<float> device_weights(weights.size());
    for (std::size_t k = 0; k < weights.size(); ++k) device_weights[k] = static_cast<float>(weights[k]);
    weights_.upload(device_weights, ledger, "mesh colliders: rest shape and skin");
    rest_host_.assign(g.kinematic_local.begin(), g.kinematic_local.end());
    joints_host_ = std::move(joints);
    weights_host_ = std::move(weights);
    maps_.allocate(kKinematicMapFloats * map_count_, ledger, "mesh colliders: maps");
    x1_.allocate(3 * count_, ledger, "mesh colliders: end positions and velocities");
    v_.allocate(3 * count_, ledger, "mesh colliders: end positions and velocities");
    maps_host_.allocate(kKinematicMapFloats * map_count_);
}

void DeviceKinematics::place(const Model& model, double t, double h, float* x0c, float* x1c, std::uint32_t stride,
                             std::uint32_t first, cudaStream_t stream) {
    if (count_ == 0) return;
    float* out = maps_host_.get();
    start_maps_.resize(map_count_);
    end_maps_.resize(map_count_);
    const bool continues = have_last_end_ && std::abs(last_end_time_ - t) <= 1e-9 * std::max(1.0, std::abs(t));
    for (std::size_t m = 0; m < colliders_.size(); ++m) {
        const ColliderDesc& c = model.colliders[colliders_[m]];
        collider_mesh_transforms(c, t, maps0_);
        collider_mesh_transforms(c, t + h, maps1_);
        const std::size_t end = m + 1 < colliders_.size() ? first_map_[m + 1] : map_count_;
        if (maps0_.size() != end - first_map_[m] || maps1_.size() != maps0_.size())
            throw Error("collider '" + c.name + "': " + std::to_string(maps0_.size()) + " skinning maps, " +
                        std::to_string(end - first_map_[m]) + " built (its skin changed after the build)");
        for (std::size_t j = 0; j < maps0_.size(); ++j) {
            float* a = out + kKinematicMapFloats * (first_map_[m] + j);
            const Affine& a0 = maps0_[j];
            const Affine& a1 = maps1_[j];
            write_map(a0.linear, a0.translation, a);
            write_map(a1.linear, a1.translation, a + 12);
            write_map((1.0 / h) * (a1.linear - a0.linear), (a1.translation - a0.translation) / h, a + 24);
            start_maps_[first_map_[m] + j] = a0;
            end_maps_[first_map_[m] + j] = a1;
        }
    }
    // Where the mesh colliders start against where the last substep ended them (the CPU backend's
    // check in cpu_collisions.cpp, begin_substep): each vertex's blend of its maps' difference.
    jump_ = 0.0;
    if (continues)
        for (std::size_t i = 0; i < count_; ++i) {
            Vec3d move{};
            for (std::size_t k = 0; k < 4; ++k) {
                const double w = weights_host_[4 * i + k];
                if (w == 0.0) continue;
                const std::uint32_t j = joints_host_[4 * i + k];
                const Affine& a = start_maps_[j];
                const Affine& b = last_end_maps_[j];
                move += w * ((a.linear - b.linear) * rest_host_[i] + (a.translation - b.translation));
            }
            jump_ = std::max(jump_, math::length(move));
        }
    last_end_maps_.swap(end_maps_);  // this substep's end, for the next one
    last_end_time_ = t + h;
    have_last_end_ = true;
    WEFT_CUDA_CHECK(cudaMemcpyAsync(maps_.get(), out, kKinematicMapFloats * map_count_ * sizeof(float),
                                    cudaMemcpyHostToDevice, stream));
    launch_place_kinematic(rest_.get(), joints_.get(), weights_.get(), maps_.get(), static_cast<std::uint32_t>(count_),
                           x0c + first, x1c + first, stride, x1_.get(), v_.get(), stream);
}

}  // namespace weft::cuda
