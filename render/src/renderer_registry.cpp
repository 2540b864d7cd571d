// create_renderer: the compiled renderers by name (see renderer.h).
#include <string>

#include "egl/egl_renderer.h"
#include "vulkan/vulkan_renderer.h"
#include "weft/error.h"
#include "weft/render/renderer.h"

namespace weft::render {

std::unique_ptr<Renderer> create_renderer(std::string_view name, const RendererOptions& options) {
    if (options.width < 1 || options.height < 1 || options.width > 16384 || options.height > 16384)
        throw Error("renderer: image size " + std::to_string(options.width) + "×" + std::to_string(options.height) +
                    " is outside 1..16384 pixels per side");
    if (options.samples != 1 && options.samples != 2 && options.samples != 4 && options.samples != 8)
        throw Error("renderer: " + std::to_string(options.samples) + " MSAA samples (expected 1, 2, 4 or 8)");
    if (options.shadow_map_size < 16 || options.shadow_map_size > 16384)
        throw Error("renderer: shadow map size " + std::to_string(options.shadow_map_size) + " is outside 16..16384");
    if (name == "vulkan") return detail::create_vulkan_renderer(options);
    if (name == "egl") return detail::create_egl_renderer(options);
    throw Error("unknown renderer '" + std::string(name) + "' (compiled: vulkan, egl)");
}

std::vector<std::string> renderer_names() { return {"vulkan", "egl"}; }

}  // namespace weft::render
