// Collision stages of a CPU substep (see cpu_collisions.h and docs/collisions.md).
#include "cpu/cpu_collisions.h"

#include <algorithm>
#include <chrono>

#include "weft/error.h"

namespace weft::cpu {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

template <typename T>
void CpuCollisions<T>::build(const FlatModel& flat, const Model& model) {
    *this = CpuCollisions{};
    self_ = model.settings.collision.self_collision;
    cloth_vertices_ = flat.vertex_count;
    const std::size_t cloths = model.cloths.size();
    std::uint32_t kinematic = 0;
    for (std::size_t k = 0; k < model.colliders.size(); ++k) {
        const ColliderDesc& c = model.colliders[k];
        if (c.is_analytic()) continue;
        if (!c.mesh) throw Error("collider '" + c.name + "' is a mesh collider without a mesh");
        meshes_.push_back({k, kinematic});
        kinematic += static_cast<std::uint32_t>(c.mesh->positions.size());
    }
    active_ = self_ || !meshes_.empty();
    if (!active_) return;

    // Triangles: the cloth's, then each mesh collider's shifted into the kinematic range.
    triangles_ = flat.triangles;
    triangle_group_.resize(flat.triangle_count());
    for (std::size_t t = 0; t < flat.triangle_count(); ++t)
        triangle_group_[t] = self_ ? flat.triangle_cloth[t] : 0;  // without self-collision: one group
    kinematic_local_.clear();
    for (std::size_t m = 0; m < meshes_.size(); ++m) {
        const MeshData& mesh = *model.colliders[meshes_[m].collider].mesh;
        const auto base = static_cast<std::uint32_t>(cloth_vertices_) + meshes_[m].first_vertex;
        for (const Triangle& tri : mesh.triangles) {
            triangles_.push_back({{base + tri.v[0], base + tri.v[1], base + tri.v[2]}});
            triangle_group_.push_back(static_cast<std::uint32_t>(cloths + m));
        }
        kinematic_local_.insert(kinematic_local_.end(), mesh.positions.begin(), mesh.positions.end());
    }
    edges_ = collision::build_edges(triangles_);
    if (self_) {
        // Built over every triangle (mesh colliders too: their patches only ever meet cloth patches
        // of other groups, which are never culled); the positions only guide the splits.
        std::vector<Vec3d> rest(flat.initial_positions);
        for (const MeshCollider& mc : meshes_)
            for (const Vec3d& p : model.colliders[mc.collider].mesh->positions) rest.push_back(p);
        hierarchy_ = std::make_unique<collision::PatchHierarchy>(
            collision::build_patch_hierarchy(rest, triangles_, edges_, triangle_group_));
        front_ = std::make_unique<collision::NormalConeFront>(*hierarchy_);
    }

    const std::size_t n = cloth_vertices_ + kinematic_local_.size();
    inverse_mass_.assign(n, 0.0);
    thickness_.assign(n, 0.0);
    friction_.assign(n, 0.0);
    for (std::size_t i = 0; i < cloth_vertices_; ++i) {
        const bool pinned = flat.vertex_pin[i] >= 0;
        inverse_mass_[i] = pinned || !(flat.mass[i] > 0.0) ? 0.0 : 1.0 / flat.mass[i];
        const Material& material = model.cloths[flat.vertex_cloth[i]].material;
        thickness_[i] = material.contact_thickness;
        friction_[i] = material.friction;
        max_thickness_ = std::max(max_thickness_, thickness_[i]);
    }
    for (const MeshCollider& mc : meshes_) {
        const ColliderDesc& c = model.colliders[mc.collider];
        const std::size_t count = c.mesh->positions.size();
        for (std::size_t j = 0; j < count; ++j)
            friction_[cloth_vertices_ + mc.first_vertex + j] = c.friction >= 0.0 ? c.friction : 0.0;
    }
    x0_.resize(n);
    x1_.resize(n);
    kinematic_x0_.resize(kinematic_local_.size());
    kinematic_x1_.resize(kinematic_local_.size());
    kinematic_x1_t_.resize(kinematic_local_.size());
    kinematic_v_t_.resize(kinematic_local_.size());
}

template <typename T>
void CpuCollisions<T>::place_kinematic(const Model& model, double t, std::vector<Vec3d>& out) const {
    for (std::size_t m = 0; m < meshes_.size(); ++m) {
        const ColliderDesc& c = model.colliders[meshes_[m].collider];
        const Transform frame = c.motion.at(t);
        const std::size_t first = meshes_[m].first_vertex;
        const std::size_t last = m + 1 < meshes_.size() ? meshes_[m + 1].first_vertex : kinematic_local_.size();
        for (std::size_t j = first; j < last; ++j) out[j] = frame.apply(kinematic_local_[j]);
    }
}

template <typename T>
void CpuCollisions<T>::begin_substep(const Model& model, double t, double h, const std::vector<V3>& x0,
                                     const std::vector<V3>& v0, StepStats& stats) {
    auto clock = Clock::now();
    const CollisionSettings& settings = model.settings.collision;
    place_kinematic(model, t, kinematic_x0_);
    place_kinematic(model, t + h, kinematic_x1_);
    const std::size_t nk = kinematic_local_.size();
    for (std::size_t j = 0; j < nk; ++j) {
        kinematic_x1_t_[j] = kinematic_x1_[j].template cast<T>();
        kinematic_v_t_[j] = ((kinematic_x1_[j] - kinematic_x0_[j]) / h).template cast<T>();
    }
    // The predicted end of the substep: x0 + h·v0 for the cloth, the pose at t + h for colliders.
    parallel_chunks(cloth_vertices_, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) {
            x0_[i] = x0[i].template cast<double>();
            x1_[i] = (x0[i] + static_cast<T>(h) * v0[i]).template cast<double>();
        }
    });
    std::copy(kinematic_x0_.begin(), kinematic_x0_.end(), x0_.begin() + static_cast<std::ptrdiff_t>(cloth_vertices_));
    std::copy(kinematic_x1_.begin(), kinematic_x1_.end(), x1_.begin() + static_cast<std::ptrdiff_t>(cloth_vertices_));

    const double thickness = settings.thickness > 0.0 ? settings.thickness : max_thickness_;
    collision::BroadPhaseInput in;
    in.x0 = x0_;
    in.x1 = x1_;
    in.triangles = triangles_;
    in.edges = edges_;
    in.triangle_cloth = triangle_group_;
    in.thickness = thickness;
    in.self_pairs = self_;
    stats.ms(Stage::BroadPhase) += ms_since(clock);
    cull(model, x0_, x1_, in, stats);
    clock = Clock::now();
    broad_.find(in, pairs_);
    stats.collision.candidate_pairs += static_cast<std::int64_t>(pairs_.vf.size() + pairs_.ee.size());
    stats.collision.culled_pairs += static_cast<std::int64_t>(pairs_.counters.culled_pairs);
    stats.ms(Stage::BroadPhase) += ms_since(clock);

    clock = Clock::now();
    collision::ProximityInput p;
    p.x0 = x0_;
    p.x1 = x1_;
    p.inverse_mass = inverse_mass_;
    p.thickness = thickness_;
    p.friction = friction_;
    p.triangles = triangles_;
    p.edges = edges_;
    p.vf = pairs_.vf;
    p.ee = pairs_.ee;
    p.h = h;
    p.thickness_override = settings.thickness;
    p.stiffness_override = settings.stiffness;
    collision::find_proximity_contacts(p, contacts_);
    terms_.set(contacts_, cloth_vertices_);
    stats.collision.contacts = static_cast<int>(contacts_.size());
    stats.ms(Stage::NarrowPhase) += ms_since(clock);
}

