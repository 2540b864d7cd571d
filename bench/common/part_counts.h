#pragma once
// The `--parts` list of the multi-GPU benchmarks: comma-separated part counts.

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "weft/error.h"

namespace weft::bench {

/// "2,4,8" → {2, 4, 8}; throws weft::Error naming the item that is not a count in 1..`largest`.
inline std::vector<std::uint32_t> parse_part_counts(const std::string& list, std::uint32_t largest) {
    std::vector<std::uint32_t> out;
    std::stringstream in(list);
    std::string item;
    while (std::getline(in, item, ',')) {
        std::size_t used = 0;
        unsigned long v = 0;
        try {
            v = std::stoul(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != item.size() || v == 0 || v > largest)
            throw Error("--parts: '" + item + "' is not a part count in 1.." + std::to_string(largest));
        out.push_back(static_cast<std::uint32_t>(v));
    }
    if (out.empty()) throw Error("--parts: no part count in '" + list + "'");
    return out;
}

}  // namespace weft::bench
