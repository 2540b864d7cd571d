// Single-reduction PCG across the parts of a partitioned system, driven on the devices
// (multi/part_pcg.h).
#include "multi/part_pcg.h"

#include <cub/block/block_reduce.cuh>

#include <algorithm>
#include <cmath>
#include <string>

#include "cuda_check.h"
#include "device_math.cuh"
#include "kernels.h"
#include "multi/peer_access.h"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

/// What a reduction's scalar step does with the two sums.
enum ReductionMode : int {
    kStart = 0,       ///< (rᵀu, bᵀM⁻¹b) of the start: γ, γ_b and the first convergence test
    kFirstAlpha = 1,  ///< (−, wᵀu) of the first product: α = γ/δ
    kIteration = 2,   ///< (γ', δ) of an iteration: the test, then β and α
};

/// Block b's sum of `value` into partials[2·b + k] (CUB's fixed tree order: deterministic).
__device__ void block_partial(double value, double* partials, int k) {
    using Reduce = cub::BlockReduce<double, kBlockSize>;
    __shared__ typename Reduce::TempStorage storage;
    const double sum = Reduce(storage).Sum(value);
    if (threadIdx.x == 0) partials[2 * blockIdx.x + k] = sum;
}

/// The part's two sums of its block partials, in a fixed order, stored into every part's gather
/// buffer at this part's slot (peer stores): targets[q] = part q's buffer + 2·part.
__global__ void share_sums_kernel(const double* partials, unsigned blocks, double* const* targets, unsigned parts,
                                  const PartPcgScalars* scalars, int mode) {
    if (mode == kIteration && scalars->running == 0) return;
    using Reduce = cub::BlockReduce<double, kBlockSize>;
    __shared__ typename Reduce::TempStorage storage;
    double sums[2];
    for (int k = 0; k < 2; ++k) {
        double acc = 0.0;
        for (unsigned b = threadIdx.x; b < blocks; b += blockDim.x) acc += partials[2 * b + k];
        sums[k] = Reduce(storage).Sum(acc);
        __syncthreads();  // storage is reused
    }
    if (threadIdx.x == 0)
        for (unsigned q = 0; q < parts; ++q) {
            targets[q][0] = sums[0];
            targets[q][1] = sums[1];
        }
}

/// Every part the same: the G pairs added in part order, then the loop's decision.
__global__ void scalars_kernel(const double* gathered, unsigned parts, PartPcgScalars* s, int mode) {
    if (mode == kIteration && s->running == 0) return;
    double first = 0.0, second = 0.0;
    for (unsigned p = 0; p < parts; ++p) {
        first += gathered[2 * p];
        second += gathered[2 * p + 1];
    }
    if (mode == kStart) {
        s->gamma = first;
        s->gamma_b = second;
        s->relative = second > 0.0 ? sqrt(fmax(first, 0.0) / second) : 0.0;
        s->converged = !(second > 0.0) || first <= s->tolerance2 * second ? 1 : 0;
        s->running = s->converged ? 0 : 1;
        return;
    }
    if (mode == kFirstAlpha) {
        if (s->running == 0) return;
        if (!(second > 0.0)) {
            s->running = 0;
            return;
        }
        s->alpha = s->gamma / second;
        s->beta = 0.0;
        return;
    }
    ++s->iterations;
    s->relative = sqrt(fmax(first, 0.0) / s->gamma_b);
    if (first <= s->tolerance2 * s->gamma_b) {
        s->converged = 1;
        s->running = 0;
        return;
    }
    const double beta = first / s->gamma;
    const double denominator = second - beta * first / s->alpha;
    if (s->iterations >= s->max_iterations || !(denominator > 0.0)) {  // the cap, or not SPD in float
        s->running = 0;
        return;
    }
    s->beta = beta;
    s->alpha = first / denominator;
    s->gamma = first;
}

__global__ void invert_diagonal_kernel(const float* blocks, const std::uint32_t* diagonal, float* precond, std::uint32_t owned) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= owned) return;
    store_block(precond, i, physics::inverse(load_block(blocks, diagonal[i])));
}

