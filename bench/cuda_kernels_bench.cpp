// CUDA kernel benchmarks on the flag scene at several sizes: device copy bandwidth (the reference),
// the sliced-ELL SpMV and one PCG iteration in bytes moved per second (the solve is memory bound, so
// bytes are the cost model and the issue's target is SpMV >= 60 % of copy bandwidth), and the whole
// step with its stage times, CG iterations and device memory.
//
//   build/bin/weft_cuda_bench                       # 80K, 200K and 1.2M triangles
//   build/bin/weft_cuda_bench --sizes 80000,400x250 --json out/cuda_kernels.json
//   build/bin/weft_cuda_bench --size 1200000@solver.dt=0.004@solver.substeps=1
//
// Without a GPU it prints "no CUDA device: REASON" and exits 0 (the JSON file, if asked for, says
// the same and holds no measurements).
#include <cuda_runtime_api.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "backend_access.h"
#include "build_info.h"
#include "cuda_check.h"
#include "device_solver.h"
#include "distribution.h"
#include "json_file.h"
#include "json_writer.h"
#include "kernels.h"
#include "scene_lookup.h"
#include "text_table.h"
#include "weft/backend/timing.h"
#include "weft/cuda/cuda_backend.h"
#include "weft/error.h"
#include "weft/scene.h"
#include "weft/stats.h"
#include "weft/world.h"

namespace {

using namespace weft;
using cli::format_fixed;
using cli::TextTable;
using json::JsonWriter;
using Clock = std::chrono::steady_clock;

constexpr double kFlagAspect = 2.0 / 1.2;  // the flag scene's 2.0 m x 1.2 m grid
constexpr std::size_t kMinCopyBytes = std::size_t{256} << 20;

// ---- options --------------------------------------------------------------------------------------

struct SizeSpec {
    int cells_x = 0, cells_y = 0;
    std::vector<std::string> overrides;  ///< applied after the global ones
    std::string label;                   ///< the size as given (triangles or CXxCY)
    std::string text;                    ///< the whole spec as given, overrides included
};

struct Options {
    std::vector<SizeSpec> sizes;
    std::vector<std::string> overrides;  ///< --set, --dt, --substeps: every size
    std::filesystem::path json_file;
    std::string scene = "flag";
    int warmup = 5;
    int frames = 30;
    int copy_reps = 50;
    int spmv_reps = 100;
    int pcg_iterations = 100;
    int pcg_reps = 5;
    bool print_sizes = false;
};

constexpr const char* kUsage = R"(Usage: weft_cuda_bench [options]

CUDA kernel benchmarks on the flag scene: device copy bandwidth, SpMV and one PCG iteration (GB/s and
ratio to copy bandwidth), and the whole step (stage times, CG iterations, device memory).

Options:
  --sizes LIST        comma-separated sizes, each a triangle count (cells chosen for the flag's 5:3
                      aspect, exact count when possible) or CXxCY grid cells, e.g. 80000,400x250
  --size SPEC         one size with its own overrides: SIZE[@KEY=VALUE...], repeatable, e.g.
                      1200000@solver.dt=0.004@solver.substeps=1
                      default (no --sizes/--size): 80000 200000 1200000@solver.dt=0.004@solver.substeps=1
                      (= cells 250x160, 400x250, 1000x600)
  --set KEY=VALUE     scene override for every size; repeatable
  --dt SECONDS        same as --set solver.dt=SECONDS
  --substeps N        same as --set solver.substeps=N
  --scene NAME|PATH   scene (default flag); its cloth must be called "flag" with a grid mesh
  --warmup N          untimed frames before measuring (the first builds; at least 1); default 5
  --frames N          timed whole-step frames; default 30
  --copy-reps N       device-to-device copies timed; default 50
  --spmv-reps N       SpMVs timed (warm and L2-flushed each); default 100
  --pcg-iterations K  CG iterations per timed batch; default 100
  --pcg-reps N        timed batches of K iterations (stream and graph each); default 5
  --json FILE         write every number as JSON
  --print-sizes       print the sizes (cells, triangles, overrides) and exit; needs no GPU
  -h, --help          this text
)";

[[noreturn]] void usage_error(const std::string& message) {
    std::cerr << "weft_cuda_bench: " << message << "\n(weft_cuda_bench --help lists the options)\n";
    std::exit(2);
}

int parse_int(const std::string& text, const std::string& what, int min) {
    try {
        std::size_t used = 0;
        const long long v = std::stoll(text, &used);
        if (used != text.size() || v < min || v > INT_MAX) throw std::invalid_argument(text);
        return static_cast<int>(v);
    } catch (const std::exception&) {
        usage_error(what + " expects an integer >= " + std::to_string(min) + ", got '" + text + "'");
    }
}

