// The GPU collision detection (cuda/src/collision/) against the CPU reference on the same
// float-representable positions:
//  - broad phase: on random triangle soups (with exploding vertices, non-finite positions, far-apart
//    clusters, any cell size), a twisted and crumpled sheet, two cloths with self pairs off, and
//    random and block patch ids, the GPU pairs contain the CPU pairs, and every extra pair is one
//    whose double boxes miss each other by less than the outward rounding of the float bounds
//    (2⁻²²·(M + 2·thickness) per axis, broad_phase_gpu.h); the same bits on every run; the
//    overflow path (tiny capacities, grow and rerun) gives the same list;
//  - proximity contacts: every CPU (double) contact whose start distance is below half the
//    thickness is found by the GPU, with the same gap;
//  - CCD: every CPU (double) hit whose distance bound is below half its eta is found by the GPU.
// The counts are printed. Every test skips without a GPU.
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "broad_phase_soups.h"
#include "collision/broad_phase.h"
#include "collision/broad_phase_gpu.h"
#include "collision/ccd_gpu.h"
#include "collision/proximity_contacts.h"
#include "collision/proximity_gpu.h"
#include "cuda_check.h"
#include "device_array.h"
#include "float_positions.h"
#include "gpu_test_util.h"
#include "random_geometry.h"
#include "weft/physics/ccd.h"
#include "weft/physics/proximity.h"

namespace weft::collision {

std::ostream& operator<<(std::ostream& os, const VertexFacePair& p) {
    return os << "(v " << p.vertex << ", t " << p.triangle << ")";
}
std::ostream& operator<<(std::ostream& os, const EdgeEdgePair& p) { return os << "(e " << p.a << ", e " << p.b << ")"; }

namespace {

namespace gpu = weft::cuda::collision;
using cuda::DeviceArray;
using cuda::MemoryLedger;

constexpr double kPi = std::numbers::pi;
constexpr std::uint32_t kNone = kNoPatch;

// ---- scenes ---------------------------------------------------------------------------------------

struct Scene {
    std::vector<Vec3d> x0, x1;
    std::vector<Triangle> triangles;
    std::vector<Edge> edges;
    std::vector<std::uint32_t> triangle_cloth;
    std::vector<std::uint32_t> vertex_patch, edge_patch, triangle_patch;
    bool self_pairs = true;
    double thickness = 0.0;

    [[nodiscard]] BroadPhaseInput cpu_input(double cell = 0.0) const {
        BroadPhaseInput in{.x0 = x0, .x1 = x1, .triangles = triangles, .edges = edges, .thickness = thickness, .cell_size = cell};
        in.self_pairs = self_pairs;
        in.triangle_cloth = triangle_cloth;
        in.vertex_patch = vertex_patch;
        in.edge_patch = edge_patch;
        in.triangle_patch = triangle_patch;
        return in;
    }
    /// Rounds every coordinate to float: the GPU and the CPU then see the very same positions.
    void snap() { test::snap_to_float(*this); }
};

/// A random triangle soup (random_geometry.h: a jittered lattice, some vertices jumping far: the
/// oversized path) with its edges and a random thickness, snapped to float.
Scene random_soup(unsigned seed, int lattice, std::size_t triangles, double motion, double outliers) {
    std::mt19937 rng(seed);
    test::RandomSoup soup = test::random_soup(rng, lattice, triangles, motion, outliers);
    Scene s;
    s.x0 = std::move(soup.x0);
    s.x1 = std::move(soup.x1);
    s.triangles = std::move(soup.triangles);
    s.edges = build_edges(s.triangles);
    s.thickness = std::uniform_real_distribution<double>(0.0, 0.2)(rng);
    s.snap();
    return s;
}

/// A smooth random displacement field (random_geometry.h): four sinusoids of wavelengths within
/// ±30 % of `wavelength` (m), amplitudes up to `amplitude` (m) per coordinate.
test::SmoothField field(std::mt19937& rng, double amplitude, double wavelength) {
    return {rng, amplitude, 0.7 * wavelength, 1.3 * wavelength};
}

/// Appends an nx × ny vertex grid of spacing h (in its own (u, w) plane coordinates, centred on 0)
/// placed by `place(u, w, t)` at t = 0 (x0) and t = 1 (x1); returns the first vertex.
std::uint32_t add_grid(Scene& s, int nx, int ny, double h, const std::function<Vec3d(double, double, int)>& place,
                       std::uint32_t cloth = 0) {
    const auto base = static_cast<std::uint32_t>(s.x0.size());
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const double u = (i - 0.5 * (nx - 1)) * h, w = (j - 0.5 * (ny - 1)) * h;
            s.x0.push_back(place(u, w, 0));
            s.x1.push_back(place(u, w, 1));
        }
    const auto id = [&](int i, int j) { return base + static_cast<std::uint32_t>(j * nx + i); };
    for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
            // Alternating diagonals, as a cloth mesher would.
            if ((i + j) % 2 == 0) {
                s.triangles.push_back({{id(i, j), id(i + 1, j), id(i + 1, j + 1)}});
                s.triangles.push_back({{id(i, j), id(i + 1, j + 1), id(i, j + 1)}});
            } else {
                s.triangles.push_back({{id(i, j), id(i + 1, j), id(i, j + 1)}});
                s.triangles.push_back({{id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)}});
            }
            s.triangle_cloth.push_back(cloth);
            s.triangle_cloth.push_back(cloth);
        }
    return base;
}

/// The twisting sheet: an n × n grid at 1 cm whose columns turn about the x axis by an angle growing
/// linearly along x (`turns` full turns over the sheet at the start, `dturns` more at the end),
/// crumpled by a smooth random field of `crumple` metres.
Scene twisted_sheet(int n, double turns, double dturns, double crumple, unsigned seed) {
    Scene s;
    std::mt19937 rng(seed);
    const test::SmoothField f0 = field(rng, crumple, 0.05), f1 = field(rng, crumple, 0.05);
    const double L = (n - 1) * 0.01;
    add_grid(s, n, n, 0.01, [&](double x, double y, int t) {
        const double phi = 2.0 * kPi * (turns + t * dturns) * x / L;
        const Vec3d d = (t == 0 ? f0 : f1).at(x, y);
        const double yy = y + d.y, zz = d.z;
        return Vec3d{x + d.x, yy * std::cos(phi) - zz * std::sin(phi), yy * std::sin(phi) + zz * std::cos(phi)};
    });
    s.edges = build_edges(s.triangles);
    s.thickness = 0.005;
    s.snap();
    return s;
}

