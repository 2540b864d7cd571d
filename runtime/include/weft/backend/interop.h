#pragma once
/// @file
/// Neutral handles for zero-copy interop between a renderer and a GPU backend (docs/design.md, "The
/// zero-copy frame loop"): the renderer exports memory and a timeline semaphore as POSIX file descriptors
/// (Vulkan's opaque fd handles), the backend imports them, and neither includes the other's headers.
#include <array>
#include <memory>
#include <string>
#include <cstdint>
#include <span>

namespace weft {

/// A device allocation exported as an opaque fd (VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT).
/// The importer takes ownership of `fd` when the import succeeds.
struct ExternalMemoryHandle {
    int fd = -1;
    std::uint64_t allocation_size = 0;  ///< bytes of the whole exported allocation
    std::uint64_t offset = 0;           ///< where the buffer starts in it, bytes
    std::uint64_t size = 0;             ///< bytes of the buffer
    bool dedicated = false;             ///< the allocation is dedicated to the buffer (import flag)
};

/// A timeline semaphore exported as an opaque fd (VK_EXTERNAL_SEMAPHORE_HANDLE_TYPE_OPAQUE_FD_BIT).
/// The importer takes ownership of `fd` when the import succeeds.
struct ExternalTimelineHandle {
    int fd = -1;
};

/// A device's identity as both APIs report it (Vulkan's deviceUUID, CUDA's uuid): interop works only
/// between the same physical GPU.
using DeviceUuid = std::array<std::uint8_t, 16>;


}  // namespace weft

namespace weft {

/// Bytes at the end of each shared cloth slot, after the vertices: two 64-bit frame stamps. The
/// writer stores the frame's stamp in the first before it writes any vertex and in the second after
/// the last; a reader that finds both equal to the frame it expects read one whole frame and no
/// part of another (the tearing check of docs/rendering.md).
inline constexpr std::uint64_t kSlotStampBytes = 16;

/// How a renderer hands a cloth slot to a backend.
enum class SlotApi : std::uint8_t {
    /// Vulkan: the memory and a timeline semaphore exported as opaque fds (`memory`, `timeline`).
    /// The timeline orders the writer against the reader on the GPU.
    vulkan_fd,
    /// OpenGL: a buffer object of the context that is current on the thread that shares the slots
    /// and begins and ends every frame (`gl_buffer`). The backend registers it (CUDA:
    /// cudaGraphicsGLRegisterBuffer) and maps it around each frame's writes: mapping orders the
    /// writes after the GL work issued before, unmapping orders the GL work issued after behind
    /// them, so the timeline values of a frame are not used.
    opengl_buffer,
};

/// An OpenGL buffer object shared as a cloth slot (SlotApi::opengl_buffer).
struct GlBufferHandle {
    std::uint32_t name = 0;  ///< the buffer object's name in the current context
    std::uint64_t size = 0;  ///< bytes of its storage
};

/// One shared cloth slot: the memory (vertices, then the stamps) and, for Vulkan, the timeline
/// semaphore that orders its writer against its reader.
struct SharedSlotHandle {
    SlotApi api = SlotApi::vulkan_fd;
    ExternalMemoryHandle memory;      ///< SlotApi::vulkan_fd
    ExternalTimelineHandle timeline;  ///< SlotApi::vulkan_fd
    GlBufferHandle gl_buffer;         ///< SlotApi::opengl_buffer
};

/// The bytes a slot holds for the writer: the exported buffer's, or the GL buffer's.
[[nodiscard]] inline std::uint64_t slot_bytes(const SharedSlotHandle& slot) {
    return slot.api == SlotApi::opengl_buffer ? slot.gl_buffer.size : slot.memory.size;
}

/// Closes the fds of `slots` that are open (≥ 0): what a side that took them and cannot import
/// them must do, so that none leaks.
void close_slot_handles(std::span<const SharedSlotHandle> slots);

/// A backend's writer into renderer-owned slots (Backend::share_output). A display frame that
/// writes slot `s` is bracketed by begin_frame and end_frame: the backend's device work after
/// begin_frame waits until the slot's timeline reaches `wait_value` (the reader is done with it),
/// writes the current state and every step's result into the slot, and end_frame signals
/// `signal_value` once those writes are done. No host thread waits for either.
class SharedOutput {
public:
    virtual ~SharedOutput() = default;
    SharedOutput() = default;
    SharedOutput(const SharedOutput&) = delete;
    SharedOutput& operator=(const SharedOutput&) = delete;

    [[nodiscard]] virtual int slots() const = 0;
    /// Binds slot `slot` ([0, slots())) as the output of the steps that follow and stamps `stamp`.
    virtual void begin_frame(int slot, std::uint64_t wait_value, std::uint64_t stamp) = 0;
    /// Stamps the slot again, signals `signal_value` (above every value the slot's timeline had) and
    /// unbinds it: steps outside a frame write nothing shared.
    virtual void end_frame(std::uint64_t signal_value) = 0;
};

class World;

/// Zero-copy output for `world` as it is now (Backend::share_output): builds the world first, so
/// that the writer knows how many vertices precede each slot's stamps. Adding a cloth or collider
/// afterwards rebuilds the world; the writer then refuses to write (share again). nullptr, with the
/// reason in `why`, where the backend cannot share.
[[nodiscard]] std::unique_ptr<SharedOutput> share_output(World& world, std::span<const SharedSlotHandle> slots,
                                                         const DeviceUuid& device, std::string& why);

}  // namespace weft
