// The EGL + OpenGL 4.5 capture renderer: draws a RenderScene offscreen with the shaders of
// render/shaders/ and reads the picture back. No window and no display server: the context comes
// from an EGL device (or Mesa's surfaceless platform, see egl_context.h), every target is a
// framebuffer object.
//
// Per frame: the cloth vertices are uploaded into the cloth buffer (or, on the zero-copy path, one
// of two exported slot buffers that the CUDA backend wrote holds them: export_cloth), a depth-only
// pass from the key light fills the shadow map, the scene is drawn into multisampled
// renderbuffers, and the resolved image is read into a pixel buffer with a fence after it: submit()
// returns without waiting, collect() waits for the fence and copies the picture out. The Vulkan
// renderer does the same with the same uniforms (frame_uniforms.h), so the two give the same
// picture.
#include "egl/egl_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "egl/egl_context.h"
#include "egl/gl_objects.h"
#include "frame_uniforms.h"
#include "shaders.h"
#include "weft/error.h"

namespace weft::render::detail {
namespace {

/// The OpenGL texture unit of the shadow map (`WEFT_SAMPLER(2)` in surface.frag).
constexpr GLuint kShadowMapUnit = 2;
/// Uniform block bindings (`WEFT_BLOCK(0)` and `WEFT_BLOCK(1)` in common.glsl).
constexpr GLuint kFrameBinding = 0;
constexpr GLuint kDrawBinding = 1;

/// What the debug callback counts; `messages` is mutable because GL hands the callback a pointer
/// to const.
struct DebugLog {
    mutable int messages = 0;
};

void APIENTRY on_debug_message(GLenum /*source*/, GLenum type, GLuint id, GLenum severity, GLsizei /*length*/,
                               const GLchar* message, const void* user) {
    // Notifications and low-severity remarks (shader statistics, buffer placement) are not
    // problems; errors are, whatever severity the driver gives them. Performance remarks are not
    // either, at any severity: NVIDIA's driver reports recompiling a shader for the GL state at
    // medium severity on every first draw.
    if (type == GL_DEBUG_TYPE_PERFORMANCE || type == GL_DEBUG_TYPE_OTHER || type == GL_DEBUG_TYPE_MARKER ||
        type == GL_DEBUG_TYPE_PUSH_GROUP || type == GL_DEBUG_TYPE_POP_GROUP)
        return;
    if (type != GL_DEBUG_TYPE_ERROR && severity != GL_DEBUG_SEVERITY_HIGH && severity != GL_DEBUG_SEVERITY_MEDIUM)
        return;
    ++static_cast<const DebugLog*>(user)->messages;
    std::fprintf(stderr, "opengl debug: [%u] %s\n", id, message);
}

/// The shader's sRGB encoding (to_srgb in surface.frag), for the clear colour: the target is plain
/// RGBA8 holding sRGB-encoded values.
float to_srgb(float c) {
    c = std::clamp(c, 0.0F, 1.0F);
    return c < 0.0031308F ? c * 12.92F : 1.055F * std::pow(c, 1.0F / 2.4F) - 0.055F;
}

GLint get_integer(GLenum what) {
    GLint value = 0;
    glGetIntegerv(what, &value);
    return value;
}

void check_framebuffer(GLuint framebuffer, const char* what) {
    const GLenum status = glCheckNamedFramebufferStatus(framebuffer, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        char hex[16];
        std::snprintf(hex, sizeof hex, "0x%04X", status);
        throw Error(std::string("egl renderer: the ") + what + " framebuffer is incomplete (status " + hex + ")");
    }
}

/// Index checks before upload: an index past its vertex buffer reads outside it on the device.
/// `per_primitive`: 3 for triangles, 2 for lines.
void check_indices(std::span<const std::uint32_t> indices, std::size_t vertices, const std::string& what,
                   std::size_t per_primitive = 3) {
    for (const std::uint32_t i : indices)
        if (i >= vertices)
            throw Error("egl renderer: " + what + " has vertex index " + std::to_string(i) + " but " +
                        std::to_string(vertices) + " vertices");
    if (indices.size() % per_primitive != 0)
        throw Error("egl renderer: " + what + " has " + std::to_string(indices.size()) + " indices, not a multiple of " +
                    std::to_string(per_primitive));
}

/// A vertex buffer (RenderVertex layout), its uint32 index buffer and the vertex array that binds
/// them: location 0 position, location 1 normal, 24-byte stride.
struct Mesh {
    gl::Buffer vertices;
    gl::Buffer indices;
    gl::VertexArray array;
    GLsizei index_count = 0;
};

/// A fence on the GL command stream, deleted when dropped.
class Fence {
public:
    Fence() = default;
    ~Fence() { reset(); }
    Fence(const Fence&) = delete;
    Fence& operator=(const Fence&) = delete;
    /// A new fence after every command issued so far (the old one dropped), flushed so that it signals.
    void insert() {
        reset();
        sync_ = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
        glFlush();
    }
    /// Blocks until the commands before the fence are done. Throws weft::Error when GL says the wait failed.
    void wait() const {
        if (sync_ == nullptr) return;
        for (;;) {
            const GLenum r = glClientWaitSync(sync_, GL_SYNC_FLUSH_COMMANDS_BIT, 100'000'000);  // 0.1 s a try
            if (r == GL_ALREADY_SIGNALED || r == GL_CONDITION_SATISFIED) return;
            if (r == GL_WAIT_FAILED) throw Error("egl renderer: glClientWaitSync failed on the frame's fence");
        }
    }
    void reset() {
        if (sync_ != nullptr) glDeleteSync(std::exchange(sync_, nullptr));
    }

private:
    GLsync sync_ = nullptr;
};

/// A vertex array reading RenderVertex from binding 0: location 0 the position, 1 the normal.
gl::VertexArray render_vertex_array() {
    gl::VertexArray array = gl::create_vertex_array();
    const GLuint a = array.get();
    glEnableVertexArrayAttrib(a, 0);
    glVertexArrayAttribFormat(a, 0, 3, GL_FLOAT, GL_FALSE, offsetof(RenderVertex, position));
    glVertexArrayAttribBinding(a, 0, 0);
    glEnableVertexArrayAttrib(a, 1);
    glVertexArrayAttribFormat(a, 1, 3, GL_FLOAT, GL_FALSE, offsetof(RenderVertex, normal));
    glVertexArrayAttribBinding(a, 1, 0);
    return array;
}

/// `vertex_flags`: GL_DYNAMIC_STORAGE_BIT for the cloth buffer rewritten every frame, 0 for the
/// static colliders.
Mesh make_mesh(std::span<const RenderVertex> vertices, std::span<const std::uint32_t> indices, GLbitfield vertex_flags) {
    Mesh mesh;
    if (vertices.empty() || indices.empty()) return mesh;  // nothing to draw (zero-size storage is an error)
    mesh.vertices = gl::create_buffer();
    glNamedBufferStorage(mesh.vertices.get(), static_cast<GLsizeiptr>(vertices.size_bytes()), vertices.data(),
                         vertex_flags);
    mesh.indices = gl::create_buffer();
    glNamedBufferStorage(mesh.indices.get(), static_cast<GLsizeiptr>(indices.size_bytes()), indices.data(), 0);
    mesh.index_count = static_cast<GLsizei>(indices.size());

    mesh.array = render_vertex_array();
    glVertexArrayVertexBuffer(mesh.array.get(), 0, mesh.vertices.get(), 0, sizeof(RenderVertex));
    glVertexArrayElementBuffer(mesh.array.get(), mesh.indices.get());
    return mesh;
}

/// The GL objects of a loaded scene.
struct SceneObjects {
    RenderScene scene;
    Mesh cloth;                  ///< the host-upload cloth buffer (all cloths) and all cloths' indices
    /// The exported cloth slots (export_cloth): vertices, then kSlotStampBytes of frame stamps.
    std::vector<gl::Buffer> slots;
    std::vector<Mesh> colliders;  ///< one per RenderScene::colliders entry
    /// The overlay lines (OverlayLines) over the cloth buffer: the wireframe's edges (RenderScene::
    /// cloth_edges as an element buffer), and the normals' array (one vertex an instance).
    gl::Buffer edges;
    gl::VertexArray wireframe, normals;
    /// The overlay's points (OverlayLines::points): their array, and their indices one list after
    /// another (grown as needed).
    gl::VertexArray points;
    gl::Buffer point_indices;
    std::size_t point_capacity = 0;  ///< indices point_indices holds
    gl::Buffer draw_uniforms;     ///< one DrawUniforms per draw, `draw_stride` apart
    GLsizeiptr draw_stride = 0;
    std::vector<std::byte> draw_staging;  ///< the next frame's DrawUniforms before upload
};

class EglRenderer final : public Renderer {
public:
    explicit EglRenderer(const RendererOptions& options);
    ~EglRenderer() override;

