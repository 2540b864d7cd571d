#pragma once
// Internal access to the device solver behind a "cuda" backend, for benchmarks and tests that
// measure kernels in isolation. Not part of the public API.

#include "device_memory_budget.h"
#include "device_solver.h"
#include "weft/backend/backend.h"

namespace weft::cuda {

/// The DeviceSolver of a CUDA backend, or nullptr for any other backend.
DeviceSolver* device_solver(Backend& backend);

/// The device memory budget of a CUDA backend (BackendOptions::device_memory_limit, which tests
/// lower and raise mid-run), or nullptr for any other backend.
DeviceMemoryBudget* device_memory_budget(Backend& backend);

}  // namespace weft::cuda
