#pragma once
/// @file
/// Portability macros for the single-source headers: every function in `weft/math/` and
/// `weft/physics/` compiles for the host and, under nvcc, for the device. These headers depend on
/// nothing but the C++ standard library.

#if defined(__CUDACC__)
/// Marks a function callable from host and device code.
#define WEFT_HD __host__ __device__
#else
/// Marks a function callable from host and device code.
#define WEFT_HD
#endif

#if defined(__CUDA_ARCH__)
#define WEFT_DEVICE_CODE 1
#else
#define WEFT_DEVICE_CODE 0
#endif
