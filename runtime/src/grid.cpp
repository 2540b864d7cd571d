// Procedural rectangular sheets (the `mesh = { grid = … }` source of scenes).
#include <string>

#include "weft/error.h"
#include "weft/mesh.h"

namespace weft {

MeshData make_grid(double width, double height, int cells_x, int cells_y, GridPlane plane) {
    if (!(width > 0.0) || !(height > 0.0))
        throw Error("grid: width and height must be positive (got " + std::to_string(width) + " × " +
                    std::to_string(height) + " m)");
    if (cells_x < 1 || cells_y < 1 || cells_x > 8192 || cells_y > 8192)
        throw Error("grid: cell counts must be in [1, 8192] (got " + std::to_string(cells_x) + " × " +
                    std::to_string(cells_y) + ")");
    MeshData mesh;
    mesh.source = "grid " + std::to_string(cells_x) + "x" + std::to_string(cells_y);
    const auto nx = static_cast<std::uint32_t>(cells_x) + 1;
    const auto ny = static_cast<std::uint32_t>(cells_y) + 1;
    mesh.positions.reserve(std::size_t{nx} * ny);
    for (std::uint32_t j = 0; j < ny; ++j) {
        for (std::uint32_t i = 0; i < nx; ++i) {
            const double u = width * (static_cast<double>(i) / cells_x - 0.5);
            const double w = height * (static_cast<double>(j) / cells_y - 0.5);
            mesh.positions.push_back(plane == GridPlane::XY ? Vec3d{u, w, 0.0} : Vec3d{u, 0.0, -w});
        }
    }
    mesh.triangles.reserve(std::size_t{2} * static_cast<std::size_t>(cells_x) * static_cast<std::size_t>(cells_y));
    for (std::uint32_t j = 0; j + 1 < ny; ++j) {
        for (std::uint32_t i = 0; i + 1 < nx; ++i) {
            const std::uint32_t a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
            // Alternate the diagonal in a checkerboard so the discretisation has no preferred shear
            // direction (a uniform diagonal makes the sheet visibly stiffer along it).
            if (((i + j) & 1U) == 0) {
                mesh.triangles.push_back({{a, b, d}});
                mesh.triangles.push_back({{a, d, c}});
            } else {
                mesh.triangles.push_back({{a, b, c}});
                mesh.triangles.push_back({{b, d, c}});
            }
        }
    }
    return mesh;
}

}  // namespace weft
