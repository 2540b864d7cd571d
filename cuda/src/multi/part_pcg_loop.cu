// The CG across parts in one cooperative launch per GPU (multi/part_pcg_loop.h).
#include "multi/part_pcg_loop.h"

#include <cooperative_groups.h>

#include <algorithm>

#include "cuda_check.h"
#include "loop_clock.cuh"
#include "multi/part_pcg_terms.cuh"
#include "schwarz_apply.cuh"

namespace weft::cuda::multi {
namespace {

namespace cg = cooperative_groups;

__device__ inline void store_release_system(unsigned* where, unsigned value) {
    asm volatile("st.release.sys.global.u32 [%0], %1;" ::"l"(where), "r"(value) : "memory");
}

__device__ inline unsigned load_acquire_system(const unsigned* where) {
    unsigned value = 0;
    asm volatile("ld.acquire.sys.global.u32 %0, [%1];" : "=r"(value) : "l"(where) : "memory");
    return value;
}

__device__ inline unsigned long long global_nanoseconds() {
    unsigned long long t = 0;
    asm volatile("mov.u64 %0, %%globaltimer;" : "=l"(t));
    return t;
}

/// Meeting `count` of the parts: every thread's stores so far (peer stores included) are visible to
/// every part when any part passes it. Block 0's first thread announces the arrival to every other
/// part and waits for theirs; the grid barriers before and after carry the order to every block.
/// Returns false, in every block, once this part has stopped waiting: a part did not arrive within
/// the timeout, or another part stopped and said so. Only this part's first thread writes its
/// decision (flags[parts + 1]), before the barrier every block reads it behind: all blocks agree.
__device__ bool meet_parts(const PartLoopView& v, unsigned count, LoopClock& clock) {
    __threadfence_system();  // this thread's peer stores, before the arrival that announces them
    cg::this_grid().sync();
    const long long wait_begin = clock64();
    unsigned* own = v.flags_of[v.part];
    const unsigned told = v.parts, decided = v.parts + 1;
    if (blockIdx.x == 0 && threadIdx.x == 0 && own[decided] == 0) {
        for (unsigned q = 0; q < v.parts; ++q)
            if (q != v.part) store_release_system(v.flags_of[q] + v.part, count);
        const unsigned long long begin = global_nanoseconds();
        unsigned stop = 0;
        for (unsigned q = 0; q < v.parts && stop == 0; ++q) {
            if (q == v.part) continue;
            // Counts only grow within a solve; the difference is read signed so that it never wraps.
            for (unsigned spins = 1; stop == 0 && static_cast<int>(load_acquire_system(own + q) - count) < 0; ++spins) {
                if ((spins & 255u) != 0) continue;
                if (const unsigned other = load_acquire_system(own + told); other != 0)
                    stop = other;
                else if (global_nanoseconds() - begin > v.timeout_ns)
                    stop = 1 + q;
            }
        }
        if (stop != 0) {
            own[decided] = stop;
            for (unsigned q = 0; q < v.parts; ++q)  // the others stop at their next meeting
                if (q != v.part) store_release_system(v.flags_of[q] + told, 1 + v.part);
        }
        clock.add(kPhaseWaiting, clock64() - wait_begin);
    }
    cg::this_grid().sync();
    return __ldcg(own + decided) == 0;
}

/// The loop of PartPcg::enqueue_iteration, phase by phase, with the batches' values (see the header).
/// Four blocks an SM: the contact gathers (random loads) are bound by the loads in flight, and left to
/// itself the compiler gives the Schwarz variants 128 registers a thread, two blocks an SM. Measured
/// on 2 × H200, the 1.2M flag with self-contact a frame (the wound twist a step): 3 blocks (80
/// registers) 185.7 ms (27.6 ms), 4 (64 registers, a few spills) 180.1 (28.2), 5 (48, spilling)
/// 190.1 (30.1); earlier, 2 against 3: 208.7 against 191.9 (29.6 against 30.6).
template <bool kSchwarz, bool kContacts>
__global__ void __launch_bounds__(kBlockSize, 4) part_pcg_loop_kernel(const __grid_constant__ PartLoopView v) {
    __shared__ float values[kSchwarz ? kSchwarzWarpsPerBlock : 1][kSchwarzDim];
    __shared__ PartReduce::TempStorage storage;
    const PartSystem& a = v.a;
    const std::uint32_t local = a.local, owned = a.owned;
    PartPcgScalars s = *v.scalars;  // the start's, the same in every block
    if (s.running == 0) return;     // uniform
    const std::uint32_t thread = blockIdx.x * blockDim.x + threadIdx.x, threads = gridDim.x * blockDim.x;
    const std::uint32_t lane = threadIdx.x % 32, warp = threadIdx.x / 32;
    const std::uint32_t first_warp = blockIdx.x * kSchwarzWarpsPerBlock + warp, warps = gridDim.x * kSchwarzWarpsPerBlock;
    const std::uint32_t pairs = kContacts && a.contacts.capacity > 0 ? contact_count(a.contacts) : 0u;
    const std::uint32_t across = kContacts ? __ldcg(&v.across[owned]) : 0u;
    unsigned meetings = 0;
    LoopClock clock(v.clock);  // profiling: block 0's first thread times the phases
    if constexpr (kContacts)
        if (pairs > 0) clock_contact_work(v.clock, a.contacts, owned);
    const auto mark = [&](int phase) { clock.mark(phase); };
    const auto meet = [&] {
        const bool going = meet_parts(v, ++meetings, clock);
        mark(kPhaseMeetings);
        return going;
    };
    for (int parity = 0;; parity ^= 1) {
        clock.iteration();
        const auto alpha = static_cast<float>(s.alpha), beta = static_cast<float>(s.beta);
        if constexpr (!kSchwarz) {
            // p, s, x, r and u = M⁻¹r (block-Jacobi), its rᵀu into slot 0.
            for (unsigned b = blockIdx.x; b < v.row_blocks; b += gridDim.x) {
                const std::uint32_t i = b * kBlockSize + threadIdx.x;
                double ru = 0.0;
                if (i < owned) ru = part_update_row(a, i, v.precond, true, alpha, beta, v.x, v.r, v.u, v.w, v.p, v.s);
                part_block_partial(ru, v.partials, b, 0, storage);
            }
        } else {
            // p, s, x and r, then u = M⁻¹r: level 0 restricted to level 1, level 1 gathered from
            // every part, the restriction down the coarse levels (whole on every GPU), every level's
            // solves in one phase (schwarz_apply.cuh), then the prolongation with rᵀu into slot 0.
            // (Updating each row in the lane that restricts its node, to save the pass and its
            // barrier, measured slower: a warp's 16 lanes chained through the order's indirection.)
            const SchwarzView& m = v.schwarz.mas;
            for (unsigned b = blockIdx.x; b < v.row_blocks; b += gridDim.x) {
                const std::uint32_t i = b * kBlockSize + threadIdx.x;
                if (i < owned) part_update_directions_row(local, i, alpha, beta, v.x, v.r, v.u, v.w, v.p, v.s);
            }
            cg::this_grid().sync();
            mark(kPhaseUpdate);
            for (std::uint32_t domain = first_warp; domain < m.level[0].domains; domain += warps)
                schwarz_restrict_only(v.schwarz, 0, domain, lane, values[warp], SchwarzInput::Residual, 0.0f);
            cg::this_grid().sync();
            mark(kPhaseFine);
            if (m.levels > 1) {
                const float* mine = m.level[1].values;
                for (std::uint32_t k = v.level1_begin + thread; k < v.level1_end; k += threads) {
                    const float value = __ldcg(&mine[k]);
                    for (unsigned q = 0; q < v.parts; ++q)
                        if (q != v.part) v.level1_to[q][k] = value;
                }
                mark(kPhaseLevel1);
                if (!meet()) break;
                for (int l = 1; l + 1 < m.levels; ++l) {
                    for (std::uint32_t domain = first_warp; domain < m.level[l].domains; domain += warps)
                        schwarz_restrict_only(v.schwarz, l, domain, lane, values[warp], SchwarzInput::Residual, 0.0f);
                    cg::this_grid().sync();
                }
                mark(kPhaseCoarse);
            }
            schwarz_solve_levels(v.schwarz, first_warp, warps, lane, values[warp]);
            cg::this_grid().sync();
            mark(kPhaseSolves);
            for (unsigned b = blockIdx.x; b < v.row_blocks; b += gridDim.x) {
                const std::uint32_t i = b * kBlockSize + threadIdx.x;
                double rz = 0.0;
                if (i < owned) {
                    const V3 z = schwarz_correction(v.schwarz, i);
                    store3(v.u, i, local, z);
                    rz = static_cast<double>(physics::dot(load3(v.r, i, local), z));
                }
                part_block_partial(rz, v.partials, b, 0, storage);
            }
        }
        cg::this_grid().sync();
        mark(kSchwarz ? kPhaseProlong : kPhaseUpdate);
        // u's ghosts into the other parts, u at the contact vertices they read into their copies.
        for (unsigned route = 0; route < v.halo_routes; ++route) {
            const LoopHaloRoute& h = v.halo[route];
            for (std::uint32_t k = thread; k < h.count; k += threads) {
                const std::uint32_t i = h.send[k];
                for (std::uint32_t c = 0; c < 3; ++c) h.to[c * h.to_stride + h.to_first + k] = v.u[c * local + i];
            }
        }
        if constexpr (kContacts) {
            for (std::uint32_t k = thread; k < across; k += threads) {
                const std::uint32_t i = v.across[k], g = v.global[i];
                for (unsigned t = 0; t < v.mirror_targets; ++t)
                    for (std::uint32_t c = 0; c < 3; ++c) v.mirror_to[t][c * v.whole + g] = v.u[c * local + i];
            }
        }
        mark(kPhasePush);
        if (!meet()) break;
        // w = A·u with wᵀu into slot 1: the contacts' pair pass first.
        if constexpr (kContacts) {
            if (pairs > 0) {
                for (std::uint32_t pair = thread; pair < pairs; pair += threads)
                    part_pair_product(a.contacts, pair, v.u, local, v.mirror_copy);
                cg::this_grid().sync();
                mark(kPhasePairs);
                contact_row_sums(a.contacts, owned, first_warp, warps);
                cg::this_grid().sync();
                mark(kPhaseRowSums);
            }
        }
        for (unsigned b = blockIdx.x; b < v.row_blocks; b += gridDim.x) {
            const std::uint32_t i = b * kBlockSize + threadIdx.x;
            double wu = 0.0;
            if (i < owned) {
                const V3 wi = part_product_row(a, i, v.u);
                store3(v.w, i, local, wi);
                wu = static_cast<double>(physics::dot(wi, load3(v.u, i, local)));
            }
            part_block_partial(wu, v.partials, b, 1, storage);
        }
        cg::this_grid().sync();
        mark(kPhaseProduct);
        // The part's two sums into every part's gather buffer, then every block takes the scalars.
        const std::size_t slot = 2 * std::size_t{v.parts} * static_cast<std::size_t>(parity);
        if (blockIdx.x == 0) {
            double sums[2];
            part_sum_partials(v.partials, v.row_blocks, sums, storage);
            if (threadIdx.x == 0)
                for (unsigned q = 0; q < v.parts; ++q) {
                    v.gather_of[q][slot + 2 * v.part] = sums[0];
                    v.gather_of[q][slot + 2 * v.part + 1] = sums[1];
                }
        }
        mark(kPhaseSums);
        if (!meet()) break;
        part_advance_scalars(v.gather_of[v.part] + slot, v.parts, s, kIteration);
        if (s.running == 0) break;  // every block and every part the same decision
    }
    if (__ldcg(v.flags_of[v.part] + v.parts + 1) != 0) s.running = 0;
    cg::this_grid().sync();  // every block has read the start's scalars
    if (blockIdx.x == 0 && threadIdx.x == 0) *v.scalars = s;
}

const void* loop_kernel(const PartLoopView& v) {
    const bool contacts = v.across != nullptr;
    if (v.use_schwarz != 0)
        return contacts ? reinterpret_cast<const void*>(&part_pcg_loop_kernel<true, true>)
                        : reinterpret_cast<const void*>(&part_pcg_loop_kernel<true, false>);
    return contacts ? reinterpret_cast<const void*>(&part_pcg_loop_kernel<false, true>)
                    : reinterpret_cast<const void*>(&part_pcg_loop_kernel<false, false>);
}

}  // namespace

int part_pcg_loop_grid(const PartLoopView& v, int device) {
    int cooperative = 0, sms = 0, per_sm = 0;
    WEFT_CUDA_CHECK(cudaDeviceGetAttribute(&cooperative, cudaDevAttrCooperativeLaunch, device));
    if (cooperative == 0) return 0;
    WEFT_CUDA_CHECK(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device));
    WEFT_CUDA_CHECK(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, loop_kernel(v), kBlockSize, 0));
    // Enough blocks for the widest phase (rows, a warp per domain, pairs), no more than fit at once.
    std::uint32_t widest = std::max(v.row_blocks, 1u);
    if (v.use_schwarz != 0) widest = std::max(widest, blocks_for(v.schwarz.mas.level[0].domains, kSchwarzWarpsPerBlock));
    if (v.across != nullptr) widest = std::max(widest, grid_for(v.a.contacts.capacity));
    return static_cast<int>(std::min<long long>(widest, static_cast<long long>(per_sm) * sms));
}

void launch_part_pcg_loop(const PartLoopView& v, int grid, cudaStream_t stream) {
    PartLoopView view = v;
    void* args[] = {&view};
    WEFT_CUDA_CHECK(cudaLaunchCooperativeKernel(loop_kernel(v), dim3(grid), dim3(kBlockSize), args, 0, stream));
    ++thread_kernel_launches;
}

}  // namespace weft::cuda::multi
