#pragma once
// Host-side launchers of the solver kernels (one .cu file per concept: state_kernels.cu,
// assembly_kernels.cu, contact_kernels.cu, pcg_kernels.cu). Each launches on `stream` and checks the launch.

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>

#include "device_layout.h"
#include "grid_size.h"
#include "device_view.h"

namespace weft::cuda {

inline constexpr int kBlockSize = 256;
[[nodiscard]] inline unsigned grid_for(std::uint32_t count) { return blocks_for(count, kBlockSize); }
/// The most blocks the one-launch CG loop is given beyond one per kBlockSize rows (its block partials
/// are sized for it): more than any device holds at once at five blocks an SM.
inline constexpr unsigned kMaxPersistentBlocks = 2048;

// ---- state (state_kernels.cu) --------------------------------------------------------------------
/// x0 = x, v0 = v, v_k = v, w_k = 0; resets the substep's stats.
void launch_begin_substep(const DeviceView& d, cudaStream_t stream);
/// Pinned vertices' velocity that lands them on their targets at t + h.
void launch_pin_velocities(const DeviceView& d, cudaStream_t stream);
/// Resets the CG control and the contact count at the start of a Newton iteration.
void launch_begin_newton(const DeviceView& d, cudaStream_t stream);
/// v_k += Δv, w_k = v_k.
void launch_newton_update(const DeviceView& d, cudaStream_t stream);
/// The line search's trial (SolverSettings::line_search): v = v_k + α·Δv (a pinned vertex takes its
/// whole prescribed Δv), written as the positions x0 + h·v and the velocity change v − v0 (the
/// inertia term's), component-major like the state, 3·n floats each.
void launch_line_search_trial(const DeviceView& d, float alpha, float* trial_x, float* trial_dv, cudaStream_t stream);
/// Δv ← α·Δv over the free vertices: the step the line search accepted.
void launch_scale_update(const DeviceView& d, float alpha, cudaStream_t stream);
/// x = x0 + h·v_k, v = v_k; counts non-finite values and restores x0, v0 if there are any. With
/// bounded analytic colliders it also records the largest free-vertex displacement in the stats.
void launch_commit(const DeviceView& d, cudaStream_t stream);
/// The swept test of every analytic collider against every free vertex's path x0 → x over the
/// substep (weft/physics/swept_collider.h, as CpuSolver::sweep_fast_colliders): a vertex the
/// collider ran into takes the corrected end position, v = (x − x0)/h and the matching previous Δv;
/// the hits are added to DeviceStats::swept_hits. Launched after the commit, outside the graph,
/// only in substeps where the host finds that some vertex may need it.
void launch_sweep_colliders(const DeviceView& d, cudaStream_t stream);
/// Writes position and area-weighted normal of every solved row's vertex (d.rows) to `out`, vertex i
/// at stride·i bytes, or at stride·index[i] with an index (part mode: the global vertex).
void launch_write_output(const DeviceView& d, void* out, std::size_t stride, cudaStream_t stream,
                         const std::uint32_t* index = nullptr);
/// x = x0, v = v0, previous Δv = 0 whatever the stats say (part mode: another part met a non-finite value).
void launch_rollback(const DeviceView& d, cudaStream_t stream);
/// The substep's solve dropped whatever the stats say (part mode: another part's vertex ran away):
/// x = x0 + h·v0 and v = v0 for the free vertices, previous Δv = 0, as launch_commit's runaway drop.
void launch_drop_solve(const DeviceView& d, cudaStream_t stream);
/// Stores `stamp` at `where` (8-byte aligned, device memory): the frame stamps of a shared slot.
void launch_write_stamp(void* where, std::uint64_t stamp, cudaStream_t stream);

// ---- forces and assembly (force_kernels.cu) -------------------------------------------------------
/// The bending models per triangle's pass 1 (solver.bending = "shell", "midedge";
/// shell_bending_kernels.cu): every triangle's terms at the Newton iteration's linearisation point
/// into d.shell_faces, which the assembly then reads through each hinge (with the mid-edge model, its
/// normals relaxed there first). Nothing without d.shell_faces.
void launch_shell_faces(const DeviceView& d, cudaStream_t stream);
/// Where the mid-edge model's normals are relaxed: at the Newton iteration's linearisation point
/// x0 + h·w_k (the solver's pass 1), or at d.x (the energy audit's state).
enum class MidEdgeAt { Linearisation, Positions };
/// The mid-edge model's normals (solver.bending = "midedge"; midedge_kernels.cu): the turns ξ that
/// minimise the bending energy at the state `at`, into d.midedge.xi, by Jacobi-preconditioned CG in
/// double in one cooperative launch of d.midedge.grid blocks. A solve of the solver's own
/// (MidEdgeAt::Linearisation) that reaches its cap counts in DeviceStats::cg_not_converged.
void launch_midedge_relax(const DeviceView& d, MidEdgeAt at, cudaStream_t stream);
/// The largest grid that launch_midedge_relax may use on `device` for d's hinges and triangles (all
/// its blocks resident at once); 0 where the device has no cooperative launch.
[[nodiscard]] int midedge_relax_grid(const DeviceView& d, int device);
/// The whole system A·Δv = b (assembly_kernels.cu): inertia, gravity, mass damping and collider
/// contacts of each vertex, membrane, damping and wind of each triangle, bending of each hinge.
/// Row gather: one launch, one warp per row (device_layout.h says when each strategy wins).
void launch_assemble_rows(const DeviceView& d, cudaStream_t stream);
/// Colour passes: a vertex launch, then one launch per triangle colour and per hinge colour.
void launch_assemble_colors(const DeviceView& d, const Coloring& triangles, const Coloring& hinges, cudaStream_t stream);

// ---- proximity contacts (contact_kernels.cu) ------------------------------------------------------
// Every launch is sized by the list's capacity (the pair kernels stride, with at most 1024 blocks) and
// reads the pair count from device memory, so a graph captured once serves any count up to the
// capacity. None of them is called when the capacity is 0.
/// Bytes of scratch the incidence build's radix sort needs for `corner_slots` corners (4 a pair of
/// capacity) whose keys are below 2^key_bits.
[[nodiscard]] std::size_t contact_sort_storage_bytes(std::uint32_t corner_slots, int key_bits);
/// Per substep (per evaluation for offset contacts): the incidence of the rows (row → 4·pair +
/// corner, in pair order, whatever order the pairs were written in) by a stable radix sort of every
/// corner slot keyed by its row (slots not in use keyed past the last row), then each row's start
/// by a binary search. No atomics: the result does not depend on scheduling.
void launch_contact_incidence(const DeviceView& d, const ContactSortScratch& scratch, cudaStream_t stream);
/// Per Newton iteration: each pair's block C = −h·D − h²·K and right-hand side at the linearisation
/// point (gathered into b and the diagonal blocks by the PCG setup).
void launch_contact_evaluate(const DeviceView& d, cudaStream_t stream);
/// First pass of the contact SpMV: per pair C·Σ_j w_j x_j. `in_cg_loop`: do nothing once the CG loop
/// has stopped (the per-iteration kernels run on after convergence until the host or graph notices).
void launch_contact_product(const DeviceView& d, const float* x, bool in_cg_loop, cudaStream_t stream);
/// The gather half as its own pass: each row's contact sum into c.row_sum (contact_row_sums) for
/// rows [0, rows); `running` (nullable): nothing once the CG loop has stopped. launch_contact_product
/// runs it after the pair pass inside the CG loop.
void launch_contact_row_sums(const ContactView& c, std::uint32_t rows, const int* running, cudaStream_t stream);

// ---- collision positions (collision_state_kernels.cu) ----------------------------------------------
// The collision stages read positions in their own index space (cloth vertices, then kinematic ones;
// SoA with component stride `stride`), filled from the solver's state (SoA, stride n).
/// x0c = x, x1c = x + h·v for the n cloth vertices (rounded as the CPU: the product, then the sum).
/// Offset mode (device_collisions.h): the momentum sums of the free cloth vertices (sums: 4 doubles:
/// Σ m·v, Σ m; in a fixed order, through `partials`: 4 × kOffsetMomentumBlocks doubles), the per-vertex
/// query radii (and their largest, as float bits), and the positions of a rerun detection (h read
/// from device memory).
inline constexpr std::uint32_t kOffsetMomentumBlocks = 1024;
void launch_offset_momentum(const float* v, const float* inverse_mass, std::uint32_t n, double* sums, double* partials,
                            cudaStream_t stream);
void launch_offset_radius(const float* x0c, const float* x1c, const float* remainder, const float* dv_previous, float h,
                          std::uint32_t n, std::uint32_t vertices, const float* shift, float relaxation, float contact,
                          float cap, float* radius, std::uint32_t* largest, cudaStream_t stream);
void launch_offset_detect_positions(const float* x0, const float* vk, std::uint32_t n, const float* h, const float* x1c,
                                    std::uint32_t vertices, float* detect, cudaStream_t stream);
void launch_collision_predict(const float* x, const float* v, std::uint32_t n, float h, float* x0c, float* x1c,
                              std::uint32_t stride, cudaStream_t stream);
/// Mesh colliders (device_kinematics.h): each of the `count` vertices is placed by the weighted maps
/// of its 4 (joint id, weight) entries; a map is kKinematicMapFloats floats: A(t), A(t + h) and
/// (A(t + h) − A(t))/h, each row-major 3×4. Writes x(t) to x0c, x(t + h) to x1c (stride `stride`),
/// and x(t + h) and the velocity to x1 and v (stride count).
inline constexpr std::size_t kKinematicMapFloats = 36;
void launch_place_kinematic(const float* rest, const std::uint32_t* joints, const float* weights, const float* maps,
                            std::uint32_t count, float* x0c, float* x1c, std::uint32_t stride, float* x1, float* v,
                            cudaStream_t stream);
/// x1c = x for the n cloth vertices (the solved end of the substep).
void launch_collision_gather(const float* x, std::uint32_t n, float* x1c, std::uint32_t stride, cudaStream_t stream);
/// After the impact zones: cloth vertices with a zone outcome (weft::collision::VertexOutcome per
/// collision vertex) take x1c, v = (x1c − x0c)·inv_h and dv_previous = v − v0, in the solver's
/// layout (stride n).
void launch_collision_scatter(const float* x1c, const float* x0c, const std::uint8_t* outcome, std::uint32_t n,
                              std::uint32_t stride, float inv_h, float* x, float* v, const float* v0,
                              float* dv_previous, cudaStream_t stream);

// ---- PCG (pcg_kernels.cu) --------------------------------------------------------------------------
/// Block-Jacobi inverse (`schwarz`: the diagonal block itself, for the Schwarz levels), Δv
/// initialised (prescribed on filtered vertices; on the others the last substep's change when
/// `first_newton` and warm starts are on, else 0), δ₀ of b (block-Jacobi only). With contacts it
/// first gathers them into the row: b_i += Σ w_i·rhs_pair, diagonal block += Σ w_i²·C_pair.
void launch_pcg_setup(const DeviceView& d, bool first_newton, bool schwarz, cudaStream_t stream);
/// r = filter(b − AΔv), c = M⁻¹r, δ; decides whether the loop runs (with contacts, A includes them:
/// the pair pass over Δv is launched first). `handle` (0: none) is the graph's while-node condition,
/// set to the loop's `running` flag. `schwarz`: M is the Schwarz preconditioner (factored by
/// launch_schwarz_factor), and δ₀ of b is its norm of b.
void launch_pcg_residual(const DeviceView& d, unsigned long long handle, bool schwarz, cudaStream_t stream);
/// One CG iteration: q = filter(A c) with cᵀq (fused; with contacts the pair pass over c comes first
/// and the SpMV gathers it), then the axpy pair with s = M⁻¹r and rᵀs (fused with block-Jacobi; the
/// Schwarz apply's kernels otherwise), then the new direction. Every kernel does nothing once the
/// loop has stopped.
void launch_pcg_iteration(const DeviceView& d, unsigned long long handle, bool schwarz, cudaStream_t stream);
/// Blocks for the one-launch CG loop on `device` (`schwarz`: its Schwarz form): as many as fit at once
/// (at most one per 256 rows), 0 if the device cannot launch cooperative kernels.
[[nodiscard]] int pcg_persistent_grid(const DeviceView& d, int device, bool schwarz);
/// The whole CG loop after its start (launch_pcg_residual), in one cooperative launch of `grid`
/// blocks (grid-wide barriers instead of kernel boundaries). Same algorithm and stopping rule;
/// different summation order of the dots than the per-iteration kernels.
void launch_pcg_persistent(const DeviceView& d, int grid, bool schwarz, cudaStream_t stream);
/// Folds the finished solve into the stats.
void launch_pcg_finish(const DeviceView& d, cudaStream_t stream);
// ---- multilevel additive Schwarz (schwarz_kernels.cu; device_schwarz.h) ---------------------------
/// After the PCG setup (which leaves each row's contact-augmented diagonal block in d.precond): every
/// level's coupling blocks from the assembled matrix, then each domain's dense matrix inverted in
/// double and stored in float. Non-positive pivots are counted in DeviceStats::pivot_failures. In
/// Newton iteration `newton`, the kernels do nothing when the staged StepParams::schwarz_refactor
/// says this one reuses the last factors.
void launch_schwarz_factor(const DeviceView& d, int newton, cudaStream_t stream);
/// The factorisation in pieces, for the multi-GPU solver (whose parts gather level 1's couplings in
/// between): the coupling blocks of levels [first_level, end_level) (level ≥ 1), then every level's
/// domain inverses.
void launch_schwarz_couplings(const DeviceView& d, int first_level, int end_level, int newton, cudaStream_t stream);
void launch_schwarz_factor_domains(const DeviceView& d, int newton, cudaStream_t stream);
/// What the apply reads: filter(b) (copied to r), r as it is, or r after the iteration's axpy pair
/// (r −= αq, Δv += αc, done here for each vertex of a level-0 domain).
enum class SchwarzInput { RightHandSide, Residual, Update };
/// What it does with z = filter(M⁻¹r): rᵀz becomes δ₀ of b (Norm); c = z and the loop's start
/// (Start); s = z, β and the stopping test (Iterate).
enum class SchwarzOutput { Norm, Start, Iterate };
/// z = M⁻¹r: the first level's domains (restricting to the next level), each coarser level's, then
/// every vertex sums its nodes' corrections with the dot product. Update and Iterate do nothing
/// once the loop has stopped.
void launch_schwarz_apply(const DeviceView& d, SchwarzInput in, SchwarzOutput out, unsigned long long handle,
                          cudaStream_t stream);
/// The apply in pieces, for the multi-GPU solver (whose parts gather level 1's restricted residual
/// between them): level 0's domains with the restriction to level 1, and the coarser levels. With
/// `running` (device memory) each kernel does nothing once it reads 0.
void launch_schwarz_fine(const DeviceView& d, SchwarzInput in, const int* running, cudaStream_t stream);
void launch_schwarz_coarse(const DeviceView& d, const int* running, cudaStream_t stream);

// ---- the energy guard's audit (energy_kernels.cu) --------------------------------------------------
/// The sums the audit returns, in this order (`sums` holds kEnergySums doubles).
enum EnergySum : int {
    kEnergyKinetic, kEnergyGravity, kEnergyContact, kEnergyColliderPower, kEnergyGrabPower,
    kEnergyMembrane, kEnergyWindPower, kEnergyBending, kEnergyPinPower,
    kEnergyOffsetContact,  ///< the offset contacts' penalty energy (collision.mode = offset), J
    kEnergyMaxStretch,     ///< the largest principal stretch of a triangle (a maximum, not a sum)
    kEnergyFaceContact,    ///< the triangles' centroid contacts' penalty energy (StepParams::face_contacts), J
    kEnergyFaceColliderPower,  ///< and their moving colliders' power bound, W
    kEnergySums
};
/// Blocks each sum was reduced over (the finishing kernel's argument).
struct EnergySumCounts {
    std::uint32_t blocks[kEnergySums];
};
/// Doubles of partials per sum: `partials` holds kEnergySums times this many.
[[nodiscard]] std::uint32_t energy_partial_stride(const DeviceView& d);
/// The audit of the state in `d` (x and v) with the parameters staged in d.staging for the
/// substep starting at the audit's time (colliders at their start pose): every sum of EnergySum into
/// `sums` (device memory), deterministically; the wind's power only `with_wind` (else 0).
/// In part mode (d.contacts.row_of set) the offset contacts name whole-model vertices: they read
/// `whole_x` (the whole model's positions on this GPU, stride `whole_n`), and each counts on the part
/// that owns its first cloth corner, so that the parts' sums add up to one GPU's; without `whole_x`
/// a part leaves them out. `with_faces`: the triangles' centroid contacts too (StepParams::
/// face_contacts; else their sums are 0).
void launch_energy_audit(const DeviceView& d, bool with_wind, bool with_faces, double* partials, double* sums,
                         cudaStream_t stream, const float* whole_x = nullptr, std::uint32_t whole_n = 0);

/// y = A·x over the fabric matrix (benchmarks; the solver's SpMV is fused with its dot product and
/// adds the contacts).
void launch_spmv(const DeviceView& d, const float* x, float* y, cudaStream_t stream);

}  // namespace weft::cuda
