#pragma once
// The collision stages of a CPU substep (docs/collisions.md): before the solve, proximity contacts
// from the broad phase over the predicted motion; after it, CCD and impact zones that leave the
// substep free of intersections. Cloth vertices come first in the collision index space, then the
// vertices of the mesh colliders (kinematic: they follow their motion and are never moved).
// Built only when the scene needs it: self-collision on, or a mesh collider present.

#include <cstdint>
#include <memory>
#include <vector>

#include "collision/broad_phase.h"
#include "collision/closed_colliders.h"
#include "collision/displacement_bounds.h"
#include "weft/backend/collision_geometry.h"
#include "collision/impact_zones.h"
#include "collision/normal_cone_front.h"
#include "weft/backend/patch_hierarchy.h"
#include "collision/proximity_contacts.h"
#include "cpu/contact_terms.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/model.h"
#include "weft/stats.h"

namespace weft::cpu {

template <typename T>
class CpuCollisions {
public:
    using V3 = physics::Vec3<T>;

    /// Builds the collision geometry for `flat` and the mesh colliders of `model`.
    void build(const FlatModel& flat, const Model& model);
    /// True when the scene has anything for these stages to do.
    [[nodiscard]] bool active() const { return active_; }
    /// True when `model`'s collision settings no longer match what was built (self-collision
    /// switched on or off live): call `build` again.
    [[nodiscard]] bool stale(const Model& model) const { return model.settings.collision.self_collision != geometry_.self; }

    /// Finds the substep's proximity contacts from the start state (x0, v0) of the cloth and the
    /// colliders' poses at t and t + h, and hands them to `terms()`.
    /// `dv_previous` (the last substep's velocity change per cloth vertex) sharpens the offset mode's
    /// prediction of each vertex's move, which sizes its query radius.
    /// First, cloth vertices inside a closed piece of a mesh collider are moved just outside it in x0
    /// and v0 (collision/closed_colliders.h); returns how many (the caller's copies of the state are
    /// then stale), also counted in stats.collision.ejected_vertices.
    std::size_t begin_substep(const Model& model, double t, double h, std::vector<V3>& x0, std::vector<V3>& v0,
                              const std::vector<V3>& dv_previous, StepStats& stats);
    /// The contact springs of the current substep (for the solve).
    [[nodiscard]] ContactTerms<T>& terms() { return terms_; }
    [[nodiscard]] const ContactTerms<T>& terms() const { return terms_; }
    [[nodiscard]] std::span<const V3> kinematic_x1() const { return kinematic_x1_t_; }
    [[nodiscard]] std::span<const V3> kinematic_v() const { return kinematic_v_t_; }

    /// Offset mode (CollisionSettings::mode): true when this substep's contacts are offset contacts
    /// and its moves must go through `truncate`.
    [[nodiscard]] bool offset() const { return offset_; }
    /// Offset mode, after each Newton update: truncates every free cloth vertex's move to its bound
    /// (from the last detection), setting v_k = (x_truncated − x0)/h for those it shortens, and checks
    /// the prescribed ones (pins, mesh colliders), whose moves cannot be shortened: one that breaks
    /// its bound sends the substep to the CCD fallback in `end_substep`. Returns the number of free
    /// vertices truncated.
    std::size_t truncate(const Model& model, double h, const std::vector<V3>& x0, std::vector<V3>& vk,
                         StepStats& stats);
    /// Offset mode: true when the last truncation shortened more than CollisionSettings::redetect_share
    /// of the free vertices and a rerun is still allowed this substep.
    [[nodiscard]] bool wants_redetection(const Model& model) const;
    /// Offset mode: detection again at the current (truncated) cloth positions x0 + h·v_k and the
    /// colliders' poses at t + h; the contacts and bounds are replaced and later moves are measured
    /// from here.
    void redetect(const Model& model, double h, const std::vector<V3>& x0, const std::vector<V3>& vk, StepStats& stats);

    /// After the solve: makes x0 → x1 free of collisions (CCD and impact zones) when continuous
    /// collisions are on, and sets v = (x1 − x0)/h for every vertex it moved. In offset mode the
    /// moves were truncated and it does nothing, unless a prescribed vertex broke its bound or
    /// `moved_after_solve` (a fast analytic collider carried cloth along after the truncation).
    void end_substep(const Model& model, double h, const std::vector<V3>& x0, std::vector<V3>& x1, std::vector<V3>& v,
                     bool moved_after_solve, StepStats& stats);

