#pragma once
/// @file
/// The owned rows of one part's matrix on its device (docs/multi-gpu.md), in the single-GPU solver's
/// sliced ELL layout (device_layout.h): rows [0, owned) of the part's local pattern, columns in local
/// numbering, ghosts included. A product over the interior rows reads owned values only, so it can
/// run while the ghosts are still on their way (P-Cloth's pipelined SpMV); the boundary rows follow
/// the exchange. Each row sums its blocks in the global row's order, so the parts' products are the
/// whole product's bits.

#include <cuda_runtime_api.h>

#include <cstdint>
#include <span>

#include "device_array.h"
#include "multi/part_system.h"
#include "weft/backend/part_model.h"

namespace weft::cuda::multi {

class PartMatrix {
public:
    /// Lays out `part`'s owned rows on CUDA device `device` (made current while allocating).
    PartMatrix(const PartModel& part, int device);

    /// Sets the owned rows' blocks from the whole matrix: 9 floats (row-major 3×3) per global pattern
    /// slot, as PartModel::global_slot indexes them. Synchronous (set-up and tests).
    void set_blocks(std::span<const float> global_blocks);
    /// y_i = Σ_j A_ij x_j for the owned rows i in [begin, end), enqueued on `stream` (the part's
    /// device must be current). x and y are local structure-of-arrays vectors of stride `local()`.
    void multiply(const float* x, float* y, std::uint32_t begin, std::uint32_t end, cudaStream_t stream) const;

    /// The owned rows as the CG across parts reads them (no fixed rows; it inverts the diagonal).
    [[nodiscard]] PartSystem system(cudaStream_t stream) const;
    /// The ELL blocks (9 floats each) and each owned row's diagonal position (device arrays).
    [[nodiscard]] const float* blocks() const { return blocks_.get(); }
    [[nodiscard]] const std::uint32_t* diagonal() const { return diagonal_.get(); }
    [[nodiscard]] std::uint32_t owned() const { return owned_; }
    [[nodiscard]] std::uint32_t interior() const { return interior_; }
    [[nodiscard]] std::uint32_t local() const { return local_; }
    [[nodiscard]] int device() const { return device_; }
    [[nodiscard]] std::size_t memory_bytes() const { return ledger_.total(); }

private:
    int device_ = 0;
    std::uint32_t owned_ = 0, interior_ = 0, local_ = 0;
    std::vector<std::uint32_t> global_slot_position_;  // per ELL position: the global slot, or ~0 for padding
    MemoryLedger ledger_;
    DeviceArray<std::uint32_t> slice_start_, column_, diagonal_;
    DeviceArray<float> blocks_;
};

}  // namespace weft::cuda::multi
