// The multilevel additive Schwarz preconditioner on the device (Wu, Wang & Wang 2022;
// docs/methods.md §2b; the levels in device_schwarz.h, the same tables as the CPU backend's
// cpu/schwarz_preconditioner.h). Every sum runs in a fixed order, so a solve has the same bits on
// every run.
//
// Factor, once per Newton iteration:
//   1. coupling kernels, level 1 up: each coupling block (a warp) sums its listed blocks of the level below
//      (level 1 reads the assembled matrix, without filtered rows and columns, with each row's
//      contact-augmented diagonal block from the PCG setup);
//   2. one thread block per domain of every level (one launch) fills its 48×48 matrix in shared memory from its
//      couplings, inverts it by Gauss–Jordan in double (SPD: no pivoting needed; a non-positive pivot
//      is counted and replaced by the diagonal's magnitude) and stores the inverse in float.
// Apply, once per CG iteration (z = M⁻¹r = Σ_l R_lᵀ D_l⁻¹ R_l r):
//   1. one warp per level-0 domain: gathers its 16 vertices' residuals (after the iteration's axpy
//      pair, fused here), multiplies by the domain's inverse, and sums the residual of each of the
//      domain's pieces into the next level;
//   2. the same per domain of each coarser level;
//   3. one thread per vertex adds the corrections of its node on every level, filters, stores z
//      and reduces rᵀz for CG's δ.
#include <cuda_runtime.h>

#include <algorithm>
#include <cstddef>

#include "cuda_check.h"
#include "device_math.cuh"
#include "pcg_control.cuh"
#include "schwarz_apply.cuh"