/// Grid cells for about `triangles` triangles (2 per cell) with the flag's aspect: the divisor pair of
/// triangles/2 closest to 5:3 when one is within 10 %, else the rounded pair closest to it.
std::pair<int, int> cells_for(long long triangles) {
    const long long half = std::max(1LL, triangles / 2);
    const double ideal_y = std::sqrt(static_cast<double>(half) / kFlagAspect);
    int best_x = 0, best_y = 0;
    double best = 1e300;
    const int hi = static_cast<int>(std::max(2.0, 2.0 * ideal_y));
    for (int cy = 1; cy <= hi; ++cy) {
        if (half % cy != 0) continue;
        const long long cx = half / cy;
        if (cx > INT_MAX) continue;
        const double err = std::abs(std::log(static_cast<double>(cx) / cy / kFlagAspect));
        if (err < best) {
            best = err;
            best_x = static_cast<int>(cx);
            best_y = cy;
        }
    }
    if (best <= std::log(1.1)) return {best_x, best_y};
    const int cy = std::max(1, static_cast<int>(std::lround(ideal_y)));
    const int cx = std::max(1, static_cast<int>(std::llround(static_cast<double>(half) / cy)));
    return {cx, cy};
}

std::vector<std::string> split(const std::string& text, char sep) {
    std::vector<std::string> out;
    std::string item;
    std::istringstream in(text);
    while (std::getline(in, item, sep)) out.push_back(item);
    return out;
}

SizeSpec parse_size(const std::string& spec) {
    std::vector<std::string> parts = split(spec, '@');
    if (parts.empty() || parts[0].empty()) usage_error("empty size in '" + spec + "'");
    SizeSpec s;
    s.label = parts[0];
    s.text = spec;
    const std::string& size = parts[0];
    const auto x = size.find_first_of("xX");
    if (x != std::string::npos) {
        s.cells_x = parse_int(size.substr(0, x), "grid cells", 1);
        s.cells_y = parse_int(size.substr(x + 1), "grid cells", 1);
    } else {
        const auto [cx, cy] = cells_for(parse_int(size, "a size in triangles", 2));
        s.cells_x = cx;
        s.cells_y = cy;
    }
    for (std::size_t k = 1; k < parts.size(); ++k) {
        if (parts[k].find('=') == std::string::npos) usage_error("size override '" + parts[k] + "' is not KEY=VALUE");
        s.overrides.push_back(parts[k]);
    }
    return s;
}

Options parse_options(int argc, char** argv) {
    Options o;
    auto need = [&](int& i) -> std::string {
        if (i + 1 >= argc) usage_error(std::string(argv[i]) + " needs a value");
        return argv[++i];
    };
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "-h" || a == "--help") {
            std::cout << kUsage;
            std::exit(0);
        } else if (a == "--sizes") {
            for (const std::string& s : split(need(i), ',')) o.sizes.push_back(parse_size(s));
        } else if (a == "--size") {
            o.sizes.push_back(parse_size(need(i)));
        } else if (a == "--set") {
            const std::string kv = need(i);
            if (kv.find('=') == std::string::npos) usage_error("--set expects KEY=VALUE, got '" + kv + "'");
            o.overrides.push_back(kv);
        } else if (a == "--dt") {
            o.overrides.push_back("solver.dt=" + need(i));
        } else if (a == "--substeps") {
            o.overrides.push_back("solver.substeps=" + std::to_string(parse_int(need(i), "--substeps", 1)));
        } else if (a == "--scene") {
            o.scene = need(i);
        } else if (a == "--json") {
            o.json_file = need(i);
        } else if (a == "--warmup") {
            o.warmup = parse_int(need(i), "--warmup", 0);
        } else if (a == "--frames") {
            o.frames = parse_int(need(i), "--frames", 1);
        } else if (a == "--copy-reps") {
            o.copy_reps = parse_int(need(i), "--copy-reps", 1);
        } else if (a == "--spmv-reps") {
            o.spmv_reps = parse_int(need(i), "--spmv-reps", 1);
        } else if (a == "--pcg-iterations") {
            o.pcg_iterations = parse_int(need(i), "--pcg-iterations", 1);
        } else if (a == "--print-sizes") {
            o.print_sizes = true;
        } else if (a == "--pcg-reps") {
            o.pcg_reps = parse_int(need(i), "--pcg-reps", 1);
        } else {
            usage_error("unknown option '" + a + "'");
        }
    }
    if (o.sizes.empty())
        for (const char* s : {"80000", "200000", "1200000@solver.dt=0.004@solver.substeps=1"}) o.sizes.push_back(parse_size(s));
    return o;
}

// ---- statistics -----------------------------------------------------------------------------------

using bench::Dist;
using bench::distribution;
using bench::write_dist;
constexpr auto kDistFields = bench::DistFields::median_min_max_mean;

double gb_per_s(double bytes, double ms) { return ms > 0.0 ? bytes / (ms * 1e-3) / 1e9 : 0.0; }

// ---- CUDA helpers ---------------------------------------------------------------------------------

