// One world stepped across several GPUs (multi/multi_solver.h): the substep's stages enqueued on
// every part in turn, the CG across the parts between assembly and update.
#include "multi/multi_solver.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <future>
#include <string>

#include "cuda_check.h"
#include "multi/peer_access.h"
#include "multi/whole_state.h"
#include "weft/backend/timing.h"
#include "weft/error.h"

namespace weft::cuda::multi {

double contact_work_per_vertex() {
    const char* env = std::getenv("WEFT_GPU_CONTACT_WORK");
    if (env == nullptr || *env == '\0') return kContactWorkPerVertex;
    char* end = nullptr;
    const double value = std::strtod(env, &end);
    if (end == env || *end != '\0' || !(value >= 0.0 && value <= 100.0))
        throw Error(std::string("WEFT_GPU_CONTACT_WORK=") + env + ": expected a number of pattern blocks in [0, 100]");
    return value;
}

// The one-GPU layout (device_upload.cpp): 'G', sizeof(float), the vertex count (u64), the substep
// count (i64), then 3n floats of the previous Δv, component by component.
namespace {
constexpr std::size_t kStateHead = 2 + sizeof(std::uint64_t) + sizeof(std::int64_t);

std::uint64_t state_vertices(std::span<const std::uint8_t> bytes) {
    std::uint64_t n = 0;
    std::memcpy(&n, bytes.data() + 2, sizeof(n));
    return n;
}
std::int64_t state_substeps(std::span<const std::uint8_t> bytes) {
    std::int64_t substeps = 0;
    std::memcpy(&substeps, bytes.data() + 2 + sizeof(std::uint64_t), sizeof(substeps));
    return substeps;
}
std::vector<std::uint8_t> state_bytes(std::uint64_t n, std::int64_t substeps) {
    std::vector<std::uint8_t> out(kStateHead + 3 * n * sizeof(float));
    out[0] = 'G';
    out[1] = sizeof(float);
    std::memcpy(out.data() + 2, &n, sizeof(n));
    std::memcpy(out.data() + 2 + sizeof(n), &substeps, sizeof(substeps));
    return out;
}
float* state_values(std::vector<std::uint8_t>& bytes) { return reinterpret_cast<float*>(bytes.data() + kStateHead); }
const float* state_values(std::span<const std::uint8_t> bytes) { return reinterpret_cast<const float*>(bytes.data() + kStateHead); }

using Clock = std::chrono::steady_clock;

/// CG iterations per graph launch of the CG across parts (the host reads the scalars between
/// launches): a multiple of 2, long enough that the host's look costs little per iteration.
constexpr int kIterationsPerLaunch = 16;

}  // namespace

MultiSolver::MultiSolver(std::vector<int> devices) : devices_(std::move(devices)) {
    if (devices_.empty()) throw Error("multi-GPU solver: no devices given");
    int count = 0;
    WEFT_CUDA_CHECK(cudaGetDeviceCount(&count));
    for (const int d : devices_)
        if (d < 0 || d >= count)
            throw Error("multi-GPU solver: device " + std::to_string(d) + " does not exist (" + std::to_string(count) +
                        " CUDA device" + (count == 1 ? "" : "s") + ")");
}

MultiSolver::~MultiSolver() {
    // The CG and the exchange hold events and graphs on the parts' streams: release them first.
    if (!devices_.empty()) cudaSetDevice(devices_.front());
    for (cudaEvent_t e : events_) cudaEventDestroy(e);
    if (user_event_ != nullptr) cudaEventDestroy(user_event_);
    if (output_copied_ != nullptr) cudaEventDestroy(output_copied_);
    if (output_ordered_ != nullptr) cudaEventDestroy(output_ordered_);
    for (cudaEvent_t e : output_written_) cudaEventDestroy(e);
    if (leader_event_ != nullptr) cudaEventDestroy(leader_event_);
    for (cudaEvent_t e : part_event_) cudaEventDestroy(e);
    for (cudaEvent_t e : part_done_) cudaEventDestroy(e);
    pcg_.reset();
    level1_couplings_.reset();
    mirror_.reset();
    for (std::size_t p = 0; p < collisions_.size(); ++p) {
        cudaSetDevice(devices_[p]);
        collisions_[p].reset();
        whole_[p] = {};
        whole_fixed_[p] = {};
    }
    halo_.reset();
    solvers_.clear();
}

void MultiSolver::build(const FlatModel& flat, const Model& model) {
    rebuild_pending_ = false;  // a new build forgets a fault's rescue (rebuild_after_fault keeps a copy)
    rescued_x_.clear();
    rescued_v_.clear();
    cold_state_.clear();
    pcg_.reset();
    level1_couplings_.reset();
    mirror_.reset();
    for (std::size_t p = 0; p < collisions_.size(); ++p) {
        WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
        collisions_[p].reset();
        whole_[p] = {};
        whole_fixed_[p] = {};
    }
    collisions_.clear();
    whole_.clear();
    whole_fixed_.clear();
    WEFT_CUDA_CHECK(cudaSetDevice(devices_.front()));
    leader_contacts_.release();
    halo_.reset();
    solvers_.clear();
    part_models_.clear();
    flat_ = &flat;
    total_mass_ = flat.total_mass();  // the CG energy test's scale (cg_energy_floor)
    const auto parts = static_cast<std::uint32_t>(devices_.size());
    hierarchy_ = build_schwarz_hierarchy(flat.initial_positions, flat.pattern, kSchwarzMaxLevels);
    if (needs_cloth_collisions(model)) {
        // The collision stages on every GPU over the whole model, each detecting its share of the
        // pairs; the whole-size copies the contacts read on every GPU. They do not depend on the
        // cut: a re-cut keeps them.
        collisions_.resize(parts);
        whole_.resize(parts);
        whole_fixed_.resize(parts);
        std::vector<std::uint8_t> fixed(flat.vertex_count, 0);
        for (std::size_t i = 0; i < fixed.size(); ++i) fixed[i] = i < flat.vertex_pin.size() && flat.vertex_pin[i] >= 0 ? 1 : 0;
        for (std::uint32_t p = 0; p < parts; ++p) {
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
            collisions_[p] = std::make_unique<DeviceCollisions>();
            collisions_[p]->build(flat, model);
            collisions_[p]->set_share(p, parts);
            // Offset mode: each share's bounds are partial until reduced over every GPU's.
            collisions_[p]->set_bounds_reduction(
                [this, p](collision::BoundsArray which, cudaStream_t stream) { return reduce_bounds_across(p, which, stream); });
            whole_[p].allocate(4 * 3 * flat.vertex_count, ledger_, "whole state for the collision stages");
            whole_fixed_[p].upload(fixed, ledger_, "whole pins for the offset truncation");
        }
        WEFT_CUDA_CHECK(cudaSetDevice(devices_.front()));
        if (leader_event_ == nullptr) WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&leader_event_, cudaEventDisableTiming));
        if (part_event_.empty())
            for (const int d : devices_) {
                WEFT_CUDA_CHECK(cudaSetDevice(d));
                cudaEvent_t e = nullptr;
                WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
                part_event_.push_back(e);
            }
    }
    found_.assign(parts, 0);
    recut_policy_ = {};
    recut_due_ = false;
    recuts_ = 0;
    build_parts(model, row_work(flat.pattern));
    output_ = nullptr;
    staged_stride_ = 0;  // the new parts are bound to the staging buffer at the next set_output
}

