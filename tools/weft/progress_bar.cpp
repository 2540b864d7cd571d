#include "progress_bar.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "text_table.h"

namespace weft::cli {

bool ProgressBar::stderr_is_terminal() { return ::isatty(STDERR_FILENO) == 1; }

std::string ProgressBar::render(int done, int total, double elapsed_s) {
    constexpr int kBarWidth = 30;
    const double fraction = total > 0 ? std::clamp(static_cast<double>(done) / total, 0.0, 1.0) : 1.0;
    const auto filled = static_cast<int>(fraction * kBarWidth);
    std::string bar(static_cast<std::size_t>(filled), '#');
    bar.append(static_cast<std::size_t>(kBarWidth - filled), '.');

    const double fps = (elapsed_s > 0.0 && done > 0) ? done / elapsed_s : 0.0;
    const std::string width = std::to_string(total);
    char head[96];
    std::snprintf(head, sizeof(head), "frame %*d/%d ", static_cast<int>(width.size()), done, total);
    std::string line = head;
    line += "[" + bar + "] ";
    line += format_fixed(100.0 * fraction, 0) + "%  ";
    line += fps > 0.0 ? format_fixed(fps, fps < 10.0 ? 2 : 1) + " fps" : std::string("- fps");
    line += "  ETA " + (fps > 0.0 ? format_duration((total - done) / fps) : std::string("-:--"));
    return line;
}

void ProgressBar::update(int done, Clock::time_point now) {
    if (!enabled_) return;
    const bool last = done >= total_;
    if (drawn_ && !last && now - last_draw_ < kMinRedrawInterval) return;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const std::string line = render(done, total_, elapsed);
    // Pad with spaces over a longer previous line instead of relying on terminal escape codes.
    const std::size_t pad = last_width_ > line.size() ? last_width_ - line.size() : 0;
    out_ << '\r' << line << std::string(pad, ' ') << std::flush;
    last_width_ = line.size();
    last_draw_ = now;
    drawn_ = true;
    ++redraws_;
}

void ProgressBar::finish() {
    if (!enabled_ || !drawn_) return;
    out_ << '\r' << std::string(last_width_, ' ') << '\r' << std::flush;
    drawn_ = false;
    last_width_ = 0;
}

}  // namespace weft::cli
