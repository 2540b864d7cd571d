// Impact zones projected by projected Gauss–Seidel over colours (collision/colored_zone_projection.h).
#include "collision/colored_zone_projection.h"

#include <algorithm>
#include <string>

#include "cuda_check.h"
#include "weft/error.h"

namespace weft::cuda::collision {
namespace {

constexpr unsigned kThreads = 1024;  // one block a zone: a zone's colour is a few hundred constraints
constexpr std::uint32_t kUncoloured = 0xFFFFFFFFU;

/// Adds M⁻¹ J_kᵀ Δλ to the displacements `d` (SoA in shared memory, component stride `stride`) for
/// the constraint packed at `at`: each of its movable vertices moves by (w_j Δλ / m_j) n.
__device__ inline void apply_multiplier(const uint4 slot, const float4 move, const float4 normal, double change,
                                        float* d, std::uint32_t stride) {
    const std::uint32_t s[4] = {slot.x, slot.y, slot.z, slot.w};
    const float m[4] = {move.x, move.y, move.z, move.w};
    for (int j = 0; j < 4; ++j) {
        if (s[j] == kNoSlot) continue;
        const auto step = static_cast<float>(m[j] * change);
        d[s[j]] += step * normal.x;
        d[stride + s[j]] += step * normal.y;
        d[2 * stride + s[j]] += step * normal.z;
    }
}

__global__ void __launch_bounds__(kThreads)
    colored_projection_kernel(ColoredZoneProjection p, std::uint32_t max_vertices, std::uint32_t min_constraints,
                              double delta, double tol, int max_sweeps) {
    extern __shared__ float d[];  // x − x̂ of the zone's vertices, SoA with stride max_vertices
    __shared__ unsigned long long worst_bits[2];  // each sweep's largest KKT residual (a double ≥ 0)
    __shared__ std::uint32_t placed;              // constraints coloured so far
    const std::uint32_t zone = blockIdx.x;
    const std::uint32_t root = p.zone_label[zone];
    if (p.action[root] != p.project_code) return;
    const std::uint32_t vb = p.voffset[zone], ve = p.voffset[zone + 1];
    const std::uint32_t cb = p.coffset[zone], ce = p.coffset[zone + 1];
    if (ve - vb > max_vertices || ce - cb <= min_constraints) return;  // the projected gradient's zone
    const std::uint32_t first_colour = cb + zone;  // this zone's run of color_start (colours ≤ its constraints)
    const std::uint32_t tid = threadIdx.x, step = blockDim.x;
    const std::uint32_t stride = max_vertices;
    const std::size_t n = p.n;

    // The zone's vertices: their slots, zero displacement, no claims. Its constraints: uncoloured.
    for (std::uint32_t i = vb + tid; i < ve; i += step) {
        const std::uint32_t v = p.unique_vertex[p.vvalue[i]];
        p.zone_slot[v] = i - vb;
        p.claim[v] = kUncoloured;
        for (int a = 0; a < 3; ++a) d[a * stride + (i - vb)] = 0.0F;
    }
    for (std::uint32_t i = cb + tid; i < ce; i += step) p.color[p.cvalue[i]] = kUncoloured;
    if (tid == 0) {
        placed = 0;
        worst_bits[0] = worst_bits[1] = 0;
    }
    __syncthreads();

    // Colouring, one colour a round: an uncoloured constraint takes the colour when it is the
    // smallest uncoloured id at each of its movable vertices. The smallest uncoloured id of the zone
    // always wins, so every round colours at least one constraint.
    std::uint32_t colours = 0;
    for (bool left = true; left; ++colours) {
        if (tid == 0) p.color_start[first_colour + colours] = placed;  // the last round's writes are behind a barrier
        for (std::uint32_t i = cb + tid; i < ce; i += step) {
            const std::uint32_t k = p.cvalue[i];
            if (p.color[k] != kUncoloured) continue;
            for (int j = 0; j < 4; ++j) {
                const std::uint32_t v = p.vertex[4 * k + j];
                if (p.inverse_mass[v] > 0.0F) atomicMin(p.claim + v, k);
            }
        }
        __syncthreads();
        for (std::uint32_t i = cb + tid; i < ce; i += step) {
            const std::uint32_t k = p.cvalue[i];
            if (p.color[k] != kUncoloured) continue;
            bool won = true;
            for (int j = 0; j < 4; ++j) {
                const std::uint32_t v = p.vertex[4 * k + j];
                if (p.inverse_mass[v] > 0.0F && p.claim[v] != k) won = false;
            }
            if (won) {
                p.color[k] = colours;
                // Within a colour the order does not matter (disjoint vertices): any slot will do.
                p.color_order[cb + atomicAdd(&placed, 1U)] = k;
            }
        }
        __syncthreads();
        // Release this round's claims: those of every constraint uncoloured at its start.
        int uncoloured = 0;
        for (std::uint32_t i = cb + tid; i < ce; i += step) {
            const std::uint32_t k = p.cvalue[i];
            const std::uint32_t c = p.color[k];
            if (c != kUncoloured && c != colours) continue;
            if (c == kUncoloured) uncoloured = 1;
            for (int j = 0; j < 4; ++j) {
                const std::uint32_t v = p.vertex[4 * k + j];
                if (p.inverse_mass[v] > 0.0F) p.claim[v] = kUncoloured;  // a fixed vertex may be in other zones
            }
        }
        left = __syncthreads_or(uncoloured) != 0;
    }
    if (tid == 0) p.color_start[first_colour + colours] = placed;

    // Each constraint's terms in colour order: g_k(x̂ + d) = (n·Σ w x̂ − δ) + n·Σ w d, 1/A_kk, λ_k.
    for (std::uint32_t i = cb + tid; i < ce; i += step) {
        const std::uint32_t k = p.color_order[i];
        double f[3] = {0.0, 0.0, 0.0}, diagonal = 0.0;
        std::uint32_t slot[4];
        float weight[4], move[4];
        for (int j = 0; j < 4; ++j) {
            const std::uint32_t v = p.vertex[4 * k + j];
            const float w = p.weight[4 * k + j], im = p.inverse_mass[v];
            for (int a = 0; a < 3; ++a) f[a] += static_cast<double>(w) * p.x_hat[a * n + v];
            const bool moves = im > 0.0F;
            if (moves) diagonal += static_cast<double>(w) * w * im;
            slot[j] = moves ? p.zone_slot[v] : kNoSlot;
            weight[j] = moves ? w : 0.0F;
            move[j] = moves ? static_cast<float>(static_cast<double>(w) * im) : 0.0F;
        }
        const float nx = p.normal[3 * k], ny = p.normal[3 * k + 1], nz = p.normal[3 * k + 2];
        p.packed_slot[i] = uint4{slot[0], slot[1], slot[2], slot[3]};
        p.packed_weight[i] = float4{weight[0], weight[1], weight[2], weight[3]};
        p.packed_move[i] = float4{move[0], move[1], move[2], move[3]};
        p.packed_normal[i] = float4{nx, ny, nz, 0.0F};
        p.packed_offset[i] = nx * f[0] + ny * f[1] + nz * f[2] - delta;
        p.packed_inverse_diagonal[i] = diagonal > 0.0 ? 1.0 / diagonal : 0.0;  // 0: only weight-0 movable vertices
        p.packed_lambda[i] = p.lambda[k];
    }
    __syncthreads();

    // Warm start from the multipliers of the zone's last projection: d = M⁻¹ Jᵀ λ, colour by colour.
    for (std::uint32_t c = 0; c < colours; ++c) {
        const std::uint32_t begin = cb + p.color_start[first_colour + c], end = cb + p.color_start[first_colour + c + 1];
        for (std::uint32_t i = begin + tid; i < end; i += step) {
            const double lambda = p.packed_lambda[i];
            if (lambda != 0.0) apply_multiplier(p.packed_slot[i], p.packed_move[i], p.packed_normal[i], lambda, d, stride);
        }
        __syncthreads();
    }

    // Sweeps: the CPU's dual coordinate ascent, each colour's constraints at once.
    int sweep = 1;
    bool converged = false;
    for (; sweep <= max_sweeps; ++sweep) {
        const int parity = sweep & 1;
        double worst = 0.0;  // the largest KKT residual of the sweep, each taken before its update
        for (std::uint32_t c = 0; c < colours; ++c) {
            const std::uint32_t begin = cb + p.color_start[first_colour + c], end = cb + p.color_start[first_colour + c + 1];
            for (std::uint32_t i = begin + tid; i < end; i += step) {
                const double inverse_diagonal = p.packed_inverse_diagonal[i];
                const uint4 slot = p.packed_slot[i];
                const float4 w = p.packed_weight[i], normal = p.packed_normal[i];
                const double offset = p.packed_offset[i], lambda = p.packed_lambda[i];
                if (!(inverse_diagonal > 0.0)) continue;  // no say (as the CPU)
                const std::uint32_t s[4] = {slot.x, slot.y, slot.z, slot.w};
                const float wj[4] = {w.x, w.y, w.z, w.w};
                float f[3] = {0.0F, 0.0F, 0.0F};
                for (int j = 0; j < 4; ++j) {
                    if (s[j] == kNoSlot) continue;
                    for (int a = 0; a < 3; ++a) f[a] += wj[j] * d[a * stride + s[j]];
                }
                const double g = offset + static_cast<double>(normal.x) * f[0] + static_cast<double>(normal.y) * f[1] +
                                 static_cast<double>(normal.z) * f[2];
                worst = fmax(worst, lambda > 0.0 ? fabs(g) : fmax(0.0, -g));
                const double next = fmax(0.0, lambda - g * inverse_diagonal);
                if (next != lambda) {
                    apply_multiplier(slot, p.packed_move[i], normal, next - lambda, d, stride);
                    p.packed_lambda[i] = next;
                }
            }
            __syncthreads();
            // Every thread has read the last sweep's slot: clear it for the next sweep.
            if (c == 0 && tid == 0) worst_bits[parity ^ 1] = 0;
        }
        atomicMax(&worst_bits[parity], static_cast<unsigned long long>(__double_as_longlong(worst)));
        __syncthreads();
        if (__longlong_as_double(static_cast<long long>(worst_bits[parity])) <= tol) {
            converged = true;
            break;
        }
    }

    for (std::uint32_t i = cb + tid; i < ce; i += step) p.lambda[p.color_order[i]] = p.packed_lambda[i];
    for (std::uint32_t i = vb + tid; i < ve; i += step) {
        const std::uint32_t v = p.unique_vertex[p.vvalue[i]];
        for (int a = 0; a < 3; ++a) p.x1[a * n + v] = p.x_hat[a * n + v] + d[a * stride + (i - vb)];
        p.outcome[v] = p.projected_code;
    }
    if (tid == 0) {
        p.action[root] = p.done_code;
        const int used = converged ? sweep : max_sweeps;
        atomicAdd(p.sweeps, static_cast<std::uint32_t>(used));
        atomicAdd(p.work, static_cast<unsigned long long>(used) * (ce - cb));
        if (!converged) atomicAdd(p.unconverged, 1U);
    }
}

}  // namespace

void launch_colored_zone_projection(const ColoredZoneProjection& p, std::uint32_t zones, std::uint32_t max_vertices,
                                    std::uint32_t min_constraints, double delta, double tol, int max_sweeps,
                                    cudaStream_t stream) {
    if (zones == 0 || max_vertices == 0) return;
    if (max_vertices > kColoredZoneVertices)
        throw Error("coloured zone projection: " + std::to_string(max_vertices) + " vertices a zone exceed " +
                    std::to_string(kColoredZoneVertices));
    const std::size_t shared = 3 * std::size_t{max_vertices} * sizeof(float);
    colored_projection_kernel<<<zones, kThreads, shared, stream>>>(p, max_vertices, min_constraints, delta, tol, max_sweeps);
    WEFT_CUDA_CHECK_LAUNCH("impact zones: coloured projection");
}

}  // namespace weft::cuda::collision
