// Forces and their Jacobians, evaluated by the same weft/physics functions as the CPU backend and
// added straight into the sliced-ELL matrix (docs/architecture.md, "the step in detail"). The vertex
// kernel writes every row first (its diagonal block, zeros elsewhere); then one launch per element
// colour adds element blocks with plain read-modify-writes: elements of one colour share no vertex,
// so no two threads touch the same block, and the summation order is fixed (colour order).
#include "cuda_check.h"
#include "device_math.cuh"
#include "weft/physics/aerodynamics.h"
#include "weft/physics/bending.h"

namespace weft::cuda {
namespace {

__global__ void vertex_terms_kernel(DeviceView d) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    const StepParams& sp = step_params(d);
    int active = 0;
    if (i < d.n) {
        const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.vertex_cloth[i]];
        const float h = sp.h, h2 = sp.h2, m = d.mass[i];
        const V3 vk = load3(d.vk, i, d.n), wk = load3(d.wk, i, d.n);
        // Inertia, gravity and mass-proportional damping: M(v0 − v_k) + h·m·g − h·α·m·v_k.
        V3 rhs = m * (load3(d.v0, i, d.n) - vk) + (h * m) * sp.gravity - (h * p.damping_mass * m) * vk;
        M3 block = M3::diagonal(m * (1.0f + h * p.damping_mass));
        if (sp.shape_count > 0 && !d.fixed[i]) {
            const V3 x = load3(d.x0, i, d.n) + h * wk;
            const V3 dvw = vk - wk;
            const auto* shapes = staged<physics::Shape<float>>(d, sp.shape_offset);
            const float* shape_friction = staged<float>(d, sp.friction_offset);
            // Penalty stiffness as on the CPU (cpu_solver.cpp): from the scene, or 100·m/h².
            const float k = sp.contact_stiffness > 0.0f ? sp.contact_stiffness : 100.0f * m / h2;
            const auto kind = static_cast<physics::HessianKind>(sp.hessian);
            for (int s = 0; s < sp.shape_count; ++s) {
                const float mu = shape_friction[s] >= 0.0f ? shape_friction[s] : p.friction;
                const physics::ContactParams<float> cp{k, p.thickness, mu, 1e-3f};
                const physics::ContactResult<float> c = physics::collider_contact(shapes[s], cp, x, vk, kind);
                if (!c.active) continue;
                ++active;
                rhs += h * c.force + h2 * (c.dfdx * dvw);
                block += -h * c.dfdv + -h2 * c.dfdx;
            }
        }
        store3(d.b, i, d.n, rhs);
        // The whole row: the diagonal block, zeros in the element slots that follow.
        const std::uint32_t slice = i / kSliceRowsDevice;
        const std::uint32_t first = d.slice_start[slice], width = (d.slice_start[slice + 1] - first) / kSliceRowsDevice;
        const std::uint32_t diag = d.diagonal[i];
        for (std::uint32_t k = 0; k < width; ++k) {
            const std::uint32_t pos = first + k * kSliceRowsDevice + i % kSliceRowsDevice;
            store_block(d.blocks, pos, pos == diag ? block : M3{});
        }
    }
    // Contact counts are integers: atomics give the same total whatever the order.
    using Reduce = cub::BlockReduce<int, kBlockSize>;
    __shared__ typename Reduce::TempStorage storage;
    const int block_active = Reduce(storage).Sum(active);
    if (threadIdx.x == 0 && block_active > 0) atomicAdd(&d.stats->contacts, block_active);
}

