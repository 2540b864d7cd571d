#pragma once
/// @file
/// The spread of a benchmark's repeated measurements (times in ms, iteration counts), as the
/// benchmarks print and write it to their JSON files.

#include <vector>

#include "json_writer.h"

namespace weft::bench {

struct Dist {
    double median = 0, min = 0, max = 0, mean = 0;
};

/// Median (the mean of the middle two for an even count), extremes and mean of `v`; all 0 when
/// `v` is empty.
[[nodiscard]] Dist distribution(std::vector<double> v);

/// Which members of a Dist a benchmark's JSON file holds (each file keeps its own layout).
enum class DistFields : unsigned char { median_min_max, median_min_max_mean };

/// Writes `d` as a JSON object {"median", "min", "max"[, "mean"]}.
void write_dist(json::JsonWriter& json, const Dist& d, DistFields fields);

}  // namespace weft::bench
