// libFuzzer target: mesh import through assimp with welding and cooking (OBJ, PLY, glTF) must answer
// every file with a mesh or a weft::Error, never a crash or a hang (issue 24, fuzzing).
//
// Input: one byte choosing the format (its value mod 4: OBJ, PLY, glTF, GLB), then the file's bytes.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "weft/assets/assimp_loader.h"
#include "weft/error.h"
#include "weft/fabric.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    static const char* const kExtensions[] = {".obj", ".ply", ".gltf", ".glb"};
    const std::filesystem::path file =
        std::filesystem::temp_directory_path() / ("weft_fuzz_mesh_" + std::to_string(getpid()) + kExtensions[data[0] % 4]);
    {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    }
    try {
        weft::MeshData mesh = weft::assets::import_mesh(file);
        (void)weft::Fabric::cook(std::move(mesh));
    } catch (const weft::Error&) {
        // A clear error is the right answer to a bad file.
    }
    std::error_code ec;
    std::filesystem::remove(file, ec);
    return 0;
}
