// Headless capture of a run to PNG frames, a contact sheet and an MP4 (see frame_capture.h).
#include "frame_capture.h"

#include "weft/error.h"

#if WEFT_HAVE_RENDER
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>

#include "weft/backend/timing.h"
#include "weft/render/cloth_feed.h"
#include "weft/render/frame_sequence.h"
#include "weft/render/renderer.h"
#include "weft/scene.h"
#include "weft/world.h"

#include "stats_report.h"

namespace weft::cli {
namespace {

constexpr int kSheetFrames = 12;
constexpr int kSheetColumns = 4;

}  // namespace

struct FrameCapture::State {
    std::string renderer_name;
    std::filesystem::path dir;
    std::optional<render::FrameSequence> pictures;
    std::unique_ptr<render::Renderer> renderer;
    render::RenderScene scene;
    std::unique_ptr<render::ClothFeed> feed;
    std::optional<render::RenderFrame> drawing;  ///< submitted, not collected
    int drawing_number = 0;
    double drawing_submit_ms = 0.0;
    int last_frame = 0;
    int digits = 4;
    std::vector<double> render_ms, write_ms;
    std::uint64_t bytes_per_frame = 0;
    std::vector<int> sheet_frames;
    std::vector<render::Image> sheet;
    int frames = 0;
};

FrameCapture::FrameCapture(const std::string& renderer, std::filesystem::path dir, int width, int height,
                           World& world, const CameraDesc& camera, int last_frame)
    : state_(std::make_unique<State>()) {
    State& s = *state_;
    s.renderer_name = renderer;
    s.dir = std::move(dir);
    s.last_frame = last_frame;
    s.digits = std::max(4, static_cast<int>(std::to_string(last_frame).size()));
    try {
        s.pictures.emplace(s.dir, s.digits);
    } catch (const Error& e) {
        throw Error(std::string("capture: ") + e.what());
    }
    render::RendererOptions options;
    options.width = width;
    options.height = height;
    s.renderer = render::create_renderer(renderer, options);
    s.scene = render::make_render_scene(world, camera);
    s.renderer->load(s.scene);
    s.feed = std::make_unique<render::ClothFeed>(world, *s.renderer, s.scene);
    for (int k = 0; k < kSheetFrames; ++k)
        s.sheet_frames.push_back(static_cast<int>(static_cast<long long>(last_frame) * k / (kSheetFrames - 1)));
}

FrameCapture::~FrameCapture() = default;

void FrameCapture::capture(int frame, const std::function<void()>& steps) {
    State& s = *state_;
    // The steps run while the GPU draws the frame submitted last time.
    render::RenderFrame next = s.feed->simulate(steps);
    const int previous_number = s.drawing_number;
    std::optional<render::Image> image = collect_drawing();
    const auto clock = std::chrono::steady_clock::now();
    s.renderer->submit(next);
    s.drawing_submit_ms = ms_since(clock);
    s.drawing = std::move(next);
    s.drawing_number = frame;
    s.bytes_per_frame = s.renderer->transfer().bytes_uploaded;
    // The previous picture is written while the GPU draws this one.
    if (image) write_image(previous_number, *image);
}

// The picture of the frame in flight (none: nothing), its stamps checked and its host time (submit
// plus collect) recorded.
std::optional<render::Image> FrameCapture::collect_drawing() {
    State& s = *state_;
    if (!s.drawing) return std::nullopt;
    const auto clock = std::chrono::steady_clock::now();
    render::Image image = s.renderer->collect();
    (void)s.feed->check(*s.drawing, s.renderer->transfer());
    s.render_ms.push_back(s.drawing_submit_ms + ms_since(clock));
    s.drawing.reset();
    return image;
}

void FrameCapture::write_image(int frame, const render::Image& image) {
    State& s = *state_;
    const auto clock = std::chrono::steady_clock::now();
    s.pictures->write(frame, image);
    s.write_ms.push_back(ms_since(clock));
    ++s.frames;
    if (std::find(s.sheet_frames.begin(), s.sheet_frames.end(), frame) != s.sheet_frames.end() &&
        s.sheet.size() < static_cast<std::size_t>(kSheetFrames))
        s.sheet.push_back(image);
}

CaptureSummary FrameCapture::finish(double fps) {
    State& s = *state_;
    if (std::optional<render::Image> image = collect_drawing()) write_image(s.drawing_number, *image);
    CaptureSummary out;
    out.renderer = s.renderer_name;
    out.device = s.renderer->device_description();
    out.path = s.feed->describe();
    out.bytes_per_frame = s.bytes_per_frame;
    out.frames = s.frames;
    out.torn_frames = s.feed->torn_frames();
    out.render_ms_median = distribution(s.render_ms).median;
    out.write_ms_median = distribution(s.write_ms).median;
    if (!s.sheet.empty()) {
        // Thumbnails about 320 pixels wide.
        const int scale = std::max(1, s.sheet.front().width / 320);
        const auto sheet_path = s.dir / "contact_sheet.png";
        render::write_png(sheet_path, render::contact_sheet(s.sheet, kSheetColumns, scale));
        out.contact_sheet = sheet_path.string();
    }
    const render::FrameSequence::Video video = s.pictures->encode_mp4(fps);
    out.video = video.file.string();
    out.video_note = video.note;
    return out;
}

}  // namespace weft::cli

#else  // a build without the renderer (WEFT_RENDER off): --capture is an error that says why

namespace weft::cli {

struct FrameCapture::State {};

FrameCapture::FrameCapture(const std::string& renderer, std::filesystem::path, int, int, World&, const CameraDesc&,
                           int) {
    throw Error("--capture " + renderer +
                ": this build has no renderer (configure with -DWEFT_RENDER=ON and the Vulkan, EGL and libpng "
                "packages of tools/deps.sh)");
}
FrameCapture::~FrameCapture() = default;
void FrameCapture::capture(int, const std::function<void()>&) {}
CaptureSummary FrameCapture::finish(double) { return {}; }

}  // namespace weft::cli

#endif
