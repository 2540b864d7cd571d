#pragma once
// The CUDA backend's writer into renderer-owned slots (weft/backend/interop.h, SharedOutput): each slot's
// memory and timeline imported once, the solver's output bound to one slot per display frame.
#include <memory>
#include <span>
#include <string>

#include "weft/backend/interop.h"

namespace weft::cuda {

class DeviceSolver;
struct DeviceInfo;

/// Imports `slots` for `solver` on `device` (nullptr and `why` when the slots live on another GPU
/// or a slot is too small for the solver's vertices; the fds are closed then). Vulkan slots are
/// matched by `uuid`; OpenGL slots (all of one kind) by the GL context current on the calling
/// thread. Throws weft::Error when CUDA refuses an import.
[[nodiscard]] std::unique_ptr<SharedOutput> make_shared_output(DeviceSolver& solver, const DeviceInfo& device,
                                                               std::span<const SharedSlotHandle> slots,
                                                               const DeviceUuid& uuid, std::string& why);

/// The OpenGL kind (gl_shared_output.cpp), after make_shared_output's checks of sizes and counts:
/// registers each slot's buffer object with CUDA. nullptr and `why` when the current GL context is
/// not on `device` (or the build has no OpenGL headers).
[[nodiscard]] std::unique_ptr<SharedOutput> make_gl_shared_output(DeviceSolver& solver, const DeviceInfo& device,
                                                                  std::span<const SharedSlotHandle> slots,
                                                                  std::string& why);

}  // namespace weft::cuda
