// Filtered block-Jacobi PCG on the device, the same algorithm as the CPU's (runtime/src/cpu/pcg.h,
// Baraff & Witkin 1998 §5.3). Every scalar of the loop (δ, α, β, the iteration count and whether to go
// on) lives in device memory, so the loop runs without the host: under a CUDA graph its while node
// reads `running` through the conditional handle each kernel sets.
//
// Three kernels per iteration, each one pass over the data it needs:
//   1. q = filter(A c) fused with the dot cᵀq, and α = δ/cᵀq in the last block;
//   2. Δv += αc, r −= αq, s = P⁻¹r fused with the dot rᵀs, and β, δ and the convergence test;
//   3. c = filter(s + βc), which needs every row's new s first (the SpMV reads neighbours).
// The reductions are deterministic (device_math.cuh, grid_sum), so a solve gives the same bits on
// every run and whether or not it runs inside a graph.
//
// Proximity contacts (contact_terms.cuh) add A_contact = Σ_pairs w wᵀ ⊗ C to A. Its product is a pass
// per pair (launched before each SpMV, or a phase of the one-launch loop) and a gather per row, fused
// here into the kernels that already form the row's product; the PCG setup gathers the pairs' share of
// b and of the diagonal blocks. Each kernel that does is compiled twice (kContacts): without a contact
// list the solver runs exactly the kernels it ran before contacts existed.
#include <cooperative_groups.h>
#include <cuda_runtime.h>

#include <algorithm>

#include "contact_terms.cuh"
#include "cuda_check.h"
#include "device_math.cuh"
#include "pcg_control.cuh"
#include "pcg_loop_environment.h"
#include "persistent_sum.cuh"
#include "loop_clock.cuh"
#include "schwarz_apply.cuh"

namespace weft::cuda {
namespace {

/// Row i of A·x.
__device__ inline V3 row_times(const DeviceView& d, std::uint32_t i, const float* x) {
    const std::uint32_t slice = i / kSliceRowsDevice;
    const std::uint32_t first = d.slice_start[slice], width = (d.slice_start[slice + 1] - first) / kSliceRowsDevice;
    V3 acc{};
    for (std::uint32_t k = 0; k < width; ++k) {
        const std::uint32_t pos = first + k * kSliceRowsDevice + i % kSliceRowsDevice;
        acc += load_block(d.blocks, pos) * load3(x, d.column[pos], d.n);
    }
    return acc;
}

template <bool kContacts>
__global__ void pcg_setup_kernel(DeviceView d, int first_newton, int schwarz) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double value = 0.0;
    if (i < d.n) {
        M3 diagonal = load_block(d.blocks, d.diagonal[i]);
        if constexpr (kContacts) {
            // As the CPU: b_i += Σ w_i·rhs_pair (add_rhs), and the preconditioner inverts the fabric's
            // diagonal block plus Σ w_i²·C_pair (SystemOperator::diagonal_block).
            const ContactView& ct = d.contacts;
            const std::uint32_t first = ct.start[i], last = ct.start[i + 1];
            if (first < last) {
                V3 b = load3(d.b, i, d.n);
                M3 acc{};
                for (std::uint32_t e = first; e < last; ++e) {
                    const std::uint32_t entry = ct.entries[e];
                    const float w = ct.entry_weight[e];
                    b += w * load3(ct.rhs, entry >> 2, ct.capacity);
                    acc += (w * w) * load_contact_block(ct, entry >> 2);
                }
                store3(d.b, i, d.n, b);
                diagonal += acc;
            }
        }
        // The Schwarz preconditioner aggregates the diagonal block itself (its δ₀ of b comes from its
        // own apply, schwarz_kernels.cu); block-Jacobi keeps the inverse.
        const M3 P = schwarz ? diagonal : physics::inverse(diagonal);
        for (int e = 0; e < 9; ++e) d.precond[e * d.n + i] = P.m[e / 3][e % 3];
        const bool fixed = d.fixed[i] != 0;
        // Filtered vertices get their prescribed change z = v_target − v_k; the rest start at 0 or,
        // warm, at the last substep's velocity change (as on the CPU).
        const bool warm = first_newton && step_params(d).cg_warm_start;
        store3(d.dv, i, d.n,
               fixed ? load3(d.pin_velocity, i, d.n) - load3(d.vk, i, d.n) : (warm ? load3(d.dv_previous, i, d.n) : V3{}));
        if (!fixed && !schwarz) {
            const V3 b = load3(d.b, i, d.n);
            value = static_cast<double>(physics::dot(b, P * b));
        }
    }
    grid_sum(value, d, [&](double total) { d.control->delta0_b = total; });
}

/// r = filter(b − AΔv); with block-Jacobi also c = P⁻¹r, δ = rᵀc and the loop's start. The
/// Schwarz path (kSchwarz) stops at r: its apply and start follow (schwarz_kernels.cu).
template <bool kContacts, bool kSchwarz>
__global__ void pcg_residual_kernel(DeviceView d, unsigned long long handle) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double value = 0.0;
    if (i < d.n) {
        V3 r{}, c{};
        if (!d.fixed[i]) {
            V3 product = row_times(d, i, d.dv);
            if constexpr (kContacts) {
                if (contact_count(d.contacts) > 0) product = contact_gather(d.contacts, i, product);
            }
            r = load3(d.b, i, d.n) - product;
            if constexpr (!kSchwarz) {
                c = load_precond(d, i) * r;
                value = static_cast<double>(physics::dot(r, c));
            }
        }
        store3(d.r, i, d.n, r);
        if constexpr (!kSchwarz) store3(d.c, i, d.n, c);
    }
    if constexpr (!kSchwarz) grid_sum(value, d, [&](double delta) { start_solve(d, delta, handle); });
}