class Event {
public:
    Event() { WEFT_CUDA_CHECK(cudaEventCreate(&e_)); }
    ~Event() { cudaEventDestroy(e_); }
    Event(const Event&) = delete;
    Event& operator=(const Event&) = delete;
    cudaEvent_t get() const { return e_; }

private:
    cudaEvent_t e_ = nullptr;
};

class Stream {
public:
    Stream() { WEFT_CUDA_CHECK(cudaStreamCreateWithFlags(&s_, cudaStreamNonBlocking)); }
    ~Stream() { cudaStreamDestroy(s_); }
    Stream(const Stream&) = delete;
    Stream& operator=(const Stream&) = delete;
    cudaStream_t get() const { return s_; }

private:
    cudaStream_t s_ = nullptr;
};

class Buffer {
public:
    explicit Buffer(std::size_t bytes) : bytes_(bytes) { WEFT_CUDA_CHECK(cudaMalloc(&p_, bytes)); }
    ~Buffer() { cudaFree(p_); }
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;
    template <typename T = unsigned char>
    T* get() const {
        return static_cast<T*>(p_);
    }
    std::size_t bytes() const { return bytes_; }

private:
    void* p_ = nullptr;
    std::size_t bytes_ = 0;
};

/// Milliseconds `work` takes on `stream`, between two events; `before` runs first, untimed.
template <typename Before, typename Work>
double time_on(cudaStream_t stream, Before before, Work work) {
    Event start, stop;
    before();
    WEFT_CUDA_CHECK(cudaEventRecord(start.get(), stream));
    work();
    WEFT_CUDA_CHECK(cudaEventRecord(stop.get(), stream));
    WEFT_CUDA_CHECK(cudaEventSynchronize(stop.get()));
    float ms = 0.0f;
    WEFT_CUDA_CHECK(cudaEventElapsedTime(&ms, start.get(), stop.get()));
    return static_cast<double>(ms);
}

// ---- results --------------------------------------------------------------------------------------

struct Rate {
    Dist ms;
    double gbps = 0, ratio = 0;  ///< GB/s from the median, and its ratio to copy bandwidth
};

struct SizeResult {
    SizeSpec spec;
    std::vector<std::string> overrides;  // all, in the order applied
    std::string error;                   // non-empty: this size failed
    std::size_t triangles = 0, vertices = 0;
    double dt = 0;
    int substeps = 0, newton = 0, cg_max_iterations = 0;
    double cg_tolerance = 0;
    double build_seconds = 0;
    std::string device_description;
    bool graph_active = false;

    // Matrix.
    std::size_t rows = 0, slices = 0, positions = 0;
    double matrix_bytes = 0;  // blocks + columns + slice_start

    // Copy.
    std::size_t copy_buffer_bytes = 0;
    Rate copy;

    // SpMV.
    double spmv_bytes = 0;
    bool spmv_l2_resident = false;
    Rate spmv_warm, spmv_cold;

    // PCG iteration.
    double pcg_bytes = 0;
    Rate pcg_stream, pcg_graph;   // ms per iteration
    int pcg_iterations_done = 0;  // iterations the control block counted in the last batch (must be K)
    bool pcg_stopped_early = false;
    std::string pcg_note;

    // Whole step.
    Dist wall_ms, step_ms;
    std::vector<Dist> stage_ms;
    Dist cg_iterations;
    int cg_not_converged = 0, non_finite_frames = 0;

    // Memory.
    std::size_t memory_bytes = 0;
    std::vector<std::pair<std::string, std::size_t>> memory_breakdown;
};

// ---- one size -------------------------------------------------------------------------------------

