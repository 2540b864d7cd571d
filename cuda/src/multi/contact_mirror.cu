// Whole-size copies of the vectors contacts read, on every part's GPU (multi/contact_mirror.h).
#include "multi/contact_mirror.h"

#include <algorithm>
#include <string>

#include "cuda_check.h"
#include "contact_terms.cuh"
#include "kernels.h"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

/// Rows with a non-empty incidence, appended in any order (each is pushed to its own place, so the
/// order changes no value); the count lives after the list.
__global__ void list_kernel(const std::uint32_t* start, std::uint32_t owned, std::uint32_t* list) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= owned || start[i + 1] == start[i]) return;
    list[atomicAdd(&list[owned], 1u)] = i;
}

/// named[v] = 1 for every cloth vertex of this part's contacts that another part owns.
__global__ void name_kernel(ContactView c, std::uint8_t* named) {
    const std::uint32_t m = contact_count(c);
    for (std::uint32_t p = blockIdx.x * blockDim.x + threadIdx.x; p < m; p += gridDim.x * blockDim.x)
        for (int j = 0; j < 4; ++j) {
            const std::uint32_t v = c.list[p].vertex[j];
            if (v < c.cloth_vertices && c.row_of[v] == ~0U) named[v] = 1;
        }
}

/// The owned rows in a contact that some other part's contacts name (`others`: their flags, read
/// across NVLink), appended in any order; the count lives after the list.
__global__ void across_kernel(const std::uint32_t* start, std::uint32_t owned, const std::uint32_t* global,
                              const std::uint8_t* const* others, std::uint32_t other_count, std::uint32_t* across) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= owned || start[i + 1] == start[i]) return;
    const std::uint32_t g = global[i];
    for (std::uint32_t q = 0; q < other_count; ++q)
        if (others[q][g] != 0) {
            across[atomicAdd(&across[owned], 1u)] = i;
            return;
        }
}

__global__ void push_kernel(const float* from, std::uint32_t stride, const std::uint32_t* list, std::uint32_t owned,
                            const std::uint32_t* global, float* to, std::uint32_t whole) {
    const std::uint32_t count = list[owned];
    for (std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x; k < count; k += gridDim.x * blockDim.x) {
        const std::uint32_t i = list[k], g = global[i];
        for (std::uint32_t c = 0; c < 3; ++c) to[c * whole + g] = from[c * stride + i];
    }
}

}  // namespace

ContactMirror::ContactMirror(std::span<const int> devices, std::span<const cudaStream_t> streams,
                             std::span<const std::uint32_t* const> global_of_owned, std::span<const std::uint32_t> owned,
                             std::uint32_t whole)
    : round_(devices, streams), whole_(whole) {
    const std::size_t parts = devices.size();
    if (streams.size() != parts || global_of_owned.size() != parts || owned.size() != parts)
        throw Error("ContactMirror: " + std::to_string(parts) + " devices, " + std::to_string(streams.size()) + " streams, " +
                    std::to_string(global_of_owned.size()) + " index lists");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    part_.resize(parts);
    for (std::size_t p = 0; p < parts; ++p) {
        Part& part = part_[p];
        part.device = devices[p];
        part.stream = streams[p];
        part.global = global_of_owned[p];
        part.owned = owned[p];
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        part.copies.allocate(std::size_t{kVectors} * 3 * whole, ledger_, "contact mirrors");
        part.copies.zero(part.stream);
        part.list.allocate(std::size_t{part.owned} + 1, ledger_, "contact mirrors");
        part.list.zero(part.stream);
        part.across.allocate(std::size_t{part.owned} + 1, ledger_, "contact mirrors");
        part.across.zero(part.stream);
        part.named.allocate(whole, ledger_, "contact mirrors");
        part.named.zero(part.stream);
        WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&part.marked, cudaEventDisableTiming));
    }
    for (std::size_t p = 0; p < parts; ++p) {  // peer access: enabled by the round
        std::vector<const std::uint8_t*> others;
        for (std::size_t q = 0; q < parts; ++q)
            if (q != p) others.push_back(part_[q].named.get());
        WEFT_CUDA_CHECK(cudaSetDevice(part_[p].device));
        part_[p].others.upload(others, ledger_, "contact mirrors");
    }
    for (const Part& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(part.stream));  // the zeroed lists before the first use
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

