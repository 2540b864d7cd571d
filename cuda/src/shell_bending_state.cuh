#pragma once
// One triangle's data for the bending model per triangle on the device (shell_bending_kernels.cu,
// energy_kernels.cu): its hinges, their vertices and rest angles, its rest area and coupling M.

#include "device_math.cuh"
#include "device_view.h"

namespace weft::cuda {

struct ShellFaceInput {
    std::int32_t hinge[3];           ///< device hinge ids, −1 where the edge has none
    std::uint32_t vertex[3][4];      ///< hinge k's vertices (0 where it has none)
    float rest_angle[3];             ///< rad (0 where none)
    physics::ShellBendingRest<float> rest;
};

__device__ inline void load_shell_face(const DeviceView& d, std::uint32_t t, ShellFaceInput& in) {
    for (int k = 0; k < 3; ++k) {
        in.hinge[k] = d.triangle_hinges[3 * t + k];
        in.rest_angle[k] = in.hinge[k] >= 0 ? d.hinge_rest[2 * in.hinge[k] + 1] : 0.0f;
        for (int a = 0; a < 4; ++a) in.vertex[k][a] = in.hinge[k] >= 0 ? d.hinge_vertices[4 * in.hinge[k] + a] : 0u;
    }
    const float* r = d.shell_rest + 10 * t;
    in.rest.area = r[0];
    for (int e = 0; e < 9; ++e) in.rest.m[e / 3][e % 3] = r[1 + e];
}

/// Triangle t's bending at positions `x` (the audit's state: SoA with stride d.n): its energy, J, and
/// the terms of each hinge (ShellBendingTerms: ∂E/∂θ_k and ∇θ_k) for the gradient.
__device__ inline physics::ShellBendingTerms<float> shell_face_at(const DeviceView& d, std::uint32_t t, float stiffness,
                                                                  const float* x, ShellFaceInput& in) {
    load_shell_face(d, t, in);
    bool present[3];
    V3 p[3][4];
    for (int k = 0; k < 3; ++k) {
        present[k] = in.hinge[k] >= 0;
        for (int a = 0; a < 4; ++a) p[k][a] = present[k] ? load3(x, in.vertex[k][a], d.n) : V3{};
    }
    return physics::shell_bending_evaluate<float>(stiffness, in.rest, present, p, in.rest_angle);
}

}  // namespace weft::cuda
