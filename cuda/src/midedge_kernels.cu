// The mid-edge bending model's normals on the device (solver.bending = "midedge";
// weft/physics/midedge_bending.h): the turns ξ, one per hinge, that minimise the bending energy at
// given positions, the same solve as the CPU's (runtime/src/midedge_normals.h): Jacobi-preconditioned
// CG on K_ξξ·ξ = −b in double, from ξ = 0, so that ξ is a function of the positions alone (nothing to
// checkpoint) and has the same bits on every run.
//
// One cooperative launch does it all, in phases separated by grid-wide barriers:
//   1. per hinge: its angle θ − θ̄ and whether it is a clamp (a triangle of it has three pinned
//      corners);
//   2. per triangle: how it reads each edge (MidEdgeEdge: the clamp's scales and the sides);
//   3. per hinge: b, the diagonal of K_ξξ, r₀ = −b, p₀ = r₀/diag; then the loop, three barriers an
//      iteration (q = K_ξξ·p with pᵀq; ξ and r with rᵀr and rᵀz; the direction).
// K_ξξ is mass-like, so the loop takes 20–60 iterations at any resolution: a launch per iteration
// would cost more than the work, and one launch needs no host round trip inside a CUDA graph.
// Every row is gathered from the hinge's (up to) two triangles in a fixed order with the host's own
// functions (midedge_xi_gradient), so rows carry no atomics.
#include <cooperative_groups.h>
#include <cuda_runtime.h>

#include <algorithm>

#include "cuda_check.h"
#include "device_math.cuh"
#include "kernels.h"
#include "persistent_sum.cuh"
#include "shell_bending_state.cuh"
#include "weft/physics/bending.h"

