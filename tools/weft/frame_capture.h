#pragma once
/// @file
/// Headless pictures of a run for `weft run --capture egl|vulkan --out DIR`: every frame drawn by a
/// renderer (weft/render/renderer.h) to DIR/frame_0000.png (frame 0 = the initial state), then a
/// contact sheet of twelve frames spread over the run (DIR/contact_sheet.png) and, when ffmpeg is
/// installed, DIR/capture.mp4 at the simulation's frame rate.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace weft {
class World;
struct CameraDesc;
}  // namespace weft

namespace weft::cli {

/// What a capture did, for the run summary and the stats JSON.
struct CaptureSummary {
    std::string renderer;           ///< "egl" or "vulkan"
    std::string device;             ///< the renderer's device description
    std::string path;               ///< how the cloth reached it: "host upload" or "interop"
    std::uint64_t bytes_per_frame = 0;  ///< host → device bytes of the last frame
    int frames = 0;
    double render_ms_median = 0.0;  ///< draw + read-back per frame
    double write_ms_median = 0.0;   ///< PNG encoding and writing per frame
    std::string contact_sheet;      ///< file, empty if none
    std::string video;              ///< file, empty when ffmpeg is missing or failed
    std::string video_note;         ///< why there is no video
};

class FrameCapture {
public:
    /// Starts `renderer` ("egl" or "vulkan") at width×height pixels for `world` seen from `camera`,
    /// writing into `dir` (created). Throws `weft::Error` when the renderer cannot start.
    FrameCapture(const std::string& renderer, std::filesystem::path dir, int width, int height, const World& world,
                 const CameraDesc& camera, int last_frame);
    ~FrameCapture();
    FrameCapture(const FrameCapture&) = delete;
    FrameCapture& operator=(const FrameCapture&) = delete;

    /// Draws `world` as frame `frame` and writes its PNG. Throws `weft::Error` on a write failure.
    void capture(int frame, const World& world);
    /// Writes the contact sheet and the video (`fps`: frames per second of simulated time).
    CaptureSummary finish(double fps);

private:
    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace weft::cli
