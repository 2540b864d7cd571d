// The mid-edge bending model over a whole sheet (runtime/src/midedge_normals.h with
// weft/physics/midedge_bending.h): the normals' solve converges, a flat or rigidly moved sheet has
// no bending energy, and a cylinder bent about a grid's diagonal costs the plate energy where the
// shell model (the same with the normals at their faces' mean) charges about 1.5×.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "midedge_normals.h"
#include "shell_bending_energy.h"
#include "weft/fabric.h"
#include "weft/mesh.h"

namespace weft {
namespace {

constexpr double kStiffness = 1e-3;  // N·m

std::shared_ptr<const Fabric> sheet(int cells, double size) {
    return Fabric::cook(make_grid(size, size, cells, cells, GridPlane::XZ), {.flat_rest_bending = true});
}

/// The sheet's bending energy at `x`: the shell model, or the mid-edge model with its normals
/// relaxed (whose report is returned through `report`).
double bending_energy(const Fabric& f, const std::vector<Vec3d>& x, bool midedge, MidEdgeSolveReport* report = nullptr,
                      const std::vector<char>* pinned = nullptr) {
    MidEdgeState state;
    if (midedge) {
        relax_midedge_normals(f, x, [&](std::uint32_t i) { return pinned != nullptr && (*pinned)[i] != 0; }, state);
        if (report != nullptr) *report = state.report;
    }
    double e = 0.0;
    for (std::size_t t = 0; t < f.triangle_count(); ++t)
        e += shell_bending_triangle(f, t, kStiffness, x, [](std::uint32_t, const Vec3d&) {}, midedge ? &state : nullptr);
    return e;
}

/// The sheet bent into a cylinder of curvature κ (1/m) whose axis runs at `angle` (rad) from x in
/// the sheet's plane, rolled away from +y.
std::vector<Vec3d> cylinder(const Fabric& f, double kappa, double angle) {
    const Vec3d axis{std::cos(angle), 0.0, std::sin(angle)}, across{-std::sin(angle), 0.0, std::cos(angle)};
    std::vector<Vec3d> x(f.vertex_count());
    for (std::size_t v = 0; v < x.size(); ++v) {
        const Vec3d p = f.rest_positions()[v];
        const double along = physics::dot(p, axis), u = physics::dot(p, across), phi = kappa * u;
        x[v] = along * axis + (std::sin(phi) / kappa) * across + Vec3d{0.0, (1.0 - std::cos(phi)) / kappa, 0.0};
    }
    return x;
}

TEST(MidEdgeNormals, AFlatOrRigidlyMovedSheetHoldsNoBendingEnergy) {
    const auto f = sheet(12, 0.4);
    std::vector<Vec3d> x(f->rest_positions().begin(), f->rest_positions().end());
    MidEdgeSolveReport report;
    EXPECT_EQ(bending_energy(*f, x, true, &report), 0.0);
    EXPECT_EQ(report.iterations, 0);  // nothing to relax
    // A rotation about a tilted axis and a shift.
    const double c = std::cos(0.7), s = std::sin(0.7);
    for (Vec3d& p : x) p = Vec3d{c * p.x - s * p.y + 0.3, s * p.x + c * p.y - 1.0, p.z + 2.0};
    EXPECT_LT(bending_energy(*f, x, true), 1e-18);
}

TEST(MidEdgeNormals, ACylinderCostsThePlateEnergyBentAboutAnyDirection) {
    const double size = 0.4, kappa = 2.0;
    const auto f = sheet(40, size);
    const double plate = 0.5 * kStiffness * kappa * kappa * size * size;
    for (const double angle : {0.0, 0.5 * std::acos(-1.0), 0.25 * std::acos(-1.0), 0.3}) {
        const std::vector<Vec3d> x = cylinder(*f, kappa, angle);
        MidEdgeSolveReport report;
        const double midedge = bending_energy(*f, x, true, &report) / plate;
        const double shell = bending_energy(*f, x, false) / plate;
        std::printf("cylinder about %.2f rad: mid-edge %.4f, shell %.4f of the plate energy (%d iterations)\n", angle, midedge, shell,
                    report.iterations);
        EXPECT_TRUE(report.converged);
        EXPECT_LT(report.iterations, 200) << "the normals' system is mass-like: few iterations at any size";
        // Within the sheet's edge effect (a free boundary row bends less: 1 − 1/40 on the axes).
        EXPECT_NEAR(midedge, 1.0, 0.04) << angle;
        if (std::abs(angle - 0.25 * std::acos(-1.0)) < 1e-9) {
            EXPECT_GT(shell, 1.4) << "the shell model's known excess about the diagonal";
        }
    }
}

// A clamp: the pinned triangles keep their edges' normals, so bending right at the clamp costs the
// whole fold (with the normals free, a pinned row of cells would turn its normals and hold no slope).
TEST(MidEdgeNormals, PinnedTrianglesHoldTheirEdgesNormals) {
    const auto f = sheet(12, 0.4);
    const std::vector<Vec3d> x = cylinder(*f, 2.0, 0.0);
    std::vector<char> pinned(f->vertex_count(), 0);
    const double free_energy = bending_energy(*f, x, true);
    for (std::size_t v = 0; v < pinned.size(); ++v) pinned[v] = f->rest_positions()[v].z < -0.15 ? 1 : 0;  // a row of cells
    const double clamped = bending_energy(*f, x, true, nullptr, &pinned);
    EXPECT_GT(clamped, 0.0);
    EXPECT_NE(clamped, free_energy) << "the pins reach the model";
}

}  // namespace
}  // namespace weft
