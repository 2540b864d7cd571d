#pragma once
// The per-domain and per-vertex pieces of the Schwarz apply z = M⁻¹r (docs/methods.md §2b), shared
// by its per-kernel form (schwarz_kernels.cu: a kernel per level) and the one-launch CG loop
// (pcg_kernels.cu: the same pieces between grid-wide barriers). A warp owns a domain: lanes hold its
// 16 nodes' values, then two rows each of the 48×48 solve.

#include "device_math.cuh"

namespace weft::cuda {

inline constexpr std::uint32_t kSchwarzWarpsPerBlock = kBlockSize / 32;
static_assert(kSchwarzDim <= 64, "a warp computes at most two rows of a domain solve per lane");

/// solved = D⁻¹v for one domain (v in shared memory), rows `lane` and `lane + 32`. The inverse is
/// column-major, so a warp's loads of one column are contiguous. (Unrolling the column loop fully,
/// to put all of a domain's loads in flight at once, measured 8-20% slower on an H100: docs/results.md.)
__device__ inline void schwarz_solve_domain(const float* inverse, const float* v, float* solved, std::uint32_t lane) {
    for (std::uint32_t row = lane; row < kSchwarzDim; row += 32) {
        float y = 0.0f;
        for (std::uint32_t j = 0; j < kSchwarzDim; ++j) y += __ldg(&inverse[j * kSchwarzDim + row]) * v[j];
        solved[row] = y;
    }
}

/// Sums the domain's values (v) of each of its pieces into the next level's node (lane k: the
/// domain's k-th piece, its members in node order).
__device__ inline void schwarz_restrict_domain(const SchwarzLevelView& level, const SchwarzLevelView& next,
                                               std::uint32_t domain, const float* v, std::uint32_t lane) {
    const std::uint32_t first = level.parent_start[domain], count = level.parent_start[domain + 1] - first;
    if (lane >= count) return;
    const std::uint32_t me = first + lane;
    float acc[3] = {0.0f, 0.0f, 0.0f};
    for (std::uint32_t k = 0; k < kSchwarzNodes; ++k) {
        const std::uint32_t node = domain * kSchwarzNodes + k;
        if (node < level.nodes && level.parent[node] == me)
            for (int c = 0; c < 3; ++c) acc[c] += v[3 * k + c];
    }
    for (int c = 0; c < 3; ++c) next.values[3 * me + c] = acc[c];
}

/// Level 0, domain `domain`: lane k < 16 puts its node's residual into v (48 floats of shared memory
/// for the warp) as `in` says (for Update, after r −= αq and Δv += αc, written back). Ends with the
/// warp converged and v complete.
__device__ inline void schwarz_fine_load(const DeviceView& d, std::uint32_t domain, std::uint32_t lane, float* v,
                                         SchwarzInput in, float alpha) {
    const SchwarzView& m = d.mas;
    const SchwarzLevelView& level = m.level[0];
    if (lane < kSchwarzNodes) {
        const std::uint32_t p = domain * kSchwarzNodes + lane;
        V3 r{};
        if (p < level.nodes) {  // all vertices on one GPU, the owned ones of a part
            const std::uint32_t i = m.order[p];
            if (in == SchwarzInput::RightHandSide) {
                r = d.fixed[i] ? V3{} : load3(d.b, i, d.n);
                store3(d.r, i, d.n, r);
            } else if (in == SchwarzInput::Residual) {
                r = load3(d.r, i, d.n);
            } else {
                r = load3(d.r, i, d.n) - alpha * load3(d.q, i, d.n);
                store3(d.dv, i, d.n, load3(d.dv, i, d.n) + alpha * load3(d.c, i, d.n));
                store3(d.r, i, d.n, r);
            }
        }
        v[3 * lane] = r.x;
        v[3 * lane + 1] = r.y;
        v[3 * lane + 2] = r.z;
    }
    __syncwarp();
}

/// Level l ≥ 1, domain `domain`: its values into v. They were written by other warps before a kernel
/// boundary or grid barrier: read past L1.
__device__ inline void schwarz_coarse_load(const DeviceView& d, int l, std::uint32_t domain, std::uint32_t lane, float* v) {
    const SchwarzLevelView& level = d.mas.level[l];
    for (std::uint32_t k = lane; k < kSchwarzDim; k += 32) v[k] = __ldcg(&level.values[domain * kSchwarzDim + k]);
    __syncwarp();
}

/// Level l's domain `domain` solved from the values in v, which are then restricted to level l + 1
/// (when there is one); v may be reused by the warp once it returns.
__device__ inline void schwarz_solve_and_restrict(const DeviceView& d, int l, std::uint32_t domain, std::uint32_t lane,
                                                  const float* v) {
    const SchwarzView& m = d.mas;
    const SchwarzLevelView& level = m.level[l];
    schwarz_solve_domain(level.inverse + static_cast<std::size_t>(domain) * kSchwarzDim * kSchwarzDim, v,
                         level.solved + domain * kSchwarzDim, lane);
    if (l + 1 < m.levels) schwarz_restrict_domain(level, m.level[l + 1], domain, v, lane);
    __syncwarp();
}

/// Level 0, domain `domain`, by a whole warp: takes its residuals (schwarz_fine_load), solves, and
/// restricts to level 1.
__device__ inline void schwarz_fine_domain(const DeviceView& d, std::uint32_t domain, std::uint32_t lane, float* v,
                                           SchwarzInput in, float alpha) {
    schwarz_fine_load(d, domain, lane, v, in, alpha);
    schwarz_solve_and_restrict(d, 0, domain, lane, v);
}

/// Level l ≥ 1, domain `domain`, by a whole warp: solve and restrict to level l + 1.
__device__ inline void schwarz_coarse_domain(const DeviceView& d, int l, std::uint32_t domain, std::uint32_t lane,
                                             float* v) {
    schwarz_coarse_load(d, l, domain, lane, v);
    schwarz_solve_and_restrict(d, l, domain, lane, v);
}

// ---- restriction first, then every level's solves (the one-launch loops) ---------------------------
// The levels are additive: each level's input is the residual restricted to it, not another level's
// solution, so the restriction chain (short: load, add, store) can run first, a grid-wide barrier a
// level, and then every level's domain solves in one phase. There the coarse levels' few domains,
// each a chain of dependent loads that used to be a phase of its own between barriers, run beside
// the fine level's many and hide behind them. Every value is the one the level-by-level form
// computes (the same sums in the same order): the same bits.

/// The restriction of level l's domain `domain` to level l + 1 (l = 0 with `in` as for
/// schwarz_fine_load, which it writes back where `in` says).
__device__ inline void schwarz_restrict_only(const DeviceView& d, int l, std::uint32_t domain, std::uint32_t lane, float* v,
                                             SchwarzInput in, float alpha) {
    const SchwarzView& m = d.mas;
    if (l == 0)
        schwarz_fine_load(d, domain, lane, v, in, alpha);
    else
        schwarz_coarse_load(d, l, domain, lane, v);
    if (l + 1 < m.levels) schwarz_restrict_domain(m.level[l], m.level[l + 1], domain, v, lane);
    __syncwarp();
}

/// The solve of level l's domain `domain` alone, its input restricted before (level 0 reads r).
__device__ inline void schwarz_solve_only(const DeviceView& d, int l, std::uint32_t domain, std::uint32_t lane, float* v) {
    const SchwarzView& m = d.mas;
    if (l == 0)
        schwarz_fine_load(d, domain, lane, v, SchwarzInput::Residual, 0.0f);
    else
        schwarz_coarse_load(d, l, domain, lane, v);
    const SchwarzLevelView& level = m.level[l];
    schwarz_solve_domain(level.inverse + static_cast<std::size_t>(domain) * kSchwarzDim * kSchwarzDim, v,
                         level.solved + domain * kSchwarzDim, lane);
    __syncwarp();
}

/// Every level's solves in one pass by warp `warp` of `warps`: the coarse levels' domains first,
/// deepest first (task 0 is the coarsest level's first domain), so that their warps start at once,
/// then the fine level's.
__device__ inline void schwarz_solve_levels(const DeviceView& d, std::uint32_t warp, std::uint32_t warps,
                                            std::uint32_t lane, float* v) {
    const SchwarzView& m = d.mas;
    std::uint32_t coarse = 0;
    for (int l = 1; l < m.levels; ++l) coarse += m.level[l].domains;
    const std::uint32_t tasks = coarse + m.level[0].domains;
    for (std::uint32_t task = warp; task < tasks; task += warps) {
        if (task >= coarse) {
            schwarz_solve_only(d, 0, task - coarse, lane, v);
            continue;
        }
        std::uint32_t t = task;
        int l = m.levels - 1;
        while (t >= m.level[l].domains) t -= m.level[l--].domains;  // uniform over the warp
        schwarz_solve_only(d, l, t, lane, v);
    }
}

/// z_i = filter(Σ_l solved_l[node_l(i)]): vertex i's correction from every level.
__device__ inline V3 schwarz_correction(const DeviceView& d, std::uint32_t i) {
    if (d.fixed[i]) return V3{};
    const SchwarzView& m = d.mas;
    std::uint32_t node = m.rank[i];
    const float* y = m.level[0].solved + 3 * node;
    V3 z{__ldcg(y), __ldcg(y + 1), __ldcg(y + 2)};
    for (int l = 1; l < m.levels; ++l) {
        node = m.level[l - 1].parent[node];
        const float* yl = m.level[l].solved + 3 * node;
        z += V3{__ldcg(yl), __ldcg(yl + 1), __ldcg(yl + 2)};
    }
    return z;
}

}  // namespace weft::cuda