/// Two wavy n × n cloths 3 mm apart (waves of at most ±1.2 mm: apart at the start), the upper one
/// offset by a third of a cell and sinking by `sink` during the step; cloth ids 0 and 1.
Scene two_cloths(int n, unsigned seed, double sink = 0.004) {
    Scene s;
    std::mt19937 rng(seed);
    const test::SmoothField a0 = field(rng, 0.0003, 0.06), a1 = field(rng, 0.0003, 0.06), b0 = field(rng, 0.0003, 0.06),
                            b1 = field(rng, 0.0003, 0.06);
    add_grid(s, n, n, 0.01, [&](double x, double y, int t) {
        const Vec3d d = (t == 0 ? a0 : a1).at(x, y);
        return Vec3d{x + 0.2 * d.x, y + 0.2 * d.y, d.z + t * 0.001};
    }, 0);
    add_grid(s, n, n, 0.01, [&](double x, double y, int t) {
        const Vec3d d = (t == 0 ? b0 : b1).at(x, y);
        return Vec3d{x + 0.0033 + 0.2 * d.x, y + 0.0033 + 0.2 * d.y, 0.003 + d.z - t * sink};
    }, 1);
    s.edges = build_edges(s.triangles);
    s.thickness = 0.004;
    s.snap();
    return s;
}

/// Random patch ids in [0, patches) with a share of kNoPatch.
void random_patches(Scene& s, unsigned seed, std::uint32_t patches, double none_share) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<std::uint32_t> pick(0, patches - 1);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const auto draw = [&](std::vector<std::uint32_t>& out, std::size_t count) {
        out.resize(count);
        for (auto& p : out) p = unit(rng) < none_share ? kNone : pick(rng);
    };
    draw(s.vertex_patch, s.x0.size());
    draw(s.edge_patch, s.edges.size());
    draw(s.triangle_patch, s.triangles.size());
}

/// Patch ids as a normal-cone front gives them: connected blocks of triangles (by the triangle's
/// first vertex's grid block), each vertex and edge in the patch of one incident triangle.
void block_patches(Scene& s, int n, int block) {
    s.triangle_patch.resize(s.triangles.size());
    s.vertex_patch.assign(s.x0.size(), kNone);
    s.edge_patch.assign(s.edges.size(), kNone);
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
        const std::uint32_t v = s.triangles[t].v[0];
        const int i = static_cast<int>(v % static_cast<std::uint32_t>(n)), j = static_cast<int>(v / static_cast<std::uint32_t>(n));
        const auto patch = static_cast<std::uint32_t>((j / block) * ((n + block - 1) / block) + i / block);
        s.triangle_patch[t] = patch;
        for (std::uint32_t c : s.triangles[t].v)
            if (s.vertex_patch[c] == kNone) s.vertex_patch[c] = patch;
    }
    for (std::size_t e = 0; e < s.edges.size(); ++e) s.edge_patch[e] = s.vertex_patch[s.edges[e].v[0]];
}

// ---- device side ---------------------------------------------------------------------------------

using test::Stream;

template <typename T>
const T* ptr(const DeviceArray<T>& a) {
    return a.size() > 0 ? a.get() : nullptr;
}

using test::soa_floats;

/// A scene on the device.
struct DeviceScene {
    MemoryLedger ledger;
    DeviceArray<float> x0, x1;
    DeviceArray<std::uint32_t> triangles, edges, cloth, vertex_patch, edge_patch, triangle_patch;
    const Scene* scene = nullptr;

    explicit DeviceScene(const Scene& s) : scene(&s) {
        x0.upload(soa_floats(s.x0), ledger, "x0");
        x1.upload(soa_floats(s.x1), ledger, "x1");
        std::vector<std::uint32_t> t, e;
        for (const Triangle& tri : s.triangles) t.insert(t.end(), tri.v, tri.v + 3);
        for (const Edge& edge : s.edges) e.insert(e.end(), edge.v, edge.v + 2);
        triangles.upload(t, ledger, "triangles");
        edges.upload(e, ledger, "edges");
        cloth.upload(s.triangle_cloth, ledger, "cloth");
        vertex_patch.upload(s.vertex_patch, ledger, "patch");
        edge_patch.upload(s.edge_patch, ledger, "patch");
        triangle_patch.upload(s.triangle_patch, ledger, "patch");
    }
    [[nodiscard]] gpu::GpuBroadPhaseInput input(double cell = 0.0) const {
        gpu::GpuBroadPhaseInput in;
        in.x0 = ptr(x0);
        in.x1 = ptr(x1);
        in.vertex_count = static_cast<std::uint32_t>(scene->x0.size());
        in.triangles = ptr(triangles);
        in.triangle_count = static_cast<std::uint32_t>(scene->triangles.size());
        in.edges = ptr(edges);
        in.edge_count = static_cast<std::uint32_t>(scene->edges.size());
        in.triangle_cloth = ptr(cloth);
        in.self_pairs = scene->self_pairs;
        in.vertex_patch = ptr(vertex_patch);
        in.edge_patch = ptr(edge_patch);
        in.triangle_patch = ptr(triangle_patch);
        in.thickness = scene->thickness;
        in.cell_size = cell;
        return in;
    }
};

struct GpuPairs {
    std::vector<std::uint64_t> keys;
    std::vector<VertexFacePair> vf;
    std::vector<EdgeEdgePair> ee;
    gpu::GpuBroadPhaseCounters counters;
};

