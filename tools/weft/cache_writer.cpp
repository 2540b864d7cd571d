// `weft run --cache` (cache_writer.h).
#include "cache_writer.h"

#include <algorithm>
#include <cctype>

#include "frame_writer.h"
#include "weft/error.h"
#include "weft/mesh.h"
#include "weft/world.h"

namespace weft::cli {

CacheWriter::CacheWriter(const std::filesystem::path& file, const World& world, double frame_seconds) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if ((ext != ".pc2" && ext != ".glb") || file.stem().empty())
        throw Error("--cache " + file.string() + ": the cache is a PC2 point cache (FILE.pc2) or a glTF binary (FILE.glb)");
    if (ext == ".glb") {
        gltf_ = std::make_unique<GltfCacheWriter>(file, world, frame_seconds);
        return;
    }
    if (file.has_parent_path()) {
        std::error_code ec;
        std::filesystem::create_directories(file.parent_path(), ec);
        if (ec) throw Error("cannot create the cache's folder '" + file.parent_path().string() + "': " + ec.message());
    }
    std::vector<std::string> stems;
    for (std::size_t c = 0; c < world.cloth_count(); ++c) {
        std::filesystem::path pc2 = file;
        if (world.cloth_count() > 1) {
            std::string stem = file_name_part(world.cloth(c).name);
            if (stem.empty() || std::find(stems.begin(), stems.end(), stem) != stems.end())
                stem += (stem.empty() ? "cloth" : "_") + std::to_string(c);
            stems.push_back(stem);
            pc2.replace_filename(file.stem().string() + "_" + stem + ".pc2");
        }
        const std::vector<Vec3d> x = world.positions(c);
        write_mesh(std::filesystem::path(pc2).replace_extension(".obj"), x, world.cloth(c).fabric->triangles());
        caches_.emplace_back(pc2, x.size());
    }
}

void CacheWriter::append(const World& world) {
    if (gltf_) gltf_->append(world);
    for (std::size_t c = 0; c < caches_.size(); ++c) caches_[c].append(world.positions(c));
}

void CacheWriter::finish(const World& world) {
    if (gltf_) gltf_->finish(world);
}

std::size_t CacheWriter::frames() const {
    if (gltf_) return gltf_->frames();
    return caches_.empty() ? 0 : caches_.front().frames();
}

std::vector<std::filesystem::path> CacheWriter::files() const {
    if (gltf_) return {gltf_->file()};
    std::vector<std::filesystem::path> out;
    for (const PointCacheWriter& w : caches_) out.push_back(w.file());
    return out;
}

}  // namespace weft::cli
