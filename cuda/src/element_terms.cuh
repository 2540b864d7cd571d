#pragma once
// The CUDA backend's side of the implicit terms (weft/physics/implicit_terms.h, shared with the CPU
// solver): each function gathers one vertex, triangle or hinge from the device layout (structure of
// arrays, parameters staged once per substep) and hands it to the shared terms. Both assembly
// strategies (assembly_kernels.cu) call these.

#include "device_math.cuh"
#include "weft/physics/implicit_terms.h"

namespace weft::cuda {

__device__ inline physics::ImplicitStep<float> implicit_step(const StepParams& sp) { return {sp.h, sp.h2}; }

/// Vertex i: inertia, gravity, mass-proportional damping, collider contacts and the grab spring.
/// Returns the number of active contacts.
__device__ inline int vertex_terms(const DeviceView& d, const StepParams& sp, std::uint32_t i, V3& rhs, M3& block) {
    const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.vertex_cloth[i]];
    const physics::VertexIterate<float> v{d.mass[i], load3(d.x0, i, d.n), load3(d.v0, i, d.n), load3(d.vk, i, d.n),
                                          load3(d.wk, i, d.n), d.fixed[i] != 0};
    const physics::ColliderSet<float> colliders{staged<physics::Shape<float>>(d, sp.shape_offset),
                                                staged<float>(d, sp.friction_offset), sp.shape_count,
                                                sp.contact_stiffness};
    const physics::GrabSpring<float> grab{sp.grab_target, sp.grab_stiffness, sp.grab_damping};
    return physics::vertex_terms(implicit_step(sp), v, p, sp.gravity, colliders, i == sp.grab_vertex, grab,
                                 static_cast<physics::HessianKind>(sp.hessian), rhs, block);
}

/// Triangle t: membrane, Rayleigh stiffness damping, wind and, with sp.face_contacts, the analytic
/// colliders at its centroid (after the membrane, as on the CPU). Returns the active centroid contacts.
using TriangleTerms = physics::ElementTerms<float, 3>;

__device__ inline int triangle_terms(const DeviceView& d, const StepParams& sp, std::uint32_t t, TriangleTerms& out) {
    const float h = sp.h;
    V3 x[3], vk[3], dvw[3];
    for (int a = 0; a < 3; ++a) {
        const std::uint32_t v = d.triangle_vertices[3 * t + a];
        const V3 w = load3(d.wk, v, d.n);
        x[a] = load3(d.x0, v, d.n) + h * w;
        vk[a] = load3(d.vk, v, d.n);
        dvw[a] = vk[a] - w;
    }
    const float* rest = d.triangle_rest + 5 * t;
    const float dm_inv[2][2] = {{rest[0], rest[1]}, {rest[2], rest[3]}};
    const physics::WindField<float> wind{sp.wind_active != 0, sp.wind,       sp.air_density, sp.turbulence,
                                         sp.turbulence_frequency, sp.turbulence_scale, sp.time};
    const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.triangle_cloth[t]];
    const auto kind = static_cast<physics::HessianKind>(sp.hessian);
    physics::triangle_terms(implicit_step(sp), dm_inv, rest[4], p, wind, x, vk, dvw, kind, out);
    if (sp.face_contacts == 0) return 0;
    const float mass = (d.mass[d.triangle_vertices[3 * t]] + d.mass[d.triangle_vertices[3 * t + 1]] +
                        d.mass[d.triangle_vertices[3 * t + 2]]) /
                       3.0f;
    const physics::ColliderSet<float> colliders{staged<physics::Shape<float>>(d, sp.shape_offset),
                                                staged<float>(d, sp.friction_offset), sp.shape_count,
                                                sp.contact_stiffness};
    return physics::face_collider_terms(implicit_step(sp), colliders, p, mass, x, vk, dvw, kind, out);
}

/// Hinge k: bending (with stiffness damping). `false` when the cloth has no bending stiffness.
using HingeTerms = physics::ElementTerms<float, 4>;

/// Hinge k's slots under the bending model per triangle (d.shell_faces set): the terms of its faces
/// that fall to it (weft/physics/shell_bending_slots.h, pass 2), from the faces' pass-1 terms of this
/// Newton iteration (shell_faces_kernel), in the CPU's face order.
__device__ inline void shell_hinge_terms(const DeviceView& d, std::uint32_t k, HingeTerms& out) {
    for (int a = 0; a < 4; ++a) {
        out.rhs[a] = V3{};
        for (int b = 0; b < 4; ++b) out.block[a][b] = M3{};
    }
    const std::uint32_t mine[4] = {d.hinge_vertices[4 * k], d.hinge_vertices[4 * k + 1], d.hinge_vertices[4 * k + 2],
                                   d.hinge_vertices[4 * k + 3]};
    for (int side = 0; side < 2; ++side) {
        const std::int32_t f = d.hinge_faces[2 * k + side];
        if (f < 0) continue;
        const physics::ShellFaceTerms<float>& face = d.shell_faces[f];
        std::uint32_t face_vertices[3][4]{};
        for (int e = 0; e < 3; ++e)
            if (face.hinge[e] >= 0)
                for (int a = 0; a < 4; ++a) face_vertices[e][a] = d.hinge_vertices[4 * face.hinge[e] + a];
        physics::shell_hinge_slots<float>(static_cast<std::int32_t>(k), mine, face, face_vertices, out.rhs, &out.block[0][0]);
    }
}

__device__ inline bool hinge_terms(const DeviceView& d, const StepParams& sp, std::uint32_t k, HingeTerms& out) {
    const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.hinge_cloth[k]];
    if (p.bending <= 0.0f) return false;  // before any load: most scenes' hinges are all live or all idle
    if (d.shell_faces != nullptr) {
        shell_hinge_terms(d, k, out);
        return true;
    }
    const float h = sp.h;
    V3 x[4], vk[4], dvw[4];
    for (int a = 0; a < 4; ++a) {
        const std::uint32_t v = d.hinge_vertices[4 * k + a];
        const V3 w = load3(d.wk, v, d.n);
        x[a] = load3(d.x0, v, d.n) + h * w;
        vk[a] = load3(d.vk, v, d.n);
        dvw[a] = vk[a] - w;
    }
    return physics::hinge_terms(implicit_step(sp), d.hinge_rest[2 * k], d.hinge_rest[2 * k + 1], p, x, vk, dvw,
                                static_cast<physics::HessianKind>(sp.hessian), out);
}

}  // namespace weft::cuda
