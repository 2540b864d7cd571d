// The multi-GPU product A·x on a scene's pattern (docs/multi-gpu.md): per part count G and device
// placement, the time of one product (a) with the halo exchange first and every row after it, and
// (b) pipelined, the interior rows running while the ghosts travel, then the boundary rows; the time
// hidden is (a) − (b), launched from the host and captured as CUDA graphs (how the solver runs). Also
// the exchange alone, the bytes it moves between devices, and the single-reduction CG's time per
// iteration (multi/part_pcg.h, graphs of 20 iterations), on a stiff SPD matrix of the scene's pattern.
// Medians of repeated timed runs, a table on stdout and JSON with --json.
//
//   weft_multi_gpu_spmv_bench SCENE.toml [--set key=value ...] [--parts 1,2] [--one-gpu] [--repeats 200] [--json FILE]
//
// Parts go round-robin over the visible GPUs; --one-gpu puts every part on GPU 0 (the test mode).
#include <cuda_runtime_api.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "cuda_check.h"
#include "multi/halo_exchange.h"
#include "multi/part_matrix.h"
#include "multi/part_pcg.h"
#include "part_counts.h"
#include "weft/backend/flat_model.h"
#include "weft/backend/part_model.h"
#include "weft/backend/schwarz_hierarchy.h"
#include "weft/backend/vertex_partition.h"
#include "weft/error.h"
#include "weft/scene.h"
#include "weft/world.h"