GpuPairs run_gpu(gpu::GpuBroadPhase& bp, const DeviceScene& d, cudaStream_t stream, double cell = 0.0,
                 std::uint32_t share_index = 0, std::uint32_t share_count = 1) {
    GpuPairs out;
    gpu::GpuBroadPhaseInput in = d.input(cell);
    in.share_index = share_index;
    in.share_count = share_count;
    out.counters = bp.find(in, stream);
    bp.download(out.keys, stream);
    const gpu::PairEncoding enc = bp.pairs().encoding;
    for (std::uint64_t k : out.keys) {
        if (enc.is_ee(k))
            out.ee.push_back({enc.first(k), enc.second(k)});
        else
            out.vf.push_back({enc.first(k), enc.second(k)});
    }
    return out;
}

// ---- checks ---------------------------------------------------------------------------------------

struct Box {
    Vec3d lo, hi;
};
/// The CPU's bound of a primitive (double, min/max of the positions ∓ thickness).
Box cpu_box(const Scene& s, std::initializer_list<std::uint32_t> vs) {
    const double inf = std::numeric_limits<double>::infinity();
    Box b{{inf, inf, inf}, {-inf, -inf, -inf}};
    for (std::uint32_t v : vs)
        for (const Vec3d& p : {s.x0[v], s.x1[v]})
            for (int k = 0; k < 3; ++k) {
                b.lo[k] = std::min(b.lo[k], p[k]);
                b.hi[k] = std::max(b.hi[k], p[k]);
            }
    for (int k = 0; k < 3; ++k) {
        b.lo[k] -= s.thickness;
        b.hi[k] += s.thickness;
    }
    return b;
}

struct ExtraStats {
    std::size_t count = 0;
    double worst = 0.0;  ///< largest gap / allowed margin over the extra pairs
};

/// An extra pair (GPU, not CPU) must be one whose double boxes miss, on every axis where they do,
/// by at most the outward rounding 2⁻²²·(M + 2·thickness) (broad_phase_gpu.h), and must pass the
/// filters the CPU applies.
void check_extra(const Scene& s, const Box& a, const Box& b, ExtraStats& st, const std::string& what) {
    bool separated = false, within = true;
    for (int k = 0; k < 3; ++k) {
        const double gap = std::max(a.lo[k] - b.hi[k], b.lo[k] - a.hi[k]);
        if (!(gap > 0.0)) continue;
        separated = true;
        const double m = std::max({std::abs(a.lo[k]), std::abs(a.hi[k]), std::abs(b.lo[k]), std::abs(b.hi[k])});
        const double margin = std::ldexp(m + 2.0 * s.thickness, -22) + 1e-30;
        st.worst = std::max(st.worst, gap / margin);
        within = within && gap <= margin;
    }
    EXPECT_TRUE(separated) << what << ": the CPU missed a pair whose double boxes overlap";
    EXPECT_TRUE(within) << what << ": double boxes miss by more than the float rounding";
    ++st.count;
}

std::uint32_t cloth_of_vertex(const Scene& s, std::uint32_t v) {
    for (std::size_t t = 0; t < s.triangles.size(); ++t)
        for (std::uint32_t c : s.triangles[t].v)
            if (c == v) return s.triangle_cloth.empty() ? 0U : s.triangle_cloth[t];
    return 0xFFFFFFFFU;
}

struct Comparison {
    std::size_t cpu_vf = 0, cpu_ee = 0, gpu_vf = 0, gpu_ee = 0;
    ExtraStats extra;
};

/// GPU ⊇ CPU, extras within the rounding margin and passing the filters, sorted and unique.
Comparison compare(const Scene& s, const BroadPhaseResult& cpu, const GpuPairs& g) {
    Comparison c{cpu.vf.size(), cpu.ee.size(), g.vf.size(), g.ee.size(), {}};
    EXPECT_TRUE(std::adjacent_find(g.keys.begin(), g.keys.end(), std::greater_equal<>()) == g.keys.end())
        << "GPU keys not strictly increasing";
    EXPECT_EQ(g.counters.vf_pairs, g.vf.size());
    EXPECT_EQ(g.counters.ee_pairs, g.ee.size());
    const auto first = [](const auto& v) {
        std::ostringstream os;
        for (std::size_t i = 0; i < std::min<std::size_t>(v.size(), 5); ++i) os << ' ' << v[i];
        return os.str();
    };
    std::vector<VertexFacePair> missing_vf, extra_vf;
    std::vector<EdgeEdgePair> missing_ee, extra_ee;
    std::set_difference(cpu.vf.begin(), cpu.vf.end(), g.vf.begin(), g.vf.end(), std::back_inserter(missing_vf));
    std::set_difference(cpu.ee.begin(), cpu.ee.end(), g.ee.begin(), g.ee.end(), std::back_inserter(missing_ee));
    std::set_difference(g.vf.begin(), g.vf.end(), cpu.vf.begin(), cpu.vf.end(), std::back_inserter(extra_vf));
    std::set_difference(g.ee.begin(), g.ee.end(), cpu.ee.begin(), cpu.ee.end(), std::back_inserter(extra_ee));
    EXPECT_TRUE(missing_vf.empty()) << missing_vf.size() << " CPU vertex-face pairs missing on the GPU:" << first(missing_vf);
    EXPECT_TRUE(missing_ee.empty()) << missing_ee.size() << " CPU edge-edge pairs missing on the GPU:" << first(missing_ee);
    const bool cull = !s.vertex_patch.empty();
    for (const VertexFacePair& p : extra_vf) {
        const Triangle& t = s.triangles[p.triangle];
        const std::string what = "extra vertex-face (v " + std::to_string(p.vertex) + ", t " + std::to_string(p.triangle) + ")";
        EXPECT_FALSE(p.vertex == t.v[0] || p.vertex == t.v[1] || p.vertex == t.v[2]) << what;
        if (cull && s.vertex_patch[p.vertex] != kNone) {
            EXPECT_NE(s.vertex_patch[p.vertex], s.triangle_patch[p.triangle]) << what;
        }
        if (!s.self_pairs) {
            EXPECT_NE(cloth_of_vertex(s, p.vertex), s.triangle_cloth[p.triangle]) << what;
        }
        check_extra(s, cpu_box(s, {p.vertex}), cpu_box(s, {t.v[0], t.v[1], t.v[2]}), c.extra, what);
    }
    for (const EdgeEdgePair& p : extra_ee) {
        const Edge &a = s.edges[p.a], &b = s.edges[p.b];
        const std::string what = "extra edge-edge (e " + std::to_string(p.a) + ", e " + std::to_string(p.b) + ")";
        EXPECT_FALSE(a.v[0] == b.v[0] || a.v[0] == b.v[1] || a.v[1] == b.v[0] || a.v[1] == b.v[1]) << what;
        if (cull && s.edge_patch[p.a] != kNone) {
            EXPECT_NE(s.edge_patch[p.a], s.edge_patch[p.b]) << what;
        }
        check_extra(s, cpu_box(s, {a.v[0], a.v[1]}), cpu_box(s, {b.v[0], b.v[1]}), c.extra, what);
    }
    return c;
}

