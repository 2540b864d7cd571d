// GPU collision detection benchmark (cuda/src/collision/): the broad phase stage by stage, the
// proximity contacts and the CCD on two procedural scenes of about 200K triangles, timed with CUDA
// events (median of the timed runs after warm-up), with and without normal-cone culling (patch ids
// computed on the device every run by GpuNormalConeCulling, whose own time is reported), and the CPU
// broad phase (with the CPU NormalConeFront's patch ids) on the same state for reference.
//   twist  a 317×317-vertex sheet at 1 cm (199,712 triangles) twisted about the axis through the
//          midpoints of two opposite edges, which turn at π/3 rad/s in opposite directions (the
//          normal-cone tests' twist field), at t = 3 s, one step of 10 ms, lightly crumpled
//   stack  8 wavy 112×112 sheets (197,136 triangles) 6 mm apart, falling and sliding during the step
//
//   build/bin/weft_cuda_collision_bench
//   build/bin/weft_cuda_collision_bench --runs 50 --json out/collision.json --scenes twist
//
// Without a GPU it prints "no CUDA device: REASON" and exits 0.
#include <cuda_runtime_api.h>
#include <tbb/info.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "build_info.h"
#include "collision/broad_phase.h"
#include "collision/broad_phase_gpu.h"
#include "collision/ccd_gpu.h"
#include "collision/normal_cone_front.h"
#include "collision/normal_cone_gpu.h"
#include "weft/backend/patch_hierarchy.h"
#include "collision/proximity_gpu.h"
#include "cuda_check.h"
#include "device_array.h"
#include "distribution.h"
#include "float_positions.h"
#include "json_file.h"
#include "json_writer.h"
#include "random_geometry.h"
#include "text_table.h"
#include "weft/backend/timing.h"
#include "weft/cuda/cuda_backend.h"
#include "weft/error.h"

namespace {

using namespace weft;
namespace gpu = weft::cuda::collision;
using cli::format_fixed;
using cli::TextTable;
using json::JsonWriter;
using Clock = std::chrono::steady_clock;
constexpr double kPi = std::numbers::pi;

// ---- options --------------------------------------------------------------------------------------

struct Options {
    std::vector<std::string> scenes{"twist", "stack"};
    int runs = 30;
    int warmup = 5;
    int twist_n = 317;
    double thickness = 0.005;
    double eta_ratio = 0.1;
    std::filesystem::path json_file;
};

constexpr const char* kUsage = R"(Usage: weft_cuda_collision_bench [options]

GPU collision detection: broad-phase stages, proximity contacts and CCD (ms, CUDA events, median of the
timed runs), pairs found with and without normal-cone culling, and the CPU broad phase for reference.

Options:
  --scenes LIST     comma-separated: twist, stack (default both)
  --runs N          timed runs per configuration (at least 20 recommended); default 30
  --warmup N        untimed runs first; default 5
  --twist-n N       vertices per side of the twist sheet; default 317 (199,712 triangles)
  --thickness M     contact thickness, m; default 0.005
  --eta-ratio R     CCD separation as a fraction of the thickness; default 0.1
  --json FILE       write every number as JSON
  -h, --help        this text
)";

[[noreturn]] void usage_error(const std::string& message) {
    std::cerr << "weft_cuda_collision_bench: " << message << "\n(--help lists the options)\n";
    std::exit(2);
}

