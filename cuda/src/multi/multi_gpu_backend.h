#pragma once
/// @file
/// The "cuda" backend on several GPUs of one host (BackendOptions::gpus > 1): a weft::Backend around
/// a MultiSolver (multi/multi_solver.h).

#include <memory>

#include "weft/backend/backend.h"

namespace weft::cuda::multi {

/// The environment variable that puts every part on the first device (`=1`): the test mode, which
/// runs the partition logic of G GPUs on a host with one.
inline constexpr const char* kPartsOnOneDeviceEnv = "WEFT_MULTI_GPU_ONE_DEVICE";

/// Parts on devices options.device, options.device + 1, … (or all on options.device in the test
/// mode). Throws weft::Error when the host has fewer GPUs than asked for, saying how many it has.
[[nodiscard]] std::unique_ptr<Backend> make_multi_gpu_backend(const BackendOptions& options);

class MultiSolver;
/// The MultiSolver behind a backend made here, or nullptr (tests and benchmarks; not public API).
MultiSolver* multi_solver(Backend& backend);
}  // namespace weft::cuda::multi

namespace weft::cuda {
class DeviceMemoryBudget;
}

namespace weft::cuda::multi {
/// The memory budget of a backend made here (BackendOptions::device_memory_limit, per GPU), or nullptr.
DeviceMemoryBudget* multi_gpu_budget(Backend& backend);

}  // namespace weft::cuda::multi