void print(const char* what, const Comparison& c, const gpu::GpuBroadPhaseCounters& k) {
    std::printf("%-34s CPU %8zu VF %8zu EE | GPU %8zu VF %8zu EE | extra %zu (worst %.3f of margin) | cell %.4g m, "
                "%u oversized, %u non-finite, max %u per cell\n",
                what, c.cpu_vf, c.cpu_ee, c.gpu_vf, c.gpu_ee, c.extra.count, c.extra.worst,
                static_cast<double>(k.cell_size), k.oversized, k.nonfinite, k.max_cell_entries);
}

Comparison check_scene(const Scene& s, const char* what, double cell = 0.0) {
    BroadPhase cpu;
    BroadPhaseResult ref;
    cpu.find(s.cpu_input(cell), ref);
    Stream stream;
    DeviceScene d(s);
    gpu::GpuBroadPhase bp;
    const GpuPairs g = run_gpu(bp, d, stream.s, cell);
    const Comparison c = compare(s, ref, g);
    print(what, c, g.counters);
    return c;
}

// ---- broad phase ----------------------------------------------------------------------------------

TEST(CollisionGpu, RandomSoupsContainTheCpuPairs) {
    WEFT_REQUIRE_GPU();
    for (const test::SoupCase& c : test::kSoupCases) {
        SCOPED_TRACE("seed " + std::to_string(c.seed));
        const Scene s = random_soup(c.seed, c.lattice, c.triangles, c.motion, c.outliers);
        const std::string what = "soup " + std::to_string(c.seed);
        const Comparison r = check_scene(s, what.c_str());
        EXPECT_GT(r.gpu_vf, 0U);
        EXPECT_GT(r.gpu_ee, 0U);
    }
}

TEST(CollisionGpu, AnyCellSizeGivesTheSamePairs) {
    WEFT_REQUIRE_GPU();
    // Tiny cells make most bounds oversized (tested against everything), huge ones put everything in
    // one cell: the GPU pair set depends on the float bounds only, so it must not change at all.
    Scene s = random_soup(7, 8, 1000, 0.2, 0.01);
    s.thickness = 0.05;
    Stream stream;
    DeviceScene d(s);
    gpu::GpuBroadPhase bp;
    const GpuPairs automatic = run_gpu(bp, d, stream.s);
    BroadPhase cpu;
    BroadPhaseResult ref;
    for (double cell : {0.02, 0.3, 1.0, 3.0, 1000.0}) {
        SCOPED_TRACE("cell " + std::to_string(cell));
        const GpuPairs g = run_gpu(bp, d, stream.s, cell);
        EXPECT_TRUE(g.keys == automatic.keys);
        EXPECT_FLOAT_EQ(g.counters.cell_size, static_cast<float>(cell));
        cpu.find(s.cpu_input(cell), ref);
        (void)compare(s, ref, g);
        if (cell == 0.02) {
            EXPECT_GT(g.counters.oversized, 0U);
        }
    }
}

TEST(CollisionGpu, NonFinitePositionsAndFarClusters) {
    WEFT_REQUIRE_GPU();
    {
        Scene s = random_soup(8, 8, 800, 0.1, 0.0);
        s.thickness = 0.1;
        test::make_non_finite(s);
        (void)check_scene(s, "soup with NaN and Inf");
    }
    {
        // 10⁷ m apart: float positions there are a metre apart, and the outward rounding is a metre too.
        Scene s = random_soup(9, 8, 800, 0.1, 0.0);
        s.thickness = 0.05;
        test::split_far_apart(s);
        s.snap();
        (void)check_scene(s, "soup split 1e7 m apart");
    }
}

TEST(CollisionGpu, TwistedSheetContainsTheCpuPairs) {
    WEFT_REQUIRE_GPU();
    for (int i = 0; i < 3; ++i) {
        const double turns = 0.5 + 0.75 * i;
        const Scene s = twisted_sheet(120, turns, 0.02, 0.003, 20U + static_cast<unsigned>(i));
        const std::string what = "twisted sheet " + std::to_string(turns) + " turns";
        const Comparison c = check_scene(s, what.c_str());
        EXPECT_GT(c.cpu_vf, 10000U);
    }
}

TEST(CollisionGpu, TwoClothsWithoutSelfPairs) {
    WEFT_REQUIRE_GPU();
    Scene s = two_cloths(60, 3);
    s.self_pairs = false;
    const Comparison c = check_scene(s, "two cloths, self pairs off");
    EXPECT_GT(c.cpu_vf, 1000U);
    EXPECT_GT(c.cpu_ee, 1000U);
    s.self_pairs = true;
    const Comparison all = check_scene(s, "two cloths, self pairs on");
    EXPECT_GT(all.gpu_vf, c.gpu_vf);
}