template <bool kContacts>
__global__ void pcg_spmv_dot_kernel(DeviceView d, unsigned long long handle) {
    if (!d.control->running) return;
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    double value = 0.0;
    const bool row = i < d.n, free_row = row && !d.fixed[i];
    V3 q{};
    if (free_row) q = row_times(d, i, d.c);
    if constexpr (kContacts) {
        // The row's contact sum from the spread pass after the pair pass (launch_contact_product).
        // An empty list skips the read (measurable on small cloth where an iteration is a few µs).
        if (free_row && contact_count(d.contacts) > 0) q += load3(d.contacts.row_sum, i, d.contacts.vertices);
    }
    if (row) {
        store3(d.q, i, d.n, q);
        value = static_cast<double>(physics::dot(load3(d.c, i, d.n), q));
    }
    grid_sum(value, d, [&](double cq) {
        PcgControl& ctl = *d.control;
        ctl.cq = cq;
        if (!(cq > 0.0)) {  // loss of positive definiteness or breakdown: stop and report
            ctl.running = 0;
            ctl.converged = 0;
            set_condition(handle, 0);
        } else {
            ctl.alpha = static_cast<float>(ctl.delta / cq);
        }
    });
}

__global__ void pcg_update_kernel(DeviceView d, unsigned long long handle) {
    if (!d.control->running) return;
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    const float alpha = d.control->alpha;
    double value = 0.0;
    if (i < d.n) {
        const V3 r = load3(d.r, i, d.n) - alpha * load3(d.q, i, d.n);
        const V3 s = load_precond(d, i) * r;
        store3(d.dv, i, d.n, load3(d.dv, i, d.n) + alpha * load3(d.c, i, d.n));
        store3(d.r, i, d.n, r);
        store3(d.s, i, d.n, s);
        value = static_cast<double>(physics::dot(r, s));
    }
    grid_sum(value, d, [&](double delta_new) { end_iteration(d, delta_new, handle); });
}

__global__ void pcg_direction_kernel(DeviceView d) {
    PcgControl& ctl = *d.control;
    if (!ctl.running) return;
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i < d.n) {
        const float beta = ctl.beta;
        store3(d.c, i, d.n, d.fixed[i] ? V3{} : load3(d.s, i, d.n) + beta * load3(d.c, i, d.n));
    }
}

__global__ void pcg_finish_kernel(DeviceView d) {
    const PcgControl& ctl = *d.control;
    DeviceStats& st = *d.stats;
    st.cg_iterations += ctl.iterations;
    st.cg_iterations_max = ctl.iterations > st.cg_iterations_max ? ctl.iterations : st.cg_iterations_max;
    const double residual = ctl.delta0 > 0.0 ? sqrt((ctl.delta > 0.0 ? ctl.delta : 0.0) / ctl.delta0) : 0.0;
    st.cg_residual = residual > st.cg_residual ? residual : st.cg_residual;
    if (!ctl.converged) ++st.cg_not_converged;
    ++st.newton_iterations;
}

