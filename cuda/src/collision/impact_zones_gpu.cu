// Impact zones on the GPU (see impact_zones_gpu.h; the CPU reference is
// runtime/src/collision/impact_zones.cpp, whose stages this follows one for one).
#include "collision/impact_zones_gpu.h"

#include <cub/block/block_reduce.cuh>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_run_length_encode.cuh>
#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "cuda_check.h"
#include "grid_size.h"
#include "weft/backend/timing.h"
#include "weft/error.h"
#include "weft/physics/eigen_sym.h"

namespace weft::cuda::collision {
namespace {

using weft::collision::VertexOutcome;

constexpr unsigned kThreads = 256;      // element-wise kernels
constexpr unsigned kZoneThreads = 128;  // one block per zone (rigid zones; projections of small zones)
// Zones of more constraints than this are projected by blocks of kLargeZoneThreads: one block runs a
// zone's whole projection, each of its iterations a few dependent loads per constraint, so a large
// zone is latency-bound and wants every warp an SM can hold.
constexpr unsigned kLargeZoneThreads = 1024;
constexpr std::uint32_t kLargeZoneConstraints = 4 * kZoneThreads;
constexpr std::uint32_t kInvalid = 0xFFFFFFFFU;

// Outcome codes on the device (weft::collision::VertexOutcome).
constexpr std::uint8_t kFixed = static_cast<std::uint8_t>(VertexOutcome::Fixed);
constexpr std::uint8_t kUntouched = static_cast<std::uint8_t>(VertexOutcome::Untouched);
constexpr std::uint8_t kProjected = static_cast<std::uint8_t>(VertexOutcome::Projected);
constexpr std::uint8_t kRigidOutcome = static_cast<std::uint8_t>(VertexOutcome::Rigid);
constexpr std::uint8_t kFrozen = static_cast<std::uint8_t>(VertexOutcome::Frozen);
constexpr std::uint8_t kCarried = static_cast<std::uint8_t>(VertexOutcome::Carried);

// Zone flags (per root, rebuilt each fallback round) and actions (per root), as on the CPU.
constexpr std::uint32_t kTouchesFixed = 1, kIsRigid = 2, kHasFrozen = 4;
constexpr std::uint8_t kNone = 0, kProject = 1, kPending = 2, kRigid = 3, kFreeze = 4;

// Eigenvalues of a rigid zone's inertia below this fraction of the largest are treated as zero (the
// CPU's kInertiaCutoff).
constexpr double kInertiaCutoff = 1e-12;

using Clock = std::chrono::steady_clock;

template <typename T>
void grow(DeviceArray<T>& a, std::size_t n) {
    if (a.size() >= n) return;
    MemoryLedger unused;
    a.allocate(std::max<std::size_t>(n, 1), unused, "impact zones");
}

/// Grows `a` to at least `n` elements keeping its first `keep` (the constraints accumulate across
/// rounds). The old buffer's cudaFree waits for the copy.
template <typename T>
void grow_keeping(DeviceArray<T>& a, std::size_t n, std::size_t keep, cudaStream_t stream) {
    if (a.size() >= n) return;
    DeviceArray<T> b;
    MemoryLedger unused;
    b.allocate(n, unused, "impact zones");
    if (keep > 0) WEFT_CUDA_CHECK(cudaMemcpyAsync(b.get(), a.get(), keep * sizeof(T), cudaMemcpyDeviceToDevice, stream));
    a = std::move(b);
}

__device__ inline float load(const float* x, std::uint32_t v, std::uint32_t stride, int c) {
    return x[static_cast<std::size_t>(c) * stride + v];
}

// ---- Union–find ------------------------------------------------------------------------------------
// Lock-free (Anderson & Woll 1991; Jaiganesh & Burtscher 2018, ECL-CC): a root is hooked under a
// smaller root with atomicCAS, so every set's root is its smallest member whatever the order of the
// hooks (the CPU's labels). Path halving writes only ancestors, which every reader accepts.

__device__ std::uint32_t find_root(std::uint32_t* parent, std::uint32_t v) {
    volatile std::uint32_t* p = parent;
    std::uint32_t next = p[v];
    while (next != v) {
        const std::uint32_t grand = p[next];
        if (grand != next) p[v] = grand;
        v = next;
        next = p[v];
    }
    return v;
}

__device__ void unite(std::uint32_t* parent, std::uint32_t a, std::uint32_t b) {
    for (;;) {
        a = find_root(parent, a);
        b = find_root(parent, b);
        if (a == b) return;
        if (b < a) {
            const std::uint32_t t = a;
            a = b;
            b = t;
        }
        const std::uint32_t old = atomicCAS(parent + b, b, a);
        if (old == b) return;
        b = old;  // b was hooked meanwhile: retry from its new parent
    }
}

// ---- Per-call set-up -----------------------------------------------------------------------------------

__global__ void init_kernel(std::uint32_t n, const float* inverse_mass, const float* x1, float* x_hat,
                            std::uint32_t* parent, std::uint32_t* label, std::uint8_t* member,
                            std::uint8_t* outcome, std::uint8_t* action, std::uint32_t* rigid_size,
                            std::uint32_t* claim) {
    const std::uint32_t v = blockIdx.x * blockDim.x + threadIdx.x;
    if (v >= n) return;
    for (int c = 0; c < 3; ++c) x_hat[c * n + v] = x1[c * n + v];
    parent[v] = v;
    label[v] = kInvalid;
    member[v] = 0;
    outcome[v] = inverse_mass[v] == 0.0F ? kFixed : kUntouched;
    action[v] = kNone;
    rigid_size[v] = 0;
    claim[v] = kInvalid;
}

// ---- Constraints and zones ----------------------------------------------------------------------------

__device__ inline std::uint32_t first_movable(const std::uint32_t* vertex, const float* inverse_mass) {
    for (int j = 0; j < 4; ++j)
        if (inverse_mass[vertex[j]] > 0.0F) return vertex[j];
    return kInvalid;
}

/// Appends hits [0, count) as constraints first .. first + count and merges their vertices' zones.
__global__ void append_kernel(const GpuCcdHit* hits, std::uint32_t count, std::uint32_t first,
                              const float* inverse_mass, std::uint32_t* c_vertex, float* c_weight, float* c_normal,
                              double* lambda, double* momentum, std::uint32_t* parent, std::uint8_t* member) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= count) return;
    const GpuCcdHit& h = hits[i];
    const std::size_t k = first + i;
    for (int j = 0; j < 4; ++j) {
        c_vertex[4 * k + j] = h.vertex[j];
        c_weight[4 * k + j] = h.weight[j];
    }
    for (int c = 0; c < 3; ++c) c_normal[3 * k + c] = h.normal[c];
    lambda[k] = 0.0;
    momentum[k] = 0.0;
    // Vertices of inverse mass 0 never join zones together (they do not move): as the CPU.
    std::uint32_t a = kInvalid;
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = h.vertex[j];
        if (!(inverse_mass[v] > 0.0F)) continue;
        member[v] = 1;
        if (a == kInvalid)
            a = v;
        else
            unite(parent, a, v);
    }
}

__global__ void label_kernel(std::uint32_t n, const std::uint8_t* member, std::uint32_t* parent, std::uint32_t* label) {
    const std::uint32_t v = blockIdx.x * blockDim.x + threadIdx.x;
    if (v >= n || member[v] == 0) return;
    std::uint32_t r = v;
    while (parent[r] != r) r = parent[r];
    label[v] = r;
    parent[v] = r;
}

/// Incidence slots (4 per constraint): key the movable vertex (kInvalid for inverse mass 0, sorted
/// last), value the slot 4k + j. A stable sort by key then lists each vertex's constraints in order.
__global__ void slot_kernel(std::uint32_t constraints, const std::uint32_t* c_vertex, const float* inverse_mass,
                            const std::uint32_t* label, std::uint32_t* slot_key, std::uint32_t* slot_value,
                            std::uint32_t* ckey, std::uint32_t* cvalue, GpuImpactZones::Counters* counters) {
    const std::uint32_t s = blockIdx.x * blockDim.x + threadIdx.x;
    if (s >= 4 * constraints) return;
    const std::uint32_t v = c_vertex[s];
    const bool movable = inverse_mass[v] > 0.0F;
    slot_key[s] = movable ? v : kInvalid;
    slot_value[s] = s;
    if (!movable) atomicAdd(&counters->fixed_slots, 1U);
    if (s % 4 == 0) {
        // The zone of a constraint: the label of its first movable vertex (all of them share it).
        const std::uint32_t k = s / 4;
        ckey[k] = label[first_movable(c_vertex + s, inverse_mass)];
        cvalue[k] = k;
    }
}

__global__ void incidence_count_kernel(std::uint32_t unique, const std::uint32_t* unique_vertex,
                                       const std::uint32_t* unique_count, const std::uint32_t* label,
                                       std::uint32_t* incidence_count, std::uint32_t* vkey, std::uint32_t* vvalue) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= unique) return;
    const std::uint32_t v = unique_vertex[i];
    incidence_count[v] = unique_count[i];
    vkey[i] = label[v];
    vvalue[i] = i;
}

