// SharedOutput for OpenGL buffer objects (weft/backend/interop.h, SlotApi::opengl_buffer): the EGL capture
// path's zero-copy link. Each slot's buffer object is registered with CUDA once
// (cudaGraphicsGLRegisterBuffer); per display frame, on the solver's stream:
//   map → first stamp → current state → every step's output → last stamp → unmap
// Mapping orders the frame's writes after the GL work issued before it (the draw that last read the
// slot), unmapping orders the GL work issued after it (the draw of this frame) after the writes
// (CUDA Runtime API, "Graphics Interoperability"), so the timeline values of the Vulkan kind are
// not needed and no host thread waits for the GPU here.
//
// The GL context that owns the buffers must be current on the thread that shares the slots and
// calls begin_frame/end_frame (the EGL renderer's thread): CUDA finds the buffer through it.
#include "shared_output.h"

// cuda_gl_interop.h declares its functions with GL's types and asks for GL's header first.
#include <GL/gl.h>
#include <cuda_gl_interop.h>

#include <algorithm>
#include <array>
#include <utility>
#include <vector>

#include "weft/cuda/cuda_backend.h"
#include "weft/error.h"

#include "cuda_check.h"
#include "kernels.h"

namespace weft::cuda {
namespace {

class GlSharedOutput final : public SharedOutput {
public:
    GlSharedOutput(std::unique_ptr<OutputSource> source, int device, std::span<const SharedSlotHandle> slots)
        : source_(std::move(source)), device_(device), vertices_(source_->vertex_count()) {
        WEFT_CUDA_CHECK(cudaSetDevice(device));
        try {
            for (const SharedSlotHandle& s : slots) {
                cudaGraphicsResource_t resource = nullptr;
                // No flags: CUDA may read and write (the writer does not overwrite all of a buffer
                // larger than the world needs, so WriteDiscard's undefined contents would show).
                WEFT_CUDA_CHECK(cudaGraphicsGLRegisterBuffer(&resource, s.gl_buffer.name, cudaGraphicsRegisterFlagsNone));
                resources_.push_back(resource);
            }
            // Defined contents (zeros, stamps 0) before the first frame writes a slot, on the
            // solver's stream (non-blocking: the legacy stream's memset would not be ordered).
            for (std::size_t s = 0; s < resources_.size(); ++s) {
                void* pointer = map(static_cast<int>(s));
                WEFT_CUDA_CHECK(cudaMemsetAsync(pointer, 0, slots[s].gl_buffer.size, source_->stream()));
                unmap(static_cast<int>(s));
            }
        } catch (...) {
            release();
            throw;
        }
    }

    ~GlSharedOutput() override {
        if (bound_ >= 0) {
            source_->bind(nullptr, sizeof(OutputVertex));
            (void)cudaGraphicsUnmapResources(1, &resources_[static_cast<std::size_t>(bound_)], source_->stream());
        }
        release();
    }

    int slots() const override { return static_cast<int>(resources_.size()); }

    void begin_frame(int slot, std::uint64_t /*wait_value*/, std::uint64_t stamp) override {
        if (slot < 0 || slot >= slots())
            throw Error("CUDA shared output (OpenGL): slot " + std::to_string(slot) + " of " + std::to_string(slots()));
        if (bound_ >= 0) throw Error("CUDA shared output (OpenGL): begin_frame() twice without end_frame()");
        if (source_->vertex_count() != vertices_)
            throw Error("CUDA shared output (OpenGL): the world has " + std::to_string(source_->vertex_count()) +
                        " vertices, the slots were shared for " + std::to_string(vertices_) + " (share them again)");
        WEFT_CUDA_CHECK(cudaSetDevice(device_));
        // The mapped address may differ from one mapping to the next: it is taken each frame.
        mapped_ = static_cast<unsigned char*>(map(slot));
        bound_ = slot;
        stamp_ = stamp;
        launch_write_stamp(mapped_ + vertices_ * sizeof(OutputVertex), stamp, source_->stream());
        source_->bind(mapped_, sizeof(OutputVertex));  // writes the state now
    }