TEST(CollisionGpu, PatchIdsCullLikeTheCpu) {
    WEFT_REQUIRE_GPU();
    Scene s = twisted_sheet(100, 1.0, 0.03, 0.003, 31);
    const Comparison unculled = check_scene(s, "twisted sheet, no patches");
    random_patches(s, 5, 6, 0.1);
    const Comparison random = check_scene(s, "twisted sheet, random patches");
    EXPECT_LT(random.gpu_vf + random.gpu_ee, unculled.gpu_vf + unculled.gpu_ee);
    block_patches(s, 100, 12);
    const Comparison blocks = check_scene(s, "twisted sheet, 12x12 block patches");
    EXPECT_LT(blocks.gpu_vf + blocks.gpu_ee, unculled.gpu_vf + unculled.gpu_ee);
    // Patches and cloth filter together.
    Scene two = two_cloths(40, 8);
    two.self_pairs = false;
    random_patches(two, 6, 4, 0.2);
    (void)check_scene(two, "two cloths, random patches");
}

TEST(CollisionGpu, SameBitsOnEveryRunAndAfterOverflow) {
    WEFT_REQUIRE_GPU();
    Scene s = twisted_sheet(100, 1.5, 0.03, 0.004, 41);
    random_patches(s, 7, 5, 0.3);
    Stream stream;
    DeviceScene d(s);
    gpu::GpuBroadPhase bp;
    const GpuPairs first = run_gpu(bp, d, stream.s);
    const GpuPairs second = run_gpu(bp, d, stream.s);
    gpu::GpuBroadPhase fresh;
    const GpuPairs third = run_gpu(fresh, d, stream.s);
    EXPECT_TRUE(first.keys == second.keys);
    EXPECT_TRUE(first.keys == third.keys);
    EXPECT_EQ(std::memcmp(&first.counters, &second.counters, sizeof first.counters), 0);
    EXPECT_EQ(bp.reruns(), fresh.reruns());
    // Tiny capacities: the first runs overflow, grow and rerun, and the result is the same.
    gpu::GpuBroadPhase tiny(gpu::GpuBroadPhase::Capacities{16, 16});
    const GpuPairs small = run_gpu(tiny, d, stream.s);
    EXPECT_GE(tiny.reruns(), 1);
    EXPECT_GE(tiny.entry_capacity(), first.counters.entries);
    EXPECT_TRUE(small.keys == first.keys);
    EXPECT_EQ(small.counters.tested_pairs, first.counters.tested_pairs);
    std::printf("determinism: %zu pairs, identical on 3 runs; tiny capacities: %d reruns to %zu entries, %zu pairs\n",
                first.keys.size(), tiny.reruns(), tiny.entry_capacity(), tiny.pair_capacity());
    // Once grown, no allocation and no rerun on the same sizes.
    const std::size_t bytes = tiny.memory_bytes();
    const int reruns = tiny.reruns();
    (void)run_gpu(tiny, d, stream.s);
    EXPECT_EQ(tiny.memory_bytes(), bytes);
    EXPECT_EQ(tiny.reruns(), reruns);
}

// A call that floods the hash (a twisted sheet crushed: 4.7M candidate pairs) grows the pair buffers;
// calm calls after it (the sheet spread out: 0.28M) need a fraction. At the end of the first trim
// window that did not hold the flood (weft/backend/buffer_trim.h, the CPU's policy) they are cut
// back, and the calm calls' pairs do not change.
TEST(CollisionGpu, AFloodOfPairsIsGivenBackAfterATrimWindow) {
    WEFT_REQUIRE_GPU();
    // The sheet crushed to a fifth (2 mm cells under a 5 mm thickness) and spread 4 times wider.
    const Scene sheet = twisted_sheet(100, 1.5, 0.03, 0.004, 41);
    Scene flood = sheet, calm = sheet;
    for (std::size_t i = 0; i < sheet.x0.size(); ++i) {
        flood.x0[i] = 0.2 * sheet.x0[i];
        flood.x1[i] = 0.2 * sheet.x1[i];
        calm.x0[i] = 4.0 * sheet.x0[i];
        calm.x1[i] = 4.0 * sheet.x1[i];
    }
    Stream stream;
    const DeviceScene calm_device(calm), flood_device(flood);
    gpu::GpuBroadPhase bp;
    const GpuPairs flooded = run_gpu(bp, flood_device, stream.s);
    const std::size_t flooded_bytes = bp.memory_bytes(), flooded_pair_bytes = bp.pair_memory_bytes();
    gpu::GpuBroadPhase fresh;
    const GpuPairs expected = run_gpu(fresh, calm_device, stream.s);
    ASSERT_GT(flooded.keys.size(), 10 * expected.keys.size()) << "the flood did not flood: the test tests nothing";
    // The flood's window ends at call kTrimPeriod (its peak is the flood's: nothing cut), the next
    // at 2·kTrimPeriod; the cut applies at the call after it.
    for (std::size_t call = 2; call <= 2 * kTrimPeriod; ++call) (void)bp.find(calm_device.input(), stream.s);
    EXPECT_EQ(bp.trims(), 0);
    const GpuPairs after = run_gpu(bp, calm_device, stream.s);
    std::printf("[ trim     ] flood %zu pairs, %.1f MB (pair lists %.1f MB); calm %zu pairs; after %zu calls %.1f MB "
                "(%.1f MB), %d trim(s)\n",
                flooded.keys.size(), static_cast<double>(flooded_bytes) / 1e6, static_cast<double>(flooded_pair_bytes) / 1e6,
                expected.keys.size(), 2 * kTrimPeriod + 1, static_cast<double>(bp.memory_bytes()) / 1e6,
                static_cast<double>(bp.pair_memory_bytes()) / 1e6, bp.trims());
    EXPECT_EQ(bp.trims(), 1);
    EXPECT_LT(bp.pair_memory_bytes(), flooded_pair_bytes / 4);
    EXPECT_LT(bp.memory_bytes(), flooded_bytes);
    EXPECT_LT(bp.pair_capacity(), 8 * expected.keys.size() + 4096);
    EXPECT_TRUE(after.keys == expected.keys);
    // A steady scene is not cut again: the next window keeps the sizes.
    const std::size_t bytes = bp.memory_bytes();
    for (std::size_t call = 0; call < kTrimPeriod + 1; ++call) (void)bp.find(calm_device.input(), stream.s);
    EXPECT_EQ(bp.trims(), 1);
    EXPECT_EQ(bp.memory_bytes(), bytes);
}

