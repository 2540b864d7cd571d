#pragma once
// Every CUDA runtime call and kernel launch is checked; a failure throws weft::Error naming the call,
// the file and the line (docs/design.md, "Errors and numerical failures").

#include <cuda_runtime_api.h>

#include <string>

#include "weft/error.h"

namespace weft::cuda {

[[noreturn]] inline void throw_cuda_error(cudaError_t err, const char* what, const char* file, int line) {
    throw Error(std::string(file) + ":" + std::to_string(line) + ": " + what + ": " + cudaGetErrorName(err) + " (" +
                cudaGetErrorString(err) + ")");
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
    } while (0)