namespace weft::cuda {
namespace {

constexpr std::uint32_t kNodes = kSchwarzNodes;
constexpr std::uint32_t kDim = kSchwarzDim;

/// Level 0's coupling block of pattern slot s: A's block, 0 where a filtered vertex is involved (the
/// solve acts on S·A·S), the contact-augmented block on the diagonal.
__device__ inline M3 fine_coupling(const DeviceView& d, std::uint32_t s) {
    const SchwarzView& m = d.mas;
    const std::uint32_t i = m.slot_row[s], j = m.slot_column[s];
    if (d.fixed[i] || d.fixed[j]) return M3{};
    return i == j ? load_precond(d, i) : load_block(d.blocks, m.slot_position[s]);
}

/// Whether Newton iteration `newton` refactors (StepParams::schwarz_refactor).
__device__ inline bool refactors(const DeviceView& d, int newton) {
    const int refactor = step_params(d).schwarz_refactor;
    return refactor == 1 || (refactor == 2 && newton == 0);
}

/// One warp a coupling block: the lanes stride over its listed blocks and a butterfly sums the
/// lanes' blocks (the same order on every run). A thread a block took 80 µs a level on a 380-vertex
/// cloth (one H200, ncu): a diagonal block of level 1 sums about a hundred fine blocks, each behind
/// a chain of dependent loads.
__global__ void schwarz_coupling_kernel(DeviceView d, int l, int newton) {
    if (!refactors(d, newton)) return;
    const SchwarzLevelView& level = d.mas.level[l];
    const std::uint32_t e = (blockIdx.x * blockDim.x + threadIdx.x) / 32, lane = threadIdx.x % 32;
    if (e >= level.entries) return;  // the same for the whole warp
    M3 acc{};
    for (std::uint32_t k = level.source_start[e] + lane; k < level.source_start[e + 1]; k += 32) {
        const std::uint32_t src = level.source[k];
        acc += l == 1 ? fine_coupling(d, src) : load_block(d.mas.level[l - 1].coupling, src);
    }
    for (int offset = 16; offset > 0; offset /= 2)
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) acc.m[r][c] += __shfl_xor_sync(0xFFFFFFFFU, acc.m[r][c], offset);
    if (lane == 0) store_block(level.coupling, level.entry_begin + e, acc);
}

/// One block a domain, every level's domains in one launch (the levels' factorisations are
/// independent once the couplings are summed): a launch a level waited for each level's 48 pivot
/// steps in turn.
__global__ void schwarz_factor_kernel(DeviceView d, int newton) {
    if (!refactors(d, newton)) return;
    int l = 0;
    std::uint32_t domain = blockIdx.x;
    while (l + 1 < d.mas.levels && domain >= d.mas.level[l].domains) domain -= d.mas.level[l++].domains;
    const SchwarzLevelView& level = d.mas.level[l];
    if (domain >= level.domains) return;
    __shared__ double A[kDim][kDim + 1];  // +1: no bank conflicts along a column
    __shared__ double column[kDim];
    __shared__ double magnitude[kDim];
    __shared__ int failed;
    for (std::uint32_t k = threadIdx.x; k < kDim * (kDim + 1); k += blockDim.x) (&A[0][0])[k] = 0.0;
    if (threadIdx.x == 0) failed = 0;
    __syncthreads();
    // Each cell comes from one coupling: no two threads write the same entries.
    for (std::uint32_t k = level.dense_start[domain] + threadIdx.x; k < level.dense_start[domain + 1]; k += blockDim.x) {
        const std::uint32_t cell = level.dense_cell[k];
        const std::uint32_t a = cell / kNodes, b = cell % kNodes;
        const M3 m = l == 0 ? fine_coupling(d, level.dense_entry[k]) : load_block(level.coupling, level.dense_entry[k]);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) A[3 * a + r][3 * b + c] = static_cast<double>(m.m[r][c]);
    }
    __syncthreads();
    if (threadIdx.x < kDim) {
        // Nodes with nothing (filtered, or padding past the last node) are decoupled: identity.
        double& diagonal = A[threadIdx.x][threadIdx.x];
        if (diagonal == 0.0) diagonal = 1.0;
        magnitude[threadIdx.x] = fabs(diagonal);
    }
    __syncthreads();
    // In-place Gauss–Jordan: after step k, column k holds the inverse's column k of the eliminated
    // part. Column k is saved before row k changes, so no thread reads a value another is writing.
    for (std::uint32_t k = 0; k < kDim; ++k) {
        if (threadIdx.x < kDim) column[threadIdx.x] = A[threadIdx.x][k];
        __syncthreads();
        double pivot = column[k];
        if (!(pivot > 0.0)) {
            pivot = magnitude[k];
            if (threadIdx.x == 0) failed = 1;
        }
        const double inverse = 1.0 / pivot;
        if (threadIdx.x < kDim) A[k][threadIdx.x] = threadIdx.x == k ? inverse : A[k][threadIdx.x] * inverse;
        __syncthreads();
        for (std::uint32_t e = threadIdx.x; e < kDim * kDim; e += blockDim.x) {
            const std::uint32_t i = e / kDim, j = e % kDim;
            if (i == k) continue;
            A[i][j] = (j == k ? 0.0 : A[i][j]) - column[i] * A[k][j];
        }
        __syncthreads();
    }
    float* out = level.inverse + static_cast<std::size_t>(domain) * kDim * kDim;
    for (std::uint32_t e = threadIdx.x; e < kDim * kDim; e += blockDim.x) {
        const std::uint32_t j = e / kDim, i = e % kDim;  // column-major: a warp stores one column
        out[e] = static_cast<float>(A[i][j]);
    }
    if (threadIdx.x == 0 && failed) atomicAdd(&d.stats->pivot_failures, 1);
}

__global__ void schwarz_fine_kernel(DeviceView d, SchwarzInput in, const int* running) {
    __shared__ float values[kSchwarzWarpsPerBlock][kDim];
    if (running != nullptr && *running == 0) return;
    const std::uint32_t warp = threadIdx.x / 32;
    const std::uint32_t domain = blockIdx.x * kSchwarzWarpsPerBlock + warp;
    if (domain >= d.mas.level[0].domains) return;
    const float alpha = in == SchwarzInput::Update ? d.control->alpha : 0.0f;
    schwarz_fine_domain(d, domain, threadIdx.x % 32, values[warp], in, alpha);
}