// ---- the whole loop in one cooperative launch (small and mid-size systems) ---------------------------
// The same iteration, with grid-wide barriers instead of kernel boundaries: a grid no larger than the
// device holds at once strides over the rows, and every block finishes each dot product itself from
// the block partials (in index order, so all blocks get the same bits and take the same decisions).
// Two partial arrays alternate so that a block still reading one dot's partials never sees the next
// dot's. Used where launch latency, not bandwidth, bounds an iteration.

/// The one-launch CG loop: the same phases as the per-kernel form, a grid-wide barrier after each
/// (the contact pair pass; SpMV and cᵀq; the preconditioner with rᵀs; the direction). With block-Jacobi
/// the preconditioner is fused into the axpy pair; with Schwarz it is the axpy pair with level 0's
/// restriction, the restriction down the coarser levels, every level's solves in one phase, then the
/// corrections (schwarz_apply.cuh). A warp keeps the same domains in every iteration.
/// Five blocks an SM (48 registers): the contact gathers and the domain solves are bound by the loads
/// in flight. Left to itself the compiler took 96–114 registers for the Schwarz variant with contacts
/// (two blocks an SM) and the 1.2M flag with self-contact ran 320.4 ms a frame; at 4, 5 and 6 blocks
/// 290.5, 288.2 and 285.1 ms, the wound twist 30.0, 30.0 and 31.3 ms a step (32.3 unbounded; one
/// H200, one build): 5 is the best of both.
template <bool kContacts, bool kSchwarz>
__global__ void __launch_bounds__(kBlockSize, 5) pcg_persistent_kernel(DeviceView d) {
    namespace cg = cooperative_groups;
    __shared__ float values[kSchwarz ? kSchwarzWarpsPerBlock : 1][kSchwarzDim];
    const StepParams& sp = step_params(d);
    PcgControl& ctl = *d.control;
    if (!ctl.running) return;  // uniform: written by the start of the solve
    double delta = ctl.delta;
    const double delta0 = ctl.delta0;
    int iterations = 0, converged = 0;
    CgEnergyWindow energy;
    energy.reset();
    double* partials[2] = {d.partials, d.partials + gridDim.x};
    const std::uint32_t stride = gridDim.x * blockDim.x;
    const std::uint32_t lane = threadIdx.x % 32, warp = threadIdx.x / 32;
    const std::uint32_t first_warp = blockIdx.x * kSchwarzWarpsPerBlock + warp, warps = gridDim.x * kSchwarzWarpsPerBlock;
    // Fixed for the whole solve, and the same in every block: the contact phase and its barrier are
    // skipped uniformly when the substep has no pairs.
    const std::uint32_t pairs = kContacts ? contact_count(d.contacts) : 0u;
    LoopClock clock(d.loop_clock);  // profiling: block 0's first thread times the phases
    if constexpr (kContacts)
        if (pairs > 0) clock_contact_work(d.loop_clock, d.contacts, d.n);
    for (;;) {
        clock.iteration();
        if constexpr (kContacts) {
            if (pairs > 0) {
                // The pair pass of A_contact·c. c is complete (the barrier that ended the last
                // iteration, or the kernel before this launch); the gather below waits for every pair
                // behind one more barrier.
                for (std::uint32_t p = blockIdx.x * blockDim.x + threadIdx.x; p < pairs; p += stride)
                    contact_pair_product(d.contacts, p, d.c, d.n);
                cg::this_grid().sync();
                clock.mark(kPhasePairs);
                // Each row's sum of its pairs' products, the rows spread over the warps.
                contact_row_sums(d.contacts, d.n, first_warp, warps);
                cg::this_grid().sync();
                clock.mark(kPhaseRowSums);
            }
        }
        double local = 0.0;
        for (std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < d.n; i += stride) {
            V3 q{};
            if (!d.fixed[i]) {
                q = row_times(d, i, d.c);
                if constexpr (kContacts) {
                    if (pairs > 0) q += load3(d.contacts.row_sum, i, d.contacts.vertices);
                }
            }
            store3(d.q, i, d.n, q);
            local += static_cast<double>(physics::dot(load3(d.c, i, d.n), q));
        }
        const double cq = persistent_sum(local, partials[0]);
        clock.mark(kPhaseProduct);
        if (!(cq > 0.0)) break;  // breakdown: reported as not converged
        const float alpha = static_cast<float>(delta / cq);
        energy.record(delta / cq, delta);
        local = 0.0;
        if constexpr (kSchwarz) {
            // r −= αq and Δv += αc with the restriction to level 1, the restriction down the coarse
            // levels, then every level's solves in one phase (schwarz_apply.cuh).
            const SchwarzView& m = d.mas;
            for (std::uint32_t domain = first_warp; domain < m.level[0].domains; domain += warps)
                schwarz_restrict_only(d, 0, domain, lane, values[warp], SchwarzInput::Update, alpha);
            cg::this_grid().sync();
            clock.mark(kPhaseFine);
            for (int l = 1; l + 1 < m.levels; ++l) {
                for (std::uint32_t domain = first_warp; domain < m.level[l].domains; domain += warps)
                    schwarz_restrict_only(d, l, domain, lane, values[warp], SchwarzInput::Residual, 0.0f);
                cg::this_grid().sync();
            }
            clock.mark(kPhaseCoarse);
            schwarz_solve_levels(d, first_warp, warps, lane, values[warp]);
            cg::this_grid().sync();
            clock.mark(kPhaseSolves);
            for (std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < d.n; i += stride) {
                const V3 z = schwarz_correction(d, i);
                store3(d.s, i, d.n, z);
                local += static_cast<double>(physics::dot(load3(d.r, i, d.n), z));
            }
        } else {
            for (std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < d.n; i += stride) {
                const V3 r = load3(d.r, i, d.n) - alpha * load3(d.q, i, d.n);
                const V3 s = load_precond(d, i) * r;
                store3(d.dv, i, d.n, load3(d.dv, i, d.n) + alpha * load3(d.c, i, d.n));
                store3(d.r, i, d.n, r);
                store3(d.s, i, d.n, s);
                local += static_cast<double>(physics::dot(r, s));
            }
        }
        const double delta_new = persistent_sum(local, partials[1]);
        clock.mark(kPhaseProlong);  // with block-Jacobi: the update and u = M⁻¹r
        const float beta = static_cast<float>(delta_new / delta);
        delta = delta_new;
        ++iterations;
        converged = delta_new <= sp.cg_eps2 * delta0;
        if ((converged && !energy.still_falling(sp.cg_energy_floor)) || iterations >= sp.cg_max_iterations) break;
        for (std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < d.n; i += stride)
            store3(d.c, i, d.n, d.fixed[i] ? V3{} : load3(d.s, i, d.n) + beta * load3(d.c, i, d.n));
        cg::this_grid().sync();
        clock.mark(kPhaseUpdate);
    }
    cg::this_grid().sync();  // every block has read `running` before it is cleared
    if (blockIdx.x == 0 && threadIdx.x == 0) {
        ctl.delta = delta;
        ctl.iterations = iterations;
        ctl.converged = converged;
        ctl.running = 0;
    }
}

