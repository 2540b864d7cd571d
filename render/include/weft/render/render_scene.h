#pragma once
/// @file
/// What a renderer draws, independent of the graphics API: the cloth's topology and colours, the
/// colliders as triangle meshes, the ground, the camera and the key light (`RenderScene`, built
/// once per topology), and the state of one frame (`RenderFrame`: cloth vertices and collider
/// poses). The Vulkan renderer and the EGL capture draw the same `RenderScene` with the same
/// shaders (render/shaders/), so they give the same picture.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "weft/scene.h"
#include "weft/world.h"

namespace weft::render {

/// One vertex as the solvers write it for drawing: position (m) and unit normal, 24 bytes. The
/// layout of the CUDA backend's output buffer (weft::cuda::OutputVertex), so that buffer can be
/// drawn as it is.
struct RenderVertex {
    float position[3];
    float normal[3];
};
static_assert(sizeof(RenderVertex) == 24, "the solver's output layout");

/// A static triangle mesh in its own frame (colliders, the ground).
struct RenderMesh {
    std::vector<RenderVertex> vertices;
    std::vector<std::uint32_t> indices;  ///< three per triangle, counter-clockwise seen from the front
};

/// One cloth: a range of the shared cloth vertex buffer and its triangles (indices into the whole
/// buffer, so all cloths draw from one buffer).
struct ClothDraw {
    std::string name;
    std::uint32_t first_vertex = 0;
    std::uint32_t vertex_count = 0;
    std::uint32_t first_index = 0;   ///< into RenderScene::cloth_indices
    std::uint32_t index_count = 0;
    glm::vec3 front_colour{0.8F, 0.3F, 0.2F};  ///< linear RGB
    glm::vec3 back_colour{0.5F, 0.5F, 0.6F};   ///< linear RGB
};

/// One collider (or the ground) drawn as a mesh placed by a per-frame model matrix.
struct ColliderDraw {
    std::string name;
    RenderMesh mesh;
    glm::vec3 colour{0.6F, 0.6F, 0.62F};   ///< linear RGB
    glm::vec3 line_colour{0.3F, 0.3F, 0.32F};  ///< grid lines (ground only)
    float grid_spacing = 0.0F;             ///< m; > 0 draws the ground's grid lines
    std::size_t collider = SIZE_MAX;       ///< index in Model::colliders, SIZE_MAX for the ground
    /// A character (a collider with a skin, which may switch clips at any step): `mesh` holds its pose
    /// at t = 0 and each frame brings new vertices
    /// (RenderFrame::collider_vertices, world space, from `first_deforming_vertex`); its model
    /// matrix is the identity.
    bool deforms = false;
    std::uint32_t first_deforming_vertex = 0;
};

/// A perspective camera, Y up.
struct Camera {
    glm::vec3 position{0.0F, 1.0F, 3.0F};  ///< m
    glm::vec3 target{0.0F, 0.5F, 0.0F};    ///< m
    float fov_degrees = 45.0F;             ///< vertical field of view
    float near_plane = 0.01F;              ///< m
    float far_plane = 200.0F;              ///< m
};

/// The key light: a directional light with a shadow map fitted to the scene's bounds.
struct Light {
    glm::vec3 direction{-0.35F, -0.85F, -0.4F};  ///< travel direction (normalised on use)
    glm::vec3 colour{1.0F, 0.96F, 0.9F};          ///< linear RGB
    float ambient = 0.35F;                         ///< strength of the sky/ground fill
    glm::vec3 sky{0.75F, 0.82F, 1.0F};             ///< fill from above
    glm::vec3 ground{0.35F, 0.3F, 0.25F};          ///< fill from below
};

struct RenderScene {
    std::vector<ClothDraw> cloths;
    std::vector<std::uint32_t> cloth_indices;  ///< all cloths' triangles, indices into the cloth buffer
    std::vector<std::uint32_t> cloth_edges;    ///< edge_indices(cloth_indices): the overlay's wireframe
    std::uint32_t cloth_vertices = 0;          ///< size of the shared cloth vertex buffer
    std::vector<ColliderDraw> colliders;       ///< the model's drawable colliders, then the ground
    std::uint32_t deforming_vertices = 0;      ///< the deforming colliders' vertices, all together
    Camera camera{};
    Light light{};
    glm::vec3 background{0.62F, 0.68F, 0.76F};  ///< linear RGB
    /// Box the shadow map covers, m: the cloth at rest and the bounded colliders, grown by half.
    glm::vec3 bounds_min{-1.0F}, bounds_max{1.0F};
};

/// Marks at some cloth vertices, one colour a list (the editor's contacts and pins).
struct OverlayPoints {
    std::vector<std::uint32_t> vertices;          ///< indices into the cloth vertex buffer
    glm::vec3 colour{1.0F, 0.55F, 0.0F};          ///< linear RGB
};

/// The most OverlayPoints lists a frame draws.
inline constexpr std::size_t kMaxOverlayPointLists = 4;

/// Lines and marks a frame draws over the cloth from the cloth buffer itself (what the solver wrote:
/// no copy through the host), depth-tested against the picture so that the far side stays hidden:
/// the editor's wireframe, normals, contacts and pins.
struct OverlayLines {
    bool wireframe = false;       ///< every cloth edge once (RenderScene::cloth_edges)
    float normal_length = 0.0F;   ///< m; > 0 draws each cloth vertex's normal this long
    glm::vec3 wireframe_colour{0.05F, 0.05F, 0.08F};  ///< linear RGB
    glm::vec3 normal_colour{0.1F, 0.45F, 1.0F};       ///< linear RGB
    /// Squares `point_size` pixels wide at the listed vertices, at most kMaxOverlayPointLists lists
    /// (more, or an index past the cloth buffer, is an Error from the renderer).
    std::vector<OverlayPoints> points;
    float point_size = 6.0F;  ///< pixels (1 where the device draws no larger points)
};

/// The state drawn in one frame.
struct RenderFrame {
    /// The cloth vertex buffer's contents (RenderScene::cloth_vertices), for renderers that upload
    /// from the host; empty when the buffer is already filled on the device (zero-copy interop).
    std::span<const RenderVertex> cloth;
    /// Local → world of each RenderScene::colliders entry at the frame's time.
    std::vector<glm::mat4> collider_models;
    /// The deforming colliders' vertices (RenderScene::deforming_vertices, world space) at the
    /// frame's time; empty: the last ones given (the pose at t = 0 until then).
    std::span<const RenderVertex> collider_vertices;
    /// Zero-copy (Renderer::export_cloth): the frame's reads of the cloth buffer wait until the
    /// timeline reaches `wait_value` (0: no wait), and the timeline is set to `signal_value` once
    /// they are done (0: no signal; otherwise larger than any value signalled before).
    std::uint64_t wait_value = 0;
    std::uint64_t signal_value = 0;
    /// The cloth slot drawn from (0 or 1 once exported; 0 otherwise), and the state's frame stamp:
    /// written into the slot's tail with an upload, expected there from the writer otherwise.
    int cloth_slot = 0;
    std::uint64_t stamp = 0;
    /// Overlay lines drawn after the scene (none by default).
    OverlayLines lines;
};

/// Every edge of `triangles` (three indices each) once, as pairs of indices, in a fixed order (each
/// edge where it first appears, its smaller index first).
[[nodiscard]] std::vector<std::uint32_t> edge_indices(std::span<const std::uint32_t> triangles);

/// The scene of `world` seen from `camera`: one draw per cloth (colours from a fixed palette, by
/// cloth index), one per analytic or mesh collider (a plane becomes the ground grid), and a ground
/// grid at y = 0 when the world has no plane.
[[nodiscard]] RenderScene make_render_scene(const World& world, const CameraDesc& camera);

/// Collider poses of `scene` at time `t` (s), from the motions of `model`.
[[nodiscard]] std::vector<glm::mat4> collider_models(const RenderScene& scene, const Model& model, double t);

/// The deforming colliders' vertices of `scene` (characters playing a clip) at time `t` (s), world
/// space, with area-weighted normals, into `out` (resized to scene.deforming_vertices).
void deforming_collider_vertices(const RenderScene& scene, const Model& model, double t, std::vector<RenderVertex>& out);

/// Positions of every cloth of `world` with area-weighted vertex normals (the sum of the incident
/// triangles' cross products, in a fixed order: the CUDA output kernel's rule), into `out`
/// (resized to scene.cloth_vertices).
void cloth_vertices(const World& world, const RenderScene& scene, std::vector<RenderVertex>& out);

/// Meshes of the analytic shapes, in their local frame (collider_contact.h's conventions).
[[nodiscard]] RenderMesh sphere_mesh(float radius, int slices = 48, int stacks = 24);
[[nodiscard]] RenderMesh capsule_mesh(float radius, float half_height, int slices = 48, int stacks = 24);
[[nodiscard]] RenderMesh box_mesh(glm::vec3 half_extents);
/// A square of side 2·half_size in the local XZ plane, normal +Y.
[[nodiscard]] RenderMesh plane_mesh(float half_size);

}  // namespace weft::render