void MultiSolver::build_parts(const Model& model, const std::vector<double>& work) {
    const FlatModel& flat = *flat_;
    const auto parts = static_cast<std::uint32_t>(devices_.size());
    synchronize();
    pcg_.reset();
    level1_couplings_.reset();
    mirror_.reset();
    halo_.reset();
    solvers_.clear();
    part_models_.clear();
    // The bending model per triangle reads two rings out: its reach becomes ghosts too (vertex_partition.h).
    per_triangle_bending_ = model.settings.solver.bending == BendingModel::Shell;
    const VertexReach reach = per_triangle_bending_ ? per_triangle_bending_reach(flat) : VertexReach{};
    // Throws, naming the count, when there are fewer level-0 domains than parts.
    partition_ = build_partition(flat.pattern, cut_order(hierarchy_.order, work, parts, SchwarzHierarchy::kDomainSize), parts, work,
                                 per_triangle_bending_ ? &reach : nullptr);
    // Each part's rows' work (without contacts): what the detections weigh its contacts against.
    part_row_work_.assign(parts, 0.0);
    const std::vector<double> rows = row_work(flat.pattern);
    for (std::size_t v = 0; v < rows.size(); ++v) part_row_work_[partition_.part_of[v]] += rows[v];
    part_models_.reserve(parts);
    for (std::uint32_t p = 0; p < parts; ++p) part_models_.push_back(extract_part(flat, partition_, p, per_triangle_bending_));
    std::vector<cudaStream_t> streams;
    for (std::uint32_t p = 0; p < parts; ++p) {
        auto solver = std::make_unique<DeviceSolver>(devices_[p]);
        solver->set_assembly(assembly_);
        solver->build_part(flat, part_models_[p], model);
        streams.push_back(solver->stream());
        solvers_.push_back(std::move(solver));
    }
    halo_ = std::make_unique<HaloExchange>(partition_, devices_, streams);
    level1_couplings_ = std::make_unique<AllGather>(devices_, streams);
    if (!collisions_.empty()) {
        std::vector<const std::uint32_t*> global;
        std::vector<std::uint32_t> owned;
        for (std::uint32_t p = 0; p < parts; ++p) {
            global.push_back(solvers_[p]->part_global_ids());
            owned.push_back(part_models_[p].owned);
        }
        const auto n = static_cast<std::uint32_t>(flat.vertex_count);
        mirror_ = std::make_unique<ContactMirror>(devices_, streams, global, owned, n);
        for (std::uint32_t p = 0; p < parts; ++p)
            solvers_[p]->part_set_contact_copies(mirror_->copy(p, ContactMirror::kX0), mirror_->copy(p, ContactMirror::kWk),
                                                 mirror_->copy(p, ContactMirror::kVk), n);
        for (const int a : devices_)
            for (const int b : devices_) enable_peer_access(a, b);
    }
    schwarz_ = false;
    pcg_.reset();
    choose_preconditioner(model.settings.solver);
}

void MultiSolver::recut(const Model& model) {
    if (collisions_.empty() || flat_ == nullptr) throw Error("multi-GPU solver: a re-cut by contact load needs cloth collisions");
    const auto n = static_cast<std::uint32_t>(flat_->vertex_count);
    // The state (x, v and the warm start) of every part into the first GPU's whole arrays, and the
    // last detection's contacts counted at each vertex, each GPU its share.
    collect_whole({kWholeX, kWholeV, kWholePrevious}, 1);
    std::vector<std::uint32_t> contacts_at(n, 0);
    {
        MemoryLedger scratch;
        std::vector<DeviceArray<std::uint32_t>> counts(solvers_.size());
        std::vector<std::uint32_t> share(n);
        for (std::size_t p = 0; p < solvers_.size(); ++p) {
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
            counts[p].allocate(n, scratch, "contacts at each vertex (re-cut)");
            counts[p].zero(solvers_[p]->stream());
            launch_count_contacts_at_vertices(collisions_[p]->contacts(), found_[p], n, counts[p].get(), solvers_[p]->stream());
            WEFT_CUDA_CHECK(cudaMemcpyAsync(share.data(), counts[p].get(), n * sizeof(std::uint32_t), cudaMemcpyDeviceToHost,
                                            solvers_[p]->stream()));
            WEFT_CUDA_CHECK(cudaStreamSynchronize(solvers_[p]->stream()));
            for (std::uint32_t v = 0; v < n; ++v) contacts_at[v] += share[v];
        }
    }
    // The whole arrays live outside the parts: they survive the rebuild, and every new part takes
    // its owned vertices and ghosts from them.
    build_parts(model, row_and_contact_work(flat_->pattern, contacts_at, contact_work_));
    spread_whole();
    if (output_ != nullptr) {
        staged_stride_ = 0;  // the new parts write into the staging buffer: bind them
        set_output(output_, output_stride_, output_synchronous_);
    }
    ++recuts_;
}

void MultiSolver::choose_preconditioner(const SolverSettings& settings) {
    const bool schwarz = settings.preconditioner == Preconditioner::Schwarz ||
                         (settings.preconditioner == Preconditioner::Auto && flat_->vertex_count >= kAutoSchwarzMinVertices);
    if (schwarz == schwarz_ && pcg_) return;
    synchronize();
    for (auto& s : solvers_) s->part_use_schwarz(schwarz, hierarchy_);
    schwarz_ = schwarz;
    make_cg();
}

void MultiSolver::make_cg() {
    synchronize();
    pcg_.reset();
    std::vector<PartSystem> systems;
    for (auto& s : solvers_) systems.push_back(s->part_system());
    pcg_ = std::make_unique<PartPcg>(systems, *halo_);
    pcg_->set_use_graph(use_graph_);
    pcg_->set_loop(pcg_loop_);
    pcg_->set_contact_mirror(mirror_.get());
}

float* MultiSolver::whole(std::size_t part, WholeArray a) const {
    return whole_.at(part).get() + static_cast<std::size_t>(a) * 3 * flat_->vertex_count;
}

void MultiSolver::collect_whole(std::initializer_list<WholeArray> arrays, std::size_t targets) {
    const auto n = static_cast<std::uint32_t>(flat_->vertex_count);
    for (std::size_t p = 0; p < solvers_.size(); ++p) {
        DeviceSolver& s = *solvers_[p];
        const DeviceView& v = s.view();
        WEFT_CUDA_CHECK(cudaSetDevice(s.device()));
        for (std::size_t q = 0; q < targets; ++q)
            for (const WholeArray a : arrays) {
                const float* from = a == kWholeX ? v.x : a == kWholeV ? v.v : a == kWholeV0 ? v.v0 : v.dv_previous;
                launch_owned_to_whole(from, v.n, v.rows, s.part_global_ids(), whole(q, a), n, s.stream());
            }
        WEFT_CUDA_CHECK(cudaEventRecord(part_event_[p], s.stream()));
    }
    for (std::size_t q = 0; q < targets; ++q) {
        DeviceSolver& target = *solvers_[q];
        WEFT_CUDA_CHECK(cudaSetDevice(target.device()));
        for (cudaEvent_t e : part_event_) WEFT_CUDA_CHECK(cudaStreamWaitEvent(target.stream(), e, 0));
    }
}

