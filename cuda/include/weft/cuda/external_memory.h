#pragma once
/// @file
/// Renderer memory and timeline semaphores imported into CUDA (weft/backend/interop.h): the buffer the
/// solver's output kernel writes positions and normals into, and the semaphore that orders those
/// writes against the renderer's reads without a host wait. Only the stream is named here, so this
/// header does not need the CUDA headers.
#include <cstdint>

#include "weft/backend/interop.h"

struct CUstream_st;

namespace weft::cuda {

/// An exported allocation mapped as a device pointer on one CUDA device.
class ImportedBuffer {
public:
    /// Imports `handle` on device `device` (its fd then belongs to CUDA). Throws `weft::Error` naming
    /// the CUDA error when the import fails (the fd is closed then too, so it never leaks).
    ImportedBuffer(int device, const ExternalMemoryHandle& handle);
    ~ImportedBuffer();
    ImportedBuffer(const ImportedBuffer&) = delete;
    ImportedBuffer& operator=(const ImportedBuffer&) = delete;

    /// The buffer's first byte (handle.offset into the allocation), on the importing device.
    [[nodiscard]] void* device_pointer() const { return pointer_; }
    [[nodiscard]] std::uint64_t size() const { return size_; }

private:
    void* memory_ = nullptr;  // cudaExternalMemory_t
    void* pointer_ = nullptr;
    std::uint64_t size_ = 0;
    int device_ = 0;
};

/// An exported timeline semaphore: stream-ordered waits and signals of its 64-bit value.
class ImportedTimeline {
public:
    /// Imports `handle` on device `device`; throws `weft::Error` as ImportedBuffer does.
    ImportedTimeline(int device, const ExternalTimelineHandle& handle);
    ~ImportedTimeline();
    ImportedTimeline(const ImportedTimeline&) = delete;
    ImportedTimeline& operator=(const ImportedTimeline&) = delete;

    /// Work enqueued on `stream` after this waits until the semaphore reaches `value`.
    void wait(std::uint64_t value, CUstream_st* stream) const;
    /// Sets the semaphore to `value` once the work enqueued on `stream` before this has finished.
    void signal(std::uint64_t value, CUstream_st* stream) const;

private:
    void* semaphore_ = nullptr;  // cudaExternalSemaphore_t
    int device_ = 0;
};

}  // namespace weft::cuda
