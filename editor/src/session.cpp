// The editor's session (see session.h).
#include "weft/editor/session.h"

#include <utility>
#include <vector>

namespace weft::editor {

Session::Session(SceneDesc scene, std::string backend, BackendOptions options, std::unique_ptr<World> world,
                 double time_scale)
    : scene_(std::move(scene)),
      backend_(std::move(backend)),
      options_(options),
      world_(std::move(world)),
      parameters_(*world_) {
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

}  // namespace weft::editor
