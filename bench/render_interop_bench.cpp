// Simulate-plus-draw per frame on one GPU: the CUDA backend steps the flag and a renderer (Vulkan, or
// the EGL capture's OpenGL) draws it through the frame pipeline (weft/render/cloth_feed.h), with the
// cloth handed over either
//   interop: the solver's output kernel writes one of the renderer's two exported slots (Vulkan:
//            timeline semaphores order writer and reader; OpenGL: CUDA maps and unmaps the
//            registered buffer; docs/rendering.md), no cloth byte crosses the bus; or
//   upload:  the feed's fallback, the state read back to the host (normals computed there) and
//            uploaded again, what runs where interop is unavailable;
// and the frames either overlapped (the steps of frame N+1 run while the GPU draws frame N: submit,
// simulate, collect) or serial (simulate, then draw and wait). Per mode: frame time percentiles
// (p50, p99) and the process CPU time per frame over the timed frames, the cloth bytes that crossed
// the bus per frame, and the frames whose stamps showed a torn read (must be 0). The draw is
// offscreen and includes the picture's read-back (the capture path), the same in every mode.
//
//   build/bin/weft_render_interop_bench --json out/interop.json            # 200K and 1.2M triangles
//   build/bin/weft_render_interop_bench --sizes 400x250:1000 --modes interop,upload --host-wait spin,block
//   build/bin/weft_render_interop_bench --renderers vulkan,egl --sizes 400x250:1000 --modes interop,upload

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "weft/backend/timing.h"
#include "weft/backend_options.h"
#include "weft/cuda/cuda_backend.h"
#include "weft/error.h"
#include "weft/render/cloth_feed.h"
#include "weft/render/renderer.h"
#include "weft/scene.h"

#include "json_file.h"
#include "json_writer.h"
#include "text_table.h"

