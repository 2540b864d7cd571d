#pragma once
/// @file
/// Profiling of the one-launch CG loops (pcg_kernels.cu on one GPU, multi/part_pcg_loop.cu across
/// GPUs): with WEFT_CUDA_PCG_CLOCK=1, block 0's first thread charges the SM cycles between the
/// loop's phases to each phase, and the owner prints µs per iteration when it goes. The phases are
/// those of the multi-GPU loop; one GPU uses the subset it has (no level-1 run, pushes or meetings).

#include <cuda_runtime_api.h>

#include <string>

namespace weft::cuda {

/// The phases of one CG iteration the loop clock times, in the order of the multi-GPU loop.
enum LoopPhase : int {
    kPhaseUpdate = 0,  ///< p, s, x, r (and u with block-Jacobi); one GPU: the direction
    kPhaseFine,        ///< Schwarz level 0's residual restricted to level 1 (one GPU: with r −= αq)
    kPhaseLevel1,      ///< level 1's run into the other parts
    kPhaseCoarse,      ///< the restriction down the coarse levels, whole on every GPU
    kPhaseSolves,      ///< every level's domain solves in one phase (schwarz_solve_levels)
    kPhaseProlong,     ///< u = Σ levels, rᵀu
    kPhasePush,        ///< u's ghosts and contact vertices into the other parts
    kPhasePairs,       ///< the contacts' pair pass
    kPhaseRowSums,     ///< each row's sum of its contacts (contact_row_sums)
    kPhaseProduct,     ///< w = A·u and its dot product
    kPhaseSums,        ///< the part's two sums into every part
    kPhaseMeetings,    ///< the meetings of the parts, whole (barriers, fences, waits)
    kPhaseWaiting,     ///< of which block 0 waited for other parts' arrivals
    kLoopPhases,
};

/// The counts a loop clock keeps after the phases' cycles.
enum LoopCount : int {
    kCountIterations = kLoopPhases,  ///< iterations timed
    kCountSolves,                    ///< loops started with contacts (the counts below are their sums)
    kCountPairs,                     ///< pairs in the (part's) contact list
    kCountActivePairs,               ///< of which in the solve (ContactView::active_mask)
    kCountEntries,                   ///< incidence entries of the rows the loop sums (contact_row_sums)
    kLoopClockEntries,               ///< entries of a loop clock in device memory
};

/// True where WEFT_CUDA_PCG_CLOCK=1 asks for the loop clock.
[[nodiscard]] bool loop_clock_requested();

/// Prints `who`'s clock (kLoopClockEntries cycles in device memory on `device`) to stderr as µs per
/// iteration at the device's clock rate, the phases it never entered left out, and the contact work
/// of an average solve (pairs, those in the solve, incidence entries): what the phases' times are for. Returns quietly where
/// the device cannot be read (it is for profiling, called from destructors).
void print_loop_clock(const std::string& who, const long long* device_cycles, int device) noexcept;

}  // namespace weft::cuda
