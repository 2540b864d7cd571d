// The energy guard's audit on the device (weft/backend/energy_audit.h; docs/methods.md §1b): the
// same sums as host_energy_audit, in float per vertex and element and in double across them, so
// the guard on the cuda backend reads back nine numbers instead of the state.
//
// Each kernel writes one double per value and block (CUB's block reduction), and one block then
// sums every value's partials in block order: the same bits on every run.
#include <cub/block/block_reduce.cuh>
#include <cuda_runtime.h>

#include "contact_terms.cuh"
#include "shell_bending_state.cuh"
#include "cuda_check.h"
#include "weft/physics/offset_contact.h"
#include "weft/physics/proximity.h"
#include "device_math.cuh"
#include "weft/physics/bending.h"
#include "weft/physics/collider_contact.h"
#include "weft/physics/implicit_terms.h"
#include "weft/physics/membrane.h"

namespace weft::cuda {
namespace {

using Reduce = cub::BlockReduce<double, kBlockSize>;

struct MaxOp {
    __device__ double operator()(double a, double b) const { return a > b ? a : b; }
};

/// Sums `value` over the block into partials[blockIdx.x] (thread 0 writes).
__device__ void block_partial(double value, double* partials) {
    __shared__ typename Reduce::TempStorage storage;
    const double sum = Reduce(storage).Sum(value);
    if (threadIdx.x == 0) partials[blockIdx.x] = sum;
    __syncthreads();  // storage is reused by the next value
}

/// The block's largest `value` into partials[blockIdx.x] (the sums' layout; audit_finish_kernel
/// takes the largest over the blocks for the values that are maxima, kEnergyMaxStretch).
__device__ void block_maximum(double value, double* partials) {
    __shared__ typename Reduce::TempStorage storage;
    const double largest = Reduce(storage).Reduce(value, MaxOp{});
    if (threadIdx.x == 0) partials[blockIdx.x] = largest;
    __syncthreads();
}

__device__ inline V3 position(const DeviceView& d, std::uint32_t i) { return load3(d.x, i, d.n); }
__device__ inline V3 velocity(const DeviceView& d, std::uint32_t i) { return load3(d.v, i, d.n); }

/// A point of mass `m` (kg) at `x` moving with `v` (a vertex, or a triangle's centroid with face
/// contacts) against the analytic colliders at their pose at t: adds its penalty energy to
/// `contact` and the moving colliders' power bound to `power` (|f|·|u| for a steady contact,
/// 2m|u|(|u| + |v|)/h for an impact; host_energy_audit).
__device__ inline void add_collider_energy(const DeviceView& d, const StepParams& sp, const ClothParams& p, float m, V3 x, V3 v,
                                           double& contact, double& power) {
    const float k = physics::collider_penalty_stiffness(sp.contact_stiffness, m, sp.h2);
    const auto* shapes = staged<physics::Shape<float>>(d, sp.shape_start_offset);
    const float* friction = staged<float>(d, sp.friction_offset);
    for (int c = 0; c < sp.shape_count; ++c) {
        const float mu = friction[c] >= 0.0f ? friction[c] : p.friction;
        const physics::ContactResult<float> r = physics::collider_contact(
            shapes[c], physics::ContactParams<float>{k, p.thickness, mu, 1e-3f}, x, v, physics::HessianKind::None);
        if (!r.active) continue;
        contact += r.energy;
        const double u = physics::length(physics::shape_point_velocity(shapes[c], x));
        power += physics::length(r.force) * u + 2.0 * m * u * (u + physics::length(v)) / sp.h;
    }
}

/// Per vertex: kinetic and gravitational energy, the analytic colliders' penalty energy and the
/// power bound of moving colliders (as host_energy_audit), the grab spring's power.
__global__ void audit_vertex_kernel(DeviceView d, double* partials, std::uint32_t stride) {
    const StepParams& sp = step_params(d);
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double kinetic = 0.0, gravity = 0.0, contact = 0.0, collider_power = 0.0, grab_power = 0.0;
    if (i < d.rows) {  // part mode: a ghost's energy is its owner's
        const float m = d.mass[i];
        const V3 x = position(d, i), v = velocity(d, i);
        kinetic = 0.5 * m * static_cast<double>(physics::dot(v, v));
        gravity = -static_cast<double>(m) * static_cast<double>(physics::dot(sp.gravity, x));
        // Pinned vertices get no collider terms in the solve (implicit_terms.h: vertex_terms).
        if (!d.fixed[i] && sp.shape_count > 0)
            add_collider_energy(d, sp, staged<ClothParams>(d, sp.cloth_offset)[d.vertex_cloth[i]], m, x, v, contact,
                                collider_power);
        if (i == sp.grab_vertex && !d.fixed[i]) {
            const V3 force = sp.grab_stiffness * (sp.grab_target - x) - sp.grab_damping * v;
            grab_power = static_cast<double>(physics::dot(force, v));
            grab_power = grab_power > 0.0 ? grab_power : 0.0;
        }
    }
    block_partial(kinetic, partials);
    block_partial(gravity, partials + stride);
    block_partial(contact, partials + 2 * stride);
    block_partial(collider_power, partials + 3 * stride);
    block_partial(grab_power, partials + 4 * stride);
}

__device__ inline void triangle_state(const DeviceView& d, std::uint32_t t, V3 (&x)[3], float (&dm_inv)[2][2], float& area) {
    for (int a = 0; a < 3; ++a) x[a] = position(d, d.triangle_vertices[3 * t + a]);
    const float* rest = d.triangle_rest + 5 * t;
    dm_inv[0][0] = rest[0];
    dm_inv[0][1] = rest[1];
    dm_inv[1][0] = rest[2];
    dm_inv[1][1] = rest[3];
    area = rest[4];
}

/// Per triangle: membrane energy and, when asked, the wind's power bound max(0, F·w) with F the
/// triangle's drag and lift at the air velocity w of its centroid (host_energy_audit).
__global__ void audit_triangle_kernel(DeviceView d, double* partials, std::uint32_t stride, int with_wind) {
    const StepParams& sp = step_params(d);
    const std::uint32_t t = blockIdx.x * blockDim.x + threadIdx.x;
    double energy = 0.0, wind_power = 0.0, stretch = 0.0;
    // Part mode: an element is the part's to count when the part owns its first corner (exactly one
    // part does; on one GPU every row is owned).
    if (t < d.triangles && d.triangle_vertices[3 * t] < d.rows) {
        V3 x[3];
        float dm_inv[2][2], area;
        triangle_state(d, t, x, dm_inv, area);
        stretch = physics::largest_stretch<float>(dm_inv, x);
        const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.triangle_cloth[t]];
        energy = physics::membrane_evaluate<float>(dm_inv, area, p.membrane, x, nullptr, nullptr, physics::HessianKind::None);
        if (with_wind && sp.wind_active && (p.drag > 0.0f || p.lift > 0.0f)) {
            V3 air = sp.wind;
            if (sp.turbulence > 0.0f)
                air += physics::wind_gust((x[0] + x[1] + x[2]) / 3.0f, sp.time, sp.turbulence, sp.turbulence_frequency,
                                          sp.turbulence_scale);
            V3 v[3];
            for (int a = 0; a < 3; ++a) v[a] = velocity(d, d.triangle_vertices[3 * t + a]);
            V3 per_vertex{};
            physics::aerodynamic_force(x, v, air, physics::AeroCoefficients<float>{sp.air_density, p.drag, p.lift}, per_vertex,
                                       static_cast<M3*>(nullptr));
            const double power = 3.0 * static_cast<double>(physics::dot(per_vertex, air));
            wind_power = power > 0.0 ? power : 0.0;
        }
    }
    block_partial(energy, partials);
    block_partial(wind_power, partials + stride);
    block_maximum(stretch, partials + (kEnergyMaxStretch - kEnergyMembrane) * stride);
}

/// Per triangle, with face contacts: its centroid's penalty energy against the analytic colliders and
/// their power bound, as the vertices' in audit_vertex_kernel (host_energy_audit's face contacts).
__global__ void audit_face_contact_kernel(DeviceView d, double* partials, std::uint32_t stride) {
    const StepParams& sp = step_params(d);
    const std::uint32_t t = blockIdx.x * blockDim.x + threadIdx.x;
    double contact = 0.0, collider_power = 0.0;
    if (t < d.triangles && d.triangle_vertices[3 * t] < d.rows) {
        V3 x{}, v{};
        float m = 0.0f;
        for (int a = 0; a < 3; ++a) {
            const std::uint32_t i = d.triangle_vertices[3 * t + a];
            x += position(d, i);
            v += velocity(d, i);
            m += d.mass[i];
        }
        x = x / 3.0f;
        v = v / 3.0f;
        m /= 3.0f;
        add_collider_energy(d, sp, staged<ClothParams>(d, sp.cloth_offset)[d.triangle_cloth[t]], m, x, v, contact,
                            collider_power);
    }
    block_partial(contact, partials);
    block_partial(collider_power, partials + stride);
}

__global__ void audit_hinge_kernel(DeviceView d, double* partials) {
    const StepParams& sp = step_params(d);
    const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    double energy = 0.0;
    if (k < d.hinges && d.hinge_vertices[4 * k] < d.rows) {
        const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.hinge_cloth[k]];
        if (p.bending > 0.0f) {
            V3 x[4];
            for (int a = 0; a < 4; ++a) x[a] = position(d, d.hinge_vertices[4 * k + a]);
            energy = physics::bending_evaluate<float>(p.bending, d.hinge_rest[2 * k], d.hinge_rest[2 * k + 1], x, nullptr,
                                                      nullptr, physics::HessianKind::None);
        }
    }
    block_partial(energy, partials);
}

