#pragma once
/// @file
/// Preconditioned CG across the parts of a partitioned system (docs/multi-gpu.md, "The CG
/// iteration"), in the single-reduction form of Chronopoulos & Gear (1989): with u = M⁻¹r and
/// w = A·u, both scalars of an iteration, γ = rᵀu and δ = wᵀu, come after the one product, so the
/// parts meet once per iteration (one reduction of two numbers) and exchange one vector (u's ghosts):
///
///   p ← u + βp,  s ← w + βs,  x ← x + αp,  r ← r − αs,  u ← M⁻¹r,  w ← A·u,
///   γ' = rᵀu,  δ = wᵀu,  β = γ'/γ,  α = γ' / (δ − β·γ'/α).
///
/// In exact arithmetic it is the textbook PCG (s = A·p by induction). M is block-Jacobi (each owned
/// row's inverse 3×3 diagonal block: local to its part). The loop is driven from the host: each
/// iteration's partial sums come back (one synchronisation) and α, β go out as kernel arguments; the
/// solver proper will run it as graphs with the reduction on the devices. The partial sums are
/// deterministic within a part and added in part order, so a solve gives the same bits on every run
/// for a given partition.

#include <cuda_runtime_api.h>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "device_array.h"
#include "multi/halo_exchange.h"
#include "multi/part_matrix.h"

namespace weft::cuda::multi {

struct PartPcgResult {
    int iterations = 0;
    double relative_residual = 0.0;  ///< sqrt(rᵀM⁻¹r / bᵀM⁻¹b) at the end
    bool converged = false;
};

class PartPcg {
public:
    /// Over the parts' matrices (part p on matrices[p]->device(), enqueuing on streams[p]) and their
    /// halo exchange. Allocates the work vectors.
    PartPcg(std::span<const PartMatrix* const> matrices, HaloExchange& halo, std::span<const cudaStream_t> streams);
    ~PartPcg();
    PartPcg(const PartPcg&) = delete;
    PartPcg& operator=(const PartPcg&) = delete;

    /// Solves A·x = b to sqrt(rᵀM⁻¹r / bᵀM⁻¹b) ≤ tolerance or `max_iterations`. b and x are each
    /// part's local vectors (stride local, owned entries read; x's ghosts are overwritten), on the
    /// part's device; x holds the start and receives the solution.
    PartPcgResult solve(std::span<const float* const> b, std::span<float* const> x, double tolerance, int max_iterations);

private:
    struct Part;
    /// Sums each part's two partials in part order (one synchronisation of every stream).
    void reduce(double& first, double& second);

    std::vector<std::unique_ptr<Part>> part_;
    HaloExchange& halo_;
};

}  // namespace weft::cuda::multi