    [[nodiscard]] std::size_t memory_bytes() const;

private:
    bool active_ = false;
    collision::CollisionGeometry geometry_;
    std::vector<collision::ClosedPiece> closed_;  // the mesh colliders' closed pieces (an inside to eject from)
    std::vector<Vec3d> kinematic_velocity_;       // their velocities over the substep, for the ejections (reused)
    // Per substep.
    std::vector<Vec3d> x0_, x1_;  // collision vertices (kinematic ones at the tail) at t and t + h
    std::vector<V3> kinematic_x1_t_, kinematic_v_t_;
    // The mesh colliders' vertices where the last substep ended them, and when: the next substep
    // must start them there, or they moved with no motion for the CCD to sweep (collider_jumps).
    std::vector<Vec3d> last_kinematic_end_;
    double last_end_time_ = -1.0;
    collision::BroadPhase broad_;
    collision::BroadPhaseResult pairs_;
    std::vector<collision::ProximityContact> contacts_;
    // The narrow phase sizes contacts_ to its candidate pairs before keeping the contacts, so a
    // flood of candidates leaves it holding that flood (the projectile soak: 44 MB after a fold).
    // It is cut back to the window's largest candidate count (collision/buffer_trim.h).
    std::size_t contact_calls_ = 0, contact_candidates_peak_ = 0;
    void find_contacts(const collision::ProximityInput& input);
    collision::ImpactZoneSolver zones_;
    // Normal-cone culling of self pairs (PSCC): the hierarchy over the fixed topology, built once,
    // and the test front kept across substeps. Null without self-collision or with culling off.
    std::unique_ptr<collision::PatchHierarchy> hierarchy_;
    std::unique_ptr<collision::NormalConeFront> front_;
    void cull(const Model& model, std::span<const Vec3d> x0, std::span<const Vec3d> x1,
              collision::BroadPhaseInput& in, StepStats& stats);
    /// The cloth's common move over the substep (x0_ → x1_), m: the broad phase's moving frame.
    [[nodiscard]] Vec3d common_motion() const;
    ContactTerms<T> terms_;

    // Offset mode: the last detection (collision vertices, kinematic ones at the tail), the frame shift
    // of the current piece (moves are bounded relative to a common translation: distances do not
    // change under it), the per-vertex query radii and what the bounds allow.
    bool offset_ = false;
    bool fallback_ = false;        // a prescribed vertex broke its bound: CCD and impact zones after the solve
    int redetections_ = 0;         // this substep
    std::size_t last_truncated_ = 0;
    std::size_t free_vertices_ = 0;
    std::vector<Vec3d> x_detect_;
    Vec3d shift_{};
    std::vector<double> radius_;
    std::vector<double> remainder_;  // per cloth vertex, the part of its last move the truncation cut, m
    collision::DisplacementBounds bounds_;
    /// Bounds and offset contacts at x_detect_ (radii in radius_), culled by the normal cones over
    /// x_detect_ → x_end when culling is on.
    void detect_offset(const Model& model, double h, std::span<const Vec3d> x_end, StepStats& stats);
    void measure_bounds(const Model& model, bool culled);
    /// The narrow phase's input for `pairs` between x0 and x1 (both modes).
    [[nodiscard]] collision::ProximityInput proximity_input(const CollisionSettings& settings, std::span<const Vec3d> x0,
                                                            std::span<const Vec3d> x1,
                                                            const collision::BroadPhaseResult& pairs, double h) const;
    void find_offset_contacts(const Model& model, double h, StepStats& stats);
    std::size_t truncate_to_bounds(const Model& model, double h, const std::vector<V3>& x0, std::vector<V3>& vk,
                                   StepStats& stats);
    bool culled_ = false;  // the current bounds skipped same-patch pairs
    std::vector<std::uint32_t> detect_patch_, update_patch_;  // vertex, edge, triangle ids, concatenated
    std::vector<V3> proposal_;
    std::vector<Vec3d> x_update_;
};

extern template class CpuCollisions<float>;
extern template class CpuCollisions<double>;

}  // namespace weft::cpu