    [[nodiscard]] std::string_view name() const override { return "egl"; }
    [[nodiscard]] std::string device_description() const override { return description_; }
    void load(const RenderScene& scene) override;
    /// Queues the frame's passes and the read of its picture into a pixel buffer, then a fence:
    /// nothing waits here, so the caller's work until collect() overlaps the drawing.
    void submit(const RenderFrame& frame) override;
    /// Waits for the fence and copies the picture (and, from a shared slot, its stamps) out.
    [[nodiscard]] Image collect() override;
    // GL slots are ordered by the writer's map and unmap, not by timeline values: nothing to keep.
    void skip_frame(const RenderFrame& /*frame*/) override {}
    [[nodiscard]] TransferStats transfer() const override { return transfer_; }
    [[nodiscard]] int validation_messages() const override { return debug_log_.messages; }
    /// Two buffer objects of this renderer's context, shared as SlotApi::opengl_buffer (the CUDA
    /// backend registers them). The context must stay current on the thread that shares them and
    /// runs the frames; a later load() drops them.
    [[nodiscard]] std::optional<ClothInterop> export_cloth(std::string& why) override;
    [[nodiscard]] std::vector<RenderVertex> read_cloth(int slot) override;

private:
    /// Draws every cloth and collider with the bound program; `shadow_pass` leaves out the draws
    /// that only receive shadows (the ground: material.x > 0).
    void draw_meshes(const std::vector<DrawUniforms>& draws, bool shadow_pass) const;
    /// The frame's overlay lines from `cloth_buffer`, after the scene's `scene_draws` draws (their
    /// uniforms follow), tested against the scene's depth and not writing it.
    void draw_lines(const OverlayLines& lines, GLuint cloth_buffer, std::size_t scene_draws) const;
    /// The frame's overlay points into SceneObjects::point_indices (grown as needed).
    void upload_points(const OverlayLines& lines);