Options parse_options(int argc, char** argv) {
    Options o;
    auto need = [&](int& i) -> std::string {
        if (i + 1 >= argc) usage_error(std::string(argv[i]) + " needs a value");
        return argv[++i];
    };
    auto number = [&](const std::string& text, const char* what) {
        try {
            std::size_t used = 0;
            const double v = std::stod(text, &used);
            if (used != text.size() || !std::isfinite(v) || v < 0.0) throw std::invalid_argument(text);
            return v;
        } catch (const std::exception&) {
            usage_error(std::string(what) + " expects a non-negative number, got '" + text + "'");
        }
    };
    auto integer = [&](const std::string& text, const char* what, int min) {
        const double v = number(text, what);
        if (v < min || v > INT_MAX || v != std::floor(v)) usage_error(std::string(what) + " expects an integer >= " + std::to_string(min));
        return static_cast<int>(v);
    };
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "-h" || a == "--help") {
            std::cout << kUsage;
            std::exit(0);
        } else if (a == "--scenes") {
            o.scenes.clear();
            std::istringstream in(need(i));
            for (std::string s; std::getline(in, s, ',');) {
                if (s != "twist" && s != "stack") usage_error("unknown scene '" + s + "'");
                o.scenes.push_back(s);
            }
        } else if (a == "--runs") {
            o.runs = integer(need(i), "--runs", 1);
        } else if (a == "--warmup") {
            o.warmup = integer(need(i), "--warmup", 1);
        } else if (a == "--twist-n") {
            o.twist_n = integer(need(i), "--twist-n", 3);
        } else if (a == "--thickness") {
            o.thickness = number(need(i), "--thickness");
        } else if (a == "--eta-ratio") {
            o.eta_ratio = number(need(i), "--eta-ratio");
        } else if (a == "--json") {
            o.json_file = need(i);
        } else {
            usage_error("unknown option '" + a + "'");
        }
    }
    return o;
}

// ---- scenes ---------------------------------------------------------------------------------------

struct Scene {
    std::string name;
    std::vector<Vec3d> rest, x0, x1;
    std::vector<Triangle> triangles;
    std::vector<collision::Edge> edges;
    std::vector<std::uint32_t> triangle_cloth;
};

/// Appends an nx × ny grid of spacing h, placed by `place(u, w, t)` (plane coordinates centred on 0)
/// at t = 0 (x0) and t = 1 (x1); rest positions flat.
void add_grid(Scene& s, int nx, int ny, double h, std::uint32_t cloth,
              const std::function<Vec3d(double, double, int)>& place) {
    const auto base = static_cast<std::uint32_t>(s.x0.size());
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const double u = (i - 0.5 * (nx - 1)) * h, w = (j - 0.5 * (ny - 1)) * h;
            s.rest.push_back({u, w, 0.0});
            s.x0.push_back(place(u, w, 0));
            s.x1.push_back(place(u, w, 1));
        }
    const auto id = [&](int i, int j) { return base + static_cast<std::uint32_t>(j * nx + i); };
    for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
            s.triangles.push_back({{id(i, j), id(i + 1, j), id(i + 1, j + 1)}});
            s.triangles.push_back({{id(i, j), id(i + 1, j + 1), id(i, j + 1)}});
            s.triangle_cloth.push_back(cloth);
            s.triangle_cloth.push_back(cloth);
        }
}

/// Smooth random displacement (random_geometry.h): four sinusoids of wavelengths within ±30 % of
/// `wavelength` (m) and amplitudes up to `amplitude` (m) per coordinate.
test::SmoothField field(std::mt19937& rng, double amplitude, double wavelength) {
    return {rng, amplitude, 0.7 * wavelength, 1.3 * wavelength};
}

using test::snap_to_float;

Scene twist_scene(int n) {
    Scene s;
    s.name = "twist";
    std::mt19937 rng(1);
    const test::SmoothField f0 = field(rng, 0.0005, 0.08), f1 = field(rng, 0.0005, 0.08);
    const double L = (n - 1) * 0.01, t = 3.0, dt = 0.01;
    add_grid(s, n, n, 0.01, 0, [&](double x, double y, int step) {
        const double phi = kPi / 3.0 * (t + step * dt) * (2.0 * x / L);
        const Vec3d d = (step == 0 ? f0 : f1).at(x, y);
        const double yy = y + d.y, zz = d.z;
        return Vec3d{x + d.x, yy * std::cos(phi) - zz * std::sin(phi), yy * std::sin(phi) + zz * std::cos(phi)};
    });
    s.edges = collision::build_edges(s.triangles);
    snap_to_float(s);
    return s;
}

