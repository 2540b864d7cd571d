// SharedOutput on the CUDA backend (see shared_output.h). Per display frame, on the solver's stream:
//   wait(slot timeline ≥ wait_value) → first stamp → current state → every step's output → last
//   stamp → signal(signal_value)
// so the reader (the renderer) never sees a slot half written, and no host thread waits.
#include "shared_output.h"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <vector>

#include "weft/cuda/cuda_backend.h"
#include "weft/cuda/external_memory.h"
#include "weft/error.h"

#include "cuda_check.h"
#include "device_solver.h"
#include "kernels.h"
#include "multi/multi_solver.h"

namespace weft::cuda {
namespace {

class SolverOutput final : public OutputSource {
public:
    explicit SolverOutput(DeviceSolver& solver) : solver_(solver) {}
    std::size_t vertex_count() const override { return solver_.vertex_count(); }
    cudaStream_t stream() const override { return solver_.stream(); }
    void bind(void* buffer, std::size_t stride) override { solver_.set_output(buffer, stride, false); }

private:
    DeviceSolver& solver_;
};

class MultiSolverOutput final : public OutputSource {
public:
    explicit MultiSolverOutput(multi::MultiSolver& solver) : solver_(solver) {}
    std::size_t vertex_count() const override { return solver_.vertex_count(); }
    cudaStream_t stream() const override { return solver_.stream(); }
    void bind(void* buffer, std::size_t stride) override { solver_.set_output(buffer, stride, false); }

private:
    multi::MultiSolver& solver_;
};

/// The Vulkan kind (SlotApi::vulkan_fd): imported fds, ordered by the slots' timelines.
class CudaSharedOutput final : public SharedOutput {
public:
    CudaSharedOutput(std::unique_ptr<OutputSource> source, int device, std::span<const SharedSlotHandle> slots)
        : source_(std::move(source)), device_(device), vertices_(source_->vertex_count()) {
        for (std::size_t s = 0; s < slots.size(); ++s) {
            try {
                Slot slot;
                // Each import owns its fd from the call on (closed on failure too); the ones after it
                // are closed here when it throws.
                slot.buffer = std::make_unique<ImportedBuffer>(device, slots[s].memory);
                slot.timeline = std::make_unique<ImportedTimeline>(device, slots[s].timeline);
                // Defined contents (zeros, stamps 0) before the first frame writes it. On the
                // solver's stream: the solver's stream is non-blocking, so a cudaMemset on the legacy
                // stream is not ordered before the first frame's writes and could land after them
                // (the first draw from each slot then read zeros where CUDA had written).
                WEFT_CUDA_CHECK(cudaSetDevice(device));
                WEFT_CUDA_CHECK(
                    cudaMemsetAsync(slot.buffer->device_pointer(), 0, slot.buffer->size(), source_->stream()));
                slots_.push_back(std::move(slot));
            } catch (...) {
                close_slot_handles(slots.subspan(s + 1));
                throw;
            }
        }
    }

    ~CudaSharedOutput() override {
        if (bound_ >= 0) source_->bind(nullptr, sizeof(OutputVertex));
    }

    int slots() const override { return static_cast<int>(slots_.size()); }

    void begin_frame(int slot, std::uint64_t wait_value, std::uint64_t stamp) override {
        if (slot < 0 || slot >= slots())
            throw Error("CUDA shared output: slot " + std::to_string(slot) + " of " + std::to_string(slots()));
        if (bound_ >= 0) throw Error("CUDA shared output: begin_frame() twice without end_frame()");
        // The stamps sit after the vertices: a world rebuilt with another vertex count since the
        // slots were shared would write them where the reader does not look.
        if (source_->vertex_count() != vertices_)
            throw Error("CUDA shared output: the world has " + std::to_string(source_->vertex_count()) +
                        " vertices, the slots were shared for " + std::to_string(vertices_) + " (share them again)");
        const Slot& s = slots_[static_cast<std::size_t>(slot)];
        WEFT_CUDA_CHECK(cudaSetDevice(device_));
        cudaStream_t stream = source_->stream();
        if (wait_value > 0) s.timeline->wait(wait_value, stream);
        launch_write_stamp(stamp_at(s, 0), stamp, stream);
        source_->bind(s.buffer->device_pointer(), sizeof(OutputVertex));  // writes the state now
        bound_ = slot;
        stamp_ = stamp;
    }