// Across GPUs each GPU hashes the cells dealt to it and reports their pairs: the shares are disjoint
// and together are the whole list, with their entries and tested slots adding up to the whole's
// (with culling, which cuts runs out of the rows, and with oversized primitives, shared out one by one).
TEST(CollisionGpu, SharesOfThePairsMakeUpTheWholeList) {
    WEFT_REQUIRE_GPU();
    Scene sheet = twisted_sheet(100, 1.5, 0.03, 0.004, 43);
    random_patches(sheet, 7, 5, 0.3);
    Scene soup = random_soup(7, 8, 1000, 0.2, 0.01);  // with 2 cm cells most bounds are oversized
    soup.thickness = 0.05;
    struct Case {
        const Scene* scene;
        double cell;
        const char* what;
    };
    Stream stream;
    for (const Case& c : {Case{&sheet, 0.0, "twisted sheet, patches"}, Case{&soup, 0.02, "soup, oversized bounds"}}) {
        DeviceScene d(*c.scene);
        gpu::GpuBroadPhase bp;
        const GpuPairs whole = run_gpu(bp, d, stream.s, c.cell);
        ASSERT_GT(whole.keys.size(), 100U) << c.what;
        for (const std::uint32_t count : {2U, 3U, 8U}) {
            std::vector<std::uint64_t> joined;
            unsigned long long tested = 0, entries = 0;
            for (std::uint32_t index = 0; index < count; ++index) {
                const GpuPairs share = run_gpu(bp, d, stream.s, c.cell, index, count);
                joined.insert(joined.end(), share.keys.begin(), share.keys.end());
                tested += share.counters.tested_pairs;
                entries += share.counters.entries;
                EXPECT_LT(share.keys.size(), whole.keys.size()) << c.what << ": share " << index << " of " << count;
            }
            std::sort(joined.begin(), joined.end());
            EXPECT_TRUE(std::adjacent_find(joined.begin(), joined.end()) == joined.end()) << c.what << ": a pair in two shares";
            EXPECT_TRUE(joined == whole.keys) << c.what << ": " << count << " shares";
            EXPECT_EQ(tested, whole.counters.tested_pairs) << c.what << ": " << count << " shares";
            // Each share hashes only its own cells: the shares' entries make up the whole table's.
            EXPECT_EQ(entries, whole.counters.entries) << c.what << ": " << count << " shares";
        }
        std::printf("shares: %s: %zu pairs (%u oversized primitives) split 2, 3 and 8 ways\n", c.what, whole.keys.size(),
                    whole.counters.oversized);
    }
    DeviceScene d(sheet);
    gpu::GpuBroadPhaseInput bad = d.input();
    bad.share_index = 2;
    bad.share_count = 2;
    gpu::GpuBroadPhase bp;
    EXPECT_THROW((void)bp.find(bad, stream.s), Error);
}

TEST(CollisionGpu, InputErrorsAreReported) {
    WEFT_REQUIRE_GPU();
    const Scene s = twisted_sheet(10, 0.5, 0.0, 0.0, 1);
    DeviceScene d(s);
    Stream stream;
    gpu::GpuBroadPhase bp;
    gpu::GpuBroadPhaseInput in = d.input();
    in.thickness = -1.0;
    EXPECT_THROW(bp.enqueue(in, stream.s), Error);
    in = d.input();
    in.vertex_patch = d.triangles.get();  // one patch list without the others
    EXPECT_THROW(bp.enqueue(in, stream.s), Error);
}

// ---- narrow phase ---------------------------------------------------------------------------------

/// A pair's identity for matching contacts and hits: its kind (0 vertex–face, 1 edge–edge) and four
/// vertices. (The four vertices alone can name a vertex–face and an edge–edge pair at once.)
using Quad = std::array<std::uint32_t, 5>;

