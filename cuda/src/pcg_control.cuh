#pragma once
// The decisions of the device CG loop, shared by the block-Jacobi kernels (pcg_kernels.cu) and the
// Schwarz apply (schwarz_kernels.cu): each runs on the one thread that finishes a grid reduction
// and writes the loop's control block (device_params.h, PcgControl), and the CUDA graph's while-node
// condition when the loop runs inside one.

#include "device_math.cuh"

namespace weft::cuda {

__device__ inline void set_condition(unsigned long long handle, int running) {
    if (handle != 0) cudaGraphSetConditional(static_cast<cudaGraphConditionalHandle>(handle), running ? 1u : 0u);
}

/// Block-Jacobi inverse (or, for the Schwarz preconditioner, the contact-augmented diagonal block)
/// of row i: 9 floats, entry e at [e·n + i].
__device__ inline M3 load_precond(const DeviceView& d, std::uint32_t i) {
    M3 m;
    for (int e = 0; e < 9; ++e) m.m[e / 3][e % 3] = d.precond[e * d.n + i];
    return m;
}

/// After r₀ and its preconditioned norm δ = r₀ᵀM⁻¹r₀: the scale convergence is measured against and
/// whether the loop runs at all.
__device__ inline void start_solve(const DeviceView& d, double delta, unsigned long long handle) {
    PcgControl& ctl = *d.control;
    const StepParams& sp = step_params(d);
    ctl.delta = delta;
    // As on the CPU: measured against the larger of |b| and the initial residual.
    ctl.delta0 = ctl.delta0_b > delta ? ctl.delta0_b : delta;
    ctl.iterations = 0;
    ctl.energy.reset();
    if (!(ctl.delta0 > 0.0)) {
        ctl.converged = ctl.delta0 == 0.0;
        ctl.running = 0;
    } else {
        ctl.converged = delta <= sp.cg_eps2 * ctl.delta0;
        ctl.running = !ctl.converged && sp.cg_max_iterations > 0;
    }
    set_condition(handle, ctl.running);
}

/// After an iteration's new δ = rᵀM⁻¹r: β, the count, and whether to stop (converged, with the
/// potential no longer falling, or capped). On exit the direction update of this iteration is
/// skipped: the CPU computes it but never uses it, so Δv is the same.
__device__ inline void end_iteration(const DeviceView& d, double delta_new, unsigned long long handle) {
    PcgControl& ctl = *d.control;
    const StepParams& sp = step_params(d);
    ctl.energy.record(ctl.delta / ctl.cq, ctl.delta);  // this iteration's α = δ/cᵀAc, in double
    ctl.beta = static_cast<float>(delta_new / ctl.delta);
    ctl.delta = delta_new;
    ++ctl.iterations;
    ctl.converged = delta_new <= sp.cg_eps2 * ctl.delta0;
    if ((ctl.converged && !ctl.energy.still_falling(sp.cg_energy_floor)) || ctl.iterations >= sp.cg_max_iterations) {
        ctl.running = 0;
        set_condition(handle, 0);
    }
}

}  // namespace weft::cuda
