// Single-reduction PCG across the parts of a partitioned system (multi/part_pcg.h).
#include "multi/part_pcg.h"

#include <cub/block/block_reduce.cuh>

#include <cmath>
#include <string>

#include "cuda_check.h"
#include "device_math.cuh"
#include "kernels.h"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

/// Block b's sum of `value` into partials[2·b + k] (CUB's fixed tree order: deterministic).
__device__ void block_partial(double value, double* partials, int k) {
    using Reduce = cub::BlockReduce<double, kBlockSize>;
    __shared__ typename Reduce::TempStorage storage;
    const double sum = Reduce(storage).Sum(value);
    if (threadIdx.x == 0) partials[2 * blockIdx.x + k] = sum;
}

/// sums[k] = Σ_b partials[2·b + k] for k = 0, 1, in a fixed order (one block).
__global__ void finish_sums_kernel(const double* partials, unsigned blocks, double* sums) {
    using Reduce = cub::BlockReduce<double, kBlockSize>;
    __shared__ typename Reduce::TempStorage storage;
    for (int k = 0; k < 2; ++k) {
        double acc = 0.0;
        for (unsigned b = threadIdx.x; b < blocks; b += blockDim.x) acc += partials[2 * b + k];
        const double total = Reduce(storage).Sum(acc);
        if (threadIdx.x == 0) sums[k] = total;
        __syncthreads();  // storage is reused
    }
}

__global__ void invert_diagonal_kernel(const float* blocks, const std::uint32_t* diagonal, float* precond, std::uint32_t owned) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= owned) return;
    store_block(precond, i, physics::inverse(load_block(blocks, diagonal[i])));
}

/// r = b − w (w = A·x), u = M⁻¹r; partials: (rᵀu, bᵀM⁻¹b).
__global__ void start_kernel(const float* b, const float* w, const float* precond, float* r, float* u, float* p, float* s,
                             std::uint32_t owned, std::uint32_t local, double* partials) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double ru = 0.0, bb = 0.0;
    if (i < owned) {
        const M3 P = load_block(precond, i);
        const V3 bi = load3(b, i, local);
        const V3 ri = bi - load3(w, i, local);
        const V3 ui = P * ri;
        store3(r, i, local, ri);
        store3(u, i, local, ui);
        store3(p, i, local, V3{});
        store3(s, i, local, V3{});
        ru = static_cast<double>(physics::dot(ri, ui));
        bb = static_cast<double>(physics::dot(bi, P * bi));
    }
    block_partial(ru, partials, 0);
    __syncthreads();
    block_partial(bb, partials, 1);
}

/// p ← u + βp, s ← w + βs, x ← x + αp, r ← r − αs, u ← M⁻¹r; partial rᵀu into slot 0.
__global__ void update_kernel(float alpha, float beta, float* x, float* r, float* u, const float* w, float* p, float* s,
                              const float* precond, std::uint32_t owned, std::uint32_t local, double* partials) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double ru = 0.0;
    if (i < owned) {
        const V3 pi = load3(u, i, local) + beta * load3(p, i, local);
        const V3 si = load3(w, i, local) + beta * load3(s, i, local);
        store3(p, i, local, pi);
        store3(s, i, local, si);
        store3(x, i, local, load3(x, i, local) + alpha * pi);
        const V3 ri = load3(r, i, local) - alpha * si;
        const V3 ui = load_block(precond, i) * ri;
        store3(r, i, local, ri);
        store3(u, i, local, ui);
        ru = static_cast<double>(physics::dot(ri, ui));
    }
    block_partial(ru, partials, 0);
}

/// Partial wᵀu into slot 1.
__global__ void dot_kernel(const float* w, const float* u, std::uint32_t owned, std::uint32_t local, double* partials) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double wu = 0.0;
    if (i < owned) wu = static_cast<double>(physics::dot(load3(w, i, local), load3(u, i, local)));
    block_partial(wu, partials, 1);
}

}  // namespace

struct PartPcg::Part {
    const PartMatrix* matrix = nullptr;
    cudaStream_t stream = nullptr;
    std::uint32_t owned = 0, local = 0;
    unsigned blocks = 0;
    MemoryLedger ledger;
    DeviceArray<float> r, u, w, p, s, precond;
    DeviceArray<double> partials, sums;
    PinnedArray<double> host;
};