void measure(const Options& opt, const std::filesystem::path& scene_path, int l2_bytes, SizeResult& r) {
    r.overrides = opt.overrides;
    r.overrides.push_back("cloth.flag.mesh.grid.cells=[" + std::to_string(r.spec.cells_x) + "," +
                          std::to_string(r.spec.cells_y) + "]");
    for (const std::string& o : r.spec.overrides) r.overrides.push_back(o);

    const auto build_start = Clock::now();
    const SceneDesc desc = load_scene(scene_path, r.overrides);
    std::unique_ptr<World> world = build_world(desc, "cuda");
    const WorldDesc& settings = world->settings();
    r.dt = settings.solver.dt;
    r.substeps = settings.solver.substeps;
    r.newton = settings.solver.newton_iterations;
    r.cg_tolerance = settings.solver.cg_tolerance;
    r.cg_max_iterations = settings.solver.cg_max_iterations;

    std::cerr << "size " << r.spec.text << " (cells " << r.spec.cells_x << "x" << r.spec.cells_y << "): build + "
              << opt.warmup << " warm-up frames" << std::endl;
    // The first step builds the backend (flattening, layout, upload) and assembles the matrix.
    world->step();
    r.build_seconds = std::chrono::duration<double>(Clock::now() - build_start).count();
    for (int i = 1; i < opt.warmup; ++i) world->step();

    // ---- whole step
    std::cerr << "  " << opt.frames << " timed frames" << std::endl;
    std::vector<double> wall, step, cg;
    std::vector<std::vector<double>> stages(static_cast<std::size_t>(Stage::Count));
    for (int f = 0; f < opt.frames; ++f) {
        const auto t0 = Clock::now();
        const StepStats& s = world->step();
        wall.push_back(ms_since(t0));
        step.push_back(s.step_ms);
        cg.push_back(static_cast<double>(s.cg_iterations));
        for (std::size_t k = 0; k < stages.size(); ++k) stages[k].push_back(s.stage_ms[k]);
        r.cg_not_converged += s.cg_not_converged;
        if (s.non_finite) ++r.non_finite_frames;
    }
    r.wall_ms = distribution(wall);
    r.step_ms = distribution(step);
    r.cg_iterations = distribution(cg);
    for (const auto& s : stages) r.stage_ms.push_back(distribution(s));

    Backend& backend = world->backend();
    r.device_description = backend.device_description();
    r.memory_bytes = backend.memory_bytes();
    if (cuda::CudaBackendApi* api = cuda::as_cuda(backend)) {
        r.memory_breakdown = api->memory_breakdown();
        r.graph_active = api->graph_active();
    }
    cuda::DeviceSolver* solver = cuda::device_solver(backend);
    if (solver == nullptr) throw Error("the world's backend is not the CUDA backend");
    const cuda::DeviceView view = solver->view();
    const cuda::EllLayout& ell = solver->layout().ell;
    r.vertices = view.n;
    r.triangles = view.triangles;
    r.rows = view.n;
    r.slices = ell.slices();
    r.positions = ell.positions();
    WEFT_CUDA_CHECK(cudaSetDevice(solver->device()));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(solver->stream()));

    const double n = static_cast<double>(view.n);
    const double positions = static_cast<double>(r.positions);
    const double slice_start_bytes = 4.0 * static_cast<double>(r.slices + 1);
    // Matrix: 9 floats per block position, one uint32 column per position, slice_start.
    r.matrix_bytes = positions * 36.0 + positions * 4.0 + slice_start_bytes;
    // SpMV: the matrix once, x read once (3n floats, at least), y written once (3n floats).
    r.spmv_bytes = r.matrix_bytes + 12.0 * n + 12.0 * n;
    r.spmv_l2_resident = r.spmv_bytes < static_cast<double>(l2_bytes);
    // PCG iteration, three kernels:
    //  spmv+dot: the SpMV bytes (c gathered, q written) + fixed (1 B/row);
    //  update: read r, q, dv, c (4 x 3n floats) and P^-1 (9n floats), write dv, r, s (3 x 3n floats);
    //  direction: read s, c (2 x 3n floats) and fixed (1 B/row), write c (3n floats).
    r.pcg_bytes = (r.spmv_bytes + n) + (4.0 * 12.0 * n + 36.0 * n + 3.0 * 12.0 * n) + (2.0 * 12.0 * n + n + 12.0 * n);

    Stream stream_owner;
    const cudaStream_t stream = stream_owner.get();

    // ---- copy bandwidth: a D2D copy about the matrix's size, at least 256 MiB (beyond the L2)
    std::cerr << "  copy, SpMV, PCG" << std::endl;
    const std::size_t copy_bytes =
        (std::max(kMinCopyBytes, static_cast<std::size_t>(r.matrix_bytes)) + 255) / 256 * 256;
    r.copy_buffer_bytes = copy_bytes;
    Buffer src(copy_bytes), dst(copy_bytes);
    WEFT_CUDA_CHECK(cudaMemsetAsync(src.get(), 1, copy_bytes, stream));
    WEFT_CUDA_CHECK(cudaMemsetAsync(dst.get(), 0, copy_bytes, stream));
    auto copy_once = [&] {
        WEFT_CUDA_CHECK(cudaMemcpyAsync(dst.get(), src.get(), copy_bytes, cudaMemcpyDeviceToDevice, stream));
    };
    copy_once();  // warm
    std::vector<double> times;
    for (int k = 0; k < opt.copy_reps; ++k) times.push_back(time_on(stream, [] {}, copy_once));
    r.copy.ms = distribution(times);
    r.copy.gbps = gb_per_s(2.0 * static_cast<double>(copy_bytes), r.copy.ms.median);
    r.copy.ratio = 1.0;
    auto rate = [&](const std::vector<double>& ms, double bytes, double per) {
        Rate out;
        std::vector<double> scaled;
        for (double t : ms) scaled.push_back(t / per);
        out.ms = distribution(scaled);
        out.gbps = gb_per_s(bytes, out.ms.median);
        out.ratio = r.copy.gbps > 0.0 ? out.gbps / r.copy.gbps : 0.0;
        return out;
    };

    // ---- SpMV on the assembled matrix: x = the positions (finite, non-trivial), y scratch
    const std::size_t vec_bytes = std::size_t{3} * view.n * sizeof(float);
    Buffer x(vec_bytes), y(vec_bytes);
    WEFT_CUDA_CHECK(cudaMemcpyAsync(x.get(), view.x, vec_bytes, cudaMemcpyDeviceToDevice, stream));
    auto spmv_once = [&] { cuda::launch_spmv(view, x.get<float>(), y.get<float>(), stream); };
    spmv_once();
    times.clear();
    for (int k = 0; k < opt.spmv_reps; ++k) times.push_back(time_on(stream, [] {}, spmv_once));
    r.spmv_warm = rate(times, r.spmv_bytes, 1.0);
    // L2 flushed first: write twice the L2 size (from the copy destination) before each SpMV.
    const std::size_t flush_bytes = std::min(copy_bytes, std::max<std::size_t>(2 * static_cast<std::size_t>(l2_bytes), 64u << 20));
    times.clear();
    for (int k = 0; k < opt.spmv_reps; ++k)
        times.push_back(time_on(
            stream, [&] { WEFT_CUDA_CHECK(cudaMemsetAsync(dst.get(), k & 0xff, flush_bytes, stream)); }, spmv_once));
    r.spmv_cold = rate(times, r.spmv_bytes, 1.0);

    // ---- PCG iterations, forced to run: eps2 = 0 and no cap in the device's copy of the header
    cuda::StepParams original{};
    auto* staging = const_cast<unsigned char*>(view.staging);
    WEFT_CUDA_CHECK(cudaMemcpyAsync(&original, staging, sizeof original, cudaMemcpyDeviceToHost, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
    cuda::StepParams forced = original;
    forced.cg_eps2 = 0.0;
    forced.cg_max_iterations = INT_MAX / 2;
    WEFT_CUDA_CHECK(cudaMemcpyAsync(staging, &forced, sizeof forced, cudaMemcpyHostToDevice, stream));
    const int K = opt.pcg_iterations;
    const int one = 1;
    auto restart = [&] {
        // A fresh solve of the last assembled system: P^-1, dv, r, c, delta; then force `running`.
        cuda::launch_pcg_setup(view, false, false, stream);  // Δv from 0 (no warm start)
        cuda::launch_pcg_residual(view, 0, false, stream);
        WEFT_CUDA_CHECK(cudaMemcpyAsync(reinterpret_cast<unsigned char*>(view.control) + offsetof(cuda::PcgControl, running),
                                        &one, sizeof one, cudaMemcpyHostToDevice, stream));
    };
    auto check = [&](const char* mode) {
        cuda::PcgControl ctl{};
        WEFT_CUDA_CHECK(cudaMemcpyAsync(&ctl, view.control, sizeof ctl, cudaMemcpyDeviceToHost, stream));
        WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
        r.pcg_iterations_done = ctl.iterations;
        if (ctl.iterations != K || ctl.running == 0) {
            r.pcg_stopped_early = true;
            r.pcg_note += std::string(mode) + ": loop stopped after " + std::to_string(ctl.iterations) + " of " +
                          std::to_string(K) + " iterations (delta " + std::to_string(ctl.delta) + ", cq " +
                          std::to_string(ctl.cq) + "); ";
        }
    };
    auto iterations = [&] {
        for (int k = 0; k < K; ++k) cuda::launch_pcg_iteration(view, 0, false, stream);
    };
    restart();
    iterations();  // warm
    times.clear();
    for (int rep = 0; rep < opt.pcg_reps; ++rep) {
        times.push_back(time_on(stream, restart, iterations));
        check("stream");
    }
    r.pcg_stream = rate(times, r.pcg_bytes, K);

    // The same K iterations as one CUDA graph (as the solver runs them, minus the while node).
    cudaGraph_t graph = nullptr;
    cudaGraphExec_t exec = nullptr;
    WEFT_CUDA_CHECK(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal));
    try {
        iterations();
    } catch (...) {
        cudaStreamEndCapture(stream, &graph);
        if (graph != nullptr) cudaGraphDestroy(graph);
        throw;
    }
    WEFT_CUDA_CHECK(cudaStreamEndCapture(stream, &graph));
    const cudaError_t inst = cudaGraphInstantiate(&exec, graph, 0);
    cudaGraphDestroy(graph);
    if (inst != cudaSuccess) cuda::throw_cuda_error(inst, "cudaGraphInstantiate", __FILE__, __LINE__);
    try {
        restart();
        WEFT_CUDA_CHECK(cudaGraphLaunch(exec, stream));  // warm
        times.clear();
        for (int rep = 0; rep < opt.pcg_reps; ++rep) {
            times.push_back(time_on(stream, restart, [&] { WEFT_CUDA_CHECK(cudaGraphLaunch(exec, stream)); }));
            check("graph");
        }
    } catch (...) {
        cudaGraphExecDestroy(exec);
        throw;
    }
    cudaGraphExecDestroy(exec);
    r.pcg_graph = rate(times, r.pcg_bytes, K);

    // Put the header back (the next substep would rewrite it anyway) and leave the device idle.
    WEFT_CUDA_CHECK(cudaMemcpyAsync(staging, &original, sizeof original, cudaMemcpyHostToDevice, stream));
    WEFT_CUDA_CHECK(cudaStreamSynchronize(stream));
}

