// A part's share of the contact list (multi/part_contacts.h).
#include "multi/part_contacts.h"

#include <cub/device/device_select.cuh>

#include <limits>
#include <string>

#include "cuda_check.h"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

/// True for a contact with a cloth vertex this part owns.
struct TouchesOwnedRow {
    const std::uint32_t* row_of;
    std::uint32_t cloth_vertices;
    __device__ bool operator()(const DeviceContact& c) const {
        for (int j = 0; j < 4; ++j) {
            const std::uint32_t v = c.vertex[j];
            if (v < cloth_vertices && row_of[v] != std::numeric_limits<std::uint32_t>::max()) return true;
        }
        return false;
    }
};

__global__ void count_contacts_at_vertices(const DeviceContact* list, std::size_t count, std::uint32_t cloth_vertices,
                                           std::uint32_t* counts) {
    const std::size_t k = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
    if (k >= count) return;
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = list[k].vertex[j];
        if (v < cloth_vertices) atomicAdd(counts + v, 1U);
    }
}

__global__ void corner_sources(ContactView c, std::uint32_t count, uint4* out) {
    const std::uint32_t p = blockIdx.x * blockDim.x + threadIdx.x;
    if (p >= count) return;
    std::uint32_t k[4];
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = c.list[p].vertex[j];
        const std::uint32_t row = v < c.cloth_vertices ? c.row_of[v] : kCornerNone;
        k[j] = v >= c.cloth_vertices ? kCornerNone : row != std::numeric_limits<std::uint32_t>::max() ? row : (kCornerFromCopy | v);
    }
    out[p] = uint4{k[0], k[1], k[2], k[3]};
}

}  // namespace

void launch_part_corner_sources(const ContactView& c, std::uint32_t count, uint4* corner_source, cudaStream_t stream) {
    if (count == 0) return;
    constexpr unsigned kBlock = 256;
    corner_sources<<<(count + kBlock - 1) / kBlock, kBlock, 0, stream>>>(c, count, corner_source);
    WEFT_CUDA_CHECK(cudaGetLastError());
}

void launch_count_contacts_at_vertices(const DeviceContact* list, std::size_t count, std::uint32_t cloth_vertices,
                                       std::uint32_t* counts, cudaStream_t stream) {
    if (count == 0) return;
    constexpr unsigned kBlock = 256;
    const auto blocks = static_cast<unsigned>((count + kBlock - 1) / kBlock);
    count_contacts_at_vertices<<<blocks, kBlock, 0, stream>>>(list, count, cloth_vertices, counts);
    WEFT_CUDA_CHECK(cudaGetLastError());
}

std::size_t part_contact_selection_bytes(std::size_t count) {
    std::size_t bytes = 0;
    WEFT_CUDA_CHECK(cub::DeviceSelect::If(nullptr, bytes, static_cast<const DeviceContact*>(nullptr),
                                          static_cast<DeviceContact*>(nullptr), static_cast<std::uint32_t*>(nullptr),
                                          static_cast<int>(count), TouchesOwnedRow{nullptr, 0}));
    return bytes;
}

void launch_select_part_contacts(const DeviceContact* from, std::size_t count, const std::uint32_t* row_of,
                                 std::uint32_t cloth_vertices, DeviceContact* to, std::uint32_t* to_count, void* scratch,
                                 std::size_t scratch_bytes, cudaStream_t stream) {
    if (count > static_cast<std::size_t>(std::numeric_limits<int>::max()))
        throw Error("launch_select_part_contacts: " + std::to_string(count) + " contacts exceed the selection's int range");
    if (count == 0) {
        WEFT_CUDA_CHECK(cudaMemsetAsync(to_count, 0, sizeof(std::uint32_t), stream));
        return;
    }
    std::size_t bytes = scratch_bytes;
    WEFT_CUDA_CHECK(cub::DeviceSelect::If(scratch, bytes, from, to, to_count, static_cast<int>(count),
                                          TouchesOwnedRow{row_of, cloth_vertices}, stream));
}

}  // namespace weft::cuda::multi
