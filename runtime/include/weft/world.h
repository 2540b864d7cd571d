#pragma once
/// @file
/// `World`: the object a game holds. Add cloths, colliders and motions, then call `step()` once a
/// frame.
///
/// @code
///   weft::World world({}, "cpu");
///   auto fabric = weft::Fabric::cook(weft::make_grid(1.0, 1.0, 32, 32));
///   world.add_cloth({.name = "sheet", .fabric = fabric});
///   for (int frame = 0; frame < 600; ++frame) world.step();
/// @endcode

#include <cstddef>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "weft/backend.h"
#include "weft/model.h"

namespace weft {

class World {
public:
    /// Creates a world stepped by the backend called `backend` ("cpu", "cuda", …).
    explicit World(const WorldDesc& desc = {}, std::string_view backend = "cpu", const BackendOptions& options = {});
    ~World();
    World(const World&) = delete;
    World& operator=(const World&) = delete;

    /// Adds a motion that pins and colliders can follow; returns its index.
    int add_motion(const Motion& motion);
    /// Adds a cloth; returns its index. Throws `weft::Error` on bad input (no fabric, pin index out
    /// of range, material out of range).
    std::size_t add_cloth(const ClothDesc& cloth);
    /// Adds a collider; returns its index. Throws `weft::Error` if its motion index is out of range.
    std::size_t add_collider(const ColliderDesc& collider);

    /// Advances one frame of `settings().solver.dt` seconds in `substeps` implicit substeps.
    /// Never throws for numerical trouble: the returned stats say what happened.
    const StepStats& step();

    /// Simulated time, s.
    [[nodiscard]] double time() const { return time_; }
    [[nodiscard]] std::size_t steps() const { return steps_; }
    [[nodiscard]] const StepStats& last_stats() const { return stats_; }

    /// Live-editable settings, materials and motions: changes apply at the next step, no rebuild.
    [[nodiscard]] WorldDesc& settings() { return model_.settings; }
    [[nodiscard]] Material& material(std::size_t cloth) { return model_.cloths.at(cloth).material; }
    [[nodiscard]] Motion& motion(int index) { return model_.motions.at(static_cast<std::size_t>(index)); }
    [[nodiscard]] const Model& model() const { return model_; }

    /// Analytic collider `index`: its sizes, friction and motion are read at every substep, so
    /// changes apply at the next step. Its shape (and a mesh collider's triangles) are cooked: add
    /// a new collider for those.
    [[nodiscard]] ColliderDesc& collider(std::size_t index) { return model_.colliders.at(index); }

    /// Pulls a vertex toward a point with a spring from the next step on, replacing any grab (an
    /// editor's drag; weft/grab.h). Moving it is setting it again. Throws `weft::Error` naming the
    /// value for a cloth or vertex out of range or a stiffness or damping outside its range.
    void set_grab(const VertexGrab& grab);
    void release_grab() { model_.grab.reset(); }
    [[nodiscard]] const std::optional<VertexGrab>& grab() const { return model_.grab; }

    /// Pins vertex `vertex` of cloth `cloth` where it is now (false: it was pinned already). Pins
    /// are cooked into the solver: the backend is rebuilt at the next step, and every cloth keeps
    /// its state through it. Throws `weft::Error` for a cloth or vertex out of range.
    bool pin(std::size_t cloth, std::uint32_t vertex);
    /// Removes every pin of vertex `vertex` of cloth `cloth` (false: it had none); rebuilt as pin().
    bool unpin(std::size_t cloth, std::uint32_t vertex);
    [[nodiscard]] bool is_pinned(std::size_t cloth, std::uint32_t vertex) const;

    /// Current positions (m) and velocities (m/s) of a cloth, copied from the backend.
    [[nodiscard]] std::vector<Vec3d> positions(std::size_t cloth) const;
    [[nodiscard]] std::vector<Vec3d> velocities(std::size_t cloth) const;
    /// Overwrites a cloth's state (sizes must equal the fabric's vertex count).
    void set_state(std::size_t cloth, std::span<const Vec3d> positions, std::span<const Vec3d> velocities);

    /// Kinetic + gravitational potential + elastic energy of all cloths, J (diagnostics and tests).
    [[nodiscard]] double energy() const;

    /// Zero-copy output (weft/interop.h, Backend::share_output) for the world as it is now: builds
    /// the backend first, so that the writer knows how many vertices precede each slot's stamps.
    /// Adding a cloth or collider afterwards rebuilds the world; the writer then refuses to write
    /// (share again). nullptr, with the reason in `why`, where the backend cannot share.
    [[nodiscard]] std::unique_ptr<SharedOutput> share_output(std::span<const SharedSlotHandle> slots,
                                                             const DeviceUuid& device, std::string& why);

    [[nodiscard]] Backend& backend() { return *backend_; }
    [[nodiscard]] const Backend& backend() const { return *backend_; }

private:
    void ensure_built() const;
    Model model_;
    std::unique_ptr<Backend> backend_;
    mutable std::uint64_t built_version_ = ~std::uint64_t{0};
    /// Each cloth's vertex count at the last build: a rebuild carries the state of a cloth whose
    /// count did not change (a pin added) instead of starting it again.
    mutable std::vector<std::size_t> built_vertex_counts_;
    double time_ = 0.0;
    std::size_t steps_ = 0;
    StepStats stats_{};
};

}  // namespace weft
