#pragma once
/// @file
/// Facts fixed when `weft` was built: version, build type, optional components, source tree.

#include <string_view>

namespace weft::cli {

struct BuildInfo {
    std::string_view version;     ///< project version from the top-level CMakeLists.txt
    std::string_view build_type;  ///< CMAKE_BUILD_TYPE
    std::string_view source_dir;  ///< the tree this binary was built from (scene lookup fallback)
    bool cuda = false;            ///< CUDA backend compiled (WEFT_CUDA found nvcc)
    bool render = false;          ///< Vulkan renderer and EGL capture (WEFT_RENDER)
    bool editor = false;          ///< ImGui editor (WEFT_EDITOR)
    bool assets = false;          ///< assimp mesh import (WEFT_ASSETS)
};

[[nodiscard]] const BuildInfo& build_info();

}  // namespace weft::cli