/// Per constraint, the step of the projected gradient: 1/D'_k with D'_k = Σ_j w_kj² c_j / m_j, c_j the
/// number of the zone's constraints at vertex j. D' majorises A = J M⁻¹ Jᵀ (for each vertex,
/// (Σ_k w_kj λ_k)² ≤ c_j Σ_k w_kj² λ_k², Cauchy–Schwarz), so λ ← max(0, λ − D'⁻¹ g) descends on the dual
/// and converges (Bertsekas, Nonlinear Programming, §2.3; the "mass splitting" of parallel PBD).
__global__ void scale_kernel(std::uint32_t constraints, const std::uint32_t* c_vertex, const float* c_weight,
                             const float* inverse_mass, const std::uint32_t* incidence_count, double* scale) {
    const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= constraints) return;
    double d = 0.0;
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = c_vertex[4 * k + j];
        const double im = inverse_mass[v];
        if (!(im > 0.0)) continue;
        const double w = c_weight[4 * k + j];
        d += w * w * im * incidence_count[v];
    }
    scale[k] = d > 0.0 ? 1.0 / d : 0.0;  // 0: only weight-0 movable vertices, no say (as the CPU)
}

/// Marks the zone of each constraint in [first, last) with `action`.
__global__ void mark_kernel(std::uint32_t first, std::uint32_t last, const std::uint32_t* c_vertex,
                            const float* inverse_mass, const std::uint32_t* label, const std::uint8_t* only_if,
                            std::uint8_t* action, std::uint8_t value) {
    const std::uint32_t k = first + blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= last) return;
    if (only_if != nullptr && only_if[k - first] == 0) return;
    action[label[first_movable(c_vertex + 4 * k, inverse_mass)]] = value;
}

// ---- The projection: one block per zone -------------------------------------------------------------------

struct ZoneLists {
    const std::uint32_t* zone_label;  // root per zone
    const std::uint32_t* coffset;     // zones + 1
    const std::uint32_t* cvalue;      // constraint ids, zone by zone, detection order
    const std::uint32_t* voffset;     // zones + 1
    const std::uint32_t* vvalue;      // indices into the unique vertex list, zone by zone
    const std::uint32_t* unique_vertex;
    const std::uint32_t* unique_offset;  // incidence range of each unique vertex
    const std::uint32_t* unique_count;
    const std::uint32_t* slot_value;  // sorted incidence: slot 4k + j
};

struct Constraints {
    const std::uint32_t* vertex;
    const float* weight;
    const float* normal;
    const double* scale;
    double* lambda;
    double* momentum;  // the extrapolated multipliers y at which x is evaluated
    double* previous;  // scratch: λ before the step
};

/// x_v = x̂_v + m_v⁻¹ Σ_k w_kv n_k y_k for the zone's vertices: the primal point of the multipliers y
/// (KKT: x = x̂ + M⁻¹ Jᵀ y), gathered in the fixed incidence order.
/// Items [vb, ve) from `first` in steps of `step` (a block's threads, or the whole grid's).
__device__ void gather_positions(const ZoneLists& z, const Constraints& c, std::uint32_t vb, std::uint32_t ve,
                                 const float* x_hat, const float* inverse_mass, float* x1, std::uint32_t n,
                                 std::uint32_t first, std::uint32_t step) {
    for (std::uint32_t i = vb + first; i < ve; i += step) {
        const std::uint32_t u = z.vvalue[i];
        const std::uint32_t v = z.unique_vertex[u];
        const double im = inverse_mass[v];
        double d[3] = {0.0, 0.0, 0.0};
        const std::uint32_t sb = z.unique_offset[u], se = sb + z.unique_count[u];
        for (std::uint32_t s = sb; s < se; ++s) {
            const std::uint32_t slot = z.slot_value[s];
            const std::uint32_t k = slot / 4;
            const double f = im * c.weight[slot] * c.momentum[k];
            for (int a = 0; a < 3; ++a) d[a] += f * c.normal[3 * k + a];
        }
        for (int a = 0; a < 3; ++a)
            x1[static_cast<std::size_t>(a) * n + v] = static_cast<float>(x_hat[static_cast<std::size_t>(a) * n + v] + d[a]);
    }
}

struct MaxSum {
    double max, sum;
};
struct MaxSumOp {
    __device__ MaxSum operator()(const MaxSum& a, const MaxSum& b) const { return {fmax(a.max, b.max), a.sum + b.sum}; }
};

/// One projected-gradient step of constraint k at the current x = x(y) (see project_kernel): λ⁺ into
/// lambda (λ kept in previous); adds its KKT residual to r.max and its restart term to r.sum.
__device__ inline void project_constraint(const Constraints& c, std::uint32_t k, const float* x1, std::uint32_t n,
                                          double delta, MaxSum& r) {
    const double s = c.scale[k];
    if (!(s > 0.0)) return;
    double f[3] = {0.0, 0.0, 0.0};
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = c.vertex[4 * k + j];
        const double w = c.weight[4 * k + j];
        for (int a = 0; a < 3; ++a) f[a] += w * load(x1, v, n, a);
    }
    const double g = c.normal[3 * k] * f[0] + c.normal[3 * k + 1] * f[1] + c.normal[3 * k + 2] * f[2] - delta;
    const double y = c.momentum[k], lambda = c.lambda[k];
    r.max = fmax(r.max, y > 0.0 ? fabs(g) : fmax(0.0, -g));
    const double next = fmax(0.0, y - s * g);
    r.sum += (y - next) * (next - lambda);
    c.previous[k] = lambda;
    c.lambda[k] = next;
}

/// FISTA's momentum after a step: β = 0 on a restart (the momentum points uphill), else from t.
__device__ inline double momentum_factor(double restart_term, double& t) {
    if (restart_term > 0.0) {
        t = 1.0;
        return 0.0;
    }
    const double next_t = 0.5 * (1.0 + sqrt(1.0 + 4.0 * t * t));
    const double beta = (t - 1.0) / next_t;
    t = next_t;
    return beta;
}

/// Harmon et al. 2008's inelastic projection of one zone: min ½ Σ m |x − x̂|² s.t. g_k(x) ≥ 0. Its dual,
/// min_{λ≥0} f(λ) = ½ λᵀAλ + λᵀ(Jx̂ − δ), has gradient g(x(λ)); FISTA (Beck & Teboulle 2009) with the
/// diagonal majoriser D' (scale_kernel) and the gradient restart of O'Donoghue & Candès 2015:
///   λ⁺ = max(0, y − D'⁻¹ g(x(y))),  y⁺ = max(0, λ⁺ + β (λ⁺ − λ)),  restart (β = 0) when
///   (y − λ⁺)·(λ⁺ − λ) > 0.
/// Stops on the CPU's rule, evaluated at the current point x(y): every constraint violated by at most
/// tol, every one with a multiplier tight to within tol. Warm-started from the last round's λ.
template <unsigned Threads>
__global__ void __launch_bounds__(Threads)
    project_kernel(ZoneLists z, Constraints c, const float* x_hat, const float* inverse_mass, float* x1,
                   std::uint32_t n, double delta, double tol, int max_sweeps, std::uint32_t giant,
                   std::uint32_t colored_vertices, std::uint32_t colored_constraints, std::uint8_t* action,
                   std::uint8_t* outcome, GpuImpactZones::Counters* counters) {
    using Reduce = cub::BlockReduce<MaxSum, Threads>;
    __shared__ typename Reduce::TempStorage storage;
    __shared__ MaxSum total;
    const std::uint32_t zone = blockIdx.x;
    const std::uint32_t root = z.zone_label[zone];
    if (action[root] != kProject) return;
    const std::uint32_t cb = z.coffset[zone], ce = z.coffset[zone + 1];
    // Zones of at most `colored_vertices` vertices and more than `colored_constraints` constraints
    // are the coloured Gauss–Seidel's.
    if (z.voffset[zone + 1] - z.voffset[zone] <= colored_vertices && ce - cb > colored_constraints) return;
    // Each zone is projected by the kernel of its size class (see kLargeZoneConstraints); zones of
    // more than `giant` constraints by the grid-wide kernels instead (project_giant_zone).
    if (ce - cb > giant) return;
    if ((ce - cb > kLargeZoneConstraints) != (Threads == kLargeZoneThreads)) return;
    const std::uint32_t vb = z.voffset[zone], ve = z.voffset[zone + 1];
    for (std::uint32_t i = cb + threadIdx.x; i < ce; i += blockDim.x) c.momentum[z.cvalue[i]] = c.lambda[z.cvalue[i]];
    __syncthreads();
    gather_positions(z, c, vb, ve, x_hat, inverse_mass, x1, n, threadIdx.x, blockDim.x);
    __syncthreads();
    double t = 1.0;
    int sweep = 1;
    bool converged = false;
    for (; sweep <= max_sweeps; ++sweep) {
        MaxSum mine{0.0, 0.0};
        for (std::uint32_t i = cb + threadIdx.x; i < ce; i += blockDim.x) project_constraint(c, z.cvalue[i], x1, n, delta, mine);
        const MaxSum all = Reduce(storage).Reduce(mine, MaxSumOp{});
        if (threadIdx.x == 0) total = all;
        __syncthreads();
        const MaxSum r = total;
        if (r.max <= tol) {
            // x = x(y) is the accepted point: keep its multipliers for the next round's warm start.
            for (std::uint32_t i = cb + threadIdx.x; i < ce; i += blockDim.x) c.lambda[z.cvalue[i]] = c.momentum[z.cvalue[i]];
            converged = true;
            break;
        }
        const double beta = momentum_factor(r.sum, t);
        for (std::uint32_t i = cb + threadIdx.x; i < ce; i += blockDim.x) {
            const std::uint32_t k = z.cvalue[i];
            const double l = c.lambda[k];
            c.momentum[k] = fmax(0.0, l + beta * (l - c.previous[k]));
        }
        __syncthreads();
        gather_positions(z, c, vb, ve, x_hat, inverse_mass, x1, n, threadIdx.x, blockDim.x);
        __syncthreads();
    }
    for (std::uint32_t i = vb + threadIdx.x; i < ve; i += blockDim.x) outcome[z.unique_vertex[z.vvalue[i]]] = kProjected;
    if (threadIdx.x == 0) {
        action[root] = kNone;
        const int used = converged ? sweep : max_sweeps;
        atomicAdd(&counters->sweeps, static_cast<std::uint32_t>(used));
        atomicAdd(&counters->work, static_cast<unsigned long long>(used) * (ce - cb));
        if (!converged) atomicAdd(&counters->unconverged, 1U);
    }
}