void MultiSolver::spread_whole() {
    const auto n = static_cast<std::uint32_t>(flat_->vertex_count);
    DeviceSolver& leader = *solvers_.front();
    WEFT_CUDA_CHECK(cudaSetDevice(leader.device()));
    WEFT_CUDA_CHECK(cudaEventRecord(leader_event_, leader.stream()));
    for (auto& sp : solvers_) {
        DeviceSolver& s = *sp;
        const DeviceView& v = s.view();
        WEFT_CUDA_CHECK(cudaSetDevice(s.device()));
        WEFT_CUDA_CHECK(cudaStreamWaitEvent(s.stream(), leader_event_, 0));
        launch_whole_to_local(whole(0, kWholeX), n, s.part_global_ids(), v.x, v.n, s.stream());
        launch_whole_to_local(whole(0, kWholeV), n, s.part_global_ids(), v.v, v.n, s.stream());
        launch_whole_to_local(whole(0, kWholePrevious), n, s.part_global_ids(), v.dv_previous, v.n, s.stream());
    }
}

void MultiSolver::detect_contacts(const Model& model, double t, double h, StepStats& stats) {
    // The detection reads x and v; offset mode's predicted moves also the previous Δv.
    const std::size_t parts = solvers_.size();
    offset_ = model.settings.collision.mode == CollisionMode::Offset;
    join_parts();  // every GPU's whole arrays are written below by every part: their readers are done
    if (offset_)
        collect_whole({kWholeX, kWholeV, kWholePrevious}, parts);
    else
        collect_whole({kWholeX, kWholeV}, parts);
    const std::vector<std::size_t> found = detect_shares(
        [&](std::size_t p, StepStats& share_stats) {
            DeviceSolver& s = *solvers_[p];
            return collisions_[p]->detect(model, t, h, whole(p, kWholeX), whole(p, kWholeV), whole(p, kWholePrevious),
                                          s.stream(), share_stats);
        },
        stats);
    distribute_contacts(model, found, stats);
}

void MultiSolver::redetect_contacts(const Model& model, double h, StepStats& stats) {
    // Whole x holds the substep's start and whole v the truncated v_k on every GPU (truncate_across_parts).
    const std::vector<std::size_t> found = detect_shares(
        [&](std::size_t p, StepStats& share_stats) {
            DeviceSolver& s = *solvers_[p];
            return collisions_[p]->redetect(model, h, whole(p, kWholeX), whole(p, kWholeV), s.step_h_device(), s.stream(),
                                            share_stats);
        },
        stats);
    distribute_contacts(model, found, stats);
}

std::vector<std::size_t> MultiSolver::detect_shares(const std::function<std::size_t(std::size_t, StepStats&)>& detect_share,
                                                    StepStats& stats) {
    const std::size_t parts = solvers_.size();
    std::vector<StepStats> share_stats(parts);
    std::vector<std::size_t> found(parts, 0);
    DeviceMemoryBudget* const budget = current_budget();  // the backend's, on this thread
    // A share overwrites its bound arrays (and the offset contact's whole arrays) while another GPU's
    // stream may still be reading them: the last truncation's reduction across the shares is only
    // waited for on the first GPU (finish_truncation). Every stream first waits for all the others.
    join_parts();
    share_failed_ = false;
    share_barrier_ = std::make_unique<std::barrier<>>(static_cast<std::ptrdiff_t>(parts));
    const auto run_share = [&](std::size_t p) {
        const BudgetScope scope(budget);  // the same on the share's thread: its buffers grow there
        const long long launches_before = thread_kernel_launches;  // this thread's (p > 0: its own)
        try {
            WEFT_CUDA_CHECK(cudaSetDevice(solvers_[p]->device()));
            found[p] = detect_share(p, share_stats[p]);
            if (p > 0) collisions_[p]->count_buffer_growths(share_stats[p]);
            share_stats[p].kernels_launched = thread_kernel_launches - launches_before;
        } catch (...) {
            // The other shares must not wait for this one at the barrier (reduce_bounds_across).
            share_failed_ = true;
            share_barrier_->arrive_and_drop();
            throw;
        }
        share_barrier_->arrive_and_drop();
    };
    // Every GPU its share at once: one host thread a GPU (each detection waits for its device).
    std::vector<std::future<void>> others;
    for (std::size_t p = 1; p < parts; ++p) others.push_back(std::async(std::launch::async, run_share, p));
    std::exception_ptr failure;
    try {
        run_share(0);
    } catch (...) {
        failure = std::current_exception();
    }
    for (auto& f : others) {
        try {
            f.get();
        } catch (...) {
            if (!failure) failure = std::current_exception();
        }
    }
    if (failure) std::rethrow_exception(failure);
    // The shares ran side by side: each stage took the longest share's time; the counts add up
    // (every share reruns together: its count once).
    std::size_t contacts = 0;
    for (std::size_t p = 0; p < parts; ++p) {
        const StepStats& a = share_stats[p];
        stats.collision.candidate_pairs += a.collision.candidate_pairs;
        stats.collision.buffer_growths += a.collision.buffer_growths;
        // Share 0 ran on this thread, whose count the backend takes; the others' threads add theirs.
        if (p > 0) stats.kernels_launched += a.kernels_launched;
        stats.collision.query_radius_max = std::max(stats.collision.query_radius_max, a.collision.query_radius_max);
        contacts += found[p];
    }
    stats.collision.redetections += share_stats[0].collision.redetections;
    for (const Stage stage : {Stage::BroadPhase, Stage::Culling, Stage::NarrowPhase}) {
        double longest = 0.0;
        for (const StepStats& a : share_stats) longest = std::max(longest, a.ms(stage));
        stats.ms(stage) += longest;
    }
    stats.collision.contacts = static_cast<int>(contacts);
    return found;
}

const std::uint32_t* MultiSolver::reduce_bounds_across(std::size_t p, collision::BoundsArray which, cudaStream_t stream) {
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));  // this share's array is complete
    share_barrier_->arrive_and_wait();                // and so is every other share's
    if (share_failed_) throw Error("multi-GPU solver: another GPU's share of the collision detection failed");
    std::vector<const std::uint32_t*> arrays;
    for (const auto& c : collisions_) arrays.push_back(c->bounds_array(which));
    return collisions_[p]->reduce_bounds(arrays, stream);
}

