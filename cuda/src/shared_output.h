#pragma once
// The CUDA backend's writer into renderer-owned slots (weft/backend/interop.h, SharedOutput): each slot's
// memory and timeline imported once, the solver's output bound to one slot per display frame.
#include <cstddef>
#include <memory>
#include <span>
#include <string>

#include "weft/backend/interop.h"

struct CUstream_st;

namespace weft::cuda {

class DeviceSolver;
struct DeviceInfo;
namespace multi {
class MultiSolver;
}

/// What a shared output writes: the solver's positions and normals, on the display GPU (the one GPU
/// of a single-GPU solver, the first GPU of a multi-GPU one), ordered on one of its streams.
class OutputSource {
public:
    virtual ~OutputSource() = default;
    /// The world's vertices as laid out in the output.
    [[nodiscard]] virtual std::size_t vertex_count() const = 0;
    /// The display GPU's stream the output's writes are ordered on (the slots' waits, stamps and
    /// signals go there).
    [[nodiscard]] virtual CUstream_st* stream() const = 0;
    /// Binds `buffer` (display-GPU memory, vertex i at stride·i bytes; nullptr unbinds): the current
    /// state is written into it on stream() now and every substep writes it, with no host wait.
    virtual void bind(void* buffer, std::size_t stride) = 0;
};

/// The source for one GPU's solver, and for the solver across GPUs (each part writes its owned
/// vertices; multi/multi_solver.h). The solver must outlive the source.
[[nodiscard]] std::unique_ptr<OutputSource> output_source(DeviceSolver& solver);
[[nodiscard]] std::unique_ptr<OutputSource> output_source(multi::MultiSolver& solver);

/// Imports `slots` for `source` on `device`, the display GPU (nullptr and `why` when the slots live
/// on another GPU or a slot is too small for the source's vertices; the fds are closed then).
/// Vulkan slots are matched by `uuid`; OpenGL slots (all of one kind) by the GL context current on
/// the calling thread. Throws weft::Error when CUDA refuses an import.
[[nodiscard]] std::unique_ptr<SharedOutput> make_shared_output(std::unique_ptr<OutputSource> source, const DeviceInfo& device,
                                                               std::span<const SharedSlotHandle> slots,
                                                               const DeviceUuid& uuid, std::string& why);

/// The OpenGL kind (gl_shared_output.cpp), after make_shared_output's checks of sizes and counts:
/// registers each slot's buffer object with CUDA. nullptr and `why` when the current GL context is
/// not on `device` (or the build has no OpenGL headers).
[[nodiscard]] std::unique_ptr<SharedOutput> make_gl_shared_output(std::unique_ptr<OutputSource> source, const DeviceInfo& device,
                                                                  std::span<const SharedSlotHandle> slots,
                                                                  std::string& why);

}  // namespace weft::cuda
