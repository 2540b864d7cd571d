// `weft info`: version, backends and the devices they run on, host threads, build options.
#include <algorithm>
#include <fstream>
#include <string>
#include <thread>

#include "weft/backend/backend.h"
#include "weft/backend_options.h"
#include "weft/mesh.h"
#if WEFT_HAVE_RENDER

#include "weft/render/renderer.h"
#endif

#include "build_info.h"
#include "gltf_cache_writer.h"
#include "commands.h"
#include "scene_lookup.h"
#include "text_table.h"

namespace weft::cli {

namespace {

std::string cpu_model() {
    std::ifstream cpuinfo("/proc/cpuinfo");
    std::string line;
    while (std::getline(cpuinfo, line)) {
        if (line.starts_with("model name")) {
            const auto colon = line.find(':');
            if (colon != std::string::npos) return line.substr(line.find_first_not_of(' ', colon + 1));
        }
    }
    return "unknown";
}

std::string yes_no(bool on, std::string_view detail) {
    return std::string(on ? "yes" : "no") + (detail.empty() ? "" : " (" + std::string(detail) + ")");
}

}  // namespace

int info_command(std::ostream& out) {
    const BuildInfo& build = build_info();
    out << "weft " << build.version << (build.build_type.empty() ? "" : " (" + std::string(build.build_type) + ")")
        << "\n\n";

    // Devices come from the backends themselves: each one says where it runs, so the CUDA backend
    // lists its GPUs here without this command knowing about CUDA.
    out << "backends\n";
    TextTable backends({{"name", TextTable::Align::Left},
                        {"device", TextTable::Align::Left},
                        {"description", TextTable::Align::Left}});
    for (const std::string& name : backend_names()) {
        std::string device;
        try {
            device = create_backend(name)->device_description();
        } catch (const std::exception& e) {
            device = std::string("unavailable: ") + e.what();
        }
        backends.add_row({name, device, backend_description(name)});
    }
    backends.print(out);

#if WEFT_HAVE_RENDER
    // Each renderer started once, small: where it draws, or why it cannot here, and whether its
    // cloth buffer can be shared zero-copy with a GPU backend (docs/rendering.md, "Zero-copy
    // interop"), found by exporting the buffer of a one-triangle scene.
    out << "\nrenderers (weft run --capture, weft view, weft edit)\n";
    TextTable renderers({{"name", TextTable::Align::Left}, {"device", TextTable::Align::Left},
                         {"zero-copy cloth", TextTable::Align::Left}});
    render::RenderScene probe;
    probe.cloth_vertices = 3;
    probe.cloth_indices = {0, 1, 2};
    probe.cloths.push_back(render::ClothDraw{.name = "probe", .vertex_count = 3, .index_count = 3});
    for (const std::string& name : render::renderer_names()) {
        std::string device, path;
        try {
            render::RendererOptions options;
            options.width = options.height = 16;
            options.samples = 1;
            options.shadow_map_size = 16;
            const auto renderer = render::create_renderer(name, options);
            device = renderer->device_description();
            renderer->load(probe);
            std::string why;
            if (auto link = renderer->export_cloth(why)) {
                close_slot_handles(link->slots);
                const bool gl = !link->slots.empty() && link->slots.front().api == SlotApi::opengl_buffer;
                // GL buffers always export; CUDA takes them only from a context on its own GPU, and
                // Mesa's software rasteriser keeps them in host memory.
                if (gl && (device.find("llvmpipe") != std::string::npos || device.find("softpipe") != std::string::npos))
                    path = "no, host upload: a software rasteriser's buffers are host memory";
                else if (gl)
                    path = "available (" + std::to_string(link->slots.size()) +
                           " GL buffer objects, registered by CUDA where its GPU runs this context)";
                else
                    path = "available (" + std::to_string(link->slots.size()) +
                           " exported cloth slots, a timeline semaphore each)";
            } else {
                path = "no, host upload: " + why;
            }
        } catch (const std::exception& e) {
            device = std::string("unavailable: ") + e.what();
            path = "-";
        }
        renderers.add_row({name, device, path});
    }
    renderers.print(out);
#endif

    out << "\nhost\n";
    out << "  CPU            " << cpu_model() << '\n';
    out << "  threads        " << std::thread::hardware_concurrency() << '\n';

    out << "\nbuild options\n";
    const auto backends_built = backend_names();
    const bool cuda_registered =
        std::find(backends_built.begin(), backends_built.end(), "cuda") != backends_built.end();
    out << "  CUDA backend   "
        << yes_no(cuda_registered, build.cuda ? (cuda_registered ? "" : "nvcc found, but no CUDA backend in this build")
                                              : "WEFT_CUDA off or no nvcc found")
        << '\n';
    out << "  renderer       " << yes_no(build.render, "WEFT_RENDER: Vulkan, EGL capture") << '\n';
    out << "  editor         " << yes_no(build.editor, "WEFT_EDITOR: ImGui") << '\n';
    out << "  mesh import    "
        << yes_no(has_mesh_file_loader(), has_mesh_file_loader() ? "assimp: OBJ, PLY, glTF, FBX, ..."
                                                                 : "WEFT_ASSETS off: procedural grids only")
        << '\n';
    out << "  caches         "
        << yes_no(true, gltf_caches_available() ? "--cache: PC2 and glTF (TinyGLTF)" : "--cache: PC2 (no TinyGLTF: no glTF)") << '\n';

    out << "\nscene folders\n";
    for (const std::filesystem::path& folder : scene_folders()) {
        const auto names = scene_names(folder);
        out << "  " << folder.string() << ": ";
        if (names.empty()) out << "(none)";
        for (std::size_t i = 0; i < names.size(); ++i) out << (i ? " " : "") << names[i];
        out << '\n';
    }
    return kExitOk;
}

}  // namespace weft::cli
