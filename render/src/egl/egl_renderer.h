#pragma once
// The EGL + OpenGL 4.5 capture renderer (offscreen): see egl_renderer.cpp.
#include <memory>

#include "weft/render/renderer.h"

namespace weft::render::detail {

/// Throws weft::Error when no EGL display gives an OpenGL 4.5 core context (device platform first,
/// then surfaceless Mesa).
[[nodiscard]] std::unique_ptr<Renderer> create_egl_renderer(const RendererOptions& options);

}  // namespace weft::render::detail