// ---- The projection of a giant zone: the whole grid ----------------------------------------------------
// One block cannot hide the latency of a zone of tens of thousands of constraints (an iteration is a
// few dependent loads per constraint), so such a zone runs the same iteration as project_kernel with
// each phase a kernel over the whole device: step (constraints; per-block partials), reduce (one
// block, fixed order: the same bits on every run), momentum, gather. The host launches them in
// batches and reads the convergence flag between batches.

constexpr unsigned kGridThreads = 256;

struct GiantState {
    double t;
    double beta;
    std::uint32_t converged;  // 1 once the residual is within tol (every later launch is a no-op)
    std::uint32_t sweeps;
};

__global__ void __launch_bounds__(kGridThreads)
    giant_step_kernel(Constraints c, const std::uint32_t* cvalue, std::uint32_t cb, std::uint32_t ce, const float* x1,
                      std::uint32_t n, double delta, const GiantState* state, MaxSum* partial) {
    using Reduce = cub::BlockReduce<MaxSum, kGridThreads>;
    __shared__ typename Reduce::TempStorage storage;
    if (state->converged != 0) return;
    MaxSum mine{0.0, 0.0};
    for (std::uint32_t i = cb + blockIdx.x * blockDim.x + threadIdx.x; i < ce; i += gridDim.x * blockDim.x)
        project_constraint(c, cvalue[i], x1, n, delta, mine);
    const MaxSum all = Reduce(storage).Reduce(mine, MaxSumOp{});
    if (threadIdx.x == 0) partial[blockIdx.x] = all;
}

__global__ void __launch_bounds__(kGridThreads)
    giant_reduce_kernel(const MaxSum* partial, unsigned blocks, double tol, GiantState* state) {
    using Reduce = cub::BlockReduce<MaxSum, kGridThreads>;
    __shared__ typename Reduce::TempStorage storage;
    if (state->converged != 0) return;
    MaxSum mine{0.0, 0.0};
    for (unsigned b = threadIdx.x; b < blocks; b += blockDim.x) mine = MaxSumOp{}(mine, partial[b]);
    const MaxSum r = Reduce(storage).Reduce(mine, MaxSumOp{});
    if (threadIdx.x != 0) return;
    ++state->sweeps;
    if (r.max <= tol) {
        state->converged = 1;
        return;
    }
    double t = state->t;
    state->beta = momentum_factor(r.sum, t);
    state->t = t;
}

__global__ void giant_momentum_kernel(Constraints c, const std::uint32_t* cvalue, std::uint32_t cb, std::uint32_t ce,
                                      const GiantState* state) {
    const bool accepted = state->converged != 0;
    const double beta = state->beta;
    for (std::uint32_t i = cb + blockIdx.x * blockDim.x + threadIdx.x; i < ce; i += gridDim.x * blockDim.x) {
        const std::uint32_t k = cvalue[i];
        const double l = c.lambda[k];
        if (accepted)
            c.lambda[k] = c.momentum[k];  // x = x(y) was accepted (idempotent once converged)
        else
            c.momentum[k] = fmax(0.0, l + beta * (l - c.previous[k]));
    }
}

__global__ void giant_gather_kernel(ZoneLists z, Constraints c, std::uint32_t vb, std::uint32_t ve, const float* x_hat,
                                    const float* inverse_mass, float* x1, std::uint32_t n, const GiantState* state) {
    if (state != nullptr && state->converged != 0) return;
    gather_positions(z, c, vb, ve, x_hat, inverse_mass, x1, n, blockIdx.x * blockDim.x + threadIdx.x,
                     gridDim.x * blockDim.x);
}

__global__ void giant_begin_kernel(Constraints c, const std::uint32_t* cvalue, std::uint32_t cb, std::uint32_t ce,
                                   GiantState* state) {
    for (std::uint32_t i = cb + blockIdx.x * blockDim.x + threadIdx.x; i < ce; i += gridDim.x * blockDim.x)
        c.momentum[cvalue[i]] = c.lambda[cvalue[i]];
    if (blockIdx.x == 0 && threadIdx.x == 0) *state = GiantState{1.0, 0.0, 0, 0};
}

__global__ void giant_end_kernel(ZoneLists z, std::uint32_t zone, std::uint8_t* action, std::uint8_t* outcome,
                                 const GiantState* state, GpuImpactZones::Counters* counters) {
    const std::uint32_t vb = z.voffset[zone], ve = z.voffset[zone + 1];
    for (std::uint32_t i = vb + blockIdx.x * blockDim.x + threadIdx.x; i < ve; i += gridDim.x * blockDim.x)
        outcome[z.unique_vertex[z.vvalue[i]]] = kProjected;
    if (blockIdx.x == 0 && threadIdx.x == 0) {
        action[z.zone_label[zone]] = kNone;
        atomicAdd(&counters->sweeps, state->sweeps);
        atomicAdd(&counters->work, static_cast<unsigned long long>(state->sweeps) * (z.coffset[zone + 1] - z.coffset[zone]));
        if (state->converged == 0) atomicAdd(&counters->unconverged, 1U);
    }
}

// ---- Fallbacks ------------------------------------------------------------------------------------------

/// Per hit of the round: has a movable vertex that is neither frozen nor carried.
__global__ void hit_free_kernel(const GpuCcdHit* hits, std::uint32_t count, const float* inverse_mass,
                                const std::uint8_t* outcome, std::uint8_t* hit_free) {
    const std::uint32_t h = blockIdx.x * blockDim.x + threadIdx.x;
    if (h >= count) return;
    std::uint8_t free = 0;
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = hits[h].vertex[j];
        if (inverse_mass[v] > 0.0F && outcome[v] != kFrozen && outcome[v] != kCarried) free = 1;
    }
    hit_free[h] = free;
}

/// Zone flags from scratch: kTouchesFixed from the constraints, kHasFrozen and kIsRigid from the
/// members' outcomes.
__global__ void flags_from_constraints_kernel(std::uint32_t constraints, const std::uint32_t* c_vertex,
                                              const float* inverse_mass, const std::uint32_t* label,
                                              std::uint32_t* flags) {
    const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= constraints) return;
    bool fixed = false;
    for (int j = 0; j < 4; ++j) fixed = fixed || !(inverse_mass[c_vertex[4 * k + j]] > 0.0F);
    if (fixed) atomicOr(flags + label[first_movable(c_vertex + 4 * k, inverse_mass)], kTouchesFixed);
}

__global__ void flags_from_vertices_kernel(std::uint32_t unique, const std::uint32_t* unique_vertex,
                                           const std::uint32_t* label, const std::uint8_t* outcome,
                                           std::uint32_t* flags) {
    const std::uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= unique) return;
    const std::uint32_t v = unique_vertex[i];
    const std::uint8_t o = outcome[v];
    if (o == kFrozen || o == kCarried) atomicOr(flags + label[v], kHasFrozen);
    if (o == kRigidOutcome) atomicOr(flags + label[v], kIsRigid);
}

/// Per pending zone: rigid while rounds are left, for zones that can move freely and grew since they
/// were last made rigid; else frozen (the CPU's rule).
__global__ void decide_kernel(std::uint32_t zones, const std::uint32_t* zone_label, const std::uint32_t* voffset,
                              const std::uint32_t* flags, std::uint32_t* rigid_size, std::uint8_t* action,
                              bool rigid_allowed, GpuImpactZones::Counters* counters) {
    const std::uint32_t z = blockIdx.x * blockDim.x + threadIdx.x;
    if (z >= zones) return;
    const std::uint32_t r = zone_label[z];
    if (action[r] != kPending) return;
    const std::uint32_t size = voffset[z + 1] - voffset[z];
    const bool repeat = rigid_size[r] == size;  // sets only grow: same root, same size, same set
    if (rigid_allowed && (flags[r] & (kTouchesFixed | kHasFrozen)) == 0 && !repeat) {
        action[r] = kRigid;
        rigid_size[r] = size;
        atomicOr(&counters->any_rigid, 1U);
    } else {
        action[r] = kFreeze;
    }
    atomicOr(&counters->progress, 1U);
}

