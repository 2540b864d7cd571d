// The multi-GPU building blocks on the device (cuda/src/multi/): the halo exchange fills every ghost
// with its owner's value, and the parts' products through it (interior rows first, boundary rows
// after the exchange, as the pipelined SpMV runs them) are the whole product's bits. G parts run on
// one GPU (the test mode, any GPU host) and, where two GPUs are present, two parts on two GPUs.
#include <cuda_runtime_api.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "gpu_test_util.h"
#include "multi/halo_exchange.h"
#include "multi/part_matrix.h"
#include "multi/part_pcg.h"
#include "weft/cuda/cuda_backend.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/part_model.h"
#include "weft/backend/vertex_partition.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

using cuda::multi::HaloExchange;
using cuda::multi::PartMatrix;
using cuda::multi::PartPcg;
using cuda::multi::PartPcgResult;

// Two cloths (a flag-like sheet and a smaller one beside it): a world's flat model.
FlatModel two_cloths() {
    World world;
    world.add_cloth({.name = "a", .fabric = Fabric::cook(make_grid(2.0, 1.2, 60, 36))});
    ClothDesc b{.name = "b", .fabric = Fabric::cook(make_grid(0.6, 0.4, 15, 9))};
    b.transform.translation = {0.3, 0.2, 0.05};
    world.add_cloth(b);
    return flatten(world.model());
}

VertexPartition partition(const FlatModel& flat, std::uint32_t parts) { return partition_along_preconditioner(flat, parts); }

// Each part's local vector on its device: owned values from `x` (global SoA), ghosts set to NaN
// so that a ghost the exchange missed shows.
struct LocalVectors {
    std::vector<float*> x, y;
    std::vector<int> device;
    LocalVectors() = default;
    LocalVectors(const LocalVectors&) = delete;
    LocalVectors& operator=(const LocalVectors&) = delete;
    ~LocalVectors() {
        for (std::size_t p = 0; p < x.size(); ++p) {
            cudaSetDevice(device[p]);
            cudaFree(x[p]);
            cudaFree(y[p]);
        }
    }
};

void upload_owned(const std::vector<PartModel>& parts, const std::vector<int>& devices, const std::vector<float>& x,
                  std::size_t n, LocalVectors& out) {
    for (std::size_t p = 0; p < parts.size(); ++p) {
        const PartModel& pm = parts[p];
        const std::size_t local = pm.model.vertex_count;
        std::vector<float> host(3 * local, std::nanf(""));
        for (std::uint32_t i = 0; i < pm.owned; ++i)
            for (std::size_t c = 0; c < 3; ++c) host[c * local + i] = x[c * n + pm.global_vertex[i]];
        WEFT_CUDA_CHECK(cudaSetDevice(devices[p]));
        float *dx = nullptr, *dy = nullptr;
        WEFT_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&dx), host.size() * sizeof(float)));
        WEFT_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&dy), host.size() * sizeof(float)));
        WEFT_CUDA_CHECK(cudaMemset(dy, 0, host.size() * sizeof(float)));  // ghost rows are never computed
        WEFT_CUDA_CHECK(cudaMemcpy(dx, host.data(), host.size() * sizeof(float), cudaMemcpyHostToDevice));
        out.x.push_back(dx);
        out.y.push_back(dy);
        out.device.push_back(devices[p]);
    }
}

// `count` parts of `flat` cut along the preconditioner's order, part p on devices[p]: each part's
// model, its owned rows' matrix (blocks from the whole matrix's `blocks`) and a stream.
struct Parts {
    VertexPartition vp;
    std::vector<PartModel> parts;
    std::vector<std::unique_ptr<PartMatrix>> matrices;
    std::vector<std::unique_ptr<test::Stream>> streams;
    std::vector<cudaStream_t> raw;
    Parts(const FlatModel& flat, const std::vector<float>& blocks, std::uint32_t count, const std::vector<int>& devices)
        : vp(partition(flat, count)) {
        for (std::uint32_t p = 0; p < count; ++p) {
            parts.push_back(extract_part(flat, vp, p));
            WEFT_CUDA_CHECK(cudaSetDevice(devices[p]));
            matrices.push_back(std::make_unique<PartMatrix>(parts.back(), devices[p]));
            matrices.back()->set_blocks(blocks);
            streams.push_back(std::make_unique<test::Stream>());
            raw.push_back(streams.back()->s);
        }
    }
};

