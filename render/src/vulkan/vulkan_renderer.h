#pragma once
// The Vulkan renderer (offscreen): see vulkan_renderer.cpp.
#include <memory>

#include "weft/render/renderer.h"

namespace weft::render::detail {

/// Throws weft::Error when no Vulkan device can render (no loader, no ICD, no validation layer
/// when asked for).
[[nodiscard]] std::unique_ptr<Renderer> create_vulkan_renderer(const RendererOptions& options);

}  // namespace weft::render::detail
