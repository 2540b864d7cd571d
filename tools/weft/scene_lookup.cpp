#include "scene_lookup.h"

#include <algorithm>
#include <string>
#include <system_error>

#include "weft/error.h"

#include "build_info.h"

namespace fs = std::filesystem;

namespace weft::cli {

namespace {

bool is_file(const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec);
}

std::string with_toml(std::string_view name) {
    std::string file(name);
    if (!fs::path(file).has_extension()) file += ".toml";
    return file;
}

}  // namespace

std::vector<fs::path> scene_folders() {
    std::vector<fs::path> folders{fs::path("assets") / "scenes"};
    // The binary sits in <tree>/<build>/bin: look in <tree>/assets/scenes even if the tree moved.
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec && exe.has_parent_path()) {
        folders.push_back(exe.parent_path().parent_path().parent_path() / "assets" / "scenes");
    }
    if (!build_info().source_dir.empty()) folders.push_back(fs::path(build_info().source_dir) / "assets" / "scenes");
    // Drop duplicates (the usual case: the last two are the same folder) but keep the order.
    std::vector<fs::path> unique;
    for (const fs::path& f : folders) {
        const fs::path normal = f.lexically_normal();
        if (std::find(unique.begin(), unique.end(), normal) == unique.end()) unique.push_back(normal);
    }
    return unique;
}

std::vector<std::string> scene_names(const fs::path& folder) {
    std::vector<std::string> names;
    std::error_code ec;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
        if (it->path().extension() == ".toml") names.push_back(it->path().stem().string());
    }
    std::sort(names.begin(), names.end());
    return names;
}

fs::path find_scene(std::string_view name, const std::vector<fs::path>& folders) {
    fs::path given(name);
    if (is_file(given)) return given;
    fs::path given_toml(with_toml(name));
    if (is_file(given_toml)) return given_toml;

    const bool bare = !given.has_parent_path();
    if (!bare) throw Error("scene file '" + std::string(name) + "' not found");

    std::vector<std::string> tried;
    for (const fs::path& folder : folders) {
        fs::path candidate = folder / given_toml;
        if (is_file(candidate)) return candidate;
        tried.push_back(candidate.string());
    }
    std::string message = "scene '" + std::string(name) + "' not found (looked for " + given_toml.string();
    for (const std::string& t : tried) message += ", " + t;
    message += ")";
    for (const fs::path& folder : folders) {
        const auto names = scene_names(folder);
        if (names.empty()) continue;
        message += "; available scenes:";
        for (const std::string& n : names) message += " " + n;
        break;
    }
    throw Error(message);
}

}  // namespace weft::cli
