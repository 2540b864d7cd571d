#pragma once
/// @file
/// One world stepped across several GPUs (docs/multi-gpu.md): the vertices cut into parts along the
/// preconditioner's order (weft/backend/vertex_partition.h), each part a DeviceSolver in part mode on
/// its GPU holding its local model (owned vertices, then ghosts), the CG run across the parts with
/// one reduction per iteration (multi/part_pcg.h), and Δv's ghosts exchanged after each solve
/// (multi/halo_exchange.h), so that every part's ghosts always hold their owners' state.
///
/// Several parts may share one GPU: the test mode that checks the partition logic on any GPU host.

#include <atomic>
#include <barrier>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "device_solver.h"
#include "device_collisions.h"
#include "device_contacts.h"
#include "multi/all_gather.h"
#include "multi/contact_mirror.h"
#include "multi/halo_exchange.h"
#include "multi/part_pcg.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/model.h"
#include "weft/backend/part_model.h"
#include "weft/backend/recut_policy.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/backend/vertex_partition.h"
#include "weft/error.h"
#include "weft/stats.h"

namespace weft::cuda::multi {

/// The re-cut's cost of a contact's vertex in pattern blocks: kContactWorkPerVertex, or the value of
/// WEFT_GPU_CONTACT_WORK (for measuring the weight; weft::Error names a value that is not a number
/// in [0, 100]).
[[nodiscard]] double contact_work_per_vertex();

class MultiSolver {
public:
    /// Part p on CUDA device `devices[p]` (one part per entry; entries may repeat). Throws
    /// weft::Error for an empty list or a device that does not exist.
    explicit MultiSolver(std::vector<int> devices);
    ~MultiSolver();
    MultiSolver(const MultiSolver&) = delete;
    MultiSolver& operator=(const MultiSolver&) = delete;

    /// Partitions `flat` (kept by reference; it must outlive the solver) and builds every part.
    /// Throws weft::Error naming what is missing when the model needs a stage not built across GPUs
    /// (cloth collisions: self-collision or mesh colliders), or when the cloth is too small to cut.
    void build(const FlatModel& flat, const Model& model);
    /// One substep across the parts. A substep that fails (out of device memory as a collision
    /// buffer grows, a CUDA error) throws weft::Error naming the stage; where every device is still
    /// usable, every part is first put back where the substep started and the state kept on the host
    /// (read_state, write_state and the warm start work on it), and the next substep or audit
    /// rebuilds the parts from it (docs/design.md, "Device faults"). A lost device fails every later
    /// substep.
    void substep(const Model& model, double t, double h, StepStats& stats);
    /// Global vertices [first, first + count) of the flat model, from their owners.
    void read_state(std::size_t first, std::size_t count, Vec3d* x, Vec3d* v) const;
    /// The vertices [first, first + count) of the model's numbering in a proximity contact in the
    /// last substep, as `first`-relative ids, each once, ascending (Backend::contact_vertices): each
    /// part reports its owned rows whose contact incidence is not empty (the rows its solve gathers
    /// contacts into; a contact across a cut is in each owner's incidence). Reads back: for tools.
    void contact_vertices(std::size_t first, std::size_t count, std::vector<std::uint32_t>& out) const;
    /// The same for the analytic colliders' contacts (DeviceSolver::collider_contact_vertices of each
    /// part's owned rows: Backend::collider_contact_vertices).
    void collider_contact_vertices(std::size_t first, std::size_t count, std::vector<std::uint32_t>& out) const;
    /// Sets global vertices [first, first + count) on their owners and every ghost copy.
    void write_state(std::size_t first, std::size_t count, const Vec3d* x, const Vec3d* v);
    /// The warm start (the previous Δv) of every vertex, gathered from its owner, in the one-GPU
    /// solver's format (DeviceSolver::solver_state): a checkpoint made on any part count resumes on
    /// any other, and on one GPU. Empty before the build.
    [[nodiscard]] std::vector<std::uint8_t> solver_state() const;
    /// Takes back solver_state's bytes (from any part count, or one GPU): every part's owned and
    /// ghost vertices get their value. Empty bytes start cold. Throws weft::Error naming a mismatch.
    void restore_solver_state(std::span<const std::uint8_t> bytes);
    /// The energy guard's audit summed over the parts, each on its device (vertices by their owner,
    /// elements by the owner of their first corner): a few numbers come back, not the state.
    [[nodiscard]] EnergyAudit energy_audit(const Model& model, double t, double h, bool with_wind);
    /// Every substep ends with each part writing its owned vertices' positions and normals into
    /// `device_buffer` (on devices()[0]), vertex i at stride·i bytes; the current state is written
    /// at once. The parts write into a buffer of the solver's on the first GPU (the other GPUs
    /// through peer access) and the first GPU copies it into `device_buffer` on stream(): memory a
    /// renderer exported (Vulkan, OpenGL) is mapped on the first GPU only. `synchronous`: the host
    /// waits for those writes (the public API's promise); a shared output does not.
    void set_output(void* device_buffer, std::size_t stride, bool synchronous = true);
    /// Vertices of the built model (0 before build).
    [[nodiscard]] std::size_t vertex_count() const { return flat_ != nullptr ? flat_->vertex_count : 0; }

