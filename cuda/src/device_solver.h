#pragma once
// All the state of the CUDA solver on one device, in one object, so that several can run side by
// side (the multi-GPU solver partitions rows across them and reuses these kernels).

#include <cuda_runtime_api.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "device_array.h"
#include "device_collisions.h"
#include "device_contacts.h"
#include "device_layout.h"
#include "device_params.h"
#include "device_schwarz.h"
#include "device_view.h"
#include "weft/cuda/cuda_backend.h"
#include "weft/error.h"
#include "weft/backend/energy_audit.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/model.h"
#include "weft/backend/part_model.h"
#include "weft/stats.h"
#include "multi/part_contacts.h"
#include "multi/part_system.h"

namespace weft::cuda {

/// Whether `model` asks for collider contacts at the triangles' centroids and has an analytic
/// collider for them (SolverSettings::face_contacts).
[[nodiscard]] bool face_contacts(const Model& model);

class DeviceSolver {
public:
    /// Binds to CUDA device `device` and creates its streams; throws weft::Error if it cannot.
    explicit DeviceSolver(int device);
    ~DeviceSolver();
    DeviceSolver(const DeviceSolver&) = delete;
    DeviceSolver& operator=(const DeviceSolver&) = delete;

    /// Uploads `flat` (kept by reference; it must outlive the solver) and allocates every buffer the
    /// step needs. `model` sizes the per-substep parameter block (cloths, colliders, pins).
    void build(const FlatModel& flat, const Model& model);
    /// One substep. A failure (a CUDA error, a buffer that cannot grow within the memory budget)
    /// throws weft::Error naming the stage it happened in; where the device is still usable the
    /// cloth is first put back where the substep started and kept on the host, and the next substep
    /// rebuilds the device buffers from it (docs/design.md, "Device faults"). After a sticky error
    /// (the context is lost) every later call throws.
    void substep(const Model& model, double t, double h, StepStats& stats);
    void read_state(std::size_t first, std::size_t count, Vec3d* x, Vec3d* v) const;
    /// The rows [first, first + count) in a contact of the last substep's solve (the incidence the
    /// solve built: offset pairs beyond their radius left out), each once, ascending, numbered from
    /// `first` (Backend::contact_vertices). Reads the incidence's starts back: for tools.
    void contact_vertices(std::size_t first, std::size_t count, std::vector<std::uint32_t>& out) const;
    /// The rows [first, first + count) in an active analytic-collider contact at the last assembly
    /// (DeviceView::collider_contact), as `first`-relative ids, ascending (Backend::collider_contact_vertices).
    /// Reads the flags back: for tools.
    void collider_contact_vertices(std::size_t first, std::size_t count, std::vector<std::uint32_t>& out) const;
    void write_state(std::size_t first, std::size_t count, const Vec3d* x, const Vec3d* v);
    /// What decides the next substep besides x and v (Backend::solver_state): the CG warm start
    /// (previous Δv) and the substep count (the preconditioner's refresh phase), as bytes.
    [[nodiscard]] std::vector<std::uint8_t> solver_state() const;
    /// Takes back what solver_state returned for the same model; throws weft::Error naming a mismatch.
    void restore_solver_state(std::span<const std::uint8_t> bytes);

    void set_stream(cudaStream_t stream);
    /// Every substep ends by writing positions and normals to `device_buffer` (and so does this call,
    /// at once). `synchronous`: the host waits for each of those writes (the public set_output's
    /// promise); otherwise they are only ordered on the active stream (shared slots, whose timeline
    /// orders them for the reader).
    void set_output(void* device_buffer, std::size_t stride, bool synchronous = true);
    [[nodiscard]] std::size_t vertex_count() const { return view_.n; }
    void set_use_graph(bool enabled);
    void set_assembly(AssemblyStrategy strategy);
    void set_pcg_loop(PcgLoop loop);

