#pragma once
/// @file
/// A folder of numbered PNG frames (frame_0000.png, …) and, when ffmpeg is installed, an MP4 made
/// from them: what `weft run --capture` and the editor's recording write.
#include <filesystem>
#include <string>

#include "weft/render/image.h"

namespace weft::render {

class FrameSequence {
public:
    /// Frames go to `folder` (created; throws weft::Error naming it when it cannot be), numbered
    /// with at least `digits` digits.
    explicit FrameSequence(std::filesystem::path folder, int digits = 4);

    /// Writes `image` as frame number `frame` (≥ 0). Throws weft::Error naming the file.
    void write(int frame, const Image& image);
    [[nodiscard]] const std::filesystem::path& folder() const { return folder_; }
    [[nodiscard]] int frames_written() const { return written_; }
    /// The printf pattern of the frames' paths (folder/frame_%04d.png).
    [[nodiscard]] std::string pattern() const;

    struct Video {
        std::filesystem::path file;  ///< folder/capture.mp4, empty when none was made
        std::string note;            ///< why there is none ("ffmpeg not installed", …)
    };
    /// Encodes the frames written, in order, at `fps` frames per second into folder/`name`.
    [[nodiscard]] Video encode_mp4(double fps, const std::string& name = "capture.mp4") const;

private:
    std::filesystem::path folder_;
    int digits_ = 4;
    int written_ = 0;
};

}  // namespace weft::render