/// Bridson et al. 2002 §7.4, as the CPU's rigid_zone: the zone moves as one rigid body with the
/// linear and angular momentum of its displacement d = x1 − x0 (h cancels), about its centre of
/// mass at x0; ω = I⁻¹L by the pseudo-inverse; x1 = x0 + v + (R(ω) − 1) r. Reductions in double.
/// Frozen zones (kFreeze) go back to x0, except vertices already carried.
__global__ void __launch_bounds__(kZoneThreads)
    rigid_freeze_kernel(ZoneLists z, const float* x0, float* x1, const float* inverse_mass, std::uint32_t n,
                        std::uint8_t* action, std::uint8_t* outcome) {
    using Reduce = cub::BlockReduce<double, kZoneThreads>;
    __shared__ typename Reduce::TempStorage storage;
    __shared__ double shared[10];
    const std::uint32_t zone = blockIdx.x;
    const std::uint32_t root = z.zone_label[zone];
    const std::uint8_t act = action[root];
    if (act != kRigid && act != kFreeze) return;
    const std::uint32_t vb = z.voffset[zone], ve = z.voffset[zone + 1];
    const auto vertex = [&](std::uint32_t i) { return z.unique_vertex[z.vvalue[i]]; };
    if (act == kFreeze) {
        for (std::uint32_t i = vb + threadIdx.x; i < ve; i += blockDim.x) {
            const std::uint32_t v = vertex(i);
            if (outcome[v] == kCarried) continue;
            for (int a = 0; a < 3; ++a) x1[static_cast<std::size_t>(a) * n + v] = load(x0, v, n, a);
            outcome[v] = kFrozen;
        }
        return;
    }
    // Pass 1: mass, first moment at x0, momentum of the displacement (7 sums).
    double part[7] = {};
    for (std::uint32_t i = vb + threadIdx.x; i < ve; i += blockDim.x) {
        const std::uint32_t v = vertex(i);
        const double m = 1.0 / inverse_mass[v];
        part[0] += m;
        for (int a = 0; a < 3; ++a) {
            const double p0 = load(x0, v, n, a);
            part[1 + a] += m * p0;
            part[4 + a] += m * (static_cast<double>(load(x1, v, n, a)) - p0);
        }
    }
    for (int q = 0; q < 7; ++q) {
        const double s = Reduce(storage).Sum(part[q]);
        if (threadIdx.x == 0) shared[q] = s;
        __syncthreads();
    }
    const double mass = shared[0];
    const double centre[3] = {shared[1] / mass, shared[2] / mass, shared[3] / mass};
    const double velocity[3] = {shared[4] / mass, shared[5] / mass, shared[6] / mass};
    __syncthreads();
    // Pass 2: angular momentum L = Σ m r × d and inertia I = Σ m (|r|² 1 − r rᵀ) (9 sums).
    double second[9] = {};
    for (std::uint32_t i = vb + threadIdx.x; i < ve; i += blockDim.x) {
        const std::uint32_t v = vertex(i);
        const double m = 1.0 / inverse_mass[v];
        double r[3], d[3];
        for (int a = 0; a < 3; ++a) {
            const double p0 = load(x0, v, n, a);
            r[a] = p0 - centre[a];
            d[a] = static_cast<double>(load(x1, v, n, a)) - p0;
        }
        second[0] += m * (r[1] * d[2] - r[2] * d[1]);
        second[1] += m * (r[2] * d[0] - r[0] * d[2]);
        second[2] += m * (r[0] * d[1] - r[1] * d[0]);
        const double rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        second[3] += m * (rr - r[0] * r[0]);
        second[4] += m * (rr - r[1] * r[1]);
        second[5] += m * (rr - r[2] * r[2]);
        second[6] += m * (-r[0] * r[1]);
        second[7] += m * (-r[0] * r[2]);
        second[8] += m * (-r[1] * r[2]);
    }
    __shared__ double sums[9];
    for (int q = 0; q < 9; ++q) {
        const double s = Reduce(storage).Sum(second[q]);
        if (threadIdx.x == 0) sums[q] = s;
        __syncthreads();
    }
    __shared__ double omega_shared[3];
    if (threadIdx.x == 0) {
        double inertia[3][3] = {{sums[3], sums[6], sums[7]}, {sums[6], sums[4], sums[8]}, {sums[7], sums[8], sums[5]}};
        double eval[3], evec[3][3];
        physics::eigen_sym<3>(inertia, eval, evec);
        const double largest = fmax(eval[0], fmax(eval[1], eval[2]));
        double omega[3] = {0.0, 0.0, 0.0};
        for (int k = 0; k < 3; ++k) {
            if (!(largest > 0.0) || !(eval[k] > kInertiaCutoff * largest)) continue;
            const double along = (evec[0][k] * sums[0] + evec[1][k] * sums[1] + evec[2][k] * sums[2]) / eval[k];
            for (int a = 0; a < 3; ++a) omega[a] += along * evec[a][k];
        }
        for (int a = 0; a < 3; ++a) omega_shared[a] = omega[a];
    }
    __syncthreads();
    const double angle = sqrt(omega_shared[0] * omega_shared[0] + omega_shared[1] * omega_shared[1] +
                              omega_shared[2] * omega_shared[2]);
    double axis[3] = {0.0, 0.0, 0.0};
    if (angle > 0.0)
        for (int a = 0; a < 3; ++a) axis[a] = omega_shared[a] / angle;
    const double cs = cos(angle), sn = sin(angle);
    for (std::uint32_t i = vb + threadIdx.x; i < ve; i += blockDim.x) {
        const std::uint32_t v = vertex(i);
        double p0[3], r[3];
        for (int a = 0; a < 3; ++a) {
            p0[a] = load(x0, v, n, a);
            r[a] = p0[a] - centre[a];
        }
        const double kr = axis[0] * r[0] + axis[1] * r[1] + axis[2] * r[2];
        const double kx[3] = {axis[1] * r[2] - axis[2] * r[1], axis[2] * r[0] - axis[0] * r[2],
                              axis[0] * r[1] - axis[1] * r[0]};
        for (int a = 0; a < 3; ++a) {
            // Rodrigues, R r − r written out (a small turn is not lost against the position).
            const double turn = (cs - 1.0) * r[a] + sn * kx[a] + (1.0 - cs) * kr * axis[a];
            x1[static_cast<std::size_t>(a) * n + v] = static_cast<float>(p0[a] + (velocity[a] + turn));
        }
        outcome[v] = kRigidOutcome;
    }
}

/// Kinematic geometry driving into frozen cloth (hits with no free vertex): the frozen vertices of the
/// hit move with the kinematic or carried points of the pair, weighted by |w|. The first hit in
/// detection order claims a vertex (atomicMin); the displacement is stored for the apply pass.
__global__ void carry_claim_kernel(const GpuCcdHit* hits, std::uint32_t count, const std::uint8_t* hit_free,
                                   const float* x0, const float* x1, const float* inverse_mass, std::uint32_t n,
                                   const std::uint8_t* outcome, std::uint32_t* claim, float* carry) {
    const std::uint32_t h = blockIdx.x * blockDim.x + threadIdx.x;
    if (h >= count || hit_free[h] != 0) return;
    double weight = 0.0, d[3] = {0.0, 0.0, 0.0};
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = hits[h].vertex[j];
        if (inverse_mass[v] > 0.0F && outcome[v] != kCarried) continue;
        const double w = fabs(static_cast<double>(hits[h].weight[j]));
        weight += w;
        for (int a = 0; a < 3; ++a) d[a] += w * (static_cast<double>(load(x1, v, n, a)) - load(x0, v, n, a));
    }
    if (!(weight > 0.0)) {
        carry[3 * h] = NAN;  // nothing drives: no carry
        return;
    }
    for (int a = 0; a < 3; ++a) carry[3 * h + a] = static_cast<float>(d[a] / weight);
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = hits[h].vertex[j];
        if (inverse_mass[v] > 0.0F && outcome[v] == kFrozen) atomicMin(claim + v, h);
    }
}

__global__ void carry_apply_kernel(const GpuCcdHit* hits, std::uint32_t count, const std::uint8_t* hit_free,
                                   const float* x0, float* x1, std::uint32_t n, std::uint32_t* claim,
                                   const float* carry, std::uint8_t* outcome, GpuImpactZones::Counters* counters) {
    const std::uint32_t h = blockIdx.x * blockDim.x + threadIdx.x;
    if (h >= count || hit_free[h] != 0 || isnan(carry[3 * h])) return;
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t v = hits[h].vertex[j];
        if (claim[v] != h) continue;
        for (int a = 0; a < 3; ++a) x1[static_cast<std::size_t>(a) * n + v] = load(x0, v, n, a) + carry[3 * h + a];
        outcome[v] = kCarried;
        atomicOr(&counters->progress, 1U);
    }
}

__global__ void claim_reset_kernel(const GpuCcdHit* hits, std::uint32_t count, std::uint32_t* claim) {
    const std::uint32_t h = blockIdx.x * blockDim.x + threadIdx.x;
    if (h >= count) return;
    for (int j = 0; j < 4; ++j) claim[hits[h].vertex[j]] = kInvalid;
}

// ---- Final figures --------------------------------------------------------------------------------------

__global__ void final_vertices_kernel(std::uint32_t n, const std::uint8_t* outcome, GpuImpactZones::Counters* counters) {
    const std::uint32_t v = blockIdx.x * blockDim.x + threadIdx.x;
    if (v >= n) return;
    if (outcome[v] == kFrozen) atomicAdd(&counters->frozen, 1U);
    if (outcome[v] == kCarried) atomicAdd(&counters->carried, 1U);
}

__global__ void final_zones_kernel(std::uint32_t zones, const std::uint32_t* zone_label, const std::uint32_t* voffset,
                                   const std::uint32_t* flags, GpuImpactZones::Counters* counters) {
    const std::uint32_t z = blockIdx.x * blockDim.x + threadIdx.x;
    if (z >= zones) return;
    atomicMax(&counters->max_zone_vertices, voffset[z + 1] - voffset[z]);
    const std::uint32_t f = flags[zone_label[z]];
    if ((f & kIsRigid) != 0 && (f & kHasFrozen) == 0) atomicAdd(&counters->rigid_zones, 1U);
}

}  // namespace

GpuImpactZones::GpuImpactZones() { counters_host_.allocate(1); }
GpuImpactZones::~GpuImpactZones() = default;

