#pragma once
// The grid-wide sums of a cooperative (one-launch) loop: the PCG loop (pcg_kernels.cu) and the
// mid-edge normals' solve (midedge_kernels.cu). Every block finishes each sum itself from the block
// partials, in index order, so all blocks get the same bits and take the same decisions, on every run.

#include <cooperative_groups.h>

#include <cub/block/block_reduce.cuh>

#include "kernels.h"

namespace weft::cuda {

/// The sums over the grid of each thread's `values[j]` into `out[j]`, with one grid-wide barrier.
/// `partials` holds N·gridDim.x doubles. A loop alternates two partial arrays between consecutive
/// calls, so that a block still reading one call's partials never sees the next call's.
template <int N>
__device__ void persistent_sums(const double (&values)[N], double* partials, double (&out)[N]) {
    namespace cg = cooperative_groups;
    using Reduce = cub::BlockReduce<double, kBlockSize>;
    __shared__ typename Reduce::TempStorage storage;
    __shared__ double total[N];
    for (int j = 0; j < N; ++j) {
        if (j > 0) __syncthreads();  // storage is reused
        const double block_sum = Reduce(storage).Sum(values[j]);
        if (threadIdx.x == 0) partials[j * gridDim.x + blockIdx.x] = block_sum;
    }
    cg::this_grid().sync();
    // Every block sums all partials with all its threads (a fixed assignment and CUB's fixed tree).
    for (int j = 0; j < N; ++j) {
        double acc = 0.0;
        for (unsigned b = threadIdx.x; b < gridDim.x; b += blockDim.x) acc += __ldcg(&partials[j * gridDim.x + b]);
        __syncthreads();  // storage is reused
        const double sum = Reduce(storage).Sum(acc);
        if (threadIdx.x == 0) total[j] = sum;
    }
    __syncthreads();
    for (int j = 0; j < N; ++j) out[j] = total[j];
    __syncthreads();  // `total` and `storage` are reused by the next call
}

/// One sum (persistent_sums with N = 1); `partials` holds gridDim.x doubles.
__device__ inline double persistent_sum(double value, double* partials) {
    const double values[1] = {value};
    double out[1];
    persistent_sums<1>(values, partials, out);
    return out[0];
}

}  // namespace weft::cuda