/// Per triangle, with the bending model per triangle (d.shell_faces set): its bending energy (as
/// host_energy_audit's shell_bending_triangle). Counted on the part that owns its first corner.
__global__ void audit_shell_kernel(DeviceView d, double* partials) {
    const StepParams& sp = step_params(d);
    const std::uint32_t t = blockIdx.x * blockDim.x + threadIdx.x;
    double energy = 0.0;
    if (t < d.triangles && d.triangle_vertices[3 * t] < d.rows) {
        const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.triangle_cloth[t]];
        if (p.bending > 0.0f) {
            ShellFaceInput in;
            energy = shell_face_at(d, t, p.bending, d.x, in).energy;
        }
    }
    block_partial(energy, partials);
}

/// ∂E_bend/∂x_i under the bending model per triangle: each hinge e at vertex i (corner `corner`)
/// takes, from each face f of e, f's ∂E/∂θ_e·∇_iθ_e. Every (face, hinge of the face holding i) pair is
/// met exactly once this way, which is the sum host_energy_audit's gradient callback forms.
__device__ inline V3 shell_bending_gradient(const DeviceView& d, const StepParams& sp, std::uint32_t e, std::uint32_t corner) {
    V3 gradient{};
    for (int side = 0; side < 2; ++side) {
        const std::int32_t f = d.hinge_faces[2 * e + side];
        if (f < 0) continue;
        const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.triangle_cloth[f]];
        if (!(p.bending > 0.0f)) continue;
        ShellFaceInput in;
        const physics::ShellBendingTerms<float> terms = shell_face_at(d, static_cast<std::uint32_t>(f), p.bending, d.x, in);
        for (int k = 0; k < 3; ++k)
            if (in.hinge[k] == static_cast<std::int32_t>(e) && terms.active[k])
                gradient += terms.force_angle[k] * terms.dtheta[k][corner];
    }
    return gradient;
}

