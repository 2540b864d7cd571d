// check_file_size (weft/world_limits.h).
#include "weft/world_limits.h"

#include <string>
#include <system_error>

#include "weft/byte_size.h"
#include "weft/error.h"

namespace weft {

void check_file_size(const std::filesystem::path& path, std::uintmax_t limit, std::string_view what) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec || size <= limit) return;
    throw Error(path.string() + ": the " + std::string(what) + " is " + format_bytes(static_cast<double>(size)) + ", more than the " +
                format_bytes(static_cast<double>(limit)) + " Weft reads (weft/world_limits.h)");
}

}  // namespace weft
