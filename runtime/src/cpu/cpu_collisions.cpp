// Collision stages of a CPU substep (see cpu_collisions.h and docs/collisions.md).
#include "cpu/cpu_collisions.h"

#include <algorithm>
#include <chrono>

#include "weft/backend/timing.h"

namespace weft::cpu {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

template <typename T>
void CpuCollisions<T>::build(const FlatModel& flat, const Model& model) {
    *this = CpuCollisions{};
    geometry_ = collision::build_collision_geometry(flat, model);
    const collision::CollisionGeometry& g = geometry_;
    active_ = g.self || !g.meshes.empty();
    if (!active_) return;
    if (g.self) {
        // Built over every triangle (mesh colliders too: their patches only ever meet cloth patches
        // of other groups, which are never culled); the positions only guide the splits.
        std::vector<Vec3d> rest(flat.initial_positions);
        rest.insert(rest.end(), g.kinematic_local.begin(), g.kinematic_local.end());
        hierarchy_ = std::make_unique<collision::PatchHierarchy>(
            collision::build_patch_hierarchy(rest, g.triangles, g.edges, g.triangle_group));
        front_ = std::make_unique<collision::NormalConeFront>(*hierarchy_);
    }
    x0_.resize(g.vertex_count());
    x1_.resize(g.vertex_count());
    kinematic_x1_t_.resize(g.kinematic_vertices());
    kinematic_v_t_.resize(g.kinematic_vertices());
}

template <typename T>
void CpuCollisions<T>::begin_substep(const Model& model, double t, double h, const std::vector<V3>& x0,
                                     const std::vector<V3>& v0, StepStats& stats) {
    auto clock = Clock::now();
    const CollisionSettings& settings = model.settings.collision;
    const collision::CollisionGeometry& g = geometry_;
    const std::size_t n = g.cloth_vertices;
    const std::span<Vec3d> kinematic_x0 = std::span<Vec3d>(x0_).subspan(n);
    const std::span<Vec3d> kinematic_x1 = std::span<Vec3d>(x1_).subspan(n);
    g.place_kinematic(model, t, kinematic_x0);
    g.place_kinematic(model, t + h, kinematic_x1);
    for (std::size_t j = 0; j < g.kinematic_vertices(); ++j) {
        kinematic_x1_t_[j] = kinematic_x1[j].template cast<T>();
        kinematic_v_t_[j] = ((kinematic_x1[j] - kinematic_x0[j]) / h).template cast<T>();
    }
    // The predicted end of the substep: x0 + h·v0 for the cloth, the pose at t + h for colliders.
    parallel_chunks(n, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) {
            x0_[i] = x0[i].template cast<double>();
            x1_[i] = (x0[i] + static_cast<T>(h) * v0[i]).template cast<double>();
        }
    });

    collision::BroadPhaseInput in;
    in.x0 = x0_;
    in.x1 = x1_;
    in.triangles = g.triangles;
    in.edges = g.edges;
    in.triangle_cloth = g.triangle_group;
    in.thickness = g.gap(settings);
    in.self_pairs = g.self;
    stats.ms(Stage::BroadPhase) += ms_since(clock);
    // The proximity stage culls only on request (CollisionSettings::cull_contacts says why).
    if (settings.cull_contacts) cull(model, x0_, x1_, in, stats);
    clock = Clock::now();
    broad_.find(in, pairs_);
    stats.collision.candidate_pairs += static_cast<std::int64_t>(pairs_.vf.size() + pairs_.ee.size());
    stats.collision.culled_pairs += static_cast<std::int64_t>(pairs_.counters.culled_pairs);
    stats.ms(Stage::BroadPhase) += ms_since(clock);

    clock = Clock::now();
    collision::ProximityInput p;
    p.x0 = x0_;
    p.x1 = x1_;
    p.inverse_mass = g.inverse_mass;
    p.thickness = g.thickness;
    p.friction = g.friction;
    p.triangles = g.triangles;
    p.edges = g.edges;
    p.vf = pairs_.vf;
    p.ee = pairs_.ee;
    p.rest = g.rest;
    p.vertex_cloth = g.vertex_cloth;
    p.rest_exclusion = settings.rest_exclusion;
    p.h = h;
    p.thickness_override = settings.thickness;
    p.stiffness_override = settings.stiffness;
    collision::find_proximity_contacts(p, contacts_);
    terms_.set(contacts_, n);
    stats.collision.contacts = static_cast<int>(contacts_.size());
    stats.ms(Stage::NarrowPhase) += ms_since(clock);
}

template <typename T>
void CpuCollisions<T>::end_substep(const Model& model, double h, const std::vector<V3>& x0, std::vector<V3>& x1,
                                   std::vector<V3>& v, StepStats& stats) {
    const CollisionSettings& settings = model.settings.collision;
    if (!settings.continuous) return;
    const collision::CollisionGeometry& g = geometry_;
    parallel_chunks(g.cloth_vertices, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) x1_[i] = x1[i].template cast<double>();
    });
    // x0_ and the kinematic part of x1_ still hold what begin_substep placed there.
    collision::ImpactZoneInput in;
    in.x0 = x0_;
    in.x1 = x1_;
    in.inverse_mass = g.inverse_mass;
    in.triangles = g.triangles;
    in.edges = g.edges;
    in.triangle_cloth = g.triangle_group;
    in.self_pairs = g.self;
    in.thickness = g.gap(settings);
    in.max_iterations = settings.max_impact_iterations;
    if (settings.impact_tolerance > 0.0) in.qp_tolerance_ratio = settings.impact_tolerance;
    if (settings.max_impact_sweeps > 0) in.qp_max_sweeps = settings.max_impact_sweeps;
    // The zones move x1 between detections, so the cones are refitted before each one: a cone
    // bounded over an older motion could cull a pair that now collides.
    in.refresh_broad_phase = [&](int /*detection*/, collision::BroadPhaseInput& b) { cull(model, b.x0, b.x1, b, stats); };
    collision::add_to_stats(zones_.resolve(in), stats);
    // Vertices the zones moved take the velocity of their corrected motion.
    const T inv_h = static_cast<T>(1.0 / h);
    parallel_chunks(g.cloth_vertices, [&](std::size_t lo, std::size_t hi) {
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
    const collision::CollisionGeometry& g = geometry_;
    return (g.kinematic_local.capacity() + x0_.capacity() + x1_.capacity()) * sizeof(Vec3d) +
           (kinematic_x1_t_.capacity() + kinematic_v_t_.capacity()) * sizeof(V3) +
           g.triangles.capacity() * sizeof(Triangle) + g.triangle_group.capacity() * sizeof(std::uint32_t) +
           g.edges.capacity() * sizeof(collision::Edge) +
           (g.inverse_mass.capacity() + g.thickness.capacity() + g.friction.capacity()) * sizeof(double) +
           contacts_.capacity() * sizeof(collision::ProximityContact) + terms_.memory_bytes();
}

template class CpuCollisions<float>;
template class CpuCollisions<double>;

}  // namespace weft::cpu