// The product of every part's owned rows as the pipelined product runs it: the exchange begins, the
// interior rows run while it travels, the boundary rows follow it; returns the global result (SoA) and checks every ghost.
std::vector<float> product_by_parts(const FlatModel& flat, const std::vector<float>& blocks, const std::vector<float>& x,
                                    std::uint32_t count, const std::vector<int>& devices) {
    const std::size_t n = flat.vertex_count;
    const Parts set(flat, blocks, count, devices);
    const VertexPartition& vp = set.vp;
    const std::vector<PartModel>& parts = set.parts;
    const auto& matrices = set.matrices;
    const std::vector<cudaStream_t>& raw = set.raw;
    LocalVectors v;
    upload_owned(parts, devices, x, n, v);
    HaloExchange halo(vp, devices, raw);
    halo.begin(v.x);
    for (std::uint32_t p = 0; p < count; ++p) {  // interior rows, while the ghosts travel
        WEFT_CUDA_CHECK(cudaSetDevice(devices[p]));
        matrices[p]->multiply(v.x[p], v.y[p], 0, matrices[p]->interior(), raw[p]);
    }
    halo.finish();
    for (std::uint32_t p = 0; p < count; ++p) {  // boundary rows, after the ghosts landed
        WEFT_CUDA_CHECK(cudaSetDevice(devices[p]));
        matrices[p]->multiply(v.x[p], v.y[p], matrices[p]->interior(), matrices[p]->owned(), raw[p]);
    }
    std::vector<float> y(3 * n, std::nanf(""));
    for (std::uint32_t p = 0; p < count; ++p) {
        const PartModel& pm = parts[p];
        const std::size_t local = pm.model.vertex_count;
        std::vector<float> hx(3 * local), hy(3 * local);
        WEFT_CUDA_CHECK(cudaSetDevice(devices[p]));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(raw[p]));
        WEFT_CUDA_CHECK(cudaMemcpy(hx.data(), v.x[p], hx.size() * sizeof(float), cudaMemcpyDeviceToHost));
        WEFT_CUDA_CHECK(cudaMemcpy(hy.data(), v.y[p], hy.size() * sizeof(float), cudaMemcpyDeviceToHost));
        for (std::size_t i = pm.owned; i < local; ++i)  // every ghost holds its owner's value
            for (std::size_t c = 0; c < 3; ++c)
                EXPECT_EQ(hx[c * local + i], x[c * n + pm.global_vertex[i]]) << "part " << p << ", ghost " << i;
        for (std::uint32_t i = 0; i < pm.owned; ++i)
            for (std::size_t c = 0; c < 3; ++c) y[c * n + pm.global_vertex[i]] = hy[c * local + i];
    }
    return y;
}

std::vector<float> random_values(std::size_t count, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0F, 1.0F);
    std::vector<float> out;
    out.reserve(count);
    for (std::size_t k = 0; k < count; ++k) out.push_back(u(rng));
    return out;
}

struct Problem {
    FlatModel flat = two_cloths();
    std::vector<float> blocks = random_values(9 * flat.pattern.block_count(), 5);
    std::vector<float> x = random_values(3 * flat.vertex_count, 6);
};

TEST(MultiGpuParts, PartsOnOneGpuGiveTheWholeProductsBits) {
    WEFT_REQUIRE_GPU();
    const Problem problem;
    const std::vector<float> whole = product_by_parts(problem.flat, problem.blocks, problem.x, 1, {0});
    for (const std::uint32_t count : {2U, 3U, 7U}) {
        const std::vector<float> by_parts =
            product_by_parts(problem.flat, problem.blocks, problem.x, count, std::vector<int>(count, 0));
        for (std::size_t k = 0; k < whole.size(); ++k)
            ASSERT_EQ(by_parts[k], whole[k]) << "entry " << k << " of " << count << " parts";
    }
}