TEST(CollisionGpu, ProximityContactsFindEveryClearCpuContact) {
    WEFT_REQUIRE_GPU();
    Scene s = two_cloths(60, 11, 0.002);
    s.thickness = 0.005;
    const std::size_t n = s.x0.size();
    std::mt19937 rng(12);
    std::uniform_real_distribution<double> mass(0.5, 2.0), unit(0.0, 1.0);
    std::vector<double> inverse_mass(n), thickness(n), friction(n);
    for (std::size_t v = 0; v < n; ++v) {
        inverse_mass[v] = unit(rng) < 0.02 ? 0.0 : static_cast<double>(static_cast<float>(1.0 / mass(rng)));
        const bool lower = v < n / 2;
        thickness[v] = lower ? 0.004 : 0.003;
        friction[v] = lower ? 0.3 : 0.5;
    }
    const double h = 1.0 / 240.0;
    // Broad phase on both sides; the narrow phase on each side's own candidates.
    BroadPhase cpu_bp;
    BroadPhaseResult ref;
    cpu_bp.find(s.cpu_input(), ref);
    // One call per kind, so that each contact's kind is known.
    std::vector<ProximityContact> cpu, cpu_ee;
    ProximityInput pin{.x0 = s.x0, .x1 = s.x1, .inverse_mass = inverse_mass, .thickness = thickness, .friction = friction,
                       .triangles = s.triangles, .edges = s.edges, .vf = ref.vf, .ee = {}, .h = h};
    find_proximity_contacts(pin, cpu);
    const std::size_t cpu_vf_contacts = cpu.size();
    pin.vf = {};
    pin.ee = ref.ee;
    find_proximity_contacts(pin, cpu_ee);
    cpu.insert(cpu.end(), cpu_ee.begin(), cpu_ee.end());

    Stream stream;
    DeviceScene d(s);
    gpu::GpuBroadPhase bp;
    bp.find(d.input(), stream.s);
    MemoryLedger ledger;
    const auto to_float = [](const std::vector<double>& v) { return std::vector<float>(v.begin(), v.end()); };
    DeviceArray<float> im, th, fr;
    im.upload(to_float(inverse_mass), ledger, "im");
    th.upload(to_float(thickness), ledger, "th");
    fr.upload(to_float(friction), ledger, "fr");
    gpu::GpuProximityInput gin;
    gin.x0 = d.x0.get();
    gin.x1 = d.x1.get();
    gin.vertex_count = static_cast<std::uint32_t>(n);
    gin.inverse_mass = im.get();
    gin.thickness = th.get();
    gin.friction = fr.get();
    gin.triangles = d.triangles.get();
    gin.edges = d.edges.get();
    gin.h = static_cast<float>(h);
    gpu::GpuProximityContacts contacts(1);  // a tiny buffer: grows and reruns
    const gpu::GpuProximityCounters counters = contacts.find(gin, bp.pairs(), stream.s);
    EXPECT_GE(contacts.reruns(), 1);
    std::vector<gpu::GpuProximityContact> got;
    contacts.download(got, stream.s);
    EXPECT_EQ(got.size(), counters.contacts);

    std::vector<std::uint64_t> keys;
    bp.download(keys, stream.s);
    const gpu::PairEncoding enc = bp.pairs().encoding;
    std::map<Quad, const gpu::GpuProximityContact*> by_pair;
    for (const auto& c : got) {
        ASSERT_LT(c.pair, keys.size());
        by_pair[{enc.is_ee(keys[c.pair]) ? 1U : 0U, c.vertex[0], c.vertex[1], c.vertex[2], c.vertex[3]}] = &c;
    }
    EXPECT_EQ(by_pair.size(), got.size()) << "a pair appears twice";
    for (std::size_t k = 1; k < got.size(); ++k) EXPECT_LT(got[k - 1].pair, got[k].pair) << "not in candidate order";
    std::size_t clear = 0, found = 0;
    double worst_gap = 0.0, worst_normal = 0.0;
    for (std::size_t k = 0; k < cpu.size(); ++k) {
        const ProximityContact& c = cpu[k];
        const std::uint32_t kind = k < cpu_vf_contacts ? 0U : 1U;
        const auto it = by_pair.find({kind, c.vertex[0], c.vertex[1], c.vertex[2], c.vertex[3]});
        if (it != by_pair.end()) {
            const gpu::GpuProximityContact& g = *it->second;
            worst_gap = std::max(worst_gap, std::abs(static_cast<double>(g.gap) - c.gap));
            const Vec3d gn{g.normal[0], g.normal[1], g.normal[2]};
            if (c.gap > 1e-4) worst_normal = std::max(worst_normal, physics::length(gn - c.normal));
            // (Weights, hence stiffness, may differ where the closest points are not unique: parallel
            // edges, whose float and double searches may pick different endpoints.)
            EXPECT_NEAR(g.thickness, c.thickness, 1e-9);
            EXPECT_NEAR(g.friction, c.friction, 1e-6);
        }
        if (!(c.gap < 0.5 * c.thickness)) continue;
        ++clear;
        if (it != by_pair.end()) {
            ++found;
        } else {
            ADD_FAILURE() << "CPU contact at gap " << c.gap << " (vertices " << c.vertex[0] << " " << c.vertex[1] << " "
                          << c.vertex[2] << " " << c.vertex[3] << ") not found on the GPU";
        }
    }
    EXPECT_LT(worst_gap, 1e-6);
    EXPECT_GT(clear, 100U);
    std::printf("proximity: %zu CPU candidates -> %zu CPU contacts; %zu GPU candidates -> %u GPU contacts; "
                "%zu CPU contacts with gap < thickness/2, %zu found; max |gap difference| %.3g m, max normal "
                "difference %.3g (gap > 0.1 mm)\n",
                ref.vf.size() + ref.ee.size(), cpu.size(), static_cast<std::size_t>(counters.candidates),
                counters.contacts, clear, found, worst_gap, worst_normal);
    // The same bits again.
    contacts.enqueue(gin, bp.pairs(), stream.s);
    contacts.read_back(stream.s);
    std::vector<gpu::GpuProximityContact> again;
    contacts.download(again, stream.s);
    ASSERT_EQ(again.size(), got.size());
    EXPECT_EQ(std::memcmp(again.data(), got.data(), got.size() * sizeof(got[0])), 0);
}

