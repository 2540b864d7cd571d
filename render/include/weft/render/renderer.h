#pragma once
/// @file
/// The renderer interface: Vulkan (render/src/vulkan/) and EGL + OpenGL 4.5 (render/src/egl/) draw a
/// RenderScene offscreen and read the picture back. Both render the same image up to rasterisation
/// rounding (tests/render/ holds them to it).
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <optional>

#include "weft/backend/interop.h"
#include "weft/render/image.h"
#include "weft/render/render_scene.h"

namespace weft::render {

struct RendererOptions {
    int width = 1280;           ///< pixels
    int height = 720;           ///< pixels
    int samples = 4;            ///< MSAA samples per pixel (1, 2, 4 or 8; lowered to what the device has)
    int shadow_map_size = 2048;  ///< texels per side
    /// Vulkan: enable VK_LAYER_KHRONOS_validation and count its messages (`validation_messages`);
    /// an error when the layer is not installed. EGL: a debug context with KHR_debug counted the same way.
    bool validation = false;
};

/// How the cloth vertices reached the renderer in the last frame.
struct TransferStats {
    std::string path;                 ///< "host upload" or "interop"
    std::uint64_t bytes_uploaded = 0;  ///< host → device bytes in the last frame
    /// The frame stamps found in the tail of the cloth slot when the last frame waited for (collect(),
    /// or a window's next present) had drawn from it (weft/backend/interop.h, kSlotStampBytes): both equal
    /// to the frame's RenderFrame::stamp when it read one whole state (a frame that read a slot
    /// mid-write shows them differing).
    std::uint64_t stamp_first = 0, stamp_last = 0;
};

/// Whether the frame that `t` reports read exactly the state stamped `stamp`, whole (no tearing).
[[nodiscard]] inline bool frame_intact(const TransferStats& t, std::uint64_t stamp) {
    return t.stamp_first == stamp && t.stamp_last == stamp;
}

/// The zero-copy link (docs/rendering.md): the renderer's cloth slots, each a vertex buffer
/// (RenderScene::cloth_vertices RenderVertex, 24 bytes apart, then kSlotStampBytes of frame stamps)
/// with its own timeline semaphore, exported for a GPU backend on the same device to import
/// (Backend::share_output). Two slots let the writer fill one while a frame draws from the other.
struct ClothInterop {
    std::vector<SharedSlotHandle> slots;
    /// Per slot, the timeline's value now, reached: a new writer (after a world was rebuilt)
    /// continues above it, since a timeline only moves up.
    std::vector<std::uint64_t> timeline_values;
    DeviceUuid device_uuid{};  ///< the GPU they live on (Vulkan slots; GL slots are found through the context)
    /// OpenGL slots: makes the context that owns them current on the calling thread. The backend
    /// finds a GL buffer through the current context, so ClothFeed calls this before it shares the
    /// slots, begins or ends a frame, and lets them go (another renderer's context may be current
    /// then). Empty for Vulkan slots.
    std::function<void()> make_current;
};

class Renderer {
public:
    virtual ~Renderer() = default;
    Renderer() = default;
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    /// "vulkan" or "egl".
    [[nodiscard]] virtual std::string_view name() const = 0;
    /// The device and driver it renders on ("llvmpipe (LLVM 15.0.6), Vulkan 1.3.230").
    [[nodiscard]] virtual std::string device_description() const = 0;
    /// Uploads the static geometry of `scene` (kept by copy) and sizes the cloth buffer.
    virtual void load(const RenderScene& scene) = 0;
    /// Starts drawing `frame` (shadow pass, then the scene with MSAA, resolved, the picture copied
    /// for the host) without waiting for it: work between submit() and collect() overlaps the
    /// drawing. A frame already submitted is collected first (its picture dropped).
    virtual void submit(const RenderFrame& frame) = 0;
    /// Waits for the submitted frame and returns its picture. Throws weft::Error when none is.
    [[nodiscard]] virtual Image collect() = 0;
    /// submit() then collect().
    [[nodiscard]] Image draw(const RenderFrame& frame) {
        submit(frame);
        return collect();
    }
    /// A frame that will not be drawn: its timeline values (if any) are still waited for and
    /// signalled, so a writer waiting on them goes on (a no-op for host-upload frames).
    virtual void skip_frame(const RenderFrame& frame) = 0;
    [[nodiscard]] virtual TransferStats transfer() const = 0;
    /// After load(): exports two cloth slots. Vulkan: exportable memory with a timeline semaphore
    /// each (new fds, owned by the caller until imported). EGL: two GL buffer objects
    /// (SlotApi::opengl_buffer) and ClothInterop::make_current. From then on a frame with no cloth
    /// vertices is drawn from what the writer put in slot RenderFrame::cloth_slot (Vulkan: with
    /// RenderFrame's wait and signal values on that slot's timeline), and a frame with vertices is
    /// uploaded into that slot. std::nullopt, with the reason in `why`, where the device cannot
    /// export (lavapipe).
    [[nodiscard]] virtual std::optional<ClothInterop> export_cloth(std::string& why) = 0;
    /// Copies cloth slot `slot` back to the host: what the renderer draws from (tests).
    [[nodiscard]] virtual std::vector<RenderVertex> read_cloth(int slot = 0) = 0;
    /// Validation or debug messages of warning or error severity so far (0 without validation).
    [[nodiscard]] virtual int validation_messages() const = 0;
};

/// Creates the renderer called `name` ("vulkan", "egl"). Throws `weft::Error` saying what is missing
/// (no Vulkan device, no EGL display, no validation layer) when it cannot start.
[[nodiscard]] std::unique_ptr<Renderer> create_renderer(std::string_view name, const RendererOptions& options = {});
/// Names of the compiled renderers.
[[nodiscard]] std::vector<std::string> renderer_names();

}  // namespace weft::render
