#pragma once
/// @file
/// The mouse on the cloth (docs/editor.md, "Mouse"): which cloth vertex is under the cursor, and
/// where a dragged vertex should go. Pure geometry on the camera the picture was drawn with, so it
/// is tested without a window.
#include <cstddef>
#include <cstdint>
#include <optional>

#include "weft/render/render_scene.h"
#include "weft/world.h"

namespace weft::editor {

/// A ray from the camera through a pixel, m.
struct CursorRay {
    Vec3d origin{};
    Vec3d direction{};  ///< unit
};

/// The ray through pixel (`x`, `y`) (pixels from the picture's top-left corner, fractional) of a
/// `width`×`height` picture drawn with `camera` (the projection of the renderers, frame_uniforms).
[[nodiscard]] CursorRay cursor_ray(const render::Camera& camera, int width, int height, double x, double y);

/// Where world point `p` (m) lands on the `width`×`height` picture drawn with `camera`, in pixels
/// from the top-left corner; std::nullopt behind the near plane.
[[nodiscard]] std::optional<glm::dvec2> project_to_picture(const render::Camera& camera, int width, int height,
                                                           const Vec3d& p);

/// A cloth vertex found under the cursor.
struct VertexPick {
    std::size_t cloth = 0;
    std::uint32_t vertex = 0;
    Vec3d position{};     ///< m, where it is now
    double pixels = 0.0;  ///< its distance from the cursor on the picture
};

/// The cloth vertex drawn within `radius` pixels of (`x`, `y`) that is nearest the camera (the one
/// in front where cloth overlaps); std::nullopt where there is none. Reads every cloth's positions.
[[nodiscard]] std::optional<VertexPick> pick_vertex(World& world, const render::Camera& camera, int width, int height,
                                                    double x, double y, double radius = 12.0);

/// Where the cursor at (`x`, `y`) puts a dragged vertex: on the plane through `through` that faces
/// the camera (the vertex keeps its depth while the mouse moves it). `through` itself where the ray
/// runs parallel to that plane.
[[nodiscard]] Vec3d drag_target(const render::Camera& camera, int width, int height, double x, double y,
                                 const Vec3d& through);

}  // namespace weft::editor