    // ---- proximity contacts (docs/collisions.md, step 1) ------------------------------------------
    // The solve adds the pair springs of a device contact list (device_contacts.h) to A and b. The
    // list persists across substeps until replaced; its count lives on the device, so it may change
    // every substep under one graph, and only a larger capacity re-captures the graph.
    /// Makes room for `pairs` contacts and `kinematic` kinematic vertices (allocates: call outside
    /// the step; a capacity above 0 switches the contact path on for good, until the next build).
    void reserve_contacts(std::size_t pairs, std::size_t kinematic);
    /// Internal, until the GPU narrow phase fills the list on the device: every later substep solves
    /// with `contacts` (vertex ids: cloth vertices of the flat model first, then kinematic ones),
    /// kinematic vertex k at `kinematic_x1[k]` (its pose at t + h) moving with `kinematic_v[k]`. One
    /// host-to-device copy on the solver's stream; grows the list first when it does not fit. An
    /// empty list with no capacity reserved leaves the contact path off.
    void set_contacts(std::span<const weft::collision::ProximityContact> contacts, std::span<const Vec3d> kinematic_x1 = {},
                      std::span<const Vec3d> kinematic_v = {});
    /// The collision stages (device_collisions.h), active when the model needs cloth collisions:
    /// before each substep's solve they fill the contact list on the device; after it, CCD and (for
    /// now on the host) impact zones.
    [[nodiscard]] const DeviceCollisions& collisions() const { return collisions_; }
    /// Pairs the device list holds room for (0: no contact path).
    [[nodiscard]] std::size_t contact_capacity() const { return contacts_.capacity(); }
    /// Graphs captured so far (tests: a changing contact count must not re-capture).
    [[nodiscard]] int graph_captures() const { return graph_captures_; }
    /// Substeps that ran the swept collider test since the build (tests: a slow collider must not).
    [[nodiscard]] int sweep_launches() const { return sweep_launches_; }
    /// The energy guard's audit (weft/backend/energy_audit.h) summed on the device, where the state
    /// lives: kinetic, gravitational, elastic and collider-penalty energy and the power bounds of
    /// moving colliders, moving pins, the grab and (`with_wind`) the wind, at time `t` (s) of
    /// substeps of `h` (s). Reads back a few numbers, not the state.
    /// In part mode, `whole_x` (the whole model's positions on this GPU, or null) lets the offset
    /// contacts' energy in (launch_energy_audit).
    [[nodiscard]] EnergyAudit energy_audit(const Model& model, double t, double h, bool with_wind,
                                           const float* whole_x = nullptr);
    /// Whether the last substep solved with the Schwarz preconditioner (SolverSettings::preconditioner).
    [[nodiscard]] bool schwarz_active() const { return schwarz_on_; }
    /// Its levels (built on first use; tests compare them with the CPU backend's).
    [[nodiscard]] const DeviceSchwarz& schwarz() const { return schwarz_; }
    /// Blocks of the one-launch CG loop, 0 when the loop runs a kernel per step.
    [[nodiscard]] int persistent_grid() const { return persistent_grid_; }
    /// Whether assembly runs as the row gather (else colour passes).
    [[nodiscard]] bool row_gather() const { return row_gather_; }
    [[nodiscard]] bool graph_active() const { return graph_active_; }
    [[nodiscard]] std::size_t memory_bytes() const { return ledger_.total(); }
    [[nodiscard]] const MemoryLedger& ledger() const { return ledger_; }
    /// The ledger with its "cloth collisions" entry split by purpose (DeviceCollisions::memory_breakdown).
    [[nodiscard]] std::vector<std::pair<std::string, std::size_t>> memory_breakdown() const;
    [[nodiscard]] int device() const { return device_; }

