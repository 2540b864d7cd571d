#pragma once
/// @file
/// The cooked, immutable part of a cloth: rest geometry, per-element rest data, hinges, lumped
/// masses and the fixed 3×3 block sparsity of the implicit system. One Fabric is shared by any
/// number of `Cloth` instances (NvCloth's Fabric/Cloth split; Jolt's SoftBodySharedSettings).

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "weft/types.h"

namespace weft {

/// Triangle mesh input to cooking. Positions are the rest shape (m).
struct MeshData {
    std::vector<Vec3d> positions;
    std::vector<Triangle> triangles;
    std::string source;  ///< file name or generator, used in error messages
    /// Vertices merged so far by `weld_by_position` (an importer's UV/normal seam splits); cooking
    /// carries it into `CookReport::welded_vertices`.
    std::size_t welded_vertices = 0;
};

/// How cooking treats the rest shape (valid ranges: the parameter table, weft/parameters.h).
struct FabricDesc {
    double density = 0.2;            ///< areal density, kg/m².
    bool flat_rest_bending = false;  ///< true: rest dihedral angles are 0 (a flat sheet); false: from the rest mesh
};

/// Per-triangle rest data of the membrane (Baraff–Witkin / StVK triangle FEM).
struct TriangleRest {
    double dm_inv[2][2]{};  ///< inverse of the 2×2 rest edge matrix in the triangle's own 2D frame, 1/m
    double area = 0.0;      ///< rest area, m²
};

/// A bending hinge: the two triangles (v0, v1, v2) and (v1, v0, v3) sharing the edge v0–v1.
struct Hinge {
    std::uint32_t v[4]{};     ///< v0, v1 on the shared edge; v2, v3 the opposite vertices
    double rest_angle = 0.0;  ///< signed dihedral angle at rest, rad
    double weight = 0.0;      ///< |e|²/(A₀+A₁), 1 (E = ½·k_b·w·(θ−θ̄)²; calibrated in tests/physics so k_b is the plate stiffness)
};

/// The hinges across a triangle's three edges: `edge[k]` for the edge from corner k to corner k+1
/// (mod 3), −1 where the edge is on the boundary, non-manifold or has no hinge. What a bending model
/// per triangle reads (weft/physics/shell_bending.h).
struct TriangleHinges {
    std::int32_t edge[3]{-1, -1, -1};
};

/// Fixed block-sparse (BSR) pattern of the implicit system of one fabric: one block row per
/// vertex, columns sorted, diagonal included. Internal-force Jacobians scatter into it through
/// precomputed slot maps so that assembly needs no search and no atomics on the CPU.
struct BlockPattern {
    std::vector<std::uint32_t> row_start;  ///< size n+1, block offsets
    std::vector<std::uint32_t> column;     ///< block column of each stored block
    std::vector<std::uint32_t> diagonal;   ///< slot of block (i,i) for each row i
    std::vector<std::uint32_t> triangle_slots;  ///< 9 slots per triangle, [a*3+b] → block (v_a, v_b)
    std::vector<std::uint32_t> hinge_slots;     ///< 16 slots per hinge, [a*4+b] → block (v_a, v_b)
    [[nodiscard]] std::size_t block_count() const { return column.size(); }
};

/// Problems found while cooking a mesh; cooking refuses input it cannot simulate and reports the rest.
struct CookReport {
    std::size_t welded_vertices = 0;        ///< duplicates merged by position
    std::size_t degenerate_triangles = 0;   ///< zero-area triangles dropped
    std::size_t duplicate_triangles = 0;    ///< repeated triangles dropped
    std::size_t non_manifold_edges = 0;     ///< edges shared by more than two triangles (no hinge made)
    std::size_t unreferenced_vertices = 0;  ///< vertices no triangle uses (removed)
    std::vector<std::string> warnings;      ///< human-readable, one per problem class
};

/// The cooked fabric. Immutable after construction; share it through `std::shared_ptr`.
class Fabric {
public:
    /// Cooks a mesh. Throws `weft::Error` naming `mesh.source` when the mesh is unusable (no
    /// triangles, indices out of range, non-finite positions, nothing left after removing degenerate
    /// triangles). Degenerate and duplicate triangles are dropped and counted in `report()`.
    static std::shared_ptr<const Fabric> cook(const MeshData& mesh, const FabricDesc& desc = {});

    [[nodiscard]] std::size_t vertex_count() const { return rest_positions_.size(); }
    [[nodiscard]] std::size_t triangle_count() const { return triangles_.size(); }
    [[nodiscard]] std::span<const Vec3d> rest_positions() const { return rest_positions_; }
    [[nodiscard]] std::span<const Triangle> triangles() const { return triangles_; }
    [[nodiscard]] std::span<const TriangleRest> triangle_rest() const { return triangle_rest_; }
    [[nodiscard]] std::span<const Hinge> hinges() const { return hinges_; }
    /// Per triangle, the hinges across its edges (indices into `hinges()`).
    [[nodiscard]] std::span<const TriangleHinges> triangle_hinges() const { return triangle_hinges_; }
    /// Lumped vertex masses, kg: a third of the density × area of each adjacent triangle.
    [[nodiscard]] std::span<const double> masses() const { return masses_; }
    [[nodiscard]] const BlockPattern& pattern() const { return pattern_; }
    [[nodiscard]] const CookReport& report() const { return report_; }
    [[nodiscard]] double density() const { return desc_.density; }
    [[nodiscard]] double total_area() const { return total_area_; }
    [[nodiscard]] double mean_edge_length() const { return mean_edge_length_; }
    /// Approximate heap bytes held by this fabric.
    [[nodiscard]] std::size_t memory_bytes() const;

private:
    Fabric() = default;
    FabricDesc desc_{};
    std::vector<Vec3d> rest_positions_;
    std::vector<Triangle> triangles_;
    std::vector<TriangleRest> triangle_rest_;
    std::vector<Hinge> hinges_;
    std::vector<TriangleHinges> triangle_hinges_;
    std::vector<double> masses_;
    BlockPattern pattern_;
    CookReport report_;
    double total_area_ = 0.0;
    double mean_edge_length_ = 0.0;
};

}  // namespace weft