void MultiSolver::distribute_contacts(const Model& model, const std::vector<std::size_t>& found, StepStats& stats) {
    const std::size_t parts = solvers_.size();
    DeviceSolver& leader = *solvers_.front();
    WEFT_CUDA_CHECK(cudaSetDevice(leader.device()));
    const std::size_t kinematic = collisions_[0]->kinematic_count();
    leader_contacts_.reserve(std::max<std::size_t>(found[0], 1), kinematic, static_cast<std::uint32_t>(flat_->vertex_count),
                             leader.stream());
    collisions_[0]->publish(leader_contacts_.inputs(), leader.stream(), stats);
    WEFT_CUDA_CHECK(cudaEventRecord(leader_event_, leader.stream()));
    std::vector<ContactShare> shares;
    for (std::size_t p = 0; p < parts; ++p) shares.push_back({collisions_[p]->contacts(), found[p]});
    bool grew = false;
    for (auto& s : solvers_) grew = s->part_receive_contacts(shares, leader_contacts_.inputs(), leader_event_, kinematic) || grew;
    std::vector<ContactView> lists;
    int largest = 0;
    for (auto& s : solvers_) {
        lists.push_back(s->view().contacts);
        largest = std::max(largest, static_cast<int>(s->part_contact_count()));
    }
    stats.collision.contacts_largest_part = std::max(stats.collision.contacts_largest_part, largest);
    found_ = found;
    if (parts > 1) {
        std::vector<std::size_t> on_part;
        for (auto& s : solvers_) on_part.push_back(s->part_contact_count());
        const double imbalance = part_work_imbalance(part_row_work_, on_part, contact_work_);
        recut_due_ = recut_policy_.observe(imbalance, model.settings.solver.gpu_rebalance) || recut_due_;
    }
    mirror_->list_contact_vertices(lists);
    if (grew || !pcg_) make_cg();  // the parts' contact arrays moved: the CG's systems and graphs with them
}

void MultiSolver::resolve_contacts(const Model& model, double h, bool swept, StepStats& stats) {
    collect_whole({kWholeX, kWholeV, kWholeV0, kWholePrevious}, 1);
    DeviceSolver& leader = *solvers_.front();
    WEFT_CUDA_CHECK(cudaSetDevice(leader.device()));
    const bool changed = collisions_[0]->resolve(model, h, whole(0, kWholeX), whole(0, kWholeV), whole(0, kWholeV0),
                                                 whole(0, kWholePrevious), swept, leader.stream(), stats);
    if (changed) spread_whole();
}

void MultiSolver::factor_schwarz(int newton) {
    // Each part's own level-1 couplings, gathered by every part, then the levels above and every
    // level's domains on every part (docs/multi-gpu.md).
    for (auto& s : solvers_) s->part_factor_level1(newton);
    if (hierarchy_.levels() > 1) {
        std::vector<float*> couplings;
        std::vector<std::size_t> begin, end;
        for (auto& s : solvers_) {
            couplings.push_back(s->view().mas.level[1].coupling);
            begin.push_back(9 * std::size_t{s->schwarz().part().entry_begin});
            end.push_back(9 * std::size_t{s->schwarz().part().entry_end});
        }
        level1_couplings_->enqueue(couplings, begin, end);
    }
    for (auto& s : solvers_) s->part_factor_rest(newton);
}

void MultiSolver::exchange_state() {
    std::vector<float*> x, v, previous;
    for (auto& s : solvers_) {
        x.push_back(s->view().x);
        v.push_back(s->view().v);
        previous.push_back(s->view().dv_previous);
    }
    halo_->exchange(x);
    halo_->exchange(v);
    halo_->exchange(previous);
}

void MultiSolver::synchronize() const {
    for (const auto& s : solvers_) {
        WEFT_CUDA_CHECK(cudaSetDevice(s->device()));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(s->stream()));
    }
}

void MultiSolver::mark(std::size_t k) {
    // On the first part's stream: it waits for the others at every exchange and reduction, so its
    // timeline brackets each stage of all parts.
    DeviceSolver& first = *solvers_.front();
    WEFT_CUDA_CHECK(cudaSetDevice(first.device()));
    while (events_.size() <= k) {
        cudaEvent_t e = nullptr;
        WEFT_CUDA_CHECK(cudaEventCreate(&e));
        events_.push_back(e);
    }
    WEFT_CUDA_CHECK(cudaEventRecord(events_[k], first.stream()));
}

double MultiSolver::detection_ms(const StepStats& stats) {
    return stats.ms(Stage::BroadPhase) + stats.ms(Stage::Culling) + stats.ms(Stage::NarrowPhase) + stats.ms(Stage::Ccd);
}

double MultiSolver::elapsed_ms(std::size_t a, std::size_t b) const {
    float ms = 0.0F;
    WEFT_CUDA_CHECK(cudaEventElapsedTime(&ms, events_[a], events_[b]));
    return static_cast<double>(ms);
}

void MultiSolver::substep(const Model& model, double t, double h, StepStats& stats) {
    if (!device_lost_.empty())
        throw Error("CUDA backend on " + std::to_string(devices_.size()) + " parts: a GPU was lost in an earlier substep (" +
                    device_lost_ + "); the state cannot be read: build a new world");
    if (rebuild_pending_) rebuild_after_fault(model);
    if (solvers_.empty() || flat_ == nullptr || flat_->vertex_count == 0) return;
    // Requests the parts cannot take are refused before any work (they are not faults).
    if (needs_cloth_collisions(model) != !collisions_.empty())
        throw Error("CUDA backend on " + std::to_string(devices_.size()) +
                    " parts: the cloth collisions were switched on or off after the build; across GPUs that takes a new world");
    require_bending_as_built(model);
    begun_ = 0;
    stage_ = "the substep's start";
    try {
        run_substep(model, t, h, stats);
    } catch (const Error& e) {
        recover_from_fault(e, t);
    }
}

// As one GPU's (DeviceSolver::recover_from_fault): out of memory and other errors that leave every
// context usable put each part that began the substep back at its start (x0 and v0, which its first
// kernel wrote; a part that had not begun has not moved) and keep the whole state on the host, from
// which the next substep rebuilds every part: a buffer that failed to grow may have left its owner
// half resized, on any GPU. A sticky error loses the context: every later substep fails.
void MultiSolver::recover_from_fault(const Error& error, double t) {
    std::string where = "CUDA backend on " + std::to_string(devices_.size()) + " parts: the substep from t = " +
                        std::to_string(t) + " s failed in " + stage_ + ": " + error.what();
    bool usable = true;
    for (const int d : devices_) usable = context_usable_after_fault(d) && usable;  // every context checked and cleared
    if (usable) {
        std::string failure;
        try {
            for (std::size_t p = 0; p < begun_; ++p) solvers_[p]->part_rollback();
            synchronize();
            const std::size_t n = flat_->vertex_count;
            std::vector<Vec3d> x(n), v(n);
            read_state(0, n, x.data(), v.data());
            std::vector<std::uint8_t> cold = solver_state();
            std::fill(cold.begin() + static_cast<std::ptrdiff_t>(std::min(cold.size(), kStateHead)), cold.end(), std::uint8_t{0});
            rescued_x_ = std::move(x);
            rescued_v_ = std::move(v);
            cold_state_ = std::move(cold);
            rebuild_pending_ = true;
        } catch (const Error& again) {
            failure = again.what();
        }
        if (failure.empty()) throw Error(where + "; every part is back where that substep started (t = " + std::to_string(t) + " s)");
        where += "; putting the parts back failed too: " + failure;
    }
    device_lost_ = error.what();
    throw Error(where + "; a device is lost (a sticky CUDA error): the state cannot be read, build a new world");
}