    RendererOptions options_;
    DebugLog debug_log_;
    EglContext context_;  // before every GL object: destroyed after them
    std::string description_;
    int samples_ = 1;  ///< MSAA samples in use (options.samples within GL_MAX_SAMPLES)

    gl::Program surface_program_;
    gl::Program shadow_program_;
    gl::Program line_program_;
    gl::Program point_program_;  ///< the overlay's points (point.vert, line.frag)
    gl::Buffer frame_uniforms_;
    gl::Texture shadow_map_;
    gl::Framebuffer shadow_target_;
    gl::Renderbuffer colour_;  ///< multisampled (single-sampled with 1 sample)
    gl::Renderbuffer depth_;
    gl::Framebuffer scene_target_;
    gl::Renderbuffer resolved_;
    gl::Framebuffer resolve_target_;
    std::optional<SceneObjects> loaded_;

    TransferStats transfer_{"host upload", 0};
    gl::Buffer readback_;               ///< the submitted frame's picture, rows bottom to top as GL gives them
    gl::Buffer stamp_readback_;         ///< the stamps of the slot the submitted frame drew from
    Fence drawn_;                       ///< after the submitted frame's last command
    bool submitted_ = false;            ///< a frame was submitted and not collected
    bool stamps_from_slot_ = false;     ///< the submitted frame drew from a slot: its stamps are in stamp_readback_
    std::vector<std::uint8_t> pixels_;  ///< read-back rows
};

EglRenderer::EglRenderer(const RendererOptions& options) : options_(options), context_(options.validation) {
    const auto gl_string = [](GLenum what) {
        const auto* s = reinterpret_cast<const char*>(glGetString(what));
        return std::string(s != nullptr ? s : "?");
    };
    description_ = gl_string(GL_RENDERER) + ", OpenGL " + gl_string(GL_VERSION) + " (EGL " +
                   std::string(context_.platform()) + ")";

    if (options_.validation) {
        if ((get_integer(GL_CONTEXT_FLAGS) & GL_CONTEXT_FLAG_DEBUG_BIT) == 0)
            throw Error("egl renderer: validation asked for, but the driver gave no debug context (" + description_ + ")");
        glEnable(GL_DEBUG_OUTPUT);
        // Messages arrive inside the call at fault, on this thread: the count is exact after each call.
        glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
        glDebugMessageCallback(on_debug_message, &debug_log_);
        glDebugMessageControl(GL_DONT_CARE, GL_DONT_CARE, GL_DONT_CARE, 0, nullptr, GL_TRUE);
    }

    const GLint max_renderbuffer = get_integer(GL_MAX_RENDERBUFFER_SIZE);
    if (options_.width > max_renderbuffer || options_.height > max_renderbuffer)
        throw Error("egl renderer: " + std::to_string(options_.width) + "×" + std::to_string(options_.height) +
                    " pixels exceed the device's GL_MAX_RENDERBUFFER_SIZE of " + std::to_string(max_renderbuffer));
    const GLint max_texture = get_integer(GL_MAX_TEXTURE_SIZE);
    if (options_.shadow_map_size > max_texture)
        throw Error("egl renderer: a shadow map of " + std::to_string(options_.shadow_map_size) +
                    " texels exceeds the device's GL_MAX_TEXTURE_SIZE of " + std::to_string(max_texture));

    // The matrices of frame_uniforms.h map depth to 0..1 (Vulkan's convention); set before the
    // programs are linked, so that no driver has to rebuild them for it.
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);

