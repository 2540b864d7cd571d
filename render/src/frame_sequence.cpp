// Numbered PNG frames and their MP4 (see weft/render/frame_sequence.h).
#include "weft/render/frame_sequence.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <system_error>

#include "weft/error.h"

namespace weft::render {
namespace {

bool have_ffmpeg() { return std::system("command -v ffmpeg > /dev/null 2>&1") == 0; }

// One argument for /bin/sh, whatever the path holds.
std::string shell_quote(const std::string& s) {
    std::string out = "'";
    for (const char c : s) {
        if (c == '\'')
            out.append("'\\''");
        else
            out.push_back(c);
    }
    out.push_back('\'');
    return out;
}

}  // namespace

FrameSequence::FrameSequence(std::filesystem::path folder, int digits) : folder_(std::move(folder)), digits_(digits) {
    std::error_code ec;
    std::filesystem::create_directories(folder_, ec);
    if (ec) throw Error("cannot create " + folder_.string() + ": " + ec.message());
}

std::string FrameSequence::pattern() const {
    return (folder_ / ("frame_%0" + std::to_string(digits_) + "d.png")).string();
}

void FrameSequence::write(int frame, const Image& image) {
    char name[48];
    std::snprintf(name, sizeof name, "frame_%0*d.png", digits_, frame);
    write_png(folder_ / name, image);
    ++written_;
}

FrameSequence::Video FrameSequence::encode_mp4(double fps, const std::string& name) const {
    Video v;
    if (written_ < 2) {
        v.note = "fewer than 2 frames";
        return v;
    }
    if (!have_ffmpeg()) {
        v.note = "ffmpeg not installed";
        return v;
    }
    const std::filesystem::path file = folder_ / name;
    std::ostringstream cmd;
    // Even sizes for yuv420p; the frames' own numbering from the first one written.
    cmd << "ffmpeg -y -loglevel error -framerate " << std::max(1.0, fps) << " -i " << shell_quote(pattern())
        << " -pix_fmt yuv420p -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' " << shell_quote(file.string());
    if (std::system(cmd.str().c_str()) == 0)
        v.file = file;
    else
        v.note = "ffmpeg failed (command: " + cmd.str() + ")";
    return v;
}

}  // namespace weft::render
