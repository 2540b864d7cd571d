#pragma once
/// @file
/// The inelastic projection of an impact zone on the GPU by projected Gauss–Seidel over colours of
/// its constraints (docs/collisions.md, "On the GPU"). The CPU reference (impact_zones.cpp,
/// `project_zone`) maximises the projection's dual one multiplier at a time, in a fixed order:
///   λ_k ← max(0, λ_k − g_k(x) / A_kk),  x ← x + M⁻¹ J_kᵀ Δλ_k,  A_kk = Σ_j w_kj² / m_j.
/// Two constraints that share no movable vertex commute: updating them together is the same as one
/// after the other. So one thread block per zone colours the zone's constraints (no two of a colour
/// share a movable vertex) and sweeps the colours in order, each colour's constraints in parallel:
/// Gauss–Seidel's convergence (Hildreth 1957; Luo & Tseng 1992) with a block's parallelism. The
/// projected gradient it replaces for such zones (FISTA with a diagonal majoriser: the step of
/// a constraint is divided by the number of constraints at each of its vertices) needed thousands of
/// iterations on stacked contact, where Gauss–Seidel needs hundreds of sweeps: the game prototype's
/// skirt on the GPU spent 32 rounds a substep re-detecting unconverged zones (docs/results.md).
///
/// Deterministic: the colouring takes, round by round, each constraint that is the smallest id
/// among the uncoloured constraints at every one of its movable vertices (an atomicMin a vertex:
/// order-independent), so colours depend only on the constraints; within a colour the updates
/// touch disjoint vertices; the convergence test is a maximum. The zone's displacements x − x̂ live
/// in shared memory (float: small numbers next to positions), the constant part of each constraint
/// (n·Σ w x̂ − δ) in double.

#include <cuda_runtime_api.h>

#include <cstdint>

namespace weft::cuda::collision {

/// Zones of at most this many vertices are projected by colours (their displacements fit a block's
/// shared memory: 12 bytes a vertex); larger zones keep the projected gradient.
inline constexpr std::uint32_t kColoredZoneVertices = 3072;

/// Device arrays the coloured projection reads and writes; every pointer on the current device.
struct ColoredZoneProjection {
    // The zones (impact_zones_gpu.cu's sorted lists).
    const std::uint32_t* zone_label = nullptr;     ///< root vertex per zone
    const std::uint32_t* coffset = nullptr;        ///< zones + 1: each zone's run of `cvalue`
    const std::uint32_t* cvalue = nullptr;         ///< constraint ids, zone by zone
    const std::uint32_t* voffset = nullptr;        ///< zones + 1: each zone's run of `vvalue`
    const std::uint32_t* vvalue = nullptr;         ///< indices into unique_vertex, zone by zone
    const std::uint32_t* unique_vertex = nullptr;  ///< vertex ids
    // The constraints n·Σ w_j x_{v_j} ≥ δ.
    const std::uint32_t* vertex = nullptr;  ///< 4 a constraint
    const float* weight = nullptr;          ///< 4 a constraint
    const float* normal = nullptr;          ///< 3 a constraint
    double* lambda = nullptr;               ///< multipliers, warm start in, result out
    // Per vertex (SoA, component stride n).
    const float* x_hat = nullptr;         ///< the positions to project, m
    const float* inverse_mass = nullptr;  ///< 1/kg; 0: not moved
    float* x1 = nullptr;                  ///< out: the zone's vertices projected, m
    std::uint32_t n = 0;
    // What to project and what it reports.
    std::uint8_t* action = nullptr;   ///< per root: zones asking `project_code` are projected, then `done_code`
    std::uint8_t* outcome = nullptr;  ///< per vertex: `projected_code` for every vertex of a projected zone
    std::uint8_t project_code = 0, done_code = 0, projected_code = 0;
    std::uint32_t* sweeps = nullptr;       ///< += sweeps used, summed over zones
    std::uint32_t* unconverged = nullptr;  ///< += zones that reached the sweep cap
    unsigned long long* work = nullptr;    ///< += sweeps × constraints, summed over zones
    // Scratch (sizes: vertices n; constraints C; zones Z).
    std::uint32_t* zone_slot = nullptr;    ///< n: a vertex's index among its zone's vertices
    std::uint32_t* claim = nullptr;        ///< n: the colouring's claims
    std::uint32_t* color = nullptr;        ///< C: each constraint's colour
    std::uint32_t* color_order = nullptr;  ///< C: the zone's constraints colour by colour
    std::uint32_t* color_start = nullptr;  ///< C + Z + 1: each colour's start in color_order
    // Each constraint's terms packed in colour order (C each), so that a sweep's loads of a
    // constraint are independent of each other (no chain of id → vertex → slot lookups per colour).
    uint4* packed_slot = nullptr;      ///< its vertices' slots among the zone's (kNoSlot: not moved)
    float4* packed_weight = nullptr;   ///< w_j (0 for a vertex not moved)
    float4* packed_move = nullptr;     ///< w_j / m_j, 1/kg
    float4* packed_normal = nullptr;   ///< n (w unused)
    double* packed_offset = nullptr;   ///< n·Σ w x̂ − δ, m
    double* packed_inverse_diagonal = nullptr;  ///< 1 / A_kk, kg (0: no say)
    double* packed_lambda = nullptr;   ///< the multiplier during the sweeps
};

/// ColoredZoneProjection::packed_slot of a vertex that is not moved (inverse mass 0).
inline constexpr std::uint32_t kNoSlot = 0xFFFFFFFFU;

/// Projects every zone of `zones` whose action is `p.project_code` and that has at most
/// `max_vertices` (≤ kColoredZoneVertices) vertices and more than `min_constraints` constraints: to `tol` (m; the CPU's rule: every constraint
/// violated by at most tol, every one with a multiplier tight to within tol over a whole sweep) or
/// `max_sweeps` sweeps. `delta` is the gap δ, m. Zones it does not take are left as they are.
void launch_colored_zone_projection(const ColoredZoneProjection& p, std::uint32_t zones, std::uint32_t max_vertices,
                                    std::uint32_t min_constraints, double delta, double tol, int max_sweeps,
                                    cudaStream_t stream);

}  // namespace weft::cuda::collision
