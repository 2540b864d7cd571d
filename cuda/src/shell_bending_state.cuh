#pragma once
// One triangle's data for the bending models per triangle on the device (shell_bending_kernels.cu,
// energy_kernels.cu, midedge_kernels.cu): its hinges, their vertices and rest angles, its rest area and
// coupling M, and with the mid-edge model how it reads each edge.

#include "device_math.cuh"
#include "device_view.h"
#include "weft/physics/midedge_bending.h"

namespace weft::cuda {

/// How a triangle of the mid-edge model reads its edge k (MidEdgeView::edge; midedge_faces on the
/// host): no hinge; the clamp (weft/physics/midedge_bending.h), read with scale 0 by the triangle whose
/// corners are all pinned and 2 by the other, no ξ; or a free edge, seen from the hinge's first
/// triangle (side +1) or its second (side −1).
enum MidEdgeEdge : std::uint8_t { kMidEdgeNone = 0, kMidEdgeClampSelf, kMidEdgeClampOther, kMidEdgeFirst, kMidEdgeSecond };

/// Triangle t of the mid-edge model for the normals' solve (its hinges' angles only `with_angles`).
__device__ inline physics::MidEdgeFace<double> midedge_face(const DeviceView& d, std::uint32_t t, bool with_angles) {
    physics::MidEdgeFace<double> f;
    for (int k = 0; k < 3; ++k) {
        const std::int32_t h = d.triangle_hinges[3 * t + k];
        f.hinge[k] = h;
        const std::uint8_t edge = d.midedge.edge[3 * t + k];
        f.side[k] = edge == kMidEdgeFirst ? 1.0 : edge == kMidEdgeSecond ? -1.0 : 0.0;
        f.scale[k] = edge == kMidEdgeClampSelf ? 0.0 : edge == kMidEdgeClampOther ? 2.0 : 1.0;
        if (with_angles && h >= 0) f.angle[k] = d.midedge.angle[h];
    }
    return f;
}

/// Triangle t's reading of its hinges at the solved ξ (MidEdgeState::reading on the host), in float.
__device__ inline physics::ShellReading<float> midedge_reading_of(const DeviceView& d, std::uint32_t t) {
    const physics::MidEdgeFace<double> f = midedge_face(d, t, false);
    double xi[3]{};
    for (int k = 0; k < 3; ++k)
        if (f.side[k] != 0.0) xi[k] = d.midedge.xi[f.hinge[k]];
    const physics::ShellReading<double> r = physics::midedge_reading(f, xi);
    physics::ShellReading<float> out;
    for (int k = 0; k < 3; ++k) {
        out.scale[k] = static_cast<float>(r.scale[k]);
        out.offset[k] = static_cast<float>(r.offset[k]);
    }
    return out;
}

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
    if (d.midedge.xi != nullptr) {  // the mid-edge model, its normals relaxed at `x` (launch_midedge_relax)
        const physics::ShellReading<float> reading = midedge_reading_of(d, t);
        return physics::shell_bending_evaluate<float>(stiffness, in.rest, present, p, in.rest_angle, &reading);
    }
    return physics::shell_bending_evaluate<float>(stiffness, in.rest, present, p, in.rest_angle);
}

}  // namespace weft::cuda
