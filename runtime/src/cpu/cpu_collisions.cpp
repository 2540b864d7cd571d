// Collision stages of a CPU substep (see cpu_collisions.h and docs/collisions.md).
#include "cpu/cpu_collisions.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include "collision/buffer_trim.h"
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
    if (!active_) {
        geometry_ = {};  // a scene without cloth collisions holds none of their memory
        return;
    }
    if (g.self) {
        // Built over every triangle (mesh colliders too: their patches only ever meet cloth patches
        // of other groups, which are never culled); the positions only guide the splits.
        std::vector<Vec3d> rest(flat.initial_positions);
        rest.insert(rest.end(), g.kinematic_local.begin(), g.kinematic_local.end());
        hierarchy_ = std::make_unique<collision::PatchHierarchy>(
            collision::build_patch_hierarchy(rest, g.triangles, g.edges, g.triangle_group));
        front_ = std::make_unique<collision::NormalConeFront>(*hierarchy_);
    }
    closed_ = collision::find_closed_pieces(g);
    x0_.resize(g.vertex_count());
    x1_.resize(g.vertex_count());
    kinematic_x1_t_.resize(g.kinematic_vertices());
    kinematic_v_t_.resize(g.kinematic_vertices());
}

template <typename T>
collision::ProximityInput CpuCollisions<T>::proximity_input(const CollisionSettings& settings, std::span<const Vec3d> x0,
                                                            std::span<const Vec3d> x1,
                                                            const collision::BroadPhaseResult& pairs, double h) const {
    const collision::CollisionGeometry& g = geometry_;
    collision::ProximityInput p;
    p.x0 = x0;
    p.x1 = x1;
    p.inverse_mass = g.inverse_mass;
    p.thickness = g.thickness;
    p.friction = g.friction;
    p.triangles = g.triangles;
    p.edges = g.edges;
    p.vf = pairs.vf;
    p.ee = pairs.ee;
    p.rest = g.rest;
    p.vertex_cloth = g.vertex_cloth;
    p.rest_exclusion = settings.rest_exclusion;
    p.h = h;
    p.thickness_override = settings.thickness;
    p.stiffness_override = settings.stiffness;
    return p;
}