TEST(MultiGpuParts, TwoPartsOnTwoGpusGiveTheWholeProductsBits) {
    WEFT_REQUIRE_GPU();
    int devices = 0;
    WEFT_CUDA_CHECK(cudaGetDeviceCount(&devices));
    if (devices < 2) GTEST_SKIP() << "one CUDA device: two are needed";
    const Problem problem;
    const std::vector<float> whole = product_by_parts(problem.flat, problem.blocks, problem.x, 1, {0});
    const std::vector<float> by_parts = product_by_parts(problem.flat, problem.blocks, problem.x, 2, {0, 1});
    for (std::size_t k = 0; k < whole.size(); ++k) ASSERT_EQ(by_parts[k], whole[k]) << "entry " << k;
}

// A stiff SPD system on the pattern: A = m·I + k·L ⊗ I₃ (L the pattern's graph Laplacian), the shape of
// cloth's k·h²/m-dominated matrices; blocks as PartMatrix::set_blocks reads them.
std::vector<float> stiff_laplacian(const BlockPattern& pattern, float mass, float k) {
    std::vector<float> blocks(9 * pattern.block_count(), 0.0F);
    for (std::size_t i = 0; i + 1 < pattern.row_start.size(); ++i) {
        float degree = 0.0F;
        for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s)
            if (pattern.column[s] != i) {
                for (int d = 0; d < 3; ++d) blocks[9 * s + 4 * d] = -k;
                degree += 1.0F;
            }
        for (int d = 0; d < 3; ++d) blocks[9 * pattern.diagonal[i] + 4 * d] = mass + k * degree;
    }
    return blocks;
}

struct Solve {
    std::vector<float> x;  // global SoA
    PartPcgResult result;
};

// The single-reduction CG across `count` parts on `devices`, from x = 0, in graphs of `batch` iterations.
Solve solve_by_parts(const FlatModel& flat, const std::vector<float>& blocks, const std::vector<float>& b, std::uint32_t count,
                     const std::vector<int>& devices, int batch = 16, cuda::PcgLoop loop = cuda::PcgLoop::Auto,
                     int max_iterations = 2000) {
    const std::size_t n = flat.vertex_count;
    const Parts set(flat, blocks, count, devices);
    const VertexPartition& vp = set.vp;
    const std::vector<PartModel>& parts = set.parts;
    const std::vector<cudaStream_t>& raw = set.raw;
    std::vector<cuda::multi::PartSystem> systems;
    for (std::size_t p = 0; p < set.matrices.size(); ++p) systems.push_back(set.matrices[p]->system(raw[p]));
    LocalVectors rhs, x;
    upload_owned(parts, devices, b, n, rhs);
    upload_owned(parts, devices, std::vector<float>(3 * n, 0.0F), n, x);
    HaloExchange halo(vp, devices, raw);
    PartPcg pcg(systems, halo);
    pcg.set_loop(loop);
    Solve out;
    out.result = pcg.solve(std::vector<const float*>(rhs.x.begin(), rhs.x.end()), x.x, 1e-5, max_iterations, batch);
    out.x.assign(3 * n, std::nanf(""));
    for (std::uint32_t p = 0; p < count; ++p) {
        const PartModel& pm = parts[p];
        const std::size_t local = pm.model.vertex_count;
        std::vector<float> hx(3 * local);
        WEFT_CUDA_CHECK(cudaSetDevice(devices[p]));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(raw[p]));
        WEFT_CUDA_CHECK(cudaMemcpy(hx.data(), x.x[p], hx.size() * sizeof(float), cudaMemcpyDeviceToHost));
        for (std::uint32_t i = 0; i < pm.owned; ++i)
            for (std::size_t c = 0; c < 3; ++c) out.x[c * n + pm.global_vertex[i]] = hx[c * local + i];
    }
    return out;
}