std::size_t GpuImpactZones::memory_bytes() const {
    std::size_t b = broad_.memory_bytes() + ccd_.memory_bytes();
    b += x_hat_.bytes() + parent_.bytes() + label_.bytes() + incidence_count_.bytes() + flags_.bytes() +
         rigid_size_.bytes() + claim_.bytes() + member_.bytes() + outcome_.bytes() + action_.bytes();
    b += c_vertex_.bytes() + c_weight_.bytes() + c_normal_.bytes() + c_scale_.bytes() + lambda_.bytes() +
         momentum_.bytes() + previous_.bytes();
    for (int i = 0; i < 2; ++i)
        b += slot_key_[i].bytes() + slot_value_[i].bytes() + ckey_[i].bytes() + cvalue_[i].bytes() + vkey_[i].bytes() +
             vvalue_[i].bytes();
    b += unique_vertex_.bytes() + unique_count_.bytes() + unique_offset_.bytes() + zone_label_.bytes() +
         zone_ccount_.bytes() + zone_coffset_.bytes() + zone_label2_.bytes() + zone_vcount_.bytes() +
         zone_voffset_.bytes() + hit_free_.bytes() + carry_.bytes() + temp_.bytes() + counters_.bytes() +
         giant_scratch_.bytes();
    b += zone_slot_.bytes() + color_claim_.bytes() + color_.bytes() + color_order_.bytes() + color_start_.bytes() +
         packed_slot_.bytes() + packed_weight_.bytes() + packed_move_.bytes() + packed_normal_.bytes() +
         packed_offset_.bytes() + packed_inverse_diagonal_.bytes() + packed_lambda_.bytes();
    return b;
}

void GpuImpactZones::reserve_vertices(std::uint32_t count) {
    if (vertices_ >= count && x_hat_.size() > 0) return;
    vertices_ = std::max<std::uint32_t>(count, 1);
    grow(x_hat_, 3 * static_cast<std::size_t>(vertices_));
    for (DeviceArray<std::uint32_t>* a :
         {&parent_, &label_, &incidence_count_, &flags_, &rigid_size_, &claim_, &zone_slot_, &color_claim_})
        grow(*a, vertices_);
    for (DeviceArray<std::uint8_t>* a : {&member_, &outcome_, &action_}) grow(*a, vertices_);
    grow(counters_, 1);
}

void GpuImpactZones::release_constraints() {
    for (DeviceArray<std::uint32_t>* a : {&c_vertex_, &unique_vertex_, &unique_count_, &unique_offset_, &zone_label_,
                                          &zone_ccount_, &zone_coffset_, &zone_label2_, &zone_vcount_, &zone_voffset_,
                                          &color_, &color_order_, &color_start_})
        *a = {};
    for (DeviceArray<float>* a : {&c_weight_, &c_normal_}) *a = {};
    for (DeviceArray<double>* a : {&c_scale_, &lambda_, &momentum_, &previous_, &packed_offset_,
                                   &packed_inverse_diagonal_, &packed_lambda_})
        *a = {};
    for (DeviceArray<float4>* a : {&packed_weight_, &packed_move_, &packed_normal_}) *a = {};
    packed_slot_ = {};
    for (int i = 0; i < 2; ++i)
        for (DeviceArray<std::uint32_t>* a : {&slot_key_[i], &slot_value_[i], &ckey_[i], &cvalue_[i], &vkey_[i], &vvalue_[i]})
            *a = {};
    capacity_ = 0;
}

void GpuImpactZones::reserve_constraints(std::size_t count, cudaStream_t stream) {
    if (count <= capacity_) return;
    const std::size_t cap = grown_capacity(count);
    const std::size_t keep = constraints_;
    grow_keeping(c_vertex_, 4 * cap, 4 * keep, stream);
    grow_keeping(c_weight_, 4 * cap, 4 * keep, stream);
    grow_keeping(c_normal_, 3 * cap, 3 * keep, stream);
    grow_keeping(lambda_, cap, keep, stream);
    grow_keeping(momentum_, cap, keep, stream);
    grow(previous_, cap);
    grow(c_scale_, cap);
    grow(color_, cap);
    grow(color_order_, cap);
    grow(color_start_, 2 * cap + 1);  // a zone's colours are at most its constraints, plus one end each
    grow(packed_slot_, cap);
    for (DeviceArray<float4>* a : {&packed_weight_, &packed_move_, &packed_normal_}) grow(*a, cap);
    for (DeviceArray<double>* a : {&packed_offset_, &packed_inverse_diagonal_, &packed_lambda_}) grow(*a, cap);
    for (int i = 0; i < 2; ++i) {
        grow(slot_key_[i], 4 * cap);
        grow(slot_value_[i], 4 * cap);
        grow(ckey_[i], cap);
        grow(cvalue_[i], cap);
        grow(vkey_[i], 4 * cap);
        grow(vvalue_[i], 4 * cap);
    }
    grow(unique_vertex_, 4 * cap);
    grow(unique_count_, 4 * cap);
    grow(unique_offset_, 4 * cap + 1);
    grow(zone_label_, cap);
    grow(zone_ccount_, cap);
    grow(zone_coffset_, cap + 1);
    grow(zone_label2_, 4 * cap);
    grow(zone_vcount_, 4 * cap);
    grow(zone_voffset_, 4 * cap + 1);
    capacity_ = cap;
}

const GpuImpactZones::Counters& GpuImpactZones::read_counters(cudaStream_t stream) {
    WEFT_CUDA_CHECK(cudaMemcpyAsync(counters_host_.get(), counters_.get(), sizeof(Counters), cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    return *counters_host_.get();
}

std::uint32_t GpuImpactZones::detect(const GpuImpactZoneInput& in, weft::collision::ImpactZoneReport& report,
                                     cudaStream_t stream) {
    auto clock = Clock::now();
    GpuBroadPhaseInput bp;
    bp.x0 = in.x0;
    bp.x1 = in.x1;
    bp.vertex_count = in.vertex_count;
    bp.triangles = in.triangles;
    bp.triangle_count = in.triangle_count;
    bp.edges = in.edges;
    bp.edge_count = in.edge_count;
    bp.triangle_cloth = in.triangle_group;
    bp.self_pairs = in.self_pairs;
    // Bounds grown by eta pair every primitive CCD could report at eta (as the CPU's detect).
    bp.thickness = report.eta;
    if (in.refresh_broad_phase) in.refresh_broad_phase(report.detections, bp);
    const GpuBroadPhaseCounters& bc = broad_.find(bp, stream);
    ++report.detections;
    report.candidate_pairs += bc.pairs;
    report.broad_phase_ms += ms_since(clock);

    clock = Clock::now();
    GpuCcdInput cin;
    cin.x0 = in.x0;
    cin.x1 = in.x1;
    cin.vertex_count = in.vertex_count;
    cin.inverse_mass = in.inverse_mass;
    cin.triangles = in.triangles;
    cin.edges = in.edges;
    cin.eta = float_at_least(report.eta);
    cin.clamp_to_start_distance = true;
    if (in.ccd_time_tolerance > 0.0) cin.t_tolerance = static_cast<float>(in.ccd_time_tolerance);
    const GpuCcdCounters& cc = ccd_.find(cin, broad_.pairs(), stream);
    report.ccd_tests += cc.tests;
    report.ccd_hits += cc.hits;
    report.ccd_ms += ms_since(clock);
    return cc.hits;
}

void GpuImpactZones::add_hits(const GpuImpactZoneInput& in, std::uint32_t hits, cudaStream_t stream) {
    const std::uint32_t first = constraints_;
    const std::uint32_t total = first + hits;
    reserve_constraints(total, stream);
    const std::uint32_t n = in.vertex_count;
    WEFT_CUDA_CHECK(cudaMemsetAsync(counters_.get(), 0, sizeof(Counters), stream));
    append_kernel<<<blocks_for(hits, kThreads), kThreads, 0, stream>>>(
        ccd_.hits(), hits, first, in.inverse_mass, c_vertex_.get(), c_weight_.get(), c_normal_.get(), lambda_.get(),
        momentum_.get(), parent_.get(), member_.get());
    WEFT_CUDA_CHECK_LAUNCH("impact zones: append");
    label_kernel<<<blocks_for(n, kThreads), kThreads, 0, stream>>>(n, member_.get(), parent_.get(), label_.get());
    WEFT_CUDA_CHECK_LAUNCH("impact zones: label");
    constraints_ = total;
    const std::uint32_t slots = 4 * total;
    slot_kernel<<<blocks_for(slots, kThreads), kThreads, 0, stream>>>(
        total, c_vertex_.get(), in.inverse_mass, label_.get(), slot_key_[0].get(), slot_value_[0].get(), ckey_[0].get(),
        cvalue_[0].get(), counters_.get());
    WEFT_CUDA_CHECK_LAUNCH("impact zones: slots");

    // Scratch for CUB: the largest of the calls below.
    cub::DoubleBuffer<std::uint32_t> sk(slot_key_[0].get(), slot_key_[1].get());
    cub::DoubleBuffer<std::uint32_t> sv(slot_value_[0].get(), slot_value_[1].get());
    cub::DoubleBuffer<std::uint32_t> ck(ckey_[0].get(), ckey_[1].get());
    cub::DoubleBuffer<std::uint32_t> cv(cvalue_[0].get(), cvalue_[1].get());
    std::size_t need = 0, bytes = 0;
    const auto take = [&](cudaError_t e) {
        WEFT_CUDA_CHECK(e);
        need = std::max(need, bytes);
    };
    // Key bits: vertex ids and labels are < n (kInvalid sorts last with all 32 bits).
    take(cub::DeviceRadixSort::SortPairs(nullptr, bytes, sk, sv, slots, 0, 32));
    take(cub::DeviceRadixSort::SortPairs(nullptr, bytes, ck, cv, total, 0, 32));
    take(cub::DeviceRunLengthEncode::Encode(nullptr, bytes, sk.Current(), unique_vertex_.get(), unique_count_.get(),
                                            &counters_.get()->incidence_runs, slots));
    take(cub::DeviceRunLengthEncode::Encode(nullptr, bytes, ck.Current(), zone_label_.get(), zone_ccount_.get(),
                                            &counters_.get()->zones, total));
    take(cub::DeviceScan::InclusiveSum(nullptr, bytes, unique_count_.get(), unique_offset_.get() + 1, slots));
    take(cub::DeviceRadixSort::SortPairs(nullptr, bytes, ck, cv, slots, 0, 32));
    if (temp_.size() < need) grow(temp_, need + need / 4);
    void* temp = temp_.get();
    std::size_t temp_bytes = temp_.size();

    WEFT_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(temp, temp_bytes, sk, sv, slots, 0, 32, stream));
    WEFT_CUDA_CHECK(cub::DeviceRunLengthEncode::Encode(temp, temp_bytes, sk.Current(), unique_vertex_.get(),
                                                       unique_count_.get(), &counters_.get()->incidence_runs, slots,
                                                       stream));
    WEFT_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(temp, temp_bytes, ck, cv, total, 0, 32, stream));
    WEFT_CUDA_CHECK(cub::DeviceRunLengthEncode::Encode(temp, temp_bytes, ck.Current(), zone_label_.get(),
                                                       zone_ccount_.get(), &counters_.get()->zones, total, stream));
    const Counters& c = read_counters(stream);
    unique_ = c.incidence_runs - (c.fixed_slots > 0 ? 1U : 0U);
    zones_ = c.zones;
    slot_sorted_ = sv.Current();
    cvalue_sorted_ = cv.Current();

    WEFT_CUDA_CHECK(cudaMemsetAsync(unique_offset_.get(), 0, sizeof(std::uint32_t), stream));
    WEFT_CUDA_CHECK(cub::DeviceScan::InclusiveSum(temp, temp_bytes, unique_count_.get(), unique_offset_.get() + 1,
                                                  unique_, stream));
    WEFT_CUDA_CHECK(cudaMemsetAsync(zone_coffset_.get(), 0, sizeof(std::uint32_t), stream));
    WEFT_CUDA_CHECK(cub::DeviceScan::InclusiveSum(temp, temp_bytes, zone_ccount_.get(), zone_coffset_.get() + 1,
                                                  zones_, stream));
    incidence_count_kernel<<<blocks_for(unique_, kThreads), kThreads, 0, stream>>>(
        unique_, unique_vertex_.get(), unique_count_.get(), label_.get(), incidence_count_.get(), vkey_[0].get(),
        vvalue_[0].get());
    WEFT_CUDA_CHECK_LAUNCH("impact zones: incidence");
    cub::DoubleBuffer<std::uint32_t> vk(vkey_[0].get(), vkey_[1].get());
    cub::DoubleBuffer<std::uint32_t> vv(vvalue_[0].get(), vvalue_[1].get());
    WEFT_CUDA_CHECK(cub::DeviceRadixSort::SortPairs(temp, temp_bytes, vk, vv, unique_, 0, 32, stream));
    WEFT_CUDA_CHECK(cub::DeviceRunLengthEncode::Encode(temp, temp_bytes, vk.Current(), zone_label2_.get(),
                                                       zone_vcount_.get(), &counters_.get()->zone_vertex_runs, unique_,
                                                       stream));
    WEFT_CUDA_CHECK(cudaMemsetAsync(zone_voffset_.get(), 0, sizeof(std::uint32_t), stream));
    WEFT_CUDA_CHECK(cub::DeviceScan::InclusiveSum(temp, temp_bytes, zone_vcount_.get(), zone_voffset_.get() + 1,
                                                  zones_, stream));
    vvalue_sorted_ = vv.Current();
    scale_kernel<<<blocks_for(total, kThreads), kThreads, 0, stream>>>(
        total, c_vertex_.get(), c_weight_.get(), in.inverse_mass, incidence_count_.get(), c_scale_.get());
    WEFT_CUDA_CHECK_LAUNCH("impact zones: scale");
}