template <typename T>
std::size_t CpuCollisions<T>::begin_substep(const Model& model, double t, double h, std::vector<V3>& x0, std::vector<V3>& v0,
                                            const std::vector<V3>& dv_previous, StepStats& stats) {
    auto clock = Clock::now();
    const CollisionSettings& settings = model.settings.collision;
    const collision::CollisionGeometry& g = geometry_;
    const std::size_t n = g.cloth_vertices;
    const std::span<Vec3d> kinematic_x0 = std::span<Vec3d>(x0_).subspan(n);
    const std::span<Vec3d> kinematic_x1 = std::span<Vec3d>(x1_).subspan(n);
    g.place_kinematic(model, t, kinematic_x0);
    g.place_kinematic(model, t + h, kinematic_x1);
    // A mesh collider that does not start this substep where it ended the last one was moved by
    // something no substep's motion covers (a game editing its motion or pose for the past, a clip
    // switched with a jump in its pose): the cloth can end up through it unseen. Counted, not fixed.
    if (last_kinematic_end_.size() == kinematic_x0.size() && std::abs(last_end_time_ - t) <= 1e-9 * std::max(1.0, std::abs(t))) {
        double jump = 0.0;
        for (std::size_t j = 0; j < kinematic_x0.size(); ++j) jump = std::max(jump, math::length(kinematic_x0[j] - last_kinematic_end_[j]));
        if (jump > 0.1 * g.gap(settings)) {
            ++stats.collision.collider_jumps;
            stats.collision.collider_jump_max = std::max(stats.collision.collider_jump_max, jump);
        }
    }
    last_kinematic_end_.assign(kinematic_x1.begin(), kinematic_x1.end());
    last_end_time_ = t + h;
    for (std::size_t j = 0; j < g.kinematic_vertices(); ++j) {
        kinematic_x1_t_[j] = kinematic_x1[j].template cast<T>();
        kinematic_v_t_[j] = ((kinematic_x1[j] - kinematic_x0[j]) / h).template cast<T>();
    }
    // Cloth inside a closed piece of a mesh collider: just outside the nearest point of its surface,
    // with the surface's velocity there plus its own along the surface (collision/closed_colliders.h).
    std::size_t ejected = 0;
    if (!closed_.empty()) {
        for (std::size_t i = 0; i < n; ++i) x0_[i] = x0[i].template cast<double>();
        kinematic_velocity_.resize(g.kinematic_vertices());
        for (std::size_t j = 0; j < kinematic_velocity_.size(); ++j) kinematic_velocity_[j] = (kinematic_x1[j] - kinematic_x0[j]) / h;
        for (const collision::Ejection& e : collision::find_ejections(g, closed_, x0_, kinematic_velocity_, g.gap(settings))) {
            Vec3d relative = v0[e.vertex].template cast<double>() - e.surface_velocity;
            const double into = math::dot(relative, e.normal);
            if (into < 0.0) relative -= into * e.normal;
            x0[e.vertex] = e.position.template cast<T>();
            v0[e.vertex] = (e.surface_velocity + relative).template cast<T>();
            ++ejected;
        }
        stats.collision.ejected_vertices += static_cast<int>(ejected);
    }
    // The predicted end of the substep: x0 + h·v0 for the cloth, the pose at t + h for colliders.
    parallel_chunks(n, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) {
            x0_[i] = x0[i].template cast<double>();
            x1_[i] = (x0[i] + static_cast<T>(h) * v0[i]).template cast<double>();
        }
    });

    offset_ = settings.mode == CollisionMode::Offset;
    if (offset_) {
        fallback_ = false;
        redetections_ = 0;
        last_truncated_ = 0;
        // The frame the moves are bounded in translates with the cloth's mean velocity (mass-weighted
        // over the free vertices): a stack falling together moves little relative to it.
        Vec3d momentum{};
        double mass = 0.0;
        free_vertices_ = 0;
        for (std::size_t i = 0; i < n; ++i) {
            if (!(g.inverse_mass[i] > 0.0)) continue;
            momentum += (1.0 / g.inverse_mass[i]) * v0[i].template cast<double>();
            mass += 1.0 / g.inverse_mass[i];
            ++free_vertices_;
        }
        shift_ = mass > 0.0 ? (h / mass) * momentum : Vec3d{};
        x_detect_ = x0_;
        // Each vertex's query radius covers 1.5× its predicted move in that frame over γ (so it is
        // rarely truncated), from one contact radius to the cap. The move is predicted both at the
        // start velocity and with the last substep's velocity change repeated (a vertex slowing
        // against a collider, or speeding up), and the longer is taken.
        const double contact = g.gap(settings), cap = settings.max_query_radius * contact;
        radius_.resize(g.vertex_count());
        for (std::size_t i = 0; i < radius_.size(); ++i) {
            double move = math::length(x1_[i] - x0_[i] - shift_);
            if (i < n) move = std::max(move, math::length(x1_[i] + h * dv_previous[i].template cast<double>() - x0_[i] - shift_));
            radius_[i] = std::clamp(1.5 * move / settings.relaxation, contact, cap);
        }
        remainder_.assign(n, 0.0);
        stats.ms(Stage::BroadPhase) += ms_since(clock);
        detect_offset(model, h, x1_, stats);
        return ejected;
    }

    collision::BroadPhaseInput in;
    in.x0 = x0_;
    in.x1 = x1_;
    in.triangles = g.triangles;
    in.edges = g.edges;
    in.triangle_cloth = g.triangle_group;
    in.thickness = g.gap(settings);
    in.self_pairs = g.self;
    in.frame_motion = common_motion();
    in.first_kinematic_group = g.first_kinematic_group;
    stats.ms(Stage::BroadPhase) += ms_since(clock);
    // The proximity stage culls only on request (CollisionSettings::cull_contacts says why).
    if (settings.cull_contacts) cull(model, x0_, x1_, in, stats);
    clock = Clock::now();
    broad_.find(in, pairs_);
    stats.collision.candidate_pairs += static_cast<std::int64_t>(pairs_.vf.size() + pairs_.ee.size());
    stats.collision.culled_pairs += static_cast<std::int64_t>(pairs_.counters.culled_pairs);
    stats.ms(Stage::BroadPhase) += ms_since(clock);

    clock = Clock::now();
    find_contacts(proximity_input(settings, x0_, x1_, pairs_, h));
    terms_.set(contacts_, n);
    stats.collision.contacts = static_cast<int>(contacts_.size());
    stats.ms(Stage::NarrowPhase) += ms_since(clock);
    return ejected;
}

