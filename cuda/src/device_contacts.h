#pragma once
// The proximity contacts of one substep on the device (docs/collisions.md, step 1): the list the
// narrow phase fills (pair springs, weft/physics/pair_contact.h) and what the solve derives from it,
// P-Cloth's "dynamic matrix" in the factored form of the CPU (runtime/src/cpu/contact_terms.h): per
// pair one 3×3 block C and its right-hand side, per cloth vertex its incidence list in pair order.
//
// Sizes. Every array is sized by a host-side capacity and the number of pairs in use lives in device
// memory, so launches are sized by the capacity and kernels stop at the count: a substep with more or
// fewer contacts replays the same CUDA graph. Only a larger capacity re-captures it. With capacity 0
// (the default: a scene without contacts) nothing is allocated and nothing is launched.
//
// Host synchronisation: none in the step (the incidence build, the evaluation and the products are
// stream-ordered kernels). Growing waits for the stream before it frees the old arrays, and the
// interim host upload waits for it before it rewrites its pinned mirror (the stream is idle then
// anyway: every substep ends with the stats read-back).

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <span>

#include "device_array.h"
#include "weft/backend/buffer_trim.h"
#include "device_params.h"
#include "weft/types.h"

namespace weft::collision {
struct ProximityContact;
}

namespace weft::cuda {

/// One contact, 64 bytes: the gap vector g = Σ_j weight[j]·x[vertex[j]] held along `normal`. The
/// layout of the GPU narrow phase's output (cuda/src/collision/proximity_gpu.h), so that it can write
/// straight into this list; four 16-byte loads read a whole contact.
struct DeviceContact {
    std::uint32_t vertex[4];  ///< cloth vertices < n, kinematic vertices n + k
    float weight[4];          ///< vertex–face (1, −(1−u−v), −u, −v); edge–edge (1−a, a, −(1−b), −b)
    float normal[3];          ///< unit, from the second primitive towards the first
    float gap;                ///< n·g at the start of the substep, m (not read by the solve)
    float thickness;          ///< m
    float stiffness;          ///< N/m
    float friction;           ///< Coulomb coefficient
    /// Index of the candidate it came from (bits below kInactiveContactBit; not read by the solve),
    /// and the three flags above it.
    std::uint32_t pair;
};
static_assert(sizeof(DeviceContact) == 64, "four 16-byte loads per contact");

/// DeviceContact::pair flag: an offset contact (weft/physics/offset_contact.h; collision.mode =
/// "offset"), whose closest points, weights and normal the solve recomputes at every evaluation and
/// whose `thickness` is the contact radius.
inline constexpr std::uint32_t kOffsetContactBit = 1U << 31;
/// DeviceContact::pair flag of an offset contact: edge–edge (vertices 0–1 against 2–3) rather than
/// vertex–face (vertex 0 against the triangle 1–2–3).
inline constexpr std::uint32_t kEdgeEdgeContactBit = 1U << 30;
/// DeviceContact::pair flag of an offset contact, set by each evaluation: the pair is beyond its
/// contact radius at the linearisation point, so its right-hand side and block are exactly zero. The
/// incidence rebuilt after the evaluation leaves it out and the pair pass skips it: the CG pays only
/// for pairs in contact, not for every pair whose bounds let it come close (most of them).
inline constexpr std::uint32_t kInactiveContactBit = 1U << 29;

/// The contact arrays as raw pointers, inside DeviceView (passed by value to every kernel).
struct ContactView {
    std::uint32_t capacity = 0;            ///< pairs the arrays hold; 0: the solve has no contact path
    std::uint32_t kinematic_capacity = 0;  ///< component stride of the kinematic arrays
    /// Written by the solve only for offset contacts (their weights follow the closest points).
    DeviceContact* list = nullptr;
    const std::uint32_t* count = nullptr;  ///< pairs in use this substep (clamped to the capacity)
    /// Kinematic vertices (mesh colliders) at t + h and their velocities, SoA with stride
    /// `kinematic_capacity`: component c of kinematic vertex k at [c·kinematic_capacity + k].
    const float* kinematic_x1 = nullptr;
    const float* kinematic_v = nullptr;
    // Incidence of the cloth vertices, rebuilt every substep: vertex i's entries 4·pair + corner at
    // [start[i], start[i + 1]), in pair order.
    std::uint32_t* start = nullptr;
    std::uint32_t* entries = nullptr;  ///< 4·capacity
    /// The weight w_i of each entry, in the incidence's order (filled with it): a row's gathers read
    /// it in sequence instead of one pair's record at a time.
    float* entry_weight = nullptr;     ///< 4·capacity
    /// Part mode (the multi-GPU solver): the list names the whole model's vertices (cloth vertices
    /// below `cloth_vertices`, kinematic ones after), and `row_of` maps a whole cloth vertex to this
    /// part's row (~0 where another part owns it); the incidence covers the part's rows. Null on one
    /// GPU, where the list's cloth vertices are the solver's rows.
    const std::uint32_t* row_of = nullptr;
    std::uint32_t cloth_vertices = 0;
    /// Part mode: per pair, where each corner's value is read in the product's pair pass (row_of
    /// looked up once a substep instead of four times a pair at every CG iteration): the part's row,
    /// kCornerFromCopy | the whole vertex (another part's, from the whole-size copy), or kCornerNone
    /// (a kinematic vertex). Null on one GPU.
    const uint4* corner_source = nullptr;
    // Per pair, written at each Newton iteration (SoA, stride capacity): C = −h·D − h²·K (9 floats,
    // row-major) and its right-hand side h·F + h²·K·Σ w_j (v_k − w_k)_j (3).
    float* block = nullptr;
    float* rhs = nullptr;
    /// Per pair, the product C·Σ_j w_j x_j of the current SpMV, one float4 (x, y, z, 0) a pair: the
    /// rows' gathers read it at random, one sector an entry (3 with SoA).
    float4* product = nullptr;
    /// One bit a pair (word p/32, bit p%32), written by each evaluation: the pair is in the solve
    /// (not kInactiveContactBit). The pair pass reads it instead of the pair's 64-byte record, whose
    /// second sector held the flag: a quarter of the pass's traffic (docs/multi-gpu.md).
    std::uint32_t* active_mask = nullptr;
    /// Per row, written at each SpMV after the pair pass (contact_row_sums): the row's sum of
    /// w_i·product over its incidence, SoA with component stride `vertices` (the solver's n).
    float* row_sum = nullptr;
    std::uint32_t vertices = 0;
};

/// ContactView::corner_source's markers.
inline constexpr std::uint32_t kCornerFromCopy = 0x80000000u;
inline constexpr std::uint32_t kCornerNone = 0xFFFFFFFFu;

/// The incidence build's scratch (launch_contact_incidence): the corners' row keys, double-buffered
/// for the radix sort, the ids the sort carries along (its second buffer is ContactView::entries),
/// and the sort's own storage.
struct ContactSortScratch {
    std::uint32_t* keys[2] = {nullptr, nullptr};  ///< 4·capacity each
    std::uint32_t* ids = nullptr;                 ///< 4·capacity
    void* storage = nullptr;
    std::size_t storage_bytes = 0;
    std::uint32_t corner_slots = 0;  ///< 4·capacity
    int key_bits = 1;                ///< bits of the largest key, n (the slots not in use)
};

/// Writable device pointers into the inputs of the contact list, for producers on the device (the GPU
/// narrow phase, device_collisions.h): the count, the list, the kinematic arrays (SoA with stride
/// `kinematic_capacity`; null when it is 0).
struct ContactInputs {
    std::uint32_t* count = nullptr;
    DeviceContact* list = nullptr;
    float* kinematic_x1 = nullptr;
    float* kinematic_v = nullptr;
    std::uint32_t capacity = 0;
    std::uint32_t kinematic_capacity = 0;
};

/// Owns the contact arrays of one DeviceSolver. Grows when a caller reserves or uploads more than
/// fits; comes down when a window of kTrimPeriod reserves needed far less than it holds (the trim
/// policy of weft/backend/buffer_trim.h: a flood of contacts in one fold is not kept for the rest of
/// the run). Either is an allocation, outside the step.
class DeviceContacts {
public:
    /// About the device bytes a pair's capacity holds: its record (64), incidence entries, weights
    /// and sort slots (4 corners), and its block, right-hand side and product (16 floats).
    static constexpr std::size_t kBytesPerPair = 64 + 4 * (4 + 4 + 8 + 4 + 4) + 16 * 4;