    void end_frame(std::uint64_t signal_value) override {
        if (bound_ < 0) throw Error("CUDA shared output: end_frame() without begin_frame()");
        const Slot& s = slots_[static_cast<std::size_t>(bound_)];
        WEFT_CUDA_CHECK(cudaSetDevice(device_));
        cudaStream_t stream = source_->stream();
        launch_write_stamp(stamp_at(s, 1), stamp_, stream);
        s.timeline->signal(signal_value, stream);
        source_->bind(nullptr, sizeof(OutputVertex));
        bound_ = -1;
    }

private:
    struct Slot {
        std::unique_ptr<ImportedBuffer> buffer;
        std::unique_ptr<ImportedTimeline> timeline;
    };

    void* stamp_at(const Slot& s, int which) const {
        return static_cast<unsigned char*>(s.buffer->device_pointer()) + vertices_ * sizeof(OutputVertex) +
               static_cast<std::size_t>(which) * sizeof(std::uint64_t);
    }

    std::unique_ptr<OutputSource> source_;
    int device_ = 0;
    std::size_t vertices_ = 0;  ///< the world's vertex count when shared: the stamps follow them
    std::vector<Slot> slots_;
    int bound_ = -1;
    std::uint64_t stamp_ = 0;
};

}  // namespace

std::unique_ptr<OutputSource> output_source(DeviceSolver& solver) { return std::make_unique<SolverOutput>(solver); }

std::unique_ptr<OutputSource> output_source(multi::MultiSolver& solver) {
    return std::make_unique<MultiSolverOutput>(solver);
}

std::unique_ptr<SharedOutput> make_shared_output(std::unique_ptr<OutputSource> source, const DeviceInfo& device,
                                                 std::span<const SharedSlotHandle> slots, const DeviceUuid& uuid,
                                                 std::string& why) {
    const auto refuse = [&](std::string reason) -> std::unique_ptr<SharedOutput> {
        close_slot_handles(slots);
        why = std::move(reason);
        return nullptr;
    };
    if (slots.empty()) return refuse("no slots to share");
    const SlotApi api = slots.front().api;
    if (std::any_of(slots.begin(), slots.end(), [&](const SharedSlotHandle& s) { return s.api != api; }))
        return refuse("the slots mix Vulkan and OpenGL handles");
    if (api == SlotApi::vulkan_fd && !std::equal(uuid.begin(), uuid.end(), std::begin(device.uuid)))
        return refuse("the renderer's GPU is not the CUDA backend's (" + device.name + ", device " +
                      std::to_string(device.ordinal) + ")");
    if (source->vertex_count() == 0) return refuse("the world is not built yet (World::share_output builds it)");
    const std::uint64_t needed = source->vertex_count() * sizeof(OutputVertex) + kSlotStampBytes;
    for (const SharedSlotHandle& s : slots)
        if (slot_bytes(s) < needed)
            return refuse("a shared slot holds " + std::to_string(slot_bytes(s)) + " bytes, the world needs " +
                          std::to_string(needed));
    if (api == SlotApi::opengl_buffer) return make_gl_shared_output(std::move(source), device, slots, why);
    return std::make_unique<CudaSharedOutput>(std::move(source), device.ordinal, slots);
}

#ifndef WEFT_CUDA_OPENGL
std::unique_ptr<SharedOutput> make_gl_shared_output(std::unique_ptr<OutputSource> /*source*/, const DeviceInfo& /*device*/,
                                                    std::span<const SharedSlotHandle> /*slots*/, std::string& why) {
    why = "this build of the CUDA backend has no OpenGL interop (GL/gl.h was not found)";
    return nullptr;
}
#endif

}  // namespace weft::cuda