void MultiSolver::rebuild_after_fault(const Model& model) {
    // build() forgets the rescue, the output binding and the warm start: copies are kept for a retry.
    const std::vector<Vec3d> x = rescued_x_, v = rescued_v_;
    const std::vector<std::uint8_t> cold = cold_state_;
    std::vector<std::uint8_t> warm = std::move(pending_solver_state_);
    pending_solver_state_.clear();
    void* const output = output_;
    const std::size_t stride = output_stride_;
    const bool synchronous = output_synchronous_;
    try {
        build(*flat_, model);
    } catch (...) {
        rescued_x_ = x;
        rescued_v_ = v;
        cold_state_ = cold;
        pending_solver_state_ = std::move(warm);
        output_ = output;
        output_stride_ = stride;
        output_synchronous_ = synchronous;
        rebuild_pending_ = true;
        throw;
    }
    write_state(0, x.size(), x.data(), v.data());
    if (!warm.empty()) restore_solver_state(warm);
    if (output != nullptr) set_output(output, stride, synchronous);
}

void MultiSolver::run_substep(const Model& model, double t, double h, StepStats& stats) {
    const bool colliding = !collisions_.empty();
    if (colliding && collisions_.front()->stale(model)) {
        for (std::size_t p = 0; p < collisions_.size(); ++p) {  // self-collision toggled live
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
            collisions_[p]->build(*flat_, model);
        }
    }
    choose_preconditioner(model.settings.solver);  // may change live
    if (recut_due_) {
        // The last detections found the contacts lastingly uneven over the parts (RecutPolicy): the
        // parts are rebuilt by rows and contacts before this substep. Its time counts as update.
        const auto recut_start = Clock::now();
        recut(model);
        recut_due_ = false;
        recut_policy_.recut_done();
        ++stats.collision.parts_recut;
        stats.ms(Stage::Update) += ms_since(recut_start);
    }
    if (user_stream_ != nullptr) {
        // After the outside stream's work so far.
        int device = 0;
        WEFT_CUDA_CHECK(cudaGetDevice(&device));
        WEFT_CUDA_CHECK(cudaEventRecord(user_event_, user_stream_));
        for (auto& s : solvers_) {
            WEFT_CUDA_CHECK(cudaSetDevice(s->device()));
            WEFT_CUDA_CHECK(cudaStreamWaitEvent(s->stream(), user_event_, 0));
        }
        WEFT_CUDA_CHECK(cudaSetDevice(device));
    }
    std::size_t e = 0;
    mark(e++);
    // The detection times its own stages (and waits for them): the first stage is what it leaves.
    const double detection_before = detection_ms(stats);
    stage_ = "collision detection";
    if (colliding) detect_contacts(model, t, h, stats);
    const double detection = detection_ms(stats) - detection_before;
    const auto host_start = Clock::now();
    if (!colliding) offset_ = false;
    stage_ = "the substep's start";
    for (auto& s : solvers_) {
        s->part_begin_substep(model, t, h, offset_);
        ++begun_;
    }
    const double host_ms = ms_since(host_start);
    mark(e++);
    const SolverSettings& settings = model.settings.solver;
    stage_ = "the solve";
    for (int it = 0; it < settings.newton_iterations; ++it) newton_iteration(model, it, stats, &e);
    for (auto& s : solvers_) s->part_commit();
    mark(e++);
    if (offset_) {
        // Offset contact: while too many moves were truncated, detect again where the truncation left
        // the cloth and take one more Newton iteration from there (CollisionSettings::redetect_share),
        // as on one GPU. Every GPU's truncation counted the same whole model: the first's counts decide.
        DeviceSolver& leader = *solvers_.front();
        stage_ = "the offset contact's reruns";
        for (;;) {
            WEFT_CUDA_CHECK(cudaSetDevice(leader.device()));
            if (!collisions_.front()->finish_truncation(model, leader.stream(), stats)) break;
            const auto extra = Clock::now();
            redetect_contacts(model, h, stats);
            newton_iteration(model, 1, stats, nullptr);
            for (auto& s : solvers_) s->part_commit();
            synchronize();
            stats.ms(Stage::Solve) += ms_since(extra);
        }
    }

    // Every part checks its own vertices (ghosts included) for NaN and Inf; one finding rolls every
    // part back, as one GPU would.
    // A part whose vertex ran away (ghosts included) dropped its own solve in its commit; then every
    // other part drops its solve too, as one GPU drops the whole system's: a part that kept its solve
    // would move its cloth while the part next to it stands still, and tear the cloth at the cut.
    int non_finite = 0, contacts = 0, runaway = 0;
    std::vector<char> ran_away;
    for (auto& s : solvers_) {
        const DeviceStats& ds = s->part_stats();
        non_finite += ds.non_finite;
        contacts += ds.contacts;
        runaway += ds.runaway;
        ran_away.push_back(ds.runaway > 0 ? 1 : 0);
    }
    if (non_finite == 0 && runaway > 0) {
        ++stats.runaway_solves;
        for (std::size_t p = 0; p < solvers_.size(); ++p)
            if (ran_away[p] == 0) solvers_[p]->part_drop_solve();
    }
    stats.collider_contacts = contacts;
    // Events: start, after the start of the substep, per Newton iteration (assembly, solve, update), end.
    stats.ms(Stage::Kinematics) += host_ms + std::max(0.0, elapsed_ms(0, 1) - detection);
    std::size_t k = 1;
    for (int it = 0; it < settings.newton_iterations; ++it, k += 3) {
        stats.ms(Stage::Forces) += elapsed_ms(k, k + 1);
        stats.ms(Stage::Solve) += elapsed_ms(k + 1, k + 2);
        stats.ms(Stage::Update) += elapsed_ms(k + 2, k + 3);
    }
    stats.ms(Stage::Update) += elapsed_ms(k, k + 1);
    const auto after = Clock::now();
    // What follows times its own stages (the sweep, CCD and the impact zones): the update stage gets
    // only the host time they leave, so that no time is counted twice.
    const auto staged = [&stats] {
        double sum = 0.0;
        for (const double ms : stats.stage_ms) sum += ms;
        return sum;
    };
    const double staged_before = staged();
    if (non_finite > 0) {
        stats.non_finite = true;
        for (auto& s : solvers_) s->part_rollback();
    } else {
        const auto moved_by_sweep = [&stats] { return stats.collision.swept_collider_hits + stats.collision.collider_overshoots; };
        const int hits_before = moved_by_sweep();
        bool swept = false;
        stage_ = "the fast-collider sweep";
        for (auto& s : solvers_) swept = s->part_sweep(stats) || swept;
        if (swept) exchange_state();  // a ghost may have been carried along differently from its owner
        stage_ = "CCD and the impact zones";
        if (colliding) resolve_contacts(model, h, moved_by_sweep() > hits_before, stats);
    }
    if (output_ != nullptr) {
        stage_ = "the output write";
        write_output();
        if (output_synchronous_) synchronize();
    }
    if (user_stream_ != nullptr) {
        // The outside stream's later work after the substep's.
        for (std::size_t p = 0; p < solvers_.size(); ++p) {
            WEFT_CUDA_CHECK(cudaSetDevice(solvers_[p]->device()));
            WEFT_CUDA_CHECK(cudaEventRecord(part_done_[p], solvers_[p]->stream()));
            WEFT_CUDA_CHECK(cudaStreamWaitEvent(user_stream_, part_done_[p], 0));
        }
    }
    stats.ms(Stage::Update) += std::max(0.0, ms_since(after) - (staged() - staged_before));
}

