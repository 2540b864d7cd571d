#include "frame_writer.h"

#include <algorithm>
#include <cstdio>
#include <system_error>

#include "weft/backend/model.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft::cli {

std::string file_name_part(std::string_view name) {
    std::string out;
    out.reserve(name.size());
    for (const char c : name) {
        const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
                          c == '_' || c == '.';
        out += keep ? c : '_';
    }
    return out;
}

FrameWriter::FrameWriter(std::filesystem::path dir, MeshFormat format, const std::vector<std::string>& cloth_names,
                         int last_frame)
    : dir_(std::move(dir)), format_(format) {
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (ec) throw Error("cannot create output folder '" + dir_.string() + "': " + ec.message());
    for (std::size_t i = 0; i < cloth_names.size(); ++i) {
        std::string stem = file_name_part(cloth_names[i]);
        if (stem.empty() || std::find(stems_.begin(), stems_.end(), stem) != stems_.end()) {
            stem += (stem.empty() ? "cloth" : "_") + std::to_string(i);
        }
        stems_.push_back(std::move(stem));
    }
    digits_ = std::max(4, static_cast<int>(std::to_string(std::max(last_frame, 0)).size()));
}

std::filesystem::path FrameWriter::path(int frame, std::size_t cloth) const {
    char number[32];
    std::snprintf(number, sizeof(number), "%0*d", digits_, frame);
    return dir_ / ("frame_" + std::string(number) + "_" + stems_.at(cloth) + std::string(extension(format_)));
}

void FrameWriter::write(int frame, const World& world) {
    const Model& model = world.model();
    for (std::size_t c = 0; c < model.cloths.size(); ++c) {
        const std::vector<Vec3d> positions = world.positions(c);
        write_mesh(path(frame, c), positions, model.cloths[c].fabric->triangles());
        ++files_written_;
    }
}

std::string FrameWriter::pattern() const {
    std::string p = (dir_ / "frame_*").string();
    if (stems_.size() == 1) p += "_" + stems_.front();
    return p + std::string(extension(format_));
}

}  // namespace weft::cli