namespace {

using namespace weft;
using cli::format_fixed;
using Clock = std::chrono::steady_clock;

struct Size {
    int cells_x = 400, cells_y = 250;
    int frames = 1000;
};

struct Mode {
    const char* name;
    const char* key;  // --modes
    bool interop;
    bool overlap;
};
constexpr Mode kModes[] = {{"interop, overlapped", "interop", true, true},
                           {"interop, serial", "interop-serial", true, false},
                           {"upload, overlapped", "upload", false, true},
                           {"upload, serial", "upload-serial", false, false}};

struct Options {
    std::vector<Size> sizes{{400, 250, 1000}, {1000, 600, 200}};
    std::vector<Mode> modes{kModes[0], kModes[1], kModes[2]};
    std::vector<HostWait> waits{HostWait::automatic};
    std::vector<std::string> renderers{"vulkan"};
    int warmup = 20;
    int width = 960, height = 540;
    std::filesystem::path json_file;
};

constexpr const char* kUsage = R"(Usage: weft_render_interop_bench [options]

The flag scene stepped by the CUDA backend and drawn by a renderer each frame, with the cloth shared
zero-copy (interop) or copied through the host (upload), the steps of a frame overlapping the draw of
the one before or not (serial): frame time p50/p99, CPU ms per frame, bytes per frame. Needs a GPU
whose Vulkan driver exports memory and timeline semaphores (vulkan), or an EGL device whose OpenGL
context CUDA can share buffers with (egl).

Options:
  --sizes LIST   comma-separated CXxCY[:FRAMES] grid cells (default 400x250:1000,1000x600:200;
                 triangles = 2·CX·CY); 1000x600 runs at dt 1/250 s, 1 substep (the P-Cloth setting)
  --modes LIST   comma-separated, of interop, interop-serial, upload, upload-serial; default
                 interop,interop-serial,upload (ratios are against the first)
  --host-wait LIST
                 comma-separated host waits for the CUDA backend (auto, spin, yield, block), each
                 mode run under each; default auto
  --renderers LIST
                 comma-separated, of vulkan, egl; default vulkan (ratios are per renderer)
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

std::vector<std::string> split(const std::string& list) {
    std::vector<std::string> items;
    std::size_t start = 0;
    while (start <= list.size()) {
        const std::size_t comma = std::min(list.find(',', start), list.size());
        items.push_back(list.substr(start, comma - start));
        start = comma + 1;
    }
    return items;
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
            for (const std::string& item : split(value())) {
                const std::size_t x = item.find('x'), colon = item.find(':');
                if (x == std::string::npos) usage_error("--sizes expects CXxCY[:FRAMES], got '" + item + "'");
                Size s;
                s.cells_x = parse_positive(item.substr(0, x), "--sizes");
                s.cells_y = parse_positive(
                    item.substr(x + 1, colon == std::string::npos ? std::string::npos : colon - x - 1), "--sizes");
                if (colon != std::string::npos) s.frames = parse_positive(item.substr(colon + 1), "--sizes");
                o.sizes.push_back(s);
            }
        } else if (a == "--modes") {
            o.modes.clear();
            for (const std::string& item : split(value())) {
                const Mode* found = nullptr;
                for (const Mode& m : kModes)
                    if (item == m.key) found = &m;
                if (found == nullptr)
                    usage_error("--modes: unknown mode '" + item +
                                "' (interop, interop-serial, upload, upload-serial)");
                o.modes.push_back(*found);
            }
        } else if (a == "--host-wait") {
            o.waits.clear();
            for (const std::string& item : split(value())) {
                try {
                    o.waits.push_back(parse_host_wait(item));
                } catch (const Error& e) {
                    usage_error(std::string("--host-wait: ") + e.what());
                }
            }
        } else if (a == "--renderers") {
            o.renderers = split(value());
            for (const std::string& r : o.renderers)
                if (r != "vulkan" && r != "egl") usage_error("--renderers: unknown renderer '" + r + "' (vulkan, egl)");
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

struct Result {
    std::string renderer, mode, host_wait;
    int cells_x = 0, cells_y = 0;
    std::size_t triangles = 0, vertices = 0;
    int frames = 0;
    double p50 = 0, p99 = 0, mean = 0, cpu_ms = 0, step_ms = 0;
    double bytes_per_frame = 0;
    std::int64_t torn = 0;
    std::string device, path;
};

Result run(const Options& o, const std::string& renderer_name, const Size& size, const Mode& mode, HostWait wait) {
    const auto file = std::filesystem::path(WEFT_SOURCE_DIR) / "assets" / "scenes" / "flag.toml";
    std::vector<std::string> overrides{"cloth.flag.mesh.grid.cells=[" + std::to_string(size.cells_x) + "," +
                                       std::to_string(size.cells_y) + "]"};
    if (size.cells_x * size.cells_y >= 500'000) {
        overrides.emplace_back("solver.dt=0.004");
        overrides.emplace_back("solver.substeps=1");
    }
    const SceneDesc desc = load_scene(file, overrides);
    BackendOptions backend;
    backend.host_wait = wait;
    auto world = build_world(desc, "cuda", backend);
    render::RendererOptions ro;
    ro.width = o.width;
    ro.height = o.height;
    auto renderer = render::create_renderer(renderer_name, ro);
    const render::RenderScene scene = render::make_render_scene(*world, desc.camera);
    renderer->load(scene);
    render::ClothFeed feed(*world, *renderer, scene, render::ClothFeed::Options{mode.interop});
    if (mode.interop && !feed.zero_copy()) throw Error("no interop on this machine: " + feed.fallback_reason());

    std::vector<double> frame_ms, step_ms;
    double cpu_total = 0.0;
    const int total = o.warmup + size.frames;
    std::optional<render::RenderFrame> drawing;
    std::uint64_t bytes = 0;
    for (int f = 0; f < total; ++f) {
        const auto t0 = Clock::now();
        const double c0 = cpu_seconds();
        double step = 0.0;
        render::RenderFrame next = feed.simulate([&] { step = world->step().step_ms; });
        if (drawing) {  // overlapped: the frame before was drawing during the step
            (void)renderer->collect();
            (void)feed.check(*drawing, renderer->transfer());
            drawing.reset();
        }
        renderer->submit(next);
        bytes = renderer->transfer().bytes_uploaded;
        if (mode.overlap) {
            drawing = std::move(next);
        } else {
            (void)renderer->collect();
            (void)feed.check(next, renderer->transfer());
        }
        if (f >= o.warmup) {
            frame_ms.push_back(ms_since(t0));
            step_ms.push_back(step);
            cpu_total += cpu_seconds() - c0;
        }
    }
    if (drawing) {
        (void)renderer->collect();
        (void)feed.check(*drawing, renderer->transfer());
    }

    Result r;
    r.renderer = renderer_name;
    r.mode = mode.name;
    r.host_wait = host_wait_name(wait);
    r.cells_x = size.cells_x;
    r.cells_y = size.cells_y;
    r.triangles = scene.cloth_indices.size() / 3;
    r.vertices = scene.cloth_vertices;
    r.frames = size.frames;
    r.p50 = percentile(frame_ms, 0.50);
    r.p99 = percentile(frame_ms, 0.99);
    r.step_ms = percentile(step_ms, 0.50);
    double sum = 0.0;
    for (const double m : frame_ms) sum += m;
    r.mean = sum / static_cast<double>(frame_ms.size());
    r.cpu_ms = 1000.0 * cpu_total / static_cast<double>(size.frames);
    // Cloth bytes over the bus per frame: the renderer's upload plus, on the upload path, the
    // read-back of the state (positions as float, the same size as the upload's positions).
    r.bytes_per_frame = static_cast<double>(bytes) +
                        (mode.interop ? 0.0 : static_cast<double>(scene.cloth_vertices) * 3.0 * sizeof(float));
    r.torn = feed.torn_frames();
    r.device = renderer->device_description();
    r.path = feed.describe();
    return r;
}

}  // namespace

int main(int argc, char** argv) {
    const Options o = parse(argc, argv);
    try {
        cuda::register_cuda_backend();
        if (cuda::devices().empty()) throw Error("no CUDA device: " + cuda::unavailable_reason());
        std::vector<Result> results;
        const std::size_t runs_per_size = o.modes.size() * o.waits.size();
        const auto run_and_print = [&](const std::string& name, const Size& s, HostWait w, const Mode& m) {
            results.push_back(run(o, name, s, m, w));
            const Result& r = results.back();
            std::printf("%s: %s, host wait %s, %zu triangles: p50 %.2f ms, p99 %.2f ms, step %.2f ms, CPU %.2f ms/frame, "
                        "%.0f B/frame, %lld torn (%s)\n",
                        r.renderer.c_str(), r.mode.c_str(), r.host_wait.c_str(), r.triangles, r.p50, r.p99, r.step_ms,
                        r.cpu_ms, r.bytes_per_frame, static_cast<long long>(r.torn), r.path.c_str());
            std::fflush(stdout);
        };
        for (const std::string& name : o.renderers)
            for (const Size& s : o.sizes)
                for (const HostWait w : o.waits)
                    for (const Mode& m : o.modes) run_and_print(name, s, w, m);
        // The headline ratio: each run's p50 against the first run of its renderer and size (by
        // default interop, overlapped, the driver's host wait).
        cli::TextTable table({{"renderer", cli::TextTable::Align::Left},
                              {"triangles"},
                              {"mode", cli::TextTable::Align::Left},
                              {"host wait"},
                              {"frames"},
                              {"p50 ms"},
                              {"p99 ms"},
                              {"mean ms"},
                              {"step p50 ms"},
                              {"CPU ms/frame"},
                              {"bus B/frame"},
                              {"torn"},
                              {"p50 / first"}});
        for (std::size_t k = 0; k < results.size(); ++k) {
            const Result& r = results[k];
            const Result& base = results[k - k % runs_per_size];
            table.add_row({r.renderer, std::to_string(r.triangles), r.mode, r.host_wait, std::to_string(r.frames),
                           format_fixed(r.p50, 2), format_fixed(r.p99, 2), format_fixed(r.mean, 2),
                           format_fixed(r.step_ms, 2), format_fixed(r.cpu_ms, 2), format_fixed(r.bytes_per_frame, 0),
                           std::to_string(r.torn), format_fixed(r.p50 / base.p50, 3) + "x"});
        }
        std::printf("\nflag, %dx%d pictures, offscreen draw with read-back, on\n", o.width, o.height);
        for (std::size_t k = 0; k < results.size(); ++k)
            if (k == 0 || results[k].renderer != results[k - 1].renderer)
                std::printf("  %s: %s\n", results[k].renderer.c_str(), results[k].device.c_str());
        table.print(std::cout);
        const auto write_results = [&](std::ostream& out) {
            json::JsonWriter json(out);
            json.begin_array();
            for (const Result& r : results) {
                json.begin_object();
                json.field("renderer", r.renderer)
                    .field("mode", r.mode)
                    .field("host_wait", r.host_wait)
                    .field("device", r.device)
                    .field("triangles", static_cast<double>(r.triangles));
                json.field("vertices", static_cast<double>(r.vertices)).field("frames", r.frames);
                json.field("p50_ms", r.p50)
                    .field("p99_ms", r.p99)
                    .field("mean_ms", r.mean)
                    .field("cpu_ms_per_frame", r.cpu_ms);
                json.field("bus_bytes_per_frame", r.bytes_per_frame).field("width", o.width).field("height", o.height);
                json.field("step_ms_p50", r.step_ms)
                    .field("torn_frames", static_cast<double>(r.torn))
                    .field("path", r.path);
                json.end_object();
            }
            json.end_array();
        };
        if (!o.json_file.empty() && !bench::write_json_file(o.json_file, "weft_render_interop_bench", write_results))
            return 1;
    } catch (const std::exception& e) {
        std::cerr << "weft_render_interop_bench: " << e.what() << '\n';
        return 1;
    }
    return 0;
}
