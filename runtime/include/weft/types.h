#pragma once
/// @file
/// Basic public types of the Weft runtime. Units are SI throughout (m, kg, s); Y is up and the
/// frame is right-handed.

#include <cstdint>

#include "weft/math/vec.h"

namespace weft {

using Vec3d = math::Vec3<double>;
using Vec3f = math::Vec3<float>;
using Mat3d = math::Mat3<double>;

/// Index triple of a triangle, counter-clockwise seen from the front face.
struct Triangle {
    std::uint32_t v[3]{};
};

/// Floating-point precision a backend computes in. Double is the accuracy reference.
enum class Precision : std::uint8_t { Float, Double };

}  // namespace weft