    // ---- part mode: one part of the multi-GPU solver (multi/multi_solver.h, docs/multi-gpu.md) -----
    // The solver holds a part's local model: it assembles the owned rows, and its ghosts (the other
    // parts' vertices its rows read) hold their owners' values, which the multi-GPU solver keeps so by
    // exchanging Δv after each solve. Every per-vertex kernel runs over the ghosts too, on the same
    // values, so their state stays their owners' bits. The CG runs across the parts (multi/part_pcg.h),
    // block-Jacobi; cloth collisions are not part of part mode yet.
    /// Builds on part `part` of `whole` (both kept by reference: they must outlive the solver).
    void build_part(const FlatModel& whole, const PartModel& part, const Model& model);
    [[nodiscard]] bool part_mode() const { return part_ != nullptr; }
    /// Stages the substep's parameters and enqueues its start (x0, v0, the pins' velocities).
    /// `moves_bounded`: the substep's contacts are offset contacts (StepParams::correct_overshoots).
    void part_begin_substep(const Model& model, double t, double h, bool moves_bounded);
    /// Enqueues one Newton iteration's system: every row's forces and blocks, then the owned rows'
    /// block-Jacobi inverse (with Schwarz: the diagonal blocks it aggregates) and Δv's start
    /// (`first_newton`: the warm start may apply). `offset_contacts`: the contacts are offset contacts,
    /// whose incidence is rebuilt after each evaluation (only the pairs in contact, as on one GPU).
    void part_assemble(bool first_newton, bool offset_contacts = false);
    /// The substep's h on the device (the staged step parameters), s: what a captured or enqueued
    /// truncation reads.
    [[nodiscard]] const float* step_h_device() const;
    /// Switches the multilevel Schwarz preconditioner across the parts on or off; on builds this
    /// part's share of `whole` (the hierarchy of the whole model) the first time.
    void part_use_schwarz(bool on, const SchwarzHierarchy& whole);
    /// Enqueues Newton iteration `newton`'s factorisation in the two pieces the parts' gather of
    /// level 1's couplings goes between: this part's level-1 couplings, then the levels above and
    /// every level's domain inverses.
    void part_factor_level1(int newton);
    void part_factor_rest(int newton);
    /// Enqueues v_k += Δv (Δv's ghosts exchanged by then).
    void part_newton_update();
    /// Enqueues x = x0 + h·v_k, v = v_k with the non-finite check (and this part's rollback).
    void part_commit();
    /// Waits for the part's work and returns its substep stats (non-finite count, collider contacts).
    const DeviceStats& part_stats();
    /// Rolls this part back to the substep's start (another part met a non-finite value).
    void part_rollback();
    /// Drops this part's solve of the substep (another part's vertex ran away): the free vertices
    /// keep their start velocity, as the runaway drop in part_commit.
    void part_drop_solve();
    /// The swept test of fast analytic colliders on this part's vertices (as in substep()), after
    /// part_stats; true when it ran (it may have moved ghosts: exchange the state then).
    bool part_sweep(StepStats& stats);
    /// Writes the owned vertices' positions and normals at their global places in the output buffer.
    void part_write_output();
    /// The owned rows' system for the CG across parts.
    [[nodiscard]] multi::PartSystem part_system() const;
    // Contacts across GPUs (docs/multi-gpu.md, "Collisions"): the substep's whole contact list,
    // found on the first GPU, copied here; this part gathers the pairs at its own rows, evaluating
    // them from the whole-size copies of x₀, w_k and v_k (multi/contact_mirror.h).
    /// The copies the contact evaluation reads (device memory on this part's GPU, SoA with stride
    /// `whole`), set once.
    void part_set_contact_copies(const float* x0, const float* wk, const float* vk, std::uint32_t whole);
    /// This part's contacts: from every GPU's share (complete: their detections have returned), in
    /// share order, those at a row this part owns (multi/part_contacts.h); after `ready` (an event
    /// on `kinematic_from`'s producer) the `kinematic` kinematic vertices of `kinematic_from`; then
    /// the incidence of this part's rows. Peer reads; waits for its stream (the selected counts).
    /// Grows the list first when needed (returns true then: the part's system changed, the CG
    /// across parts must be made again).
    bool part_receive_contacts(std::span<const multi::ContactShare> shares, const ContactInputs& kinematic_from,
                               cudaEvent_t ready, std::size_t kinematic);
    /// The whole model's id of every local vertex (device memory), owned first.
    /// The contacts the last part_receive_contacts kept (those at this part's rows).
    [[nodiscard]] std::size_t part_contact_count() const { return part_contact_count_; }
    [[nodiscard]] const std::uint32_t* part_global_ids() const { return global_index_.get(); }

