#pragma once
/// @file
/// WEFT_CUDA_PCG=one|kernels|auto: how the CG loop runs, for one GPU and across GPUs alike
/// (PcgLoop). Read by both backends' factories, so that one spelling means one thing.

#include <optional>

#include "weft/cuda/cuda_backend.h"

namespace weft::cuda {

/// The loop WEFT_CUDA_PCG asks for; empty where it is unset. Throws weft::Error naming the value
/// where it is none of one, kernels and auto.
[[nodiscard]] std::optional<PcgLoop> pcg_loop_from_environment();

/// WEFT_CUDA_PCG_BLOCKS=N (profiling): the one-launch CG loop's grid in blocks, where the default
/// is one block per 256 rows (pcg_persistent_grid); capped at what the device holds at once. Absent:
/// nullopt. Anything but a positive integer is an Error naming the value.
[[nodiscard]] std::optional<int> pcg_blocks_from_environment();

}  // namespace weft::cuda
