// Single-reduction PCG across the parts of a partitioned system, driven on the devices
// (multi/part_pcg.h).
#include "multi/part_pcg.h"

#include <algorithm>
#include <cstddef>
#include <cmath>
#include <cstdlib>
#include <string>

#include "cuda_check.h"
#include "device_math.cuh"
#include "kernels.h"
#include "loop_clock.h"
#include "multi/all_gather.h"
#include "multi/peer_access.h"
#include "contact_terms.cuh"
#include "multi/contact_mirror.h"
#include "multi/part_pcg_loop.h"
#include "multi/part_pcg_terms.cuh"
#include "schwarz_apply.cuh"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

/// Block b's sum of `value` into partials[2·b + k].
__device__ void block_partial(double value, double* partials, int k) {
    __shared__ PartReduce::TempStorage storage;
    part_block_partial(value, partials, blockIdx.x, k, storage);
}

/// The part's two sums of its block partials, stored into every part's gather buffer at this part's
/// slot (peer stores): targets[q] = part q's buffer + 2·part.
__global__ void share_sums_kernel(const double* partials, unsigned blocks, double* const* targets, unsigned parts,
                                  const PartPcgScalars* scalars, int mode) {
    if (mode == kIteration && scalars->running == 0) return;
    __shared__ PartReduce::TempStorage storage;
    double sums[2];
    part_sum_partials(partials, blocks, sums, storage);
    if (threadIdx.x == 0)
        for (unsigned q = 0; q < parts; ++q) {
            targets[q][0] = sums[0];
            targets[q][1] = sums[1];
        }
}

/// Every part the same: the G pairs added in part order, then the loop's decision.
__global__ void scalars_kernel(const double* gathered, unsigned parts, PartPcgScalars* s, int mode) {
    if (mode == kIteration && s->running == 0) return;
    PartPcgScalars next = *s;
    part_advance_scalars(gathered, parts, next, mode);
    *s = next;
}

/// The device address of the loop's running flag (computed without touching device memory).
const int* check_flag(const PartPcgScalars* scalars) {
    return reinterpret_cast<const int*>(reinterpret_cast<const char*>(scalars) + offsetof(PartPcgScalars, running));
}

__global__ void invert_diagonal_kernel(PartSystem a, float* precond) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= a.owned) return;
    const M3 inverse = physics::inverse(load_block(a.blocks, a.diagonal[i]));
    for (int e = 0; e < 9; ++e) precond[e * a.local + i] = inverse.m[e / 3][e % 3];
}

/// w = filter(A·x) over the owned rows (part_product_row); with `dot_with`, the partial
/// wᵀ·dot_with into slot 1. `check`: nothing once the loop has stopped.
__global__ void product_kernel(PartSystem a, const float* x, float* w, const float* dot_with, const PartPcgScalars* scalars,
                               int check, double* partials) {
    if (check != 0 && scalars->running == 0) return;
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double value = 0.0;
    if (i < a.owned) {
        const V3 acc = part_product_row(a, i, x);
        store3(w, i, a.local, acc);
        if (dot_with != nullptr) value = static_cast<double>(physics::dot(acc, load3(dot_with, i, a.local)));
    }
    if (dot_with != nullptr) block_partial(value, partials, 1);
}

/// The pair pass of the contact product over this part's contacts (part_pair_product).
__global__ void pair_pass_kernel(ContactView c, const float* x, std::uint32_t local, const float* copy, const PartPcgScalars* scalars,
                                 int check) {
    if (check != 0 && scalars->running == 0) return;
    const std::uint32_t m = contact_count(c);
    for (std::uint32_t p = blockIdx.x * blockDim.x + threadIdx.x; p < m; p += gridDim.x * blockDim.x)
        part_pair_product(c, p, x, local, copy);
}

