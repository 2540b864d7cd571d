// format_bytes (weft/byte_size.h): the unit that keeps the number below 1024.
#include "weft/byte_size.h"

#include <cstdio>

namespace weft {

std::string format_bytes(double bytes) {
    static constexpr const char* kUnits[] = {"B", "KiB", "MiB", "GiB", "TiB"};
    int unit = 0;
    while (bytes >= 1024.0 && unit < 4) {
        bytes /= 1024.0;
        ++unit;
    }
    const int decimals = unit == 0 ? 0 : (bytes < 10.0 ? 2 : (bytes < 100.0 ? 1 : 0));
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.*f %s", decimals, bytes, kUnits[unit]);
    return buf;
}

}  // namespace weft
