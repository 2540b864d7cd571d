// CPU kernel micro-benchmarks: the SpMV and one PCG iteration in bytes moved per second (the
// solve is memory bound, so bytes are the cost model), and a whole substep.
//   build/bin/weft_micro_bench --benchmark_format=json --benchmark_out=cpu.json
#include <benchmark/benchmark.h>

#include "cpu/bsr_matrix.h"
#include "cpu/pcg.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace {

using namespace weft;

// A flag-like grid with about `triangles` triangles (aspect 5:3).
std::shared_ptr<const Fabric> flag_fabric(std::int64_t triangles) {
    const int cy = std::max(1, int(std::sqrt(double(triangles) * 3.0 / 10.0)));
    const int cx = std::max(1, int(double(triangles) / (2.0 * cy)));
    return Fabric::cook(make_grid(2.0, 1.2, cx, cy));
}

template <typename T>
void spmv(benchmark::State& state) {
    auto fabric = flag_fabric(state.range(0));
    cpu::BsrMatrix<T> A;
    A.resize(fabric->pattern());
    for (std::size_t s = 0; s < fabric->pattern().block_count(); ++s) A.set_block(s, physics::Mat3<T>::diagonal(T(1)));
    std::vector<physics::Vec3<T>> x(fabric->vertex_count(), physics::Vec3<T>{T(1), T(2), T(3)}), y(x.size());
    for (auto _ : state) {
        A.multiply(x, y);
        benchmark::DoNotOptimize(y.data());
    }
    // Bytes: every block (9 T) and its column index, x gathered once per block, y and row_start once per row.
    const double blocks = double(fabric->pattern().block_count()), rows = double(x.size());
    const double bytes = blocks * (9.0 * sizeof(T) + 4.0 + 3.0 * sizeof(T)) + rows * (3.0 * sizeof(T) + 4.0);
    state.SetBytesProcessed(std::int64_t(bytes) * state.iterations());
    state.counters["triangles"] = double(fabric->triangle_count());
    state.counters["blocks"] = blocks;
}

template <typename T>
void pcg_iteration(benchmark::State& state) {
    auto fabric = flag_fabric(state.range(0));
    cpu::BsrMatrix<T> A;
    A.resize(fabric->pattern());
    // A diagonally dominant SPD matrix, so every solve runs exactly the iteration cap.
    for (std::size_t i = 0; i < fabric->vertex_count(); ++i)
        for (std::uint32_t s = fabric->pattern().row_start[i]; s < fabric->pattern().row_start[i + 1]; ++s)
            A.set_block(s, s == fabric->pattern().diagonal[i] ? physics::Mat3<T>::diagonal(T(20)) : physics::Mat3<T>::diagonal(T(-1)));
    const std::size_t n = fabric->vertex_count();
    std::vector<physics::Vec3<T>> b(n, physics::Vec3<T>{T(1), T(0), T(-1)}), x(n);
    std::vector<std::uint8_t> fixed(n, 0);
    cpu::Pcg<T> pcg;
    pcg.resize(n);
    const int iterations = 20;
    for (auto _ : state) {
        std::fill(x.begin(), x.end(), physics::Vec3<T>{});
        auto r = pcg.solve(A, b, fixed, x, 1e-30, iterations);
        benchmark::DoNotOptimize(r);
    }
    state.SetItemsProcessed(state.iterations() * iterations);
    state.counters["triangles"] = double(fabric->triangle_count());
}

void substep(benchmark::State& state) {
    WorldDesc desc;
    desc.solver.precision = state.range(1) ? Precision::Double : Precision::Float;
    desc.wind.velocity = {8.0, 0.0, 0.0};
    desc.wind.turbulence = 2.0;
    World world(desc);
    auto fabric = flag_fabric(state.range(0));
    ClothDesc flag{.name = "flag", .fabric = fabric};
    world.add_cloth(flag);
    for (int i = 0; i < 3; ++i) world.step();
    int cg = 0;
    for (auto _ : state) cg += world.step().cg_iterations;
    state.counters["cg_per_step"] = benchmark::Counter(cg, benchmark::Counter::kAvgIterations);
    state.counters["triangles"] = double(fabric->triangle_count());
}

BENCHMARK(spmv<float>)->Arg(20000)->Arg(80000)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(spmv<double>)->Arg(20000)->Arg(80000)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(pcg_iteration<float>)->Arg(20000)->Arg(80000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(pcg_iteration<double>)->Arg(20000)->Arg(80000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(substep)->Args({20000, 0})->Args({20000, 1})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