template <typename T>
void CpuCollisions<T>::end_substep(const Model& model, double h, const std::vector<V3>& x0, std::vector<V3>& x1,
                                   std::vector<V3>& v, StepStats& stats) {
    const CollisionSettings& settings = model.settings.collision;
    if (!settings.continuous) return;
    parallel_chunks(cloth_vertices_, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) x1_[i] = x1[i].template cast<double>();
    });
    // x0_ and the kinematic part of x1_ still hold what begin_substep placed there.
    collision::ImpactZoneInput in;
    in.x0 = x0_;
    in.x1 = x1_;
    in.inverse_mass = inverse_mass_;
    in.triangles = triangles_;
    in.edges = edges_;
    in.triangle_cloth = triangle_group_;
    in.self_pairs = self_;
    in.thickness = settings.thickness > 0.0 ? settings.thickness : max_thickness_;
    in.max_iterations = settings.max_impact_iterations;
    // The zones move x1 between detections, so the cones are refitted before each one: a cone
    // bounded over an older motion could cull a pair that now collides.
    in.refresh_broad_phase = [&](int /*detection*/, collision::BroadPhaseInput& b) { cull(model, b.x0, b.x1, b, stats); };
    const collision::ImpactZoneReport r = zones_.resolve(in);
    CollisionStats& c = stats.collision;
    c.candidate_pairs += r.candidate_pairs;
    c.ccd_tests += r.ccd_tests;
    c.ccd_hits += r.ccd_hits;
    c.impact_zones += r.zones;
    c.impact_iterations = std::max(c.impact_iterations, r.iterations);
    c.rigid_zones += r.rigid_zones;
    c.frozen_vertices += r.frozen_vertices;
    if (!r.resolved) ++c.unresolved_substeps;
    stats.ms(Stage::BroadPhase) += r.broad_phase_ms;
    stats.ms(Stage::Ccd) += r.ccd_ms;
    stats.ms(Stage::ImpactZones) += r.zones_ms;
    // Vertices the zones moved take the velocity of their corrected motion.
    const T inv_h = static_cast<T>(1.0 / h);
    parallel_chunks(cloth_vertices_, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) {
            const V3 corrected = x1_[i].template cast<T>();
            if (corrected.x == x1[i].x && corrected.y == x1[i].y && corrected.z == x1[i].z) continue;
            x1[i] = corrected;
            v[i] = (corrected - x0[i]) * inv_h;
        }
    });
}