namespace {

using Clock = std::chrono::steady_clock;
using weft::cuda::multi::HaloExchange;
using weft::cuda::multi::PartMatrix;
using weft::cuda::multi::PartPcg;

struct Row {
    std::uint32_t parts = 0;
    int devices = 0;
    double exchange_us = 0, sequential_us = 0, pipelined_us = 0, sequential_graph_us = 0, pipelined_graph_us = 0;
    double cg_iteration_us = 0;
    std::uint64_t halo_bytes = 0;
};

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

/// Everything G parts need: matrices, streams, local vectors.
class Setup {
public:
    Setup(const weft::FlatModel& flat, const weft::SchwarzHierarchy& h, std::uint32_t parts, const std::vector<int>& devices)
        : devices_(devices) {
        const std::vector<double> work = weft::row_work(flat.pattern);
        vp_ = weft::build_partition(flat.pattern, weft::cut_order(h.order, work, parts, weft::SchwarzHierarchy::kDomainSize),
                                    parts, work);
        std::mt19937 rng(3);
        std::uniform_real_distribution<float> u(-1.0F, 1.0F);
        // A stiff SPD matrix on the pattern (m·I + k·L ⊗ I₃) so that the CG runs too; the product's
        // cost does not depend on the values.
        std::vector<float> blocks(9 * flat.pattern.block_count(), 0.0F);
        for (std::size_t i = 0; i < flat.vertex_count; ++i) {
            float degree = 0.0F;
            for (std::uint32_t s = flat.pattern.row_start[i]; s < flat.pattern.row_start[i + 1]; ++s)
                if (flat.pattern.column[s] != i) {
                    for (int d = 0; d < 3; ++d) blocks[9 * s + 4 * d] = -100.0F;
                    degree += 1.0F;
                }
            for (int d = 0; d < 3; ++d) blocks[9 * flat.pattern.diagonal[i] + 4 * d] = 1.0F + 100.0F * degree;
        }
        for (std::uint32_t p = 0; p < parts; ++p) {
            const weft::PartModel pm = weft::extract_part(flat, vp_, p);
            WEFT_CUDA_CHECK(cudaSetDevice(devices[p]));
            matrices_.push_back(std::make_unique<PartMatrix>(pm, devices[p]));
            matrices_.back()->set_blocks(blocks);
            cudaStream_t s = nullptr;
            WEFT_CUDA_CHECK(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking));
            streams_.push_back(s);
            std::vector<float> x(3 * pm.model.vertex_count);
            for (float& v : x) v = u(rng);
            float *dx = nullptr, *dy = nullptr;
            WEFT_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&dx), x.size() * sizeof(float)));
            WEFT_CUDA_CHECK(cudaMalloc(reinterpret_cast<void**>(&dy), x.size() * sizeof(float)));
        WEFT_CUDA_CHECK(cudaMemset(dy, 0, x.size() * sizeof(float)));  // ghost rows are never computed
            WEFT_CUDA_CHECK(cudaMemcpy(dx, x.data(), x.size() * sizeof(float), cudaMemcpyHostToDevice));
            x_.push_back(dx);
            y_.push_back(dy);
        }
        halo_ = std::make_unique<HaloExchange>(vp_, devices_, streams_);
        std::vector<weft::cuda::multi::PartSystem> systems;
        for (std::size_t p = 0; p < matrices_.size(); ++p) systems.push_back(matrices_[p]->system(streams_[p]));
        pcg_ = std::make_unique<PartPcg>(systems, *halo_);
    }

    /// Mean µs per iteration of the single-reduction CG run for `iterations` (tolerance 0; a multiple of
    /// 20, the batch each graph launch runs), with x as the right-hand side.
    double cg_us_per_iteration(int iterations) {
        std::vector<float*> solution;
        for (std::size_t p = 0; p < y_.size(); ++p) {
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
            WEFT_CUDA_CHECK(cudaMemsetAsync(y_[p], 0, 3 * matrices_[p]->local() * sizeof(float), streams_[p]));
            solution.push_back(y_[p]);
        }
        const std::vector<const float*> rhs(x_.begin(), x_.end());
        const auto t = Clock::now();
        const weft::cuda::multi::PartPcgResult r = pcg_->solve(rhs, solution, 0.0, iterations, 20);
        sync();
        const double us = std::chrono::duration<double, std::micro>(Clock::now() - t).count();
        return us / std::max(1, r.iterations);
    }
    ~Setup() {
        pcg_.reset();
        halo_.reset();
        for (std::size_t p = 0; p < x_.size(); ++p) {
            cudaSetDevice(devices_[p]);
            cudaFree(x_[p]);
            cudaFree(y_[p]);
            cudaStreamDestroy(streams_[p]);
        }
    }
    Setup(const Setup&) = delete;
    Setup& operator=(const Setup&) = delete;

    void exchange() { halo_->exchange(x_); }
    void begin_exchange() { halo_->begin(x_); }
    void finish_exchange() { halo_->finish(); }
    void rows(bool interior, bool boundary) {
        for (std::size_t p = 0; p < matrices_.size(); ++p) {
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
            const PartMatrix& m = *matrices_[p];
            m.multiply(x_[p], y_[p], interior ? 0 : m.interior(), boundary ? m.owned() : m.interior(), streams_[p]);
        }
    }
    void sync() {
        for (std::size_t p = 0; p < streams_.size(); ++p) {
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
            WEFT_CUDA_CHECK(cudaStreamSynchronize(streams_[p]));
        }
    }
    [[nodiscard]] std::uint64_t halo_bytes() const { return halo_->bytes_between_devices(); }

    /// Median wall time of `body` (µs) over `repeats` runs, each run synchronised at its end; with
    /// `graph`, `body` is captured once into a CUDA graph across the parts' devices and replayed.
    template <typename Body>
    double time_us(int repeats, Body body, bool graph = false) {
        if (graph) return time_graph_us(repeats, body);
        for (int w = 0; w < 5; ++w) body();
        sync();
        std::vector<double> us;
        for (int r = 0; r < repeats; ++r) {
            const auto t = Clock::now();
            body();
            sync();
            us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t).count());
        }
        return median(us);
    }

