#include "output_file.h"

#include <string>
#include <system_error>

#include "weft/error.h"

namespace weft::cli {

std::ofstream open_output_file(const std::filesystem::path& file, std::string_view what) {
    if (file.has_parent_path()) {
        std::error_code ec;
        std::filesystem::create_directories(file.parent_path(), ec);
        if (ec) {
            throw Error("cannot create the folder of " + std::string(what) + " '" + file.string() +
                        "': " + ec.message());
        }
    }
    std::ofstream stream(file, std::ios::binary | std::ios::trunc);
    if (!stream) throw Error("cannot open " + std::string(what) + " '" + file.string() + "' for writing");
    return stream;
}

void close_output_file(std::ofstream& stream, const std::filesystem::path& file, std::string_view what) {
    stream.close();
    if (!stream) throw Error("failed writing " + std::string(what) + " '" + file.string() + "'");
}

}  // namespace weft::cli
