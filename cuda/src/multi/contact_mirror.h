#pragma once
/// @file
/// Contacts across GPUs (docs/multi-gpu.md, "Collisions"): a contact couples four vertices that may
/// lie on different GPUs, so every part's GPU keeps whole-size copies of the few vectors a contact
/// reads: the linearisation point (x₀, w_k) and velocity v_k at each Newton iteration, and the CG's
/// vector at each product. Only contact vertices are filled: each part stores its owned vertices that
/// are in a contact into every part's copy (peer stores), in the whole model's numbering, so the
/// single-GPU contact kernels read a copy as they read the solver's own vectors.
///
/// The CG's vector is pushed far less: a part reads its own vertices from its own vector, so each
/// part pushes only its vertices that another part's contacts name (`push_across`), those of the
/// contacts across the cut.
///
/// Ordered as the halo exchange (multi/halo_exchange.h): each push follows the work enqueued so far
/// on its sender's stream and on every receiver's, and each part's later work waits for the pushes.

#include <cuda_runtime_api.h>

#include <cstdint>
#include <span>
#include <vector>

#include "device_array.h"
#include "device_contacts.h"
#include "multi/peer_round.h"

namespace weft::cuda::multi {

class ContactMirror {
public:
    enum Vector : int { kX0 = 0, kWk = 1, kVk = 2, kCg = 3, kVectors = 4 };

    /// Part p on `devices[p]` with `streams[p]`; `global_of_owned[p]` (device memory on part p's
    /// device) its owned vertices' whole ids, `owned[p]` their count; `whole` the model's vertices.
    ContactMirror(std::span<const int> devices, std::span<const cudaStream_t> streams,
                  std::span<const std::uint32_t* const> global_of_owned, std::span<const std::uint32_t> owned,
                  std::uint32_t whole);
    ~ContactMirror();
    ContactMirror(const ContactMirror&) = delete;
    ContactMirror& operator=(const ContactMirror&) = delete;

    /// Enqueued on every part after its contact list and incidence are built (`contacts[p]`, in part
    /// mode: row_of, cloth_vertices): the part's owned rows that are in some contact become what
    /// `push` sends, and those that another part's contacts name what `push_across` sends.
    void list_contact_vertices(std::span<const ContactView> contacts);
    /// Part p's values of `vectors[p]` (its local SoA vector, component stride `stride[p]`) at its
    /// contact vertices into copy `which` on every part's GPU.
    void push(Vector which, std::span<const float* const> vectors, std::span<const std::uint32_t> stride);
    /// As `push`, but only the vertices other parts' contacts name, and only into other parts'
    /// copies: for readers that take their own vertices from their own vector.
    void push_across(Vector which, std::span<const float* const> vectors, std::span<const std::uint32_t> stride);
    /// Part p's copy `which` (device memory on its GPU): SoA, component stride whole().
    [[nodiscard]] float* copy(std::size_t p, Vector which) const;
    [[nodiscard]] std::uint32_t whole() const { return whole_; }
    /// What part p's `push_across` sends, for loops that push from inside their own kernels: its
    /// owned rows that other parts' contacts name (device memory; their count at [owned(p)]), and
    /// every owned row's whole id.
    [[nodiscard]] const std::uint32_t* across_rows(std::size_t p) const { return part_.at(p).across.get(); }
    [[nodiscard]] const std::uint32_t* global_ids(std::size_t p) const { return part_.at(p).global; }
    [[nodiscard]] std::uint32_t owned(std::size_t p) const { return part_.at(p).owned; }
    [[nodiscard]] std::size_t memory_bytes() const { return ledger_.total(); }

private:
    struct Part {
        int device = 0;
        cudaStream_t stream = nullptr;
        const std::uint32_t* global = nullptr;
        std::uint32_t owned = 0;
        DeviceArray<float> copies;          // kVectors whole-size SoA vectors
        DeviceArray<std::uint32_t> list;    // owned rows in a contact, then (last entry) their count
        DeviceArray<std::uint32_t> across;  // owned rows another part's contacts name, then their count
        DeviceArray<std::uint8_t> named;    // whole-size: 1 where this part's contacts name another's vertex
        DeviceArray<const std::uint8_t*> others;  // the other parts' `named` (peer pointers)
        cudaEvent_t marked = nullptr;
    };
    /// Every part's push of `which`: its `list` rows into every part's copy, or (`across`) its
    /// `across` rows into the other parts' copies.
    void enqueue_push(Vector which, std::span<const float* const> vectors, std::span<const std::uint32_t> stride, bool across);
    std::vector<Part> part_;
    PeerRound round_;  // the pushes
    std::uint32_t whole_ = 0;
    MemoryLedger ledger_;
};

}  // namespace weft::cuda::multi