/// r = filter(b − w) (w = A·x), u = M⁻¹r, p = s = 0; partials (rᵀu, bᵀM⁻¹b over the free rows).
/// `jacobi`: with block-Jacobi, u = M⁻¹r and both partials here; otherwise (Schwarz) r only, the
/// apply follows.
__global__ void start_kernel(PartSystem a, const float* precond, int jacobi, const float* b, const float* w, float* r, float* u,
                             float* p, float* s, double* partials) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double ru = 0.0, bb = 0.0;
    if (i < a.owned) {
        V3 ri{}, ui{};
        if (!part_is_fixed(a, i)) {
            const V3 bi = load3(b, i, a.local);
            ri = bi - load3(w, i, a.local);
            if (jacobi != 0) {
                const M3 P = part_load_precond(precond, i, a.local);
                ui = P * ri;
                ru = static_cast<double>(physics::dot(ri, ui));
                bb = static_cast<double>(physics::dot(bi, P * bi));
            }
        }
        store3(r, i, a.local, ri);
        if (jacobi != 0) store3(u, i, a.local, ui);
        store3(p, i, a.local, V3{});
        store3(s, i, a.local, V3{});
    }
    if (jacobi == 0) return;
    block_partial(ru, partials, 0);
    block_partial(bb, partials, 1);
}

/// u = z = M⁻¹r from the Schwarz levels (every level solved, schwarz_apply.cuh), with the partial
/// rᵀz into slot `slot`. `check`: nothing once the loop has stopped.
__global__ void prolong_kernel(DeviceView v, std::uint32_t owned, float* u, const PartPcgScalars* scalars, int check,
                               double* partials, int slot) {
    if (check != 0 && scalars->running == 0) return;
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double value = 0.0;
    if (i < owned) {
        const V3 z = schwarz_correction(v, i);
        store3(u, i, v.n, z);
        value = static_cast<double>(physics::dot(load3(v.r, i, v.n), z));
    }
    block_partial(value, partials, slot);
}

/// The update (part_update_row); partial rᵀu into slot 0 with block-Jacobi.
__global__ void update_kernel(PartSystem a, const float* precond, int jacobi, const PartPcgScalars* scalars, float* x, float* r,
                              float* u, const float* w, float* p, float* s, double* partials) {
    if (scalars->running == 0) return;
    const auto alpha = static_cast<float>(scalars->alpha), beta = static_cast<float>(scalars->beta);
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double ru = 0.0;
    if (i < a.owned) ru = part_update_row(a, i, precond, jacobi != 0, alpha, beta, x, r, u, w, p, s);
    if (jacobi != 0) block_partial(ru, partials, 0);
}

}  // namespace

struct PartPcg::Part {
    PartSystem system;
    DeviceView schwarz;                   // with the Schwarz preconditioner: the solver's view, r = this part's r
    unsigned blocks = 0;
    MemoryLedger ledger;
    DeviceArray<float> r, u, w, p, s, own_precond;
    const float* precond = nullptr;       // the system's, or own_precond
    DeviceArray<double> partials;
    DeviceArray<double> gather;           // 2 parities × 2 sums × parts, written by every part
    DeviceArray<double*> targets[2];      // per parity: where this part's sums go, one pointer per part
    DeviceArray<PartPcgScalars> scalars;
    PinnedArray<PartPcgScalars> host;
    DeviceArray<unsigned> flags;          // the one-launch loop's meetings (PartLoopView::flags_of)
    DeviceArray<long long> clock;         // WEFT_CUDA_PCG_CLOCK=1: the loop's phase cycles (PartLoopView::clock)
    PinnedArray<unsigned> host_flags;
    cudaEvent_t shared = nullptr;
};