private:
    template <typename Body>
    double time_graph_us(int repeats, Body body) {
        // Capture on part 0's stream; the other parts' streams fork from it and join it again.
        cudaStream_t origin = streams_[0];
        std::vector<cudaEvent_t> events(streams_.size());
        for (std::size_t p = 0; p < streams_.size(); ++p) {
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
            WEFT_CUDA_CHECK(cudaEventCreateWithFlags(&events[p], cudaEventDisableTiming));
        }
        WEFT_CUDA_CHECK(cudaSetDevice(devices_[0]));
        WEFT_CUDA_CHECK(cudaStreamBeginCapture(origin, cudaStreamCaptureModeGlobal));
        WEFT_CUDA_CHECK(cudaEventRecord(events[0], origin));
        for (std::size_t p = 1; p < streams_.size(); ++p) {
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
            WEFT_CUDA_CHECK(cudaStreamWaitEvent(streams_[p], events[0], 0));
        }
        body();
        for (std::size_t p = 1; p < streams_.size(); ++p) {
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
            WEFT_CUDA_CHECK(cudaEventRecord(events[p], streams_[p]));
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[0]));
            WEFT_CUDA_CHECK(cudaStreamWaitEvent(origin, events[p], 0));
        }
        WEFT_CUDA_CHECK(cudaSetDevice(devices_[0]));
        cudaGraph_t g = nullptr;
        WEFT_CUDA_CHECK(cudaStreamEndCapture(origin, &g));
        cudaGraphExec_t exec = nullptr;
        WEFT_CUDA_CHECK(cudaGraphInstantiate(&exec, g, 0));
        for (int w = 0; w < 5; ++w) WEFT_CUDA_CHECK(cudaGraphLaunch(exec, origin));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(origin));
        std::vector<double> us;
        for (int r = 0; r < repeats; ++r) {
            const auto t = Clock::now();
            WEFT_CUDA_CHECK(cudaGraphLaunch(exec, origin));
            WEFT_CUDA_CHECK(cudaStreamSynchronize(origin));
            us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t).count());
        }
        cudaGraphExecDestroy(exec);
        cudaGraphDestroy(g);
        for (std::size_t p = 0; p < events.size(); ++p) {
            WEFT_CUDA_CHECK(cudaSetDevice(devices_[p]));
            cudaEventDestroy(events[p]);
        }
        return median(us);
    }

    std::vector<int> devices_;
    weft::VertexPartition vp_;
    std::vector<std::unique_ptr<PartMatrix>> matrices_;
    std::vector<cudaStream_t> streams_;
    std::vector<float*> x_, y_;
    std::unique_ptr<HaloExchange> halo_;
    std::unique_ptr<PartPcg> pcg_;
};

}  // namespace

