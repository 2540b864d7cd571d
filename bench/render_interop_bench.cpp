// Simulate-plus-draw per frame on one GPU: the CUDA backend steps the flag and the Vulkan renderer
// draws it, with the cloth handed over either
//   interop: the solver's output kernel writes the renderer's exported buffer, a timeline semaphore
//            orders the two (docs/rendering.md), no cloth byte crosses the bus; or
//   upload:  the solver writes its own device buffer, the host copies it out (D2H) and the renderer
//            uploads it again (H2D), the fallback where interop is unavailable.
// Per mode: frame time percentiles (p50, p99) and the process CPU time per frame over the timed
// frames, and the cloth bytes that crossed the bus per frame. The draw is offscreen and includes the
// picture's read-back (the capture path), the same in both modes.
//
//   build/bin/weft_render_interop_bench --json out/interop.json            # 200K and 1.2M triangles
//   build/bin/weft_render_interop_bench --sizes 400x250 --frames 1000
#include <cuda_runtime_api.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "json_writer.h"
#include "text_table.h"
#include "weft/cuda/cuda_backend.h"
#include "weft/cuda/external_memory.h"
#include "weft/error.h"
#include "weft/render/renderer.h"
#include "weft/scene.h"

namespace {

using namespace weft;
using cli::format_fixed;
using Clock = std::chrono::steady_clock;

struct Size {
    int cells_x = 400, cells_y = 250;
    int frames = 1000;
};

struct Options {
    std::vector<Size> sizes{{400, 250, 1000}, {1000, 600, 300}};
    int warmup = 20;
    int width = 960, height = 540;
    std::filesystem::path json_file;
};

constexpr const char* kUsage = R"(Usage: weft_render_interop_bench [options]

The flag scene stepped by the CUDA backend and drawn by the Vulkan renderer each frame, with the cloth
shared zero-copy (interop) or copied through the host (upload): frame time p50/p99, CPU ms per frame,
bytes per frame. Needs a GPU whose Vulkan driver exports memory and timeline semaphores.

Options:
  --sizes LIST   comma-separated CXxCY[:FRAMES] grid cells (default 400x250:1000,1000x600:300;
                 triangles = 2·CX·CY); 1000x600 runs at dt 1/250 s, 1 substep (the P-Cloth setting)
  --warmup N     untimed frames per run; default 20
  --size WxH     picture size; default 960x540
  --json FILE    write the results as JSON
  -h, --help     this text
)";

[[noreturn]] void usage_error(const std::string& m) {
    std::cerr << "weft_render_interop_bench: " << m << "\n(--help lists the options)\n";
    std::exit(2);
}

int parse_positive(const std::string& text, const std::string& what) {
    try {
        std::size_t used = 0;
        const int v = std::stoi(text, &used);
        if (used != text.size() || v < 1) throw std::invalid_argument(text);
        return v;
    } catch (const std::exception&) {
        usage_error(what + " expects a positive integer, got '" + text + "'");
    }
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) usage_error(a + " needs a value");
            return argv[++i];
        };
        if (a == "-h" || a == "--help") {
            std::cout << kUsage;
            std::exit(0);
        } else if (a == "--sizes") {
            o.sizes.clear();
            std::string list = value();
            std::size_t start = 0;
            while (start <= list.size()) {
                const std::size_t comma = std::min(list.find(',', start), list.size());
                const std::string item = list.substr(start, comma - start);
                const std::size_t x = item.find('x'), colon = item.find(':');
                if (x == std::string::npos) usage_error("--sizes expects CXxCY[:FRAMES], got '" + item + "'");
                Size s;
                s.cells_x = parse_positive(item.substr(0, x), "--sizes");
                s.cells_y = parse_positive(item.substr(x + 1, colon == std::string::npos ? std::string::npos : colon - x - 1),
                                           "--sizes");
                if (colon != std::string::npos) s.frames = parse_positive(item.substr(colon + 1), "--sizes");
                o.sizes.push_back(s);
                start = comma + 1;
            }
        } else if (a == "--warmup") {
            o.warmup = parse_positive(value(), a);
        } else if (a == "--size") {
            const std::string v = value();
            const std::size_t x = v.find('x');
            if (x == std::string::npos) usage_error("--size expects WxH, got '" + v + "'");
            o.width = parse_positive(v.substr(0, x), a);
            o.height = parse_positive(v.substr(x + 1), a);
        } else if (a == "--json") {
            o.json_file = value();
        } else {
            usage_error("unknown option '" + a + "'");
        }
    }
    return o;
}

double cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double percentile(std::vector<double> v, double p) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const auto k = static_cast<std::size_t>(std::ceil(p * static_cast<double>(v.size()))) - 1;
    return v[std::min(k, v.size() - 1)];
}

void check(cudaError_t e, const char* what) {
    if (e != cudaSuccess) throw Error(std::string(what) + ": " + cudaGetErrorString(e));
}

struct Result {
    std::string mode;
    int cells_x = 0, cells_y = 0;
    std::size_t triangles = 0, vertices = 0;
    int frames = 0;
    double p50 = 0, p99 = 0, mean = 0, cpu_ms = 0;
    double bytes_per_frame = 0;
    std::string device, path;
};

Result run(const Options& o, const Size& size, bool interop) {
    const auto file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / "flag.toml";
    std::vector<std::string> overrides{"cloth.flag.mesh.grid.cells=[" + std::to_string(size.cells_x) + "," +
                                       std::to_string(size.cells_y) + "]"};
    if (size.cells_x * size.cells_y >= 500'000) {
        overrides.emplace_back("solver.dt=0.004");
        overrides.emplace_back("solver.substeps=1");
    }
    const SceneDesc desc = load_scene(file, overrides);
    auto world = build_world(desc, "cuda");
    render::RendererOptions ro;
    ro.width = o.width;
    ro.height = o.height;
    auto renderer = render::create_renderer("vulkan", ro);
    const render::RenderScene scene = render::make_render_scene(*world, desc.camera);
    renderer->load(scene);
    cuda::CudaBackendApi* api = cuda::as_cuda(world->backend());
    cudaStream_t stream = nullptr;
    check(cudaStreamCreate(&stream), "cudaStreamCreate");
    api->set_stream(stream);
    const std::size_t bytes = std::size_t{scene.cloth_vertices} * sizeof(render::RenderVertex);

    std::unique_ptr<cuda::ImportedBuffer> buffer;
    std::unique_ptr<cuda::ImportedTimeline> timeline;
    void* device_output = nullptr;
    render::RenderVertex* host = nullptr;
    if (interop) {
        std::string why;
        auto link = renderer->export_cloth(why);
        if (!link) throw Error("no interop on this machine: " + why);
        buffer = std::make_unique<cuda::ImportedBuffer>(0, link->memory);
        timeline = std::make_unique<cuda::ImportedTimeline>(0, link->timeline);
        api->set_output(buffer->device_pointer());
    } else {
        check(cudaMalloc(&device_output, bytes), "cudaMalloc");
        check(cudaMallocHost(reinterpret_cast<void**>(&host), bytes), "cudaMallocHost");
        api->set_output(device_output);
    }

    std::vector<double> frame_ms;
    double cpu_total = 0.0;
    std::uint64_t value = 0;
    const int total = o.warmup + size.frames;
    for (int f = 0; f < total; ++f) {
        const auto t0 = Clock::now();
        const double c0 = cpu_seconds();
        render::RenderFrame frame;
        frame.collider_models = render::collider_models(scene, world->model(), world->time() + world->settings().solver.dt);
        if (interop) {
            timeline->wait(value, stream);  // the renderer's reads of the last frame are done
            (void)world->step();
            timeline->signal(++value, stream);
            frame.wait_value = value;
            frame.signal_value = ++value;
        } else {
            (void)world->step();
            check(cudaMemcpyAsync(host, device_output, bytes, cudaMemcpyDeviceToHost, stream), "cudaMemcpyAsync");
            check(cudaStreamSynchronize(stream), "cudaStreamSynchronize");
            frame.cloth = std::span<const render::RenderVertex>(host, scene.cloth_vertices);
        }
        (void)renderer->draw(frame);
        if (f >= o.warmup) {
            frame_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
            cpu_total += cpu_seconds() - c0;
        }
    }
    check(cudaStreamSynchronize(stream), "cudaStreamSynchronize");

    Result r;
    r.mode = interop ? "interop" : "upload";
    r.cells_x = size.cells_x;
    r.cells_y = size.cells_y;
    r.triangles = scene.cloth_indices.size() / 3;
    r.vertices = scene.cloth_vertices;
    r.frames = size.frames;
    r.p50 = percentile(frame_ms, 0.50);
    r.p99 = percentile(frame_ms, 0.99);
    double sum = 0.0;
    for (const double m : frame_ms) sum += m;
    r.mean = sum / static_cast<double>(frame_ms.size());
    r.cpu_ms = 1000.0 * cpu_total / static_cast<double>(size.frames);
    // Cloth bytes over the bus per frame: the renderer's upload plus, on the upload path, the copy out.
    r.bytes_per_frame = static_cast<double>(renderer->transfer().bytes_uploaded) + (interop ? 0.0 : static_cast<double>(bytes));
    r.device = renderer->device_description();
    r.path = renderer->transfer().path;

    api->set_output(nullptr);
    api->set_stream(nullptr);
    timeline.reset();
    buffer.reset();
    if (device_output != nullptr) cudaFree(device_output);
    if (host != nullptr) cudaFreeHost(host);
    cudaStreamDestroy(stream);
    return r;
}

}  // namespace

