#pragma once
/// @file
/// One part's linear system as the CG across parts reads it (multi/part_pcg.h): the owned rows of
/// its matrix in sliced ELL (columns in local numbering, ghosts included), the rows held fixed, and
/// the block-Jacobi preconditioner. Both the test and benchmark matrices (PartMatrix) and the
/// solver's own assembled matrix (DeviceSolver in part mode) describe themselves this way.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>

#include "device_view.h"

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
    /// With the multilevel Schwarz preconditioner across the parts: the part's solver view, its
    /// levels factored (mas.levels > 0; level 0 the part's, levels ≥ 1 whole, part_schwarz.h), and
    /// the floats of level 1's restricted residual this part computes, [level1_begin, level1_end)
    /// of mas.level[1].values, which the CG gathers from every part. Null: block-Jacobi.
    const DeviceView* schwarz = nullptr;
    std::size_t level1_begin = 0, level1_end = 0;
    /// Proximity contacts at the owned rows (capacity 0: none): the whole contact list, this part's
    /// incidence; the pairs read the CG's vector from the whole-size copy the CG keeps filled
    /// (PartPcg::set_contact_mirror).
    ContactView contacts;
};

}  // namespace weft::cuda::multi