PartPcg::PartPcg(std::span<const PartSystem> systems, HaloExchange& halo) : halo_(halo) {
    clock_ = loop_clock_requested();
    const std::size_t parts = halo.parts();
    if (systems.size() != parts)
        throw Error("PartPcg: " + std::to_string(systems.size()) + " systems for " + std::to_string(parts) + " parts");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    for (std::size_t k = 0; k < parts; ++k) {
        auto part = std::make_unique<Part>();
        part->system = systems[k];
        const PartSystem& a = part->system;
        if (a.local != halo.local_count(static_cast<std::uint32_t>(k)) || a.owned > a.local)
            throw Error("PartPcg: part " + std::to_string(k) + " has " + std::to_string(a.owned) + " owned of " +
                        std::to_string(a.local) + " local vertices in its system and " +
                        std::to_string(halo.local_count(static_cast<std::uint32_t>(k))) + " in the exchange");
        part->blocks = std::max(grid_for(a.owned), 1U);
        WEFT_CUDA_CHECK(cudaSetDevice(a.device));
        const std::size_t n3 = 3 * std::size_t{a.local};
        for (DeviceArray<float>* v : {&part->r, &part->u, &part->w, &part->p, &part->s}) {
            v->allocate(n3, part->ledger, "multi-GPU CG vectors");
            v->zero(a.stream);  // ghost entries stay zero except u's, which only the exchange writes
        }
        if (a.precond == nullptr) {
            part->own_precond.allocate(9 * std::size_t{std::max(a.local, 1U)}, part->ledger, "multi-GPU CG preconditioner");
            part->precond = part->own_precond.get();
        } else {
            part->precond = a.precond;
        }
        if (a.schwarz != nullptr) {
            part->schwarz = *a.schwarz;
            part->schwarz.r = part->r.get();
        }
        part->partials.allocate(2 * std::size_t{part->blocks}, part->ledger, "multi-GPU CG partial sums");
        part->partials.zero(a.stream);
        part->gather.allocate(4 * parts, part->ledger, "multi-GPU CG partial sums");
        part->gather.zero(a.stream);
        part->scalars.allocate(1, part->ledger, "multi-GPU CG scalars");
        part->host.allocate(1);
        part->flags.allocate(parts + 2, part->ledger, "multi-GPU CG partial sums");
        part->host_flags.allocate(parts + 2);
        if (clock_) {
            part->clock.allocate(kLoopClockEntries, part->ledger, "multi-GPU CG clock");
            part->clock.zero(a.stream);
        }
        WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&part->shared, cudaEventDisableTiming));
        part_.push_back(std::move(part));
    }
    const std::size_t with_schwarz = static_cast<std::size_t>(
        std::count_if(systems.begin(), systems.end(), [](const PartSystem& a) { return a.schwarz != nullptr; }));
    if (with_schwarz != 0 && with_schwarz != parts)
        throw Error("PartPcg: " + std::to_string(with_schwarz) + " of " + std::to_string(parts) +
                    " parts with the Schwarz preconditioner (all or none)");
    schwarz_ = with_schwarz == parts;
    if (schwarz_) {
        std::vector<int> devices;
        std::vector<cudaStream_t> streams;
        for (const auto& part : part_) {
            devices.push_back(part->system.device);
            streams.push_back(part->system.stream);
        }
        level1_ = std::make_unique<AllGather>(devices, streams);
    }
    std::vector<int> devices;
    for (const auto& part : part_) devices.push_back(part->system.device);
    std::sort(devices.begin(), devices.end());
    one_launch_possible_ = parts > 1 && parts <= kLoopMaxParts && std::adjacent_find(devices.begin(), devices.end()) == devices.end();
    // Every part stores its sums into every other part's gather buffer.
    for (std::size_t k = 0; k < parts; ++k)
        for (std::size_t q = 0; q < parts; ++q) enable_peer_access(part_[k]->system.device, part_[q]->system.device);
    for (std::size_t k = 0; k < parts; ++k) {
        Part& part = *part_[k];
        WEFT_CUDA_CHECK(cudaSetDevice(part.system.device));
        for (int parity = 0; parity < 2; ++parity) {
            std::vector<double*> where(parts);
            for (std::size_t q = 0; q < parts; ++q) where[q] = part_[q]->gather.get() + 2 * parts * parity + 2 * k;
            part.targets[parity].upload(where, part.ledger, "multi-GPU CG partial sums");
        }
        WEFT_CUDA_CHECK(cudaStreamSynchronize(part.system.stream));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

void PartPcg::print_clock() const {
    for (std::size_t p = 0; p < part_.size(); ++p)
        print_loop_clock("part " + std::to_string(p), part_[p]->clock.get(), part_[p]->system.device);
}

std::size_t PartPcg::memory_bytes(std::size_t p) const { return part_.at(p)->ledger.total(); }

PartPcg::~PartPcg() {
    if (clock_) print_clock();
    if (graph_ != nullptr) cudaGraphExecDestroy(graph_);
    for (auto& part : part_)
        if (part->shared != nullptr) cudaEventDestroy(part->shared);
}

void PartPcg::enqueue_reduction(int parity, int mode) {
    const auto parts = static_cast<unsigned>(part_.size());
    for (auto& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part->system.device));
        share_sums_kernel<<<1, kBlockSize, 0, part->system.stream>>>(part->partials.get(), part->blocks,
                                                                     part->targets[parity].get(), parts, part->scalars.get(), mode);
        WEFT_CUDA_CHECK_LAUNCH("share_sums_kernel");
        WEFT_CUDA_CHECK(cudaEventRecord(part->shared, part->system.stream));
    }
    for (std::size_t q = 0; q < part_.size(); ++q) {
        Part& part = *part_[q];
        WEFT_CUDA_CHECK(cudaSetDevice(part.system.device));
        for (std::size_t k = 0; k < part_.size(); ++k)
            if (k != q) WEFT_CUDA_CHECK(cudaStreamWaitEvent(part.system.stream, part_[k]->shared, 0));
        scalars_kernel<<<1, 1, 0, part.system.stream>>>(part.gather.get() + 2 * parts * parity, parts, part.scalars.get(), mode);
        WEFT_CUDA_CHECK_LAUNCH("scalars_kernel");
    }
}