/// r = b − w (w = A·x), u = M⁻¹r, p = s = 0; partials (rᵀu, bᵀM⁻¹b).
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
__global__ void update_kernel(const PartPcgScalars* scalars, float* x, float* r, float* u, const float* w, float* p, float* s,
                              const float* precond, std::uint32_t owned, std::uint32_t local, double* partials) {
    if (scalars->running == 0) return;
    const auto alpha = static_cast<float>(scalars->alpha), beta = static_cast<float>(scalars->beta);
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
__global__ void dot_kernel(const PartPcgScalars* scalars, const float* w, const float* u, std::uint32_t owned,
                           std::uint32_t local, double* partials) {
    if (scalars->running == 0) return;
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double wu = 0.0;
    if (i < owned) wu = static_cast<double>(physics::dot(load3(w, i, local), load3(u, i, local)));
    block_partial(wu, partials, 1);
}

}  // namespace

struct PartPcg::Part {
    const PartMatrix* matrix = nullptr;
    int device = 0;
    cudaStream_t stream = nullptr;
    std::uint32_t owned = 0, local = 0;
    unsigned blocks = 0;
    MemoryLedger ledger;
    DeviceArray<float> r, u, w, p, s, precond;
    DeviceArray<double> partials;
    DeviceArray<double> gather;           // 2 parities × 2 sums × parts, written by every part
    DeviceArray<double*> targets[2];      // per parity: where this part's sums go, one pointer per part
    DeviceArray<PartPcgScalars> scalars;
    PinnedArray<PartPcgScalars> host;
    cudaEvent_t shared = nullptr;
};

PartPcg::PartPcg(std::span<const PartMatrix* const> matrices, HaloExchange& halo, std::span<const cudaStream_t> streams)
    : halo_(halo) {
    const std::size_t parts = halo.parts();
    if (matrices.size() != parts || streams.size() != parts)
        throw Error("PartPcg: " + std::to_string(matrices.size()) + " matrices and " + std::to_string(streams.size()) +
                    " streams for " + std::to_string(parts) + " parts");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    for (std::size_t k = 0; k < parts; ++k) {
        auto part = std::make_unique<Part>();
        part->matrix = matrices[k];
        part->device = matrices[k]->device();
        part->stream = streams[k];
        part->owned = matrices[k]->owned();
        part->local = matrices[k]->local();
        if (part->local != halo.local_count(static_cast<std::uint32_t>(k)))
            throw Error("PartPcg: part " + std::to_string(k) + " has " + std::to_string(part->local) +
                        " local vertices in its matrix and " + std::to_string(halo.local_count(static_cast<std::uint32_t>(k))) +
                        " in the exchange");
        part->blocks = std::max(grid_for(part->owned), 1U);
        WEFT_CUDA_CHECK(cudaSetDevice(part->device));
        const std::size_t n3 = 3 * std::size_t{part->local};
        for (DeviceArray<float>* v : {&part->r, &part->u, &part->w, &part->p, &part->s}) {
            v->allocate(n3, part->ledger, "multi-GPU CG vectors");
            v->zero(part->stream);  // ghost entries stay zero except u's, which only the exchange writes
        }
        part->precond.allocate(9 * std::size_t{std::max(part->owned, 1U)}, part->ledger, "multi-GPU CG preconditioner");
        part->partials.allocate(2 * std::size_t{part->blocks}, part->ledger, "multi-GPU CG partial sums");
        part->partials.zero(part->stream);
        part->gather.allocate(4 * parts, part->ledger, "multi-GPU CG partial sums");
        part->gather.zero(part->stream);
        part->scalars.allocate(1, part->ledger, "multi-GPU CG scalars");
        part->host.allocate(1);
        WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&part->shared, cudaEventDisableTiming));
        part_.push_back(std::move(part));
    }
    // Every part stores its sums into every other part's gather buffer.
    for (std::size_t k = 0; k < parts; ++k)
        for (std::size_t q = 0; q < parts; ++q) enable_peer_access(part_[k]->device, part_[q]->device);
    for (std::size_t k = 0; k < parts; ++k) {
        Part& part = *part_[k];
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        for (int parity = 0; parity < 2; ++parity) {
            std::vector<double*> where(parts);
            for (std::size_t q = 0; q < parts; ++q) where[q] = part_[q]->gather.get() + 2 * parts * parity + 2 * k;
            part.targets[parity].upload(where, part.ledger, "multi-GPU CG partial sums");
        }
        WEFT_CUDA_CHECK(cudaStreamSynchronize(part.stream));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

PartPcg::~PartPcg() {
    if (graph_ != nullptr) cudaGraphExecDestroy(graph_);
    for (auto& part : part_)
        if (part->shared != nullptr) cudaEventDestroy(part->shared);
}

void PartPcg::enqueue_reduction(int parity, int mode) {
    const auto parts = static_cast<unsigned>(part_.size());
    for (auto& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part->device));
        share_sums_kernel<<<1, kBlockSize, 0, part->stream>>>(part->partials.get(), part->blocks, part->targets[parity].get(),
                                                              parts, part->scalars.get(), mode);
        WEFT_CUDA_CHECK_LAUNCH("share_sums_kernel");
        WEFT_CUDA_CHECK(cudaEventRecord(part->shared, part->stream));
    }
    for (std::size_t q = 0; q < part_.size(); ++q) {
        Part& part = *part_[q];
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        for (std::size_t k = 0; k < part_.size(); ++k)
            if (k != q) WEFT_CUDA_CHECK(cudaStreamWaitEvent(part.stream, part_[k]->shared, 0));
        scalars_kernel<<<1, 1, 0, part.stream>>>(part.gather.get() + 2 * parts * parity, parts, part.scalars.get(), mode);
        WEFT_CUDA_CHECK_LAUNCH("scalars_kernel");
    }
}

