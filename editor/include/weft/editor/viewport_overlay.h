#pragma once
/// @file
/// What the View panel draws over the shaded picture (docs/editor.md, "Display"). The cloth's
/// wireframe, vertex normals, contacts and pins are drawn by the renderer from the cloth buffer the
/// solver wrote, depth-tested (`overlay_lines`, RenderFrame::lines; the marks as OverlayPoints): no
/// copy of the positions through the host to draw them. Which vertices are marked comes from the
/// world: pins from the model, cloth contacts and contacts with an analytic collider from the backend
/// (World::contact_vertices, World::collider_contact_vertices: ids, not positions). The grab's
/// spring is a picture-space mark drawn by ImGui in the window's overlay pass.
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
    std::vector<OverlaySegment> segments;  ///< ImGui's: the grab's spring
    std::vector<OverlayMark> marks;        ///< ImGui's: the grab's ends
    /// The renderer's marks (RenderFrame::lines.points): collider contacts (orange), cloth contacts
    /// (magenta), pins (blue), as indices into the cloth vertex buffer (make_render_scene's order).
    std::vector<render::OverlayPoints> points;
    std::size_t contacts = 0;  ///< vertices in an active contact with an analytic collider (the last substep)
    bool collider_contacts_reported = true;  ///< false: the backend does not report them
    std::size_t cloth_contacts = 0;       ///< vertices in a proximity contact (cloth or a mesh collider)
    bool cloth_contacts_reported = true;  ///< false: the backend does not report its proximity contacts
    std::size_t pins = 0;      ///< pin marks drawn
    bool grab = false;         ///< the grab's spring is drawn
};

/// The lines the renderer draws for the toggles in `options`: the wireframe, and normals 1.5 mean
/// rest edges long (of the cloth with the shortest edges).
[[nodiscard]] render::OverlayLines overlay_lines(const World& world, const DisplayOptions& options);

/// The marks of `world` for the contact and pin toggles in `options` (contacts: orange against
/// analytic colliders, magenta in the backend's proximity pairs with cloth or a mesh collider; pins
/// blue), for the renderer; the grab's spring whenever a vertex is grabbed, as drawn with `camera`
/// on a `width`×`height` picture (left out behind the camera). Reads the positions of a cloth only
/// for the grab.
[[nodiscard]] ViewportOverlay build_viewport_overlay(World& world, const render::Camera& camera, int width, int height,
                                                     const DisplayOptions& options);

/// Draws `overlay` into ImGui's background list (under the panels, over the picture). Call between
/// ImGuiLayer::begin_frame and end_frame.
void draw_viewport_overlay(const ViewportOverlay& overlay);

}  // namespace weft::editor