// ---- output ---------------------------------------------------------------------------------------

std::string ratio_text(double gbps, double ratio) {
    return format_fixed(gbps, 0) + " (" + format_fixed(100.0 * ratio, 0) + "%)";
}

void print_table(std::ostream& out, const std::vector<SizeResult>& results) {
    TextTable kernels({{"size", TextTable::Align::Left},
                       {"cells", TextTable::Align::Left},
                       {"triangles"},
                       {"ELL pos"},
                       {"copy GB/s"},
                       {"SpMV us"},
                       {"SpMV GB/s warm"},
                       {"SpMV GB/s cold"},
                       {"PCG it us"},
                       {"PCG GB/s graph"},
                       {"PCG GB/s stream"}});
    for (const SizeResult& r : results) {
        const std::string cells = std::to_string(r.spec.cells_x) + "x" + std::to_string(r.spec.cells_y);
        if (!r.error.empty()) {
            kernels.add_row({r.spec.label, cells, "failed: " + r.error});
            continue;
        }
        kernels.add_row({r.spec.label, cells, std::to_string(r.triangles), std::to_string(r.positions),
                         format_fixed(r.copy.gbps, 0), format_fixed(1000.0 * r.spmv_warm.ms.median, 1),
                         ratio_text(r.spmv_warm.gbps, r.spmv_warm.ratio), ratio_text(r.spmv_cold.gbps, r.spmv_cold.ratio),
                         format_fixed(1000.0 * r.pcg_graph.ms.median, 1), ratio_text(r.pcg_graph.gbps, r.pcg_graph.ratio),
                         ratio_text(r.pcg_stream.gbps, r.pcg_stream.ratio)});
    }
    out << "\nkernels (medians; GB/s counts the bytes the kernel must move; % of device-to-device copy bandwidth)\n";
    kernels.print(out);

    std::vector<TextTable::Column> columns{{"size", TextTable::Align::Left}, {"dt"}, {"substeps"}, {"frames/s"}, {"step ms"}};
    for (const std::string_view stage : kStageNames) columns.push_back({std::string(stage)});
    columns.push_back({"CG it/step"});
    columns.push_back({"B/triangle"});
    columns.push_back({"warnings", TextTable::Align::Left});
    TextTable steps(std::move(columns));
    for (const SizeResult& r : results) {
        if (!r.error.empty()) continue;
        std::vector<std::string> row{r.spec.label, format_fixed(r.dt, 5), std::to_string(r.substeps),
                                     format_fixed(r.wall_ms.median > 0 ? 1000.0 / r.wall_ms.median : 0.0, 1),
                                     format_fixed(r.wall_ms.median, 3)};
        for (const Dist& d : r.stage_ms) row.push_back(format_fixed(d.median, 3));
        row.push_back(format_fixed(r.cg_iterations.mean, 1));
        row.push_back(format_fixed(r.triangles > 0 ? static_cast<double>(r.memory_bytes) / static_cast<double>(r.triangles) : 0.0, 0));
        std::string warn;
        if (r.cg_not_converged > 0) warn += std::to_string(r.cg_not_converged) + " not converged";
        if (r.non_finite_frames > 0) warn += (warn.empty() ? "" : ", ") + std::to_string(r.non_finite_frames) + " NaN";
        if (r.pcg_stopped_early) warn += (warn.empty() ? "" : ", ") + std::string("PCG bench loop stopped early");
        if (!r.graph_active) warn += (warn.empty() ? "" : ", ") + std::string("no CUDA graph");
        row.push_back(warn.empty() ? "-" : warn);
        steps.add_row(std::move(row));
    }
    out << "\nwhole step (median wall ms per frame over the timed frames; stages summed over substeps)\n";
    steps.print(out);

    for (const SizeResult& r : results) {
        if (!r.error.empty()) continue;
        out << "\ndevice memory, " << r.spec.label << ": " << weft::format_bytes(static_cast<double>(r.memory_bytes)) << " ("
            << format_fixed(static_cast<double>(r.memory_bytes) / static_cast<double>(std::max<std::size_t>(1, r.triangles)), 0)
            << " B/triangle)\n";
        for (const auto& [name, bytes] : r.memory_breakdown)
            out << "  " << name << ": " << weft::format_bytes(static_cast<double>(bytes)) << '\n';
        if (!r.pcg_note.empty()) out << "  note: " << r.pcg_note << '\n';
    }
}