Scene stack_scene() {
    Scene s;
    s.name = "stack";
    constexpr int kSheets = 8, kN = 112;
    std::mt19937 rng(2);
    for (int k = 0; k < kSheets; ++k) {
        // Layers 6 mm apart (just above the 5 mm contact thickness, as a settled stack rests) with waves
        // of ±1 mm; during the step each layer slides up to 2 mm, its waves travel with it, and it
        // falls 2 mm plus 0.3 mm per layer (the stack settling).
        const test::SmoothField f = field(rng, 0.001, 0.25);
        std::uniform_real_distribution<double> slide(-0.002, 0.002);
        const double sx = slide(rng), sy = slide(rng), off = 0.0033 * k;
        add_grid(s, kN, kN, 0.01, static_cast<std::uint32_t>(k), [&, sx, sy, off, k](double x, double y, int step) {
            const Vec3d d = f.at(x, y);
            return Vec3d{x + off + step * sx, y + off + step * sy, 0.006 * k + d.z - step * (0.002 + 0.0003 * k)};
        });
    }
    s.edges = collision::build_edges(s.triangles);
    snap_to_float(s);
    return s;
}

// ---- statistics -----------------------------------------------------------------------------------

using bench::Dist;
using bench::distribution;
using bench::write_dist;
// The file's layout: no mean (the medians are what the tables compare).
constexpr auto kDistFields = bench::DistFields::median_min_max;

// ---- measurement ----------------------------------------------------------------------------------

struct Event {
    cudaEvent_t e = nullptr;
    Event() { WEFT_CUDA_CHECK(cudaEventCreate(&e)); }
    ~Event() { cudaEventDestroy(e); }
    Event(const Event&) = delete;
    Event& operator=(const Event&) = delete;
};

/// One configuration (scene, with or without culling).
struct Result {
    std::string scene, culling;
    std::size_t vertices = 0, edges = 0, triangles = 0;
    gpu::GpuBroadPhaseCounters counters{};
    std::uint32_t contacts = 0, ccd_tests = 0, ccd_box_rejected = 0, ccd_hits = 0, ccd_conservative = 0;
    std::array<Dist, gpu::GpuBroadPhase::kStageCount> stage{};
    Dist broad, proximity, ccd, wall;
    std::size_t memory = 0;
    int reruns = 0;
    double cpu_ms = 0.0;  ///< CPU broad phase, median of a few warm calls
    std::size_t cpu_pairs = 0, cpu_culled = 0;
    std::size_t patches = 0;      ///< normal-cone patches of the GPU ids (the device's front)
    std::size_t cpu_patches = 0;  ///< of the CPU's NormalConeFront::rebuild on the same state
    double cpu_front_ms = 0.0;    ///< that rebuild (refit + front + ids), median of a few calls
    Dist cones;                   ///< GPU normal-cone pass (refit, tests, ids) per call, ms
    gpu::GpuNormalConeCounters cone_counters{};
};

using test::soa_floats;