__global__ void schwarz_coarse_kernel(DeviceView d, int l, const int* running) {
    __shared__ float values[kSchwarzWarpsPerBlock][kDim];
    if (running != nullptr && *running == 0) return;
    const std::uint32_t warp = threadIdx.x / 32;
    const std::uint32_t domain = blockIdx.x * kSchwarzWarpsPerBlock + warp;
    if (domain >= d.mas.level[l].domains) return;
    schwarz_coarse_domain(d, l, domain, threadIdx.x % 32, values[warp]);
}

__global__ void schwarz_prolong_kernel(DeviceView d, SchwarzOutput out, unsigned long long handle) {
    if (out == SchwarzOutput::Iterate && !d.control->running) return;
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double value = 0.0;
    if (i < d.n) {
        const V3 z = schwarz_correction(d, i);
        if (out == SchwarzOutput::Start) store3(d.c, i, d.n, z);
        if (out == SchwarzOutput::Iterate) store3(d.s, i, d.n, z);
        value = static_cast<double>(physics::dot(load3(d.r, i, d.n), z));
    }
    grid_sum(value, d, [&](double total) {
        if (out == SchwarzOutput::Norm)
            d.control->delta0_b = total;
        else if (out == SchwarzOutput::Start)
            start_solve(d, total, handle);
        else
            end_iteration(d, total, handle);
    });
}

}  // namespace

void launch_schwarz_couplings(const DeviceView& d, int first_level, int end_level, int newton, cudaStream_t stream) {
    const SchwarzView& m = d.mas;
    for (int l = std::max(first_level, 1); l < std::min(end_level, m.levels); ++l) {
        if (m.level[l].entries == 0) continue;
        schwarz_coupling_kernel<<<blocks_for(m.level[l].entries, kBlockSize / 32), kBlockSize, 0, stream>>>(d, l, newton);
        WEFT_CUDA_CHECK_LAUNCH("schwarz_coupling_kernel");
    }
}

void launch_schwarz_factor_domains(const DeviceView& d, int newton, cudaStream_t stream) {
    const SchwarzView& m = d.mas;
    std::uint32_t domains = 0;
    for (int l = 0; l < m.levels; ++l) domains += m.level[l].domains;
    if (domains == 0) return;
    schwarz_factor_kernel<<<domains, kBlockSize, 0, stream>>>(d, newton);
    WEFT_CUDA_CHECK_LAUNCH("schwarz_factor_kernel");
}

void launch_schwarz_factor(const DeviceView& d, int newton, cudaStream_t stream) {
    launch_schwarz_couplings(d, 1, d.mas.levels, newton, stream);
    launch_schwarz_factor_domains(d, newton, stream);
}

void launch_schwarz_fine(const DeviceView& d, SchwarzInput in, const int* running, cudaStream_t stream) {
    schwarz_fine_kernel<<<blocks_for(d.mas.level[0].domains, kSchwarzWarpsPerBlock), kBlockSize, 0, stream>>>(d, in, running);
    WEFT_CUDA_CHECK_LAUNCH("schwarz_fine_kernel");
}

void launch_schwarz_coarse(const DeviceView& d, const int* running, cudaStream_t stream) {
    const SchwarzView& m = d.mas;
    for (int l = 1; l < m.levels; ++l) {
        schwarz_coarse_kernel<<<blocks_for(m.level[l].domains, kSchwarzWarpsPerBlock), kBlockSize, 0, stream>>>(d, l, running);
        WEFT_CUDA_CHECK_LAUNCH("schwarz_coarse_kernel");
    }
}

void launch_schwarz_apply(const DeviceView& d, SchwarzInput in, SchwarzOutput out, unsigned long long handle,
                          cudaStream_t stream) {
    // In the CG loop (Update) every kernel does nothing once the loop has stopped.
    // (The flag's device address, computed without touching device memory.)
    const int* running = in == SchwarzInput::Update
                             ? reinterpret_cast<const int*>(reinterpret_cast<const char*>(d.control) + offsetof(PcgControl, running))
                             : nullptr;
    launch_schwarz_fine(d, in, running, stream);
    launch_schwarz_coarse(d, running, stream);
    schwarz_prolong_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d, out, handle);
    WEFT_CUDA_CHECK_LAUNCH("schwarz_prolong_kernel");
}

}  // namespace weft::cuda