__global__ void spmv_kernel(DeviceView d, const float* x, float* y) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i < d.n) store3(y, i, d.n, row_times(d, i, x));
}

}  // namespace

void launch_pcg_setup(const DeviceView& d, bool first_newton, bool schwarz, cudaStream_t stream) {
    const int first = first_newton ? 1 : 0, mas = schwarz ? 1 : 0;
    if (d.contacts.capacity > 0)
        pcg_setup_kernel<true><<<grid_for(d.n), kBlockSize, 0, stream>>>(d, first, mas);
    else
        pcg_setup_kernel<false><<<grid_for(d.n), kBlockSize, 0, stream>>>(d, first, mas);
    WEFT_CUDA_CHECK_LAUNCH("pcg_setup_kernel");
}

void launch_pcg_residual(const DeviceView& d, unsigned long long handle, bool schwarz, cudaStream_t stream) {
    if (schwarz) {
        // δ₀ of b in the Schwarz norm first (as the CPU: b·M⁻¹b), then r₀ and its apply.
        launch_schwarz_apply(d, SchwarzInput::RightHandSide, SchwarzOutput::Norm, 0, stream);
        if (d.contacts.capacity > 0) {
            launch_contact_product(d, d.dv, false, stream);
            pcg_residual_kernel<true, true><<<grid_for(d.n), kBlockSize, 0, stream>>>(d, handle);
        } else {
            pcg_residual_kernel<false, true><<<grid_for(d.n), kBlockSize, 0, stream>>>(d, handle);
        }
        WEFT_CUDA_CHECK_LAUNCH("pcg_residual_kernel");
        launch_schwarz_apply(d, SchwarzInput::Residual, SchwarzOutput::Start, handle, stream);
        return;
    }
    if (d.contacts.capacity > 0) {
        launch_contact_product(d, d.dv, false, stream);
        pcg_residual_kernel<true, false><<<grid_for(d.n), kBlockSize, 0, stream>>>(d, handle);
    } else {
        pcg_residual_kernel<false, false><<<grid_for(d.n), kBlockSize, 0, stream>>>(d, handle);
    }
    WEFT_CUDA_CHECK_LAUNCH("pcg_residual_kernel");
}

