// The progress bar: content, at most ten redraws a second, silent when disabled.
#include <gtest/gtest.h>

#include <chrono>
#include <sstream>

#include "progress_bar.h"

namespace weft::cli {
namespace {

using namespace std::chrono_literals;

TEST(ProgressBar, RenderShowsFrameFpsAndEta) {
    const std::string line = ProgressBar::render(50, 200, 2.0);
    EXPECT_NE(line.find("frame  50/200"), std::string::npos) << line;
    EXPECT_NE(line.find("25%"), std::string::npos) << line;
    EXPECT_NE(line.find("25.0 fps"), std::string::npos) << line;
    EXPECT_NE(line.find("ETA 0:06"), std::string::npos) << line;
    const std::string start = ProgressBar::render(0, 10, 0.0);
    EXPECT_NE(start.find("- fps"), std::string::npos) << start;
    EXPECT_NE(start.find("ETA -:--"), std::string::npos) << start;
}

TEST(ProgressBar, RedrawsAtMostTenTimesASecond) {
    std::ostringstream out;
    const auto t0 = ProgressBar::Clock::time_point{};
    {
        ProgressBar bar(out, 1000, true, t0);
        // 1000 frames in one second: one update per millisecond.
        for (int frame = 1; frame <= 1000; ++frame) bar.update(frame, t0 + frame * 1ms);
        EXPECT_LE(bar.redraws(), 11);
        EXPECT_GE(bar.redraws(), 10);
    }
    const std::string text = out.str();
    EXPECT_NE(text.find("frame 1000/1000"), std::string::npos) << "the last frame is always drawn";
    EXPECT_EQ(text.find('\n'), std::string::npos) << "the bar stays on one line";
}

TEST(ProgressBar, DisabledWritesNothing) {
    std::ostringstream out;
    {
        ProgressBar bar(out, 10, false);
        for (int frame = 1; frame <= 10; ++frame) bar.update(frame);
        bar.finish();
    }
    EXPECT_TRUE(out.str().empty());
}

}  // namespace
}  // namespace weft::cli
