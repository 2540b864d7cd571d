#pragma once
/// @file
/// The model flattened into one system for a backend: every cloth's vertices, triangles and hinges
/// concatenated with global indices, one block pattern for the whole world (cloths are independent
/// diagonal blocks of it), and the gather tables that make assembly deterministic. The CPU and CUDA
/// backends build their state from this; it is rebuilt only when `Model::topology_version` changes.

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "weft/fabric.h"
#include "weft/backend/model.h"
#include "weft/physics/shell_bending.h"

namespace weft {

struct FlatModel {
    std::size_t vertex_count = 0;
    std::vector<std::uint32_t> cloth_vertex_offset;    ///< size cloths+1
    std::vector<std::uint32_t> cloth_triangle_offset;  ///< size cloths+1
    std::vector<std::uint32_t> cloth_hinge_offset;     ///< size cloths+1
    std::vector<Vec3d> initial_positions;              ///< rest shape placed by each cloth's transform, m
    std::vector<Vec3d> initial_velocities;             ///< m/s
    std::vector<double> mass;                          ///< lumped, kg
    std::vector<std::uint32_t> vertex_cloth;           ///< owning cloth of each vertex
    std::vector<Triangle> triangles;                   ///< global vertex indices
    std::vector<TriangleRest> triangle_rest;
    std::vector<std::uint32_t> triangle_cloth;
    std::vector<Hinge> hinges;                         ///< global vertex indices
    std::vector<std::uint32_t> hinge_cloth;
    /// Per triangle, the global hinges across its edges (Fabric::triangle_hinges), and the rest data
    /// of the bending model per triangle (SolverSettings::bending = Shell; weft/physics/shell_bending.h).
    std::vector<TriangleHinges> triangle_hinges;
    std::vector<physics::ShellBendingRest<double>> shell_rest;
    BlockPattern pattern;                              ///< global; slot maps index global triangles/hinges

    /// Element force entries: triangle t, corner a → 3t + a; hinge k, corner a → 3T + 4k + a.
    /// `vertex_force_index[vertex_force_start[i] .. vertex_force_start[i+1])` lists vertex i's entries
    /// in a fixed order, so summing them gives the same bits on any thread count.
    std::vector<std::uint32_t> vertex_force_start, vertex_force_index;
    /// Element Hessian blocks: triangle t, pair (a,b) → 9t + 3a + b; hinge k → 9T + 16k + 4a + b.
    /// `slot_block_index[slot_block_start[s] .. slot_block_start[s+1])` lists the blocks summed into
    /// BSR slot s, in a fixed order.
    std::vector<std::uint32_t> slot_block_start, slot_block_index;

    /// Pins: vertex, motion followed (−1: fixed) and the vertex position in that motion's frame at t=0.
    std::vector<std::uint32_t> pin_vertex;
    std::vector<int> pin_motion;
    std::vector<Vec3d> pin_local;
    /// Pins that follow a collider vertex (PinDesc::collider; −1: none): the collider, its vertex,
    /// and in pin_local the pin's world offset from that vertex at t = 0. Pins that follow a joint
    /// of its skin (pin_collider_joint ≥ 0): pin_local is the pin's place in the joint's frame at
    /// t = 0 (the inverse of collider_mesh_transforms' map applied to it).
    std::vector<int> pin_collider;
    std::vector<std::uint32_t> pin_collider_vertex;
    std::vector<int> pin_collider_joint;
    std::vector<std::int32_t> vertex_pin;  ///< pin index of each vertex or −1

    /// The cloths' mass, kg (the CG energy test's scale: cg_energy_floor).
    [[nodiscard]] double total_mass() const {
        double m = 0.0;
        for (const double v : mass) m += v;
        return m;
    }
    [[nodiscard]] std::size_t triangle_count() const { return triangles.size(); }
    [[nodiscard]] std::size_t hinge_count() const { return hinges.size(); }
    [[nodiscard]] std::size_t memory_bytes() const;
    /// First global vertex and vertex count of `cloth`, checked against the sizes of the caller's
    /// position and velocity arrays (throws `weft::Error` naming the cloth on a mismatch).
    [[nodiscard]] std::pair<std::size_t, std::size_t> cloth_vertices(std::size_t cloth, std::size_t positions,
                                                                     std::size_t velocities) const;
};

/// Fills `f`'s gather tables (vertex_force_*, slot_block_*) from its elements and pattern.
void build_gather_tables(FlatModel& f);

/// Flattens `model` (throws `weft::Error` if a cloth has no fabric).
[[nodiscard]] FlatModel flatten(const Model& model);

/// Every pin's target at time `t` (s; m, world), in `f`'s pin order: its fixed point, its point in a
/// motion's frame, or its collider vertex (skinned where the collider plays a clip) plus its offset.
/// Both backends stage the targets from this.
void pin_targets(const Model& model, const FlatModel& f, double t, std::span<Vec3d> out);

}  // namespace weft