int main(int argc, char** argv) {
    const Options o = parse(argc, argv);
    try {
        cuda::register_cuda_backend();
        if (cuda::devices().empty()) throw Error("no CUDA device: " + cuda::unavailable_reason());
        std::vector<Result> results;
        for (const Size& s : o.sizes)
            for (const bool interop : {true, false}) {
                results.push_back(run(o, s, interop));
                const Result& r = results.back();
                std::printf("%s %zu triangles: p50 %.2f ms, p99 %.2f ms, CPU %.2f ms/frame, %.0f B/frame (%s)\n",
                            r.mode.c_str(), r.triangles, r.p50, r.p99, r.cpu_ms, r.bytes_per_frame, r.path.c_str());
            }
        cli::TextTable table({{"triangles"}, {"mode", cli::TextTable::Align::Left}, {"frames"}, {"p50 ms"}, {"p99 ms"},
                              {"mean ms"}, {"CPU ms/frame"}, {"bus B/frame"}, {"interop speed-up (p50)"}});
        for (std::size_t k = 0; k < results.size(); ++k) {
            const Result& r = results[k];
            const Result& other = results[k ^ 1U];
            table.add_row({std::to_string(r.triangles), r.mode, std::to_string(r.frames), format_fixed(r.p50, 2),
                           format_fixed(r.p99, 2), format_fixed(r.mean, 2), format_fixed(r.cpu_ms, 2),
                           format_fixed(r.bytes_per_frame, 0),
                           r.mode == "interop" ? format_fixed(other.p50 / r.p50, 3) + "x" : ""});
        }
        std::printf("\nflag on %s, %dx%d pictures, offscreen draw with read-back\n", results.front().device.c_str(),
                    o.width, o.height);
        table.print(std::cout);
        if (!o.json_file.empty()) {
            std::ofstream out(o.json_file);
            cli::JsonWriter json(out);
            json.begin_array();
            for (const Result& r : results) {
                json.begin_object();
                json.field("mode", r.mode).field("device", r.device).field("triangles", static_cast<double>(r.triangles));
                json.field("vertices", static_cast<double>(r.vertices)).field("frames", r.frames);
                json.field("p50_ms", r.p50).field("p99_ms", r.p99).field("mean_ms", r.mean).field("cpu_ms_per_frame", r.cpu_ms);
                json.field("bus_bytes_per_frame", r.bytes_per_frame).field("width", o.width).field("height", o.height);
                json.end_object();
            }
            json.end_array();
            out << '\n';
        }
    } catch (const std::exception& e) {
        std::cerr << "weft_render_interop_bench: " << e.what() << '\n';
        return 1;
    }
    return 0;
}