Result measure(const Options& opt, const Scene& s, bool cull, cudaStream_t stream) {
    Result r;
    r.scene = s.name;
    r.culling = cull ? "normal cones" : "none";
    r.vertices = s.x0.size();
    r.edges = s.edges.size();
    r.triangles = s.triangles.size();
    const std::size_t n = s.x0.size();

    // The hierarchy (once per topology), and the CPU front's patch ids for the CPU reference; the GPU
    // broad phase below takes the ids the device computes itself.
    collision::PatchHierarchy h;
    std::vector<std::uint32_t> vp, ep, tp;
    if (cull) {
        h = collision::build_patch_hierarchy(s.rest, s.triangles, s.edges, s.triangle_cloth);
        collision::NormalConeFront front(h);
        std::vector<double> ms;
        for (int k = 0; k < 3; ++k) {
            const auto t0 = Clock::now();
            front.rebuild(s.x0, s.x1);
            ms.push_back(ms_since(t0));
        }
        r.cpu_front_ms = distribution(ms).median;
        vp.assign(front.vertex_patch().begin(), front.vertex_patch().end());
        ep.assign(front.edge_patch().begin(), front.edge_patch().end());
        tp.assign(front.triangle_patch().begin(), front.triangle_patch().end());
        r.cpu_patches = front.front().size();
    }

    // CPU reference: same state, same filters.
    {
        collision::BroadPhase cpu;
        collision::BroadPhaseResult out;
        collision::BroadPhaseInput in{.x0 = s.x0, .x1 = s.x1, .triangles = s.triangles, .edges = s.edges,
                                      .thickness = opt.thickness};
        in.vertex_patch = vp;
        in.edge_patch = ep;
        in.triangle_patch = tp;
        in.count_culled = true;
        std::vector<double> ms;
        for (int k = 0; k < 3; ++k) {
            const auto t0 = Clock::now();
            cpu.find(in, out);
            if (k > 0) ms.push_back(ms_since(t0));
        }
        r.cpu_ms = distribution(ms).median;
        r.cpu_pairs = out.vf.size() + out.ee.size();
        r.cpu_culled = out.counters.culled_pairs;
    }

    // Device data.
    cuda::MemoryLedger ledger;
    cuda::DeviceArray<float> x0, x1, inverse_mass, thickness, friction;
    cuda::DeviceArray<std::uint32_t> tri, edge;
    x0.upload(soa_floats(s.x0), ledger, "x0");
    x1.upload(soa_floats(s.x1), ledger, "x1");
    inverse_mass.upload(std::vector<float>(n, 1.0F), ledger, "inverse mass");
    thickness.upload(std::vector<float>(n, static_cast<float>(opt.thickness)), ledger, "thickness");
    friction.upload(std::vector<float>(n, 0.3F), ledger, "friction");
    std::vector<std::uint32_t> t, e;
    for (const Triangle& x : s.triangles) t.insert(t.end(), x.v, x.v + 3);
    for (const collision::Edge& x : s.edges) e.insert(e.end(), x.v, x.v + 2);
    tri.upload(t, ledger, "triangles");
    edge.upload(e, ledger, "edges");
    gpu::GpuNormalConeCulling cones;
    if (cull) {
        gpu::GpuNormalConeLayout layout;
        layout.vertex_count = layout.cloth_vertices = static_cast<std::uint32_t>(n);
        layout.edge_count = layout.cloth_edges = static_cast<std::uint32_t>(s.edges.size());
        layout.triangle_count = layout.cloth_triangles = static_cast<std::uint32_t>(s.triangles.size());
        cones.build(h, layout);
    }

    gpu::GpuBroadPhaseInput bin;
    bin.x0 = x0.get();
    bin.x1 = x1.get();
    bin.vertex_count = static_cast<std::uint32_t>(n);
    bin.triangles = tri.get();
    bin.triangle_count = static_cast<std::uint32_t>(s.triangles.size());
    bin.edges = edge.get();
    bin.edge_count = static_cast<std::uint32_t>(s.edges.size());
    bin.thickness = opt.thickness;
    if (cull) {
        bin.vertex_patch = cones.vertex_patch();
        bin.edge_patch = cones.edge_patch();
        bin.triangle_patch = cones.triangle_patch();
    }
    gpu::GpuProximityInput pin;
    pin.x0 = x0.get();
    pin.x1 = x1.get();
    pin.vertex_count = bin.vertex_count;
    pin.inverse_mass = inverse_mass.get();
    pin.thickness = thickness.get();
    pin.friction = friction.get();
    pin.triangles = tri.get();
    pin.edges = edge.get();
    pin.h = 1.0F / 240.0F;
    gpu::GpuCcdInput cin;
    cin.x0 = x0.get();
    cin.x1 = x1.get();
    cin.vertex_count = bin.vertex_count;
    cin.inverse_mass = inverse_mass.get();
    cin.triangles = tri.get();
    cin.edges = edge.get();
    cin.eta = static_cast<float>(opt.eta_ratio * opt.thickness);

    gpu::GpuBroadPhase bp;
    gpu::GpuProximityContacts prox;
    gpu::GpuCcd ccd;
    // Warm-up: sizes settle (first-use allocation, reruns), caches and clocks warm up.
    for (int k = 0; k < opt.warmup; ++k) {
        if (cull) cones.enqueue(bin.x0, bin.x1, bin.vertex_count, stream);
        bp.find(bin, stream);
        prox.find(pin, bp.pairs(), stream);
        ccd.find(cin, bp.pairs(), stream);
    }
    r.reruns = bp.reruns();
    bp.set_stage_timing(true);
    Event before_cones, start, after_broad, after_proximity, after_ccd;
    std::vector<std::vector<double>> stage(gpu::GpuBroadPhase::kStageCount);
    std::vector<double> cone_ms, broad, proximity, narrow, wall;
    for (int k = 0; k < opt.runs; ++k) {
        const auto t0 = Clock::now();
        WEFT_CUDA_CHECK(cudaEventRecord(before_cones.e, stream));
        // The patch ids of this state, on the device, right before the broad phase that reads them.
        if (cull) cones.enqueue(bin.x0, bin.x1, bin.vertex_count, stream);
        WEFT_CUDA_CHECK(cudaEventRecord(start.e, stream));
        bp.enqueue(bin, stream);
        WEFT_CUDA_CHECK(cudaEventRecord(after_broad.e, stream));
        prox.enqueue(pin, bp.pairs(), stream);
        WEFT_CUDA_CHECK(cudaEventRecord(after_proximity.e, stream));
        ccd.enqueue(cin, bp.pairs(), stream);
        WEFT_CUDA_CHECK(cudaEventRecord(after_ccd.e, stream));
        // The one synchronisation of a step: the counters (overflow checks) of all three.
        const gpu::GpuBroadPhaseCounters& c = bp.read_back(stream);
        prox.read_back(stream);
        ccd.read_back(stream);
        wall.push_back(ms_since(t0));
        if (c.overflow != 0 || prox.counters().overflow != 0 || ccd.counters().overflow != 0)
            throw Error("a buffer overflowed after warm-up (the state does not change between runs)");
        const auto ms = bp.stage_ms();
        for (int st = 0; st < gpu::GpuBroadPhase::kStageCount; ++st) stage[st].push_back(ms[st]);
        float a = 0, b = 0, d = 0, q = 0;
        WEFT_CUDA_CHECK(cudaEventElapsedTime(&q, before_cones.e, start.e));
        WEFT_CUDA_CHECK(cudaEventElapsedTime(&a, start.e, after_broad.e));
        WEFT_CUDA_CHECK(cudaEventElapsedTime(&b, after_broad.e, after_proximity.e));
        WEFT_CUDA_CHECK(cudaEventElapsedTime(&d, after_proximity.e, after_ccd.e));
        if (cull) cone_ms.push_back(q);
        broad.push_back(a);
        proximity.push_back(b);
        narrow.push_back(d);
    }
    for (int st = 0; st < gpu::GpuBroadPhase::kStageCount; ++st) r.stage[st] = distribution(stage[st]);
    r.cones = distribution(cone_ms);
    r.broad = distribution(broad);
    r.proximity = distribution(proximity);
    r.ccd = distribution(narrow);
    r.wall = distribution(wall);
    r.counters = bp.counters();
    r.contacts = prox.counters().contacts;
    r.ccd_tests = ccd.counters().tests;
    r.ccd_box_rejected = ccd.counters().box_rejected;
    r.ccd_hits = ccd.counters().hits;
    r.ccd_conservative = ccd.counters().conservative;
    r.memory = bp.memory_bytes() + prox.memory_bytes() + ccd.memory_bytes() + cones.memory_bytes();
    if (cull) {
        r.cone_counters = cones.read_back(stream);
        r.patches = r.cone_counters.front_size;
    }
    return r;
}

