#pragma once
// The command line of the two bending benchmarks (bending_convergence_bench.cpp,
// bending_models_bench.cpp): which strips to sweep.
//
//   [--cells 12,24,48] [--aspect 0.5,1,2] [--load 0.5,2,6.6] [--json FILE]

#include <stdexcept>
#include <string>
#include <vector>

#include "weft/error.h"

namespace weft::bench {

struct StripSweep {
    std::vector<double> cells{12, 24, 48};   ///< cells along the strip
    std::vector<double> aspects{0.5, 1.0, 2.0};  ///< a cell's length along over its width across
    std::vector<double> loads{0.5, 2.0, 6.6};    ///< ρ·g·L³/D
    std::string json;                        ///< where to write the rows ("" for nowhere)
};

/// "1,2.5,3" as positive numbers; throws weft::Error naming `flag` and the bad item.
inline std::vector<double> parse_positive_list(const std::string& flag, const std::string& value) {
    std::vector<double> out;
    std::size_t at = 0;
    while (at <= value.size()) {
        const std::size_t comma = value.find(',', at);
        const std::string item = value.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
        try {
            std::size_t used = 0;
            out.push_back(std::stod(item, &used));
            if (used != item.size() || !(out.back() > 0.0)) throw std::invalid_argument(item);
        } catch (const std::exception&) {
            throw Error(flag + ": '" + item + "' is not a positive number (e.g. " + flag + " 1,2)");
        }
        if (comma == std::string::npos) break;
        at = comma + 1;
    }
    return out;
}

/// The sweep `argv` asks for; throws weft::Error for an unknown option or a bad value.
inline StripSweep parse_strip_sweep(int argc, char** argv) {
    StripSweep sweep;
    for (int i = 1; i < argc; ++i) {
        const std::string flag = argv[i];
        if (i + 1 >= argc) throw Error(flag + " needs a value");
        const std::string value = argv[++i];
        if (flag == "--cells")
            sweep.cells = parse_positive_list(flag, value);
        else if (flag == "--aspect")
            sweep.aspects = parse_positive_list(flag, value);
        else if (flag == "--load")
            sweep.loads = parse_positive_list(flag, value);
        else if (flag == "--json")
            sweep.json = value;
        else
            throw Error("unknown option '" + flag + "' (--cells, --aspect, --load, --json)");
    }
    return sweep;
}

}  // namespace weft::bench
