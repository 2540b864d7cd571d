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
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "heavy_elastica.h"
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
    double seconds = 0.0;
};

std::vector<double> parse_list(const std::string& flag, const std::string& value) {
    std::vector<double> out;
    std::size_t at = 0;
    while (at <= value.size()) {
        const std::size_t comma = value.find(',', at);
        const std::string item = value.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
        try {
            std::size_t used = 0;
            out.push_back(std::stod(item, &used));
            if (used != item.size() || !(out.back() > 0.0)) throw std::invalid_argument(item);
        } catch (const std::exception&) {
            throw weft::Error(flag + ": '" + item + "' is not a positive number (e.g. " + flag + " 1,2)");
        }
        if (comma == std::string::npos) break;
        at = comma + 1;
    }
    return out;
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
    // The clamp ends at the second column: the free length is L − dx.
    row.reference = weft::test::heavy_elastica_deflection(load / (kLength * kLength * kLength), kLength - dx);
    row.error = (row.deflection - row.reference) / row.reference;
    return row;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        std::vector<double> cells{12, 24, 48}, aspects{0.5, 1.0, 2.0}, loads{0.5, 2.0, 6.6};
        std::string json;
        for (int i = 1; i < argc; ++i) {
            const std::string flag = argv[i];
            if (i + 1 >= argc) throw weft::Error(flag + " needs a value");
            const std::string value = argv[++i];
            if (flag == "--cells")
                cells = parse_list(flag, value);
            else if (flag == "--aspect")
                aspects = parse_list(flag, value);
            else if (flag == "--load")
                loads = parse_list(flag, value);
            else if (flag == "--json")
                json = value;
            else
                throw weft::Error("unknown option '" + flag + "' (--cells, --aspect, --load, --json)");
        }
        std::vector<Row> rows;
        std::printf("| load ρgL³/D | cells along × across | cell aspect | tip deflection m | heavy elastica m | error | s |\n");
        std::printf("|---|---|---|---|---|---|---|\n");
        for (const double load : loads)
            for (const double aspect : aspects)
                for (const double n : cells) {
                    const Row r = simulate(load, static_cast<int>(n), aspect);
                    std::printf("| %.2g | %d × %d | %.2f | %.5f | %.5f | %+.2f%% | %.1f |\n", r.load, r.cells_along, r.cells_across,
                                r.aspect, r.deflection, r.reference, 100.0 * r.error, r.seconds);
                    std::fflush(stdout);
                    rows.push_back(r);
                }
        if (!json.empty()) {
            std::ofstream out(json);
            if (!out) throw weft::Error("--json: cannot write " + json);
            out << "[\n";
            for (std::size_t k = 0; k < rows.size(); ++k) {
                const Row& r = rows[k];
                out << "  {\"load\": " << r.load << ", \"cells_along\": " << r.cells_along << ", \"cells_across\": " << r.cells_across
                    << ", \"aspect\": " << r.aspect << ", \"deflection_m\": " << r.deflection << ", \"elastica_m\": " << r.reference
                    << ", \"error\": " << r.error << ", \"seconds\": " << r.seconds << "}" << (k + 1 < rows.size() ? "," : "") << "\n";
            }
            out << "]\n";
            if (!out) throw weft::Error("--json: cannot write " + json);
            std::printf("results: %s\n", json.c_str());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "weft_bending_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
