#pragma once
// Every CUDA runtime call and kernel launch is checked; a failure throws weft::Error naming the call,
// the file and the line (docs/design.md, "Errors and numerical failures").

#include <cuda_runtime_api.h>

#include <atomic>
#include <map>
#include <string>

#include "weft/error.h"

namespace weft::cuda {

/// Launch record (launch_record.cpp): while on, every checked launch (WEFT_CUDA_CHECK_LAUNCH) counts
/// under "FILE: NAME" (FILE relative to cuda/src, e.g. "collision/broad_phase_gpu.cu: bounds_kernel"),
/// process-wide. Kernels inside a replayed CUDA graph are counted once, at capture:
/// record with graphs off (WEFT_CUDA_GRAPHS=0, CudaBackendApi::set_use_graph) to see every launch.
/// For the stage-pruning test and benchmark: which kernels a scene launches.
inline std::atomic<bool> launch_record_on{false};
/// Kernels this thread has enqueued: every checked launch, and each CUDA graph launch adds the kernel
/// nodes it holds (a graph's capture is taken back out). The backends report the difference over a
/// step as StepStats::kernels_launched. Per thread, so that worlds stepped side by side on several
/// threads each count their own.
inline thread_local long long thread_kernel_launches = 0;
void note_launch(const char* file, const char* name);
/// Starts counting (clears the counts).
void start_launch_record();
/// Stops counting and returns the launches by name.
[[nodiscard]] std::map<std::string, long long> stop_launch_record();

[[noreturn]] inline void throw_cuda_error(cudaError_t err, const char* what, const char* file, int line) {
    throw Error(std::string(file) + ":" + std::to_string(line) + ": " + what + ": " + cudaGetErrorName(err) + " (" +
                cudaGetErrorString(err) + ")");
}

/// After a failed step: whether `device`'s context is still usable, leaving it current and its
/// error state cleared. An asynchronous error is reported by the first synchronisation and
/// cleared; a sticky one (the context is lost) by every one, so a second synchronisation tells
/// them apart.
[[nodiscard]] inline bool context_usable_after_fault(int device) {
    (void)cudaSetDevice(device);
    (void)cudaGetLastError();
    bool usable = cudaDeviceSynchronize() == cudaSuccess;
    if (!usable) {
        (void)cudaGetLastError();
        usable = cudaDeviceSynchronize() == cudaSuccess;
    }
    (void)cudaGetLastError();
    return usable;
}

}  // namespace weft::cuda

/// Checks a CUDA runtime call.
#define WEFT_CUDA_CHECK(call)                                                                     \
    do {                                                                                          \
        const cudaError_t weft_cuda_err_ = (call);                                                \
        if (weft_cuda_err_ != cudaSuccess) ::weft::cuda::throw_cuda_error(weft_cuda_err_, #call, __FILE__, __LINE__); \
    } while (0)

/// Checks the launch just made (configuration errors); execution errors surface at the next sync.
#define WEFT_CUDA_CHECK_LAUNCH(name)                                                              \
    do {                                                                                          \
        const cudaError_t weft_cuda_err_ = cudaGetLastError();                                    \
        if (weft_cuda_err_ != cudaSuccess) ::weft::cuda::throw_cuda_error(weft_cuda_err_, "launch of " name, __FILE__, __LINE__); \
        ++::weft::cuda::thread_kernel_launches;                                                   \
        if (::weft::cuda::launch_record_on.load(std::memory_order_relaxed)) ::weft::cuda::note_launch(__FILE__, name);       \
    } while (0)