int main(int argc, char** argv) {
    try {
        if (argc < 2) {
            std::cerr << "usage: weft_multi_gpu_spmv_bench SCENE.toml [--set key=value ...] [--parts 1,2] [--one-gpu] "
                         "[--repeats N] [--json FILE]\n";
            return 2;
        }
        std::vector<std::string> overrides;
        std::vector<std::uint32_t> counts{1, 2};
        bool one_gpu = false;
        int repeats = 200;
        std::string json_path;
        for (int a = 2; a < argc; ++a) {
            const std::string arg = argv[a];
            if (arg == "--one-gpu") {
                one_gpu = true;
                continue;
            }
            if (a + 1 >= argc) throw weft::Error("'" + arg + "' needs a value");
            if (arg == "--set") overrides.emplace_back(argv[++a]);
            else if (arg == "--parts") counts = weft::bench::parse_part_counts(argv[++a], 64);
            else if (arg == "--repeats") repeats = std::max(1, std::stoi(argv[++a]));
            else if (arg == "--json") json_path = argv[++a];
            else throw weft::Error("unknown argument '" + arg + "'");
        }
        int gpus = 0;
        WEFT_CUDA_CHECK(cudaGetDeviceCount(&gpus));
        if (gpus == 0) throw weft::Error("no CUDA device");
        const weft::SceneDesc scene = weft::load_scene(argv[1], overrides);
        const auto world = weft::build_world(scene, "cpu");
        const weft::FlatModel flat = weft::flatten(world->model());
        const weft::SchwarzHierarchy h = weft::build_schwarz_hierarchy(flat.initial_positions, flat.pattern);
        cudaDeviceProp prop{};
        WEFT_CUDA_CHECK(cudaGetDeviceProperties(&prop, 0));
        std::printf("%s: %zu vertices, %zu blocks; %d × %s%s\n", argv[1], flat.vertex_count, flat.pattern.block_count(), gpus,
                    prop.name, one_gpu ? " (every part on GPU 0)" : "");
        std::vector<Row> rows;
        for (const std::uint32_t parts : counts) {
            std::vector<int> devices(parts);
            for (std::uint32_t p = 0; p < parts; ++p) devices[p] = one_gpu ? 0 : static_cast<int>(p % static_cast<std::uint32_t>(gpus));
            Setup setup(flat, h, parts, devices);
            Row r;
            r.parts = parts;
            r.devices = one_gpu ? 1 : std::min<int>(gpus, static_cast<int>(parts));
            r.exchange_us = setup.time_us(repeats, [&] { setup.exchange(); });
            r.sequential_us = setup.time_us(repeats, [&] {
                setup.exchange();
                setup.rows(true, true);
            });
            r.pipelined_us = setup.time_us(repeats, [&] {
                setup.begin_exchange();
                setup.rows(true, false);
                setup.finish_exchange();
                setup.rows(false, true);
            });
            // The same two, each captured once into a CUDA graph over the parts' devices and replayed
            // (how the solver runs a substep): the host's launch and event calls leave the critical path.
            r.sequential_graph_us = setup.time_us(repeats, [&] {
                setup.exchange();
                setup.rows(true, true);
            }, true);
            r.pipelined_graph_us = setup.time_us(repeats, [&] {
                setup.begin_exchange();
                setup.rows(true, false);
                setup.finish_exchange();
                setup.rows(false, true);
            }, true);
            r.halo_bytes = setup.halo_bytes();
            setup.cg_us_per_iteration(20);  // warm
            r.cg_iteration_us = setup.cg_us_per_iteration(200);
            rows.push_back(r);
        }
        std::printf("| parts | GPUs | exchange µs | exchange then product µs | pipelined µs | the same as graphs: exchange then product µs | pipelined µs | hidden by the pipeline µs | bytes between GPUs | CG µs per iteration |\n");
        std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
        for (const Row& r : rows)
            std::printf("| %u | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %llu | %.1f |\n", r.parts, r.devices, r.exchange_us,
                        r.sequential_us, r.pipelined_us, r.sequential_graph_us, r.pipelined_graph_us,
                        r.sequential_graph_us - r.pipelined_graph_us, static_cast<unsigned long long>(r.halo_bytes),
                        r.cg_iteration_us);
        if (!json_path.empty()) {
            std::ofstream json(json_path);
            json << "{\"scene\": \"" << argv[1] << "\", \"gpu\": \"" << prop.name << "\", \"rows\": [";
            for (std::size_t k = 0; k < rows.size(); ++k) {
                const Row& r = rows[k];
                json << (k ? ", " : "") << "{\"parts\": " << r.parts << ", \"gpus\": " << r.devices
                     << ", \"exchange_us\": " << r.exchange_us << ", \"sequential_us\": " << r.sequential_us
                     << ", \"pipelined_us\": " << r.pipelined_us << ", \"sequential_graph_us\": " << r.sequential_graph_us
                     << ", \"pipelined_graph_us\": " << r.pipelined_graph_us << ", \"cg_iteration_us\": " << r.cg_iteration_us
                     << ", \"halo_bytes\": " << r.halo_bytes << "}";
            }
            json << "]}\n";
            if (!json) throw weft::Error("cannot write '" + json_path + "'");
        }
        return 0;
    } catch (const std::exception& e) {
        std::cerr << "weft_multi_gpu_spmv_bench: " << e.what() << "\n";
        return 1;
    }
}
