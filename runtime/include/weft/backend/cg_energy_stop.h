#pragma once
/// @file
/// The CG's second stopping test (backend kit; docs/methods.md §1c), shared by every CG loop: the
/// CPU's (cpu/pcg.h), one GPU's (pcg_control.cuh and the one-launch loop) and the loop across GPUs
/// (multi/part_pcg_terms.cuh).
///
/// The residual test alone can stop a solve on a plateau: a slow, stiff mode whose error the
/// preconditioned residual hardly shows, so that a substep now and then ends far from the minimiser
/// of implicit Euler's incremental potential Φ(Δv) = ½ΔvᵀAΔv − bᵀΔv and gains energy (the flag's
/// one substep in 10,000 that gains a joule at the default tolerance; docs/results.md, "Soak").
/// Each CG iteration lowers Φ by exactly ½·α_j·δ_j (α_j the step length, δ_j = r_jᵀP⁻¹r_j), and the sum
/// of those falls over the d iterations after j is a lower bound of ½‖e_j‖²_A, the energy-norm
/// error that iterate j still had (Hestenes & Stiefel 1952, Thm. 6:1; Strakoš & Tichý 2002 use it
/// as an estimate; Arioli 2004 stops on it). Φ is in joules (A is the mass matrix plus h·damping and
/// h²·stiffness, Δv in m/s), and A ⪰ M, so ½‖e‖²_A ≥ ½‖e‖²_M = ½·m·ē², ē the mass-weighted RMS
/// velocity error. Past the residual test the loop goes on while the fall over the last
/// kCgEnergyDelay iterations says ē may still exceed the tolerance: its cost lands in the substeps
/// that have a plateau and nowhere else. A stalled float solve falls by nothing and stops.

#include "weft/math/host_device.h"

namespace weft {

/// Iterations the fall of Φ is summed over (the estimate's delay d).
inline constexpr int kCgEnergyDelay = 4;

/// The fall of Φ over kCgEnergyDelay iterations, J, below which the CG may stop: ½·m·ε², the
/// kinetic energy of cloth of mass `mass` (kg) moving at `velocity_tolerance` (m/s). 0 (no test)
/// when either is not positive.
WEFT_HD inline double cg_energy_floor(double mass, double velocity_tolerance) {
    return mass > 0.0 && velocity_tolerance > 0.0 ? 0.5 * mass * velocity_tolerance * velocity_tolerance : 0.0;
}

/// The last kCgEnergyDelay falls of Φ of one solve. Plain data: it lives in the device loops'
/// control blocks as well as on the host stack.
struct CgEnergyWindow {
    double fall[kCgEnergyDelay];
    int count;

    WEFT_HD void reset() {
        for (double& f : fall) f = 0.0;
        count = 0;
    }
    /// After an iteration with step length α and δ = rᵀP⁻¹r before it (Φ fell by ½·α·δ), J.
    WEFT_HD void record(double alpha, double delta) {
        fall[count % kCgEnergyDelay] = 0.5 * alpha * delta;
        ++count;
    }
    /// Whether a loop whose residual test has passed must still go on: the fall over the last
    /// kCgEnergyDelay iterations (over all of them while there are fewer) exceeds `floor` (J;
    /// cg_energy_floor). False with no test (floor 0) and for a solve that converged before its first
    /// iteration (the residual of its warm start already passed: nothing to estimate from).
    [[nodiscard]] WEFT_HD bool still_falling(double floor) const {
        if (!(floor > 0.0) || count == 0) return false;
        double sum = 0.0;
        for (const double f : fall) sum += f;
        return sum > floor;
    }
};

}  // namespace weft