__global__ void triangle_terms_kernel(DeviceView d, std::uint32_t first, std::uint32_t last) {
    const std::uint32_t t = first + blockIdx.x * blockDim.x + threadIdx.x;
    if (t >= last) return;
    const StepParams& sp = step_params(d);
    const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.triangle_cloth[t]];
    const float h = sp.h, h2 = sp.h2;
    std::uint32_t vid[3];
    V3 x[3], vk[3], dvw[3], grad[3];
    for (int a = 0; a < 3; ++a) {
        vid[a] = d.triangle_vertices[3 * t + a];
        const V3 w = load3(d.wk, vid[a], d.n);
        x[a] = load3(d.x0, vid[a], d.n) + h * w;
        vk[a] = load3(d.vk, vid[a], d.n);
        dvw[a] = vk[a] - w;
    }
    const float* rest = d.triangle_rest + 5 * t;
    const float dm_inv[2][2] = {{rest[0], rest[1]}, {rest[2], rest[3]}};
    M3 H[3][3];
    physics::membrane_evaluate(dm_inv, rest[4], p.membrane, x, grad, H, static_cast<physics::HessianKind>(sp.hessian));
    // Rayleigh stiffness damping as on the CPU: (hβ + h²)H into A, h·f − H(hβ v_k + h²(v_k − w_k)) into b.
    const float coef = h * p.damping_stiffness + h2;
    V3 rhs[3];
    for (int a = 0; a < 3; ++a) {
        V3 acc = -h * grad[a];
        for (int b = 0; b < 3; ++b) acc -= H[a][b] * (h * p.damping_stiffness * vk[b] + h2 * dvw[b]);
        rhs[a] = acc;
    }
    M3 D{};
    bool aero = false;
    if (sp.wind_active && (p.drag > 0.0f || p.lift > 0.0f)) {
        const V3 centroid = (x[0] + x[1] + x[2]) / 3.0f;
        V3 wind = sp.wind;
        if (sp.turbulence > 0.0f)
            wind += physics::wind_gust(centroid, sp.time, sp.turbulence, sp.turbulence_frequency, sp.turbulence_scale);
        V3 force{};
        physics::aerodynamic_force(x, vk, wind, physics::AeroCoefficients<float>{sp.air_density, p.drag, p.lift}, force, &D);
        for (int a = 0; a < 3; ++a) rhs[a] += h * force;
        D = (h / 9.0f) * D;
        aero = true;
    }
    for (int a = 0; a < 3; ++a) {
        for (int comp = 0; comp < 3; ++comp) d.b[comp * d.n + vid[a]] += rhs[a][comp];
        for (int b = 0; b < 3; ++b) {
            M3 block = coef * H[a][b];
            if (aero) block += D;
            add_block(d.blocks, d.triangle_positions[9 * t + 3 * a + b], block);
        }
    }
}

__global__ void hinge_terms_kernel(DeviceView d, std::uint32_t first, std::uint32_t last) {
    const std::uint32_t k = first + blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= last) return;
    const StepParams& sp = step_params(d);
    const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.hinge_cloth[k]];
    if (p.bending <= 0.0f) return;
    const float h = sp.h, h2 = sp.h2;
    std::uint32_t vid[4];
    V3 x[4], vk[4], dvw[4], grad[4];
    for (int a = 0; a < 4; ++a) {
        vid[a] = d.hinge_vertices[4 * k + a];
        const V3 w = load3(d.wk, vid[a], d.n);
        x[a] = load3(d.x0, vid[a], d.n) + h * w;
        vk[a] = load3(d.vk, vid[a], d.n);
        dvw[a] = vk[a] - w;
    }
    M3 H[4][4];
    physics::bending_evaluate(p.bending, d.hinge_rest[2 * k], d.hinge_rest[2 * k + 1], x, grad, H,
                              static_cast<physics::HessianKind>(sp.hessian));
    const float coef = h * p.damping_stiffness + h2;
    for (int a = 0; a < 4; ++a) {
        V3 acc = -h * grad[a];
        for (int b = 0; b < 4; ++b) acc -= H[a][b] * (h * p.damping_stiffness * vk[b] + h2 * dvw[b]);
        for (int comp = 0; comp < 3; ++comp) d.b[comp * d.n + vid[a]] += acc[comp];
        for (int b = 0; b < 4; ++b) add_block(d.blocks, d.hinge_positions[16 * k + 4 * a + b], coef * H[a][b]);
    }
}

}  // namespace

void launch_vertex_terms(const DeviceView& d, cudaStream_t stream) {
    vertex_terms_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("vertex_terms_kernel");
}

void launch_triangle_terms(const DeviceView& d, std::uint32_t first, std::uint32_t last, cudaStream_t stream) {
    if (last <= first) return;
    triangle_terms_kernel<<<grid_for(last - first), kBlockSize, 0, stream>>>(d, first, last);
    WEFT_CUDA_CHECK_LAUNCH("triangle_terms_kernel");
}

void launch_hinge_terms(const DeviceView& d, std::uint32_t first, std::uint32_t last, cudaStream_t stream) {
    if (last <= first) return;
    hinge_terms_kernel<<<grid_for(last - first), kBlockSize, 0, stream>>>(d, first, last);
    WEFT_CUDA_CHECK_LAUNCH("hinge_terms_kernel");
}

}  // namespace weft::cuda
