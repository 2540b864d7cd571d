#pragma once
/// @file
/// Byte counts for people: "512 B", "840 KiB", "1.21 GiB" (binary units, three significant figures).

#include <string>

namespace weft {

/// `bytes` in B, KiB, MiB, GiB or TiB, with 0–2 decimals.
[[nodiscard]] std::string format_bytes(double bytes);

}  // namespace weft
