#pragma once
// The CPU implementation of one implicit substep (docs/architecture.md, "the step in detail").

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "cpu/bsr_matrix.h"
#include "cpu/cpu_collisions.h"
#include "cpu/pcg.h"
#include "cpu/schwarz_preconditioner.h"
#include "cpu/shell_bending_terms.h"
#include "midedge_normals.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/material_terms.h"
#include "weft/backend/model.h"
#include "weft/backend/runaway.h"
#include "weft/physics/bending.h"
#include "weft/physics/collider_contact.h"
#include "weft/physics/implicit_terms.h"
#include "weft/physics/membrane.h"
#include "weft/stats.h"

namespace weft::cpu {

/// Implicit Euler with Newton iterations on the velocity (Baraff & Witkin 1998), in scalar T.
template <typename T>
class CpuSolver {
public:
    using V3 = physics::Vec3<T>;
    using M3 = physics::Mat3<T>;

    /// Allocates all state for `flat` (kept by reference: it must outlive the solver) and the
    /// collision stages `model` needs.
    void build(const FlatModel& flat, const Model& model);
    void substep(const Model& model, double t, double h, StepStats& stats);
    void read_state(std::size_t first, std::size_t count, Vec3d* x, Vec3d* v) const;
    void write_state(std::size_t first, std::size_t count, const Vec3d* x, const Vec3d* v);
    /// The CG warm start and the substep count (the preconditioner's refresh phase) as bytes, for a
    /// checkpoint; restore_solver_state takes them back (after write_state, which clears the warm
    /// start) and throws weft::Error when they come from another precision or vertex count.
    [[nodiscard]] std::vector<std::uint8_t> solver_state() const;
    void restore_solver_state(std::span<const std::uint8_t> bytes);
    [[nodiscard]] std::size_t memory_bytes() const;
    /// The share of `memory_bytes` held by the collision pipeline.
    [[nodiscard]] std::size_t collision_memory_bytes() const { return collisions_.memory_bytes(); }
    /// The flat model's cloth vertices in a proximity contact in the last substep (ContactTerms).
    void contact_vertices(std::vector<std::uint32_t>& out) const { collisions_.terms().contact_vertices(out); }
    /// The vertices [first, first + count), as `first`-relative ids, in an active analytic-collider
    /// contact at the last assembly: their own, or a face contact of a triangle they are a corner of.
    void collider_contact_vertices(std::size_t first, std::size_t count, std::vector<std::uint32_t>& out) const;
    /// Offset mode: the penalty energy of the current substep's offset contacts at the current state,
    /// J (0 in the other mode, or before a substep).
    [[nodiscard]] double offset_contact_energy() const;

    /// Test hook (tests/gpu/test_cuda_contacts.cpp holds the CUDA contact solve against this one):
    /// every later substep solves with `contacts` as if the collision stages had found them, kinematic
    /// vertex k at `kinematic_x1[k]` moving with `kinematic_v[k]`; no CCD or impact zones follow. A
    /// scene whose collision stages are active keeps its own contacts.
    void set_contacts_for_test(std::span<const collision::ProximityContact> contacts, std::span<const V3> kinematic_x1,
                               std::span<const V3> kinematic_v) {
        test_contacts_.set(contacts, n_);
        test_kinematic_x1_.assign(kinematic_x1.begin(), kinematic_x1.end());
        test_kinematic_v_.assign(kinematic_v.begin(), kinematic_v.end());
        has_test_contacts_ = true;
    }

private:
    using ClothParams = MaterialTerms<T>;
    struct TriangleRestT {
        T dm_inv[2][2];
        T area;
    };
    struct HingeRestT {
        T weight;
        T rest_angle;
    };

    void prepare_parameters(const Model& model, double t, double h);
    void evaluate_elements(const Model& model, double t, T h);
    /// The bending model per triangle into the hinges' element slots (SolverSettings::bending = Shell).
    void evaluate_shell_bending(T h);
    int evaluate_vertices(const Model& model, T h);
    void assemble();
    /// Carried vertices (fast colliders) in .first, overshoots put back on a surface in .second.
    /// `correct_overshoots` false (offset contact): slow overshoots are left to the next substep's
    /// penalty, because the correction would move a vertex past its displacement bound.
    std::pair<int, int> sweep_fast_colliders(T h, bool correct_overshoots);
    /// Implicit Euler's objective at velocities `v`: ½ Σ m|v − v₀|² + Ψ(x₀ + h·v), Ψ the elastic,
    /// gravity and collider potentials (and offset contact's), at time `t1`, J (line_search).
    double incremental_potential(const Model& model, double t1, T h, const std::vector<V3>& v);
    /// Halves dv_ (free vertices) while vk_ + dv_ raises incremental_potential; returns the halvings.
    int line_search(const Model& model, double t1, T h);

