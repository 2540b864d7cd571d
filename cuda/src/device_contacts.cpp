// The contact arrays of the device solve (device_contacts.h): allocation, growth and the host upload.
#include "device_contacts.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>

#include "weft/backend/proximity_contact.h"
#include "kernels.h"
#include "weft/error.h"

namespace weft::cuda {
namespace {

std::size_t align16(std::size_t bytes) { return (bytes + 15) / 16 * 16; }

/// Capacities grow to the next power of two (at least 256) so that a slowly rising contact count
/// reallocates, and re-captures the graph, only a handful of times.
std::size_t grown(std::size_t needed) { return needed == 0 ? 0 : std::max<std::size_t>(256, std::bit_ceil(needed)); }

}  // namespace

bool DeviceContacts::reserve(std::size_t pairs, std::size_t kinematic, std::uint32_t n, cudaStream_t stream) {
    const bool list_fits = pairs <= view_.capacity;
    const bool kinematic_fits = kinematic <= view_.kinematic_capacity;
    // The trim window: a capacity far above what a window of reserves needed is cut to twice the
    // window's peak (never below what this call needs, nor below 256).
    std::size_t cut = 0;
    if (view_.capacity > 0)
        if (const std::size_t kept = trim_.record(pairs, view_.capacity, kBytesPerPair, 256)) {
            const std::size_t to = grown(std::max(kept, pairs));
            if (to < view_.capacity) cut = to;
        }
    if (list_fits && kinematic_fits && cut == 0) return false;
    if (pairs > 0xffffffffu / 16)
        throw Error("CUDA backend: " + std::to_string(pairs) + " proximity contacts is more than the solver indexes");
    // Nothing may still read or write the arrays being replaced.
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    const std::size_t capacity = cut != 0                             ? cut
                                 : list_fits && view_.capacity > 0 ? view_.capacity
                                                                   : grown(std::max<std::size_t>(pairs, 1));
    if (cut != 0) ++trims_;
    const std::size_t kinematic_capacity = kinematic_fits ? view_.kinematic_capacity : grown(kinematic);
    release();

    // One block for what an upload writes: count, list, kinematic positions and velocities.
    count_offset_ = 0;
    const std::size_t list_offset = 16;
    kinematic_offset_ = list_offset + align16(capacity * sizeof(DeviceContact));
    const std::size_t input_bytes = kinematic_offset_ + 2 * 3 * kinematic_capacity * sizeof(float);
    input_.allocate(input_bytes, ledger_, "proximity contacts");
    host_input_.allocate(input_bytes);
    std::memset(host_input_.get(), 0, input_bytes);
    WEFT_CUDA_CHECK(cudaMemsetAsync(input_.get(), 0, input_bytes, stream));  // count 0

    start_.allocate(n + 1, ledger_, "proximity contacts");
    row_sum_.allocate(3 * std::size_t{std::max(n, 1U)}, ledger_, "proximity contacts");
    entries_.allocate(4 * capacity, ledger_, "proximity contacts");
    per_pair_.allocate(16 * capacity, ledger_, "proximity contacts");
    entry_weight_.allocate(4 * capacity, ledger_, "proximity contacts");
    active_mask_.allocate((capacity + 31) / 32 + 1, ledger_, "proximity contacts");
    const auto corner_slots = static_cast<std::uint32_t>(4 * capacity);
    const int key_bits = std::max(1, static_cast<int>(std::bit_width(n)));  // n itself keys the unused slots
    sort_keys_.allocate(2 * std::size_t{corner_slots}, ledger_, "proximity contacts: incidence sort");
    sort_ids_.allocate(corner_slots, ledger_, "proximity contacts: incidence sort");
    sort_storage_.allocate(std::max<std::size_t>(1, contact_sort_storage_bytes(corner_slots, key_bits)), ledger_,
                           "proximity contacts: incidence sort");
    sort_scratch_ = {{sort_keys_.get(), sort_keys_.get() + corner_slots}, sort_ids_.get(), sort_storage_.get(),
                     sort_storage_.bytes(), corner_slots, key_bits};
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));

    ContactView& v = view_;
    v.capacity = static_cast<std::uint32_t>(capacity);
    v.kinematic_capacity = static_cast<std::uint32_t>(kinematic_capacity);
    unsigned char* base = input_.get();
    v.count = reinterpret_cast<const std::uint32_t*>(base + count_offset_);
    v.list = reinterpret_cast<DeviceContact*>(base + list_offset);
    v.kinematic_x1 = kinematic_capacity > 0 ? reinterpret_cast<const float*>(base + kinematic_offset_) : nullptr;
    v.kinematic_v = kinematic_capacity > 0 ? v.kinematic_x1 + 3 * kinematic_capacity : nullptr;
    v.start = start_.get();
    v.entries = entries_.get();
    v.row_sum = row_sum_.get();
    v.vertices = n;
    v.block = per_pair_.get();
    v.rhs = v.block + 9 * capacity;
    v.product = reinterpret_cast<float4*>(v.rhs + 3 * capacity);  // 12·capacity floats in: 16-byte aligned
    v.entry_weight = entry_weight_.get();
    v.active_mask = active_mask_.get();
    return true;
}

