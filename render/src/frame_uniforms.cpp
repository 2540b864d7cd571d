// Camera, light and per-draw uniforms shared by both renderers (see frame_uniforms.h).
#include "frame_uniforms.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "weft/error.h"

namespace weft::render::detail {

FrameUniforms frame_uniforms(const RenderScene& scene, int width, int height, int shadow_map_size) {
    FrameUniforms u{};
    const Camera& c = scene.camera;
    const float aspect = static_cast<float>(width) / static_cast<float>(std::max(height, 1));
    const glm::mat4 projection = glm::perspectiveRH_ZO(glm::radians(c.fov_degrees), aspect, c.near_plane, c.far_plane);
    // A camera looking straight up or down needs another up vector.
    const glm::vec3 forward = glm::normalize(c.target - c.position);
    const glm::vec3 up = std::abs(forward.y) > 0.999F ? glm::vec3(0.0F, 0.0F, -1.0F) : glm::vec3(0.0F, 1.0F, 0.0F);
    u.view_projection = projection * glm::lookAtRH(c.position, c.target, up);

    // The shadow map: an orthographic box along the light around the bounds' bounding sphere.
    const glm::vec3 d = glm::normalize(scene.light.direction);
    const glm::vec3 centre = 0.5F * (scene.bounds_min + scene.bounds_max);
    const float radius = std::max(0.5F * glm::length(scene.bounds_max - scene.bounds_min), 1e-3F);
    const glm::vec3 light_up = std::abs(d.y) > 0.999F ? glm::vec3(0.0F, 0.0F, 1.0F) : glm::vec3(0.0F, 1.0F, 0.0F);
    const glm::mat4 light_view = glm::lookAtRH(centre - d * (2.0F * radius), centre, light_up);
    const glm::mat4 light_ortho = glm::orthoRH_ZO(-radius, radius, -radius, radius, 0.0F, 4.0F * radius);
    u.light_projection = light_ortho * light_view;

    const float texel = 1.0F / static_cast<float>(std::max(shadow_map_size, 1));
    const float world_texel = 2.0F * radius * texel;  // m
    u.camera_position = glm::vec4(c.position, texel);
    u.light_direction = glm::vec4(d, 0.0F);
    u.light_colour = glm::vec4(scene.light.colour, scene.light.ambient);
    u.sky_colour = glm::vec4(scene.light.sky, world_texel);
    // Depth bias: the depth of 1.5 world texels, a texel's slope at about 56°, in the 0..1 range of
    // the 4·radius deep light box.
    u.ground_colour = glm::vec4(scene.light.ground, 1.5F * world_texel / (4.0F * radius));
    return u;
}

std::vector<DrawUniforms> draw_uniforms(const RenderScene& scene, const RenderFrame& frame) {
    std::vector<DrawUniforms> out;
    out.reserve(scene.cloths.size() + scene.colliders.size());
    for (const ClothDraw& cloth : scene.cloths) {
        DrawUniforms u{};
        u.model = glm::mat4(1.0F);
        u.front_colour = glm::vec4(cloth.front_colour, 1.0F);
        u.back_colour = glm::vec4(cloth.back_colour, 1.0F);
        u.material = glm::vec4(0.0F, 0.85F, 1.0F, 0.0F);
        out.push_back(u);
    }
    for (std::size_t k = 0; k < scene.colliders.size(); ++k) {
        const ColliderDraw& collider = scene.colliders[k];
        DrawUniforms u{};
        u.model = k < frame.collider_models.size() ? frame.collider_models[k] : glm::mat4(1.0F);
        u.front_colour = glm::vec4(collider.colour, 1.0F);
        u.back_colour = glm::vec4(collider.grid_spacing > 0.0F ? collider.line_colour : collider.colour, 1.0F);
        u.material = glm::vec4(collider.grid_spacing, collider.grid_spacing > 0.0F ? 1.0F : 0.5F, 0.0F, 0.0F);
        out.push_back(u);
    }
    return out;
}

std::array<DrawUniforms, kOverlayDraws> overlay_uniforms(const OverlayLines& lines) {
    std::array<DrawUniforms, kOverlayDraws> out{};
    for (DrawUniforms& u : out) u.model = glm::mat4(1.0F);
    out[0].front_colour = glm::vec4(lines.wireframe_colour, 1.0F);
    out[1].front_colour = glm::vec4(lines.normal_colour, 1.0F);
    out[1].material.w = lines.normal_length;
    for (std::size_t p = 0; p < lines.points.size() && p < kMaxOverlayPointLists; ++p) {
        out[2 + p].front_colour = glm::vec4(lines.points[p].colour, 1.0F);
        out[2 + p].material.w = lines.point_size;
    }
    return out;
}

void check_overlay_points(const OverlayLines& lines, std::uint32_t cloth_vertices, std::string_view renderer) {
    if (lines.points.size() > kMaxOverlayPointLists)
        throw Error(std::string(renderer) + ": " + std::to_string(lines.points.size()) + " overlay point lists (at most " +
                    std::to_string(kMaxOverlayPointLists) + ")");
    for (const OverlayPoints& list : lines.points)
        for (const std::uint32_t v : list.vertices)
            if (v >= cloth_vertices)
                throw Error(std::string(renderer) + ": overlay point at cloth vertex " + std::to_string(v) +
                            ", the cloth buffer has " + std::to_string(cloth_vertices));
    if (!(lines.point_size > 0.0F) || !std::isfinite(lines.point_size))
        throw Error(std::string(renderer) + ": overlay point size " + std::to_string(lines.point_size) +
                    " (expected a positive number of pixels)");
}

}  // namespace weft::render::detail