    // For benchmarks: the arrays, the layout and the stream the solver uses.
    [[nodiscard]] const DeviceView& view() const { return view_; }
    [[nodiscard]] const DeviceLayout& layout() const { return layout_; }
    [[nodiscard]] cudaStream_t stream() const { return active_stream(); }

private:
    /// Timing events a Newton iteration records: after forces and assembly, after the preconditioner's
    /// setup, after the solve, after the update.
    static constexpr std::size_t kEventsPerNewton = 4;
    /// Enqueues one whole substep on `stream`. In graph mode (`capturing`) the CG loop becomes a
    /// conditional while node; otherwise it is driven from the host with a check every few iterations.
    void record(cudaStream_t stream, bool capturing);
    void record_pcg_loop(cudaStream_t stream, bool capturing, int newton);
    /// Enqueues the substep's kernels on `stream` with `newton_iterations` Newton iterations: through
    /// the captured graph (captured again when the iteration count changed) once warm and where graphs
    /// work, else recorded directly with the host-driven CG loop.
    void launch_substep(cudaStream_t stream, int newton_iterations);
    /// Offset contact: one more Newton iteration after a rerun of the detection (recorded directly,
    /// never in the graph), then the commit again.
    void record_extra_newton(cudaStream_t stream);
    /// Backtracking on the Newton update just solved (SolverSettings::line_search, as
    /// CpuSolver::line_search): Δv is scaled by the first of 1, ½, ¼, … (8 halvings at most) at which
    /// implicit Euler's objective (inertia, gravity, elastic, collider and offset contact potentials
    /// at t + h, summed by the audit's kernels) is not above the update's start. Host-driven: one
    /// read-back per trial, so a substep that searches runs outside the graph. Returns the halvings.
    int line_search(cudaStream_t stream);
    /// The audit's parameter block and sums (allocated on first use).
    void ensure_audit_buffers(cudaStream_t stream);
    /// The audit's sums over `view` (its staging the audit's), read back (synchronises `stream`).
    const double* audit_sums(const DeviceView& view, bool with_wind, bool with_faces, const float* whole_x, cudaStream_t stream);
    /// The contacts' evaluation at the Newton iterate, and in offset mode the incidence of the pairs in
    /// contact.
    void record_contact_evaluation(cudaStream_t stream);
    /// Offset contact: the truncation after a Newton update (when `offset_model_` is set).
    void record_truncation(cudaStream_t stream);
    /// Fills the substep's parameter block (with whether it refactors the Schwarz preconditioner) and
    /// enqueues its upload on `stream`.
    void stage_substep(const Model& model, double t, double h, cudaStream_t stream);
    /// Lays out the per-substep parameter block for `model` and allocates it (host and device).
    void layout_staging(const Model& model);
    /// Writes the parameters of the substep from `t` to `t + h` into the host block.
    /// Writes the parameters of the substep from `t` to `t + h` into the host block at `base` (the
    /// solver's own, or the energy audit's).
    void fill_staging(const Model& model, double t, double h, unsigned char* base) const;
    void build_collisions(const Model& model);
    /// Switches the preconditioner to `preconditioner` (builds the Schwarz levels the first time;
    /// the graph is re-captured with the other kernels).
    void choose_preconditioner(Preconditioner preconditioner);
    /// Points the view at the bending models per triangle's arrays while solver.bending = "shell" or
    /// "midedge" (uploaded on the first substep that asks for them, kept until the next build), or at
    /// none.
    void choose_bending(BendingModel bending);
    void upload_shell_bending();
    /// The mid-edge model's arrays beside the shell model's (uploaded on the first substep that asks).
    void upload_midedge_bending();
    void capture_graph();
    void choose_assembly();
    void choose_pcg_loop();
    void destroy_graph();
    void contacts_resized();
    // ---- fast analytic colliders (weft/physics/swept_collider.h; docs/collisions.md, step 4) -------
    // After the graph: the commit recorded the largest free-vertex displacement; from it and the
    // colliders' motion the host decides, per substep, whether any vertex's relative motion may exceed
    // a quarter of a collider's width. Only then is the swept test launched, on the same stream,
    // and its hit count read back. With no sphere, capsule or box nothing of this runs at all.
    /// True when some free vertex moving at most `largest_move` (m) in the substep may need the
    /// swept test against some collider (the staged parameters of this substep).
    [[nodiscard]] bool sweep_needed(float largest_move) const;
    /// Runs the swept test when `sweep_needed`; adds its hits to `stats`. Synchronises `stream` then.
    void sweep_colliders(float largest_move, cudaStream_t stream, StepStats& stats);
    [[nodiscard]] cudaStream_t active_stream() const { return user_stream_ != nullptr ? user_stream_ : stream_; }

