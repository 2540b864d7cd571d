#include "json_file.h"

#include <fstream>
#include <iostream>
#include <system_error>

#include "weft/atomic_file.h"
#include "weft/error.h"

namespace weft::bench {

using weft::AtomicFile;

bool write_json_file(const std::filesystem::path& file, std::string_view program,
                     const std::function<void(std::ostream&)>& write) {
    if (file.has_parent_path()) {
        std::error_code ec;
        std::filesystem::create_directories(file.parent_path(), ec);  // a failure shows when opening
    }
    try {
        AtomicFile out(file, true);  // whole or not at all
        write(out.stream());
        out.stream() << '\n';
        out.commit();
    } catch (const weft::Error& e) {
        std::cerr << program << ": " << e.what() << '\n';
        return false;
    }
    std::cout << "\nresults: " << file.string() << '\n';
    return true;
}

}  // namespace weft::bench
