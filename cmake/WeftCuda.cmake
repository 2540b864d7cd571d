# weft_enable_cuda(): finds nvcc (on PATH or in /usr/local/cuda) and, when found, enables the CUDA
# language with Weft's defaults and sets WEFT_NVCC_FOUND. Used by the top-level build (the CUDA
# backend) and by tests/physics (the device compile check, which runs even with WEFT_CUDA=OFF).
macro(weft_enable_cuda)
  if(NOT CMAKE_CUDA_COMPILER AND EXISTS /usr/local/cuda/bin/nvcc)
    set(CMAKE_CUDA_COMPILER /usr/local/cuda/bin/nvcc)
  endif()
  include(CheckLanguage)
  check_language(CUDA)
  set(WEFT_NVCC_FOUND OFF)
  if(CMAKE_CUDA_COMPILER)
    set(WEFT_NVCC_FOUND ON)
    # Hopper SASS (H100/H200, where Weft is measured) plus PTX that any GPU from Turing on compiles
    # at load. Override with -DCMAKE_CUDA_ARCHITECTURES=89 (say) for a faster build for one card.
    if(NOT CMAKE_CUDA_ARCHITECTURES)
      set(CMAKE_CUDA_ARCHITECTURES "90-real;75-virtual")
    endif()
    enable_language(CUDA)
    # CMake 3.25 predates nvcc 12's C++20 support and knows no flag for CUDA20, while a CUDA target
    # inherits CXX_STANDARD 20 from the project; tell it the flag (newer CMake already has it).
    if(NOT CMAKE_CUDA20_STANDARD_COMPILE_OPTION)
      set(CMAKE_CUDA20_STANDARD_COMPILE_OPTION "-std=c++20")
      set(CMAKE_CUDA20_EXTENSION_COMPILE_OPTION "-std=c++20")
    endif()
  endif()
endmacro()
