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
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "weft/backend_options.h"
#include "weft/cloth.h"
#include "weft/collider.h"
#include "weft/grab.h"
#include "weft/motion.h"
#include "weft/settings.h"
#include "weft/stats.h"

namespace weft {

// The backend kit's types (weft/backend/): a game never needs their definitions.
class Backend;
struct Model;
struct EnergyAudit;

/// A pair of triangles going through each other (World::intersections): a cloth's triangle, and
/// another cloth triangle (of the same cloth or another) or a mesh collider's.
struct IntersectingTriangles {
    std::size_t cloth = 0;          ///< the cloth
    std::uint32_t triangle = 0;     ///< its triangle, in the fabric's order
    bool with_collider = false;     ///< the other triangle is a mesh collider's
    std::size_t other = 0;          ///< the other cloth, or the collider (World::collider index)
    std::uint32_t other_triangle = 0;  ///< in that cloth's fabric, or that collider's mesh
};

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
    [[nodiscard]] WorldDesc& settings();
    [[nodiscard]] const WorldDesc& settings() const;
    [[nodiscard]] Material& material(std::size_t cloth);
    [[nodiscard]] Motion& motion(int index);

    /// Analytic collider `index`: its sizes, friction and motion are read at every substep, so
    /// changes apply at the next step. Its shape is cooked: change it with set_collider_shape (a mesh
    /// collider's triangles: add a new collider).
    [[nodiscard]] ColliderDesc& collider(std::size_t index);
    /// Turns analytic collider `index` into another analytic shape (plane, sphere, capsule, box),
    /// keeping its name, motion, place and friction. The new shape takes the old one's extent along
    /// its local y axis and across it (a sphere: its radius both ways; a capsule: half height +
    /// radius, radius; a box: its y half extent, the larger of x and z; a plane: its `radius` field):
    /// a box of those half extents, a capsule of the radius across reaching as far along y, a sphere
    /// of the larger. A pole stays a pole, a ball a cube.
    /// The shape is cooked into the backend: the world is rebuilt at the next step, every cloth
    /// keeping its state (as pin()). Throws weft::Error naming the collider for an index out of
    /// range or a mesh on either side (a mesh collider's triangles come from add_collider).
    void set_collider_shape(std::size_t index, ColliderShape shape);

    /// What was added, in order: cloth `index` as added (its material as tuned since, its pins as
    /// they are now), and the counts. Throw std::out_of_range for an index out of range.
    [[nodiscard]] const ClothDesc& cloth(std::size_t index) const;
    [[nodiscard]] std::size_t cloth_count() const;
    [[nodiscard]] std::size_t collider_count() const;
    [[nodiscard]] std::size_t motion_count() const;

    /// Everything the backend simulates (weft/backend/model.h): for tools and backends.
    [[nodiscard]] const Model& model() const;

    /// Pulls a vertex toward a point with a spring from the next step on, replacing any grab (an
    /// editor's drag; weft/grab.h). Moving it is setting it again. Throws `weft::Error` naming the
    /// value for a cloth or vertex out of range or a stiffness or damping outside its range.
    void set_grab(const VertexGrab& grab);
    void release_grab();
    [[nodiscard]] const std::optional<VertexGrab>& grab() const;

    /// Pins vertex `vertex` of cloth `cloth` where it is now (false: it was pinned already). Pins
    /// are cooked into the solver: the backend is rebuilt at the next step, and every cloth keeps
    /// its state through it. Throws `weft::Error` for a cloth or vertex out of range.
    bool pin(std::size_t cloth, std::uint32_t vertex);
    /// Removes every pin of vertex `vertex` of cloth `cloth` (false: it had none); rebuilt as pin().
    bool unpin(std::size_t cloth, std::uint32_t vertex);
    [[nodiscard]] bool is_pinned(std::size_t cloth, std::uint32_t vertex) const;

    /// The vertices of `cloth` in a proximity contact with cloth or a mesh collider in the last
    /// substep (Backend::contact_vertices), or std::nullopt where the backend does not report them.
    [[nodiscard]] std::optional<std::vector<std::uint32_t>> contact_vertices(std::size_t cloth) const;
    /// The vertices of `cloth` in an active contact with an analytic collider in the last substep
    /// (Backend::collider_contact_vertices), or std::nullopt where the backend does not report them.
    [[nodiscard]] std::optional<std::vector<std::uint32_t>> collider_contact_vertices(std::size_t cloth) const;

    /// Current positions (m) and velocities (m/s) of a cloth, copied from the backend.
    [[nodiscard]] std::vector<Vec3d> positions(std::size_t cloth) const;
    [[nodiscard]] std::vector<Vec3d> velocities(std::size_t cloth) const;
    /// Overwrites a cloth's state (sizes must equal the fabric's vertex count).
    void set_state(std::size_t cloth, std::span<const Vec3d> positions, std::span<const Vec3d> velocities);