namespace {

ZoneLists zone_lists(const DeviceArray<std::uint32_t>& zone_label, const DeviceArray<std::uint32_t>& coffset,
                     const std::uint32_t* cvalue, const DeviceArray<std::uint32_t>& voffset, const std::uint32_t* vvalue,
                     const DeviceArray<std::uint32_t>& unique_vertex, const DeviceArray<std::uint32_t>& unique_offset,
                     const DeviceArray<std::uint32_t>& unique_count, const std::uint32_t* slot_value) {
    return {zone_label.get(),    coffset.get(),       cvalue, voffset.get(), vvalue, unique_vertex.get(),
            unique_offset.get(), unique_count.get(), slot_value};
}

}  // namespace

ColoredZoneProjection GpuImpactZones::colored_projection(const GpuImpactZoneInput& in) {
    ColoredZoneProjection p;
    p.zone_label = zone_label_.get();
    p.coffset = zone_coffset_.get();
    p.cvalue = cvalue_sorted_;
    p.voffset = zone_voffset_.get();
    p.vvalue = vvalue_sorted_;
    p.unique_vertex = unique_vertex_.get();
    p.vertex = c_vertex_.get();
    p.weight = c_weight_.get();
    p.normal = c_normal_.get();
    p.lambda = lambda_.get();
    p.x_hat = x_hat_.get();
    p.inverse_mass = in.inverse_mass;
    p.x1 = in.x1;
    p.n = in.vertex_count;
    p.action = action_.get();
    p.outcome = outcome_.get();
    p.project_code = kProject;
    p.done_code = kNone;
    p.projected_code = kProjected;
    p.sweeps = &counters_.get()->sweeps;
    p.unconverged = &counters_.get()->unconverged;
    p.work = &counters_.get()->work;
    p.zone_slot = zone_slot_.get();
    p.claim = color_claim_.get();
    p.color = color_.get();
    p.color_order = color_order_.get();
    p.color_start = color_start_.get();
    p.packed_slot = packed_slot_.get();
    p.packed_weight = packed_weight_.get();
    p.packed_move = packed_move_.get();
    p.packed_normal = packed_normal_.get();
    p.packed_offset = packed_offset_.get();
    p.packed_inverse_diagonal = packed_inverse_diagonal_.get();
    p.packed_lambda = packed_lambda_.get();
    return p;
}