void PartPcg::enqueue_schwarz(SchwarzInput in, int slot, int check) {
    // Level 0 and the restriction on every part; level 1 gathered; the coarse levels on every part
    // (each GPU all of them, the same bits); each part's owned rows of u with the partial rᵀu.
    const auto running = [](const Part& part) {
        return check_flag(part.scalars.get());
    };
    std::vector<float*> values;
    std::vector<std::size_t> begin, end;
    for (auto& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part->system.device));
        launch_schwarz_fine(part->schwarz, in, check != 0 ? running(*part) : nullptr, part->system.stream);
        values.push_back(part->schwarz.mas.level[1].values);
        begin.push_back(part->system.level1_begin);
        end.push_back(part->system.level1_end);
    }
    if (part_.front()->schwarz.mas.levels > 1) level1_->enqueue(values, begin, end);
    for (auto& part : part_) {
        const PartSystem& a = part->system;
        WEFT_CUDA_CHECK(cudaSetDevice(a.device));
        launch_schwarz_coarse(part->schwarz, check != 0 ? running(*part) : nullptr, a.stream);
        prolong_kernel<<<part->blocks, kBlockSize, 0, a.stream>>>(part->schwarz, a.owned, part->u.get(), part->scalars.get(), check,
                                                                  part->partials.get(), slot);
        WEFT_CUDA_CHECK_LAUNCH("prolong_kernel");
    }
}

void PartPcg::enqueue_contacts(std::span<float* const> x, int check) {
    if (contacts_ == nullptr) return;
    std::vector<const float*> from(x.begin(), x.end());
    std::vector<std::uint32_t> stride;
    for (auto& part : part_) stride.push_back(part->system.local);
    contacts_->push_across(ContactMirror::kCg, from, stride);
    for (std::size_t k = 0; k < part_.size(); ++k) {
        const PartSystem& a = part_[k]->system;
        if (a.contacts.capacity == 0) continue;
        WEFT_CUDA_CHECK(cudaSetDevice(a.device));
        const unsigned blocks = std::max(1u, std::min(1024u, grid_for(a.contacts.capacity)));
        pair_pass_kernel<<<blocks, kBlockSize, 0, a.stream>>>(a.contacts, x[k], a.local, contacts_->copy(k, ContactMirror::kCg),
                                                              part_[k]->scalars.get(), check);
        WEFT_CUDA_CHECK_LAUNCH("pair_pass_kernel");
        launch_contact_row_sums(a.contacts, a.owned, check != 0 ? check_flag(part_[k]->scalars.get()) : nullptr, a.stream);
    }
}

void PartPcg::enqueue_product(int check) {
    std::vector<float*> u(part_.size());
    for (std::size_t k = 0; k < part_.size(); ++k) u[k] = part_[k]->u.get();
    halo_.exchange(u);
    enqueue_contacts(u, check);
    for (auto& part : part_) {
        const PartSystem& a = part->system;
        WEFT_CUDA_CHECK(cudaSetDevice(a.device));
        product_kernel<<<part->blocks, kBlockSize, 0, a.stream>>>(a, part->u.get(), part->w.get(), part->u.get(),
                                                                  part->scalars.get(), check, part->partials.get());
        WEFT_CUDA_CHECK_LAUNCH("product_kernel");
    }
}

