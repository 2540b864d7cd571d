#pragma once
/// @file
/// A one-line progress bar (frame, fps, ETA) for `weft run` on a terminal. It redraws at most ten
/// times a second so that fast scenes are not slowed down by terminal output.

#include <chrono>
#include <ostream>
#include <string>

namespace weft::cli {

class ProgressBar {
public:
    using Clock = std::chrono::steady_clock;
    static constexpr Clock::duration kMinRedrawInterval = std::chrono::milliseconds(100);

    /// With `enabled` false (not a terminal, --quiet) every call does nothing.
    ProgressBar(std::ostream& out, int total, bool enabled, Clock::time_point start = Clock::now())
        : out_(out), total_(total), enabled_(enabled), start_(start) {}
    ProgressBar(const ProgressBar&) = delete;
    ProgressBar& operator=(const ProgressBar&) = delete;
    ~ProgressBar() { finish(); }

    /// `done` frames of `total` are complete at `now`. Draws when 100 ms passed since the last
    /// draw, or at the last frame.
    void update(int done, Clock::time_point now = Clock::now());
    /// Erases the bar so that the next output starts on a clean line. Idempotent.
    void finish();

    [[nodiscard]] int redraws() const { return redraws_; }

    /// The text of the bar for `done` of `total` frames after `elapsed_s` seconds.
    [[nodiscard]] static std::string render(int done, int total, double elapsed_s);
    /// True when stderr is an interactive terminal.
    [[nodiscard]] static bool stderr_is_terminal();

private:
    std::ostream& out_;
    int total_;
    bool enabled_;
    Clock::time_point start_;
    Clock::time_point last_draw_{};
    bool drawn_ = false;
    int redraws_ = 0;
    std::size_t last_width_ = 0;
};

}  // namespace weft::cli