template <typename T>
void CpuCollisions<T>::detect_offset(const Model& model, double h, std::span<const Vec3d> x_end, StepStats& stats) {
    const auto clock = Clock::now();
    const CollisionSettings& settings = model.settings.collision;
    // Normal-cone culling of the bound query (with CollisionSettings::cull_contacts: the bound query
    // is this mode's contact detection): patches free of self-collision over the predicted motion
    // x_detect → x_end measure no pairs inside them; `truncate` certifies them again over the actual
    // update and measures everything where that fails (docs/methods.md §7b). Off by default: where
    // it culls (sheets finer than the query radius) the patches fail over the actual update in a
    // third of the updates, and the re-measurement cost more than the culling saved (5 sheets of 69²
    // cells on the CPU: 10.2 against 9.1 s per frame).
    culled_ = front_ != nullptr && settings.culling == CollisionCulling::NormalCone && settings.cull_contacts;
    if (culled_) {
        const auto cull_clock = Clock::now();
        front_->update(x_detect_, x_end);
        const auto ids = [&](auto& out) {
            out.clear();
            for (const auto span : {front_->vertex_patch(), front_->edge_patch(), front_->triangle_patch()})
                out.insert(out.end(), span.begin(), span.end());
        };
        ids(detect_patch_);
        stats.ms(Stage::Culling) += ms_since(cull_clock);
    }
    measure_bounds(model, culled_);
    stats.collision.candidate_pairs += static_cast<std::int64_t>(bounds_.vf_pairs + bounds_.ee_pairs);
    for (const double r : radius_) stats.collision.query_radius_max = std::max(stats.collision.query_radius_max, r);
    stats.ms(Stage::BroadPhase) += ms_since(clock);
    find_offset_contacts(model, h, stats);
}

template <typename T>
void CpuCollisions<T>::measure_bounds(const Model& model, bool culled) {
    const CollisionSettings& settings = model.settings.collision;
    const collision::CollisionGeometry& g = geometry_;
    collision::DisplacementBoundsInput in;
    in.x = x_detect_;
    in.triangles = g.triangles;
    in.edges = g.edges;
    in.radius = radius_;
    in.relaxation = settings.relaxation;
    in.self_pairs = g.self;
    in.triangle_group = g.triangle_group;
    if (culled) {
        const std::size_t nv = g.vertex_count(), ne = g.edges.size();
        in.vertex_patch = std::span<const std::uint32_t>(detect_patch_).subspan(0, nv);
        in.edge_patch = std::span<const std::uint32_t>(detect_patch_).subspan(nv, ne);
        in.triangle_patch = std::span<const std::uint32_t>(detect_patch_).subspan(nv + ne);
    }
    collision::compute_displacement_bounds(in, broad_, bounds_);
}

template <typename T>
void CpuCollisions<T>::find_contacts(const collision::ProximityInput& input) {
    contact_candidates_peak_ = std::max(contact_candidates_peak_, input.vf.size() + input.ee.size());
    collision::find_proximity_contacts(input, contacts_);
    if (++contact_calls_ < collision::kTrimPeriod) return;
    (void)collision::trim_to_peak(contacts_, contact_candidates_peak_);
    contact_calls_ = 0;
    contact_candidates_peak_ = 0;
}

template <typename T>
void CpuCollisions<T>::find_offset_contacts(const Model& model, double h, StepStats& stats) {
    const auto clock = Clock::now();
    const CollisionSettings& settings = model.settings.collision;
    const collision::CollisionGeometry& g = geometry_;
    collision::ProximityInput p = proximity_input(settings, x_detect_, x_detect_, bounds_.pairs, h);
    p.offset_bound = bounds_.bound;
    find_contacts(p);
    terms_.set(contacts_, g.cloth_vertices, true);
    stats.collision.contacts = static_cast<int>(contacts_.size());
    stats.ms(Stage::NarrowPhase) += ms_since(clock);
}

