// The editor's session (see session.h).
#include "weft/editor/session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "weft/error.h"

namespace weft::editor {
namespace {

std::vector<std::string> motion_names(const SceneDesc& scene) {
    std::vector<std::string> names;
    for (const SceneMotion& m : scene.motions) names.push_back(m.name);
    return names;
}

}  // namespace

Session::Session(SceneDesc scene, std::string backend, BackendOptions options, std::unique_ptr<World> world,
                 double time_scale)
    : scene_(std::move(scene)),
      backend_(std::move(backend)),
      options_(options),
      world_(std::move(world)),
      parameters_(*world_, motion_names(scene_)) {
    FrameLoop::Options loop_options;
    loop_options.time_scale = time_scale;
    loop_ = std::make_unique<FrameLoop>(*world_, loop_options);
}

double Session::apply(const Parameter& p, double value) {
    applied_at_[p.key] = steps_before_reset_ + loop_->steps();
    return ParameterTable::apply(p, *world_, value);
}

std::optional<std::int64_t> Session::applied_at(const std::string& key) const {
    const auto it = applied_at_.find(key);
    if (it == applied_at_.end()) return std::nullopt;
    // Reported in the current loop's count (a reset starts a new loop at 0).
    return it->second - steps_before_reset_;
}

void Session::save(const std::filesystem::path& path) const {
    SceneDesc tuned = scene_;
    update_scene_from_world(tuned, *world_);
    save_scene(tuned, path);
}

std::filesystem::path Session::default_save_path() const {
    const std::filesystem::path& source = scene_.path;
    return source.parent_path() / (source.stem().string() + "_tuned.toml");
}

void Session::reset() {
    // What the designer tuned survives: only the state goes back to the start.
    const WorldDesc settings = world_->settings();
    std::vector<Material> materials;
    for (std::size_t i = 0; i < world_->model().cloths.size(); ++i) materials.push_back(world_->material(i));
    const bool paused = loop_->paused();
    FrameLoop::Options loop_options;
    loop_options.time_scale = loop_->time_scale();
    steps_before_reset_ += loop_->steps();

    loop_.reset();
    grab_anchor_.reset();  // the new world has no grab
    if (before_rebuild_) before_rebuild_();
    world_.reset();
    world_ = build_world(scene_, backend_, options_);
    world_->settings() = settings;
    for (std::size_t i = 0; i < materials.size() && i < world_->model().cloths.size(); ++i)
        world_->material(i) = materials[i];
    loop_ = std::make_unique<FrameLoop>(*world_, loop_options);
    loop_->set_paused(paused);
    history_.clear();
    ++resets_;
}

void Session::grab(const VertexPick& pick) {
    double mass = 0.0;
    for (const double m : world_->model().cloths.at(pick.cloth).fabric->masses()) mass += m;
    // Strong enough to carry the whole cloth (2 cm of sag under its weight) and to win against its
    // membrane: ten times the stretch stiffness (N/m), so that the vertex follows the cursor to
    // within about a tenth of how far the cloth is stretched to get there.
    const double k = std::max(grab_stiffness_for(mass), 10.0 * world_->material(pick.cloth).stretch_stiffness);
    // Damping near critical for the grabbed vertex on its own (c = 2·sqrt(k·m_vertex)): the drag
    // does not ring, and the rest of the cloth keeps its own damping.
    const double vertex_mass = world_->model().cloths[pick.cloth].fabric->masses()[pick.vertex];
    world_->set_grab({.cloth = pick.cloth, .vertex = pick.vertex, .target = pick.position, .stiffness = k,
                      .damping = std::min(1e6, 2.0 * std::sqrt(k * vertex_mass))});
    grab_anchor_ = pick.position;
    char text[200];
    std::snprintf(text, sizeof text, "grabbed vertex %u of cloth '%s' (spring %.3g N/m)", pick.vertex,
                  world_->model().cloths[pick.cloth].name.c_str(), k);
    message_ = text;
}

void Session::drag_to(const Vec3d& target) {
    if (!world_->grab()) return;
    VertexGrab g = *world_->grab();
    g.target = target;
    world_->set_grab(g);
}

void Session::release_grab() {
    if (!world_->grab()) return;
    const std::optional<double> d = grab_distance();
    char text[160];
    std::snprintf(text, sizeof text, "released vertex %u, %.3f m from the cursor", world_->grab()->vertex, d.value_or(0.0));
    message_ = text;
    world_->release_grab();
    grab_anchor_.reset();
}

std::optional<double> Session::grab_distance() {
    if (!world_->grab()) return std::nullopt;
    const VertexGrab& g = *world_->grab();
    return physics::length(world_->positions(g.cloth)[g.vertex] - g.target);
}

bool Session::toggle_pin(std::size_t cloth, std::uint32_t vertex) {
    if (before_rebuild_) before_rebuild_();
    const bool pinned = world_->is_pinned(cloth, vertex) ? !world_->unpin(cloth, vertex) : world_->pin(cloth, vertex);
    // The rebuild happens at the next read or step; timed here so that the panel can say what it cost.
    const auto start = std::chrono::steady_clock::now();
    (void)world_->positions(cloth);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    char text[200];
    std::snprintf(text, sizeof text, "%s vertex %u of cloth '%s' (solver rebuilt in %.1f ms, state kept)",
                  pinned ? "pinned" : "unpinned", vertex, world_->model().cloths[cloth].name.c_str(), ms);
    message_ = text;
    return pinned;
}

double Session::recook_grid(const std::string& cloth, int cells_x, int cells_y) {
    std::size_t entry = scene_.cloth_placements.size();
    for (std::size_t e = 0; e < scene_.cloth_placements.size(); ++e)
        if (scene_.cloth_placements[e].name == cloth) entry = e;
    if (entry == scene_.cloth_placements.size()) throw Error("re-cook: no cloth '" + cloth + "' in the scene");
    if (cells_x < 1 || cells_y < 1 || cells_x > 4096 || cells_y > 4096)
        throw Error("re-cook: " + std::to_string(cells_x) + "x" + std::to_string(cells_y) +
                    " cells is outside [1, 4096] per side");
    std::size_t triangles_before = 0, triangles_after = 0;
    int old_x = 0, old_y = 0;
    SceneDesc changed = scene_;
    for (SceneCloth& c : changed.cloths) {
        if (c.entry != entry) continue;
        if (c.source.kind != ClothSource::Kind::Grid)
            throw Error("re-cook: cloth '" + cloth + "' comes from a mesh file, not a grid");
        old_x = c.source.cells_x;
        old_y = c.source.cells_y;
        triangles_before += 2 * static_cast<std::size_t>(old_x) * static_cast<std::size_t>(old_y);
        triangles_after += 2 * static_cast<std::size_t>(cells_x) * static_cast<std::size_t>(cells_y);
        c.source.cells_x = cells_x;
        c.source.cells_y = cells_y;
    }
    // What was tuned goes into the changed scene too, so that reset() keeps it.
    update_scene_from_world(changed, *world_);
    const SceneDesc previous = std::exchange(scene_, std::move(changed));
    const auto start = std::chrono::steady_clock::now();
    try {
        reset();
    } catch (...) {
        scene_ = previous;
        reset();
        throw;
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    char text[256];
    std::snprintf(text, sizeof text, "re-cooked cloth '%s': %dx%d -> %dx%d cells (%zu -> %zu triangles) in %.1f ms",
                  cloth.c_str(), old_x, old_y, cells_x, cells_y, triangles_before, triangles_after, ms);
    message_ = text;
    return ms;
}

}  // namespace weft::editor