namespace weft::cuda {
namespace {

using Vec3d = physics::Vec3<double>;

/// Vertex v at the state the normals are relaxed at: x0 + h·w_k in float, as the solver's pass 1
/// forms its linearisation point (shell_faces_kernel), or x.
__device__ inline Vec3d relax_position(const DeviceView& d, std::uint32_t v, bool at_x, float h) {
    const V3 p = at_x ? load3(d.x, v, d.n) : load3(d.x0, v, d.n) + h * load3(d.wk, v, d.n);
    return {static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)};
}

__device__ inline physics::ShellBendingRest<double> rest_of(const DeviceView& d, std::uint32_t t) {
    const float* r = d.shell_rest + 10 * t;
    physics::ShellBendingRest<double> rest;
    rest.area = r[0];
    for (int e = 0; e < 9; ++e) rest.m[e / 3][e % 3] = r[1 + e];
    return rest;
}

/// Hinge h's row of K_ξξ·v (`v` non-null) or of b (v null: the angles' part), summed over its faces in
/// their fixed order, as the host's solve_midedge_normals.
__device__ inline double midedge_row(const DeviceView& d, std::uint32_t h, const double* v) {
    double sum = 0.0;
    for (int s = 0; s < 2; ++s) {
        const std::int32_t t = d.hinge_faces[2 * h + s];
        if (t < 0) continue;
        const physics::MidEdgeFace<double> f = midedge_face(d, static_cast<std::uint32_t>(t), v == nullptr);
        int k = -1;
        double local[3]{};
        for (int l = 0; l < 3; ++l) {
            if (f.hinge[l] == static_cast<std::int32_t>(h)) k = l;
            if (v != nullptr && f.side[l] != 0.0) local[l] = v[f.hinge[l]];
        }
        if (k < 0 || f.side[k] == 0.0) continue;
        const physics::ShellBendingRest<double> rest = rest_of(d, static_cast<std::uint32_t>(t));
        sum += rest.area * physics::midedge_xi_gradient(f, rest, local, k, v == nullptr);
    }
    return sum;
}

/// Hinge h's diagonal entry of K_ξξ: Σ over its faces that give it a ξ of 4·A·M'_kk.
__device__ inline double midedge_diagonal(const DeviceView& d, std::uint32_t h) {
    double diag = 0.0;
    for (int s = 0; s < 2; ++s) {
        const std::int32_t t = d.hinge_faces[2 * h + s];
        if (t < 0) continue;
        for (int k = 0; k < 3; ++k) {
            const std::uint8_t edge = d.midedge.edge[3 * t + k];
            if (d.triangle_hinges[3 * t + k] == static_cast<std::int32_t>(h) && (edge == kMidEdgeFirst || edge == kMidEdgeSecond)) {
                const float* r = d.shell_rest + 10 * t;
                diag += 4.0 * static_cast<double>(r[0]) * static_cast<double>(r[1 + 4 * k]);
            }
        }
    }
    return diag;
}

__global__ void __launch_bounds__(kBlockSize) midedge_relax_kernel(DeviceView d, int at_x, int count) {
    namespace cg = cooperative_groups;
    const MidEdgeView& m = d.midedge;
    const std::uint32_t first = blockIdx.x * blockDim.x + threadIdx.x, stride = gridDim.x * blockDim.x;
    const float h = at_x ? 0.0f : step_params(d).h;
    const auto pinned = [&](std::uint32_t v) { return d.fixed[v] != 0; };

    // 1. Each hinge's angle and clamp. Its triangles are (v0, v1, v2) and (v1, v0, v3).
    for (std::uint32_t e = first; e < d.hinges; e += stride) {
        const std::uint32_t* hv = d.hinge_vertices + 4 * e;
        Vec3d p[4];
        for (int a = 0; a < 4; ++a) p[a] = relax_position(d, hv[a], at_x != 0, h);
        m.angle[e] = physics::detail::wrap_angle(physics::dihedral_angle(p) - static_cast<double>(d.hinge_rest[2 * e + 1]));
        m.clamp[e] = pinned(hv[0]) && pinned(hv[1]) && (pinned(hv[2]) || pinned(hv[3])) ? 1 : 0;
    }
    cg::this_grid().sync();

    // 2. How each triangle reads its edges (the host's midedge_faces).
    for (std::uint32_t t = first; t < d.triangles; t += stride) {
        const std::uint32_t* tv = d.triangle_vertices + 3 * t;
        const bool self_pinned = pinned(tv[0]) && pinned(tv[1]) && pinned(tv[2]);
        for (int k = 0; k < 3; ++k) {
            const std::int32_t e = d.triangle_hinges[3 * t + k];
            std::uint8_t edge = kMidEdgeNone;
            if (e >= 0) {
                if (m.clamp[e] != 0)
                    edge = self_pinned ? kMidEdgeClampSelf : kMidEdgeClampOther;
                else
                    edge = physics::midedge_side(tv[k], d.hinge_vertices[4 * e]) > 0 ? kMidEdgeFirst : kMidEdgeSecond;
            }
            m.edge[3 * t + k] = edge;
        }
    }
    cg::this_grid().sync();

    // 3. b, the Jacobi diagonal and the first residual and direction; ξ = 0.
    double* partials[2] = {m.partials, m.partials + 2 * gridDim.x};
    int which = 0;
    double local[2] = {0.0, 0.0}, sums[2];
    for (std::uint32_t e = first; e < d.hinges; e += stride) {
        const double diag = midedge_diagonal(d, e);
        const double r = diag > 0.0 ? -midedge_row(d, e, nullptr) : 0.0;
        const double z = diag > 0.0 ? r / diag : 0.0;
        m.diag[e] = diag;
        m.r[e] = r;
        m.p[e] = z;
        m.xi[e] = 0.0;
        local[0] += r * r;
        local[1] += r * z;
    }
    persistent_sums<2>(local, partials[which], sums);
    which ^= 1;
    const double bb = sums[0];
    double rr = bb, rz = sums[1];
    const double stop = physics::kMidEdgeTolerance * physics::kMidEdgeTolerance * bb;
    int iterations = 0;
    if (bb > 0.0) {
        while (rr > stop && iterations < physics::kMidEdgeMaxIterations) {
            double pq_local[1] = {0.0}, pq[1];
            for (std::uint32_t e = first; e < d.hinges; e += stride) {
                const double q = m.diag[e] > 0.0 ? midedge_row(d, e, m.p) : 0.0;
                m.q[e] = q;
                pq_local[0] += m.p[e] * q;
            }
            persistent_sums<1>(pq_local, partials[which], pq);
            which ^= 1;
            if (!(pq[0] > 0.0)) break;
            const double alpha = rz / pq[0];
            local[0] = local[1] = 0.0;
            for (std::uint32_t e = first; e < d.hinges; e += stride) {
                const double diag = m.diag[e];
                m.xi[e] += alpha * m.p[e];
                const double r = m.r[e] - alpha * m.q[e];
                m.r[e] = r;
                const double z = diag > 0.0 ? r / diag : 0.0;
                local[0] += r * r;
                local[1] += r * z;
            }
            persistent_sums<2>(local, partials[which], sums);
            which ^= 1;
            rr = sums[0];
            const double beta = sums[1] / rz;
            rz = sums[1];
            for (std::uint32_t e = first; e < d.hinges; e += stride) {
                const double diag = m.diag[e];
                m.p[e] = (diag > 0.0 ? m.r[e] / diag : 0.0) + beta * m.p[e];
            }
            ++iterations;
            cg::this_grid().sync();  // every direction is complete before the next product reads it
        }
    }
    if (count != 0 && first == 0 && bb > 0.0 && !(rr <= stop)) ++d.stats->cg_not_converged;
}

}  // namespace

int midedge_relax_grid(const DeviceView& d, int device) {
    int per_sm = 0, sms = 0, cooperative = 0;
    WEFT_CUDA_CHECK(cudaDeviceGetAttribute(&cooperative, cudaDevAttrCooperativeLaunch, device));
    if (cooperative == 0) return 0;
    WEFT_CUDA_CHECK(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device));
    WEFT_CUDA_CHECK(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, &midedge_relax_kernel, kBlockSize, 0));
    const int needed = static_cast<int>(grid_for(std::max(std::max(d.hinges, d.triangles), 1u)));
    return std::min(needed, per_sm * sms);
}

void launch_midedge_relax(const DeviceView& d, MidEdgeAt at, cudaStream_t stream) {
    if (d.midedge.xi == nullptr || d.midedge.grid <= 0) return;
    DeviceView view = d;
    int at_x = at == MidEdgeAt::Positions ? 1 : 0;
    int count = at == MidEdgeAt::Linearisation ? 1 : 0;
    void* args[] = {&view, &at_x, &count};
    WEFT_CUDA_CHECK(cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(&midedge_relax_kernel), dim3(d.midedge.grid),
                                                dim3(kBlockSize), args, 0, stream));
    WEFT_CUDA_CHECK_LAUNCH("midedge_relax_kernel");
}

}  // namespace weft::cuda