void MultiSolver::newton_iteration(const Model& model, int newton, StepStats& stats, std::size_t* marks) {
    const SolverSettings& settings = model.settings.solver;
    if (!collisions_.empty()) {
        // The linearisation point of every contact vertex, on every GPU.
        std::vector<const float*> x0, wk, vk;
        std::vector<std::uint32_t> stride;
        for (auto& s : solvers_) {
            x0.push_back(s->view().x0);
            wk.push_back(s->view().wk);
            vk.push_back(s->view().vk);
            stride.push_back(s->view().n);
        }
        mirror_->push(ContactMirror::kX0, x0, stride);
        mirror_->push(ContactMirror::kWk, wk, stride);
        mirror_->push(ContactMirror::kVk, vk, stride);
    }
    for (auto& s : solvers_) s->part_assemble(newton == 0, offset_);
    if (schwarz_) factor_schwarz(newton);
    // The first part's stream waits for the others' work at the solve's first exchange.
    if (marks != nullptr) mark((*marks)++);
    std::vector<const float*> b;
    std::vector<float*> dv;
    for (auto& s : solvers_) {
        b.push_back(s->view().b);
        dv.push_back(s->view().dv);
    }
    pcg_->set_energy_floor(cg_energy_floor(total_mass_, settings.cg_velocity_tolerance));
    const PartPcgResult r = pcg_->solve(b, dv, settings.cg_tolerance, settings.cg_max_iterations, kIterationsPerLaunch);
    if (marks != nullptr) mark((*marks)++);
    stats.cg_iterations += r.iterations;
    stats.cg_iterations_max = std::max(stats.cg_iterations_max, r.iterations);
    stats.cg_residual = std::max(stats.cg_residual, r.relative_residual);
    if (!r.converged) ++stats.cg_not_converged;
    ++stats.newton_iterations;
    for (auto& s : solvers_) s->part_newton_update();
    if (offset_) truncate_across_parts(model);
    if (marks != nullptr) mark((*marks)++);
}

void MultiSolver::truncate_across_parts(const Model& model) {
    const auto n = static_cast<std::uint32_t>(flat_->vertex_count);
    const std::size_t parts = solvers_.size();
    // The reads of the whole arrays and of the shares before this (the last truncation, the
    // detection's reductions) are done everywhere before they are written again.
    join_parts();
    // v_k of every vertex, from its owner, on every GPU (whole x holds the substep's start).
    for (std::size_t p = 0; p < parts; ++p) {
        DeviceSolver& s = *solvers_[p];
        const DeviceView& v = s.view();
        WEFT_CUDA_CHECK(cudaSetDevice(s.device()));
        for (std::size_t q = 0; q < parts; ++q) launch_owned_to_whole(v.vk, v.n, v.rows, s.part_global_ids(), whole(q, kWholeV), n, s.stream());
    }
    join_parts();
    // Each GPU's share of the pair limits, then (once all are done) their minimum on every GPU.
    for (std::size_t q = 0; q < parts; ++q) {
        DeviceSolver& s = *solvers_[q];
        WEFT_CUDA_CHECK(cudaSetDevice(s.device()));
        collisions_[q]->enqueue_share_limits(model, whole(q, kWholeX), whole(q, kWholeV), s.step_h_device(), s.stream());
    }
    join_parts();
    std::vector<const std::uint32_t*> shares;
    for (const auto& c : collisions_) shares.push_back(c->bounds_array(collision::BoundsArray::Shares));
    for (std::size_t q = 0; q < parts; ++q) {
        DeviceSolver& s = *solvers_[q];
        const DeviceView& v = s.view();
        WEFT_CUDA_CHECK(cudaSetDevice(s.device()));
        collisions_[q]->enqueue_reduced_truncation(model, shares, whole(q, kWholeX), whole(q, kWholeV), whole_fixed_[q].get(),
                                                   s.step_h_device(), s.stream());
        // After a Newton update w_k = v_k at every vertex, truncated or not: both from the whole v_k.
        launch_whole_to_local(whole(q, kWholeV), n, s.part_global_ids(), v.vk, v.n, s.stream());
        launch_whole_to_local(whole(q, kWholeV), n, s.part_global_ids(), v.wk, v.n, s.stream());
    }
}

void MultiSolver::join_parts() {
    for (std::size_t p = 0; p < solvers_.size(); ++p) {
        WEFT_CUDA_CHECK(cudaSetDevice(solvers_[p]->device()));
        WEFT_CUDA_CHECK(cudaEventRecord(part_event_[p], solvers_[p]->stream()));
    }
    for (std::size_t p = 0; p < solvers_.size(); ++p) {
        WEFT_CUDA_CHECK(cudaSetDevice(solvers_[p]->device()));
        for (std::size_t q = 0; q < solvers_.size(); ++q)
            if (q != p) WEFT_CUDA_CHECK(cudaStreamWaitEvent(solvers_[p]->stream(), part_event_[q], 0));
    }
}

void MultiSolver::set_stream(cudaStream_t stream) {
    synchronize();
    if (user_event_ == nullptr && stream != nullptr) {
        // The event lives on the stream's device; the parts' on theirs.
        WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&user_event_, cudaEventDisableTiming));
        for (const int d : devices_) {
            WEFT_CUDA_CHECK(cudaSetDevice(d));
            cudaEvent_t e = nullptr;
            WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
            part_done_.push_back(e);
        }
    }
    user_stream_ = stream;
}

cudaStream_t MultiSolver::stream() const {
    if (user_stream_ != nullptr) return user_stream_;
    return solvers_.empty() ? nullptr : solvers_.front()->stream();
}

void MultiSolver::set_pcg_loop(PcgLoop loop) {
    pcg_loop_ = loop;
    if (pcg_) pcg_->set_loop(loop);
}

bool MultiSolver::one_launch_cg() const { return pcg_ != nullptr && pcg_->one_launch(); }

void MultiSolver::set_use_graph(bool enabled) {
    use_graph_ = enabled;
    if (pcg_) pcg_->set_use_graph(enabled);
}

void MultiSolver::set_assembly(AssemblyStrategy strategy) {
    assembly_ = strategy;
    for (auto& s : solvers_) s->set_assembly(strategy);
}

