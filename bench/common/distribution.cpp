#include "distribution.h"

#include <algorithm>
#include <cstddef>

namespace weft::bench {

Dist distribution(std::vector<double> v) {
    Dist d;
    if (v.empty()) return d;
    std::sort(v.begin(), v.end());
    const std::size_t m = v.size() / 2;
    d.median = v.size() % 2 == 1 ? v[m] : 0.5 * (v[m - 1] + v[m]);
    d.min = v.front();
    d.max = v.back();
    for (double x : v) d.mean += x;
    d.mean /= static_cast<double>(v.size());
    return d;
}

void write_dist(json::JsonWriter& json, const Dist& d, DistFields fields) {
    json.begin_object().field("median", d.median).field("min", d.min).field("max", d.max);
    if (fields == DistFields::median_min_max_mean) json.field("mean", d.mean);
    json.end_object();
}

}  // namespace weft::bench