/// Per pinned vertex: ∇U·v, the power the pin puts in by holding the vertex against the elastic
/// force (a static pin has v = 0 and adds nothing; host_energy_audit counts moving pins only). One
/// warp a pin, the lanes over its triangles and hinges, a butterfly for the sum (the same order on
/// every run): a thread a pin walked a dozen elements in a chain of dependent loads (52 µs a call
/// on the 672-triangle runner, one H200 under ncu), and the audit runs every substep that may split.
__global__ void audit_pin_kernel(DeviceView d, double* partials) {
    const StepParams& sp = step_params(d);
    const std::uint32_t k = (blockIdx.x * blockDim.x + threadIdx.x) / 32, lane = threadIdx.x % 32;
    double power = 0.0;
    if (k < d.pins) {  // the same for the whole warp
        const std::uint32_t i = d.pin_vertex[k];
        V3 gradient{};
        for (std::uint32_t e = d.vertex_triangle_start[i] + lane; e < d.vertex_triangle_start[i + 1]; e += 32) {
            const std::uint32_t t = d.vertex_triangle[e] >> 2, corner = d.vertex_triangle[e] & 3u;
            V3 x[3], grad[3];
            float dm_inv[2][2], area;
            triangle_state(d, t, x, dm_inv, area);
            const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.triangle_cloth[t]];
            (void)physics::membrane_evaluate<float>(dm_inv, area, p.membrane, x, grad, nullptr, physics::HessianKind::None);
            gradient += grad[corner];
        }
        for (std::uint32_t e = d.vertex_hinge_start[i] + lane; e < d.vertex_hinge_start[i + 1]; e += 32) {
            const std::uint32_t h = d.vertex_hinge[e] >> 2, corner = d.vertex_hinge[e] & 3u;
            if (d.shell_faces != nullptr) {
                gradient += shell_bending_gradient(d, sp, h, corner);
                continue;
            }
            const ClothParams& p = staged<ClothParams>(d, sp.cloth_offset)[d.hinge_cloth[h]];
            if (!(p.bending > 0.0f)) continue;
            V3 x[4], grad[4];
            for (int a = 0; a < 4; ++a) x[a] = position(d, d.hinge_vertices[4 * h + a]);
            (void)physics::bending_evaluate<float>(p.bending, d.hinge_rest[2 * h], d.hinge_rest[2 * h + 1], x, grad,
                                                   nullptr, physics::HessianKind::None);
            gradient += grad[corner];
        }
        for (int offset = 16; offset > 0; offset /= 2) {
            gradient.x += __shfl_xor_sync(0xFFFFFFFFU, gradient.x, offset);
            gradient.y += __shfl_xor_sync(0xFFFFFFFFU, gradient.y, offset);
            gradient.z += __shfl_xor_sync(0xFFFFFFFFU, gradient.z, offset);
        }
        if (lane == 0) power = static_cast<double>(physics::dot(gradient, velocity(d, i)));
    }
    block_partial(power, partials);
}

