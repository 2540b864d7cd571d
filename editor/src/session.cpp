// The editor's session (see session.h).
#include "weft/editor/session.h"

#include <chrono>
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