// ---- output ---------------------------------------------------------------------------------------

void print(std::ostream& out, const std::vector<Result>& results) {
    using S = gpu::GpuBroadPhase;
    TextTable stages({{"scene", TextTable::Align::Left},
                      {"culling", TextTable::Align::Left},
                      {"AABB+count"},
                      {"patch order"},
                      {"scan"},
                      {"sort"},
                      {"cell ranges"},
                      {"pair gen"},
                      {"canonical"},
                      {"cones"},
                      {"broad total"},
                      {"proximity"},
                      {"CCD"},
                      {"wall"},
                      {"CPU broad"}});
    const auto f = [](double ms) { return format_fixed(ms, 3); };
    for (const Result& r : results) {
        const auto m = [&](int s) { return r.stage[static_cast<std::size_t>(s)].median; };
        stages.add_row({r.scene, r.culling, f(m(S::Bounds) + m(S::CellSize) + m(S::Count)), f(m(S::PatchOrder)), f(m(S::Scan)),
                        f(m(S::Sort)), f(m(S::Ranges)), f(m(S::Workload) + m(S::Pairs)), f(m(S::Canonical)),
                        r.culling == "none" ? "-" : f(r.cones.median), f(r.broad.median), f(r.proximity.median),
                        f(r.ccd.median), f(r.wall.median), f(r.cpu_ms)});
    }
    out << "\nms per call (median; CUDA events; AABB+count = bounds + cell size + count, pair gen = workload table +"
           " pairs; cones = the GPU normal-cone pass that computes the culled run's patch ids, not part of broad"
           " total; wall = host time of the enqueues and the one read-back; CPU broad = "
        << tbb::info::default_concurrency() << " threads, no narrow phase)\n";
    stages.print(out);

    TextTable detail({{"scene", TextTable::Align::Left}, {"culling", TextTable::Align::Left}, {"bounds"}, {"cell size"},
                      {"count"}, {"workload"}, {"pairs"}});
    for (const Result& r : results) {
        const auto m = [&](int s) { return f(r.stage[static_cast<std::size_t>(s)].median); };
        detail.add_row({r.scene, r.culling, m(S::Bounds), m(S::CellSize), m(S::Count), m(S::Workload), m(S::Pairs)});
    }
    out << "\nsplit stages (ms, median)\n";
    detail.print(out);

    TextTable counts({{"scene", TextTable::Align::Left},
                      {"culling", TextTable::Align::Left},
                      {"triangles"},
                      {"patches"},
                      {"cell mm"},
                      {"entries"},
                      {"cells"},
                      {"max/cell"},
                      {"slots"},
                      {"VF pairs"},
                      {"EE pairs"},
                      {"CPU pairs"},
                      {"contacts"},
                      {"CCD searched"},
                      {"CCD hits"},
                      {"MiB"}});
    for (const Result& r : results) {
        const gpu::GpuBroadPhaseCounters& c = r.counters;
        counts.add_row({r.scene, r.culling, std::to_string(r.triangles), r.patches > 0 ? std::to_string(r.patches) : "-",
                        format_fixed(1000.0 * static_cast<double>(c.cell_size), 2), std::to_string(c.entries),
                        std::to_string(c.cells_occupied), std::to_string(c.max_cell_entries), std::to_string(c.tested_pairs),
                        std::to_string(c.vf_pairs), std::to_string(c.ee_pairs), std::to_string(r.cpu_pairs),
                        std::to_string(r.contacts), std::to_string(r.ccd_tests), std::to_string(r.ccd_hits),
                        format_fixed(static_cast<double>(r.memory) / (1024.0 * 1024.0), 0)});
    }
    out << "\ncounts (patches = the GPU's; slots = pair tests enumerated from the workload table; CPU pairs = the CPU "
           "reference's, culled with the CPU front's ids)\n";
    counts.print(out);

    TextTable cones({{"scene", TextTable::Align::Left},
                     {"GPU ms"},
                     {"min"},
                     {"max"},
                     {"patches"},
                     {"contour tests"},
                     {"refused"},
                     {"tile pairs"},
                     {"CPU patches"},
                     {"CPU front ms"}});
    for (const Result& r : results) {
        if (r.culling == "none") continue;
        const gpu::GpuNormalConeCounters& c = r.cone_counters;
        cones.add_row({r.scene, f(r.cones.median), f(r.cones.min), f(r.cones.max), std::to_string(c.front_size),
                       std::to_string(c.contour_tests), std::to_string(c.contour_failed), std::to_string(c.contour_items),
                       std::to_string(r.cpu_patches), f(r.cpu_front_ms)});
    }
    out << "\nnormal cones on the GPU (refit + pass tests + patch ids per call, CUDA events, median/min/max of the timed "
           "runs) against the CPU's NormalConeFront::rebuild on the same state ("
        << tbb::info::default_concurrency() << " threads)\n";
    cones.print(out);
    for (std::size_t i = 0; i + 1 < results.size(); i += 2) {
        const Result &a = results[i], &b = results[i + 1];
        const double pa = a.counters.pairs, pb = b.counters.pairs;
        out << "  " << a.scene << ": normal-cone culling keeps " << format_fixed(pa > 0 ? 100.0 * pb / pa : 0.0, 1)
            << " % of the pairs (" << b.counters.pairs << " of " << a.counters.pairs << ") and "
            << format_fixed(a.counters.tested_pairs > 0 ? 100.0 * static_cast<double>(b.counters.tested_pairs) /
                                                              static_cast<double>(a.counters.tested_pairs)
                                                        : 0.0,
                            1)
            << " % of the slots; broad phase " << format_fixed(a.broad.median, 3) << " -> " << format_fixed(b.broad.median, 3)
            << " ms, plus " << format_fixed(b.cones.median, 3) << " ms for the GPU normal cones\n";
    }
}

