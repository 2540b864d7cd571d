#pragma once
// Shared helpers of the GPU tests. They build and are registered on every machine with nvcc, but
// most CI machines have no GPU: there each test must show as SKIPPED with the reason, not pass
// silently and not fail.

#include <gtest/gtest.h>

#include "weft/cuda/cuda_backend.h"

/// Registers the "cuda" backend, then skips the current test (with the CUDA runtime's reason) when
/// no device is present. Use it first thing in every test that touches the GPU.
#define WEFT_REQUIRE_GPU()                                                                                             \
    do {                                                                                                               \
        ::weft::cuda::register_cuda_backend();                                                                         \
        if (::weft::cuda::devices().empty()) GTEST_SKIP() << "no CUDA device: " << ::weft::cuda::unavailable_reason(); \
    } while (false)