    int device_ = 0;
    cudaStream_t stream_ = nullptr;       // the solver's own stream
    cudaStream_t body_stream_ = nullptr;  // captures the CG loop body into the while node
    cudaStream_t user_stream_ = nullptr;
    const FlatModel* flat_ = nullptr;
    double total_mass_ = 0.0;  // kg, every cloth's (build)
    // Part mode: the whole model, the part, each global vertex's local id (~0: not here) and the
    // owned vertices' global ids on the device (the output's places).
    const FlatModel* whole_ = nullptr;
    const PartModel* part_ = nullptr;
    std::size_t part_contact_count_ = 0;  // part_receive_contacts' selection
    std::vector<std::uint32_t> local_of_global_;
    DeviceArray<std::uint32_t> output_index_;
    DeviceArray<std::uint32_t> global_index_;  // every local vertex's whole id
    DeviceArray<std::uint32_t> row_of_;        // whole vertex → owned row or ~0 (the contact incidence)
    DeviceArray<uint4> corner_source_;         // ContactView::corner_source, the contacts' capacity
    const float* contact_x0_ = nullptr;        // whole-size copies the contact evaluation reads
    const float* contact_wk_ = nullptr;
    const float* contact_vk_ = nullptr;
    std::uint32_t contact_whole_ = 0;
    DeviceArray<unsigned char> contact_selection_;  // scratch of the part's contact selection
    DeviceArray<std::uint32_t> selected_count_;      // one share's selected count
    PinnedArray<std::uint32_t> selected_host_;      // the same, read back (the next share's place)
    DeviceLayout layout_;
    MemoryLedger ledger_;
    DeviceView view_;

    DeviceArray<float> state_;        // x, v, x0, v0, vk, wk, b, dv, pin velocity, previous dv: 3n each
    DeviceArray<float> cg_vectors_;   // r, c, q, s: 3n each, and the preconditioner: 9n
    DeviceArray<float> mass_;
    DeviceArray<std::uint8_t> fixed_;
    DeviceArray<std::uint8_t> collider_contact_;  // DeviceView::collider_contact
    DeviceArray<std::uint32_t> vertex_cloth_;
    DeviceArray<float> blocks_;
    DeviceArray<std::uint32_t> column_, slice_start_, diagonal_;
    DeviceArray<std::uint32_t> triangle_vertices_, triangle_cloth_, triangle_positions_;
    DeviceArray<float> triangle_rest_;
    DeviceArray<std::uint32_t> hinge_vertices_, hinge_cloth_, hinge_positions_;
    // The bending model per triangle (DeviceView::triangle_hinges …; empty until a substep asks).
    DeviceArray<std::int32_t> triangle_hinges_, hinge_faces_;
    DeviceArray<float> shell_rest_;
    DeviceArray<physics::ShellFaceTerms<float>> shell_faces_;
    // The mid-edge model (DeviceView::midedge): its condensed rest data (10 floats a triangle), the
    // normals' vectors (ξ, angle, r, p, q, diagonal: one double each a hinge), the hinges' clamps and
    // the triangles' edge readings, the solve's partial sums and its cooperative grid.
    DeviceArray<float> midedge_rest_;
    DeviceArray<double> midedge_vectors_;
    DeviceArray<std::uint8_t> midedge_flags_;
    DeviceArray<double> midedge_partials_;
    int midedge_grid_ = 0;
    DeviceArray<float> hinge_rest_;
    DeviceArray<std::uint32_t> vertex_triangle_start_, vertex_triangle_, vertex_hinge_start_, vertex_hinge_;
    DeviceArray<std::uint32_t> pin_vertex_;
    DeviceArray<unsigned char> staging_;
    DeviceArray<PcgControl> control_;
    DeviceArray<DeviceStats> stats_;
    DeviceArray<double> partials_;
    DeviceArray<long long> loop_clock_;  // WEFT_CUDA_PCG_CLOCK=1 (loop_clock.h)
    DeviceContacts contacts_;
    DeviceCollisions collisions_;
    DeviceSchwarz schwarz_;
    bool schwarz_on_ = false;
    bool schwarz_factored_ = false;  // the device holds factors to reuse (preconditioner_refresh)
    long long substep_count_ = 0;    // substeps since the build

