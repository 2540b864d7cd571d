// Headless capture of a run to PNG frames, a contact sheet and an MP4 (see frame_capture.h).
#include "frame_capture.h"

#include "weft/error.h"

#if WEFT_HAVE_RENDER
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <sstream>

#include "weft/render/renderer.h"
#include "weft/scene.h"
#include "weft/world.h"

#include "stats_report.h"

namespace weft::cli {
namespace {

constexpr int kSheetFrames = 12;
constexpr int kSheetColumns = 4;

double ms_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

bool have_ffmpeg() { return std::system("command -v ffmpeg > /dev/null 2>&1") == 0; }

std::string shell_quote(const std::string& s) {
    std::string out = "'";
    for (const char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

}  // namespace

struct FrameCapture::State {
    std::string renderer_name;
    std::filesystem::path dir;
    std::unique_ptr<render::Renderer> renderer;
    render::RenderScene scene;
    std::vector<render::RenderVertex> vertices;
    int last_frame = 0;
    int digits = 4;
    std::vector<double> render_ms, write_ms;
    std::vector<int> sheet_frames;
    std::vector<render::Image> sheet;
    int frames = 0;
};

FrameCapture::FrameCapture(const std::string& renderer, std::filesystem::path dir, int width, int height,
                           const World& world, const CameraDesc& camera, int last_frame)
    : state_(std::make_unique<State>()) {
    State& s = *state_;
    s.renderer_name = renderer;
    s.dir = std::move(dir);
    s.last_frame = last_frame;
    s.digits = std::max(4, static_cast<int>(std::to_string(last_frame).size()));
    std::error_code ec;
    std::filesystem::create_directories(s.dir, ec);
    if (ec) throw Error("capture: cannot create " + s.dir.string() + ": " + ec.message());
    render::RendererOptions options;
    options.width = width;
    options.height = height;
    s.renderer = render::create_renderer(renderer, options);
    s.scene = render::make_render_scene(world, camera);
    s.renderer->load(s.scene);
    for (int k = 0; k < kSheetFrames; ++k)
        s.sheet_frames.push_back(static_cast<int>(static_cast<long long>(last_frame) * k / (kSheetFrames - 1)));
}

FrameCapture::~FrameCapture() = default;

void FrameCapture::capture(int frame, const World& world) {
    State& s = *state_;
    auto clock = std::chrono::steady_clock::now();
    render::cloth_vertices(world, s.scene, s.vertices);
    render::RenderFrame f;
    f.cloth = s.vertices;
    f.collider_models = render::collider_models(s.scene, world.model(), world.time());
    const render::Image image = s.renderer->draw(f);
    s.render_ms.push_back(ms_since(clock));
    clock = std::chrono::steady_clock::now();
    std::ostringstream name;
    name << "frame_" << std::setw(s.digits) << std::setfill('0') << frame << ".png";
    render::write_png(s.dir / name.str(), image);
    s.write_ms.push_back(ms_since(clock));
    ++s.frames;
    if (std::find(s.sheet_frames.begin(), s.sheet_frames.end(), frame) != s.sheet_frames.end() &&
        s.sheet.size() < static_cast<std::size_t>(kSheetFrames))
        s.sheet.push_back(image);
}

CaptureSummary FrameCapture::finish(double fps) {
    State& s = *state_;
    CaptureSummary out;
    out.renderer = s.renderer_name;
    out.device = s.renderer->device_description();
    const render::TransferStats t = s.renderer->transfer();
    out.path = t.path;
    out.bytes_per_frame = t.bytes_uploaded;
    out.frames = s.frames;
    out.render_ms_median = distribution(s.render_ms).median;
    out.write_ms_median = distribution(s.write_ms).median;
    if (!s.sheet.empty()) {
        // Thumbnails about 320 pixels wide.
        const int scale = std::max(1, s.sheet.front().width / 320);
        const auto sheet_path = s.dir / "contact_sheet.png";
        render::write_png(sheet_path, render::contact_sheet(s.sheet, kSheetColumns, scale));
        out.contact_sheet = sheet_path.string();
    }
    if (s.frames < 2) {
        out.video_note = "fewer than 2 frames";
    } else if (!have_ffmpeg()) {
        out.video_note = "ffmpeg not installed";
    } else {
        const auto video = s.dir / "capture.mp4";
        std::ostringstream cmd;
        cmd << "ffmpeg -y -loglevel error -framerate " << std::max(1.0, fps) << " -i "
            << shell_quote((s.dir / ("frame_%0" + std::to_string(s.digits) + "d.png")).string())
            << " -pix_fmt yuv420p -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' " << shell_quote(video.string());
        if (std::system(cmd.str().c_str()) == 0) {
            out.video = video.string();
        } else {
            out.video_note = "ffmpeg failed (command: " + cmd.str() + ")";
        }
    }
    return out;
}

}  // namespace weft::cli

#else  // a build without the renderer (WEFT_RENDER off): --capture is an error that says why

namespace weft::cli {

struct FrameCapture::State {};

FrameCapture::FrameCapture(const std::string& renderer, std::filesystem::path, int, int, const World&,
                           const CameraDesc&, int) {
    throw Error("--capture " + renderer +
                ": this build has no renderer (configure with -DWEFT_RENDER=ON and the Vulkan, EGL and libpng "
                "packages of tools/deps.sh)");
}
FrameCapture::~FrameCapture() = default;
void FrameCapture::capture(int, const World&) {}
CaptureSummary FrameCapture::finish(double) { return {}; }

}  // namespace weft::cli

#endif