PartPcg::PartPcg(std::span<const PartMatrix* const> matrices, HaloExchange& halo, std::span<const cudaStream_t> streams)
    : halo_(halo) {
    if (matrices.size() != halo.parts() || streams.size() != halo.parts())
        throw Error("PartPcg: " + std::to_string(matrices.size()) + " matrices and " + std::to_string(streams.size()) +
                    " streams for " + std::to_string(halo.parts()) + " parts");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    for (std::size_t k = 0; k < matrices.size(); ++k) {
        auto part = std::make_unique<Part>();
        part->matrix = matrices[k];
        part->stream = streams[k];
        part->owned = matrices[k]->owned();
        part->local = matrices[k]->local();
        if (part->local != halo.local_count(static_cast<std::uint32_t>(k)))
            throw Error("PartPcg: part " + std::to_string(k) + " has " + std::to_string(part->local) +
                        " local vertices in its matrix and " + std::to_string(halo.local_count(static_cast<std::uint32_t>(k))) +
                        " in the exchange");
        part->blocks = grid_for(part->owned);
        WEFT_CUDA_CHECK(cudaSetDevice(matrices[k]->device()));
        const std::size_t n3 = 3 * std::size_t{part->local};
        for (DeviceArray<float>* v : {&part->r, &part->u, &part->w, &part->p, &part->s}) {
            v->allocate(n3, part->ledger, "multi-GPU CG vectors");
            v->zero(part->stream);  // ghost entries stay zero except u's, which only the exchange writes
        }
        part->precond.allocate(9 * std::size_t{part->owned}, part->ledger, "multi-GPU CG preconditioner");
        part->partials.allocate(2 * std::size_t{std::max(part->blocks, 1U)}, part->ledger, "multi-GPU CG partial sums");
        part->sums.allocate(2, part->ledger, "multi-GPU CG partial sums");
        part->host.allocate(2);
        part_.push_back(std::move(part));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

PartPcg::~PartPcg() = default;

void PartPcg::reduce(double& first, double& second) {
    for (const auto& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part->matrix->device()));
        if (part->owned == 0) continue;
        finish_sums_kernel<<<1, kBlockSize, 0, part->stream>>>(part->partials.get(), part->blocks, part->sums.get());
        WEFT_CUDA_CHECK_LAUNCH("finish_sums_kernel");
        WEFT_CUDA_CHECK(cudaMemcpyAsync(part->host.get(), part->sums.get(), 2 * sizeof(double), cudaMemcpyDeviceToHost, part->stream));
    }
    first = second = 0.0;
    for (const auto& part : part_) {  // part order: the same sum on every run
        if (part->owned == 0) continue;
        WEFT_CUDA_CHECK(cudaSetDevice(part->matrix->device()));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(part->stream));
        first += part->host[0];
        second += part->host[1];
    }
}

PartPcgResult PartPcg::solve(std::span<const float* const> b, std::span<float* const> x, double tolerance, int max_iterations) {
    if (b.size() != part_.size() || x.size() != part_.size())
        throw Error("PartPcg::solve: " + std::to_string(b.size()) + " right-hand sides and " + std::to_string(x.size()) +
                    " solutions for " + std::to_string(part_.size()) + " parts");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    const auto for_parts = [&](auto body) {
        for (std::size_t k = 0; k < part_.size(); ++k) {
            Part& part = *part_[k];
            WEFT_CUDA_CHECK(cudaSetDevice(part.matrix->device()));
            if (part.owned > 0) body(k, part);
        }
    };
    std::vector<float*> u(part_.size());
    for (std::size_t k = 0; k < part_.size(); ++k) u[k] = part_[k]->u.get();

    // r = b − A·x, u = M⁻¹r, then w = A·u: γ = rᵀu and bᵀM⁻¹b, then δ = wᵀu.
    halo_.exchange(x);
    for_parts([&](std::size_t k, Part& part) {
        invert_diagonal_kernel<<<part.blocks, kBlockSize, 0, part.stream>>>(part.matrix->blocks(), part.matrix->diagonal(),
                                                                             part.precond.get(), part.owned);
        WEFT_CUDA_CHECK_LAUNCH("invert_diagonal_kernel");
        part.matrix->multiply(x[k], part.w.get(), 0, part.owned, part.stream);
        start_kernel<<<part.blocks, kBlockSize, 0, part.stream>>>(b[k], part.w.get(), part.precond.get(), part.r.get(),
                                                                   part.u.get(), part.p.get(), part.s.get(), part.owned,
                                                                   part.local, part.partials.get());
        WEFT_CUDA_CHECK_LAUNCH("start_kernel");
    });
    double gamma = 0.0, gamma_b = 0.0;
    reduce(gamma, gamma_b);
    PartPcgResult result;
    const auto relative = [&](double g) { return gamma_b > 0.0 ? std::sqrt(std::max(g, 0.0) / gamma_b) : 0.0; };
    result.relative_residual = relative(gamma);
    if (gamma_b <= 0.0 || result.relative_residual <= tolerance) {
        result.converged = true;
        WEFT_CUDA_CHECK(cudaSetDevice(previous));
        return result;
    }
    // One exchange (u's ghosts), one product and one reduction per iteration.
    const auto product_and_dot = [&](double& ru, double& wu) {
        halo_.exchange(u);
        for_parts([&](std::size_t, Part& part) {
            part.matrix->multiply(part.u.get(), part.w.get(), 0, part.owned, part.stream);
            dot_kernel<<<part.blocks, kBlockSize, 0, part.stream>>>(part.w.get(), part.u.get(), part.owned, part.local,
                                                                     part.partials.get());
            WEFT_CUDA_CHECK_LAUNCH("dot_kernel");
        });
        reduce(ru, wu);
    };
    double ignored = 0.0, delta = 0.0;
    product_and_dot(ignored, delta);  // slot 0 still holds the start's rᵀu partials: γ as reduced above
    double alpha = delta != 0.0 ? gamma / delta : 0.0, beta = 0.0;
    while (result.iterations < max_iterations) {
        for_parts([&](std::size_t k, Part& part) {
            update_kernel<<<part.blocks, kBlockSize, 0, part.stream>>>(
                static_cast<float>(alpha), static_cast<float>(beta), x[k], part.r.get(), part.u.get(), part.w.get(),
                part.p.get(), part.s.get(), part.precond.get(), part.owned, part.local, part.partials.get());
            WEFT_CUDA_CHECK_LAUNCH("update_kernel");
        });
        ++result.iterations;
        double gamma_next = 0.0;
        product_and_dot(gamma_next, delta);
        result.relative_residual = relative(gamma_next);
        if (result.relative_residual <= tolerance) {
            result.converged = true;
            break;
        }
        beta = gamma_next / gamma;
        const double denominator = delta - beta * gamma_next / alpha;
        if (!(denominator > 0.0)) break;  // A or M not SPD in float: stop, not converged
        alpha = gamma_next / denominator;
        gamma = gamma_next;
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
    return result;
}

}  // namespace weft::cuda::multi
