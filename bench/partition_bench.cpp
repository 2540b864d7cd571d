// How well the multi-GPU vertex partition cuts a scene (weft/backend/vertex_partition.h): the cut
// along the preconditioner's Morton order (what the solver uses) against METIS's k-way partition of
// the same pattern graph where METIS was found at configure time. Per part count: cut blocks, halo
// and boundary vertices, the imbalance of the row work, the bytes one product's halo exchange moves
// (float3 per ghost) and the time to build; and the cut along the order with the bending model per
// triangle's deeper reach (its ghosts). A table on stdout, JSON with --json.
//
// With --cg, also what the cut does to the multilevel Schwarz preconditioner if no level crossed it
// (each part's preconditioner built on its own rows, no communication): CG iterations (CPU, double)
// on a stiff SPD matrix of the scene's pattern, m·I + k·L ⊗ I₃ with k/m = 1000 (cloth's k·h²/m
// regime), against the whole preconditioner and block-Jacobi.
//
//   weft_partition_bench SCENE.toml [--set key=value ...] [--parts 2,4,8] [--cg] [--json FILE]
#include <chrono>
#include <random>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "cpu/bsr_matrix.h"
#include "cpu/pcg.h"
#include "cpu/schwarz_preconditioner.h"
#include "part_counts.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/backend/vertex_partition.h"
#include "weft/error.h"
#include "weft/scene.h"
#include "weft/world.h"

#if WEFT_HAVE_METIS
#include <metis.h>
#endif

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

struct Row {
    std::string method;
    std::uint32_t parts = 0;
    weft::PartitionQuality quality;
    double build_ms = 0.0;
};

#if WEFT_HAVE_METIS
/// METIS k-way on the pattern's graph (diagonal blocks dropped), vertex weights the row work.
std::vector<std::uint32_t> metis_parts(const weft::BlockPattern& pattern, std::uint32_t parts) {
    auto n = static_cast<idx_t>(pattern.row_start.size() - 1);  // METIS takes every argument by pointer
    std::vector<idx_t> xadj(static_cast<std::size_t>(n) + 1, 0), adjncy, vwgt(static_cast<std::size_t>(n));
    for (idx_t i = 0; i < n; ++i) {
        const auto row = static_cast<std::size_t>(i);
        for (std::uint32_t s = pattern.row_start[row]; s < pattern.row_start[row + 1]; ++s)
            if (pattern.column[s] != row) adjncy.push_back(static_cast<idx_t>(pattern.column[s]));
        xadj[row + 1] = static_cast<idx_t>(adjncy.size());
        vwgt[row] = static_cast<idx_t>(pattern.row_start[row + 1] - pattern.row_start[row]);
    }
    idx_t constraints = 1, k = static_cast<idx_t>(parts), cut = 0;
    idx_t options[METIS_NOPTIONS];
    METIS_SetDefaultOptions(options);
    options[METIS_OPTION_SEED] = 1;  // the same cut on every run
    std::vector<idx_t> part(static_cast<std::size_t>(n), 0);
    if (parts > 1 && METIS_PartGraphKway(&n, &constraints, xadj.data(), adjncy.data(), vwgt.data(), nullptr, nullptr, &k,
                                         nullptr, nullptr, options, &cut, part.data()) != METIS_OK)
        throw weft::Error("METIS_PartGraphKway failed for " + std::to_string(parts) + " parts");
    return {part.begin(), part.end()};
}
#endif

using V3 = weft::physics::Vec3<double>;
using M3 = weft::physics::Mat3<double>;

/// m·I + k·L ⊗ I₃ on `pattern` (L the pattern's graph Laplacian).
weft::cpu::BsrMatrix<double> stiff_laplacian(const weft::BlockPattern& pattern, double mass, double k) {
    weft::cpu::BsrMatrix<double> A;
    A.resize(pattern);
    for (std::size_t i = 0; i + 1 < pattern.row_start.size(); ++i) {
        double degree = 0.0;
        for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s)
            if (pattern.column[s] != i) {
                A.set_block(s, M3::diagonal(-k));
                degree += 1.0;
            }
        A.set_block(pattern.diagonal[i], M3::diagonal(mass + k * degree));
    }
    return A;
}