void MultiSolver::read_state(std::size_t first, std::size_t count, Vec3d* x, Vec3d* v) const {
    if (first + count > (flat_ != nullptr ? flat_->vertex_count : 0))
        throw Error("multi-GPU solver: read_state of vertices [" + std::to_string(first) + ", " + std::to_string(first + count) +
                    ") past the model");
    if (rebuild_pending_) {  // after a fault the state is on the host (substep)
        std::copy_n(rescued_x_.begin() + static_cast<std::ptrdiff_t>(first), count, x);
        std::copy_n(rescued_v_.begin() + static_cast<std::ptrdiff_t>(first), count, v);
        return;
    }
    for (std::size_t p = 0; p < solvers_.size(); ++p) {
        const PartModel& pm = part_models_[p];
        std::vector<Vec3d> px(pm.owned), pv(pm.owned);
        solvers_[p]->read_state(0, pm.owned, px.data(), pv.data());
        for (std::uint32_t i = 0; i < pm.owned; ++i) {
            const std::size_t g = pm.global_vertex[i];
            if (g < first || g >= first + count) continue;
            x[g - first] = px[i];
            v[g - first] = pv[i];
        }
    }
}

namespace {

/// The vertices [first, first + count) of the model that `part_rows(p, rows)` lists among each
/// part's owned rows, as `first`-relative ids, ascending (every vertex has one owner).
template <class PartRows>
void owned_rows_in_range(const std::vector<PartModel>& parts, std::size_t first, std::size_t count, PartRows part_rows,
                         std::vector<std::uint32_t>& out) {
    std::vector<std::uint32_t> rows;
    for (std::size_t p = 0; p < parts.size(); ++p) {
        part_rows(p, rows);
        for (const std::uint32_t i : rows) {
            const std::size_t g = parts[p].global_vertex[i];
            if (g >= first && g < first + count) out.push_back(static_cast<std::uint32_t>(g - first));
        }
    }
    std::sort(out.begin(), out.end());
}

}  // namespace

void MultiSolver::contact_vertices(std::size_t first, std::size_t count, std::vector<std::uint32_t>& out) const {
    out.clear();
    if (first + count > (flat_ != nullptr ? flat_->vertex_count : 0))
        throw Error("multi-GPU solver: contact_vertices of vertices [" + std::to_string(first) + ", " +
                    std::to_string(first + count) + ") past the model");
    if (rebuild_pending_ || count == 0) return;  // after a fault the state is on the host: no contacts
    owned_rows_in_range(part_models_, first, count, [&](std::size_t p, std::vector<std::uint32_t>& rows) {
        solvers_[p]->contact_vertices(0, part_models_[p].owned, rows);  // rows with a contact incidence
    }, out);
}

void MultiSolver::collider_contact_vertices(std::size_t first, std::size_t count, std::vector<std::uint32_t>& out) const {
    out.clear();
    if (first + count > (flat_ != nullptr ? flat_->vertex_count : 0))
        throw Error("multi-GPU solver: collider_contact_vertices of vertices [" + std::to_string(first) + ", " +
                    std::to_string(first + count) + ") past the model");
    if (rebuild_pending_ || count == 0) return;
    owned_rows_in_range(part_models_, first, count, [&](std::size_t p, std::vector<std::uint32_t>& rows) {
        solvers_[p]->collider_contact_vertices(0, part_models_[p].owned, rows);
    }, out);
}

void MultiSolver::write_state(std::size_t first, std::size_t count, const Vec3d* x, const Vec3d* v) {
    if (first + count > (flat_ != nullptr ? flat_->vertex_count : 0))
        throw Error("multi-GPU solver: write_state of vertices [" + std::to_string(first) + ", " +
                    std::to_string(first + count) + ") past the model");
    if (rebuild_pending_) {
        std::copy_n(x, count, rescued_x_.begin() + static_cast<std::ptrdiff_t>(first));
        std::copy_n(v, count, rescued_v_.begin() + static_cast<std::ptrdiff_t>(first));
        return;
    }
    for (std::size_t p = 0; p < solvers_.size(); ++p) {
        const PartModel& pm = part_models_[p];
        const std::size_t local = pm.model.vertex_count;
        std::vector<Vec3d> px(local), pv(local);
        solvers_[p]->read_state(0, local, px.data(), pv.data());
        bool touched = false;
        for (std::size_t i = 0; i < local; ++i) {
            const std::size_t g = pm.global_vertex[i];
            if (g < first || g >= first + count) continue;
            px[i] = x[g - first];
            pv[i] = v[g - first];
            touched = true;
        }
        if (touched) solvers_[p]->write_state(0, local, px.data(), pv.data());
    }
}


std::vector<std::uint8_t> MultiSolver::solver_state() const {
    // After a fault: what was restored meanwhile, else the cold start the rebuild begins with.
    if (rebuild_pending_) return pending_solver_state_.empty() ? cold_state_ : pending_solver_state_;
    if (solvers_.empty() || flat_ == nullptr) return {};
    const std::uint64_t n = flat_->vertex_count;
    std::vector<std::uint8_t> out;
    for (std::size_t p = 0; p < solvers_.size(); ++p) {
        const std::vector<std::uint8_t> local = solvers_[p]->solver_state();
        const PartModel& pm = part_models_[p];
        const std::uint64_t local_n = state_vertices(local);
        if (p == 0) out = state_bytes(n, state_substeps(local));
        float* whole = state_values(out);
        const float* values = state_values(std::span<const std::uint8_t>(local));
        std::vector<float> aligned(3 * local_n);  // the bytes after the head need not be float-aligned
        std::memcpy(aligned.data(), values, aligned.size() * sizeof(float));
        for (std::uint32_t i = 0; i < pm.owned; ++i)
            for (std::size_t c = 0; c < 3; ++c) {
                const float value = aligned[c * local_n + i];
                std::memcpy(whole + c * n + pm.global_vertex[i], &value, sizeof(float));
            }
    }
    return out;
}

void MultiSolver::restore_solver_state(std::span<const std::uint8_t> bytes) {
    if (bytes.empty()) return;
    if (bytes.size() < kStateHead || bytes[0] != 'G')
        throw Error("cuda backend: the checkpoint's solver state is not the CUDA backend's");
    if (bytes[1] != sizeof(float)) throw Error("cuda backend: the checkpoint's solver state is not in float");
    const std::uint64_t n = state_vertices(bytes);
    const std::size_t vertices = flat_ != nullptr ? flat_->vertex_count : 0;
    if (n != vertices || bytes.size() != kStateHead + 3 * n * sizeof(float))
        throw Error("cuda backend: the checkpoint's solver state is for " + std::to_string(n) + " vertices, this world has " +
                    std::to_string(vertices));
    if (rebuild_pending_) {  // kept for the rebuild after a fault
        pending_solver_state_.assign(bytes.begin(), bytes.end());
        return;
    }
    std::vector<float> whole(3 * n);
    std::memcpy(whole.data(), state_values(bytes), whole.size() * sizeof(float));
    for (std::size_t p = 0; p < solvers_.size(); ++p) {
        const PartModel& pm = part_models_[p];
        const std::uint64_t local_n = pm.model.vertex_count;
        std::vector<std::uint8_t> local = state_bytes(local_n, state_substeps(bytes));
        std::vector<float> values(3 * local_n);
        for (std::uint64_t i = 0; i < local_n; ++i)  // owned and ghost vertices alike
            for (std::size_t c = 0; c < 3; ++c) values[c * local_n + i] = whole[c * n + pm.global_vertex[i]];
        std::memcpy(state_values(local), values.data(), values.size() * sizeof(float));
        solvers_[p]->restore_solver_state(local);
    }
}

