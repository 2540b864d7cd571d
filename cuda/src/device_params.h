#pragma once
// Plain structs shared by the host side of the CUDA backend and its kernels: the per-substep
// parameters uploaded in one copy, the device-resident CG control block and the stats the device
// accumulates. float throughout except the CG scalars, which are reduced in double like the CPU's.

#include <cstdint>

#include "weft/backend/cg_energy_stop.h"
#include "weft/backend/material_terms.h"
#include "weft/material.h"
#include "weft/physics/collider_contact.h"
#include "weft/physics/membrane.h"
#include "weft/physics/vec.h"

namespace weft::cuda {

using V3 = physics::Vec3<float>;
using M3 = physics::Mat3<float>;

/// One cloth's material in solver units (float).
using ClothParams = MaterialTerms<float>;

/// Everything that may change from one substep to the next, uploaded with one copy. The arrays
/// (cloth parameters, shapes at the end of the substep, their friction, pin targets, shapes at its
/// start) follow the header in the same buffer at the offsets the header gives (bytes from the start
/// of the buffer).
struct StepParams {
    float h = 0, h2 = 0, time = 0;
    int hessian = 0;  ///< physics::HessianKind
    V3 gravity{}, wind{};
    int wind_active = 0;
    float air_density = 0, turbulence = 0, turbulence_frequency = 0, turbulence_scale = 1;
    float contact_stiffness = 0;
    int shape_count = 0;
    /// Analytic colliders that a vertex can pass through (spheres, capsules, boxes; not planes). When
    /// there are any, the commit records the largest displacement of a free vertex, from which the
    /// host decides whether the swept collider test has to run (DeviceStats::largest_move_bits).
    int bounded_shape_count = 0;
    /// 1: a slow vertex that ends inside a bounded collider it started outside goes back onto its
    /// surface (swept_collider.h). 0 under offset contact, whose moves must stay within their
    /// displacement bounds: the next substep's penalty pushes it out (CpuSolver::sweep_fast_colliders).
    int correct_overshoots = 1;
    /// 1: the analytic colliders also push each triangle's centroid (SolverSettings::face_contacts,
    /// weft/physics/implicit_terms.h: face_collider_terms); 0 without it or without analytic colliders.
    int face_contacts = 0;
    int pin_count = 0;
    int cg_max_iterations = 0;
    int cg_warm_start = 0;
    double cg_eps2 = 0;
    double cg_energy_floor = 0;  ///< J: the CG's energy test (weft/backend/cg_energy_stop.h); 0 = off
    std::uint32_t cloth_offset = 0, shape_offset = 0, friction_offset = 0, pin_target_offset = 0;
    std::uint32_t shape_start_offset = 0;  ///< the shapes at the start of the substep (swept test)
    /// Model::grab: the global vertex (0xFFFFFFFF when there is none), its target (m) and spring.
    std::uint32_t grab_vertex = 0xFFFFFFFFu;
    /// Schwarz preconditioner: refactor in every Newton iteration (1), or only in the first Newton
    /// iteration of this substep (2), or not at all in this substep (0): SolverSettings::
    /// preconditioner_refresh, decided by the host per substep.
    int schwarz_refactor = 1;
    float grab_stiffness = 0, grab_damping = 0;
    V3 grab_target{};
};

/// The PCG state that lives on the device, so the loop needs no host round trip.
struct PcgControl {
    double delta0_b;   ///< filter(b)ᵀ P⁻¹ filter(b)
    double delta;      ///< rᵀ P⁻¹ r of the current iterate
    double delta0;     ///< the scale convergence is measured against
    double cq;         ///< cᵀ A c of the current direction
    float alpha, beta;
    CgEnergyWindow energy;  ///< the falls of Φ the energy test sums
    int iterations;
    int running;       ///< 1 while the loop must go on
    int converged;
    std::uint32_t counter;  ///< blocks finished in the current grid reduction
};

/// What one substep reports, accumulated on the device and read back once at its end.
struct DeviceStats {
    int cg_iterations;
    int cg_iterations_max;
    double cg_residual;
    int cg_not_converged;
    int newton_iterations;
    int contacts;
    int non_finite;
    int proximity_contacts;  ///< pairs of the contact list in this substep's solve
    /// Bits of the largest |x1 − x0| (m, a non-negative float, so its bits order like it) over the
    /// free vertices, recorded by the commit when StepParams::bounded_shape_count > 0, else 0.
    unsigned int largest_move_bits;
    int swept_hits;      ///< vertices the swept collider test carried along (one per vertex and collider)
    int overshoot_hits;  ///< slow vertices it put back onto a collider's surface (read with swept_hits)
    int pivot_failures;  ///< Schwarz domain factorisations that met a non-positive pivot
    int runaway;         ///< free vertices the commit found faster than kRunawaySpeed (weft/backend/runaway.h)
};

}  // namespace weft::cuda
