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
/// row's inverse 3×3 diagonal block: local to its part) or the multilevel Schwarz preconditioner
/// across the parts (PartSystem::schwarz: level 1 gathered from every part at each apply, so it is
/// the single-GPU preconditioner). Rows marked fixed (pinned vertices) are
/// filtered as in the single-GPU solve: their residual and product are zero, so their unknowns keep
/// their start values. Convergence is measured as on one GPU: rᵀM⁻¹r against the larger of
/// bᵀM⁻¹b (free rows) and the start's r₀ᵀM⁻¹r₀.
///
/// The loop runs on the devices: each part sums its partials in a fixed order, stores its two sums
/// into every part's gather buffer (peer stores), and every part adds the G pairs in part order and
/// takes α, β and the convergence test itself, so all parts hold the same scalars and stop together
/// with no host in the loop. Two forms of the loop give the same bits (every sum over the same rows
/// in the same order): where every part has its own GPU, one cooperative kernel per GPU runs the
/// whole loop, the parts meeting through peer memory (multi/part_pcg_loop.h); otherwise (parts
/// sharing a GPU, the test mode) batches of iterations are captured once as a CUDA graph across the
/// parts' devices and replayed, a stopped solve's remaining kernels returning at once, and the host
/// reads the scalars between batches only. The same bits on every run for a given partition.

#include <cuda_runtime_api.h>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "device_array.h"
#include "kernels.h"
#include "multi/all_gather.h"
#include "multi/contact_mirror.h"
#include "multi/halo_exchange.h"
#include "weft/backend/cg_energy_stop.h"
#include "multi/part_system.h"
#include "weft/cuda/cuda_backend.h"

namespace weft::cuda::multi {

struct PartPcgResult {
    int iterations = 0;
    double relative_residual = 0.0;  ///< sqrt(rᵀM⁻¹r / reference) at the end
    bool converged = false;
};

/// The scalars of the loop, one copy per part (all parts compute the same values).
struct PartPcgScalars {
    double gamma = 0.0;     ///< rᵀu of the current iterate
    double reference = 0.0; ///< max(bᵀM⁻¹b, r₀ᵀM⁻¹r₀): what the residual is measured against
    double alpha = 0.0, beta = 0.0;
    double tolerance2 = 0.0;  ///< squared relative tolerance
    double energy_floor = 0.0;  ///< J: the energy test (weft/backend/cg_energy_stop.h); 0 = off
    CgEnergyWindow energy{};    ///< the falls of Φ it sums
    double relative = 0.0;    ///< sqrt(γ/reference)
    int iterations = 0;
    int max_iterations = 0;
    int running = 0;          ///< 1 while the loop goes on
    int converged = 0;
};

class PartPcg {
public:
    /// Over the parts' systems (part p on systems[p].device, enqueuing on systems[p].stream, the
    /// streams `halo` was made with) and their halo exchange. Allocates the work vectors; enables
    /// peer access between every two devices. The systems' arrays must outlive the solver.
    PartPcg(std::span<const PartSystem> systems, HaloExchange& halo);
    ~PartPcg();
    PartPcg(const PartPcg&) = delete;
    PartPcg& operator=(const PartPcg&) = delete;

    /// The energy test's floor for the next solves, J (cg_energy_floor; 0 turns it off): past the
    /// residual test the loop goes on while Φ fell by more than this over its last kCgEnergyDelay
    /// iterations, as on one GPU.
    void set_energy_floor(double joules) { energy_floor_ = joules; }

    /// Solves A·x = b to sqrt(rᵀM⁻¹r / reference) ≤ tolerance or `max_iterations`. b and x are each
    /// part's local vectors (stride local, owned entries read; x's ghosts are overwritten), on the
    /// part's device; x holds the start and receives the solution, its ghosts included (exchanged at the
    /// end, on the parts' streams). The iterations run in graphs of
    /// `batch` (even) iterations, captured at the first solve for these vectors.
    PartPcgResult solve(std::span<const float* const> b, std::span<float* const> x, double tolerance, int max_iterations,
                        int batch = 16);

