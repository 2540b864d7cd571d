// Does the bending model converge? A strip clamped at one end sags under its own weight to rest
// (CPU backend, double, Newton and CG converged), and its tip deflection is compared with the exact
// heavy elastica (tests/common/heavy_elastica.h) over loads from nearly straight to strongly bent,
// mesh refinements, and cell aspect ratios (cells stretched along the strip, square, stretched
// across). A bending model that converges gives errors that shrink with refinement whatever the
// aspect; the table shows whether this one does. Table on stdout, JSON with --json.
//
//   weft_bending_bench [--cells 12,24,48] [--aspect 0.5,1,2] [--load 0.5,2,6.6] [--json FILE]
//
// (96 cells along take minutes per row on a 2-core machine.)
//
// load: ρ·g·L³/D, the dimensionless weight against stiffness (0.5: nearly straight, 20: hanging).
// aspect: a cell's length along the strip over its width across.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "heavy_elastica.h"
#include "json_file.h"
#include "json_writer.h"
#include "strip_sweep_args.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace {

constexpr double kLength = 0.3, kWidth = 0.04, kDensity = 0.2, kGravity = 9.81;

struct Row {
    double load = 0.0;
    int cells_along = 0, cells_across = 0;
    double aspect = 0.0;  // the cells' actual length over width
    double deflection = 0.0, reference = 0.0, error = 0.0;
    /// At mid-length: the centreline's curvature along the strip and the cross-section's curvature
    /// across it (1/m, from the sagitta of its middle over the chord between its edges): a strip
    /// curling across as it bends (anticlastic curvature) shows a ratio away from 0.
    double curvature_along = 0.0, curvature_across = 0.0;
    double seconds = 0.0;
};

weft::Vec3d point(const std::vector<weft::Vec3d>& x, int nx, int i, int j) { return x[static_cast<std::size_t>(j * nx + i)]; }

/// Menger curvature of three points (1/m).
double menger(const weft::Vec3d& a, const weft::Vec3d& b, const weft::Vec3d& c) {
    const double ab = weft::math::length(b - a), bc = weft::math::length(c - b), ca = weft::math::length(a - c);
    const double area2 = weft::math::length(weft::math::cross(b - a, c - a));  // twice the triangle's area
    return ab * bc * ca > 0.0 ? 2.0 * area2 / (ab * bc * ca) : 0.0;
}


/// The strip at rest; returns its mean tip deflection (m).
Row simulate(double load, int cells_along, double aspect) {
    Row row;
    row.load = load;
    row.cells_along = cells_along;
    const double dx = kLength / cells_along;
    row.cells_across = std::max(2, static_cast<int>(std::lround(kWidth / (dx / aspect))));
    row.aspect = dx / (kWidth / row.cells_across);
    const double bending = kDensity * kGravity * kLength * kLength * kLength / load;
    weft::WorldDesc desc;
    desc.solver.dt = 1.0 / 24.0;
    desc.solver.newton_iterations = 3;
    desc.solver.cg_tolerance = 1e-8;
    desc.solver.cg_max_iterations = 5000;
    weft::World world(desc);
    auto fabric = weft::Fabric::cook(weft::make_grid(kLength, kWidth, cells_along, row.cells_across, weft::GridPlane::XZ),
                                     {.density = kDensity});
    weft::ClothDesc c{.name = "strip", .fabric = fabric};
    c.material.stretch_stiffness = 1e6;  // effectively inextensible, as the elastica assumes
    c.material.poisson_ratio = 0.0;      // no anticlastic coupling in a narrow strip
    c.material.bending_stiffness = bending;
    c.material.damping_mass = 5.0;
    const int nx = cells_along + 1;
    // The clamp: the first two columns (the second holds the slope), as in the cantilever test.
    for (int j = 0; j <= row.cells_across; ++j)
        for (int i = 0; i < 2; ++i) c.pins.push_back({static_cast<std::uint32_t>(j * nx + i), -1});
    world.add_cloth(c);
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < 400; ++i) (void)world.step();
    row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const auto x = world.positions(0);
    double tip = 0.0;
    for (int j = 0; j <= row.cells_across; ++j) tip += x[static_cast<std::size_t>(j * nx + cells_along)].y;
    row.deflection = -tip / (row.cells_across + 1);
    // The shape at mid-length.
    const int mid = cells_along / 2, step = std::max(1, cells_along / 8);
    const auto centre = [&](int i) {
        weft::Vec3d sum{};
        for (int j = 0; j <= row.cells_across; ++j) sum = sum + point(x, nx, i, j);
        return sum * (1.0 / (row.cells_across + 1));
    };
    row.curvature_along = menger(centre(mid - step), centre(mid), centre(mid + step));
    const weft::Vec3d edge0 = point(x, nx, mid, 0), edge1 = point(x, nx, mid, row.cells_across);
    weft::Vec3d middle = (point(x, nx, mid, row.cells_across / 2) + point(x, nx, mid, (row.cells_across + 1) / 2)) * 0.5;
    const weft::Vec3d chord = edge1 - edge0;
    const double chord_length = weft::math::length(chord);
    const double sagitta = weft::math::length(weft::math::cross(middle - edge0, chord)) / chord_length;
    row.curvature_across = 8.0 * sagitta / (chord_length * chord_length);
    // The clamp ends at the second column: the free length is L − dx.
    row.reference = weft::test::heavy_elastica_deflection(load / (kLength * kLength * kLength), kLength - dx);
    row.error = (row.deflection - row.reference) / row.reference;
    return row;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const weft::bench::StripSweep sweep = weft::bench::parse_strip_sweep(argc, argv);
        std::vector<Row> rows;
        std::printf("| load ρgL³/D | cells along × across | cell aspect | tip deflection m | heavy elastica m | error | "
                    "curvature across / along at mid-length | s |\n");
        std::printf("|---|---|---|---|---|---|---|---|\n");
        for (const double load : sweep.loads)
            for (const double aspect : sweep.aspects)
                for (const double n : sweep.cells) {
                    const Row r = simulate(load, static_cast<int>(n), aspect);
                    std::printf("| %.2g | %d × %d | %.2f | %.5f | %.5f | %+.2f%% | %.3f | %.1f |\n", r.load, r.cells_along,
                                r.cells_across, r.aspect, r.deflection, r.reference, 100.0 * r.error,
                                r.curvature_along > 0.0 ? r.curvature_across / r.curvature_along : 0.0, r.seconds);
                    std::fflush(stdout);
                    rows.push_back(r);
                }
        if (!sweep.json.empty() &&
            !weft::bench::write_json_file(sweep.json, "weft_bending_bench", [&](std::ostream& out) {
                weft::json::JsonWriter json(out);
                json.begin_array();
                for (const Row& r : rows)
                    json.begin_object()
                        .field("load", r.load)
                        .field("cells_along", r.cells_along)
                        .field("cells_across", r.cells_across)
                        .field("aspect", r.aspect)
                        .field("deflection_m", r.deflection)
                        .field("elastica_m", r.reference)
                        .field("error", r.error)
                        .field("curvature_along", r.curvature_along)
                        .field("curvature_across", r.curvature_across)
                        .field("seconds", r.seconds)
                        .end_object();
                json.end_array();
            }))
            return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "weft_bending_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
