#pragma once
/// @file
/// The physics headers' vector types: those of `weft/math/vec.h`, named here as `physics::Vec3<T>`
/// and so on, so that the element math reads the same on host and device without qualifying every
/// type. The using-directive is confined to `weft::physics`.

#include "weft/math/vec.h"

namespace weft::physics {
using namespace weft::math;
}  // namespace weft::physics