template <typename T>
std::size_t CpuCollisions<T>::truncate(const Model& model, double h, const std::vector<V3>& x0, std::vector<V3>& vk,
                                       StepStats& stats) {
    if (!culled_) return truncate_to_bounds(model, h, x0, vk, stats);
    // The culled pairs are safe only if their patches stay free of self-collision over the update
    // actually taken (the detection's front was over the predicted motion): the front is updated over
    // x_detect → the truncated positions; where a culled patch no longer holds, every pair is measured
    // and the proposal truncated again.
    proposal_ = vk;
    const std::size_t count = truncate_to_bounds(model, h, x0, vk, stats);
    const auto clock = Clock::now();
    const collision::CollisionGeometry& g = geometry_;
    const std::size_t n = g.cloth_vertices;
    x_update_.resize(g.vertex_count());
    for (std::size_t i = 0; i < n; ++i) x_update_[i] = (x0[i] + static_cast<T>(h) * vk[i]).template cast<double>() - shift_;
    for (std::size_t i = n; i < g.vertex_count(); ++i) x_update_[i] = x1_[i] - shift_;
    front_->update(x_detect_, x_update_);
    update_patch_.clear();
    for (const auto span : {front_->vertex_patch(), front_->edge_patch(), front_->triangle_patch()})
        update_patch_.insert(update_patch_.end(), span.begin(), span.end());
    stats.ms(Stage::Culling) += ms_since(clock);
    if (collision::patches_hold(detect_patch_, update_patch_)) return count;
    ++stats.collision.uncullings;
    culled_ = false;
    measure_bounds(model, false);
    stats.collision.truncated_vertices -= static_cast<std::int64_t>(count);
    vk = proposal_;
    return truncate_to_bounds(model, h, x0, vk, stats);
}

template <typename T>
std::size_t CpuCollisions<T>::truncate_to_bounds(const Model& model, double h, const std::vector<V3>& x0,
                                                 std::vector<V3>& vk, StepStats& stats) {
    const auto clock = Clock::now();
    const bool planar = model.settings.collision.bound_shape == BoundShape::Planar;
    const collision::CollisionGeometry& g = geometry_;
    const std::size_t n = g.cloth_vertices;
    std::atomic<std::size_t> truncated{0};
    std::atomic<bool> broken{false};
    parallel_chunks(n, [&](std::size_t lo, std::size_t hi) {
        std::size_t count = 0;
        for (std::size_t i = lo; i < hi; ++i) {
            const Vec3d x = (x0[i] + static_cast<T>(h) * vk[i]).template cast<double>();
            const Vec3d move = x - shift_ - x_detect_[i];
            const double t = collision::kept_share(bounds_, i, move, planar);
            remainder_[i] = t < 1.0 ? (1.0 - t) * math::length(move) : 0.0;
            if (t >= 1.0) continue;
            if (!(g.inverse_mass[i] > 0.0)) {  // pinned: its move is prescribed
                broken = true;
                continue;
            }
            const Vec3d kept = x_detect_[i] + t * move + shift_;
            vk[i] = ((kept - x0[i].template cast<double>()) / h).template cast<T>();
            ++count;
        }
        truncated += count;
    });
    // Mesh colliders move as prescribed: their whole move of the piece is checked.
    for (std::size_t i = n; i < g.vertex_count() && !broken; ++i)
        if (collision::kept_share(bounds_, i, x1_[i] - shift_ - x_detect_[i], planar) < 1.0) broken = true;
    fallback_ = fallback_ || broken;
    last_truncated_ = truncated;
    stats.collision.truncated_vertices += static_cast<std::int64_t>(last_truncated_);
    stats.ms(Stage::Update) += ms_since(clock);
    return last_truncated_;
}

template <typename T>
bool CpuCollisions<T>::wants_redetection(const Model& model) const {
    const CollisionSettings& settings = model.settings.collision;
    return offset_ && redetections_ < settings.max_redetections &&
           static_cast<double>(last_truncated_) > settings.redetect_share * static_cast<double>(free_vertices_);
}

template <typename T>
void CpuCollisions<T>::redetect(const Model& model, double h, const std::vector<V3>& x0, const std::vector<V3>& vk,
                                StepStats& stats) {
    const CollisionSettings& settings = model.settings.collision;
    const collision::CollisionGeometry& g = geometry_;
    const std::size_t n = g.cloth_vertices;
    // From here the colliders stand at t + h and the cloth where the truncation left it; each radius
    // covers 1.5× what the truncation cut from the vertex's last move.
    const double contact = g.gap(settings), cap = settings.max_query_radius * contact;
    for (std::size_t i = 0; i < n; ++i) {
        x_detect_[i] = (x0[i] + static_cast<T>(h) * vk[i]).template cast<double>();
        radius_[i] = std::clamp(1.5 * remainder_[i] / settings.relaxation, contact, cap);
    }
    for (std::size_t i = n; i < g.vertex_count(); ++i) {
        x_detect_[i] = x1_[i];
        radius_[i] = contact;
    }
    shift_ = Vec3d{};
    ++redetections_;
    ++stats.collision.redetections;
    detect_offset(model, h, x_detect_, stats);
}