    /// Orders every substep after the work enqueued so far on `stream` and makes `stream` wait for
    /// the substep (nullptr: no outside stream). The parts keep their own streams.
    void set_stream(cudaStream_t stream);
    /// The outside stream, or the first part's.
    [[nodiscard]] cudaStream_t stream() const;
    /// CG iterations as multi-device graphs (default) or launched one by one: the same results.
    void set_use_graph(bool enabled);
    [[nodiscard]] bool graph_active() const { return use_graph_; }
    void set_assembly(AssemblyStrategy strategy);
    /// How the CG across parts runs (PartPcg::set_loop); takes effect at the next solve.
    void set_pcg_loop(PcgLoop loop);
    /// Whether the CG runs as one cooperative kernel per GPU (false before build).
    [[nodiscard]] bool one_launch_cg() const;

    [[nodiscard]] std::size_t parts() const { return devices_.size(); }
    [[nodiscard]] const std::vector<int>& devices() const { return devices_; }
    [[nodiscard]] const VertexPartition& partition() const { return partition_; }
    [[nodiscard]] const DeviceSolver& part(std::size_t p) const { return *solvers_.at(p); }
    /// Device memory of all parts, bytes.
    [[nodiscard]] std::size_t memory_bytes() const;
    /// Device memory per GPU ("GPU d: ...") and per purpose.
    [[nodiscard]] std::vector<std::pair<std::string, std::size_t>> memory_breakdown() const;
    /// Bytes crossing between devices per exchange of one float3 vector.
    [[nodiscard]] std::uint64_t halo_bytes() const { return halo_ ? halo_->bytes_between_devices() : 0; }
    /// Whether the CG runs with the multilevel Schwarz preconditioner across the parts (else block-Jacobi).
    [[nodiscard]] bool schwarz_active() const { return schwarz_; }
    /// Re-cuts of the parts by contact load since the build (solver.gpu_rebalance).
    [[nodiscard]] int recuts() const { return recuts_; }
    /// Re-cuts the parts now by rows and the last detection's contacts (what the policy does when the
    /// imbalance lasts; public for tests). The state, the warm start and the output carry over; the
    /// steps after it are the steps of a world built with that cut. Needs cloth collisions.
    void recut(const Model& model);

private:
    /// The substep's work (substep() handles its failure).
    void run_substep(const Model& model, double t, double h, StepStats& stats);
    /// After a failed substep: every part that began it back at its start, the state onto the host,
    /// the rebuild pending; throws weft::Error with `error`'s reason, the stage and what became of
    /// the cloth.
    [[noreturn]] void recover_from_fault(const Error& error, double t);
    /// Builds the parts again from the state kept at the fault, with the warm start and the output
    /// binding set meanwhile; a rebuild that fails keeps them for the next try.
    void rebuild_after_fault(const Model& model);
    /// Exchanges the ghosts of x, v and the previous Δv (after a sweep or a rollback changed them).
    void exchange_state();
    void synchronize() const;
    /// The preconditioner `settings` asks for (Auto: Schwarz from kAutoSchwarzMinVertices vertices,
    /// as on one GPU); switching builds the parts' Schwarz levels the first time and a new CG.
    void choose_preconditioner(const SolverSettings& settings);
    /// Enqueues Newton iteration `newton`'s Schwarz factorisation on every part.
    void factor_schwarz(int newton);
    /// A new CG across the parts for their current systems (preconditioner or contact list changed).
    void make_cg();
    /// Cuts the vertices along the Schwarz order into parts of equal `work` (a weight a vertex) and
    /// builds every part, the halo, the level-1 all-gather, the contact mirror and the CG. The
    /// state is the flat model's initial one.
    void build_parts(const Model& model, const std::vector<double>& work);
    /// Throws weft::Error when solver.bending changed between the hinge and the per-triangle model
    /// since the parts were cut (their ghosts and elements follow the model).
    void require_bending_as_built(const Model& model) const;
    // ---- cloth collisions across GPUs (docs/multi-gpu.md, "Collisions") ---------------------------
    /// Whole arrays on every GPU: x, v, v0 and the previous Δv, 3 × vertices each.
    enum WholeArray : int { kWholeX = 0, kWholeV = 1, kWholeV0 = 2, kWholePrevious = 3 };
    [[nodiscard]] float* whole(std::size_t part, WholeArray a) const;
    /// Every part's owned values of `arrays` into the whole arrays of the first `targets` parts'
    /// GPUs (peer stores); those parts' streams wait.
    void collect_whole(std::initializer_list<WholeArray> arrays, std::size_t targets);
    /// Every part's local vertices (owned and ghosts) of x, v and the previous Δv from the first
    /// GPU's whole arrays.
    void spread_whole();
    /// Before the solve: every GPU hashes the whole state and narrows down its share of the pairs
    /// (concurrently, one host thread a GPU); each part takes the contacts at its rows from every
    /// share, then builds its incidence and contact vertices. In offset mode the shares' bounds are
    /// reduced across the GPUs on the way (reduce_bounds_across).
    void detect_contacts(const Model& model, double t, double h, StepStats& stats);
    /// Offset mode: the detection again at the truncated state (the whole v_k that
    /// truncate_across_parts left on every GPU), then the contacts to the parts, as detect_contacts.
    void redetect_contacts(const Model& model, double h, StepStats& stats);
    /// Runs `detect_share(p, its stats)` for every share at once, one host thread a GPU, with the
    /// barrier that reduce_bounds_across waits at; merges the shares' stats into `stats` and
    /// returns each share's contact count.
    std::vector<std::size_t> detect_shares(const std::function<std::size_t(std::size_t, StepStats&)>& detect_share,
                                           StepStats& stats);
    /// Each part takes the contacts at its rows from every share (`found`: the shares' counts).
    void distribute_contacts(const Model& model, const std::vector<std::size_t>& found, StepStats& stats);
    /// Offset mode, called by share p's detection (collision::BoundsReduction): waits until every
    /// share's array of `which` is complete (host barrier), then enqueues their minimum on GPU p.
    const std::uint32_t* reduce_bounds_across(std::size_t p, collision::BoundsArray which, cudaStream_t stream);
    /// One Newton iteration across the parts: the contacts' linearisation point, assembly, the
    /// Schwarz factorisation, the CG, the update and, in offset mode, the truncation. `marks`: the
    /// next stage event to record (none when null).
    void newton_iteration(const Model& model, int newton, StepStats& stats, std::size_t* marks);
    /// Offset mode, after a Newton update: v_k gathered whole on every GPU, each GPU's share of the
    /// pair limits, their minimum applied to the whole v_k on every GPU (the same bits on each), and
    /// every part's local v_k and w_k taken back from it (ghosts included).
    void truncate_across_parts(const Model& model);
    /// Every part's stream waits for the work enqueued so far on every other part's (events only).
    void join_parts();
    /// After the solve: CCD and the impact zones on the first GPU; the vertices they moved back to
    /// the parts. `swept`: a fast collider carried vertices in this substep.
    void resolve_contacts(const Model& model, double h, bool swept, StepStats& stats);
    /// Records stage event k on the first part's stream (created on first use).
    void mark(std::size_t k);
    /// The collision detection's stage times in `stats` so far, ms (its stages record themselves).
    [[nodiscard]] static double detection_ms(const StepStats& stats);
    [[nodiscard]] double elapsed_ms(std::size_t a, std::size_t b) const;