// ‖b − A·x‖ / ‖b‖ in double on the host.
double relative_residual(const BlockPattern& pattern, const std::vector<float>& blocks, const std::vector<float>& b,
                         const std::vector<float>& x) {
    const std::size_t n = pattern.row_start.size() - 1;
    double rr = 0.0, bb = 0.0;
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t r = 0; r < 3; ++r) {
            double acc = static_cast<double>(b[r * n + i]);
            for (std::uint32_t s = pattern.row_start[i]; s < pattern.row_start[i + 1]; ++s)
                for (std::size_t c = 0; c < 3; ++c)
                    acc -= static_cast<double>(blocks[9 * s + 3 * r + c]) * static_cast<double>(x[c * n + pattern.column[s]]);
            rr += acc * acc;
            bb += static_cast<double>(b[r * n + i]) * static_cast<double>(b[r * n + i]);
        }
    return std::sqrt(rr / bb);
}

// The parts' CG, driven on the devices, solves the whole system: it converges, its residual is small
// in double, and it takes the iterations of the one-part solve (their sums differ only in the order
// the parts add them).
TEST(MultiGpuParts, SingleReductionCgAcrossPartsMatchesOnePart) {
    WEFT_REQUIRE_GPU();
    const Problem problem;
    const std::vector<float> blocks = stiff_laplacian(problem.flat.pattern, 1.0F, 200.0F);
    const Solve one = solve_by_parts(problem.flat, blocks, problem.x, 1, {0});
    ASSERT_TRUE(one.result.converged) << one.result.iterations << " iterations, residual " << one.result.relative_residual;
    EXPECT_GT(one.result.iterations, 20) << "too easy a system to test anything";
    EXPECT_LT(relative_residual(problem.flat.pattern, blocks, problem.x, one.x), 1e-3);
    int devices = 0;
    WEFT_CUDA_CHECK(cudaGetDeviceCount(&devices));
    std::vector<std::pair<std::uint32_t, std::vector<int>>> cases{{3, {0, 0, 0}}, {5, {0, 0, 0, 0, 0}}};
    if (devices >= 2) cases.push_back({2, {0, 1}});
    for (const auto& [count, placement] : cases) {
        const Solve parts = solve_by_parts(problem.flat, blocks, problem.x, count, placement);
        SCOPED_TRACE(std::to_string(count) + " parts on " + (placement.back() == 0 ? "one GPU" : "two GPUs"));
        std::printf("[ multi    ] %u parts: %d iterations (one part: %d), residual %.2e\n", count, parts.result.iterations,
                    one.result.iterations, parts.result.relative_residual);
        ASSERT_TRUE(parts.result.converged);
        EXPECT_LE(std::abs(parts.result.iterations - one.result.iterations), 2);
        EXPECT_LT(relative_residual(problem.flat.pattern, blocks, problem.x, parts.x), 1e-3);
        double largest = 0.0, difference = 0.0;
        for (std::size_t k = 0; k < one.x.size(); ++k) {
            largest = std::max(largest, std::abs(static_cast<double>(one.x[k])));
            difference = std::max(difference, std::abs(static_cast<double>(parts.x[k]) - static_cast<double>(one.x[k])));
        }
        EXPECT_LT(difference, 1e-3 * largest);
    }
    // The batch only groups launches: an iteration past the stop changes nothing, so any batch gives
    // the same iterations and the same bits.
    const Solve short_batches = solve_by_parts(problem.flat, blocks, problem.x, 3, {0, 0, 0}, 2);
    const Solve long_batches = solve_by_parts(problem.flat, blocks, problem.x, 3, {0, 0, 0}, 64);
    EXPECT_EQ(short_batches.result.iterations, long_batches.result.iterations);
    for (std::size_t k = 0; k < short_batches.x.size(); ++k) ASSERT_EQ(short_batches.x[k], long_batches.x[k]) << "entry " << k;
}

