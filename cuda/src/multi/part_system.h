#pragma once
/// @file
/// One part's linear system as the CG across parts reads it (multi/part_pcg.h): the owned rows of
/// its matrix in sliced ELL (columns in local numbering, ghosts included), the rows held fixed, and
/// the block-Jacobi preconditioner. Both the test and benchmark matrices (PartMatrix) and the
/// solver's own assembled matrix (DeviceSolver in part mode) describe themselves this way.

#include <cuda_runtime_api.h>

#include <cstdint>

namespace weft::cuda::multi {

struct PartSystem {
    int device = 0;                 ///< CUDA device holding every array below
    cudaStream_t stream = nullptr;  ///< where the part's work is enqueued
    std::uint32_t owned = 0;        ///< rows solved here: local vertices [0, owned)
    std::uint32_t local = 0;        ///< owned + ghosts: the component stride of every vector
    const std::uint32_t* slice_start = nullptr;  ///< sliced ELL (device_layout.h), slices covering the owned rows
    const std::uint32_t* column = nullptr;
    const std::uint32_t* diagonal = nullptr;     ///< ELL position of each owned row's diagonal block
    const float* blocks = nullptr;               ///< 9 floats (row-major) per ELL position
    /// Rows whose unknown is prescribed (pinned vertices: their residual and product rows are
    /// filtered to zero, so the start value stays), 1 byte per local vertex; null: none.
    const std::uint8_t* fixed = nullptr;
    /// The block-Jacobi inverse, entry e of row i at [e·local + i]; null: the CG inverts the
    /// diagonal blocks itself at each solve.
    const float* precond = nullptr;
};

}  // namespace weft::cuda::multi
