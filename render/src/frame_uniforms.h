#pragma once
// The uniform blocks of render/shaders/common.glsl, laid out std140, and how a scene and a frame
// fill them. Shared by the Vulkan and the EGL renderer: same numbers in, same picture out.
#include <array>

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

/// The two overlay draws that follow draw_uniforms' (line.vert, line.frag): the wireframe (colour,
/// no offset), then the normals (colour, material.w the normals' length).
[[nodiscard]] std::array<DrawUniforms, 2> overlay_uniforms(const OverlayLines& lines);

}  // namespace weft::render::detail