    /// Makes room for `pairs` contacts and `kinematic` kinematic vertices over `n` cloth vertices,
    /// and records `pairs` in the trim window (at a window's end the list may be cut to twice its
    /// peak); returns true when it reallocated (the caller's view and graph are then stale). Contents
    /// are kept only where nothing was reallocated; the count is 0 after a reallocation.
    bool reserve(std::size_t pairs, std::size_t kinematic, std::uint32_t n, cudaStream_t stream);
    /// Times the list was cut back by the trim window.
    [[nodiscard]] int trims() const { return trims_; }
    /// Uploads `contacts` (vertex ids < n + kinematic count) and the kinematic poses at t + h and
    /// velocities, in one host-to-device copy on `stream`; grows first if needed (returns true then).
    /// Throws weft::Error for a vertex id out of range or mismatched kinematic arrays.
    bool upload(std::span<const weft::collision::ProximityContact> contacts, std::span<const Vec3d> kinematic_x1,
                std::span<const Vec3d> kinematic_v, std::uint32_t n, cudaStream_t stream);
    /// Frees everything (the model was rebuilt: vertex ids changed meaning).
    void release();

    [[nodiscard]] ContactView view() const { return view_; }
    /// The same arrays, writable (they live in device memory this object owns).
    [[nodiscard]] ContactInputs inputs() {
        return {const_cast<std::uint32_t*>(view_.count), const_cast<DeviceContact*>(view_.list),
                const_cast<float*>(view_.kinematic_x1), const_cast<float*>(view_.kinematic_v), view_.capacity,
                view_.kinematic_capacity};
    }
    [[nodiscard]] std::size_t capacity() const { return view_.capacity; }
    [[nodiscard]] std::size_t bytes() const { return ledger_.total(); }
    /// Scratch of the incidence build (sized for the capacity and the n of the last reserve).
    [[nodiscard]] const ContactSortScratch& sort_scratch() const { return sort_scratch_; }

private:
    MemoryLedger ledger_;
    ContactView view_{};
    // The list, the count and the kinematic arrays in one block, mirrored in pinned host memory, so
    // that an upload is one copy.
    DeviceArray<unsigned char> input_;
    PinnedArray<unsigned char> host_input_;
    std::size_t count_offset_ = 0, kinematic_offset_ = 0;
    DeviceArray<std::uint32_t> start_, entries_;
    DeviceArray<float> row_sum_;
    DeviceArray<std::uint32_t> sort_keys_, sort_ids_;  // 2 and 1 × 4·capacity
    DeviceArray<float> per_pair_;                      // block, rhs (SoA), product (float4): 16 floats a pair
    DeviceArray<float> entry_weight_;                  // ContactView::entry_weight
    DeviceArray<std::uint32_t> active_mask_;           // ContactView::active_mask
    DeviceArray<unsigned char> sort_storage_;
    ContactSortScratch sort_scratch_{};
    CapacityTrim trim_;  // the pairs each reserve needed (weft/backend/buffer_trim.h)
    int trims_ = 0;
};

}  // namespace weft::cuda