    PinnedArray<unsigned char> host_staging_;
    // The energy audit's own parameter block (same layout) and sums.
    PinnedArray<unsigned char> audit_host_staging_;
    DeviceArray<unsigned char> audit_staging_;
    DeviceArray<double> audit_partials_;
    PinnedArray<double> audit_sums_;
    // The line search's trial positions and velocity changes (3n floats each, allocated on first use),
    // the model and end time of the substep that searches (null: none) and its halvings so far.
    DeviceArray<float> trial_x_, trial_dv_;
    const Model* line_search_model_ = nullptr;
    double line_search_t1_ = 0.0, line_search_h_ = 0.0;
    int line_search_halvings_ = 0;
    PinnedArray<DeviceStats> host_stats_;
    PinnedArray<int> host_running_;
    StepParams layout_params_{};  // offsets of the arrays in the staging block

    // Device faults (substep): the stage running, whether the substep's start (x0, v0) is on the
    // device (the solve was enqueued, so x and v may have moved), and after a fault the state kept on
    // the host until the next substep rebuilds the buffers, or why the device is lost.
    void run_substep(const Model& model, double t, double h, StepStats& stats);
    [[noreturn]] void recover_from_fault(const Error& error, double t);
    void rebuild_after_fault(const Model& model);
    const char* stage_ = "";
    bool substep_started_ = false;
    // While a rebuild is pending the buffers may be freed (a rebuild that failed too): nothing reads
    // view_ then. The state is on the host, a restored warm start waits for the rebuild, and an
    // output buffer is written by the rebuild's first substep.
    bool rebuild_pending_ = false;
    std::vector<Vec3d> rescued_x_, rescued_v_;
    std::vector<std::uint8_t> pending_solver_state_;
    std::string device_lost_;

    void* output_ = nullptr;
    std::size_t output_stride_ = 0;
    bool output_synchronous_ = true;

    // Stage timing: events recorded between stages (in the graph too).
    std::vector<cudaEvent_t> events_;
    int recorded_newton_ = 0;
    /// The model of the substep being recorded when its contacts are offset contacts (the
    /// truncation reads its settings); null otherwise.
    const Model* offset_model_ = nullptr;
    /// The substep being staged keeps every move within a displacement bound (offset contact), so
    /// the sweep leaves slow overshoots alone (StepParams::correct_overshoots).
    bool moves_bounded_ = false;
    /// Kernel nodes of the captured graph (counted per launch in thread_kernel_launches).
    long long graph_kernels_ = 0;
    /// The truncation the graph was captured with (DeviceCollisions::truncation_key; 0: none).
    std::uint64_t graph_truncation_key_ = 0;

    AssemblyStrategy assembly_ = AssemblyStrategy::Auto;
    bool row_gather_ = true;
    PcgLoop pcg_loop_ = PcgLoop::Auto;
    int persistent_grid_ = 0;
    bool use_graph_ = true;
    bool graph_active_ = false;
    bool graph_unsupported_ = false;
    bool warm_ = false;
    cudaGraphExec_t graph_exec_ = nullptr;
    int graph_captures_ = 0;
    int sweep_launches_ = 0;
    int graph_newton_ = 0;            // settings the graph was captured with
};

}  // namespace weft::cuda