void write_rate(JsonWriter& json, const char* name, const Rate& rate, double bytes, const char* ms_key = "ms") {
    json.key(name).begin_object();
    json.field("bytes", bytes);
    json.key(ms_key);
    write_dist(json, rate.ms, kDistFields);
    json.field("gb_per_s", rate.gbps).field("ratio_to_copy", rate.ratio);
    json.end_object();
}

void write_json(std::ostream& stream, const Options& opt, const std::filesystem::path& scene_path,
                const cuda::DeviceInfo* gpu, int l2_bytes, const std::string& unavailable,
                const std::vector<SizeResult>& results) {
    JsonWriter json(stream);
    json.begin_object();
    json.field("benchmark", "weft_cuda_bench");
    json.field("weft_version", cli::build_info().version);
    json.field("cuda_available", gpu != nullptr);
    if (gpu == nullptr) {
        json.field("reason", unavailable);
        json.key("gpu").null();
        json.key("sizes").begin_array().end_array();
        json.end_object();
        return;
    }
    int runtime = 0, driver = 0;
    cudaRuntimeGetVersion(&runtime);
    cudaDriverGetVersion(&driver);
    json.key("gpu").begin_object();
    json.field("name", gpu->name);
    json.field("compute_capability", std::to_string(gpu->compute_major) + "." + std::to_string(gpu->compute_minor));
    json.field("memory_bytes", gpu->memory_bytes).field("multiprocessors", gpu->multiprocessors);
    json.field("l2_bytes", l2_bytes);
    json.field("cuda_runtime_version", runtime).field("cuda_driver_version", driver);
    json.end_object();
    json.field("scene_file", scene_path.string());
    json.key("settings").begin_object();
    json.field("warmup_frames", opt.warmup).field("step_frames", opt.frames);
    json.field("copy_reps", opt.copy_reps).field("spmv_reps", opt.spmv_reps);
    json.field("pcg_iterations_per_batch", opt.pcg_iterations).field("pcg_batches", opt.pcg_reps);
    json.end_object();
    json.key("byte_counts").begin_object();
    json.field("copy", "2 x buffer bytes (read + write); buffer = max(256 MiB, matrix bytes)");
    json.field("matrix", "positions x 36 (blocks) + positions x 4 (columns) + (slices + 1) x 4 (slice_start)");
    json.field("spmv", "matrix + 3n x 4 (x, read once) + 3n x 4 (y, written)");
    json.field("pcg_iteration",
               "spmv + n (fixed) [q = A c, dot]; + 4 x 3n x 4 (read r, q, dv, c) + 9n x 4 (P^-1) + 3 x 3n x 4 "
               "(write dv, r, s) [update]; + 2 x 3n x 4 (read s, c) + n (fixed) + 3n x 4 (write c) [direction]"
               " = matrix + 182 n");
    json.field("spmv_cold", "L2 flushed (memset of 2 x L2 bytes) before each timed SpMV; warm: back to back");
    json.end_object();

    json.key("sizes").begin_array();
    for (const SizeResult& r : results) {
        json.begin_object();
        json.field("label", r.spec.label).field("spec", r.spec.text);
        json.key("cells").begin_array(true).value(r.spec.cells_x).value(r.spec.cells_y).end_array();
        json.key("overrides").begin_array();
        for (const std::string& o : r.overrides) json.value(o);
        json.end_array();
        if (!r.error.empty()) {
            json.field("error", r.error);
            json.end_object();
            continue;
        }
        json.field("triangles", r.triangles).field("vertices", r.vertices);
        json.field("dt", r.dt).field("substeps", r.substeps).field("newton_iterations", r.newton);
        json.field("cg_tolerance", r.cg_tolerance).field("cg_max_iterations", r.cg_max_iterations);
        json.field("device", r.device_description).field("graph_active", r.graph_active);
        json.field("build_and_first_step_seconds", r.build_seconds);

        json.key("matrix").begin_object();
        json.field("rows", r.rows).field("slices", r.slices).field("positions", r.positions);
        json.field("positions_per_row", r.rows > 0 ? static_cast<double>(r.positions) / static_cast<double>(r.rows) : 0.0);
        json.field("bytes", r.matrix_bytes);
        json.end_object();

        json.key("copy").begin_object();
        json.field("buffer_bytes", r.copy_buffer_bytes).field("bytes", 2.0 * static_cast<double>(r.copy_buffer_bytes));
        json.key("ms");
        write_dist(json, r.copy.ms, kDistFields);
        json.field("gb_per_s", r.copy.gbps);
        json.end_object();

        json.key("spmv").begin_object();
        json.field("bytes", r.spmv_bytes).field("l2_resident", r.spmv_l2_resident);
        write_rate(json, "warm", r.spmv_warm, r.spmv_bytes);
        write_rate(json, "cold", r.spmv_cold, r.spmv_bytes);
        json.key("meets_60_percent_target").begin_object();
        json.field("warm", r.spmv_warm.ratio >= 0.6).field("cold", r.spmv_cold.ratio >= 0.6);
        json.end_object();
        json.end_object();

        json.key("pcg_iteration").begin_object();
        json.field("bytes", r.pcg_bytes);
        json.field("iterations_per_batch", opt.pcg_iterations);
        json.field("iterations_done_last_batch", r.pcg_iterations_done);
        json.field("stopped_early", r.pcg_stopped_early);
        if (!r.pcg_note.empty()) json.field("note", r.pcg_note);
        write_rate(json, "graph", r.pcg_graph, r.pcg_bytes, "ms_per_iteration");
        write_rate(json, "stream", r.pcg_stream, r.pcg_bytes, "ms_per_iteration");
        json.end_object();

        json.key("step").begin_object();
        json.field("frames", opt.frames);
        json.key("wall_ms");
        write_dist(json, r.wall_ms, kDistFields);
        json.key("step_ms");
        write_dist(json, r.step_ms, kDistFields);
        json.field("fps", r.wall_ms.median > 0 ? 1000.0 / r.wall_ms.median : 0.0);
        json.key("stage_ms").begin_object();
        for (std::size_t k = 0; k < r.stage_ms.size(); ++k) {
            json.key(kStageNames[k]);
            write_dist(json, r.stage_ms[k], kDistFields);
        }
        json.end_object();
        json.key("cg_iterations_per_step");
        write_dist(json, r.cg_iterations, kDistFields);
        json.field("cg_not_converged", r.cg_not_converged).field("non_finite_frames", r.non_finite_frames);
        json.end_object();

        json.key("memory").begin_object();
        json.field("backend_bytes", r.memory_bytes);
        json.field("bytes_per_triangle",
                   r.triangles > 0 ? static_cast<double>(r.memory_bytes) / static_cast<double>(r.triangles) : 0.0);
        json.key("breakdown").begin_object();
        for (const auto& [name, bytes] : r.memory_breakdown) json.field(name, bytes);
        json.end_object();
        json.end_object();

        json.end_object();
    }
    json.end_array();
    json.end_object();
}

}  // namespace