void PartPcg::enqueue_iteration(std::span<float* const> x, int parity) {
    for (std::size_t k = 0; k < part_.size(); ++k) {
        Part& part = *part_[k];
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        update_kernel<<<part.blocks, kBlockSize, 0, part.stream>>>(part.scalars.get(), x[k], part.r.get(), part.u.get(),
                                                                    part.w.get(), part.p.get(), part.s.get(),
                                                                    part.precond.get(), part.owned, part.local,
                                                                    part.partials.get());
        WEFT_CUDA_CHECK_LAUNCH("update_kernel");
    }
    std::vector<float*> u(part_.size());
    for (std::size_t k = 0; k < part_.size(); ++k) u[k] = part_[k]->u.get();
    halo_.exchange(u);
    for (auto& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part->device));
        part->matrix->multiply(part->u.get(), part->w.get(), 0, part->owned, part->stream);
        dot_kernel<<<part->blocks, kBlockSize, 0, part->stream>>>(part->scalars.get(), part->w.get(), part->u.get(), part->owned,
                                                                   part->local, part->partials.get());
        WEFT_CUDA_CHECK_LAUNCH("dot_kernel");
    }
    enqueue_reduction(parity, kIteration);
}

PartPcgResult PartPcg::solve(std::span<const float* const> b, std::span<float* const> x, double tolerance, int max_iterations,
                             int batch) {
    if (b.size() != part_.size() || x.size() != part_.size())
        throw Error("PartPcg::solve: " + std::to_string(b.size()) + " right-hand sides and " + std::to_string(x.size()) +
                    " solutions for " + std::to_string(part_.size()) + " parts");
    if (batch < 2 || batch % 2 != 0) throw Error("PartPcg::solve: batch " + std::to_string(batch) + " (an even count ≥ 2)");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    PartPcgScalars start;
    start.tolerance2 = tolerance * tolerance;
    start.max_iterations = max_iterations;
    // The start, launched directly: r = b − A·x, u = M⁻¹r (γ, γ_b), then w = A·u (the first α).
    halo_.exchange(x);
    for (std::size_t k = 0; k < part_.size(); ++k) {
        Part& part = *part_[k];
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        *part.host.get() = start;
        WEFT_CUDA_CHECK(cudaMemcpyAsync(part.scalars.get(), part.host.get(), sizeof start, cudaMemcpyHostToDevice, part.stream));
        invert_diagonal_kernel<<<part.blocks, kBlockSize, 0, part.stream>>>(part.matrix->blocks(), part.matrix->diagonal(),
                                                                             part.precond.get(), part.owned);
        WEFT_CUDA_CHECK_LAUNCH("invert_diagonal_kernel");
        part.matrix->multiply(x[k], part.w.get(), 0, part.owned, part.stream);
        start_kernel<<<part.blocks, kBlockSize, 0, part.stream>>>(b[k], part.w.get(), part.precond.get(), part.r.get(),
                                                                   part.u.get(), part.p.get(), part.s.get(), part.owned,
                                                                   part.local, part.partials.get());
        WEFT_CUDA_CHECK_LAUNCH("start_kernel");
    }
    enqueue_reduction(0, kStart);
    std::vector<float*> u(part_.size());
    for (std::size_t k = 0; k < part_.size(); ++k) u[k] = part_[k]->u.get();
    halo_.exchange(u);
    for (auto& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part->device));
        part->matrix->multiply(part->u.get(), part->w.get(), 0, part->owned, part->stream);
        dot_kernel<<<part->blocks, kBlockSize, 0, part->stream>>>(part->scalars.get(), part->w.get(), part->u.get(), part->owned,
                                                                   part->local, part->partials.get());
        WEFT_CUDA_CHECK_LAUNCH("dot_kernel");
    }
    enqueue_reduction(1, kFirstAlpha);

    // The batches: captured once (part 0's stream forks to the others and joins them), replayed
    // until the scalars say stop.
    Part& origin = *part_[0];
    const std::vector<float*> xs(x.begin(), x.end());
    if (graph_ == nullptr || graph_x_ != xs || graph_batch_ != batch) {
        if (graph_ != nullptr) WEFT_CUDA_CHECK(cudaGraphExecDestroy(graph_));
        graph_ = nullptr;
        std::vector<cudaEvent_t> fork(part_.size());
        for (std::size_t k = 0; k < part_.size(); ++k) {
            WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->device));
            WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&fork[k], cudaEventDisableTiming));
        }
        WEFT_CUDA_CHECK(cudaSetDevice(origin.device));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(origin.stream));
        WEFT_CUDA_CHECK(cudaStreamBeginCapture(origin.stream, cudaStreamCaptureModeGlobal));
        WEFT_CUDA_CHECK(cudaEventRecord(fork[0], origin.stream));
        for (std::size_t k = 1; k < part_.size(); ++k) {
            WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->device));
            WEFT_CUDA_CHECK(cudaStreamWaitEvent(part_[k]->stream, fork[0], 0));
        }
        for (int it = 0; it < batch; ++it) enqueue_iteration(x, it % 2);
        for (std::size_t k = 1; k < part_.size(); ++k) {
            WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->device));
            WEFT_CUDA_CHECK(cudaEventRecord(fork[k], part_[k]->stream));
            WEFT_CUDA_CHECK(cudaSetDevice(origin.device));
            WEFT_CUDA_CHECK(cudaStreamWaitEvent(origin.stream, fork[k], 0));
        }
        WEFT_CUDA_CHECK(cudaSetDevice(origin.device));
        cudaGraph_t graph = nullptr;
        WEFT_CUDA_CHECK(cudaStreamEndCapture(origin.stream, &graph));
        WEFT_CUDA_CHECK(cudaGraphInstantiate(&graph_, graph, 0));
        WEFT_CUDA_CHECK(cudaGraphDestroy(graph));
        for (std::size_t k = 0; k < part_.size(); ++k) {
            WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->device));
            WEFT_CUDA_CHECK(cudaEventDestroy(fork[k]));
        }
        graph_x_ = xs;
        graph_batch_ = batch;
    }
    // The graph starts on the origin's stream: the other parts' start work must be done first.
    for (std::size_t k = 1; k < part_.size(); ++k) {
        WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->device));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(part_[k]->stream));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(origin.device));
    const auto read_scalars = [&] {
        WEFT_CUDA_CHECK(cudaMemcpyAsync(origin.host.get(), origin.scalars.get(), sizeof(PartPcgScalars), cudaMemcpyDeviceToHost,
                                        origin.stream));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(origin.stream));
        return *origin.host.get();
    };
    PartPcgScalars s = read_scalars();
    while (s.running != 0) {
        WEFT_CUDA_CHECK(cudaGraphLaunch(graph_, origin.stream));
        s = read_scalars();
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
    PartPcgResult result;
    result.iterations = s.iterations;
    result.relative_residual = s.relative;
    result.converged = s.converged != 0;
    return result;
}

}  // namespace weft::cuda::multi