// Where every part has its own GPU the loop runs as one cooperative kernel per GPU, the parts meeting
// through peer memory; it must give the graph batches' iterations and bits (the same sums in the
// same order), and parts sharing a GPU must keep the batches.
TEST(MultiGpuParts, OneLaunchPerGpuGivesTheBatchesBits) {
    WEFT_REQUIRE_GPU();
    int devices = 0;
    WEFT_CUDA_CHECK(cudaGetDeviceCount(&devices));
    if (devices < 2) GTEST_SKIP() << "one CUDA device: the one-launch loop needs a GPU per part";
    const Problem problem;
    const std::vector<float> blocks = stiff_laplacian(problem.flat.pattern, 1.0F, 200.0F);
    const Solve batches = solve_by_parts(problem.flat, blocks, problem.x, 2, {0, 1}, 16, cuda::PcgLoop::PerKernel);
    const Solve one_launch = solve_by_parts(problem.flat, blocks, problem.x, 2, {0, 1}, 16, cuda::PcgLoop::OneLaunch);
    std::printf("[ multi    ] 2 GPUs: %d iterations in batches, %d in one launch per GPU\n", batches.result.iterations,
                one_launch.result.iterations);
    ASSERT_TRUE(one_launch.result.converged);
    EXPECT_GT(one_launch.result.iterations, 20) << "too easy a system to test anything";
    EXPECT_EQ(one_launch.result.iterations, batches.result.iterations);
    EXPECT_EQ(one_launch.result.relative_residual, batches.result.relative_residual);
    for (std::size_t k = 0; k < batches.x.size(); ++k) ASSERT_EQ(one_launch.x[k], batches.x[k]) << "entry " << k;
    // A cap of a few iterations stops both forms at the same iterate.
    const Solve capped_batches = solve_by_parts(problem.flat, blocks, problem.x, 2, {0, 1}, 16, cuda::PcgLoop::PerKernel, 7);
    const Solve capped_one = solve_by_parts(problem.flat, blocks, problem.x, 2, {0, 1}, 16, cuda::PcgLoop::OneLaunch, 7);
    EXPECT_FALSE(capped_one.result.converged);
    EXPECT_EQ(capped_one.result.iterations, 7);
    EXPECT_EQ(capped_batches.result.iterations, 7);
    for (std::size_t k = 0; k < capped_batches.x.size(); ++k) ASSERT_EQ(capped_one.x[k], capped_batches.x[k]) << "entry " << k;
    const Parts set(problem.flat, blocks, 2, {0, 1});
    std::vector<cuda::multi::PartSystem> systems;
    for (std::size_t p = 0; p < set.matrices.size(); ++p) systems.push_back(set.matrices[p]->system(set.raw[p]));
    HaloExchange halo(set.vp, std::vector<int>{0, 1}, set.raw);
    PartPcg pcg(systems, halo);
    EXPECT_TRUE(pcg.one_launch());
    pcg.set_loop(cuda::PcgLoop::PerKernel);
    EXPECT_FALSE(pcg.one_launch());
    const Parts shared(problem.flat, blocks, 2, {0, 0});
    std::vector<cuda::multi::PartSystem> on_one;
    for (std::size_t p = 0; p < shared.matrices.size(); ++p) on_one.push_back(shared.matrices[p]->system(shared.raw[p]));
    HaloExchange shared_halo(shared.vp, std::vector<int>{0, 0}, shared.raw);
    EXPECT_FALSE(PartPcg(on_one, shared_halo).one_launch()) << "parts sharing a GPU cannot all be resident at once";
}

TEST(MultiGpuParts, BadInputIsAnError) {
    WEFT_REQUIRE_GPU();
    const Problem problem;
    const VertexPartition vp = partition(problem.flat, 2);
    test::Stream s;
    const std::vector<cudaStream_t> one{s.s};
    EXPECT_THROW(HaloExchange(vp, std::vector<int>{0}, one), Error);
    const PartModel pm = extract_part(problem.flat, vp, 0);
    PartMatrix m(pm, 0);
    EXPECT_THROW(m.multiply(nullptr, nullptr, 0, m.owned() + 1, s.s), Error);
    EXPECT_THROW(m.set_blocks(std::span<const float>(problem.blocks).first(9)), Error);
}

}  // namespace
}  // namespace weft
