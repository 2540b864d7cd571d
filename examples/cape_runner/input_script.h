#pragma once
// A scripted player: a text file of timed key events, so that the game runs the same way every time
// (the CI test, the README's picture). One event a line, `#` starts a comment:
//
//   0.0  forward down      # hold forward from the start
//   1.5  right down
//   2.0  right up
//   2.5  jump tap          # held for one frame
//
// Keys: forward, back, left, right, jump, run; actions: down, up, tap. Times in simulated seconds,
// non-decreasing. A bad line throws std::runtime_error naming the file and the line.
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "runner.h"

namespace cape_runner {

class InputScript {
public:
    explicit InputScript(const std::string& file) {
        std::ifstream in(file);
        if (!in) throw std::runtime_error(file + ": cannot read the input script");
        static const std::set<std::string> kKeys = {"forward", "back", "left", "right", "jump", "run"};
        std::string line;
        for (int number = 1; std::getline(in, line); ++number) {
            if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
            std::istringstream words(line);
            Event e;
            if (!(words >> e.time)) {
                if (line.find_first_not_of(" \t\r") == std::string::npos) continue;  // blank
                throw std::runtime_error(file + ":" + std::to_string(number) + ": expected TIME KEY ACTION");
            }
            std::string extra;
            if (!(words >> e.key >> e.action) || (words >> extra) || !kKeys.contains(e.key) ||
                (e.action != "down" && e.action != "up" && e.action != "tap") || !(e.time >= last_time_))
                throw std::runtime_error(file + ":" + std::to_string(number) + ": '" + line +
                                         "': expected TIME KEY ACTION, keys forward back left right jump run, actions "
                                         "down up tap, times in order");
            last_time_ = e.time;
            events_.push_back(e);
        }
    }

    /// The controls of the frame that starts at `t` (s): every event up to then applied.
    Controls at(double t) {
        taps_.clear();
        for (; next_ < events_.size() && events_[next_].time <= t + 1e-9; ++next_) {
            const Event& e = events_[next_];
            if (e.action == "tap") taps_.insert(e.key);
            held_[e.key] = e.action == "down";
        }
        const auto on = [&](const char* key) { return held_[key] || taps_.contains(key); };
        Controls c;
        c.forward = (on("forward") ? 1.0 : 0.0) - (on("back") ? 1.0 : 0.0);
        c.turn = (on("right") ? 1.0 : 0.0) - (on("left") ? 1.0 : 0.0);
        c.jump = on("jump");
        c.run = on("run");
        return c;
    }

    /// The time of the last event (s).
    [[nodiscard]] double length() const { return last_time_; }

private:
    struct Event {
        double time = 0.0;
        std::string key, action;
    };
    std::vector<Event> events_;
    std::size_t next_ = 0;
    double last_time_ = 0.0;
    std::map<std::string, bool> held_;
    std::set<std::string> taps_;
};

}  // namespace cape_runner
