#pragma once
// The terms of A·Δv = b that each vertex, triangle and hinge contributes, evaluated by the same
// weft/physics functions as the CPU backend (runtime/src/cpu/cpu_solver.cpp, which derives them;
// docs/architecture.md, "the step in detail"). Both assembly strategies (assembly_kernels.cu) call these.

#include "device_math.cuh"
#include "weft/physics/aerodynamics.h"
#include "weft/physics/bending.h"

namespace weft::cuda {

/// Vertex i: inertia, gravity, mass-proportional damping and collider contacts. Returns the number of
/// active contacts.
__device__ inline int vertex_terms(const DeviceView& d, const StepParams& sp, std::uint32_t i, V3& rhs, M3& block) {
    const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.vertex_cloth[i]];
    const float h = sp.h, h2 = sp.h2, m = d.mass[i];
    const V3 vk = load3(d.vk, i, d.n), wk = load3(d.wk, i, d.n);
    // M(v0 − v_k) + h·m·g − h·α·m·v_k, and M(1 + hα) on the diagonal.
    rhs = m * (load3(d.v0, i, d.n) - vk) + (h * m) * sp.gravity - (h * p.damping_mass * m) * vk;
    block = M3::diagonal(m * (1.0f + h * p.damping_mass));
    int active = 0;
    if (sp.shape_count > 0 && !d.fixed[i]) {
        const V3 x = load3(d.x0, i, d.n) + h * wk;
        const V3 dvw = vk - wk;
        const auto* shapes = staged<physics::Shape<float>>(d, sp.shape_offset);
        const float* shape_friction = staged<float>(d, sp.friction_offset);
        // Penalty stiffness as on the CPU: from the scene, or 100·m/h².
        const float k = sp.contact_stiffness > 0.0f ? sp.contact_stiffness : 100.0f * m / h2;
        const auto kind = static_cast<physics::HessianKind>(sp.hessian);
        for (int s = 0; s < sp.shape_count; ++s) {
            const float mu = shape_friction[s] >= 0.0f ? shape_friction[s] : p.friction;
            const physics::ContactParams<float> cp{k, p.thickness, mu, 1e-3f};
            const physics::ContactResult<float> c = physics::collider_contact(shapes[s], cp, x, vk, kind);
            if (!c.active) continue;
            ++active;
            // f(x0 + h·v) ≈ f + K·h·(v − w): h·f + h²·K·(v_k − w_k) into b, −h·D − h²·K into A.
            rhs += h * c.force + h2 * (c.dfdx * dvw);
            block += -h * c.dfdv + -h2 * c.dfdx;
        }
    }
    if (i == sp.grab_vertex && !d.fixed[i]) {
        // The grab spring (weft/grab.h), as on the CPU: h·f − h²k(v_k − w_k) into b, (hc + h²k)·I into A.
        const V3 x = load3(d.x0, i, d.n) + h * wk;
        const float k = sp.grab_stiffness, c = sp.grab_damping;
        rhs += h * (k * (sp.grab_target - x) - c * vk) - (h2 * k) * (vk - wk);
        block += M3::diagonal(h * c + h2 * k);
    }
    return active;
}

/// Triangle t: membrane, Rayleigh stiffness damping and wind.
struct TriangleTerms {
    V3 rhs[3];
    M3 block[3][3];
};

__device__ inline void triangle_terms(const DeviceView& d, const StepParams& sp, std::uint32_t t, TriangleTerms& out) {
    const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.triangle_cloth[t]];
    const float h = sp.h, h2 = sp.h2;
    V3 x[3], vk[3], dvw[3], grad[3];
    for (int a = 0; a < 3; ++a) {
        const std::uint32_t v = d.triangle_vertices[3 * t + a];
        const V3 w = load3(d.wk, v, d.n);
        x[a] = load3(d.x0, v, d.n) + h * w;
        vk[a] = load3(d.vk, v, d.n);
        dvw[a] = vk[a] - w;
    }
    const float* rest = d.triangle_rest + 5 * t;
    const float dm_inv[2][2] = {{rest[0], rest[1]}, {rest[2], rest[3]}};
    M3 H[3][3];
    physics::membrane_evaluate(dm_inv, rest[4], p.membrane, x, grad, H, static_cast<physics::HessianKind>(sp.hessian));
    // Stiffness damping f = −βHv puts (hβ + h²)H into A (Baraff–Witkin eq. 18 with ∂f/∂v = −βH);
    // b gets −h∇E − H(hβ v_k + h²(v_k − w_k)).
    const float coef = h * p.damping_stiffness + h2;
    M3 D{};
    V3 wind_force{};
    if (sp.wind_active && (p.drag > 0.0f || p.lift > 0.0f)) {
        const V3 centroid = (x[0] + x[1] + x[2]) / 3.0f;
        V3 wind = sp.wind;
        if (sp.turbulence > 0.0f)
            wind += physics::wind_gust(centroid, sp.time, sp.turbulence, sp.turbulence_frequency, sp.turbulence_scale);
        physics::aerodynamic_force(x, vk, wind, physics::AeroCoefficients<float>{sp.air_density, p.drag, p.lift},
                                   wind_force, &D);
        // Each vertex carries a third of the force and sees a third of each velocity: (h/9)·D per pair.
        wind_force = h * wind_force;
        D = (h / 9.0f) * D;
    }
    for (int a = 0; a < 3; ++a) {
        V3 acc = -h * grad[a];
        for (int b = 0; b < 3; ++b) acc -= H[a][b] * (h * p.damping_stiffness * vk[b] + h2 * dvw[b]);
        out.rhs[a] = acc + wind_force;
        for (int b = 0; b < 3; ++b) out.block[a][b] = coef * H[a][b] + D;
    }
}

/// Hinge k: bending (with stiffness damping). `false` when the cloth has no bending stiffness.
struct HingeTerms {
    V3 rhs[4];
    M3 block[4][4];
};

__device__ inline bool hinge_terms(const DeviceView& d, const StepParams& sp, std::uint32_t k, HingeTerms& out) {
    const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.hinge_cloth[k]];
    if (p.bending <= 0.0f) return false;
    const float h = sp.h, h2 = sp.h2;
    V3 x[4], vk[4], dvw[4], grad[4];
    for (int a = 0; a < 4; ++a) {
        const std::uint32_t v = d.hinge_vertices[4 * k + a];
        const V3 w = load3(d.wk, v, d.n);
        x[a] = load3(d.x0, v, d.n) + h * w;
        vk[a] = load3(d.vk, v, d.n);
        dvw[a] = vk[a] - w;
    }
    physics::bending_evaluate(p.bending, d.hinge_rest[2 * k], d.hinge_rest[2 * k + 1], x, grad, out.block,
                              static_cast<physics::HessianKind>(sp.hessian));
    const float coef = h * p.damping_stiffness + h2;
    for (int a = 0; a < 4; ++a) {
        V3 acc = -h * grad[a];
        for (int b = 0; b < 4; ++b) acc -= out.block[a][b] * (h * p.damping_stiffness * vk[b] + h2 * dvw[b]);
        out.rhs[a] = acc;
    }
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) out.block[a][b] = coef * out.block[a][b];
    return true;
}

}  // namespace weft::cuda