    surface_program_ =
        gl::link_program("surface", surface_vertex_shader().glsl, surface_fragment_shader().glsl);
    line_program_ = gl::link_program("line", line_vertex_shader().glsl, line_fragment_shader().glsl);
    point_program_ = gl::link_program("point", point_vertex_shader().glsl, line_fragment_shader().glsl);
    shadow_program_ = gl::link_program("shadow", shadow_vertex_shader().glsl, shadow_fragment_shader().glsl);

    frame_uniforms_ = gl::create_buffer();
    glNamedBufferStorage(frame_uniforms_.get(), sizeof(FrameUniforms), nullptr, GL_DYNAMIC_STORAGE_BIT);

    // Shadow map: depth from the key light, read with hardware comparison (sampler2DShadow) and
    // linear filtering, so each PCF tap is already a 2×2 blend.
    const GLsizei s = options_.shadow_map_size;
    shadow_map_ = gl::create_texture(GL_TEXTURE_2D);
    glTextureStorage2D(shadow_map_.get(), 1, GL_DEPTH_COMPONENT32F, s, s);
    glTextureParameteri(shadow_map_.get(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(shadow_map_.get(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(shadow_map_.get(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(shadow_map_.get(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTextureParameteri(shadow_map_.get(), GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTextureParameteri(shadow_map_.get(), GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    shadow_target_ = gl::create_framebuffer();
    glNamedFramebufferTexture(shadow_target_.get(), GL_DEPTH_ATTACHMENT, shadow_map_.get(), 0);
    glNamedFramebufferDrawBuffer(shadow_target_.get(), GL_NONE);
    glNamedFramebufferReadBuffer(shadow_target_.get(), GL_NONE);
    check_framebuffer(shadow_target_.get(), "shadow map");

    // Scene target: multisampled colour and depth. Storage with 0 samples is single-sampled (1 may
    // give a multisampled buffer of the driver's choosing); the driver may round a count up, so the
    // count actually allocated is what is kept.
    const GLint max_samples = std::max(get_integer(GL_MAX_SAMPLES), 1);
    const GLsizei requested = std::min(options_.samples, max_samples);
    const GLsizei w = options_.width;
    const GLsizei h = options_.height;
    colour_ = gl::create_renderbuffer();
    glNamedRenderbufferStorageMultisample(colour_.get(), requested > 1 ? requested : 0, GL_RGBA8, w, h);
    depth_ = gl::create_renderbuffer();
    glNamedRenderbufferStorageMultisample(depth_.get(), requested > 1 ? requested : 0, GL_DEPTH_COMPONENT32F, w, h);
    GLint allocated = 0;
    glGetNamedRenderbufferParameteriv(colour_.get(), GL_RENDERBUFFER_SAMPLES, &allocated);
    samples_ = std::max(allocated, 1);
    scene_target_ = gl::create_framebuffer();
    glNamedFramebufferRenderbuffer(scene_target_.get(), GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, colour_.get());
    glNamedFramebufferRenderbuffer(scene_target_.get(), GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_.get());
    glNamedFramebufferDrawBuffer(scene_target_.get(), GL_COLOR_ATTACHMENT0);
    check_framebuffer(scene_target_.get(), "scene");

    // Resolve target: single-sampled RGBA8 to blit into and read back from.
    resolved_ = gl::create_renderbuffer();
    glNamedRenderbufferStorage(resolved_.get(), GL_RGBA8, w, h);
    resolve_target_ = gl::create_framebuffer();
    glNamedFramebufferRenderbuffer(resolve_target_.get(), GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolved_.get());
    glNamedFramebufferDrawBuffer(resolve_target_.get(), GL_COLOR_ATTACHMENT0);
    glNamedFramebufferReadBuffer(resolve_target_.get(), GL_COLOR_ATTACHMENT0);
    check_framebuffer(resolve_target_.get(), "resolve");

    // The picture's pixel buffer: written by the GPU, read by the host (GL_CLIENT_STORAGE_BIT asks
    // for host memory, where the read costs no second copy).
    readback_ = gl::create_buffer();
    glNamedBufferStorage(readback_.get(), static_cast<GLsizeiptr>(w) * h * 4, nullptr,
                         GL_MAP_READ_BIT | GL_CLIENT_STORAGE_BIT);
    stamp_readback_ = gl::create_buffer();
    glNamedBufferStorage(stamp_readback_.get(), static_cast<GLsizeiptr>(kSlotStampBytes), nullptr,
                         GL_MAP_READ_BIT | GL_CLIENT_STORAGE_BIT);

    // Fixed state: depth test, no blending, no culling (cloth is two-sided: the fragment shader
    // picks the colour by gl_FrontFacing, front = counter-clockwise, GL's default).
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glFrontFace(GL_CCW);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    gl::check_errors("setting up (" + description_ + ")");
}

EglRenderer::~EglRenderer() {
    try {
        context_.make_current();
        if (options_.validation) glDebugMessageCallback(nullptr, nullptr);
    } catch (const Error&) {
        // The context is current on another thread: with no context current here, the deletes of
        // the members below touch nothing (destroying the context frees its objects instead).
        context_.release_current();
    }
}

void EglRenderer::load(const RenderScene& scene) {
    context_.make_current();
    if (submitted_) (void)collect();  // the frame in flight draws from the objects replaced here
    for (const ClothDraw& c : scene.cloths)
        if (std::size_t{c.first_index} + c.index_count > scene.cloth_indices.size() ||
            std::size_t{c.first_vertex} + c.vertex_count > scene.cloth_vertices)
            throw Error("egl renderer: cloth '" + c.name + "' reaches past the scene's cloth indices or vertices");
    check_indices(scene.cloth_indices, scene.cloth_vertices, "the cloth index list");
    for (const ColliderDraw& c : scene.colliders)
        check_indices(c.mesh.indices, c.mesh.vertices.size(), "collider '" + c.name + "'");

    SceneObjects o;
    o.scene = scene;
    // Zeros until the first frame (or the device) fills it: drawing an unfilled buffer is defined.
    const std::vector<RenderVertex> zeros(scene.cloth_vertices, RenderVertex{});
    o.cloth = make_mesh(zeros, scene.cloth_indices, GL_DYNAMIC_STORAGE_BIT);
    if (!scene.cloth_edges.empty() && scene.cloth_vertices > 0) {
        check_indices(scene.cloth_edges, scene.cloth_vertices, "the cloth edge list", 2);
        o.edges = gl::create_buffer();
        glNamedBufferStorage(o.edges.get(), static_cast<GLsizeiptr>(scene.cloth_edges.size() * sizeof(std::uint32_t)),
                             scene.cloth_edges.data(), 0);
    }
    o.wireframe = render_vertex_array();
    o.normals = render_vertex_array();
    if (o.edges.get() != 0) glVertexArrayElementBuffer(o.wireframe.get(), o.edges.get());
    glVertexArrayBindingDivisor(o.normals.get(), 0, 1);  // one cloth vertex an instance
    o.points = render_vertex_array();
    o.colliders.reserve(scene.colliders.size());
    for (const ColliderDraw& c : scene.colliders)  // a deforming collider's vertices are rewritten each frame
        o.colliders.push_back(make_mesh(c.mesh.vertices, c.mesh.indices, c.deforms ? GL_DYNAMIC_STORAGE_BIT : 0));

    // One buffer holds every draw's uniforms; each draw binds its range, which must start on the
    // device's offset alignment.
    const GLsizeiptr alignment = std::max(get_integer(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT), 1);
    o.draw_stride = (static_cast<GLsizeiptr>(sizeof(DrawUniforms)) + alignment - 1) / alignment * alignment;
    const std::size_t draws = scene.cloths.size() + scene.colliders.size() + kOverlayDraws;
    o.draw_staging.assign(draws * static_cast<std::size_t>(o.draw_stride), std::byte{0});
    o.draw_uniforms = gl::create_buffer();
    glNamedBufferStorage(o.draw_uniforms.get(), static_cast<GLsizeiptr>(o.draw_staging.size()), nullptr,
                         GL_DYNAMIC_STORAGE_BIT);
    gl::check_errors("load");
    // The load's uploads finish before the first frame is drawn: on NVIDIA's driver without a debug
    // context, the first frame of a process drew without its cloth (docs/rendering.md, "Known
    // problems"). Once per scene load, so it costs no frame anything.
    glFinish();
    loaded_ = std::move(o);
}

void EglRenderer::draw_meshes(const std::vector<DrawUniforms>& draws, bool shadow_pass) const {
    const SceneObjects& o = *loaded_;
    const auto bind_draw = [&](std::size_t k) {
        glBindBufferRange(GL_UNIFORM_BUFFER, kDrawBinding, o.draw_uniforms.get(),
                          static_cast<GLintptr>(k) * o.draw_stride, sizeof(DrawUniforms));
    };
    std::size_t k = 0;
    if (o.cloth.index_count > 0) glBindVertexArray(o.cloth.array.get());
    for (const ClothDraw& c : o.scene.cloths) {
        if (c.index_count > 0 && o.cloth.index_count > 0) {
            bind_draw(k);
            glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(c.index_count), GL_UNSIGNED_INT,
                           reinterpret_cast<const void*>(std::uintptr_t{c.first_index} * sizeof(std::uint32_t)));
        }
        ++k;
    }
    for (const Mesh& m : o.colliders) {
        // The ground receives shadows but casts none: leaving it out of the shadow map keeps its own
        // depth from shadowing it (acne) and the map's depth range for what does cast.
        const bool receiver_only = draws[k].material.x > 0.0F;
        if (m.index_count > 0 && !(shadow_pass && receiver_only)) {
            bind_draw(k);
            glBindVertexArray(m.array.get());
            glDrawElements(GL_TRIANGLES, m.index_count, GL_UNSIGNED_INT, nullptr);
        }
        ++k;
    }
    glBindVertexArray(0);
}

void EglRenderer::upload_points(const OverlayLines& lines) {
    SceneObjects& o = *loaded_;
    std::vector<std::uint32_t> all;
    for (const OverlayPoints& list : lines.points) all.insert(all.end(), list.vertices.begin(), list.vertices.end());
    if (all.empty()) return;
    if (all.size() > o.point_capacity) {
        o.point_capacity = std::max<std::size_t>(all.size(), 1024);
        o.point_indices = gl::create_buffer();
        glNamedBufferStorage(o.point_indices.get(), static_cast<GLsizeiptr>(o.point_capacity * sizeof(std::uint32_t)),
                             nullptr, GL_DYNAMIC_STORAGE_BIT);
    }
    glNamedBufferSubData(o.point_indices.get(), 0, static_cast<GLsizeiptr>(all.size() * sizeof(std::uint32_t)), all.data());
}

void EglRenderer::draw_lines(const OverlayLines& lines, GLuint cloth_buffer, std::size_t scene_draws) const {
    const SceneObjects& o = *loaded_;
    const bool wireframe = lines.wireframe && o.edges.get() != 0;
    const bool normals = lines.normal_length > 0.0F && o.scene.cloth_vertices > 0;
    bool points = false;
    for (const OverlayPoints& list : lines.points) points = points || !list.vertices.empty();
    if (!wireframe && !normals && !points) return;
    glUseProgram(line_program_.get());
    glDepthMask(GL_FALSE);  // lines do not hide lines
    glDepthFunc(GL_LEQUAL);
    const auto bind_draw = [&](std::size_t k) {
        glBindBufferRange(GL_UNIFORM_BUFFER, kDrawBinding, o.draw_uniforms.get(),
                          static_cast<GLintptr>(k) * o.draw_stride, sizeof(DrawUniforms));
    };
    if (wireframe) {
        bind_draw(scene_draws);
        glVertexArrayVertexBuffer(o.wireframe.get(), 0, cloth_buffer, 0, sizeof(RenderVertex));
        glBindVertexArray(o.wireframe.get());
        glDrawElements(GL_LINES, static_cast<GLsizei>(o.scene.cloth_edges.size()), GL_UNSIGNED_INT, nullptr);
    }
    if (normals) {
        bind_draw(scene_draws + 1);
        glVertexArrayVertexBuffer(o.normals.get(), 0, cloth_buffer, 0, sizeof(RenderVertex));
        glBindVertexArray(o.normals.get());
        glDrawArraysInstanced(GL_LINES, 0, 2, static_cast<GLsizei>(o.scene.cloth_vertices));
    }
    if (points) {
        glUseProgram(point_program_.get());
        glEnable(GL_PROGRAM_POINT_SIZE);  // the size from point.vert
        glVertexArrayVertexBuffer(o.points.get(), 0, cloth_buffer, 0, sizeof(RenderVertex));
        glVertexArrayElementBuffer(o.points.get(), o.point_indices.get());
        glBindVertexArray(o.points.get());
        std::size_t first = 0;
        for (std::size_t p = 0; p < lines.points.size(); ++p) {
            const std::size_t count = lines.points[p].vertices.size();
            if (count == 0) continue;
            bind_draw(scene_draws + 2 + p);
            glDrawElements(GL_POINTS, static_cast<GLsizei>(count), GL_UNSIGNED_INT,
                           reinterpret_cast<const void*>(first * sizeof(std::uint32_t)));
            first += count;
        }
        glDisable(GL_PROGRAM_POINT_SIZE);
    }
    glBindVertexArray(0);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
}

std::optional<ClothInterop> EglRenderer::export_cloth(std::string& why) {
    if (!loaded_) throw Error("egl renderer: export_cloth() before load()");
    SceneObjects& o = *loaded_;
    if (o.scene.cloth_vertices == 0) {
        why = "the scene has no cloth";
        return std::nullopt;
    }
    context_.make_current();
    if (submitted_) (void)collect();  // a frame in flight may draw from the slots replaced here
    const std::uint64_t bytes = o.scene.cloth_vertices * sizeof(RenderVertex) + kSlotStampBytes;
    const std::vector<std::uint8_t> zeros(bytes, 0);
    ClothInterop link;
    link.make_current = [this] { context_.make_current(); };
    o.slots.clear();
    for (int k = 0; k < 2; ++k) {
        gl::Buffer slot = gl::create_buffer();
        // Dynamic: a host-upload frame (the backend would not share) is uploaded into its slot, as
        // on the Vulkan path, so that read_cloth(slot) is what frames of that slot drew.
        glNamedBufferStorage(slot.get(), static_cast<GLsizeiptr>(bytes), zeros.data(), GL_DYNAMIC_STORAGE_BIT);
        SharedSlotHandle h;
        h.api = SlotApi::opengl_buffer;
        h.gl_buffer = {slot.get(), bytes};
        link.slots.push_back(h);
        link.timeline_values.push_back(0);
        o.slots.push_back(std::move(slot));
    }
    gl::check_errors("export_cloth");
    // The buffers exist on the device before another API looks them up (glFlush would order the
    // commands; glFinish also completes the zero fill, once per export).
    glFinish();
    return link;
}

std::vector<RenderVertex> EglRenderer::read_cloth(int slot) {
    if (!loaded_) throw Error("egl renderer: read_cloth() before load()");
    const SceneObjects& o = *loaded_;
    const int slots = o.slots.empty() ? 1 : static_cast<int>(o.slots.size());
    if (slot < 0 || slot >= slots)
        throw Error("egl renderer: cloth slot " + std::to_string(slot) + " (it has " + std::to_string(slots) + ")");
    context_.make_current();
    const GLuint buffer = o.slots.empty() ? o.cloth.vertices.get() : o.slots[static_cast<std::size_t>(slot)].get();
    std::vector<RenderVertex> out(o.scene.cloth_vertices);
    if (!out.empty())
        glGetNamedBufferSubData(buffer, 0, static_cast<GLsizeiptr>(out.size() * sizeof(RenderVertex)), out.data());
    return out;
}

Image EglRenderer::collect() {
    if (!submitted_) throw Error("egl renderer: collect() without a submitted frame");
    context_.make_current();
    submitted_ = false;
    drawn_.wait();
    drawn_.reset();
    const GLint w = options_.width;
    const GLint h = options_.height;
    const std::size_t row = static_cast<std::size_t>(w) * 4;
    pixels_.resize(row * static_cast<std::size_t>(h));
    glGetNamedBufferSubData(readback_.get(), 0, static_cast<GLsizeiptr>(pixels_.size()), pixels_.data());
    if (stamps_from_slot_) {
        std::uint64_t stamps[2] = {0, 0};
        glGetNamedBufferSubData(stamp_readback_.get(), 0, sizeof stamps, stamps);
        transfer_.stamp_first = stamps[0];
        transfer_.stamp_last = stamps[1];
    }
    gl::check_errors("collect");

    // GL's rows run bottom to top, the image's top to bottom.
    Image image(w, h);
    for (GLint y = 0; y < h; ++y)
        std::memcpy(image.rgba.data() + static_cast<std::size_t>(y) * row,
                    pixels_.data() + static_cast<std::size_t>(h - 1 - y) * row, row);
    return image;
}

void EglRenderer::submit(const RenderFrame& frame) {
    if (!loaded_) throw Error("egl renderer: draw() before load()");
    check_overlay_points(frame.lines, loaded_->scene.cloth_vertices, "egl renderer");
    context_.make_current();
    if (submitted_) (void)collect();  // one frame in flight: the one before is dropped
    SceneObjects& o = *loaded_;
    const bool exported = !o.slots.empty();
    const bool from_slot = frame.cloth.empty() && exported;
    if (!exported && (frame.cloth_slot != 0 || frame.wait_value != 0 || frame.signal_value != 0))
        throw Error("egl renderer: a frame for shared cloth slots, but nothing is exported");
    if (exported && (frame.cloth_slot < 0 || static_cast<std::size_t>(frame.cloth_slot) >= o.slots.size()))
        throw Error("egl renderer: cloth slot " + std::to_string(frame.cloth_slot) + " of " +
                    std::to_string(o.slots.size()));

    // Cloth vertices from the host (into the frame's slot once slots are exported), or from the slot
    // the backend wrote (no host copy: the backend's unmap ordered its writes before these draws).
    // An uploaded frame's stamps are its own; a shared slot's are read back with the picture.
    const GLuint cloth_buffer =
        exported ? o.slots[static_cast<std::size_t>(frame.cloth_slot)].get() : o.cloth.vertices.get();
    if (o.cloth.index_count > 0) glVertexArrayVertexBuffer(o.cloth.array.get(), 0, cloth_buffer, 0, sizeof(RenderVertex));
    transfer_ = from_slot ? TransferStats{"interop", 0, 0, 0} : TransferStats{"host upload", 0, frame.stamp, frame.stamp};
    stamps_from_slot_ = from_slot;
    if (!frame.cloth.empty()) {
        if (frame.cloth.size() != o.scene.cloth_vertices)
            throw Error("egl renderer: the frame has " + std::to_string(frame.cloth.size()) +
                        " cloth vertices, the scene " + std::to_string(o.scene.cloth_vertices));
        glNamedBufferSubData(cloth_buffer, 0, static_cast<GLsizeiptr>(frame.cloth.size_bytes()),
                             frame.cloth.data());
        transfer_.bytes_uploaded = frame.cloth.size_bytes();
    }
    if (!frame.collider_vertices.empty()) {  // characters playing a clip: their new pose
        if (frame.collider_vertices.size() != o.scene.deforming_vertices)
            throw Error("egl renderer: the frame has " + std::to_string(frame.collider_vertices.size()) +
                        " deforming collider vertices, the scene " + std::to_string(o.scene.deforming_vertices));
        for (std::size_t k = 0; k < o.scene.colliders.size(); ++k) {
            const ColliderDraw& c = o.scene.colliders[k];
            if (!c.deforms || o.colliders[k].index_count == 0) continue;
            glNamedBufferSubData(o.colliders[k].vertices.get(), 0,
                                 static_cast<GLsizeiptr>(c.mesh.vertices.size() * sizeof(RenderVertex)),
                                 frame.collider_vertices.data() + c.first_deforming_vertex);
        }
    }

    const FrameUniforms frame_data = frame_uniforms(o.scene, options_.width, options_.height, options_.shadow_map_size);
    glNamedBufferSubData(frame_uniforms_.get(), 0, sizeof frame_data, &frame_data);
    const std::vector<DrawUniforms> draws = draw_uniforms(o.scene, frame);
    for (std::size_t k = 0; k < draws.size(); ++k)
        std::memcpy(o.draw_staging.data() + k * static_cast<std::size_t>(o.draw_stride), &draws[k], sizeof(DrawUniforms));
    const std::array<DrawUniforms, kOverlayDraws> lines = overlay_uniforms(frame.lines);
    upload_points(frame.lines);
    for (std::size_t k = 0; k < lines.size(); ++k)
        std::memcpy(o.draw_staging.data() + (draws.size() + k) * static_cast<std::size_t>(o.draw_stride), &lines[k],
                    sizeof(DrawUniforms));
    glNamedBufferSubData(o.draw_uniforms.get(), 0, static_cast<GLsizeiptr>(o.draw_staging.size()), o.draw_staging.data());
    glBindBufferBase(GL_UNIFORM_BUFFER, kFrameBinding, frame_uniforms_.get());

    // Shadow pass. The map is unbound from its unit while it is written (no feedback loop).
    const GLfloat far_depth = 1.0F;
    // The program whose shadow sampler reads the unit is never current while the unit is empty
    // (NVIDIA checks the state at glUseProgram and reports undefined behaviour otherwise).
    glUseProgram(shadow_program_.get());
    glBindTextureUnit(kShadowMapUnit, 0);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, shadow_target_.get());
    glViewport(0, 0, options_.shadow_map_size, options_.shadow_map_size);
    glClearNamedFramebufferfv(shadow_target_.get(), GL_DEPTH, 0, &far_depth);
    draw_meshes(draws, true);

    // Scene pass.
    const GLfloat background[4] = {to_srgb(o.scene.background.r), to_srgb(o.scene.background.g),
                                   to_srgb(o.scene.background.b), 1.0F};
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, scene_target_.get());
    glViewport(0, 0, options_.width, options_.height);
    glClearNamedFramebufferfv(scene_target_.get(), GL_COLOR, 0, background);
    glClearNamedFramebufferfv(scene_target_.get(), GL_DEPTH, 0, &far_depth);
    glBindTextureUnit(kShadowMapUnit, shadow_map_.get());
    glUseProgram(surface_program_.get());
    draw_meshes(draws, false);
    draw_lines(frame.lines, cloth_buffer, draws.size());

    // Resolve, and read into the pixel buffer: queued, collect() waits for it.
    const GLint w = options_.width;
    const GLint h = options_.height;
    glBlitNamedFramebuffer(scene_target_.get(), resolve_target_.get(), 0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT,
                           GL_NEAREST);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_target_.get());
    glBindBuffer(GL_PIXEL_PACK_BUFFER, readback_.get());
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    if (from_slot)  // the stamps of what the draws read, after them in GL's order
        glCopyNamedBufferSubData(cloth_buffer, stamp_readback_.get(),
                                 static_cast<GLintptr>(o.scene.cloth_vertices * sizeof(RenderVertex)), 0,
                                 static_cast<GLsizeiptr>(kSlotStampBytes));
    gl::check_errors("draw");
    drawn_.insert();
    submitted_ = true;
}

}  // namespace

std::unique_ptr<Renderer> create_egl_renderer(const RendererOptions& options) {
    return std::make_unique<EglRenderer>(options);
}

}  // namespace weft::render::detail