    const FlatModel* flat_ = nullptr;
    std::size_t n_ = 0;
    // State and its copy at the start of the substep (also the rollback point on NaN).
    std::vector<V3> x_, v_, x0_, v0_;
    // Newton iterate: velocity guess v_k and the velocity w_k that places the linearisation point
    // x0 + h·w_k (w_0 = 0 gives Baraff–Witkin's first step exactly; w_k = v_k afterwards).
    std::vector<V3> vk_, wk_;
    std::vector<T> mass_;
    double total_mass_ = 0.0;  ///< kg, of every cloth: the CG energy test's scale (cg_energy_floor)
    std::vector<TriangleRestT> triangle_rest_;
    std::vector<HingeRestT> hinge_rest_;
    // The bending model per triangle (SolverSettings::bending = Shell; cpu/shell_bending_terms.h):
    // its rest data, each hinge's (up to) two triangles, pass 1's output per triangle, and the
    // linearisation point and v_k − w_k per vertex that pass 1 reads.
    BendingModel bending_ = BendingModel::Hinge;
    bool face_contacts_ = false;   // SolverSettings::face_contacts
    int face_contacts_active_ = 0;  // of the last evaluate_elements
    std::vector<std::uint8_t> face_contact_;  // per triangle: 1 where its centroid contact was active (the last evaluate_elements)
    std::vector<physics::ShellBendingRest<T>> shell_rest_;
    std::vector<std::array<std::int32_t, 2>> hinge_faces_;
    std::vector<ShellFaceTerms<T>> shell_faces_;
    // The mid-edge model (SolverSettings::bending = MidEdge; midedge_normals.h): its normals relaxed
    // at the linearisation point, its triangles' condensed rest data in T, and its normals' solves
    // that hit their cap since the stats last took them.
    MidEdgeState midedge_;
    std::vector<physics::ShellBendingRest<T>> midedge_rest_;
    int midedge_not_converged_ = 0;
    std::vector<V3> x_lin_, d_lin_;
    // Per-element outputs gathered per vertex / per BSR slot in fixed order (deterministic).
    std::vector<V3> element_rhs_;
    std::vector<M3> element_blocks_;
    std::vector<V3> vertex_rhs_;
    std::vector<M3> vertex_blocks_;
    std::vector<V3> b_, dv_, pin_velocity_;
    std::vector<Vec3d> pin_targets_;  // this substep's, from pin_targets (weft/backend/flat_model.h)
    std::vector<V3> dv_previous_;  // v − v0 of the last substep: the warm start of the next first solve
    std::vector<std::uint8_t> fixed_;
    std::vector<int> contacts_;
    std::vector<double> partials_;
    // The line search's trial velocities and the per-cloth positions its energy reads (double).
    std::vector<V3> trial_v_, merit_positions_;
    std::vector<std::vector<Vec3d>> merit_x_, merit_v_;
    BsrMatrix<T> A_;
    Pcg<T> pcg_;
    // Multilevel additive Schwarz (SolverSettings::preconditioner): levels built from the initial
    // positions on first use, factored once per Newton iteration.
    SchwarzHierarchy schwarz_levels_;
    SchwarzPreconditioner<T> schwarz_;
    bool schwarz_factored_ = false;  // its factors are current enough to reuse (preconditioner_refresh)
    long long substep_count_ = 0;    // substeps since the build
    CpuCollisions<T> collisions_;
    std::vector<ClothParams> cloth_params_;
    std::vector<physics::Shape<T>> shapes_;        // analytic colliders at the end of the substep
    std::vector<physics::Shape<T>> shapes_start_;  // and at its start (for the swept test)
    std::vector<T> shape_friction_;
    physics::HessianKind hessian_ = physics::HessianKind::Fast;
    V3 gravity_{};
    physics::WindField<T> wind_{};
    T contact_stiffness_ = T(0);
    // Model::grab for this substep: the global vertex (n_ when there is none) and its spring.
    std::size_t grab_vertex_ = 0;
    physics::GrabSpring<T> grab_{};
    ContactTerms<T> test_contacts_;  // set_contacts_for_test
    std::vector<V3> test_kinematic_x1_, test_kinematic_v_;
    bool has_test_contacts_ = false;
};

extern template class CpuSolver<float>;
extern template class CpuSolver<double>;

}  // namespace weft::cpu
