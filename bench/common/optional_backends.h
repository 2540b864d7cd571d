#pragma once
// What a benchmark that loads scenes and picks a backend by name sets up first, as the weft tool does:
// the mesh loader (WEFT_HAVE_ASSETS, linked weft::assets) and the CUDA backend (WEFT_HAVE_CUDA_BACKEND,
// linked weft::cuda). Without them a scene with mesh files, or --backend cuda, is refused by name.

#if WEFT_HAVE_ASSETS
#include "weft/assets/assimp_loader.h"
#endif
#if WEFT_HAVE_CUDA_BACKEND
#include "weft/cuda/cuda_backend.h"
#endif

namespace weft::bench {

inline void install_optional_backends() {
#if WEFT_HAVE_ASSETS
    weft::assets::install_mesh_loader();
#endif
#if WEFT_HAVE_CUDA_BACKEND
    weft::cuda::register_cuda_backend();
#endif
}

}  // namespace weft::bench
