#pragma once
// Grid sizes of kernel launches, shared by every launcher of the CUDA backend.

#include <cstdint>

namespace weft::cuda {

/// Blocks of `threads` threads (> 0) that cover `count` items, one thread each: at least one block,
/// since a launch of zero blocks is an error; the kernels compare their index with the count.
[[nodiscard]] constexpr unsigned blocks_for(std::uint64_t count, unsigned threads) {
    const std::uint64_t blocks = (count + threads - 1) / threads;
    return static_cast<unsigned>(blocks > 0 ? blocks : 1);
}

}  // namespace weft::cuda
