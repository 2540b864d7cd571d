#pragma once
/// @file
/// The whole model's state on one GPU, for the collision stages across GPUs (docs/multi-gpu.md,
/// "Collisions"): each part stores its owned vertices into the whole arrays (peer stores), and takes
/// its local vertices (owned and ghosts) back from them after the impact zones moved some.

#include <cuda_runtime_api.h>

#include <cstdint>

namespace weft::cuda::multi {

/// whole[c·whole_n + global[i]] = local[c·local_n + i] for the owned vertices i < owned.
void launch_owned_to_whole(const float* local, std::uint32_t local_n, std::uint32_t owned, const std::uint32_t* global,
                           float* whole, std::uint32_t whole_n, cudaStream_t stream);
/// local[c·local_n + i] = whole[c·whole_n + global[i]] for every local vertex i < local_n.
void launch_whole_to_local(const float* whole, std::uint32_t whole_n, const std::uint32_t* global, float* local,
                           std::uint32_t local_n, cudaStream_t stream);

}  // namespace weft::cuda::multi
