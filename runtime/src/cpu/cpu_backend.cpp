// The CPU backend: a TBB task arena around a CpuSolver in float or double.
#include "cpu/cpu_backend.h"

#include <tbb/info.h>
#include <tbb/task_arena.h>

#include <string>
#include <variant>

#include "cpu/cpu_solver.h"
#include "weft/error.h"
#include "weft/backend/flat_model.h"

namespace weft::cpu {
namespace {

class CpuBackend final : public Backend {
public:
    explicit CpuBackend(const BackendOptions& options)
        : threads_(options.threads > 0 ? options.threads : tbb::info::default_concurrency()), arena_(threads_) {}

    std::string_view name() const override { return "cpu"; }

    std::string device_description() const override {
        return "CPU, " + std::to_string(threads_) + " thread" + (threads_ == 1 ? "" : "s") + ", " +
               (precision_ == Precision::Double ? "double" : "float");
    }

    void build(const Model& model) override {
        flat_ = flatten(model);
        precision_ = model.settings.solver.precision;
        build_solver(model);
    }

    void substep(const Model& model, double t, double h, StepStats& stats) override {
        if (model.settings.solver.precision != precision_) switch_precision(model);
        arena_.execute([&] { std::visit([&](auto& s) { s.substep(model, t, h, stats); }, solver_); });
    }

    void read_state(std::size_t cloth, std::span<Vec3d> x, std::span<Vec3d> v) const override {
        // Named copies, not a structured binding: a lambda may capture those only from clang 16
        // (the fuzz preset builds with clang 14).
        const auto range = flat_.cloth_vertices(cloth, x.size(), v.size());
        const std::size_t first = range.first, count = range.second;
        std::visit([&](const auto& s) { s.read_state(first, count, x.data(), v.data()); }, solver_);
    }

    bool contact_vertices(std::size_t cloth, std::vector<std::uint32_t>& out) const override {
        std::vector<std::uint32_t> all;
        std::visit([&](const auto& s) { s.contact_vertices(all); }, solver_);
        const std::uint32_t first = flat_.cloth_vertex_offset.at(cloth), end = flat_.cloth_vertex_offset.at(cloth + 1);
        out.clear();
        for (const std::uint32_t v : all)
            if (v >= first && v < end) out.push_back(v - first);
        return true;
    }

    bool collider_contact_vertices(std::size_t cloth, std::vector<std::uint32_t>& out) const override {
        const std::uint32_t first = flat_.cloth_vertex_offset.at(cloth), end = flat_.cloth_vertex_offset.at(cloth + 1);
        std::visit([&](const auto& s) { s.collider_contact_vertices(first, end - first, out); }, solver_);
        return true;
    }

    std::vector<std::uint8_t> solver_state() const override {
        return std::visit([](const auto& s) { return s.solver_state(); }, solver_);
    }
    void restore_solver_state(std::span<const std::uint8_t> bytes) override {
        std::visit([&](auto& s) { s.restore_solver_state(bytes); }, solver_);
    }

    void write_state(std::size_t cloth, std::span<const Vec3d> x, std::span<const Vec3d> v) override {
        const auto range = flat_.cloth_vertices(cloth, x.size(), v.size());
        const std::size_t first = range.first, count = range.second;
        std::visit([&](auto& s) { s.write_state(first, count, x.data(), v.data()); }, solver_);
    }

    // The host audit plus the offset contacts' penalty energy, a potential of the state like the
    // membrane's (pair springs have none: their normal is frozen per substep).
    EnergyAudit energy_audit(const Model& model, double t, double h, bool with_wind) const override {
        EnergyAudit audit = Backend::energy_audit(model, t, h, with_wind);
        audit.contact += std::visit([](const auto& s) { return s.offset_contact_energy(); }, solver_);
        return audit;
    }

    std::size_t memory_bytes() const override {
        return flat_.memory_bytes() + std::visit([](const auto& s) { return s.memory_bytes(); }, solver_);
    }
    std::vector<std::pair<std::string, std::size_t>> memory_breakdown() const override {
        const std::size_t collisions = std::visit([](const auto& s) { return s.collision_memory_bytes(); }, solver_);
        return {{"model", flat_.memory_bytes()},
                {"solver", std::visit([](const auto& s) { return s.memory_bytes(); }, solver_) - collisions},
                {"collisions", collisions}};
    }

private:
    /// A solver of precision_ for the flattened model, built inside the backend's task arena.
    void build_solver(const Model& model) {
        arena_.execute([&] {
            if (precision_ == Precision::Double)
                solver_.emplace<CpuSolver<double>>().build(flat_, model);
            else
                solver_.emplace<CpuSolver<float>>().build(flat_, model);
        });
    }

    // Changing precision live keeps the state (converted) and rebuilds the solver.
    void switch_precision(const Model& model) {
        std::vector<Vec3d> x(flat_.vertex_count), v(flat_.vertex_count);
        std::visit([&](const auto& s) { s.read_state(0, flat_.vertex_count, x.data(), v.data()); }, solver_);
        precision_ = model.settings.solver.precision;
        build_solver(model);
        std::visit([&](auto& s) { s.write_state(0, flat_.vertex_count, x.data(), v.data()); }, solver_);
    }

    int threads_;
    tbb::task_arena arena_;
    FlatModel flat_;
    Precision precision_ = Precision::Double;
    std::variant<CpuSolver<double>, CpuSolver<float>> solver_;
};

}  // namespace

std::unique_ptr<Backend> make_cpu_backend(const BackendOptions& options) { return std::make_unique<CpuBackend>(options); }

}  // namespace weft::cpu