TEST(CollisionGpu, CcdFindsEveryClearCpuHit) {
    WEFT_REQUIRE_GPU();
    // The upper cloth sinks 8 mm through the lower one's waves: real crossings and near misses.
    Scene s = two_cloths(50, 13, 0.008);
    const std::size_t n = s.x0.size();
    std::vector<double> inverse_mass(n, 1.0);
    for (std::size_t v = 0; v < n; v += 37) inverse_mass[v] = 0.0;
    const double eta = 0.1 * s.thickness;

    BroadPhase cpu_bp;
    BroadPhaseResult ref;
    cpu_bp.find(s.cpu_input(), ref);
    // CPU reference: the impact zones' detection in double (eta lowered to half the start distance).
    // A hit is "clear" when the pair provably comes within 0.6·eta: the CPU search at half the eta
    // hits with a distance bound below 0.6·eta (a hit at eta itself is found where the distance first
    // reaches eta, so its bound is about eta, not below it). Pairs whose eta was lowered below
    // 10⁻³·eta by a near-touching start are left out: float cannot resolve their start distance.
    struct Hit {
        bool hit = false, clear = false;
        double bound = 0.0, eta = 0.0, half_bound = 0.0;
        physics::CcdStatus status{};
    };
    const std::size_t nvf = ref.vf.size(), total = nvf + ref.ee.size();
    std::vector<Quad> quads(total);
    std::vector<Hit> hits(total);
    tbb::parallel_for(std::size_t{0}, total, [&](std::size_t i) {
        Quad q;
        const bool vf = i < nvf;
        if (vf) {
            const Triangle& t = s.triangles[ref.vf[i].triangle];
            q = {0U, ref.vf[i].vertex, t.v[0], t.v[1], t.v[2]};
        } else {
            const Edge &a = s.edges[ref.ee[i - nvf].a], &b = s.edges[ref.ee[i - nvf].b];
            q = {1U, a.v[0], a.v[1], b.v[0], b.v[1]};
        }
        quads[i] = q;
        if (inverse_mass[q[1]] == 0.0 && inverse_mass[q[2]] == 0.0 && inverse_mass[q[3]] == 0.0 && inverse_mass[q[4]] == 0.0)
            return;
        Vec3d a0[4], a1[4];
        for (std::size_t k = 0; k < 4; ++k) {
            a0[k] = s.x0[q[k + 1]];
            a1[k] = s.x1[q[k + 1]];
        }
        const double d0 = vf ? physics::point_triangle_proximity(a0[0], a0[1], a0[2], a0[3]).distance
                             : physics::edge_edge_proximity(a0[0], a0[1], a0[2], a0[3]).distance;
        const double e = std::min(eta, 0.5 * d0);
        const physics::CcdResult<double> r =
            vf ? physics::vertex_face_ccd(a0[0], a0[1], a0[2], a0[3], a1[0], a1[1], a1[2], a1[3], e)
               : physics::edge_edge_ccd(a0[0], a0[1], a0[2], a0[3], a1[0], a1[1], a1[2], a1[3], e);
        hits[i] = {r.hit, false, r.diag.distance_bound, e, 0.0, r.diag.status};
        if (!r.hit || !(e >= 1e-3 * eta)) return;
        const physics::CcdResult<double> half =
            vf ? physics::vertex_face_ccd(a0[0], a0[1], a0[2], a0[3], a1[0], a1[1], a1[2], a1[3], 0.5 * e)
               : physics::edge_edge_ccd(a0[0], a0[1], a0[2], a0[3], a1[0], a1[1], a1[2], a1[3], 0.5 * e);
        hits[i].half_bound = half.diag.distance_bound;
        hits[i].clear = half.hit && half.diag.distance_bound >= 0.0 && half.diag.distance_bound < 0.6 * e;
    });

    Stream stream;
    DeviceScene d(s);
    gpu::GpuBroadPhase bp;
    bp.find(d.input(), stream.s);
    MemoryLedger ledger;
    DeviceArray<float> im;
    im.upload(std::vector<float>(inverse_mass.begin(), inverse_mass.end()), ledger, "im");
    gpu::GpuCcdInput cin;
    cin.x0 = d.x0.get();
    cin.x1 = d.x1.get();
    cin.vertex_count = static_cast<std::uint32_t>(n);
    cin.inverse_mass = im.get();
    cin.triangles = d.triangles.get();
    cin.edges = d.edges.get();
    cin.eta = static_cast<float>(eta);
    gpu::GpuCcd ccd(1);  // a tiny buffer: grows and compacts again
    const gpu::GpuCcdCounters counters = ccd.find(cin, bp.pairs(), stream.s);
    EXPECT_GE(ccd.reruns(), 1);
    std::vector<gpu::GpuCcdHit> got;
    ccd.download(got, stream.s);
    EXPECT_EQ(got.size(), counters.hits);
    std::vector<std::uint64_t> keys;
    bp.download(keys, stream.s);
    const gpu::PairEncoding enc = bp.pairs().encoding;
    const auto quad = [&](const gpu::GpuCcdHit& h) {
        return Quad{enc.is_ee(keys.at(h.pair)) ? 1U : 0U, h.vertex[0], h.vertex[1], h.vertex[2], h.vertex[3]};
    };
    std::map<Quad, const gpu::GpuCcdHit*> by_pair;
    for (const auto& h : got) {
        by_pair[quad(h)] = &h;
        EXPECT_GE(h.toi, 0.0F);
        EXPECT_LE(h.toi, 1.0F);
        EXPECT_NEAR(std::hypot(h.normal[0], h.normal[1], h.normal[2]), 1.0, 1e-5);
    }
    std::size_t cpu_hits = 0, clear = 0, found = 0, gpu_only = 0, below_half = 0;
    std::map<Quad, bool> cpu_hit;
    for (std::size_t i = 0; i < total; ++i) {
        if (!hits[i].hit) continue;
        ++cpu_hits;
        cpu_hit[quads[i]] = true;
        if (hits[i].bound < 0.5 * hits[i].eta) ++below_half;
        if (!hits[i].clear) continue;
        ++clear;
        if (by_pair.count(quads[i]) != 0) {
            ++found;
        } else {
            ADD_FAILURE() << "CPU CCD hit coming within " << hits[i].half_bound << " m (eta " << hits[i].eta
                          << ") not found on the GPU (pair " << i << ")";
        }
    }
    for (const auto& h : got) gpu_only += cpu_hit.count(quad(h)) == 0 ? 1 : 0;
    EXPECT_GT(clear, 20U);
    std::printf("CCD (eta %.2g m): %zu CPU candidates -> %zu CPU hits (%zu with distance bound < eta/2), %zu clearly "
                "inside (within 0.6 eta), %zu found by the GPU; GPU: %u candidates, %u immovable, %u box-rejected, %u "
                "searched, %u hits (%u conservative), %zu not CPU hits\n",
                eta, total, cpu_hits, below_half, clear, found, counters.candidates, counters.immovable,
                counters.box_rejected, counters.tests, counters.hits, counters.conservative, gpu_only);
    // The same bits again.
    ccd.enqueue(cin, bp.pairs(), stream.s);
    ccd.read_back(stream.s);
    std::vector<gpu::GpuCcdHit> again;
    ccd.download(again, stream.s);
    ASSERT_EQ(again.size(), got.size());
    EXPECT_EQ(std::memcmp(again.data(), got.data(), got.size() * sizeof(got[0])), 0);
}

}  // namespace
}  // namespace weft::collision
