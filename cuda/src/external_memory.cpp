// Imports of renderer memory and timeline semaphores (see weft/cuda/external_memory.h).
#include "weft/cuda/external_memory.h"

#include <cuda_runtime_api.h>
#include <unistd.h>

#include <string>

#include "cuda_check.h"
#include "weft/error.h"

namespace weft::cuda {
namespace {

[[noreturn]] void import_failed(const char* what, cudaError_t err, int fd) {
    // On failure the fd still belongs to the caller's side of the contract: close it here, since the
    // handle says the importer owns it.
    if (fd >= 0) ::close(fd);
    cudaGetLastError();
    throw Error(std::string("CUDA interop: ") + what + " failed: " + cudaGetErrorName(err) + " (" +
                cudaGetErrorString(err) + ")");
}

}  // namespace

ImportedBuffer::ImportedBuffer(int device, const ExternalMemoryHandle& handle) : size_(handle.size), device_(device) {
    if (handle.fd < 0) throw Error("CUDA interop: no memory to import (fd " + std::to_string(handle.fd) + ")");
    if (handle.size == 0 || handle.offset + handle.size > handle.allocation_size)
        import_failed("importing memory (the buffer does not lie inside the allocation)", cudaErrorInvalidValue,
                      handle.fd);
    WEFT_CUDA_CHECK(cudaSetDevice(device));
    cudaExternalMemoryHandleDesc desc{};
    desc.type = cudaExternalMemoryHandleTypeOpaqueFd;
    desc.handle.fd = handle.fd;
    desc.size = handle.allocation_size;
    desc.flags = handle.dedicated ? cudaExternalMemoryDedicated : 0;
    cudaExternalMemory_t memory = nullptr;
    if (const cudaError_t err = cudaImportExternalMemory(&memory, &desc); err != cudaSuccess)
        import_failed("cudaImportExternalMemory", err, handle.fd);
    // From here CUDA owns the fd.
    cudaExternalMemoryBufferDesc buffer{};
    buffer.offset = handle.offset;
    buffer.size = handle.size;
    void* pointer = nullptr;
    if (const cudaError_t err = cudaExternalMemoryGetMappedBuffer(&pointer, memory, &buffer); err != cudaSuccess) {
        cudaDestroyExternalMemory(memory);
        import_failed("cudaExternalMemoryGetMappedBuffer", err, -1);
    }
    memory_ = memory;
    pointer_ = pointer;
}

ImportedBuffer::~ImportedBuffer() {
    cudaSetDevice(device_);
    if (pointer_ != nullptr) cudaFree(pointer_);  // mapped buffers are freed with cudaFree
    if (memory_ != nullptr) cudaDestroyExternalMemory(static_cast<cudaExternalMemory_t>(memory_));
}

ImportedTimeline::ImportedTimeline(int device, const ExternalTimelineHandle& handle) : device_(device) {
    if (handle.fd < 0) throw Error("CUDA interop: no semaphore to import (fd " + std::to_string(handle.fd) + ")");
    WEFT_CUDA_CHECK(cudaSetDevice(device));
    cudaExternalSemaphoreHandleDesc desc{};
    desc.type = cudaExternalSemaphoreHandleTypeTimelineSemaphoreFd;
    desc.handle.fd = handle.fd;
    cudaExternalSemaphore_t semaphore = nullptr;
    if (const cudaError_t err = cudaImportExternalSemaphore(&semaphore, &desc); err != cudaSuccess)
        import_failed("cudaImportExternalSemaphore (timeline)", err, handle.fd);
    semaphore_ = semaphore;
}

ImportedTimeline::~ImportedTimeline() {
    cudaSetDevice(device_);
    if (semaphore_ != nullptr) cudaDestroyExternalSemaphore(static_cast<cudaExternalSemaphore_t>(semaphore_));
}

void ImportedTimeline::wait(std::uint64_t value, CUstream_st* stream) const {
    cudaExternalSemaphoreWaitParams params{};
    params.params.fence.value = value;
    const auto semaphore = static_cast<cudaExternalSemaphore_t>(semaphore_);
    WEFT_CUDA_CHECK(cudaWaitExternalSemaphoresAsync(&semaphore, &params, 1, stream));
}

void ImportedTimeline::signal(std::uint64_t value, CUstream_st* stream) const {
    cudaExternalSemaphoreSignalParams params{};
    params.params.fence.value = value;
    const auto semaphore = static_cast<cudaExternalSemaphore_t>(semaphore_);
    WEFT_CUDA_CHECK(cudaSignalExternalSemaphoresAsync(&semaphore, &params, 1, stream));
}

}  // namespace weft::cuda