ContactMirror::~ContactMirror() {
    for (Part& part : part_)
        if (part.marked != nullptr) cudaEventDestroy(part.marked);
}

float* ContactMirror::copy(std::size_t p, Vector which) const {
    return part_.at(p).copies.get() + static_cast<std::size_t>(which) * 3 * whole_;
}

void ContactMirror::list_contact_vertices(std::span<const ContactView> contacts) {
    if (contacts.size() != part_.size())
        throw Error("ContactMirror::list_contact_vertices: " + std::to_string(contacts.size()) + " contact lists for " +
                    std::to_string(part_.size()) + " parts");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    // The vertices each part's contacts name on other parts.
    for (std::size_t p = 0; p < part_.size(); ++p) {
        Part& part = part_[p];
        const ContactView& c = contacts[p];
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        part.named.zero(part.stream);
        if (c.capacity > 0) {
            const unsigned blocks = std::max(1u, std::min(1024u, grid_for(c.capacity)));
            name_kernel<<<blocks, kBlockSize, 0, part.stream>>>(c, part.named.get());
            WEFT_CUDA_CHECK_LAUNCH("contact mirror name_kernel");
        }
        WEFT_CUDA_CHECK(cudaEventRecord(part.marked, part.stream));
    }
    for (std::size_t p = 0; p < part_.size(); ++p) {
        Part& part = part_[p];
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        for (const Part& other : part_) WEFT_CUDA_CHECK(cudaStreamWaitEvent(part.stream, other.marked, 0));
        WEFT_CUDA_CHECK(cudaMemsetAsync(part.list.get() + part.owned, 0, sizeof(std::uint32_t), part.stream));
        WEFT_CUDA_CHECK(cudaMemsetAsync(part.across.get() + part.owned, 0, sizeof(std::uint32_t), part.stream));
        if (part.owned == 0) continue;
        list_kernel<<<grid_for(part.owned), kBlockSize, 0, part.stream>>>(contacts[p].start, part.owned, part.list.get());
        WEFT_CUDA_CHECK_LAUNCH("contact mirror list_kernel");
        across_kernel<<<grid_for(part.owned), kBlockSize, 0, part.stream>>>(
            contacts[p].start, part.owned, part.global, part.others.get(), static_cast<std::uint32_t>(part_.size() - 1),
            part.across.get());
        WEFT_CUDA_CHECK_LAUNCH("contact mirror across_kernel");
    }
    // A part's flags are rewritten at the next call: not before every part has read them.
    for (Part& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        WEFT_CUDA_CHECK(cudaEventRecord(part.marked, part.stream));
    }
    for (Part& part : part_) {
        WEFT_CUDA_CHECK(cudaSetDevice(part.device));
        for (const Part& other : part_) WEFT_CUDA_CHECK(cudaStreamWaitEvent(part.stream, other.marked, 0));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

void ContactMirror::push(Vector which, std::span<const float* const> vectors, std::span<const std::uint32_t> stride) {
    enqueue_push(which, vectors, stride, false);
}

void ContactMirror::push_across(Vector which, std::span<const float* const> vectors, std::span<const std::uint32_t> stride) {
    enqueue_push(which, vectors, stride, true);
}

void ContactMirror::enqueue_push(Vector which, std::span<const float* const> vectors, std::span<const std::uint32_t> stride,
                                 bool across) {
    const std::size_t parts = part_.size();
    if (vectors.size() != parts || stride.size() != parts)
        throw Error("ContactMirror::push: " + std::to_string(vectors.size()) + " vectors for " + std::to_string(parts) + " parts");
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    round_.open();
    for (std::size_t p = 0; p < parts; ++p) {
        const Part& from = part_[p];
        WEFT_CUDA_CHECK(cudaSetDevice(from.device));
        const unsigned blocks = std::max(1u, std::min(1024u, grid_for(from.owned)));
        const std::uint32_t* rows = across ? from.across.get() : from.list.get();
        for (std::size_t q = 0; q < parts; ++q) {
            if (across && q == p) continue;
            push_kernel<<<blocks, kBlockSize, 0, round_.side(p)>>>(vectors[p], stride[p], rows, from.owned, from.global,
                                                                  copy(q, which), whole_);
            WEFT_CUDA_CHECK_LAUNCH("contact mirror push_kernel");
        }
    }
    round_.close();
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

}  // namespace weft::cuda::multi
