#pragma once
/// @file
/// Scalar helpers for the single-source physics headers: `min_`, `max_`, `clamp_`, `sqr_` and the
/// machine epsilon of float and double. `std::min`/`std::numeric_limits` are constexpr host
/// functions that nvcc only accepts on the device with --expt-relaxed-constexpr, so Weft writes
/// its own (a handful of lines) and stays compilable with plain nvcc flags.

#include "weft/math/host_device.h"

namespace weft::physics {

/// Smaller of two values (returns `a` when they compare equal or unordered).
template <typename T> WEFT_HD constexpr T min_(T a, T b) { return b < a ? b : a; }
/// Larger of two values (returns `a` when they compare equal or unordered).
template <typename T> WEFT_HD constexpr T max_(T a, T b) { return a < b ? b : a; }
/// `x` limited to [lo, hi] (the caller guarantees lo ≤ hi).
template <typename T> WEFT_HD constexpr T clamp_(T x, T lo, T hi) { return x < lo ? lo : (hi < x ? hi : x); }
/// x².
template <typename T> WEFT_HD constexpr T sqr_(T x) { return x * x; }
/// +1 for x ≥ 0, −1 otherwise (never 0, so it can pick a side).
template <typename T> WEFT_HD constexpr T sign_(T x) { return x < T(0) ? T(-1) : T(1); }

/// Machine constants of the scalar type, usable in device code.
template <typename T> struct ScalarTraits;
template <> struct ScalarTraits<float> {
    static constexpr float epsilon = 1.1920929e-7F;  ///< 2⁻²³
    static constexpr float pi = 3.14159265358979F;
};
template <> struct ScalarTraits<double> {
    static constexpr double epsilon = 2.220446049250313e-16;  ///< 2⁻⁵²
    static constexpr double pi = 3.14159265358979323846;
};

}  // namespace weft::physics