/// `pattern` without the blocks between different parts (the triangle and hinge slot maps are not
/// carried: only the rows are used).
weft::BlockPattern cut_pattern(const weft::BlockPattern& pattern, const std::vector<std::uint32_t>& part_of) {
    weft::BlockPattern out;
    out.row_start.push_back(0);
    for (std::size_t i = 0; i + 1 < pattern.row_start.size(); ++i) {
        for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s) {
            if (part_of[pattern.column[s]] != part_of[i]) continue;
            if (s == pattern.diagonal[i]) out.diagonal.push_back(static_cast<std::uint32_t>(out.column.size()));
            out.column.push_back(pattern.column[s]);
        }
        out.row_start.push_back(static_cast<std::uint32_t>(out.column.size()));
    }
    return out;
}

/// CG iterations to 1e-6 with the multilevel Schwarz preconditioner built on `pattern` (the whole
/// pattern, or a cut one) for the system `A` of the whole pattern.
int schwarz_iterations(const weft::FlatModel& flat, const weft::cpu::BsrMatrix<double>& A, const weft::BlockPattern& pattern,
                       const std::vector<V3>& b) {
    const std::size_t n = flat.vertex_count;
    weft::cpu::BsrMatrix<double> restricted = stiff_laplacian(pattern, 1e-3, 1.0);  // the same values where kept
    const weft::SchwarzHierarchy h = weft::build_schwarz_hierarchy(flat.initial_positions, pattern);
    weft::cpu::SchwarzPreconditioner<double> M;
    M.build(h, pattern);
    const std::vector<std::uint8_t> fixed(n, 0);
    M.factor(restricted, fixed, [](std::size_t) { return M3{}; });
    weft::cpu::Pcg<double> pcg;
    pcg.resize(n);
    std::vector<V3> x(n);
    const auto r = pcg.solve(A, b, fixed, x, 1e-6, 20000, &M);
    return r.converged ? r.iterations : -r.iterations;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2) {
            std::cerr << "usage: weft_partition_bench SCENE.toml [--set key=value ...] [--parts 2,4,8] [--cg] [--json FILE]\n";
            return 2;
        }
        std::vector<std::string> overrides;
        std::vector<std::uint32_t> counts{2, 4, 8};
        std::string json_path;
        bool cg = false;
        for (int a = 2; a < argc; ++a) {
            const std::string arg = argv[a];
            if (arg == "--cg") {
                cg = true;
                continue;
            }
            if (a + 1 >= argc) throw weft::Error("'" + arg + "' needs a value");
            if (arg == "--set") overrides.emplace_back(argv[++a]);
            else if (arg == "--parts") counts = weft::bench::parse_part_counts(argv[++a], 4096);
            else if (arg == "--json") json_path = argv[++a];
            else throw weft::Error("unknown argument '" + arg + "'");
        }
        const weft::SceneDesc scene = weft::load_scene(argv[1], overrides);
        const auto world = weft::build_world(scene, "cpu");
        auto clock = Clock::now();
        const weft::FlatModel flat = weft::flatten(world->model());
        const weft::SchwarzHierarchy hierarchy = weft::build_schwarz_hierarchy(flat.initial_positions, flat.pattern);
        const double prepare_ms = ms_since(clock);
        const std::vector<double> work = weft::row_work(flat.pattern);
        std::printf("%s: %zu vertices, %zu triangles, %zu pattern blocks (flatten and preconditioner order %.0f ms)\n",
                    argv[1], flat.vertex_count, flat.triangle_count(), flat.pattern.block_count(), prepare_ms);

        std::vector<Row> rows;
        for (const std::uint32_t parts : counts) {
            clock = Clock::now();
            const auto order_cut = weft::cut_order(hierarchy.order, work, parts, weft::SchwarzHierarchy::kDomainSize);
            const weft::VertexPartition by_order = weft::build_partition(flat.pattern, order_cut, parts, work);
            rows.push_back({"preconditioner order", parts, by_order.quality, ms_since(clock)});
            // The same cut for solver.bending = "shell": the per-triangle model's reach as ghosts too.
            clock = Clock::now();
            const weft::VertexReach reach = weft::per_triangle_bending_reach(flat);
            const weft::VertexPartition with_reach = weft::build_partition(flat.pattern, order_cut, parts, work, &reach);
            rows.push_back({"preconditioner order, shell bending's reach", parts, with_reach.quality, ms_since(clock)});
#if WEFT_HAVE_METIS
            clock = Clock::now();
            const auto metis_cut = metis_parts(flat.pattern, parts);
            const weft::VertexPartition by_metis = weft::build_partition(flat.pattern, metis_cut, parts, work);
            rows.push_back({"METIS k-way", parts, by_metis.quality, ms_since(clock)});
#endif
        }