    void end_frame(std::uint64_t /*signal_value*/) override {
        if (bound_ < 0) throw Error("CUDA shared output (OpenGL): end_frame() without begin_frame()");
        WEFT_CUDA_CHECK(cudaSetDevice(device_));
        launch_write_stamp(mapped_ + vertices_ * sizeof(OutputVertex) + sizeof(std::uint64_t), stamp_, source_->stream());
        source_->bind(nullptr, sizeof(OutputVertex));
        const int slot = std::exchange(bound_, -1);
        mapped_ = nullptr;
        unmap(slot);
    }

private:
    void* map(int slot) {
        cudaGraphicsResource_t& resource = resources_[static_cast<std::size_t>(slot)];
        WEFT_CUDA_CHECK(cudaGraphicsMapResources(1, &resource, source_->stream()));
        void* pointer = nullptr;
        std::size_t bytes = 0;
        WEFT_CUDA_CHECK(cudaGraphicsResourceGetMappedPointer(&pointer, &bytes, resource));
        const std::size_t needed = vertices_ * sizeof(OutputVertex) + kSlotStampBytes;
        if (bytes < needed) {
            (void)cudaGraphicsUnmapResources(1, &resource, source_->stream());
            throw Error("CUDA shared output (OpenGL): slot " + std::to_string(slot) + " maps " + std::to_string(bytes) +
                        " bytes, the world needs " + std::to_string(needed));
        }
        return pointer;
    }

    void unmap(int slot) {
        WEFT_CUDA_CHECK(cudaGraphicsUnmapResources(1, &resources_[static_cast<std::size_t>(slot)], source_->stream()));
    }

    void release() noexcept {
        for (cudaGraphicsResource_t r : resources_) (void)cudaGraphicsUnregisterResource(r);
        resources_.clear();
    }

    std::unique_ptr<OutputSource> source_;
    int device_ = 0;
    std::size_t vertices_ = 0;  ///< the world's vertex count when shared: the stamps follow them
    std::vector<cudaGraphicsResource_t> resources_;
    unsigned char* mapped_ = nullptr;  ///< the bound slot's address while it is mapped
    int bound_ = -1;
    std::uint64_t stamp_ = 0;
};

}  // namespace

std::unique_ptr<SharedOutput> make_gl_shared_output(std::unique_ptr<OutputSource> source, const DeviceInfo& device,
                                                    std::span<const SharedSlotHandle> slots, std::string& why) {
    // The GL context current on this thread must live on the backend's GPU (a Mesa context, or one
    // on another GPU, has no CUDA device or another one).
    WEFT_CUDA_CHECK(cudaSetDevice(device.ordinal));
    std::array<int, 16> gl_devices{};
    unsigned int count = 0;
    const cudaError_t found = cudaGLGetDevices(&count, gl_devices.data(), static_cast<unsigned>(gl_devices.size()),
                                               cudaGLDeviceListAll);
    if (found != cudaSuccess) {
        (void)cudaGetLastError();  // not sticky; cleared so that the next check does not report it
        why = std::string("CUDA finds no GPU of its own under the current OpenGL context (") + cudaGetErrorName(found) +
              ": " + cudaGetErrorString(found) + ")";
        return nullptr;
    }
    const auto end = gl_devices.begin() + std::min<unsigned>(count, gl_devices.size());
    if (std::find(gl_devices.begin(), end, device.ordinal) == end) {
        why = "the OpenGL context is not on the CUDA backend's GPU (" + device.name + ", device " +
              std::to_string(device.ordinal) + ")";
        return nullptr;
    }
    return std::make_unique<GlSharedOutput>(std::move(source), device.ordinal, slots);
}

}  // namespace weft::cuda
