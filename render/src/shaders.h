#pragma once
// The compiled shaders of render/shaders/: SPIR-V for Vulkan and GLSL text (includes inlined) for
// OpenGL, both generated at build time from the same files (render/CMakeLists.txt).
#include <cstdint>
#include <span>

namespace weft::render::detail {

struct ShaderCode {
    std::span<const std::uint32_t> spirv;  ///< Vulkan 1.1 SPIR-V
    const char* glsl = nullptr;            ///< `#version 450` source for OpenGL 4.5
};

[[nodiscard]] ShaderCode surface_vertex_shader();
[[nodiscard]] ShaderCode surface_fragment_shader();
[[nodiscard]] ShaderCode shadow_vertex_shader();
[[nodiscard]] ShaderCode shadow_fragment_shader();
[[nodiscard]] ShaderCode line_vertex_shader();    ///< the overlay lines (OverlayLines)
[[nodiscard]] ShaderCode line_fragment_shader();
[[nodiscard]] ShaderCode point_vertex_shader();   ///< the overlay points (OverlayLines::points), with line.frag

}  // namespace weft::render::detail
