// The View panel's overlay (see viewport_overlay.h).
#include "weft/backend/model.h"
#include "weft/editor/viewport_overlay.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include <imgui.h>

#include "weft/editor/vertex_picking.h"
#include "weft/physics/vec.h"

namespace weft::editor {
namespace {

// The renderer's marks, linear RGB (the sRGB of orange 255,140,0, magenta 230,40,200, blue 30,60,230).
constexpr glm::vec3 kContact{1.0F, 0.262F, 0.0F};
constexpr glm::vec3 kClothContact{0.791F, 0.021F, 0.578F};
constexpr glm::vec3 kPin{0.013F, 0.045F, 0.791F};
constexpr std::uint32_t kGrab = overlay_colour(255, 220, 40);

// The mean rest edge length, m: the scale of a normal's line.
double rest_spacing(const Fabric& fabric) {
    const auto rest = fabric.rest_positions();
    double sum = 0.0;
    std::size_t count = 0;
    for (const Triangle& t : fabric.triangles())
        for (int k = 0; k < 3; ++k) {
            sum += physics::length(rest[t.v[(k + 1) % 3]] - rest[t.v[k]]);
            ++count;
        }
    return count > 0 ? sum / static_cast<double>(count) : 0.01;
}

}  // namespace

render::OverlayLines overlay_lines(const World& world, const DisplayOptions& options) {
    render::OverlayLines lines;
    lines.wireframe = options.wireframe;
    if (options.normals) {
        double spacing = 0.0;
        for (const ClothDesc& cloth : world.model().cloths) {
            const double s = rest_spacing(*cloth.fabric);
            spacing = spacing == 0.0 ? s : std::min(spacing, s);
        }
        lines.normal_length = static_cast<float>(1.5 * (spacing > 0.0 ? spacing : 0.01));
    }
    return lines;
}

ViewportOverlay build_viewport_overlay(World& world, const render::Camera& camera, int width, int height,
                                       const DisplayOptions& options) {
    ViewportOverlay out;
    const auto project = [&](const Vec3d& p) { return project_to_picture(camera, width, height, p); };
    const auto segment = [&](const Vec3d& a, const Vec3d& b, std::uint32_t colour) {
        const std::optional<glm::dvec2> pa = project(a), pb = project(b);
        if (!pa || !pb) return false;
        out.segments.push_back({static_cast<float>(pa->x), static_cast<float>(pa->y), static_cast<float>(pb->x),
                                static_cast<float>(pb->y), colour});
        return true;
    };
    const auto mark = [&](const Vec3d& p, OverlayMark::Shape shape, float size, std::uint32_t colour) {
        const std::optional<glm::dvec2> q = project(p);
        if (!q) return false;
        out.marks.push_back({shape, static_cast<float>(q->x), static_cast<float>(q->y), size, colour});
        return true;
    };
    const Model& model = world.model();

    render::OverlayPoints collider_contacts{.vertices = {}, .colour = kContact};
    render::OverlayPoints cloth_contacts{.vertices = {}, .colour = kClothContact};
    render::OverlayPoints pin_marks{.vertices = {}, .colour = kPin};
    std::uint32_t first = 0;  // the cloth's first vertex in the cloth buffer (make_render_scene's order)
    for (std::size_t c = 0; c < model.cloths.size(); ++c) {
        const ClothDesc& cloth = model.cloths[c];
        const auto vertex_count = static_cast<std::uint32_t>(cloth.fabric->vertex_count());
        const bool grabbed = model.grab && model.grab->cloth == c;
        if (options.contacts) {
            // Against an analytic collider: the contacts the solver's last assembly found active.
            if (const std::optional<std::vector<std::uint32_t>> touching = world.collider_contact_vertices(c)) {
                for (const std::uint32_t v : *touching) collider_contacts.vertices.push_back(first + v);
            } else {
                out.collider_contacts_reported = false;
            }

            // Cloth against cloth (or a mesh collider): the backend's own proximity pairs.
            if (const std::optional<std::vector<std::uint32_t>> touching = world.contact_vertices(c)) {
                for (const std::uint32_t v : *touching) cloth_contacts.vertices.push_back(first + v);
            } else {
                out.cloth_contacts_reported = false;
            }
        }
        if (options.pins)
            for (const PinDesc& pin : cloth.pins) pin_marks.vertices.push_back(first + pin.vertex);
        if (grabbed) {
            const VertexGrab& g = *model.grab;
            const Vec3d at = world.positions(c)[g.vertex];
            out.grab = segment(at, g.target, kGrab);
            (void)mark(g.target, OverlayMark::Shape::cross, 6.0F, kGrab);
            (void)mark(at, OverlayMark::Shape::dot, 3.5F, kGrab);
        }
        first += vertex_count;
    }
    out.contacts = collider_contacts.vertices.size();
    out.cloth_contacts = cloth_contacts.vertices.size();
    out.pins = pin_marks.vertices.size();
    for (render::OverlayPoints* list : {&collider_contacts, &cloth_contacts, &pin_marks})
        if (!list->vertices.empty()) out.points.push_back(std::move(*list));
    return out;
}

void draw_viewport_overlay(const ViewportOverlay& overlay) {
    ImDrawList* list = ImGui::GetBackgroundDrawList();
    for (const OverlaySegment& s : overlay.segments) list->AddLine(ImVec2(s.x0, s.y0), ImVec2(s.x1, s.y1), s.colour, 1.0F);
    for (const OverlayMark& m : overlay.marks) {
        const ImVec2 c(m.x, m.y);
        switch (m.shape) {
            case OverlayMark::Shape::square:
                list->AddRectFilled(ImVec2(c.x - m.size, c.y - m.size), ImVec2(c.x + m.size, c.y + m.size), m.colour);
                break;
            case OverlayMark::Shape::dot:
                list->AddCircleFilled(c, m.size, m.colour, 8);
                break;
            case OverlayMark::Shape::cross:
                list->AddLine(ImVec2(c.x - m.size, c.y - m.size), ImVec2(c.x + m.size, c.y + m.size), m.colour, 2.0F);
                list->AddLine(ImVec2(c.x - m.size, c.y + m.size), ImVec2(c.x + m.size, c.y - m.size), m.colour, 2.0F);
                break;
        }
    }
}

}  // namespace weft::editor