void PartPcg::enqueue_iteration(std::span<float* const> x, int parity) {
    for (std::size_t k = 0; k < part_.size(); ++k) {
        Part& part = *part_[k];
        const PartSystem& a = part.system;
        WEFT_CUDA_CHECK(cudaSetDevice(a.device));
        update_kernel<<<part.blocks, kBlockSize, 0, a.stream>>>(a, part.precond, schwarz_ ? 0 : 1, part.scalars.get(), x[k],
                                                                part.r.get(), part.u.get(), part.w.get(), part.p.get(),
                                                                part.s.get(), part.partials.get());
        WEFT_CUDA_CHECK_LAUNCH("update_kernel");
    }
    if (schwarz_) enqueue_schwarz(SchwarzInput::Residual, 0, 1);
    enqueue_product(1);
    enqueue_reduction(parity, kIteration);
}

PartPcgScalars PartPcg::run_one_launch(std::span<float* const> x) {
    // A fault on one GPU must not hang the others: a part waits this long for another at a meeting.
    constexpr unsigned long long kMeetingTimeoutNs = 20'000'000'000ULL;
    const auto parts = static_cast<unsigned>(part_.size());
    std::vector<PartLoopView> views(parts);
    for (unsigned k = 0; k < parts; ++k) {
        const Part& part = *part_[k];
        PartLoopView& v = views[k];
        v.a = part.system;
        v.a.schwarz = nullptr;
        if (schwarz_) {
            v.schwarz = part.schwarz;
            v.use_schwarz = 1;
            v.level1_begin = static_cast<std::uint32_t>(part.system.level1_begin);
            v.level1_end = static_cast<std::uint32_t>(part.system.level1_end);
            for (unsigned q = 0; q < parts; ++q)
                if (q != k && part.schwarz.mas.levels > 1) v.level1_to[q] = part_[q]->schwarz.mas.level[1].values;
        }
        v.precond = part.precond;
        v.x = x[k];
        v.r = part.r.get();
        v.u = part.u.get();
        v.w = part.w.get();
        v.p = part.p.get();
        v.s = part.s.get();
        v.partials = part.partials.get();
        v.row_blocks = part.blocks;
        v.scalars = part.scalars.get();
        v.part = k;
        v.parts = parts;
        for (const HaloExchange::Route& route : halo_.routes(k)) {
            const Part& to = *part_[route.to_part];
            v.halo[v.halo_routes++] = {route.send, route.count, to.u.get(), to.system.local, route.to_first};
        }
        if (contacts_ != nullptr) {
            v.across = contacts_->across_rows(k);
            v.global = contacts_->global_ids(k);
            for (unsigned q = 0; q < parts; ++q)
                if (q != k) v.mirror_to[v.mirror_targets++] = contacts_->copy(q, ContactMirror::kCg);
            v.whole = contacts_->whole();
            v.mirror_copy = contacts_->copy(k, ContactMirror::kCg);
        }
        for (unsigned q = 0; q < parts; ++q) {
            v.gather_of[q] = part_[q]->gather.get();
            v.flags_of[q] = part_[q]->flags.get();
        }
        v.timeout_ns = kMeetingTimeoutNs;
        v.clock = clock_ ? part.clock.get() : nullptr;
    }
    // Every part's start is done and its flags are zero before any loop runs: a loop that began
    // early could meet a part still in its start, or have its arrival zeroed.
    for (auto& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part->system.device));
        part->flags.zero(part->system.stream);
    }
    for (auto& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part->system.device));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(part->system.stream));
    }
    for (unsigned k = 0; k < parts; ++k) {
        const PartSystem& a = part_[k]->system;
        WEFT_CUDA_CHECK(cudaSetDevice(a.device));
        const int grid = part_pcg_loop_grid(views[k], a.device);
        if (grid <= 0) throw Error("PartPcg: GPU " + std::to_string(a.device) + " cannot launch the one-launch CG loop cooperatively");
        launch_part_pcg_loop(views[k], grid, a.stream);
    }
    for (auto& part : part_) {
        const PartSystem& a = part->system;
        WEFT_CUDA_CHECK(cudaSetDevice(a.device));
        WEFT_CUDA_CHECK(cudaMemcpyAsync(part->host.get(), part->scalars.get(), sizeof(PartPcgScalars), cudaMemcpyDeviceToHost, a.stream));
        WEFT_CUDA_CHECK(cudaMemcpyAsync(part->host_flags.get(), part->flags.get(), (parts + 2) * sizeof(unsigned),
                                        cudaMemcpyDeviceToHost, a.stream));
    }
    for (auto& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part->system.device));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(part->system.stream));
    }
    for (unsigned k = 0; k < parts; ++k) {
        const unsigned stopped = part_[k]->host_flags.get()[parts + 1];
        if (stopped != 0)
            throw Error("multi-GPU CG: part " + std::to_string(k) + " (GPU " + std::to_string(part_[k]->system.device) +
                        ") stopped waiting for part " + std::to_string(stopped - 1) + " after " +
                        std::to_string(kMeetingTimeoutNs / 1'000'000'000ULL) + " s (that GPU faulted or hangs)");
        if (part_[k]->host.get()->iterations != part_[0]->host.get()->iterations)
            throw Error("multi-GPU CG: part " + std::to_string(k) + " stopped after " +
                        std::to_string(part_[k]->host.get()->iterations) + " iterations, part 0 after " +
                        std::to_string(part_[0]->host.get()->iterations) + " (the parts' scalars disagree)");
    }
    return *part_[0]->host.get();
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
    start.energy_floor = energy_floor_;
    // The start, launched directly: r = filter(b − A·x), u = M⁻¹r (γ and the reference), then
    // w = A·u (the first α). With Schwarz, bᵀM⁻¹b comes from an apply to b first (as on one GPU).
    if (schwarz_) {
        for (std::size_t k = 0; k < part_.size(); ++k) part_[k]->schwarz.b = const_cast<float*>(b[k]);
        enqueue_schwarz(SchwarzInput::RightHandSide, 1, 0);
    }
    halo_.exchange(x);
    enqueue_contacts(x, 0);
    for (std::size_t k = 0; k < part_.size(); ++k) {
        Part& part = *part_[k];
        const PartSystem& a = part.system;
        WEFT_CUDA_CHECK(cudaSetDevice(a.device));
        *part.host.get() = start;
        WEFT_CUDA_CHECK(cudaMemcpyAsync(part.scalars.get(), part.host.get(), sizeof start, cudaMemcpyHostToDevice, a.stream));
        if (a.precond == nullptr) {
            invert_diagonal_kernel<<<part.blocks, kBlockSize, 0, a.stream>>>(a, part.own_precond.get());
            WEFT_CUDA_CHECK_LAUNCH("invert_diagonal_kernel");
        }
        product_kernel<<<part.blocks, kBlockSize, 0, a.stream>>>(a, x[k], part.w.get(), nullptr, part.scalars.get(), 0,
                                                                 part.partials.get());
        WEFT_CUDA_CHECK_LAUNCH("product_kernel");
        start_kernel<<<part.blocks, kBlockSize, 0, a.stream>>>(a, part.precond, schwarz_ ? 0 : 1, b[k], part.w.get(),
                                                               part.r.get(), part.u.get(), part.p.get(), part.s.get(),
                                                               part.partials.get());
        WEFT_CUDA_CHECK_LAUNCH("start_kernel");
    }
    if (schwarz_) enqueue_schwarz(SchwarzInput::Residual, 0, 0);  // u = M⁻¹r₀, rᵀu
    enqueue_reduction(0, kStart);
    enqueue_product(1);
    enqueue_reduction(1, kFirstAlpha);

    Part& origin = *part_[0];
    if (one_launch()) {
        const PartPcgScalars s = run_one_launch(x);
        halo_.exchange(x);  // the solution's ghosts (the caller's next use of x needs them)
        WEFT_CUDA_CHECK(cudaSetDevice(previous));
        return {s.iterations, s.relative, s.converged != 0};
    }
    // The batches: captured once (part 0's stream forks to the others and joins them), replayed
    // until the scalars say stop.
    const std::vector<float*> xs(x.begin(), x.end());
    if (use_graph_ && (graph_ == nullptr || graph_x_ != xs || graph_batch_ != batch)) {
        if (graph_ != nullptr) WEFT_CUDA_CHECK(cudaGraphExecDestroy(graph_));
        graph_ = nullptr;
        std::vector<cudaEvent_t> fork(part_.size());
        for (std::size_t k = 0; k < part_.size(); ++k) {
            WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->system.device));
            WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&fork[k], cudaEventDisableTiming));
        }
        WEFT_CUDA_CHECK(cudaSetDevice(origin.system.device));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(origin.system.stream));
        const long long launches_before = thread_kernel_launches;  // a capture enqueues nothing
        WEFT_CUDA_CHECK(cudaStreamBeginCapture(origin.system.stream, cudaStreamCaptureModeGlobal));
        WEFT_CUDA_CHECK(cudaEventRecord(fork[0], origin.system.stream));
        for (std::size_t k = 1; k < part_.size(); ++k) {
            WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->system.device));
            WEFT_CUDA_CHECK(cudaStreamWaitEvent(part_[k]->system.stream, fork[0], 0));
        }
        for (int it = 0; it < batch; ++it) enqueue_iteration(x, it % 2);
        for (std::size_t k = 1; k < part_.size(); ++k) {
            WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->system.device));
            WEFT_CUDA_CHECK(cudaEventRecord(fork[k], part_[k]->system.stream));
            WEFT_CUDA_CHECK(cudaSetDevice(origin.system.device));
            WEFT_CUDA_CHECK(cudaStreamWaitEvent(origin.system.stream, fork[k], 0));
        }
        WEFT_CUDA_CHECK(cudaSetDevice(origin.system.device));
        cudaGraph_t graph = nullptr;
        WEFT_CUDA_CHECK(cudaStreamEndCapture(origin.system.stream, &graph));
        graph_kernels_ = thread_kernel_launches - launches_before;
        thread_kernel_launches = launches_before;
        WEFT_CUDA_CHECK(cudaGraphInstantiate(&graph_, graph, 0));
        WEFT_CUDA_CHECK(cudaGraphDestroy(graph));
        for (std::size_t k = 0; k < part_.size(); ++k) {
            WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->system.device));
            WEFT_CUDA_CHECK(cudaEventDestroy(fork[k]));
        }
        graph_x_ = xs;
        graph_batch_ = batch;
    }
    // The graph starts on the origin's stream: the other parts' start work must be done first.
    for (std::size_t k = 1; k < part_.size(); ++k) {
        WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->system.device));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(part_[k]->system.stream));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(origin.system.device));
    const auto read_scalars = [&] {
        WEFT_CUDA_CHECK(cudaMemcpyAsync(origin.host.get(), origin.scalars.get(), sizeof(PartPcgScalars), cudaMemcpyDeviceToHost,
                                        origin.system.stream));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(origin.system.stream));
        return *origin.host.get();
    };
    PartPcgScalars s = read_scalars();
    while (s.running != 0) {
        if (use_graph_) {
            WEFT_CUDA_CHECK(cudaGraphLaunch(graph_, origin.system.stream));
            thread_kernel_launches += graph_kernels_;
        } else {
            for (int it = 0; it < batch; ++it) enqueue_iteration(x, it % 2);
            // The origin's read below must follow every part's batch.
            for (std::size_t k = 1; k < part_.size(); ++k) {
                WEFT_CUDA_CHECK(cudaSetDevice(part_[k]->system.device));
                WEFT_CUDA_CHECK(cudaStreamSynchronize(part_[k]->system.stream));
            }
            WEFT_CUDA_CHECK(cudaSetDevice(origin.system.device));
        }
        s = read_scalars();
    }
    // The ghosts of the solution get their owners' values (the caller's next use of x needs them).
    halo_.exchange(x);
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
    PartPcgResult result;
    result.iterations = s.iterations;
    result.relative_residual = s.relative;
    result.converged = s.converged != 0;
    return result;
}

}  // namespace weft::cuda::multi
