#pragma once
/// @file
/// Neutral handles for zero-copy interop between a renderer and a GPU backend (DESIGN.md, "Zero-copy
/// frame loop"): the renderer exports memory and a timeline semaphore as POSIX file descriptors
/// (Vulkan's opaque fd handles), the backend imports them, and neither includes the other's headers.
#include <array>
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

/// One shared cloth slot: the memory (vertices, then the stamps) and the timeline semaphore that
/// orders its writer against its reader.
struct SharedSlotHandle {
    ExternalMemoryHandle memory;
    ExternalTimelineHandle timeline;
};

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

}  // namespace weft