void write_json(std::ostream& stream, const Options& opt, const cuda::DeviceInfo* device, const std::string& reason,
                const std::vector<Result>& results) {
    JsonWriter json(stream);
    json.begin_object();
    json.field("benchmark", "weft_cuda_collision_bench");
    json.field("weft_version", cli::build_info().version);
    json.field("cuda_available", device != nullptr);
    if (device == nullptr) {
        json.field("reason", reason);
        json.key("results").begin_array().end_array();
        json.end_object();
        return;
    }
    json.key("gpu").begin_object();
    json.field("name", device->name);
    json.field("compute_capability", std::to_string(device->compute_major) + "." + std::to_string(device->compute_minor));
    json.field("multiprocessors", device->multiprocessors);
    json.end_object();
    json.key("settings").begin_object();
    json.field("runs", opt.runs).field("warmup", opt.warmup).field("thickness_m", opt.thickness);
    json.field("eta_m", opt.eta_ratio * opt.thickness).field("cpu_threads", tbb::info::default_concurrency());
    json.end_object();
    json.key("results").begin_array();
    for (const Result& r : results) {
        const gpu::GpuBroadPhaseCounters& c = r.counters;
        json.begin_object();
        json.field("scene", r.scene).field("culling", r.culling);
        json.field("vertices", r.vertices).field("edges", r.edges).field("triangles", r.triangles);
        json.field("patches", r.patches);
        if (r.culling != "none") {
            json.key("normal_cones").begin_object();
            json.key("gpu_ms");
            write_dist(json, r.cones, kDistFields);
            json.field("gpu_patches", r.cone_counters.front_size).field("contour_tests", r.cone_counters.contour_tests);
            json.field("contour_refused", r.cone_counters.contour_failed);
            json.field("contour_tile_pairs", r.cone_counters.contour_items);
            json.field("cpu_patches", r.cpu_patches).field("cpu_front_ms", r.cpu_front_ms);
            json.end_object();
        }
        json.key("stage_ms").begin_object();
        for (int s = 0; s < gpu::GpuBroadPhase::kStageCount; ++s) {
            json.key(gpu::GpuBroadPhase::kStageNames[static_cast<std::size_t>(s)]);
            write_dist(json, r.stage[static_cast<std::size_t>(s)], kDistFields);
        }
        json.end_object();
        json.key("broad_phase_ms");
        write_dist(json, r.broad, kDistFields);
        json.key("proximity_ms");
        write_dist(json, r.proximity, kDistFields);
        json.key("ccd_ms");
        write_dist(json, r.ccd, kDistFields);
        json.key("wall_ms");
        write_dist(json, r.wall, kDistFields);
        json.field("cpu_broad_phase_ms", r.cpu_ms).field("cpu_pairs", r.cpu_pairs).field("cpu_culled_pairs", r.cpu_culled);
        json.key("counters").begin_object();
        json.field("cell_size_m", static_cast<double>(c.cell_size)).field("entries", c.entries);
        json.field("cells", c.cells_occupied).field("max_cell_entries", c.max_cell_entries);
        json.field("tested_pairs", c.tested_pairs).field("vf_pairs", c.vf_pairs).field("ee_pairs", c.ee_pairs);
        json.field("oversized", c.oversized).field("nonfinite", c.nonfinite).field("key_bits", c.key_bits);
        json.field("contacts", r.contacts).field("ccd_searched", r.ccd_tests).field("ccd_box_rejected", r.ccd_box_rejected);
        json.field("ccd_hits", r.ccd_hits).field("ccd_conservative", r.ccd_conservative);
        json.end_object();
        json.field("device_memory_bytes", r.memory).field("warmup_reruns", r.reruns);
        json.end_object();
    }
    json.end_array();
    json.end_object();
}

}  // namespace

