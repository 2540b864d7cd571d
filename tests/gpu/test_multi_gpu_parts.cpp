// The multi-GPU building blocks on the device (cuda/src/multi/): the halo exchange fills every ghost
// with its owner's value, and the parts' products through it (interior rows first, boundary rows
// after the exchange, as the pipelined SpMV runs them) are the whole product's bits. G parts run on
// one GPU (the test mode, any GPU host) and, where two GPUs are present, two parts on two GPUs.
#include <cuda_runtime_api.h>

#include <cstdio>
#include <random>
#include <vector>

#include "gpu_test_util.h"
#include "multi/halo_exchange.h"
#include "multi/part_matrix.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/part_model.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/backend/vertex_partition.h"
#include "weft/fabric.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft {
namespace {

using cuda::multi::HaloExchange;
using cuda::multi::PartMatrix;

// Two cloths (a flag-like sheet and a smaller one beside it): a world's flat model.
FlatModel two_cloths() {
    World world;
    world.add_cloth({.name = "a", .fabric = Fabric::cook(make_grid(2.0, 1.2, 60, 36))});
    ClothDesc b{.name = "b", .fabric = Fabric::cook(make_grid(0.6, 0.4, 15, 9))};
    b.transform.translation = {0.3, 0.2, 0.05};
    world.add_cloth(b);
    return flatten(world.model());
}

VertexPartition partition(const FlatModel& flat, std::uint32_t parts) {
    const SchwarzHierarchy h = build_schwarz_hierarchy(flat.initial_positions, flat.pattern);
    const std::vector<double> work = row_work(flat.pattern);
    return build_partition(flat.pattern, cut_order(h.order, work, parts, SchwarzHierarchy::kDomainSize), parts, work);
}

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

// The product of every part's owned rows as the pipelined product runs it: the exchange begins, the
// interior rows run while it travels, the boundary rows follow it; returns the global result (SoA) and checks every ghost.
std::vector<float> product_by_parts(const FlatModel& flat, const std::vector<float>& blocks, const std::vector<float>& x,
                                    std::uint32_t count, const std::vector<int>& devices) {
    const std::size_t n = flat.vertex_count;
    const VertexPartition vp = partition(flat, count);
    std::vector<PartModel> parts;
    std::vector<std::unique_ptr<PartMatrix>> matrices;
    std::vector<std::unique_ptr<test::Stream>> streams;
    std::vector<cudaStream_t> raw;
    for (std::uint32_t p = 0; p < count; ++p) {
        parts.push_back(extract_part(flat, vp, p));
        WEFT_CUDA_CHECK(cudaSetDevice(devices[p]));
        matrices.push_back(std::make_unique<PartMatrix>(parts.back(), devices[p]));
        matrices.back()->set_blocks(blocks);
        streams.push_back(std::make_unique<test::Stream>());
        raw.push_back(streams.back()->s);
    }
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