int main(int argc, char** argv) {
    const Options opt = parse_options(argc, argv);
    if (opt.print_sizes) {
        for (const SizeSpec& s : opt.sizes) {
            std::cout << s.text << ": cells " << s.cells_x << "x" << s.cells_y << " = "
                      << 2LL * s.cells_x * s.cells_y << " triangles";
            for (const std::string& o : opt.overrides) std::cout << ", " << o;
            for (const std::string& o : s.overrides) std::cout << ", " << o;
            std::cout << '\n';
        }
        return 0;
    }
    try {
        const std::vector<cuda::DeviceInfo> gpus = cuda::devices();
        if (gpus.empty()) {
            const std::string reason = cuda::unavailable_reason();
            std::cout << "no CUDA device: " << reason << " (nothing measured)\n";
            if (!opt.json_file.empty())
                bench::write_json_file(opt.json_file, "weft_cuda_bench",
                                       [&](std::ostream& s) { write_json(s, opt, {}, nullptr, 0, reason, {}); });
            return 0;
        }
        cuda::register_cuda_backend();
        const std::filesystem::path scene_path = cli::find_scene(opt.scene);
        const cuda::DeviceInfo& gpu = gpus[0];
        int l2_bytes = 0;
        WEFT_CUDA_CHECK(cudaDeviceGetAttribute(&l2_bytes, cudaDevAttrL2CacheSize, gpu.ordinal));
        std::cout << "GPU: " << gpu.name << " (sm_" << gpu.compute_major << gpu.compute_minor << ", "
                  << weft::format_bytes(static_cast<double>(gpu.memory_bytes)) << ", L2 "
                  << weft::format_bytes(static_cast<double>(l2_bytes)) << ")\nscene: " << scene_path.string() << '\n';

        std::vector<SizeResult> results;
        for (const SizeSpec& spec : opt.sizes) {
            SizeResult r;
            r.spec = spec;
            try {
                measure(opt, scene_path, l2_bytes, r);
            } catch (const std::exception& e) {
                r.error = e.what();
                std::cerr << "weft_cuda_bench: size " << spec.text << " failed: " << e.what() << std::endl;
                cudaGetLastError();
            }
            results.push_back(std::move(r));
        }
        print_table(std::cout, results);
        bool ok = true;
        if (!opt.json_file.empty())
            ok = bench::write_json_file(opt.json_file, "weft_cuda_bench", [&](std::ostream& s) {
                write_json(s, opt, scene_path, &gpu, l2_bytes, "", results);
            });
        for (const SizeResult& r : results) ok = ok && r.error.empty();
        return ok ? 0 : 1;
    } catch (const std::exception& e) {
        std::cerr << "weft_cuda_bench: " << e.what() << '\n';
        return 1;
    }
}
