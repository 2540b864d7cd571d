#pragma once
/// @file
/// What the View panel draws over the shaded picture (docs/editor.md, "Display"): the cloth's
/// wireframe, vertex normals, the vertices touching a collider, pins and the grab's spring. Built
/// as picture-space lines and marks from a host copy of the state (World::positions), then drawn by
/// ImGui in the window's overlay pass; the cloth itself is still drawn from the solver's buffers.
/// Lines are not depth-tested: the wireframe of the cloth's far side shows through it.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "weft/render/render_scene.h"
#include "weft/world.h"

#include "weft/editor/session.h"

namespace weft::editor {

/// Colours as ImGui packs them (IM_COL32: R in the low byte, A in the high byte).
constexpr std::uint32_t overlay_colour(unsigned r, unsigned g, unsigned b, unsigned a = 255) {
    return r | (g << 8U) | (b << 16U) | (a << 24U);
}

struct OverlaySegment {
    float x0 = 0.0F, y0 = 0.0F, x1 = 0.0F, y1 = 0.0F;  ///< picture pixels from the top-left corner
    std::uint32_t colour = 0;
};

struct OverlayMark {
    enum class Shape : unsigned char { square, dot, cross } shape = Shape::dot;
    float x = 0.0F, y = 0.0F;  ///< picture pixels
    float size = 3.0F;         ///< half-width, pixels
    std::uint32_t colour = 0;
};

struct ViewportOverlay {
    std::vector<OverlaySegment> segments;
    std::vector<OverlayMark> marks;
    std::size_t edges = 0;     ///< wireframe edges drawn (each shared edge once)
    std::size_t normals = 0;   ///< normal lines drawn
    std::size_t contacts = 0;  ///< vertices within their contact thickness of an analytic collider
    std::size_t pins = 0;      ///< pin marks drawn
    bool grab = false;         ///< the grab's spring is drawn
};

/// The overlay of `world` as drawn with `camera` on a `width`×`height` picture, for the toggles in
/// `options`; the grab's spring whenever a vertex is grabbed. Points behind the camera are left
/// out. Reads the positions of a cloth only when something is drawn for it.
[[nodiscard]] ViewportOverlay build_viewport_overlay(World& world, const render::Camera& camera, int width, int height,
                                                     const DisplayOptions& options);

/// Draws `overlay` into ImGui's background list (under the panels, over the picture). Call between
/// ImGuiLayer::begin_frame and end_frame.
void draw_viewport_overlay(const ViewportOverlay& overlay);

}  // namespace weft::editor