template <typename T>
void CpuCollisions<T>::cull(const Model& model, std::span<const Vec3d> x0, std::span<const Vec3d> x1,
                            collision::BroadPhaseInput& in, StepStats& stats) {
    const CollisionSettings& settings = model.settings.collision;
    in.count_culled = settings.count_culled;
    if (!front_ || settings.culling != CollisionCulling::NormalCone) {
        in.vertex_patch = {};
        in.edge_patch = {};
        in.triangle_patch = {};
        return;
    }
    const auto clock = Clock::now();
    front_->update(x0, x1);
    in.vertex_patch = front_->vertex_patch();
    in.edge_patch = front_->edge_patch();
    in.triangle_patch = front_->triangle_patch();
    stats.ms(Stage::Culling) += ms_since(clock);
}

template <typename T>
std::size_t CpuCollisions<T>::memory_bytes() const {
    return (kinematic_local_.capacity() + x0_.capacity() + x1_.capacity() + kinematic_x0_.capacity() +
            kinematic_x1_.capacity()) * sizeof(Vec3d) +
           (kinematic_x1_t_.capacity() + kinematic_v_t_.capacity()) * sizeof(V3) +
           triangles_.capacity() * sizeof(Triangle) + triangle_group_.capacity() * sizeof(std::uint32_t) +
           edges_.capacity() * sizeof(collision::Edge) +
           (inverse_mass_.capacity() + thickness_.capacity() + friction_.capacity()) * sizeof(double) +
           contacts_.capacity() * sizeof(collision::ProximityContact) + terms_.memory_bytes();
}

template class CpuCollisions<float>;
template class CpuCollisions<double>;

}  // namespace weft::cpu