/// The offset contacts of the last substep (docs/methods.md §7b) at the current state: their penalty
/// energy with the closest points taken here, as the CPU's ContactTerms::energy_at. Grid-stride over
/// the list (its count lives on the device); one partial per block.
__global__ void audit_offset_contact_kernel(DeviceView d, double* partials, const float* whole_x, std::uint32_t whole_n) {
    const ContactView& c = d.contacts;
    const std::uint32_t m = contact_count(c);
    // Part mode: whole-model ids, read from the whole positions; one GPU: the solver's own.
    const float* x_of = whole_x != nullptr ? whole_x : d.x;
    const std::uint32_t n = whole_x != nullptr ? whole_n : d.n;
    double energy = 0.0;
    for (std::uint32_t p = blockIdx.x * blockDim.x + threadIdx.x; p < m; p += gridDim.x * blockDim.x) {
        const DeviceContact& pair = c.list[p];
        if ((pair.pair & kOffsetContactBit) == 0) continue;
        if (c.row_of != nullptr) {
            // Counted once across the parts: by the owner of the first cloth corner.
            std::uint32_t first = 0xFFFFFFFFu;
            for (int j = 0; j < 4 && first == 0xFFFFFFFFu; ++j)
                if (pair.vertex[j] < n) first = pair.vertex[j];
            if (first == 0xFFFFFFFFu || c.row_of[first] == 0xFFFFFFFFu) continue;
        }
        V3 x[4];
        for (int j = 0; j < 4; ++j) {
            const std::uint32_t v = pair.vertex[j];
            x[j] = v < n ? load3(x_of, v, n) : load3(c.kinematic_x1, v - n, c.kinematic_capacity);
        }
        const float distance = (pair.pair & kEdgeEdgeContactBit) != 0
                                   ? physics::edge_edge_proximity(x[0], x[1], x[2], x[3]).distance
                                   : physics::point_triangle_proximity(x[0], x[1], x[2], x[3]).distance;
        energy += static_cast<double>(physics::offset_penalty(distance, pair.stiffness, pair.thickness).energy);
    }
    block_partial(energy, partials);
}

/// One block: sums[k] = the partials of value k in block order.
__global__ void audit_finish_kernel(const double* partials, std::uint32_t stride, EnergySumCounts counts, double* sums) {
    for (int k = 0; k < kEnergySums; ++k) {
        const bool maximum = k == kEnergyMaxStretch;  // the largest over the blocks, not the sum
        double acc = 0.0;
        for (std::uint32_t b = threadIdx.x; b < counts.blocks[k]; b += blockDim.x)
            acc = maximum ? fmax(acc, partials[k * stride + b]) : acc + partials[k * stride + b];
        __shared__ typename Reduce::TempStorage storage;
        const double total = maximum ? Reduce(storage).Reduce(acc, MaxOp{}) : Reduce(storage).Sum(acc);
        if (threadIdx.x == 0) sums[k] = total;
        __syncthreads();
    }
}

}  // namespace

/// audit_pin_kernel's blocks: a warp a pin.
static std::uint32_t pin_blocks(const DeviceView& d) { return blocks_for(d.pins, kBlockSize / 32); }

std::uint32_t energy_partial_stride(const DeviceView& d) {
    std::uint32_t blocks = 1;
    for (const std::uint32_t count : {d.n, d.triangles, d.hinges}) blocks = std::max(blocks, grid_for(count));
    return std::max(blocks, pin_blocks(d));
}