    std::vector<int> devices_;
    const FlatModel* flat_ = nullptr;
    double total_mass_ = 0.0;  // kg, every cloth's (build)
    VertexPartition partition_;
    std::vector<double> part_row_work_;  // each part's row_work, summed (the re-cut's measure)
    std::vector<PartModel> part_models_;
    std::vector<std::unique_ptr<DeviceSolver>> solvers_;
    std::unique_ptr<HaloExchange> halo_;
    std::unique_ptr<PartPcg> pcg_;
    SchwarzHierarchy hierarchy_;                // the whole model's: the partition's order, the parts' levels
    bool schwarz_ = false;
    std::unique_ptr<AllGather> level1_couplings_;  // the Schwarz factorisation's level 1, every Newton iteration
    // Per part, on its GPU, over the whole model: its share of the detection (the first also runs
    // the impact zones), and the whole arrays.
    std::vector<std::unique_ptr<DeviceCollisions>> collisions_;
    DeviceContacts leader_contacts_;  // the first GPU's share, published: the kinematic arrays
    std::vector<DeviceArray<float>> whole_;
    std::vector<DeviceArray<std::uint8_t>> whole_fixed_;  // per GPU: 1 at the whole model's pinned vertices
    bool offset_ = false;                                  // this substep's detection ran in offset mode
    bool per_triangle_bending_ = false;                    // the parts were cut for solver.bending = "shell"
    std::unique_ptr<std::barrier<>> share_barrier_;        // detect_shares: the shares' meeting point
    std::atomic<bool> share_failed_{false};                // a share threw: the others stop at the barrier
    MemoryLedger ledger_;                            // what the solver holds beside the parts
    std::unique_ptr<ContactMirror> mirror_;
    cudaEvent_t leader_event_ = nullptr;             // on the first GPU
    std::vector<cudaEvent_t> part_event_;            // per part, on its GPU
    /// The output (set_output): the target, the parts' staging buffer on the first GPU, and the
    /// events that order the parts' writes, the copy and the next writes.
    void write_output();
    void* output_ = nullptr;
    std::size_t output_stride_ = 0;
    bool output_synchronous_ = true;
    DeviceArray<unsigned char> output_staging_;
    std::size_t staged_stride_ = 0;              // the parts are bound to the staging buffer with it (0: not bound)
    cudaEvent_t output_copied_ = nullptr;        // on the first GPU: the staging buffer is free again
    std::vector<cudaEvent_t> output_written_;    // per part, on its GPU: its vertices are in the staging buffer
    cudaEvent_t output_ordered_ = nullptr;       // on the outside stream's device: its work before the copy
    std::vector<cudaEvent_t> events_;  // stage timing, on devices_.front()
    cudaStream_t user_stream_ = nullptr;
    cudaEvent_t user_event_ = nullptr;  // on the outside stream's device
    std::vector<cudaEvent_t> part_done_;  // per part: its substep's end, for the outside stream
    bool use_graph_ = true;
    // Device faults (substep, recover_from_fault): the stage running, how many parts began the
    // substep (wrote its start), and after a fault the state on the host until the rebuild.
    const char* stage_ = "";
    std::size_t begun_ = 0;
    bool rebuild_pending_ = false;
    std::vector<Vec3d> rescued_x_, rescued_v_;
    std::vector<std::uint8_t> cold_state_;             // the warm start after a fault: zeros
    std::vector<std::uint8_t> pending_solver_state_;   // restored while the rebuild was pending
    std::string device_lost_;                          // a sticky error's reason
    PcgLoop pcg_loop_ = PcgLoop::Auto;
    AssemblyStrategy assembly_ = AssemblyStrategy::Auto;
    // Re-cutting by contact load: the last detection's contacts per share, the policy, whether the
    // end of this substep re-cuts, and how many re-cuts so far.
    std::vector<std::size_t> found_;
    RecutPolicy recut_policy_;
    bool recut_due_ = false;
    int recuts_ = 0;
    /// A contact's vertex in pattern blocks for the re-cut (kContactWorkPerVertex; profiling may
    /// override it with WEFT_GPU_CONTACT_WORK: docs/multi-gpu.md, "Re-cutting by contact load").
    double contact_work_ = contact_work_per_vertex();
};

}  // namespace weft::cuda::multi
