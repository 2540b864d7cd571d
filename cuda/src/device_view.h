#pragma once
// The device solver's arrays as one struct of raw pointers, passed by value to every kernel.
// Vertex vectors are structure-of-arrays: component c of vertex i is at [c·n + i], so a warp's loads
// of one component are contiguous. Matrix blocks are 9 floats (row-major) per sliced-ELL position.

#include <cstdint>

#include "device_contacts.h"
#include "device_params.h"
#include "device_schwarz.h"
#include "weft/physics/shell_bending_slots.h"

namespace weft::cuda {

/// The mid-edge bending model's normals (solver.bending = "midedge"; weft/physics/midedge_bending.h,
/// midedge_kernels.cu): per hinge the turn ξ of its edge's normal (rad) and the solve's vectors, per
/// triangle the reading of each edge (MidEdgeEdge). Null (and unused) with the other models.
struct MidEdgeView {
    double* xi = nullptr;     ///< rad, one per hinge (0 where the edge has no ξ)
    double* angle = nullptr;  ///< θ − θ̄ at the relaxed state, rad, one per hinge
    double *r = nullptr, *p = nullptr, *q = nullptr, *diag = nullptr;  ///< the CG's vectors, one per hinge
    std::uint8_t* clamp = nullptr;  ///< per hinge: 1 where a triangle of it has its three corners pinned
    std::uint8_t* edge = nullptr;   ///< per triangle, 3: how it reads edge k (MidEdgeEdge)
    double* partials = nullptr;     ///< 4 per block of the solve's grid
    int grid = 0;                   ///< blocks of the cooperative solve (all resident at once)
};

struct DeviceView {
    std::uint32_t n = 0, triangles = 0, hinges = 0, pins = 0, slices = 0;
    /// Rows this device assembles and solves: n, or in part mode (the multi-GPU solver) the owned
    /// vertices [0, rows); the others are ghosts whose values come from their owners.
    std::uint32_t rows = 0;
    // Vertex state and solver vectors, 3n floats each.
    float *x = nullptr, *v = nullptr, *x0 = nullptr, *v0 = nullptr, *vk = nullptr, *wk = nullptr;
    float *b = nullptr, *dv = nullptr, *pin_velocity = nullptr;
    float* dv_previous = nullptr;  ///< v − v0 of the last substep (CG warm start)
    float *r = nullptr, *c = nullptr, *q = nullptr, *s = nullptr;
    float* precond = nullptr;  ///< block-Jacobi inverse, 9n floats, entry e of vertex i at [e·n + i]
    const float* mass = nullptr;
    const std::uint8_t* fixed = nullptr;
    const std::uint32_t* vertex_cloth = nullptr;
    /// 1 where the last assembly found vertex i in an active contact with an analytic collider (its
    /// own, or a face contact of a triangle it is a corner of), else 0; n bytes, rows [0, rows)
    /// written (Backend::collider_contact_vertices).
    std::uint8_t* collider_contact = nullptr;
    // Matrix (sliced ELL).
    float* blocks = nullptr;
    const std::uint32_t* column = nullptr;
    const std::uint32_t* slice_start = nullptr;
    const std::uint32_t* diagonal = nullptr;
    // Triangles and hinges, in the flat model's order.
    const std::uint32_t* triangle_vertices = nullptr;  ///< 3 per triangle
    const float* triangle_rest = nullptr;              ///< Dm⁻¹ (4, row-major) and area, 5 per triangle
    const std::uint32_t* triangle_cloth = nullptr;
    const std::uint32_t* triangle_positions = nullptr; ///< 9 ELL positions per triangle
    const std::uint32_t* hinge_vertices = nullptr;     ///< 4 per hinge
    const float* hinge_rest = nullptr;                 ///< weight and rest angle, 2 per hinge
    const std::uint32_t* hinge_cloth = nullptr;
    const std::uint32_t* hinge_positions = nullptr;    ///< 16 ELL positions per hinge
    /// The bending model per triangle (solver.bending = "shell"; null with hinges, the default): per
    /// triangle its hinges (3, −1 where none) and rest data (area and the 3×3 coupling M: 10 floats),
    /// per hinge its faces (2, −1 where none; ascending in the flat model's order, as the CPU sums
    /// them), and the per-triangle terms of the Newton iteration (pass 1, shell_faces_kernel), all in
    /// the device's colour order.
    const std::int32_t* triangle_hinges = nullptr;
    const std::int32_t* hinge_faces = nullptr;
    const float* shell_rest = nullptr;
    physics::ShellFaceTerms<float>* shell_faces = nullptr;
    /// With solver.bending = "midedge" the same arrays (shell_rest then holds the mid-edge model's
    /// condensed rest data) and the normals' turns; midedge.xi is null with the other models.
    MidEdgeView midedge;
    // Vertex → incident (element, corner) pairs, entries 4·element + corner (device_layout.h).
    const std::uint32_t* vertex_triangle_start = nullptr;
    const std::uint32_t* vertex_triangle = nullptr;
    const std::uint32_t* vertex_hinge_start = nullptr;
    const std::uint32_t* vertex_hinge = nullptr;
    const std::uint32_t* pin_vertex = nullptr;
    // Per-substep parameters, CG control, stats and reduction scratch.
    const unsigned char* staging = nullptr;
    PcgControl* control = nullptr;
    DeviceStats* stats = nullptr;
    double* partials = nullptr;
    long long* loop_clock = nullptr;  ///< WEFT_CUDA_PCG_CLOCK=1: the one-launch loop's clock (loop_clock.h)
    // Proximity contacts (device_contacts.h); capacity 0 leaves the solve as it is without them.
    ContactView contacts;
    // The Schwarz preconditioner's levels (device_schwarz.h); levels 0 until it is first used.
    SchwarzView mas;
};

}  // namespace weft::cuda
