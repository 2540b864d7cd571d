#pragma once
/// @file
/// Neutral handles for zero-copy interop between a renderer and a GPU backend (DESIGN.md, "Zero-copy
/// frame loop"): the renderer exports memory and a timeline semaphore as POSIX file descriptors
/// (Vulkan's opaque fd handles), the backend imports them, and neither includes the other's headers.
#include <array>
#include <cstdint>

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
