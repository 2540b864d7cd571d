#pragma once
/// @file
/// The backend interface and its factory (backend kit). The CPU backend lives in `runtime/`; the
/// CUDA backends register themselves from `cuda/` through `register_backend()`. A game chooses a
/// backend by name and `BackendOptions` (weft/backend_options.h) and never includes this header.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "weft/backend/energy_audit.h"
#include "weft/backend/interop.h"
#include "weft/backend/model.h"
#include "weft/backend_options.h"
#include "weft/stats.h"

namespace weft {

/// A simulation backend. It owns the simulation state (on the host or a device) and steps it.
/// Threading: one thread drives a backend at a time.
class Backend {
public:
    virtual ~Backend() = default;
    Backend() = default;
    Backend(const Backend&) = delete;
    Backend& operator=(const Backend&) = delete;

    /// Short name used on the command line ("cpu", "cuda").
    [[nodiscard]] virtual std::string_view name() const = 0;
    /// Human-readable description of where it runs (CPU model and threads, GPU name).
    [[nodiscard]] virtual std::string device_description() const = 0;
    /// Builds all state for `model`: every allocation happens here, none in `substep()`.
    /// Initial positions come from each cloth's fabric and transform.
    virtual void build(const Model& model) = 0;
    /// Advances one implicit substep of `h` seconds starting at time `t`, reading the current
    /// parameters of `model`, and adds its counters and stage times to `stats`.
    virtual void substep(const Model& model, double t, double h, StepStats& stats) = 0;
    /// Copies a cloth's positions (m) and velocities (m/s) out, converting to double.
    virtual void read_state(std::size_t cloth, std::span<Vec3d> positions, std::span<Vec3d> velocities) const = 0;
    /// Overwrites a cloth's positions and velocities (reset, editing, tests).
    virtual void write_state(std::size_t cloth, std::span<const Vec3d> positions, std::span<const Vec3d> velocities) = 0;
    /// What besides the positions and velocities decides the next substep (the CG warm start, the
    /// preconditioner's refresh phase), as bytes for a checkpoint (World::save_state); empty when
    /// the backend keeps nothing more. Read after the state: restore_solver_state comes after
    /// write_state, which clears it.
    [[nodiscard]] virtual std::vector<std::uint8_t> solver_state() const { return {}; }
    /// Restores what solver_state returned on a backend of the same kind, precision and model.
    /// Throws weft::Error naming what does not match.
    virtual void restore_solver_state(std::span<const std::uint8_t> bytes);
    /// The energy guard's audit of the current state at time `t` (s) of substeps of `h` (s), with the
    /// wind's power when `with_wind` (weft/backend/energy_audit.h). The default reads every cloth back
    /// with `read_state` and sums on the host; a backend that keeps its state on a device may sum there
    /// and return the result.
    [[nodiscard]] virtual EnergyAudit energy_audit(const Model& model, double t, double h, bool with_wind) const;
    /// The vertices of cloth `cloth` (its own numbering) in a proximity contact with cloth or with a
    /// mesh collider in the last substep (offset pairs beyond their radius left out), each once,
    /// ascending, into `out`. False, with `out` empty, where the backend does not report them (what
    /// the editor's contact marks then say). Reads back and allocates: for tools, not every frame of a game.
    [[nodiscard]] virtual bool contact_vertices(std::size_t cloth, std::vector<std::uint32_t>& out) const {
        (void)cloth;
        out.clear();
        return false;
    }
    /// The vertices of cloth `cloth` (its own numbering) in an active contact with an analytic
    /// collider in the last assembly of the last substep: their own contact, or with
    /// solver.face_contacts a centroid contact of a triangle they are a corner of. Each once,
    /// ascending, into `out`; false, with `out` empty, where the backend does not report them. The
    /// solver's own decision (the editor's contact marks), read back: for tools, not every frame of a game.
    [[nodiscard]] virtual bool collider_contact_vertices(std::size_t cloth, std::vector<std::uint32_t>& out) const {
        (void)cloth;
        out.clear();
        return false;
    }
    /// Bytes of simulation state held (host or device).
    [[nodiscard]] virtual std::size_t memory_bytes() const = 0;
    /// `memory_bytes` split by purpose (bytes each, summing to it), for stats and benchmarks. The
    /// default is one entry, "state".
    [[nodiscard]] virtual std::vector<std::pair<std::string, std::size_t>> memory_breakdown() const;
    /// Zero-copy output (weft/backend/interop.h): imports `slots` (each holds one 24-byte vertex per world
    /// vertex, positions then normals in float, then kSlotStampBytes) made on the GPU `device`, and
    /// returns their writer. The fds belong to the backend from the call on, imported or closed.
    /// nullptr, with the reason in `why`, where the backend cannot (host memory, another GPU).
    [[nodiscard]] virtual std::unique_ptr<SharedOutput> share_output(std::span<const SharedSlotHandle> slots,
                                                                     const DeviceUuid& device, std::string& why);
};

using BackendFactory = std::function<std::unique_ptr<Backend>(const BackendOptions&)>;

/// Registers a backend under `name` (replacing one of the same name).
void register_backend(std::string name, std::string description, BackendFactory factory);
/// Creates the backend called `name`; throws `weft::Error` listing the compiled backends if unknown.
[[nodiscard]] std::unique_ptr<Backend> create_backend(std::string_view name, const BackendOptions& options = {});

}  // namespace weft