int main(int argc, char** argv) {
    const Options opt = parse_options(argc, argv);
    try {
        const std::vector<cuda::DeviceInfo> gpus = cuda::devices();
        if (gpus.empty()) {
            const std::string reason = cuda::unavailable_reason();
            std::cout << "no CUDA device: " << reason << " (nothing measured)\n";
            if (!opt.json_file.empty())
                bench::write_json_file(opt.json_file, "weft_cuda_collision_bench",
                                       [&](std::ostream& s) { write_json(s, opt, nullptr, reason, {}); });
            return 0;
        }
        const cuda::DeviceInfo& device = gpus[0];
        WEFT_CUDA_CHECK(cudaSetDevice(device.ordinal));
        std::cout << "GPU: " << device.name << " (sm_" << device.compute_major << device.compute_minor << ", "
                  << device.multiprocessors << " SMs); thickness " << opt.thickness * 1000.0 << " mm, CCD eta "
                  << opt.eta_ratio * opt.thickness * 1000.0 << " mm; " << opt.runs << " timed runs after " << opt.warmup
                  << " warm-up\n";
        cudaStream_t stream = nullptr;
        WEFT_CUDA_CHECK(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
        std::vector<Result> results;
        for (const std::string& name : opt.scenes) {
            const Scene s = name == "twist" ? twist_scene(opt.twist_n) : stack_scene();
            std::cerr << "scene " << name << ": " << s.x0.size() << " vertices, " << s.triangles.size() << " triangles"
                      << std::endl;
            for (bool cull : {false, true}) results.push_back(measure(opt, s, cull, stream));
        }
        cudaStreamDestroy(stream);
        print(std::cout, results);
        if (!opt.json_file.empty() &&
            !bench::write_json_file(opt.json_file, "weft_cuda_collision_bench",
                                    [&](std::ostream& s) { write_json(s, opt, &device, "", results); }))
            return 1;
        return 0;
    } catch (const std::exception& e) {
        std::cerr << "weft_cuda_collision_bench: " << e.what() << '\n';
        return 1;
    }
}
