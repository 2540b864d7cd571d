// The owned rows of one part's matrix on its device (multi/part_matrix.h).
#include "multi/part_matrix.h"

#include <limits>
#include <string>
#include <vector>

#include "cuda_check.h"
#include "device_layout.h"
#include "device_math.cuh"
#include "kernels.h"
#include "weft/error.h"

namespace weft::cuda::multi {
namespace {

constexpr std::uint32_t kPadding = std::numeric_limits<std::uint32_t>::max();

/// Row i of A·x, as the single-GPU SpMV (pcg_kernels.cu, row_times) over this layout.
__global__ void part_multiply_kernel(const std::uint32_t* slice_start, const std::uint32_t* column, const float* blocks,
                                     const float* x, float* y, std::uint32_t local, std::uint32_t begin, std::uint32_t end) {
    const std::uint32_t i = begin + blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= end) return;
    const std::uint32_t slice = i / kSliceRowsDevice;
    const std::uint32_t first = slice_start[slice], width = (slice_start[slice + 1] - first) / kSliceRowsDevice;
    V3 acc{};
    for (std::uint32_t k = 0; k < width; ++k) {
        const std::uint32_t pos = first + k * kSliceRowsDevice + i % kSliceRowsDevice;
        acc += load_block(blocks, pos) * load3(x, column[pos], local);
    }
    store3(y, i, local, acc);
}

}  // namespace

PartMatrix::PartMatrix(const PartModel& part, int device)
    : device_(device), owned_(part.owned), interior_(part.interior),
      local_(static_cast<std::uint32_t>(part.model.vertex_count)) {
    // The owned rows of the local pattern (their columns may name ghosts).
    const BlockPattern& lp = part.model.pattern;
    BlockPattern rows;
    rows.row_start.assign(lp.row_start.begin(), lp.row_start.begin() + owned_ + 1);
    rows.column.assign(lp.column.begin(), lp.column.begin() + rows.row_start.back());
    rows.diagonal.assign(lp.diagonal.begin(), lp.diagonal.begin() + owned_);
    const EllLayout ell = make_ell_layout(rows);
    global_slot_position_.assign(ell.positions(), kPadding);
    for (std::uint32_t s = 0; s < rows.block_count(); ++s) global_slot_position_[ell.slot_position[s]] = part.global_slot[s];
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    slice_start_.upload(ell.slice_start, ledger_, "part matrix structure");
    column_.upload(ell.column, ledger_, "part matrix structure");
    diagonal_.upload(ell.diagonal, ledger_, "part matrix structure");
    blocks_.allocate(9 * ell.positions(), ledger_, "part matrix blocks");
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

void PartMatrix::set_blocks(std::span<const float> global_blocks) {
    std::vector<float> host(blocks_.size(), 0.0F);
    for (std::size_t pos = 0; pos < global_slot_position_.size(); ++pos) {
        const std::uint32_t s = global_slot_position_[pos];
        if (s == kPadding) continue;
        if (9 * std::size_t{s} + 9 > global_blocks.size())
            throw Error("PartMatrix::set_blocks: " + std::to_string(global_blocks.size() / 9) + " blocks, slot " +
                        std::to_string(s) + " asked for");
        for (int e = 0; e < 9; ++e) host[9 * pos + e] = global_blocks[9 * std::size_t{s} + e];
    }
    int previous = 0;
    WEFT_CUDA_CHECK(cudaGetDevice(&previous));
    WEFT_CUDA_CHECK(cudaSetDevice(device_));
    if (!host.empty()) {
        WEFT_CUDA_CHECK(cudaMemcpy(blocks_.get(), host.data(), host.size() * sizeof(float), cudaMemcpyHostToDevice));
        wait_for_default_stream();
    }
    WEFT_CUDA_CHECK(cudaSetDevice(previous));
}

void PartMatrix::multiply(const float* x, float* y, std::uint32_t begin, std::uint32_t end, cudaStream_t stream) const {
    if (begin > end || end > owned_)
        throw Error("PartMatrix::multiply: rows [" + std::to_string(begin) + ", " + std::to_string(end) + ") of " +
                    std::to_string(owned_) + " owned");
    if (begin == end) return;
    part_multiply_kernel<<<grid_for(end - begin), kBlockSize, 0, stream>>>(slice_start_.get(), column_.get(), blocks_.get(),
                                                                          x, y, local_, begin, end);
    WEFT_CUDA_CHECK_LAUNCH("part_multiply_kernel");
}

PartSystem PartMatrix::system(cudaStream_t stream) const {
    PartSystem s;
    s.device = device_;
    s.stream = stream;
    s.owned = owned_;
    s.local = local_;
    s.slice_start = slice_start_.get();
    s.column = column_.get();
    s.diagonal = diagonal_.get();
    s.blocks = blocks_.get();
    return s;
}

}  // namespace weft::cuda::multi