void GpuImpactZones::project_giant_zones(const GpuImpactZoneInput& in, double tol, int max_sweeps, cudaStream_t stream) {
    // No zone can be giant while all the constraints together are not: no read-back in that case.
    if (constraints_ <= in.giant_zone_constraints) return;
    // The zones' sizes and roots on the host (one copy each; zones are few next to vertices).
    host_coffset_.resize(zones_ + 1);
    WEFT_CUDA_CHECK(cudaMemcpyAsync(host_coffset_.data(), zone_coffset_.get(), (zones_ + 1) * sizeof(std::uint32_t),
                                    cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    host_voffset_.resize(zones_ + 1);
    WEFT_CUDA_CHECK(cudaMemcpyAsync(host_voffset_.data(), zone_voffset_.get(), (zones_ + 1) * sizeof(std::uint32_t),
                                    cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    std::vector<std::uint32_t> giant;
    for (std::uint32_t z = 0; z < zones_; ++z)
        if (host_coffset_[z + 1] - host_coffset_[z] > in.giant_zone_constraints &&
            (host_voffset_[z + 1] - host_voffset_[z] > in.colored_zone_vertices ||
             host_coffset_[z + 1] - host_coffset_[z] <= in.colored_zone_constraints))  // not the coloured projection's
            giant.push_back(z);
    if (giant.empty()) return;
    host_label_.resize(zones_);
    WEFT_CUDA_CHECK(cudaMemcpyAsync(host_label_.data(), zone_label_.get(), zones_ * sizeof(std::uint32_t),
                                    cudaMemcpyDeviceToHost, stream));
    std::vector<std::uint8_t> dirty(giant.size());
    for (std::size_t i = 0; i < giant.size(); ++i)
        WEFT_CUDA_CHECK(cudaMemcpyAsync(&dirty[i], action_.get() + host_label_[giant[i]], 1, cudaMemcpyDeviceToHost,
                                        stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    if (multiprocessors_ == 0) {
        int device = 0;
        WEFT_CUDA_CHECK(cudaGetDevice(&device));
        WEFT_CUDA_CHECK(cudaDeviceGetAttribute(&multiprocessors_, cudaDevAttrMultiProcessorCount, device));
    }
    const unsigned max_blocks = 4U * static_cast<unsigned>(std::max(multiprocessors_, 1));
    grow(giant_scratch_, 4 + 2 * static_cast<std::size_t>(max_blocks));
    if (giant_flag_.size() == 0) giant_flag_.allocate(1);
    auto* state = reinterpret_cast<GiantState*>(giant_scratch_.get());
    auto* partial = reinterpret_cast<MaxSum*>(giant_scratch_.get() + 4);
    static_assert(sizeof(GiantState) <= 4 * sizeof(double) && sizeof(MaxSum) == 2 * sizeof(double));
    const ZoneLists zl = zone_lists(zone_label_, zone_coffset_, cvalue_sorted_, zone_voffset_, vvalue_sorted_,
                                    unique_vertex_, unique_offset_, unique_count_, slot_sorted_);
    const Constraints c{c_vertex_.get(), c_weight_.get(), c_normal_.get(), c_scale_.get(),
                        lambda_.get(),   momentum_.get(), previous_.get()};
    const std::uint32_t n = in.vertex_count;
    constexpr int kBatch = 16;  // iterations between two reads of the convergence flag
    for (std::size_t i = 0; i < giant.size(); ++i) {
        if (dirty[i] != kProject) continue;
        const std::uint32_t z = giant[i];
        const std::uint32_t cb = host_coffset_[z], ce = host_coffset_[z + 1];
        const std::uint32_t vb = host_voffset_[z], ve = host_voffset_[z + 1];
        const unsigned cblocks = std::min(blocks_for(ce - cb, kGridThreads), max_blocks);
        const unsigned vblocks = std::min(blocks_for(ve - vb, kGridThreads), max_blocks);
        giant_begin_kernel<<<cblocks, kGridThreads, 0, stream>>>(c, cvalue_sorted_, cb, ce, state);
        giant_gather_kernel<<<vblocks, kGridThreads, 0, stream>>>(zl, c, vb, ve, x_hat_.get(), in.inverse_mass, in.x1,
                                                                  n, nullptr);
        WEFT_CUDA_CHECK_LAUNCH("impact zones: giant zone set-up");
        for (int done = 0; done < max_sweeps;) {
            const int batch = std::min(kBatch, max_sweeps - done);
            for (int b = 0; b < batch; ++b) {
                giant_step_kernel<<<cblocks, kGridThreads, 0, stream>>>(c, cvalue_sorted_, cb, ce, in.x1, n,
                                                                        in.thickness, state, partial);
                giant_reduce_kernel<<<1, kGridThreads, 0, stream>>>(partial, cblocks, tol, state);
                giant_momentum_kernel<<<cblocks, kGridThreads, 0, stream>>>(c, cvalue_sorted_, cb, ce, state);
                giant_gather_kernel<<<vblocks, kGridThreads, 0, stream>>>(zl, c, vb, ve, x_hat_.get(), in.inverse_mass,
                                                                          in.x1, n, state);
            }
            WEFT_CUDA_CHECK_LAUNCH("impact zones: giant zone iteration");
            done += batch;
            WEFT_CUDA_CHECK(cudaMemcpyAsync(giant_flag_.get(), &state->converged, sizeof(std::uint32_t),
                                            cudaMemcpyDeviceToHost, stream));
            WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
            if (giant_flag_[0] != 0) break;
        }
        giant_end_kernel<<<vblocks, kGridThreads, 0, stream>>>(zl, z, action_.get(), outcome_.get(), state,
                                                               counters_.get());
        WEFT_CUDA_CHECK_LAUNCH("impact zones: giant zone end");
    }
}

namespace {

/// Each vertex's broad-phase group (its cloth), from its triangles' (zero where none is given).
__global__ void vertex_group_kernel(const std::uint32_t* triangles, const std::uint32_t* triangle_group,
                                    std::uint32_t triangle_count, std::uint32_t* vertex_group) {
    const std::uint32_t t = blockIdx.x * blockDim.x + threadIdx.x;
    if (t >= triangle_count) return;
    for (int j = 0; j < 3; ++j) vertex_group[triangles[3 * t + j]] = triangle_group[t];  // one value a vertex
}

/// Flags the groups of the vertices of the round's hits (group ids are below the triangle count:
/// every group has a triangle).
__global__ void hit_groups_kernel(const GpuCcdHit* hits, std::uint32_t count, const std::uint32_t* vertex_group,
                                  std::uint32_t groups, std::uint8_t* hit_group) {
    const std::uint32_t h = blockIdx.x * blockDim.x + threadIdx.x;
    if (h >= count) return;
    for (int j = 0; j < 4; ++j) {
        const std::uint32_t g = vertex_group[hits[h].vertex[j]];
        if (g < groups) hit_group[g] = 1;
    }
}

/// The last fallback before the round cap: every movable vertex of a flagged group, not frozen or
/// carried, is held at x0.
__global__ void freeze_all_kernel(std::uint32_t n, const float* inverse_mass, const std::uint32_t* vertex_group,
                                  std::uint32_t groups, const std::uint8_t* hit_group, const float* x0, float* x1,
                                  std::uint8_t* outcome, GpuImpactZones::Counters* counters) {
    const std::uint32_t v = blockIdx.x * blockDim.x + threadIdx.x;
    if (v >= n || !(inverse_mass[v] > 0.0F) || outcome[v] == kFrozen || outcome[v] == kCarried) return;
    if (vertex_group[v] >= groups || hit_group[vertex_group[v]] == 0) return;
    for (int a = 0; a < 3; ++a) x1[static_cast<std::size_t>(a) * n + v] = load(x0, v, n, a);
    outcome[v] = kFrozen;
    counters->progress = 1;
}

}  // namespace

void GpuImpactZones::fallbacks(const GpuImpactZoneInput& in, std::uint32_t hits,
                               weft::collision::ImpactZoneReport& report, cudaStream_t stream) {
    const std::uint32_t n = in.vertex_count;
    for (int round = 0; round < weft::collision::kImpactZoneMaxFallbackRounds; ++round) {
        const auto clock = Clock::now();
        grow(hit_free_, hits);
        grow(carry_, 3 * static_cast<std::size_t>(hits));
        // Before the hits join: which of them still have a vertex the zones can move.
        hit_free_kernel<<<blocks_for(hits, kThreads), kThreads, 0, stream>>>(ccd_.hits(), hits, in.inverse_mass,
                                                                             outcome_.get(), hit_free_.get());
        WEFT_CUDA_CHECK_LAUNCH("impact zones: hit_free");
        const std::uint32_t first_new = constraints_;
        add_hits(in, hits, stream);  // colliding zones merge
        const ZoneLists z = zone_lists(zone_label_, zone_coffset_, cvalue_sorted_, zone_voffset_, vvalue_sorted_,
                                       unique_vertex_, unique_offset_, unique_count_, slot_sorted_);
        WEFT_CUDA_CHECK(cudaMemsetAsync(flags_.get(), 0, n * sizeof(std::uint32_t), stream));
        flags_from_constraints_kernel<<<blocks_for(constraints_, kThreads), kThreads, 0, stream>>>(
            constraints_, c_vertex_.get(), in.inverse_mass, label_.get(), flags_.get());
        flags_from_vertices_kernel<<<blocks_for(unique_, kThreads), kThreads, 0, stream>>>(
            unique_, unique_vertex_.get(), label_.get(), outcome_.get(), flags_.get());
        mark_kernel<<<blocks_for(hits, kThreads), kThreads, 0, stream>>>(first_new, constraints_, c_vertex_.get(),
                                                                         in.inverse_mass, label_.get(), hit_free_.get(),
                                                                         action_.get(), kPending);
        decide_kernel<<<blocks_for(zones_, kThreads), kThreads, 0, stream>>>(
            zones_, zone_label_.get(), zone_voffset_.get(), flags_.get(), rigid_size_.get(), action_.get(),
            round < in.max_rigid_rounds, counters_.get());
        WEFT_CUDA_CHECK_LAUNCH("impact zones: decide");
        rigid_freeze_kernel<<<zones_, kZoneThreads, 0, stream>>>(z, in.x0, in.x1, in.inverse_mass, n, action_.get(),
                                                                 outcome_.get());
        WEFT_CUDA_CHECK_LAUNCH("impact zones: rigid/freeze");
        if (round == in.max_rigid_rounds + weft::collision::kImpactZoneFreezeRounds) {
            // Whole cloths at x0 at once (kImpactZoneFreezeRounds), after the zones' actions and before
            // the carries, as on the CPU.
            // The cloths (broad-phase groups) this round's hits touch; one group when none is given.
            const std::uint32_t groups = std::max<std::uint32_t>(in.triangle_count, 1);
            grow(vertex_group_, n);
            grow(hit_group_, groups);
            WEFT_CUDA_CHECK(cudaMemsetAsync(vertex_group_.get(), 0, n * sizeof(std::uint32_t), stream));
            WEFT_CUDA_CHECK(cudaMemsetAsync(hit_group_.get(), 0, groups, stream));
            if (in.triangle_group != nullptr)
                vertex_group_kernel<<<blocks_for(in.triangle_count, kThreads), kThreads, 0, stream>>>(
                    in.triangles, in.triangle_group, in.triangle_count, vertex_group_.get());
            hit_groups_kernel<<<blocks_for(hits, kThreads), kThreads, 0, stream>>>(ccd_.hits(), hits, vertex_group_.get(),
                                                                                   groups, hit_group_.get());
            freeze_all_kernel<<<blocks_for(n, kThreads), kThreads, 0, stream>>>(
                n, in.inverse_mass, vertex_group_.get(), groups, hit_group_.get(), in.x0, in.x1, outcome_.get(),
                counters_.get());
            WEFT_CUDA_CHECK_LAUNCH("impact zones: freeze all");
            report.froze_all = true;
        }
        carry_claim_kernel<<<blocks_for(hits, kThreads), kThreads, 0, stream>>>(
            ccd_.hits(), hits, hit_free_.get(), in.x0, in.x1, in.inverse_mass, n, outcome_.get(), claim_.get(),
            carry_.get());
        carry_apply_kernel<<<blocks_for(hits, kThreads), kThreads, 0, stream>>>(
            ccd_.hits(), hits, hit_free_.get(), in.x0, in.x1, n, claim_.get(), carry_.get(), outcome_.get(),
            counters_.get());
        claim_reset_kernel<<<blocks_for(hits, kThreads), kThreads, 0, stream>>>(ccd_.hits(), hits, claim_.get());
        WEFT_CUDA_CHECK_LAUNCH("impact zones: carry");
        // The actions of this round are spent (the next round marks afresh).
        WEFT_CUDA_CHECK(cudaMemsetAsync(action_.get(), kNone, n, stream));
        const Counters& c = read_counters(stream);
        if (c.any_rigid != 0) ++report.rigid_rounds;
        const bool progress = c.progress != 0;
        report.zones_ms += ms_since(clock);
        // No move left to try: report what still collides rather than loop.
        if (!progress) return;
        hits = detect(in, report, stream);
        remaining_ = hits;
        if (hits == 0) return;
    }
}

weft::collision::ImpactZoneReport GpuImpactZones::resolve(const GpuImpactZoneInput& in, cudaStream_t stream) {
    if (in.x0 == nullptr || in.x1 == nullptr || in.inverse_mass == nullptr || in.triangles == nullptr ||
        (in.edge_count > 0 && in.edges == nullptr))
        throw Error("GPU impact zones: missing positions, inverse masses or topology");
    if (!std::isfinite(in.thickness) || !(in.thickness > 0.0))
        throw Error("GPU impact zones: thickness must be finite and > 0 (got " + std::to_string(in.thickness) + ")");
    if (!(in.separation_ratio > 0.0 && in.separation_ratio < 1.0))
        throw Error("GPU impact zones: separation_ratio must be in (0, 1) (got " + std::to_string(in.separation_ratio) +
                    ")");
    if (in.max_iterations < 0 || in.max_rigid_rounds < 0 || in.max_sweeps < 1 || in.giant_zone_constraints < 1 ||
        in.max_work < 1)
        throw Error("GPU impact zones: max_iterations and max_rigid_rounds must be ≥ 0, max_sweeps, max_work and "
                    "giant_zone_constraints ≥ 1");
    if (!std::isfinite(in.tolerance_ratio) || !(in.tolerance_ratio > 0.0))
        throw Error("GPU impact zones: tolerance_ratio must be finite and > 0");
    if (!(in.ccd_time_tolerance >= 0.0 && in.ccd_time_tolerance < 1.0))
        throw Error("GPU impact zones: ccd_time_tolerance must be in [0, 1) (0: the float CCD's default), got " +
                    std::to_string(in.ccd_time_tolerance));
    if (in.colored_zone_vertices > kColoredZoneVertices)
        throw Error("GPU impact zones: colored_zone_vertices must be at most " + std::to_string(kColoredZoneVertices) +
                    " (got " + std::to_string(in.colored_zone_vertices) + ")");
    if (in.vertex_count >= kInvalid) throw Error("GPU impact zones: more than 2^32 − 2 vertices");

    weft::collision::ImpactZoneReport report;
    report.eta = in.separation_ratio * in.thickness;
    const std::uint32_t n = in.vertex_count;
    reserve_vertices(n);
    vertices_in_call_ = n;
    constraints_ = 0;
    zones_ = unique_ = 0;
    remaining_ = 0;
    init_kernel<<<blocks_for(n, kThreads), kThreads, 0, stream>>>(
        n, in.inverse_mass, in.x1, x_hat_.get(), parent_.get(), label_.get(), member_.get(), outcome_.get(),
        action_.get(), rigid_size_.get(), claim_.get());
    WEFT_CUDA_CHECK_LAUNCH("impact zones: init");

    std::uint32_t hits = detect(in, report, stream);
    remaining_ = hits;
    const double tol = in.tolerance_ratio * in.thickness;
    while (hits > 0 && report.iterations < in.max_iterations) {
        // Not one iteration of every constraint the round could project fits what is left of the
        // work budget (max_work): the fallbacks take the hits (the CPU's rule).
        const std::int64_t left = in.max_work - report.qp_work;
        if (left < static_cast<std::int64_t>(constraints_) + hits) {
            report.qp_work_spent = true;
            break;
        }
        // The round's iteration cap: what is left over every constraint there will be (an upper
        // bound of those the round projects; at least one, by the check above).
        const int round_sweeps = static_cast<int>(
            std::min<std::int64_t>(in.max_sweeps, std::max<std::int64_t>(left / (std::int64_t{constraints_} + hits), 1)));
        ++report.iterations;
        const auto clock = Clock::now();
        const std::uint32_t first_new = constraints_;
        add_hits(in, hits, stream);
        const ZoneLists z = zone_lists(zone_label_, zone_coffset_, cvalue_sorted_, zone_voffset_, vvalue_sorted_,
                                       unique_vertex_, unique_offset_, unique_count_, slot_sorted_);
        // Only zones that gained a constraint change; the others keep their converged projection.
        mark_kernel<<<blocks_for(hits, kThreads), kThreads, 0, stream>>>(
            first_new, constraints_, c_vertex_.get(), in.inverse_mass, label_.get(), nullptr, action_.get(), kProject);
        WEFT_CUDA_CHECK_LAUNCH("impact zones: mark");
        const Constraints c{c_vertex_.get(), c_weight_.get(), c_normal_.get(), c_scale_.get(),
                            lambda_.get(),   momentum_.get(), previous_.get()};
        const std::uint32_t giant = in.giant_zone_constraints, colored = in.colored_zone_vertices;
        launch_colored_zone_projection(colored_projection(in), zones_, colored, in.colored_zone_constraints, in.thickness,
                                       tol, round_sweeps, stream);
        project_kernel<kLargeZoneThreads><<<zones_, kLargeZoneThreads, 0, stream>>>(
            z, c, x_hat_.get(), in.inverse_mass, in.x1, n, in.thickness, tol, round_sweeps, giant, colored,
            in.colored_zone_constraints, action_.get(), outcome_.get(), counters_.get());
        WEFT_CUDA_CHECK_LAUNCH("impact zones: project (large zones)");
        project_kernel<kZoneThreads><<<zones_, kZoneThreads, 0, stream>>>(z, c, x_hat_.get(), in.inverse_mass, in.x1,
                                                                          n, in.thickness, tol, round_sweeps, giant,
                                                                          colored, in.colored_zone_constraints,
                                                                          action_.get(), outcome_.get(), counters_.get());
        WEFT_CUDA_CHECK_LAUNCH("impact zones: project");
        project_giant_zones(in, tol, round_sweeps, stream);
        const Counters& counters = read_counters(stream);
        if (counters.zone_vertex_runs != zones_)
            throw Error("GPU impact zones: internal error, " + std::to_string(zones_) + " zones by constraints but " +
                        std::to_string(counters.zone_vertex_runs) + " by vertices");
        report.qp_sweeps += counters.sweeps;
        report.qp_work += static_cast<std::int64_t>(counters.work);
        report.qp_unconverged += static_cast<int>(counters.unconverged);
        report.zones_ms += ms_since(clock);
        hits = detect(in, report, stream);
        remaining_ = hits;
    }
    if (hits > 0) fallbacks(in, hits, report, stream);

    // Final figures.
    const auto clock = Clock::now();
    report.resolved = remaining_ == 0;
    report.remaining_hits = static_cast<int>(remaining_);
    report.constraints = static_cast<int>(constraints_);
    report.zones = static_cast<int>(zones_);
    if (constraints_ > 0) {
        WEFT_CUDA_CHECK(cudaMemsetAsync(counters_.get(), 0, sizeof(Counters), stream));
        WEFT_CUDA_CHECK(cudaMemsetAsync(flags_.get(), 0, n * sizeof(std::uint32_t), stream));
        flags_from_vertices_kernel<<<blocks_for(unique_, kThreads), kThreads, 0, stream>>>(
            unique_, unique_vertex_.get(), label_.get(), outcome_.get(), flags_.get());
        final_vertices_kernel<<<blocks_for(n, kThreads), kThreads, 0, stream>>>(n, outcome_.get(), counters_.get());
        final_zones_kernel<<<blocks_for(zones_, kThreads), kThreads, 0, stream>>>(
            zones_, zone_label_.get(), zone_voffset_.get(), flags_.get(), counters_.get());
        WEFT_CUDA_CHECK_LAUNCH("impact zones: figures");
        const Counters& c = read_counters(stream);
        report.max_zone_vertices = static_cast<int>(c.max_zone_vertices);
        report.rigid_zones = static_cast<int>(c.rigid_zones);
        report.frozen_vertices = static_cast<int>(c.frozen);
        report.carried_vertices = static_cast<int>(c.carried);
    }
    // The trim window (weft/backend/buffer_trim.h): constraints a fold once needed are not kept for
    // the rest of the run. Freed here, at the end of a call, nothing reads them any more (the frees
    // wait for the device); the next call that needs constraints allocates what it needs.
    if (const std::size_t kept = constraint_trim_.record(constraints_, capacity_, kBytesPerConstraint, 1024))
        if (grown_capacity(kept) < capacity_) {
            release_constraints();
            ++trims_;
        }
    report.zones_ms += ms_since(clock);
    return report;
}

void GpuImpactZones::download(std::vector<weft::collision::VertexOutcome>& outcome, std::vector<std::uint32_t>& zone,
                              cudaStream_t stream) const {
    outcome.resize(vertices_in_call_);
    zone.resize(vertices_in_call_);
    if (vertices_in_call_ == 0) return;
    static_assert(sizeof(weft::collision::VertexOutcome) == 1);
    WEFT_CUDA_CHECK(cudaMemcpyAsync(outcome.data(), outcome_.get(), vertices_in_call_, cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaMemcpyAsync(zone.data(), label_.get(), vertices_in_call_ * sizeof(std::uint32_t),
                                    cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
}

}  // namespace weft::cuda::collision
