#pragma once
// Small device helpers shared by the kernel files: SoA loads and stores, block access and the
// deterministic grid-wide reduction.

#include <cub/block/block_reduce.cuh>

#include "device_view.h"
#include "kernels.h"

namespace weft::cuda {
/// Rows per ELL slice, as in device_layout.h (kSliceRows), for device code.
inline constexpr std::uint32_t kSliceRowsDevice = 32;
}  // namespace weft::cuda

namespace weft::cuda {

__device__ inline V3 load3(const float* a, std::uint32_t i, std::uint32_t n) { return {a[i], a[i + n], a[i + 2 * n]}; }
__device__ inline void store3(float* a, std::uint32_t i, std::uint32_t n, V3 v) {
    a[i] = v.x;
    a[i + n] = v.y;
    a[i + 2 * n] = v.z;
}
__device__ inline M3 load_block(const float* blocks, std::uint32_t pos) {
    const float* p = blocks + 9 * static_cast<std::size_t>(pos);
    M3 m;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) m.m[r][c] = p[3 * r + c];
    return m;
}
__device__ inline void store_block(float* blocks, std::uint32_t pos, const M3& m) {
    float* p = blocks + 9 * static_cast<std::size_t>(pos);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) p[3 * r + c] = m.m[r][c];
}
__device__ inline void add_block(float* blocks, std::uint32_t pos, const M3& m) {
    float* p = blocks + 9 * static_cast<std::size_t>(pos);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) p[3 * r + c] += m.m[r][c];
}
__device__ inline const StepParams& step_params(const DeviceView& d) {
    return *reinterpret_cast<const StepParams*>(d.staging);
}
template <typename U>
__device__ inline const U* staged(const DeviceView& d, std::uint32_t offset) {
    return reinterpret_cast<const U*>(d.staging + offset);
}

/// Sums `value` over the whole grid and calls `finish(total)` on one thread of the last block to
/// finish. Each block reduces in CUB's fixed tree order and the last block adds the block partials
/// in index order, so the total has the same bits on every run (unlike floating-point atomics).
template <typename Finish>
__device__ void grid_sum(double value, const DeviceView& d, Finish&& finish) {
    using Reduce = cub::BlockReduce<double, kBlockSize>;
    __shared__ typename Reduce::TempStorage storage;
    __shared__ bool last;
    const double block_sum = Reduce(storage).Sum(value);
    if (threadIdx.x == 0) {
        d.partials[blockIdx.x] = block_sum;
        __threadfence();
        last = atomicAdd(&d.control->counter, 1u) == gridDim.x - 1;
    }
    __syncthreads();
    if (!last) return;
    double acc = 0.0;
    for (unsigned i = threadIdx.x; i < gridDim.x; i += blockDim.x) acc += __ldcg(&d.partials[i]);
    __syncthreads();  // storage is reused
    const double total = Reduce(storage).Sum(acc);
    if (threadIdx.x == 0) {
        d.control->counter = 0;
        finish(total);
    }
}

}  // namespace weft::cuda