#if !WEFT_HAVE_METIS
        std::printf("(METIS not found at configure time: libmetis-dev; only the preconditioner order is measured)\n");
#endif
        std::printf("| method | parts | cut blocks | halo vertices | boundary vertices | imbalance | halo KB per product | build ms |\n");
        std::printf("|---|---|---|---|---|---|---|---|\n");
        for (const Row& r : rows)
            std::printf("| %s | %u | %llu | %llu | %llu | %.3f | %.1f | %.0f |\n", r.method.c_str(), r.parts,
                        static_cast<unsigned long long>(r.quality.cut_blocks),
                        static_cast<unsigned long long>(r.quality.halo_vertices),
                        static_cast<unsigned long long>(r.quality.boundary_vertices), r.quality.imbalance,
                        12.0 * static_cast<double>(r.quality.halo_vertices) / 1024.0, r.build_ms);
        int jacobi_iterations = 0, whole_iterations = 0;
        std::vector<std::pair<std::uint32_t, int>> per_part_iterations;
        if (cg) {
            // The stiff system, the whole preconditioner, block-Jacobi, then each cut's.
            const weft::cpu::BsrMatrix<double> A = stiff_laplacian(flat.pattern, 1e-3, 1.0);
            std::mt19937 rng(11);
            std::uniform_real_distribution<double> u(-1.0, 1.0);
            std::vector<V3> b(flat.vertex_count);
            for (V3& v : b) v = {u(rng), u(rng), u(rng)};
            weft::cpu::Pcg<double> pcg;
            pcg.resize(flat.vertex_count);
            std::vector<V3> x(flat.vertex_count);
            const auto jacobi = pcg.solve(A, b, std::vector<std::uint8_t>(flat.vertex_count, 0), x, 1e-6, 20000);
            jacobi_iterations = jacobi.converged ? jacobi.iterations : -jacobi.iterations;
            whole_iterations = schwarz_iterations(flat, A, flat.pattern, b);
            std::printf("\nCG iterations to 1e-6 (negative: not converged), m·I + k·L with k/m = 1000: block-Jacobi %d, "
                        "the whole multilevel Schwarz preconditioner %d\n",
                        jacobi_iterations, whole_iterations);
            std::printf("| parts | Schwarz built on each part's rows (no level crosses a cut) |\n|---|---|\n");
            for (const std::uint32_t parts : counts) {
                const auto part_of = weft::cut_order(hierarchy.order, work, parts, weft::SchwarzHierarchy::kDomainSize);
                per_part_iterations.emplace_back(parts, schwarz_iterations(flat, A, cut_pattern(flat.pattern, part_of), b));
                std::printf("| %u | %d |\n", parts, per_part_iterations.back().second);
            }
        }
        if (!json_path.empty()) {
            std::ofstream json(json_path);
            json << "{\"scene\": \"" << argv[1] << "\", \"vertices\": " << flat.vertex_count << ", \"rows\": [";
            for (std::size_t k = 0; k < rows.size(); ++k) {
                const Row& r = rows[k];
                json << (k ? ", " : "") << "{\"method\": \"" << r.method << "\", \"parts\": " << r.parts
                     << ", \"cut_blocks\": " << r.quality.cut_blocks << ", \"halo_vertices\": " << r.quality.halo_vertices
                     << ", \"boundary_vertices\": " << r.quality.boundary_vertices << ", \"imbalance\": " << r.quality.imbalance
                     << ", \"build_ms\": " << r.build_ms << "}";
            }
            json << "]";
            if (cg) {
                json << ", \"cg_iterations\": {\"block_jacobi\": " << jacobi_iterations << ", \"schwarz_whole\": " << whole_iterations
                     << ", \"schwarz_per_part\": {";
                for (std::size_t k = 0; k < per_part_iterations.size(); ++k)
                    json << (k ? ", " : "") << "\"" << per_part_iterations[k].first << "\": " << per_part_iterations[k].second;
                json << "}}";
            }
            json << "}\n";
            if (!json) throw weft::Error("cannot write '" + json_path + "'");
        }
        return 0;
    } catch (const std::exception& e) {
        std::cerr << "weft_partition_bench: " << e.what() << "\n";
        return 1;
    }
}
