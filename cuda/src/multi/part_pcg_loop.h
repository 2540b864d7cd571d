#pragma once
/// @file
/// The CG across parts in one cooperative launch per GPU (docs/multi-gpu.md, "The CG iteration").
/// The batches of PartPcg run about a dozen kernels per part and iteration, with the parts' streams
/// waiting on each other's events three times an iteration; on a wound sheet whose iteration is
/// ~100 µs of work, those launches and cross-device waits cost as much as the work. Here each GPU runs
/// the whole loop in one kernel: grid-wide barriers inside the GPU, and between the GPUs a meeting
/// through peer memory (each part stores its arrival count into every other part's flags with a
/// system-scope release and waits for theirs with acquire loads). The exchanges become peer stores
/// from inside the kernel: u's ghosts (the halo), u at the contact vertices other parts read (the
/// contact mirror), level 1 of the Schwarz preconditioner (the all-gather), and the two sums.
///
/// It computes every value as the batches do (multi/part_pcg_terms.cuh, the same row blocks and
/// sum trees): the same bits. It needs every part on its own device (parts sharing a GPU could not
/// all be resident at once) and cooperative launch. A part that does not arrive within the timeout
/// (a fault on another GPU) stops the loop on every GPU, and the solve reports which part it waited
/// for, instead of hanging.

#include <cuda_runtime_api.h>

#include <cstdint>

#include "device_view.h"
#include "loop_clock.h"
#include "multi/part_pcg.h"
#include "multi/part_system.h"

namespace weft::cuda::multi {

inline constexpr unsigned kLoopMaxParts = 8;

/// A run of u's ghost values for another part (HaloExchange::Route with the receiver's vector).
struct LoopHaloRoute {
    const std::uint32_t* send = nullptr;  ///< the sender's owned rows
    std::uint32_t count = 0;
    float* to = nullptr;                  ///< the receiver's u (peer memory)
    std::uint32_t to_stride = 0;          ///< the receiver's local vertex count
    std::uint32_t to_first = 0;
};

/// Everything one part's loop reads and writes (device pointers; peer pointers where named).
struct PartLoopView {
    PartSystem a;               ///< the part's system (a.schwarz is a host pointer: unused on the device)
    DeviceView schwarz;         ///< with `use_schwarz`: the part's solver view, r = this part's r
    int use_schwarz = 0;
    const float* precond = nullptr;  ///< block-Jacobi inverse (without `use_schwarz`)
    float *x = nullptr, *r = nullptr, *u = nullptr, *w = nullptr, *p = nullptr, *s = nullptr;
    double* partials = nullptr;      ///< 2 per row block
    unsigned row_blocks = 0;         ///< ⌈owned / kBlockSize⌉
    PartPcgScalars* scalars = nullptr;
    unsigned part = 0, parts = 0;
    // Level 1 of the Schwarz preconditioner: this part's run of its values into every other part's.
    std::uint32_t level1_begin = 0, level1_end = 0;
    float* level1_to[kLoopMaxParts] = {};
    // u's ghosts for the other parts.
    LoopHaloRoute halo[kLoopMaxParts] = {};
    unsigned halo_routes = 0;
    // u at this part's vertices that other parts' contacts read (ContactMirror::push_across).
    const std::uint32_t* across = nullptr;  ///< rows, their count at [a.owned]; null: no contacts
    const std::uint32_t* global = nullptr;  ///< whole id of each owned row
    float* mirror_to[kLoopMaxParts] = {};   ///< the other parts' whole-size copies of u
    unsigned mirror_targets = 0;
    std::uint32_t whole = 0;
    const float* mirror_copy = nullptr;     ///< this part's own copy (what its pair pass reads)
    // The sums and the meetings.
    double* gather_of[kLoopMaxParts] = {};  ///< every part's gather buffer (2 parities × 2 sums × parts)
    /// Every part's flags, parts + 2 entries: entry q the count of meetings part q has reached;
    /// entry `parts` 1 + a part that stopped and told this one; entry `parts + 1` 1 + the part this
    /// one stopped waiting for (0: it did not stop). Zeroed before each solve.
    unsigned* flags_of[kLoopMaxParts] = {};
    unsigned long long timeout_ns = 0;
    /// Non-null: the loop clock (loop_clock.h, kLoopClockEntries in device memory). For profiling.
    long long* clock = nullptr;
};

/// The cooperative grid for `v` on `device` (every block resident at once, no more than the work
/// needs); 0 where the device cannot launch cooperatively.
[[nodiscard]] int part_pcg_loop_grid(const PartLoopView& v, int device);
/// Runs the iterations from the scalars the start left until they say stop (on `stream`, the
/// part's; every other part's loop must be launched too, or this one waits out the timeout).
void launch_part_pcg_loop(const PartLoopView& v, int grid, cudaStream_t stream);

}  // namespace weft::cuda::multi
