#include "output_file.h"

#include <string>
#include <system_error>

#include "weft/error.h"

namespace weft::cli {

AtomicFile open_output_file(const std::filesystem::path& file, std::string_view what) {
    try {
        return AtomicFile(file, true);
    } catch (const Error& e) {
        throw Error("cannot open " + std::string(what) + " '" + file.string() + "' for writing: " + e.what());
    }
}

void close_output_file(AtomicFile& out, const std::filesystem::path& file, std::string_view what) {
    try {
        out.commit();
    } catch (const Error& e) {
        throw Error("failed writing " + std::string(what) + " '" + file.string() + "': " + e.what());
    }
}

}  // namespace weft::cli