    /// Checkpoints (docs/design.md, "Checkpoints"). save_state writes everything that decides the
    /// next step besides the scene's settings: simulated time and step count, every cloth's
    /// positions, velocities and pins, the grab, and the backend's solver state (the CG warm start);
    /// versioned, with a checksum, whole or not at all. Throws weft::Error naming the file.
    void save_state(const std::filesystem::path& file) const;
    /// Restores a checkpoint of this world (the same scene: cloths and vertex counts, backend and
    /// precision): stepping on gives the bits the saved world would have given on the CPU backend.
    /// Throws weft::Error naming the file and the reason for a corrupt, cut or mismatched
    /// checkpoint, before changing anything.
    void load_state(const std::filesystem::path& file);

    /// The pairs of triangles going through each other now, cloth with cloth and cloth with a mesh
    /// collider (the exact check that `collision.check` runs after every step, here on demand and
    /// naming the triangles: which part of a body a cloth is caught in). At most `max_pairs`, in a
    /// fixed order; pairs of two collider triangles are not listed. Costly: for diagnostics.
    [[nodiscard]] std::vector<IntersectingTriangles> intersections(std::size_t max_pairs = 100000) const;

    /// Kinetic + gravitational potential + elastic energy of all cloths, J (diagnostics and tests).
    [[nodiscard]] double energy() const;

    /// Builds the backend for the world as it is now (every allocation of the simulation), so that
    /// the next `step()` does not pay for it. `step()` builds when cloths, pins or colliders changed;
    /// calling this is never needed, only earlier. Zero-copy output (weft/backend/interop.h,
    /// `share_output`) needs the built world.
    void build();

    /// The backend's name ("cpu", "cuda"), where it runs (CPU model and threads, GPU name), and the
    /// bytes of simulation state it holds (host or device).
    [[nodiscard]] std::string_view backend_name() const;
    [[nodiscard]] std::string device_description() const;
    [[nodiscard]] std::size_t memory_bytes() const;
    /// `memory_bytes` split by purpose (bytes each): where a scene's memory goes.
    [[nodiscard]] std::vector<std::pair<std::string, std::size_t>> memory_breakdown() const;

    /// The backend that steps this world (weft/backend/backend.h): for tools and backend-specific
    /// hooks such as `weft::cuda::as_cuda(world.backend())`.
    [[nodiscard]] Backend& backend() {
        forget_audit();  // the caller may change the state behind the world's back
        return *backend_;
    }
    [[nodiscard]] const Backend& backend() const { return *backend_; }

private:
    void ensure_built() const;
    void guarded_substep(double t, double h, bool retry, EnergyAudit& audit);
    /// One substep of `h` from time `t` under the energy guard's setting, leaving `audit` at its end.
    void audited_substep(double t, double h, EnergyAudit& audit);
    /// As audited_substep, split into halves where it overstretched a cloth (split_stretch), `depth`
    /// halvings below the step's substep; returns the pieces it took.
    int split_substep(double t, double h, EnergyAudit& audit, int depth);
    void read_all_states(std::vector<std::vector<Vec3d>>& x, std::vector<std::vector<Vec3d>>& v) const;
    void write_all_states(const std::vector<std::vector<Vec3d>>& x, const std::vector<std::vector<Vec3d>>& v);
    /// Every way to change the model or the state between steps calls this: the next step audits
    /// its start again instead of taking the last step's end audit.
    void forget_audit();
    std::unique_ptr<Model> model_;
    std::unique_ptr<Backend> backend_;
    mutable std::uint64_t built_version_ = ~std::uint64_t{0};
    /// Each cloth's vertex count at the last build: a rebuild carries the state of a cloth whose
    /// count did not change (a pin added) instead of starting it again.
    mutable std::vector<std::size_t> built_vertex_counts_;
    /// The state at the start of the current substep, kept for the energy guard's redo (retry mode).
    std::vector<std::vector<Vec3d>> guard_x_, guard_v_;
    /// The energy guard's audit of the last step's end (the same state, time, h and wind as the next
    /// step's start while nothing changed in between): the next step starts from it instead of
    /// auditing again (the same numbers, one audit fewer a step).
    std::unique_ptr<EnergyAudit> carried_audit_;
    double carried_h_ = 0.0;
    bool carried_wind_ = false;
    /// split_substep's saved states, one pair a depth (its start, and the whole attempt while the
    /// halves run), sized before a step's substeps and reused: no allocation in step() once warm.
    struct SavedStates {
        std::vector<std::vector<Vec3d>> x, v;
    };
    std::vector<SavedStates> split_start_, split_whole_;
    /// split_stretch's controller: the halvings every substep starts with (those the last splits
    /// needed), the deepest split of the current step, and the substeps since the last split.
    int split_level_ = 0, deepest_split_ = 0, substeps_since_split_ = 0;
    double time_ = 0.0;
    std::size_t steps_ = 0;
    StepStats stats_{};
};

}  // namespace weft