bool DeviceContacts::upload(std::span<const weft::collision::ProximityContact> contacts, std::span<const Vec3d> kinematic_x1,
                            std::span<const Vec3d> kinematic_v, std::uint32_t n, cudaStream_t stream) {
    if (kinematic_x1.size() != kinematic_v.size())
        throw Error("set_contacts: " + std::to_string(kinematic_x1.size()) + " kinematic positions but " +
                    std::to_string(kinematic_v.size()) + " velocities");
    const std::size_t nk = kinematic_x1.size();
    for (std::size_t p = 0; p < contacts.size(); ++p)
        for (std::uint32_t id : contacts[p].vertex)
            if (id >= n + nk)
                throw Error("set_contacts: contact " + std::to_string(p) + " names vertex " + std::to_string(id) + ", but there are " +
                            std::to_string(n) + " cloth and " + std::to_string(nk) + " kinematic vertices");
    if (contacts.empty() && view_.capacity == 0) return false;  // no contact path to feed: leave it off
    const bool grew = reserve(contacts.size(), nk, n, stream);
    // The pinned mirror may still feed the last upload's copy.
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));

    unsigned char* base = host_input_.get();
    const auto count = static_cast<std::uint32_t>(contacts.size());
    std::memcpy(base + count_offset_, &count, sizeof count);
    auto* list = reinterpret_cast<DeviceContact*>(base + 16);
    for (std::size_t p = 0; p < contacts.size(); ++p) {
        const weft::collision::ProximityContact& c = contacts[p];
        DeviceContact& d = list[p];
        for (int j = 0; j < 4; ++j) {
            d.vertex[j] = c.vertex[j];
            d.weight[j] = static_cast<float>(c.weight[j]);
        }
        for (int k = 0; k < 3; ++k) d.normal[k] = static_cast<float>(c.normal[k]);
        d.gap = static_cast<float>(c.gap);
        d.thickness = static_cast<float>(c.thickness);
        d.stiffness = static_cast<float>(c.stiffness);
        d.friction = static_cast<float>(c.friction);
        d.pair = static_cast<std::uint32_t>(p);
    }
    auto* kin = reinterpret_cast<float*>(base + kinematic_offset_);
    const std::size_t stride = view_.kinematic_capacity;
    for (std::size_t k = 0; k < nk; ++k)
        for (int c = 0; c < 3; ++c) {
            kin[c * stride + k] = static_cast<float>(kinematic_x1[k][c]);
            kin[(3 + c) * stride + k] = static_cast<float>(kinematic_v[k][c]);
        }
    WEFT_CUDA_CHECK(cudaMemcpyAsync(input_.get(), host_input_.get(), host_input_.size(), cudaMemcpyHostToDevice, stream));
    return grew;
}

void DeviceContacts::release() {
    input_ = {};
    start_ = {};
    row_sum_ = {};
    entries_ = {};
    sort_keys_ = {};
    sort_ids_ = {};
    per_pair_ = {};
    entry_weight_ = {};
    active_mask_ = {};
    sort_storage_ = {};
    sort_scratch_ = {};
    ledger_.clear();
    view_ = ContactView{};
    trim_ = {};
}

}  // namespace weft::cuda
