// Mesh import through assimp, merged into one triangle mesh and welded by position.
#include "weft/assets/assimp_loader.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <exception>
#include <fstream>
#include <limits>

#include "weft/error.h"
#include "weft/world_limits.h"
#include "weft/mesh.h"
#include "file_signature.h"
#include "weft/assets/skinned_import.h"
#include "obj_scan.h"
#include "ply_scan.h"

namespace weft::assets {

MeshData import_mesh(const std::filesystem::path& path, ImportReport* report) {
    const std::string file = path.string();
    ImportReport local;
    ImportReport& r = report != nullptr ? *report : local;
    r = ImportReport{};
    r.file = file;

    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(file + ": mesh file not found");
    check_file_size(path, kMaxMeshFileBytes, "mesh file");

    // An OBJ is scanned first: assimp keeps only the vertices faces use and stops where the file
    // ends, so a file cut short would load as a smaller cloth without a word (obj_scan.h).
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    // assimp tries every reader it has on a file its extension's reader refuses, and some of those
    // readers overflow their buffers on garbage (a ".gltf" of text: found by fuzz_mesh_import). A
    // file whose start is not its extension's format is refused here first.
    const bool ply_magic = check_signature(path, ext);
    // A PLY's header is checked too (ply_scan.h): assimp loops forever on one without `end_header`
    // and reads past the data of a file cut short. It picks its PLY reader by the content as well as
    // the extension, so the magic decides here too.
    if (ext == ".ply" || ply_magic) (void)scan_ply(path);
    if (ext == ".obj") {
        const ObjScan scan = scan_obj(path);
        if (scan.ends_mid_line)
            throw Error(file + ": the file ends in the middle of a vertex or face line (cut short?): " + std::to_string(scan.vertices) +
                        " vertices and " + std::to_string(scan.faces) + " faces read");
        if (scan.unreferenced > 0)
            throw Error(file + ": " + std::to_string(scan.unreferenced) + " of its " + std::to_string(scan.vertices) +
                        " vertices are in no face: a file cut short loses its last faces (remove unused vertices if "
                        "the file is whole)");
    }

    Assimp::Importer importer;
    // Points and lines are not cloth: let SortByPType drop them instead of failing on them later.
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    // Triangulate polygons; JoinIdenticalVertices undoes the per-corner vertices some formats load
    // (vertices still differ at UV/normal seams: the weld below merges those); PreTransformVertices
    // applies node transforms so that the mesh comes out as the file shows it.
    // ValidateDataStructure runs before the other steps: a truncated or inconsistent file (a binary
    // PLY cut short leaves faces indexing vertices that were never read) is refused there instead of
    // crashing the steps after it.
    const unsigned flags = aiProcess_ValidateDataStructure | aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                           aiProcess_PreTransformVertices | aiProcess_SortByPType;
    const aiScene* scene = nullptr;
    try {
        scene = importer.ReadFile(file, flags);
    } catch (const std::exception& e) {
        throw Error(file + ": cannot import mesh: " + e.what());
    }
    if (scene == nullptr) throw Error(file + ": cannot import mesh: " + importer.GetErrorString());
    if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0U || scene->mNumMeshes == 0)
        throw Error(file + ": cannot import mesh: the file holds no triangle mesh");

    MeshData mesh;
    mesh.source = file;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh& in = *scene->mMeshes[m];
        if ((in.mPrimitiveTypes & (aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON)) == 0U) continue;
        ++r.meshes;
        if (mesh.positions.size() + in.mNumVertices > std::numeric_limits<std::uint32_t>::max() - 1U)
            throw Error(file + ": too many vertices");
        const auto base = static_cast<std::uint32_t>(mesh.positions.size());
        for (unsigned v = 0; v < in.mNumVertices; ++v) {
            const aiVector3D& p = in.mVertices[v];
            mesh.positions.push_back({static_cast<double>(p.x), static_cast<double>(p.y), static_cast<double>(p.z)});
        }
        for (unsigned f = 0; f < in.mNumFaces; ++f) {
            const aiFace& face = in.mFaces[f];
            if (face.mNumIndices != 3) {
                ++r.skipped_primitives;
                continue;
            }
            Triangle t;
            for (int k = 0; k < 3; ++k) {
                const unsigned index = face.mIndices[k];
                if (index >= in.mNumVertices)
                    throw Error(file + ": mesh " + std::to_string(m) + " face " + std::to_string(f) +
                                " refers to vertex " + std::to_string(index) + " of " + std::to_string(in.mNumVertices));
                t.v[k] = base + index;
            }
            mesh.triangles.push_back(t);
        }
    }
    if (mesh.triangles.empty()) throw Error(file + ": cannot import mesh: the file holds no triangles");
    r.imported_vertices = mesh.positions.size();
    r.triangles = mesh.triangles.size();

    // Assimp keeps one vertex per (position, UV, normal) combination, so a garment arrives cut open
    // along its UV seams. Weld by position, relative to the model's size so that millimetre and
    // metre models behave alike.
    const double diagonal = bounding_box_diagonal(mesh);
    if (!std::isfinite(diagonal)) throw Error(file + ": the mesh has non-finite vertex positions");
    r.weld_tolerance = kSeamWeldRelativeTolerance * diagonal;
    weld_by_position(mesh, r.weld_tolerance);
    r.welded_vertices = mesh.welded_vertices;
    if (r.welded_vertices > 0)
        r.warnings.push_back(std::to_string(r.welded_vertices) + " vertices split at UV/normal seams welded back");
    if (r.skipped_primitives > 0)
        r.warnings.push_back(std::to_string(r.skipped_primitives) + " non-triangle primitives skipped");
    return mesh;
}

void install_mesh_loader() {
    set_mesh_file_loader([](const std::filesystem::path& path) { return import_mesh(path); });
    set_skinned_mesh_file_loader([](const std::filesystem::path& path) { return import_skinned_mesh(path); });
}

}  // namespace weft::assets