template <typename T>
void CpuCollisions<T>::end_substep(const Model& model, double h, const std::vector<V3>& x0, std::vector<V3>& x1,
                                   std::vector<V3>& v, bool moved_after_solve, StepStats& stats) {
    const CollisionSettings& settings = model.settings.collision;
    if (offset_) {
        if (!fallback_ && !moved_after_solve) return;
        ++stats.collision.bound_fallbacks;
    }
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
    in.broad_phase.frame_motion = common_motion();
    in.broad_phase.first_kinematic_group = g.first_kinematic_group;
    in.max_iterations = settings.max_impact_iterations;
    if (settings.impact_tolerance > 0.0) in.qp_tolerance_ratio = settings.impact_tolerance;
    if (settings.max_impact_sweeps > 0) in.qp_max_sweeps = settings.max_impact_sweeps;
    if (settings.max_impact_work >= 1.0) in.qp_max_work = static_cast<std::int64_t>(settings.max_impact_work);
    in.ccd_time_tolerance = settings.ccd_time_tolerance;
    // The zones move x1 between detections, so the cones are refitted before each one: a cone
    // bounded over an older motion could cull a pair that now collides.
    in.refresh_broad_phase = [&](int /*detection*/, collision::BroadPhaseInput& b) { cull(model, b.x0, b.x1, b, stats); };
    // The proximity detection's pairs hold the first detection's wherever the solve moved no vertex
    // much farther than predicted: its bounds are grown by the contact thickness, the CCD's by eta.
    in.earlier_broad_phase = &broad_;
    in.earlier_pairs = &pairs_;
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
Vec3d CpuCollisions<T>::common_motion() const {
    // The mass-weighted mean of the free cloth vertices' moves x1_ − x0_, in vertex order (the same
    // bits on any thread count): the broad phase's frame (BroadPhaseInput::frame_motion).
    const collision::CollisionGeometry& g = geometry_;
    Vec3d momentum{};
    double mass = 0.0;
    for (std::size_t i = 0; i < g.cloth_vertices; ++i) {
        if (!(g.inverse_mass[i] > 0.0)) continue;
        const double m = 1.0 / g.inverse_mass[i];
        momentum += m * (x1_[i] - x0_[i]);
        mass += m;
    }
    const Vec3d motion = mass > 0.0 ? (1.0 / mass) * momentum : Vec3d{};
    return physics::is_finite(motion) ? motion : Vec3d{};  // a non-finite vertex is the broad phase's to skip
}

template <typename T>
std::size_t CpuCollisions<T>::memory_bytes() const {
    const collision::CollisionGeometry& g = geometry_;
    return (g.kinematic_local.capacity() + x0_.capacity() + x1_.capacity()) * sizeof(Vec3d) +
           (kinematic_x1_t_.capacity() + kinematic_v_t_.capacity()) * sizeof(V3) +
           g.triangles.capacity() * sizeof(Triangle) + g.triangle_group.capacity() * sizeof(std::uint32_t) +
           g.edges.capacity() * sizeof(collision::Edge) +
           (g.inverse_mass.capacity() + g.thickness.capacity() + g.friction.capacity()) * sizeof(double) +
           contacts_.capacity() * sizeof(collision::ProximityContact) + terms_.memory_bytes() +
           x_detect_.capacity() * sizeof(Vec3d) + (radius_.capacity() + remainder_.capacity()) * sizeof(double) +
           (bounds_.bound.capacity() + bounds_.reach.capacity() + bounds_.vf_distance.capacity() +
            bounds_.ee_distance.capacity()) * sizeof(double) +
           bounds_.partner_start.capacity() * sizeof(std::uint32_t) +
           bounds_.partners.capacity() * sizeof(collision::PartnerLimit) +
           bounds_.pairs.vf.capacity() * sizeof(collision::VertexFacePair) +
           bounds_.pairs.ee.capacity() * sizeof(collision::EdgeEdgePair) +
           // The hash's scratch and the pair lists: the largest buffers where a frame folds a lot.
           broad_.scratch_bytes() + pairs_.vf.capacity() * sizeof(collision::VertexFacePair) +
           pairs_.ee.capacity() * sizeof(collision::EdgeEdgePair);
}

template class CpuCollisions<float>;
template class CpuCollisions<double>;

}  // namespace weft::cpu