void MultiSolver::require_bending_as_built(const Model& model) const {
    if ((model.settings.solver.bending == BendingModel::Shell) != per_triangle_bending_)
        throw Error("CUDA backend on " + std::to_string(devices_.size()) +
                    " parts: solver.bending was switched between \"hinge\" and \"shell\" after the build; the parts are cut for "
                    "the model they were built with, so across GPUs that takes a new world");
}

EnergyAudit MultiSolver::energy_audit(const Model& model, double t, double h, bool with_wind) {
    if (!device_lost_.empty())
        throw Error("CUDA backend on " + std::to_string(devices_.size()) + " parts: a GPU was lost in an earlier substep (" +
                    device_lost_ + "); the state cannot be audited");
    // After a fault the parts are rebuilt first (a failed rebuild throws here, reading nothing).
    if (rebuild_pending_) rebuild_after_fault(model);
    require_bending_as_built(model);
    EnergyAudit sum;
    sum.with_wind = with_wind;
    // Offset contacts name vertices of the whole model: every part reads them from its GPU's whole x.
    // The other contact modes leave no contact blocks to audit, so they skip the gather.
    if (offset_) collect_whole({kWholeX}, solvers_.size());
    for (std::size_t p = 0; p < solvers_.size(); ++p) {
        const EnergyAudit a =
            solvers_[p]->energy_audit(model, t, h, with_wind, offset_ ? whole(p, kWholeX) : nullptr);
        sum.bounded = sum.bounded && a.bounded;
        sum.kinetic += a.kinetic;
        sum.gravity += a.gravity;
        sum.contact += a.contact;
        sum.elastic += a.elastic;
        sum.max_stretch = std::max(sum.max_stretch, a.max_stretch);
        sum.external_power += a.external_power;
    }
    return sum;
}

void MultiSolver::set_output(void* device_buffer, std::size_t stride, bool synchronous) {
    if (device_buffer != nullptr && stride < 6 * sizeof(float))
        throw Error("CUDA backend: output stride " + std::to_string(stride) + " is smaller than one vertex (24 bytes)");
    output_ = device_buffer;
    output_stride_ = stride;
    output_synchronous_ = synchronous;
    // After a fault the binding waits for the rebuild (rebuild_after_fault binds it and writes the state).
    if (device_buffer == nullptr || solvers_.empty() || rebuild_pending_) return;
    const std::size_t bytes = flat_->vertex_count * stride;
    if (output_staging_.size() != bytes || staged_stride_ != stride) {
        // The staging buffer lives on the first part's GPU; the others write into it through peer
        // access. Replaced only when the size changes: every earlier copy out of it is done first.
        synchronize();
        WEFT_CUDA_CHECK(cudaSetDevice(devices_.front()));
        output_staging_ = {};
        output_staging_.allocate(bytes, ledger_, "output staging (first GPU)");
        ledger_.set("output staging (first GPU)", bytes);
        if (output_copied_ == nullptr) {
            WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&output_copied_, cudaEventDisableTiming));
            WEFT_CUDA_CHECK(cudaEventRecord(output_copied_, solvers_.front()->stream()));
            for (const int d : devices_) {
                WEFT_CUDA_CHECK(cudaSetDevice(d));
                cudaEvent_t e = nullptr;
                WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&e, cudaEventDisableTiming));
                output_written_.push_back(e);
            }
        }
        for (auto& s : solvers_) enable_peer_access(s->device(), devices_.front());
        // Every part writes into the staging buffer from now on (part_write_output); this writes
        // the current state there at once, before the copy below.
        for (auto& s : solvers_) s->set_output(output_staging_.get(), stride, false);
        staged_stride_ = stride;
    }
    write_output();
    if (synchronous) synchronize();
}

void MultiSolver::write_output() {
    DeviceSolver& leader = *solvers_.front();
    // Each part writes its owned vertices once the last copy has read the staging buffer.
    for (std::size_t p = 0; p < solvers_.size(); ++p) {
        DeviceSolver& s = *solvers_[p];
        WEFT_CUDA_CHECK(cudaSetDevice(s.device()));
        WEFT_CUDA_CHECK(cudaStreamWaitEvent(s.stream(), output_copied_, 0));
        s.part_write_output();
        WEFT_CUDA_CHECK(cudaEventRecord(output_written_[p], s.stream()));
    }
    WEFT_CUDA_CHECK(cudaSetDevice(leader.device()));
    for (cudaEvent_t e : output_written_) WEFT_CUDA_CHECK(cudaStreamWaitEvent(leader.stream(), e, 0));
    if (user_stream_ != nullptr) {
        // The target is ordered on the outside stream (a shared slot's wait comes before the copy).
        if (output_ordered_ == nullptr) WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&output_ordered_, cudaEventDisableTiming));
        WEFT_CUDA_CHECK(cudaEventRecord(output_ordered_, user_stream_));
        WEFT_CUDA_CHECK(cudaStreamWaitEvent(leader.stream(), output_ordered_, 0));
    }
    WEFT_CUDA_CHECK(cudaMemcpyAsync(output_, output_staging_.get(), output_staging_.size(), cudaMemcpyDeviceToDevice,
                                    leader.stream()));
    WEFT_CUDA_CHECK(cudaEventRecord(output_copied_, leader.stream()));
    if (user_stream_ != nullptr) WEFT_CUDA_CHECK(cudaStreamWaitEvent(user_stream_, output_copied_, 0));
}

std::size_t MultiSolver::memory_bytes() const {
    std::size_t total = (halo_ ? halo_->memory_bytes() : 0) + ledger_.total() + (mirror_ ? mirror_->memory_bytes() : 0) +
                        leader_contacts_.bytes();
    for (const auto& c : collisions_) total += c->memory_bytes();
    for (std::size_t p = 0; p < solvers_.size(); ++p) total += solvers_[p]->memory_bytes() + (pcg_ ? pcg_->memory_bytes(p) : 0);
    return total;
}

std::vector<std::pair<std::string, std::size_t>> MultiSolver::memory_breakdown() const {
    std::vector<std::pair<std::string, std::size_t>> out;
    for (std::size_t p = 0; p < solvers_.size(); ++p) {
        const std::string prefix = "part " + std::to_string(p) + " (GPU " + std::to_string(devices_[p]) + "): ";
        for (const auto& [what, bytes] : solvers_[p]->memory_breakdown()) out.emplace_back(prefix + what, bytes);
        if (pcg_) out.emplace_back(prefix + "CG across parts", pcg_->memory_bytes(p));
    }
    if (halo_) out.emplace_back("halo exchange", halo_->memory_bytes());
    if (!collisions_.empty()) {
        for (std::size_t p = 0; p < collisions_.size(); ++p)
            out.emplace_back("GPU " + std::to_string(devices_[p]) + ": cloth collisions (its share of the pairs" +
                                 (p == 0 ? ", the impact zones)" : ")"),
                             collisions_[p]->memory_bytes());
        out.emplace_back("whole state (every GPU) and the first GPU's published contacts", ledger_.total() + leader_contacts_.bytes());
        out.emplace_back("contact mirrors (every GPU)", mirror_->memory_bytes());
    }
    return out;
}

}  // namespace weft::cuda::multi
