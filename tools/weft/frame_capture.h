#pragma once
/// @file
/// Headless pictures of a run for `weft run --capture egl|vulkan --out DIR`: every frame drawn by a
/// renderer (weft/render/renderer.h) to DIR/frame_0000.png (frame 0 = the initial state), then a
/// contact sheet of twelve frames spread over the run (DIR/contact_sheet.png) and, when ffmpeg is
/// installed, DIR/capture.mp4 at the simulation's frame rate.
///
/// The cloth reaches the renderer through a ClothFeed (weft/render/cloth_feed.h): zero-copy where the
/// backend and the renderer share a GPU, a host upload otherwise. Frames are pipelined: the steps of
/// frame N+1 run while the GPU draws frame N, and frame N's PNG is written while it draws N+1.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace weft {
class World;
struct CameraDesc;
}  // namespace weft

namespace weft::render {
struct Image;
}  // namespace weft::render

namespace weft::cli {

/// What a capture did, for the run summary and the stats JSON.
struct CaptureSummary {
    std::string renderer;           ///< "egl" or "vulkan"
    std::string device;             ///< the renderer's device description
    std::string path;               ///< how the cloth reached it: "interop (…)" or "host upload (why)"
    std::uint64_t bytes_per_frame = 0;  ///< host → device bytes of the last frame
    int frames = 0;
    std::int64_t torn_frames = 0;   ///< frames whose stamps showed more than one state (must be 0)
    double render_ms_median = 0.0;  ///< host time per frame to submit the draw and collect the picture
    double write_ms_median = 0.0;   ///< PNG encoding and writing per frame
    std::string contact_sheet;      ///< file, empty if none
    std::string video;              ///< file, empty when ffmpeg is missing or failed
    std::string video_note;         ///< why there is no video
};

class FrameCapture {
public:
    /// Starts `renderer` ("egl" or "vulkan") at width×height pixels for `world` seen from `camera`,
    /// writing into `dir` (created). Throws `weft::Error` when the renderer cannot start.
    FrameCapture(const std::string& renderer, std::filesystem::path dir, int width, int height, World& world,
                 const CameraDesc& camera, int last_frame);
    ~FrameCapture();
    FrameCapture(const FrameCapture&) = delete;
    FrameCapture& operator=(const FrameCapture&) = delete;

    /// Runs `steps` (the frame's simulation; empty for frame 0) while the previous frame is drawn,
    /// then submits frame `frame` and writes the previous frame's PNG. Throws `weft::Error` on a
    /// write failure.
    void capture(int frame, const std::function<void()>& steps);
    /// Collects and writes the last frame, then the contact sheet and the video (`fps`: frames per
    /// second of simulated time).
    CaptureSummary finish(double fps);

private:
    void write_image(int frame, const render::Image& image);
    [[nodiscard]] std::optional<render::Image> collect_drawing();

    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace weft::cli
