#pragma once
// Positions as the CUDA backend sees them: rounded to float, in the structure-of-arrays layout of its
// vertex arrays. Shared by the GPU tests and the GPU collision benchmark, so that their double
// references (the CPU, brute force) look at exactly the device's input.
#include <cstddef>
#include <limits>
#include <vector>

#include "weft/types.h"

namespace weft::test {

/// Rounds every coordinate of `s.x0` and `s.x1` (std::vector<Vec3d>) to float.
template <typename Scene>
void snap_to_float(Scene& s) {
    for (auto* xs : {&s.x0, &s.x1})
        for (Vec3d& p : *xs)
            for (int k = 0; k < 3; ++k) p[k] = static_cast<double>(static_cast<float>(p[k]));
}

/// `x` in float, component k of vertex i at [k·stride + i]; `stride` 0 means x.size(), and the
/// padding past x.size() holds NaN.
inline std::vector<float> soa_floats(const std::vector<Vec3d>& x, std::size_t stride = 0) {
    const std::size_t n = x.size();
    if (stride == 0) stride = n;
    std::vector<float> out(3 * stride, std::numeric_limits<float>::quiet_NaN());
    for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) out[static_cast<std::size_t>(k) * stride + i] = static_cast<float>(x[i][k]);
    return out;
}

}  // namespace weft::test
