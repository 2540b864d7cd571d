// Picking and dragging cloth vertices with the mouse (see vertex_picking.h).
#include "weft/backend/model.h"
#include "weft/editor/vertex_picking.h"

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>

namespace weft::editor {
namespace {

// The renderers' camera matrix (render/src/frame_uniforms.cpp): right-handed, depth 0..1, y up in
// clip space, up = +Y. Kept in double here: picking compares distances of nearby vertices.
glm::dmat4 view_projection(const render::Camera& c, int width, int height) {
    const double aspect = static_cast<double>(width) / static_cast<double>(std::max(height, 1));
    const glm::dmat4 projection = glm::perspectiveRH_ZO(glm::radians(static_cast<double>(c.fov_degrees)), aspect,
                                                        static_cast<double>(c.near_plane), static_cast<double>(c.far_plane));
    return projection * glm::lookAtRH(glm::dvec3(c.position), glm::dvec3(c.target), glm::dvec3(0.0, 1.0, 0.0));
}

Vec3d to_vec(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

}  // namespace

CursorRay cursor_ray(const render::Camera& camera, int width, int height, double x, double y) {
    const glm::dmat4 inverse = glm::inverse(view_projection(camera, width, height));
    // Pixel centres to normalised device coordinates: rows run down the picture, clip y up.
    const double nx = 2.0 * x / width - 1.0;
    const double ny = 1.0 - 2.0 * y / height;
    const glm::dvec4 near = inverse * glm::dvec4(nx, ny, 0.0, 1.0);
    const glm::dvec4 far = inverse * glm::dvec4(nx, ny, 1.0, 1.0);
    const glm::dvec3 a = glm::dvec3(near) / near.w;
    const glm::dvec3 b = glm::dvec3(far) / far.w;
    return {to_vec(a), to_vec(glm::normalize(b - a))};
}

std::optional<glm::dvec2> project_to_picture(const render::Camera& camera, int width, int height, const Vec3d& p) {
    const glm::dvec4 clip = view_projection(camera, width, height) * glm::dvec4(p.x, p.y, p.z, 1.0);
    if (clip.w < static_cast<double>(camera.near_plane)) return std::nullopt;
    return glm::dvec2((clip.x / clip.w + 1.0) * 0.5 * width, (1.0 - clip.y / clip.w) * 0.5 * height);
}

std::optional<VertexPick> pick_vertex(World& world, const render::Camera& camera, int width, int height, double x,
                                      double y, double radius) {
    const glm::dmat4 vp = view_projection(camera, width, height);
    std::optional<VertexPick> best;
    double best_depth = 0.0;
    for (std::size_t c = 0; c < world.model().cloths.size(); ++c) {
        const std::vector<Vec3d> positions = world.positions(c);
        for (std::uint32_t i = 0; i < positions.size(); ++i) {
            const Vec3d& p = positions[i];
            const glm::dvec4 clip = vp * glm::dvec4(p.x, p.y, p.z, 1.0);
            if (clip.w <= 0.0) continue;  // behind the camera
            const double px = (clip.x / clip.w + 1.0) * 0.5 * width;
            const double py = (1.0 - clip.y / clip.w) * 0.5 * height;
            const double d = std::hypot(px - x, py - y);
            if (d > radius) continue;
            // Nearest the camera first; among vertices at about the same depth (one cloth's
            // neighbours), nearest the cursor.
            const double depth = clip.w;
            const bool nearer = !best || depth < best_depth - 1e-3 || (depth < best_depth + 1e-3 && d < best->pixels);
            if (nearer) {
                best = VertexPick{c, i, p, d};
                best_depth = depth;
            }
        }
    }
    return best;
}

Vec3d drag_target(const render::Camera& camera, int width, int height, double x, double y, const Vec3d& through) {
    const CursorRay ray = cursor_ray(camera, width, height, x, y);
    const glm::dvec3 forward = glm::normalize(glm::dvec3(camera.target) - glm::dvec3(camera.position));
    const Vec3d n{forward.x, forward.y, forward.z};
    const double along = math::dot(ray.direction, n);
    if (std::abs(along) < 1e-9) return through;
    const double t = math::dot(through - ray.origin, n) / along;
    return ray.origin + t * ray.direction;
}

}  // namespace weft::editor
