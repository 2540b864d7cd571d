#include "json_file.h"

#include <fstream>
#include <iostream>
#include <system_error>

namespace weft::bench {

bool write_json_file(const std::filesystem::path& file, std::string_view program,
                     const std::function<void(std::ostream&)>& write) {
    if (file.has_parent_path()) {
        std::error_code ec;
        std::filesystem::create_directories(file.parent_path(), ec);  // a failure shows when opening
    }
    std::ofstream stream(file);
    if (!stream) {
        std::cerr << program << ": cannot write " << file.string() << '\n';
        return false;
    }
    write(stream);
    stream << '\n';
    stream.close();
    if (!stream) {
        std::cerr << program << ": error writing " << file.string() << '\n';
        return false;
    }
    std::cout << "\nresults: " << file.string() << '\n';
    return true;
}

}  // namespace weft::bench