void launch_energy_audit(const DeviceView& d, bool with_wind, bool with_faces, double* partials, double* sums, cudaStream_t stream,
                         const float* whole_x, std::uint32_t whole_n) {
    const std::uint32_t stride = energy_partial_stride(d);
    EnergySumCounts counts{};
    const std::uint32_t vertex_blocks = grid_for(d.n);
    for (int k = 0; k < 5; ++k) counts.blocks[k] = vertex_blocks;
    audit_vertex_kernel<<<vertex_blocks, kBlockSize, 0, stream>>>(d, partials, stride);
    WEFT_CUDA_CHECK_LAUNCH("audit_vertex_kernel");
    counts.blocks[kEnergyMembrane] = counts.blocks[kEnergyWindPower] = counts.blocks[kEnergyMaxStretch] =
        d.triangles > 0 ? grid_for(d.triangles) : 0;
    static_assert(kEnergyWindPower == kEnergyMembrane + 1, "the triangle kernel writes both, one stride apart");
    if (d.triangles > 0) {
        audit_triangle_kernel<<<grid_for(d.triangles), kBlockSize, 0, stream>>>(d, partials + kEnergyMembrane * stride,
                                                                                 stride, with_wind ? 1 : 0);
        WEFT_CUDA_CHECK_LAUNCH("audit_triangle_kernel");
    }
    if (with_faces && d.triangles > 0) {  // the centroid contacts (StepParams::face_contacts)
        static_assert(kEnergyFaceColliderPower == kEnergyFaceContact + 1, "the face kernel writes both, one stride apart");
        counts.blocks[kEnergyFaceContact] = counts.blocks[kEnergyFaceColliderPower] = grid_for(d.triangles);
        audit_face_contact_kernel<<<grid_for(d.triangles), kBlockSize, 0, stream>>>(d, partials + kEnergyFaceContact * stride,
                                                                                     stride);
        WEFT_CUDA_CHECK_LAUNCH("audit_face_contact_kernel");
    }
    if (d.shell_faces != nullptr) {  // the bending models per triangle
        counts.blocks[kEnergyBending] = d.triangles > 0 ? grid_for(d.triangles) : 0;
        if (d.triangles > 0) {
            // The mid-edge model's energy is its minimum over the normals: relaxed at this state first
            // (the pins' power below reads them too), as the host audit's relax_midedge_normals.
            launch_midedge_relax(d, MidEdgeAt::Positions, stream);
            audit_shell_kernel<<<grid_for(d.triangles), kBlockSize, 0, stream>>>(d, partials + kEnergyBending * stride);
            WEFT_CUDA_CHECK_LAUNCH("audit_shell_kernel");
        }
    } else {
        counts.blocks[kEnergyBending] = d.hinges > 0 ? grid_for(d.hinges) : 0;
        if (d.hinges > 0) {
            audit_hinge_kernel<<<grid_for(d.hinges), kBlockSize, 0, stream>>>(d, partials + kEnergyBending * stride);
            WEFT_CUDA_CHECK_LAUNCH("audit_hinge_kernel");
        }
    }
    counts.blocks[kEnergyPinPower] = d.pins > 0 ? pin_blocks(d) : 0;
    if (d.pins > 0) {
        audit_pin_kernel<<<pin_blocks(d), kBlockSize, 0, stream>>>(d, partials + kEnergyPinPower * stride);
        WEFT_CUDA_CHECK_LAUNCH("audit_pin_kernel");
    }
    // Offset contacts: at most `stride` blocks (grid-stride over the list), none without a list.
    const bool readable = d.contacts.row_of == nullptr || whole_x != nullptr;  // a part needs the whole positions
    counts.blocks[kEnergyOffsetContact] =
        d.contacts.capacity > 0 && readable ? std::min(stride, grid_for(d.contacts.capacity)) : 0;
    if (counts.blocks[kEnergyOffsetContact] > 0) {
        audit_offset_contact_kernel<<<counts.blocks[kEnergyOffsetContact], kBlockSize, 0, stream>>>(
            d, partials + kEnergyOffsetContact * stride, whole_x, whole_n);
        WEFT_CUDA_CHECK_LAUNCH("audit_offset_contact_kernel");
    }
    audit_finish_kernel<<<1, kBlockSize, 0, stream>>>(partials, stride, counts, sums);
    WEFT_CUDA_CHECK_LAUNCH("audit_finish_kernel");
}

}  // namespace weft::cuda