void launch_pcg_iteration(const DeviceView& d, unsigned long long handle, bool schwarz, cudaStream_t stream) {
    // The pair pass cannot join the direction kernel before it: it reads c at four arbitrary rows, so
    // every row's new c must be written first (a kernel boundary). It is one small launch over the
    // contact capacity that returns at once past the pair count.
    if (d.contacts.capacity > 0) {
        launch_contact_product(d, d.c, true, stream);
        pcg_spmv_dot_kernel<true><<<grid_for(d.n), kBlockSize, 0, stream>>>(d, handle);
    } else {
        pcg_spmv_dot_kernel<false><<<grid_for(d.n), kBlockSize, 0, stream>>>(d, handle);
    }
    WEFT_CUDA_CHECK_LAUNCH("pcg_spmv_dot_kernel");
    if (schwarz) {
        // The axpy pair runs inside the apply's first level (schwarz_kernels.cu), s = M⁻¹r and rᵀs
        // in its last kernel.
        launch_schwarz_apply(d, SchwarzInput::Update, SchwarzOutput::Iterate, handle, stream);
    } else {
        pcg_update_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d, handle);
        WEFT_CUDA_CHECK_LAUNCH("pcg_update_kernel");
    }
    pcg_direction_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("pcg_direction_kernel");
}

namespace {

const void* persistent_kernel(bool contacts, bool schwarz) {
    if (schwarz)
        return contacts ? reinterpret_cast<const void*>(&pcg_persistent_kernel<true, true>)
                        : reinterpret_cast<const void*>(&pcg_persistent_kernel<false, true>);
    return contacts ? reinterpret_cast<const void*>(&pcg_persistent_kernel<true, false>)
                    : reinterpret_cast<const void*>(&pcg_persistent_kernel<false, false>);
}

}  // namespace

int pcg_persistent_grid(const DeviceView& d, int device, bool schwarz) {
    int per_sm = 0, sms = 0, cooperative = 0;
    WEFT_CUDA_CHECK(cudaDeviceGetAttribute(&cooperative, cudaDevAttrCooperativeLaunch, device));
    if (cooperative == 0) return 0;
    WEFT_CUDA_CHECK(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device));
    // The variant the solver will launch: with contacts it may hold more registers, so fewer blocks.
    WEFT_CUDA_CHECK(cudaOccupancyMaxActiveBlocksPerMultiprocessor(
        &per_sm, persistent_kernel(d.contacts.capacity > 0, schwarz), kBlockSize, 0));
    // At least one block an SM: below that the warp-per-domain phases of the Schwarz apply take two
    // or more rounds on a few SMs while the rest idle. One H200, µs per CG iteration (the loop
    // clock, the game preset), a block per 256 rows against 132 blocks: the 9.7K-triangle flag 34.1
    // against 26.1 (restriction 6.0 → 3.6, domain solves 9.6 → 4.2), the 672-triangle runner 23.8
    // against 19.7; two blocks an SM (264) gave 32.1 and 24.0 (every barrier waits for more blocks).
    const int needed = std::max(static_cast<int>(grid_for(d.n)), sms);
    const int wanted = std::min(pcg_blocks_from_environment().value_or(needed),
                                std::max(needed, static_cast<int>(kMaxPersistentBlocks)));
    return std::min(wanted, per_sm * sms);
}

void launch_pcg_persistent(const DeviceView& d, int grid, bool schwarz, cudaStream_t stream) {
    DeviceView view = d;
    void* args[] = {&view};
    WEFT_CUDA_CHECK(cudaLaunchCooperativeKernel(persistent_kernel(d.contacts.capacity > 0, schwarz), dim3(grid),
                                                dim3(kBlockSize), args, 0, stream));
}

void launch_pcg_finish(const DeviceView& d, cudaStream_t stream) {
    pcg_finish_kernel<<<1, 1, 0, stream>>>(d);
    WEFT_CUDA_CHECK_LAUNCH("pcg_finish_kernel");
}

void launch_spmv(const DeviceView& d, const float* x, float* y, cudaStream_t stream) {
    spmv_kernel<<<grid_for(d.n), kBlockSize, 0, stream>>>(d, x, y);
    WEFT_CUDA_CHECK_LAUNCH("spmv_kernel");
}

}  // namespace weft::cuda
