#pragma once
// A whole file's bytes, for tests that check what was written.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace weft::test {

/// The bytes of `path` (empty when it cannot be read).
inline std::string file_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

}  // namespace weft::test
