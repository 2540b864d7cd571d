#pragma once
// The uniform blocks of render/shaders/common.glsl, laid out std140, and how a scene and a frame
// fill them. Shared by the Vulkan and the EGL renderer: same numbers in, same picture out.
#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "weft/render/render_scene.h"

namespace weft::render::detail {

/// `Frame` in common.glsl (std140: mat4 = 64 B, vec4 = 16 B).
struct FrameUniforms {
    glm::mat4 view_projection;
    glm::mat4 light_projection;
    glm::vec4 camera_position;  ///< w: shadow map texel size in texture coordinates (1 / size)
    glm::vec4 light_direction;
    glm::vec4 light_colour;  ///< w: ambient strength
    glm::vec4 sky_colour;    ///< w: shadow map texel size in the world, m (the normal offset)
    glm::vec4 ground_colour; ///< w: depth bias of the shadow test
};
static_assert(sizeof(FrameUniforms) == 208, "std140 layout of Frame");

/// `Draw` in common.glsl.
struct DrawUniforms {
    glm::mat4 model;
    glm::vec4 front_colour;
    glm::vec4 back_colour;
    glm::vec4 material;  ///< x: grid spacing (m), y: roughness, z: 1 for cloth; w: overlay normal length (m)
};
static_assert(sizeof(DrawUniforms) == 112, "std140 layout of Draw");

/// Camera and light matrices for an image of `width`×`height` pixels. Clip depth is 0..1 on both
/// APIs (Vulkan natively, OpenGL through glClipControl), and clip y points up: the Vulkan renderer
/// flips its viewport so that both give the same image with rows top to bottom after read-back.
[[nodiscard]] FrameUniforms frame_uniforms(const RenderScene& scene, int width, int height, int shadow_map_size);

/// The uniforms of each draw, in draw order: every cloth, then every collider (model matrices from
/// `frame`; identity where it has fewer entries).
[[nodiscard]] std::vector<DrawUniforms> draw_uniforms(const RenderScene& scene, const RenderFrame& frame);

/// The overlay draws that follow draw_uniforms': the wireframe (line.vert, line.frag; colour, no
/// offset), the normals (colour, material.w the normals' length), then one a point list
/// (point.vert, line.frag; colour, material.w the size in pixels), kMaxOverlayPointLists of them.
inline constexpr std::size_t kOverlayDraws = 2 + kMaxOverlayPointLists;
[[nodiscard]] std::array<DrawUniforms, kOverlayDraws> overlay_uniforms(const OverlayLines& lines);

/// Throws weft::Error naming `renderer` for more point lists than kMaxOverlayPointLists, a point past
/// the `cloth_vertices` of the cloth buffer, or a point size that is not a positive number.
void check_overlay_points(const OverlayLines& lines, std::uint32_t cloth_vertices, std::string_view renderer);

}  // namespace weft::render::detail