    /// Proximity contacts across the parts (PartSystem::contacts): before each product the vector's
    /// values at every part's contact vertices go into `mirror`'s whole-size copies, which the pair
    /// pass reads. Null: no contacts. Set before the first solve (the graphs hold it).
    void set_contact_mirror(ContactMirror* mirror) { contacts_ = mirror; }
    /// Batches of iterations as one multi-device CUDA graph each (default), or launched directly (the
    /// same kernels and results: for tools that cannot follow graphs).
    void set_use_graph(bool enabled) { use_graph_ = enabled; }
    /// How the loop runs: OneLaunch (one cooperative kernel per GPU) where every part has its own
    /// GPU and the GPUs launch cooperatively, else the batches; PerKernel always the batches; Auto
    /// as OneLaunch. Takes effect at the next solve.
    void set_loop(PcgLoop loop) { loop_ = loop; }
    /// Whether the next solve runs one launch per GPU.
    [[nodiscard]] bool one_launch() const { return loop_ != PcgLoop::PerKernel && one_launch_possible_; }
    /// Device memory the solver holds on part p's device, bytes.
    [[nodiscard]] std::size_t memory_bytes(std::size_t p) const;

private:
    struct Part;
    /// Exchanges u, then w = filter(A·u) with the partial wᵀu on every part (`check`: nothing once
    /// the loop has stopped).
    void enqueue_product(int check);
    /// The contacts' share of a product of `x` (one local vector per part): its values at the
    /// contact vertices into the whole-size copies, then every part's pair pass.
    void enqueue_contacts(std::span<float* const> x, int check);
    /// u = M⁻¹r (`in`: r as it is, or filter(b) into r first) by the Schwarz levels across the
    /// parts, with the partial rᵀu into `slot` (`check`: nothing once the loop has stopped).
    void enqueue_schwarz(SchwarzInput in, int slot, int check);
    /// Enqueues one iteration on every part (update, exchange, product, reduction, scalars), its
    /// reduction writing the gather buffers of `parity`.
    void enqueue_iteration(std::span<float* const> x, int parity);
    /// Each part's two partial sums into every part's gather buffer `parity`, then each part's
    /// scalars from them (`mode`: γ and the reference of the start, γ' and δ of an iteration, or the
    /// first α).
    void enqueue_reduction(int parity, int mode);
    /// The iterations as one cooperative kernel per GPU, from the start's scalars; returns part 0's
    /// scalars at the end. Throws weft::Error naming the part a GPU stopped waiting for.
    PartPcgScalars run_one_launch(std::span<float* const> x);
    /// WEFT_CUDA_PCG_CLOCK=1 (profiling): each part's time per phase of the one-launch loop, to stderr.
    void print_clock() const;

    std::vector<std::unique_ptr<Part>> part_;
    HaloExchange& halo_;
    double energy_floor_ = 0.0;  // J; set_energy_floor
    bool schwarz_ = false;                 // the Schwarz preconditioner across the parts, else block-Jacobi
    std::unique_ptr<AllGather> level1_;    // its level 1, gathered every apply
    cudaGraphExec_t graph_ = nullptr;
    std::vector<float*> graph_x_;  // the vectors the graph was captured with
    int graph_batch_ = 0;
    long long graph_kernels_ = 0;  // kernel nodes of the captured batch (counted per launch)
    bool use_graph_ = true;
    PcgLoop loop_ = PcgLoop::Auto;
    bool one_launch_possible_ = false;  // every part on its own device, at most kLoopMaxParts
    bool clock_ = false;                // WEFT_CUDA_PCG_CLOCK=1: time the one-launch loop's phases
    ContactMirror* contacts_ = nullptr;
};

}  // namespace weft::cuda::multi
